-- The buddy's gait follows a speed that rises and falls: walk and run blended by it,
-- in step (the avatars plugin keeps blended clips on one phase).

local buddy

function onStart()
  buddy = find("buddy")
end

function onUpdate(dt)
  if buddy == nil then return end
  local run = 0.5 + 0.5 * math.sin(time() * 0.6)  -- 0 (walking) .. 1 (running)
  buddy:blend({Walk = 1 - run, Run = run})
end

function onAnimationEnd(avatar, clip)
  if clip == "Wave" then log(avatar:getName() .. " waved") end
end
