-- Scene script: loads plugins the way the paper's Listing 2 does, spawns crates
-- from scene-format text, and shifts the toon shader's colour over time.
requestPlugin("physics")
requestPlugin("osg")
requestPlugin("openalpp")

local dropped = 0

every(2.0, function()
  if dropped < 3 then
    dropped = dropped + 1
    spawn(string.format([[
      Object { ID "gift%d" Position [%f 0 6] Size [0.5 0.5 0.5]
        VisualAttributes { Geometry { Primitive "box" } Color [0.9 0.2 0.3] }
        PhysicalAttributes { Mass 0.5 Material "wood" Geometry { Primitive "box" } } }
    ]], dropped, 2.5 + 0.2 * dropped))
  end
end)

function onUpdate(dt)
  local t = time()
  setUniform("toon", "DiffuseColor", {0.5 + 0.5 * math.sin(t), 0.25, 1.0})
end

function onKey(key, pressed)
  if pressed and key == "space" then
    local ball = find("ball")
    if ball then ball:addImpulse(0, 0, 6) end
  end
end
