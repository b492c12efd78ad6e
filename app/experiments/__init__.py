"""``colosseum experiment run|report|replay|simulate``: the commands over a study. The
study's logic (design, staircases, session files) is core, in ``engine.experiments``; the
plugin that runs trials is ``systems.experiments``."""
