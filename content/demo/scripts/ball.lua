-- Attached to the object "ball" (self). Kicks it toward the tower and counts the bounces.
local bounces = 0

function onStart()
  -- at 0.5 s: a state saved later (--save-state) and run again has had its kick
  if time() < 0.5 then
    after(0.5 - time(), function() self:addImpulse(4, 0, 2) end)
  end
end

function onCollision(other, impulse)
  if impulse > 0.5 then
    bounces = bounces + 1
    log(string.format("ball hit %s (impulse %.2f N s), bounce %d", other:getName(), impulse, bounces))
  end
end
