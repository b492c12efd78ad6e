-- The stroke study's trials (experiment.scene): each task trial switches the condition's
-- anomaly on at its severity and ends when the breakfast is set; each staircase trial
-- (its contrast loss is set by the experiment itself) ends with the experimenter's Y
-- (noticed) or N (not noticed). Outside `colosseum experiment run` it does nothing.

-- Severities: the anomaly's parameters, mild and severe.
local SEVERITY = {
  hemianopia = {mild = {sparing = 10, depth = 0.7}, severe = {sparing = 2, depth = 1}},
  neglect = {mild = {width = 30, depth = 0.5}, severe = {width = 15, depth = 0.95}},
  blur = {mild = {acuity = 0.2, motion = 0.3}, severe = {acuity = 0.8, motion = 0.7}},
}
local ALL = {"double_vision", "blur", "perspective", "neglect", "hemianopia"}

function onTrialStart(trial)
  for _, name in ipairs(ALL) do setAnomaly(name, false) end
  local anomaly = experiment:condition("anomaly")
  if anomaly ~= nil then
    setAnomaly(anomaly, true, SEVERITY[anomaly][experiment:condition("severity")])
    emit("hud", "trial " .. trial.index .. (trial.practice and " (practice)" or "")
         .. ": set the table for breakfast")
  else
    emit("hud", "trial " .. trial.index .. ": does the view look faded? Y / N")
  end
end

local function breakfast(data)
  local trial = experiment:trial()
  if trial ~= nil and trial.staircase == nil and data.task == "breakfast"
      and data.event == "done" then
    trial:finish("done")
  end
end

function onStart()
  on("task", breakfast)
end

function onKey(key, pressed)
  local trial = experiment:trial()
  if not pressed or trial == nil or trial.staircase == nil then return end
  if key == "y" or key == "n" then
    trial:respond("seen", key == "y")
    trial:finish("answered")
  end
end
