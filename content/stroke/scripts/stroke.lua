-- The stroke simulator's scene script: the tasks (tasks.lua), the HUD's line with the
-- wheelchair's mode and the anomalies on (anomalies.lua), and the keys: 0 switches every
-- anomaly off (3-8 switch one each: their Input in main.scene), M switches the chair
-- between velocity and feedback mode.

local tasks = require("tasks")
local anomalies = require("anomalies")
tasks.emit = emit
local mode = "velocity"

local function chair_mode(data) mode = data.mode end

function onStart()
  on("wheelchair_mode", chair_mode)
  tasks.start()
end

function onUpdate(dt)
  local status = mode
  local on = anomalies.summary()
  if on ~= "" then status = status .. " | " .. on end
  tasks.update(dt, status)
end

function onKey(key, pressed)
  if not pressed then return end
  if key == "m" then
    emit("wheelchair", {mode = mode == "velocity" and "feedback" or "velocity"})
  else
    anomalies.key(key)
  end
end
