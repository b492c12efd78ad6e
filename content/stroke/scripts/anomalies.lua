-- The anomalies of a stroke as the content's scripts use them (paper section 6). The
-- anomalies themselves are the scene's blocks (main.scene: DoubleVision, Blur, ...), each
-- switched by its own key; this module adds what a session wants on top: one key that
-- switches them all off, and the HUD's summary of what is on.
--
--   local anomalies = require("anomalies")
--   anomalies.key("0")                         -- 0 switches all off
--   anomalies.summary()                        -- "blur, neglect" (sorted), "" with none on
--   setAnomaly("neglect", true, {depth = 0.6}) -- any script sets one directly

local M = {}

-- The scene's anomalies, by their IDs, and what the HUD calls them.
M.SHORT = {double_vision = "diplopia", blur = "blur", perspective = "perspective",
           neglect = "neglect", hemianopia = "hemianopia", contrast_loss = "contrast"}

function M.key(key)
  if string.gsub(key, "^number_", "") ~= "0" then return end
  for name in pairs(M.SHORT) do
    if getAnomaly(name).enabled then setAnomaly(name, false) end
  end
end

function M.summary()
  local parts = {}
  for name, short in pairs(M.SHORT) do
    if getAnomaly(name).enabled then parts[#parts + 1] = short end
  end
  table.sort(parts)
  return table.concat(parts, ", ")
end

return M
