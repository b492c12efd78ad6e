-- Attached to the object "ball" (self). Kicks it toward the tower and counts the bounces.
local bounces = 0

function onStart()
  after(0.5, function() self:addImpulse(4, 0, 2) end)
end

function onCollision(other, impulse)
  if impulse > 0.5 then
    bounces = bounces + 1
    log(string.format("ball hit %s (impulse %.2f N s), bounce %d", other:getName(), impulse, bounces))
  end
end
