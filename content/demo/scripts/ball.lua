-- Attached to the object "ball" (self). Kicks it toward the tower and counts the bounces.
-- A saved state (--save-state) keeps `bounces` and the pending kick: run again, the script
-- resumes (onStart is not called twice). A timer's function needs a name to be saved.
local bounces = 0

local function kick() self:addImpulse(4, 0, 2) end

function onStart()
  after(0.5, kick)
end

function onCollision(other, impulse)
  if impulse > 0.5 then
    bounces = bounces + 1
    log(string.format("ball hit %s (impulse %.2f N s), bounce %d", other:getName(), impulse, bounces))
  end
end
