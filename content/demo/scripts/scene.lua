-- Scene script: loads plugins the way the paper's Listing 2 does, spawns crates
-- from scene-format text, and shifts the toon shader's colour over time.
requestPlugin("physics")
requestPlugin("osg")
requestPlugin("openalpp")

-- a crate every 2 s, three in all (a saved state keeps the count: run again, it goes on)
local dropped = 0

function onUpdate(dt)
  local t = time()
  while dropped < 3 and t >= 2.0 * (dropped + 1) do
    dropped = dropped + 1
    spawn(string.format([[
      Object { ID "gift%d" Position [%f 0 6] Size [0.5 0.5 0.5]
        VisualAttributes { Geometry { Primitive "box" } Color [0.9 0.2 0.3] }
        PhysicalAttributes { Mass 0.5 Material "wood" Geometry { Primitive "box" } } }
    ]], dropped, 2.5 + 0.2 * dropped))
  end
  setUniform("toon", "DiffuseColor", {0.5 + 0.5 * math.sin(t), 0.25, 1.0})
end

function onKey(key, pressed)
  if pressed and key == "space" then
    local ball = find("ball")
    if ball then ball:addImpulse(0, 0, 6) end
  end
end
