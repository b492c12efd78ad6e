-- Listing 2 of Backman, "Colosseum3D - Authoring framework for Virtual Environments"
-- (EGVE 2005, section 4.2), "Loading plugin modules from Lua", as printed: typographic
-- quotes and the paper's "requrestPlugin" spelling included.
requestPlugin(“physics”)
requrestPlugin(“osg”)
requrestPlugin(“osgsim”)
requrestPlugin(“openalpp”)
