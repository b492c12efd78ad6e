-- The stroke simulator's tasks (paper section 6): set the breakfast table, sweep the
-- kitchen floor. The tracker checks the scene a few times a second, emits task events
-- (emit("task", {task = ..., event = ..., ...}); the session log records them and sends
-- them as markers), shows progress on the HUD and ends the session (emit("session_end",
-- {reason = "done" | "timeout"})) when both are done or the time is up.
--
-- Breakfast: plate, bowl, cup, spoon and cereal each rest upright in its place on the
-- table, not held. Sweep: SWEPT of the crumbs lie in the dust pan or in the floor zone by
-- the shelves. The places are the marks main.scene draws ("mark plate", "mark sweep"):
-- move a mark there and the task follows.

local M = {}

M.TIME_LIMIT = 900     -- s the session may take
M.CHECK_EVERY = 0.25   -- s between checks
M.TABLE_TOP = 0.75     -- m
M.UPRIGHT = 0.9        -- its up axis at most ~25 degrees from vertical
M.RESTING = 0.05       -- m/s: moving slower than this, a thing is put down
-- Each thing, its mark, and how near the mark's centre it must stand (m).
M.BREAKFAST = {
  {object = "plate", mark = "mark plate", within = 0.08},
  {object = "bowl", mark = "mark bowl", within = 0.08},
  {object = "cup", mark = "mark cup", within = 0.07},
  {object = "spoon", mark = "mark spoon", within = 0.08},
  {object = "cereal", mark = "mark cereal", within = 0.1},
}
M.CRUMBS = 200
M.SWEPT = 0.9          -- share of the crumbs
M.ZONE = "mark sweep"  -- the floor zone: its mark, and half its size (m)
M.ZONE_HALF = {0.25, 0.225}
M.PAN = "dust pan"     -- inside: within its floor (0.25 x 0.22 m), up to its walls' top
M.PAN_HALF = {0.125, 0.11}
M.HANDS = {"right hand", "left hand"}

-- What stands now: the things placed, the crumbs swept, when each task was done.
M.placed = {}
M.swept = 0
M.done = {}
M.since_check = 0
M.ended = false
M.shown = nil
-- A module has no emit() of its own: the script that requires it hands over its own.
M.emit = nil

local function task(name, event, extra)
  local data = extra or {}
  data.task, data.event = name, event
  M.emit("task", data)
end

local function upright(obj)
  local _, x, y = obj:getOrientation()
  return 1 - 2 * (x * x + y * y) >= M.UPRIGHT
end

local function held()
  local ids = {}
  for _, name in ipairs(M.HANDS) do
    local hand = find(name)
    if hand then
      for _, obj in ipairs(hand:getHeld()) do ids[obj.id] = true end
    end
  end
  return ids
end

local function in_place(item, obj, holding)
  if holding[obj.id] then return false end
  local mark = find(item.mark)
  if not mark then return false end
  local mx, my = mark:getPosition()
  local x, y, z = obj:getPosition()
  local dx, dy = x - mx, y - my
  if dx * dx + dy * dy > item.within * item.within then return false end
  if z < M.TABLE_TOP or z > M.TABLE_TOP + 0.3 then return false end
  local vx, vy, vz = obj:getVelocity()
  return vx * vx + vy * vy + vz * vz <= M.RESTING * M.RESTING and upright(obj)
end

-- A vector in the frame of an object turned by unit quaternion (w, x, y, z).
local function into(w, x, y, z, vx, vy, vz)
  x, y, z = -x, -y, -z
  local tx, ty, tz = 2 * (y * vz - z * vy), 2 * (z * vx - x * vz), 2 * (x * vy - y * vx)
  return vx + w * tx + (y * tz - z * ty), vy + w * ty + (z * tx - x * tz),
         vz + w * tz + (x * ty - y * tx)
end

local function check_breakfast()
  local holding = held()
  local count = 0
  for _, item in ipairs(M.BREAKFAST) do
    local obj = find(item.object)
    local now = obj ~= nil and in_place(item, obj, holding)
    if now ~= (M.placed[item.object] == true) then
      M.placed[item.object] = now or nil
      task("breakfast", now and "placed" or "removed", {object = item.object})
    end
    if now then count = count + 1 end
  end
  if count == #M.BREAKFAST and not M.done.breakfast then
    M.done.breakfast = time()
    task("breakfast", "done", {seconds = time()})
  end
  return count
end

local function check_sweep()
  local pan = find(M.PAN)
  local px, py, pz, qw, qx, qy, qz
  if pan then
    px, py, pz = pan:getPosition()
    qw, qx, qy, qz = pan:getOrientation()
  end
  local zx, zy = 0, 0
  local zone = find(M.ZONE)
  if zone then zx, zy = zone:getPosition() end
  local x0, x1 = zx - M.ZONE_HALF[1], zx + M.ZONE_HALF[1]
  local y0, y1 = zy - M.ZONE_HALF[2], zy + M.ZONE_HALF[2]
  local swept = 0
  for i = 0, M.CRUMBS - 1 do
    local crumb = find("crumb " .. i)
    if crumb then
      local x, y, z = crumb:getPosition()
      local inside = zone ~= nil and x >= x0 and x <= x1 and y >= y0 and y <= y1
        and z < 0.05
      if not inside and pan then
        local lx, ly, lz = into(qw, qx, qy, qz, x - px, y - py, z - pz)
        inside = math.abs(lx) <= M.PAN_HALF[1] and math.abs(ly) <= M.PAN_HALF[2]
          and lz >= -0.03 and lz <= 0.05
      end
      if inside then swept = swept + 1 end
    end
  end
  if swept ~= M.swept then
    M.swept = swept
    task("sweep", "progress", {swept = swept})
  end
  if swept >= M.SWEPT * M.CRUMBS and not M.done.sweep then
    M.done.sweep = time()
    task("sweep", "done", {seconds = time(), swept = swept})
  end
end

local function finish(reason)
  M.ended = true
  M.emit("session_end", {reason = reason, breakfast = M.done.breakfast ~= nil,
                       sweep = M.done.sweep ~= nil})
end

function M.start()
  task("breakfast", "start")
  task("sweep", "start")
end

-- Called every frame with the frame's length and what else the HUD shows.
function M.update(dt, status)
  if M.ended then return end
  M.since_check = M.since_check + dt
  if M.since_check < M.CHECK_EVERY then return end
  M.since_check = 0
  local placed = check_breakfast()
  check_sweep()
  local left = math.max(0, M.TIME_LIMIT - time())
  local text = string.format("breakfast %d/%d%s | swept %d/%d%s | %d:%02d left%s",
    placed, #M.BREAKFAST, M.done.breakfast and " done" or "", M.swept, M.CRUMBS,
    M.done.sweep and " done" or "", math.floor(left / 60), math.floor(left % 60),
    (status ~= "" and " | " .. status) or "")
  if text ~= M.shown then
    M.shown = text
    M.emit("hud", text)
  end
  if M.done.breakfast and M.done.sweep then
    finish("done")
  elseif left <= 0 then
    finish("timeout")
  end
end

return M
