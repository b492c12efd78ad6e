"""The Lua sandbox: what a script may touch, and the budget that stops it.

The kernel below runs once per runtime with the full Lua 5.4 standard library,
keeps private references to the few dangerous functions it needs
(``debug.sethook``, ``debug.getinfo``, ``debug.traceback``, ``load``) and then
strips the global table. Scripts never see ``_G``: each one gets an environment
table whose ``__index`` is the frozen table of safe globals, with private copies
of the library tables so one script cannot patch ``string`` for another.

Refused: ``io``, ``os`` (except ``clock``/``time``/``date``), ``package``,
``debug``, ``dofile``/``loadfile``, ``string.dump``, loading bytecode (``load``
is text-only and defaults to the script's own environment), ``__gc``
finalizers, ``collectgarbage`` modes other than count/collect/step, and any
attribute of a Python object (the runtime's attribute filter refuses all).
``require`` resolves only modules in the content folder's ``scripts/``.

The budget is an instruction count hook; work done inside C library calls the
hook cannot see is charged to the same budget: by its size where the arguments
or the result tell it (strings built, items sorted, moved or concatenated), so
the charge is the same in every run, and for pattern matching by the bytes it may scan
and the CPU time a call takes beyond a tenth of a millisecond (backtracking).
Patterns whose backtracking could run for seconds on the given subject are
refused before they start.

Once a callback exceeds the budget the kernel enters a *killed* state in which
the hook raises on every instruction of any Lua function except the kernel's
own dispatcher, so ``pcall`` loops, ``xpcall`` message handlers (never run
after a kill: Lua calls them with hooks off) and coroutines (whose hooks are
installed by the wrapped ``coroutine.create``/``wrap``) all unwind back to the
dispatcher.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

log = logging.getLogger("colosseum.script")

#: Marker at the end of the error raised when a callback runs out of budget.
BUDGET_MESSAGE = "script exceeded its instruction budget"
#: Lua's own message when an allocation fails (the runtime's memory cap).
MEMORY_MESSAGE = "not enough memory"
#: Hook granularity: the hook runs once every HOOK_STEP VM instructions.
HOOK_STEP = 1000
#: How the budget counts time spent in C library calls (matching, sorting): one second
#: costs as much as this many VM instructions (Lua 5.4 runs ~5e8 simple ones per second).
INSTRUCTIONS_PER_SECOND = 5e8

_CURLY = {"\u201c": '"', "\u201d": '"', "\u201e": '"', "\u2018": "'", "\u2019": "'"}
_CURLY_RE = re.compile("[\u201c\u201d\u201e\u2018\u2019]")
_MODULE_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")


def normalise_quotes(source: str, chunkname: str) -> str:
    """Replace typographic quotes by ASCII ones, warning once with the first place.

    Text copied from papers and word processors (the paper's Listing 2) is
    otherwise a syntax error Lua reports as "unexpected symbol near '<\\226>'".
    """
    first = _CURLY_RE.search(source)
    if first is None:
        return source
    line = source.count("\n", 0, first.start()) + 1
    col = first.start() - (source.rfind("\n", 0, first.start()) + 1) + 1
    count = len(_CURLY_RE.findall(source))
    log.warning("%s:%d:%d: warning: %d typographic quote(s) replaced by ASCII quotes",
                chunkname, line, col, count)
    return _CURLY_RE.sub(lambda m: _CURLY[m.group(0)], source)


def resolve_module(scripts_dir: Path | None, name: object) -> Path:
    """The file ``require(name)`` may load: ``scripts/a/b.lua`` for ``"a.b"``, nothing else."""
    if not isinstance(name, str) or not _MODULE_RE.match(name):
        raise ValueError(f"require: invalid module name {name!r} "
                         "(use dotted Lua names such as 'lib.vector')")
    if scripts_dir is None:
        raise ValueError(f"require: no content folder, cannot load module {name!r}")
    root = scripts_dir.resolve()
    path = (root / (name.replace(".", "/") + ".lua")).resolve()
    if not path.is_relative_to(root):
        raise ValueError(f"require: module {name!r} is outside the content folder")
    if not path.is_file():
        raise ValueError(f"require: module {name!r} not found in {scripts_dir}")
    return path


#: The kernel: args (hook step, budget ticks, budget message, instructions per second);
#: returns table K.
KERNEL = r"""
local STEP, LIMIT, BUDGET_MESSAGE, INSTRUCTIONS_PER_SECOND = ...
local sethook, getinfo, traceback = debug.sethook, debug.getinfo, debug.traceback
local getupvalue, setupvalue, upvalueid = debug.getupvalue, debug.setupvalue, debug.upvalueid
local sort = table.sort
local co_create, co_resume, co_running, co_status = coroutine.create, coroutine.resume,
  coroutine.running, coroutine.status
local base_load, error, type, tostring, select, pairs = load, error, type, tostring, select, pairs
local rawget, rawset, setmetatable, getmetatable = rawget, rawset, setmetatable, getmetatable
local xpcall, pack, unpack, collectgarbage = xpcall, table.pack, table.unpack, collectgarbage
local format, sub, raw_find = string.format, string.sub, string.find

local K = {}
local budget, limit, killed, kill_message = 0, LIMIT, false, nil
-- A safety net for work inside one statement that neither the count nor the charges
-- below see (joining megabyte strings with ..): a callback running over WALL_SECONDS of
-- real time (os.time's whole seconds: stopped between 1 and 2 s) is stopped too.
-- `started` is the running callback's start (nil between callbacks: the kernel's own
-- loops, a batch's scripts without the function, are never judged by an old start);
-- `outer` holds the starts of the callbacks a nested one runs inside.
local time, WALL_SECONDS, started, outer, depth = os.time, 1, nil, {}, 0
local exempt = setmetatable({}, {__mode = "k"})

local function where(level)
  -- first frame at or above `level` that belongs to a script file ("@" chunks)
  while true do
    local info = getinfo(level, "Sl")
    if info == nil then return "" end
    if sub(info.source, 1, 1) == "@" and info.currentline > 0 then
      return info.short_src .. ":" .. info.currentline .. ": "
    end
    level = level + 1
  end
end

local function hook()
  if killed then
    local f = getinfo(2, "f").func
    if exempt[f] then return end
    sethook(co_running(), hook, "", 1)
    error(kill_message, 0)
  end
  budget = budget - 1
  local why
  if budget < 0 then
    why = format("%d instructions per callback", limit * STEP)
  elseif started ~= nil and time() - started > WALL_SECONDS then
    why = "ran over a second of real time, in work the instruction count cannot see "
          .. "such as joining long strings"
  else
    return
  end
  -- Asked only here, where a script is about to be stopped, so the common tick stays
  -- cheap: the kernel's own code around a callback is not the script's (a tick landing in
  -- finish before it resets the budget raised outside xpcall, into the engine), and
  -- neither is kernel work the engine asks for between callbacks (the names of a
  -- reloaded script, garbage collection): that starts the count afresh. A script's own
  -- code run between callbacks (a metamethod Python touched) is still stopped.
  local info = getinfo(2, "Sf")
  if info and exempt[info.func] then return end
  if started == nil and info and info.source == "=colosseum" then
    budget = limit
    return
  end
  -- the message first: a tick landing in where() while `killed` stood without it
  -- raised nil, and the script was told "error object is a nil value"
  kill_message = where(2) .. format("%s (%s)", BUDGET_MESSAGE, why)
  killed = true
  sethook(co_running(), hook, "", 1)
  error(kill_message, 0)
end

local function handler(e)
  if killed then return kill_message end
  budget = limit  -- the report itself must not run out of budget
  local t = type(e)
  if t == "string" then
    if sub(e, 1, 1) == "[" or not raw_find(e, "^[^:]+:%d+: ") then e = where(2) .. e end
  elseif t == "userdata" then  -- a Python exception raised by an API function
    e = where(2) .. tostring(e)
  else  -- never call a script's __tostring here: it would run outside the budget
    e = where(2) .. "error object is a " .. t .. " value"
  end
  local tb = traceback(e, 2)
  local cut, at = nil, 1
  while true do  -- drop the kernel's own frames below the last xpcall
    local i = raw_find(tb, "\n\t[C]: in function 'xpcall'", at, true)
    if i == nil then break end
    cut, at = i, i + 1
  end
  return cut and sub(tb, 1, cut - 1) or tb
end

-- A callback starts: a fresh budget and start time (finish restores the outer start).
local function enter()
  depth = depth + 1
  outer[depth] = started or false
  budget, started = limit, time()
end

local function finish(ok, err)
  budget, started = limit, outer[depth] or nil
  outer[depth] = nil
  depth = depth - 1
  if killed then  -- still exempt here: restore the normal hook, then leave the killed state
    sethook(hook, "", STEP)
    killed = false
  end
  if ok then return nil end
  if type(err) ~= "string" then return "error object is a " .. type(err) .. " value" end
  return err
end

-- Run fn(...) under a fresh budget. Returns nil, or the error message with traceback.
local function dispatch(fn, ...)
  enter()
  return finish(xpcall(fn, handler, ...))
end

-- Call env[name](...) when the script defines it.
local function call(env, name, ...)
  local fn = rawget(env, name)
  if fn == nil then return nil end
  enter()
  return finish(xpcall(fn, handler, ...))
end

K.where = where  -- "file:line: " of the script calling an API function (for its messages)
exempt[hook] = true; exempt[handler] = true; exempt[enter] = true; exempt[finish] = true
exempt[dispatch] = true; exempt[call] = true
K.dispatch, K.call = dispatch, call
sethook(hook, "", STEP)
budget = limit

function K.set_limit(ticks) limit = ticks; budget = ticks end
function K.collect() collectgarbage("collect"); return collectgarbage("count") end
function K.memory() return collectgarbage("count") end

-- coroutines: every new coroutine gets the budget hook (hooks are per thread)
local co = {}
for k, v in pairs(coroutine) do co[k] = v end
function co.create(f)
  local c = co_create(f)
  sethook(c, hook, "", STEP)
  return c
end
function co.wrap(f)
  local c = co.create(f)
  return function(...)
    local r = pack(co_resume(c, ...))
    if r[1] then return unpack(r, 2, r.n) end
    error(r[2], 0)
  end
end

-- object handles: read-only proxies, one per entity, shared by all scripts
local handle_ids = setmetatable({}, {__mode = "k"})
local handles = {}
local Object = {}
K.Object = Object
-- Read-only fields computed when read (hand.state, hand.held): name -> getter(handle)
local Fields = {}
K.Fields = Fields
local handle_mt = {
  __index = function(h, k)
    if k == "id" then return handle_ids[h] end
    local field = Fields[k]
    if field ~= nil then return field(h) end
    return Object[k]
  end,
  __newindex = function() error("object handles are read-only", 2) end,
  __tostring = function(h) return "object " .. tostring(handle_ids[h]) end,
  __eq = function(a, b) return handle_ids[a] == handle_ids[b] end,
  __metatable = false,
}
function K.handle(id)
  if id == nil or id < 0 then return nil end
  local h = handles[id]
  if h == nil then
    h = setmetatable({}, handle_mt)
    handle_ids[h] = id
    handles[id] = h
  end
  return h
end
function K.forget(id) handles[id] = nil end
function K.id_of(h)
  local id = type(h) == "table" and handle_ids[h]
  if id then return id end
  if math.type(h) == "integer" then return h end
  return nil
end
-- A copy of a value as plain data: handles become entity ids, metatables are dropped.
function K.plain(v, depth)
  if type(v) ~= "table" then return v end
  local id = handle_ids[v]
  if id ~= nil then return id end
  depth = (depth or 0) + 1
  if depth > 16 then error("data nested too deeply (more than 16 levels)", 0) end
  local t = {}
  for k, x in next, v do t[k] = K.plain(x, depth) end
  return t
end
function K.collide(env, other, impulse)
  local fn = rawget(env, "onCollision")
  if fn == nil then return nil end
  enter()
  return finish(xpcall(fn, handler, K.handle(other), impulse))
end
function K.collide_scene(env, a, b, impulse)
  local fn = rawget(env, "onCollision")
  if fn == nil then return nil end
  enter()
  return finish(xpcall(fn, handler, K.handle(a), K.handle(b), impulse))
end
-- Many onCollision calls in one go: returns nil, or the index that failed and its error.
local function collide_batch(envs, others, impulses, n, i)
  local handle = K.handle
  while i <= n do
    local fn = rawget(envs[i], "onCollision")
    if fn ~= nil then
      enter()
      local err = finish(xpcall(fn, handler, handle(others[i]), impulses[i]))
      if err ~= nil then return i, err end
    end
    i = i + 1
  end
  return nil
end
K.collide_batch = collide_batch
-- env[name](...) on envs[i..n]: returns nil, or the index that failed and its error.
local function call_batch(envs, name, n, i, ...)
  while i <= n do
    local fn = rawget(envs[i], name)
    if fn ~= nil then
      enter()
      local err = finish(xpcall(fn, handler, ...))
      if err ~= nil then return i, err end
    end
    i = i + 1
  end
  return nil
end
K.call_batch = call_batch
-- env[name](...) with its first n arguments (entity ids) given as handles (nil for -1).
function K.call_handles(env, name, n, ...)
  local fn = rawget(env, name)
  if fn == nil then return nil end
  local args = pack(...)
  for i = 1, n do args[i] = K.handle(args[i]) end
  enter()
  return finish(xpcall(fn, handler, unpack(args, 1, args.n)))
end
exempt[K.call_handles] = true
exempt[K.collide] = true; exempt[K.collide_scene] = true; exempt[collide_batch] = true
exempt[call_batch] = true

-- safe globals
local function safe_setmetatable(t, mt)
  if type(mt) == "table" and rawget(mt, "__gc") ~= nil then
    error("__gc finalizers are not allowed in scripts", 2)
  end
  return setmetatable(t, mt)
end
local function safe_rawset(t, k, v)
  if handle_ids[t] then error("object handles are read-only", 2) end
  return rawset(t, k, v)
end
-- Lua calls a message handler at the error point, where an error raised by the hook
-- has left hooks disabled: a script's handler must never run then.
local function safe_xpcall(f, msgh, ...)
  return xpcall(f, function(e)
    if killed then return e end
    return msgh(e)
  end, ...)
end
local gc_modes = {count = true, collect = true, step = true}
local function safe_collectgarbage(opt, ...)
  opt = opt or "collect"
  if not gc_modes[opt] then error("collectgarbage('" .. tostring(opt) .. "') is not allowed", 2) end
  return collectgarbage(opt, ...)
end

local SAFE = {
  assert = assert, error = error, ipairs = ipairs, next = next, pairs = pairs, pcall = pcall,
  xpcall = safe_xpcall, rawequal = rawequal, rawget = rawget, rawlen = rawlen, rawset = safe_rawset,
  select = select, tonumber = tonumber, tostring = tostring, type = type, _VERSION = _VERSION,
  getmetatable = getmetatable, setmetatable = safe_setmetatable,
  collectgarbage = safe_collectgarbage,
}
K.SAFE = SAFE
-- Pattern matching runs in C, out of the hook's reach, and backtracks: ("a"):rep(1e5)
-- :find("a+b") takes 40 s, and ("a"):rep(63):find(("a*"):rep(7) .. "b") a minute. Estimate
-- the worst case before matching: within a run of repeated items not separated by a
-- literal, k repetitions cost up to n^k/k! steps when something after them can fail (a
-- trailing run never backtracks: one repetition less); an unanchored search multiplies by
-- n start positions. Refuse above MATCH_STEPS. A pattern's runs are read once (RUNS).
local MATCH_STEPS = 2e7
local QUANT = {["*"] = true, ["+"] = true, ["-"] = true}
local RUNS, runs_cached = {}, 0
local function pattern_runs(p)
  local runs = RUNS[p]
  if runs then return runs end
  runs = {anchored = sub(p, 1, 1) == "^"}
  local i, len, k = runs.anchored and 2 or 1, #p, 0
  while i <= len do
    local c = sub(p, i, i)
    local item_end, literal = i, false
    if c == "%" then
      local d = sub(p, i + 1, i + 1)
      if d == "b" then item_end = i + 3; k = k + 1
      elseif d == "f" then  -- frontier: skip its set
        local j = raw_find(p, "]", i + 4, true)
        item_end = j or len
      else
        item_end = i + 1
        literal = not raw_find(d, "^%w")  -- the kernel's own find: no recursion
      end
    elseif c == "[" then
      local j = i + 1
      if sub(p, j, j) == "^" then j = j + 1 end
      if sub(p, j, j) == "]" then j = j + 1 end
      while j <= len and sub(p, j, j) ~= "]" do
        if sub(p, j, j) == "%" then j = j + 1 end
        j = j + 1
      end
      item_end = j
    elseif c == "(" or c == ")" or c == "." then
      item_end = i
    else
      literal = not (c == "$" and i == len)
    end
    local q = sub(p, item_end + 1, item_end + 1)
    if QUANT[q] then
      k = k + 1
      item_end = item_end + 1
    elseif q == "?" then
      item_end = item_end + 1
    elseif literal or (c == "$" and i == len) then
      if k > 0 then runs[#runs + 1] = k end
      k = 0
    end
    i = item_end + 1
  end
  if k > 1 then runs[#runs + 1] = k - 1 end  -- a trailing run succeeds once it has expanded
  if runs_cached >= 256 then RUNS, runs_cached = {}, 0 end
  RUNS[p], runs_cached = runs, runs_cached + 1
  return runs
end
local function check_pattern(what, s, p, plain)
  if plain or type(s) ~= "string" or type(p) ~= "string" then return end
  local n = #s
  local runs = pattern_runs(p)
  local worst = 1
  for r = 1, #runs do
    local cost = 1
    for j = 1, runs[r] do cost = cost * n / j end
    if cost > worst then worst = cost end
  end
  if not runs.anchored then worst = worst * n end
  if worst > MATCH_STEPS then
    error(format("%s: pattern %q on a %d-byte string may backtrack for up to %.0e steps "
                 .. "(limit %.0e); use a plain find (4th argument true) or split the text",
                 what, p, n, worst, MATCH_STEPS), 3)
  end
end
-- Work done in C (building strings, sorting, moving table items, matching) is invisible
-- to the count hook. Where its size is known from the arguments or the result it is
-- charged by size, the same in every run: one instruction per byte built or scanned and
-- four per item sorted, concatenated or moved (measured on Lua 5.4: ~3 ns a byte, ~15 ns
-- an item, ~3.5 ns an instruction). Matching, whose cost depends on backtracking, is
-- charged the bytes it may scan and, beyond MATCH_FREE seconds a call, the time it took on
-- the process's CPU clock: an ordinary match costs the same in every run (a tick of the
-- clock or an interrupt during one used to be charged as hundreds of thousands of
-- instructions, and a script near its budget was stopped in one run and not the next),
-- while a backtracking one still pays for what it does.
local clock = os.clock
local TICKS_PER_SECOND = INSTRUCTIONS_PER_SECOND / STEP
local MATCH_FREE = 1e-4
local ITEM = 4
local COMPILE = 10  -- instructions charged per byte of source a script compiles
local function charge(instructions)
  budget = budget - instructions / STEP
end
local function charged(t0, ...)
  local spent = clock() - t0
  if spent > MATCH_FREE then budget = budget - (spent - MATCH_FREE) * TICKS_PER_SECOND end
  return ...
end
local function scanned(s, init)  -- bytes a match from `init` may look at
  if type(s) ~= "string" then return 0 end
  init = math.tointeger(init) or 1
  if init < 0 then init = #s + init + 1 end
  return math.max(#s - math.max(init, 1) + 1, 0)
end
local function bytes_out(r, ...)  -- charge the string a call returned
  if type(r) == "string" then charge(#r) end
  return r, ...
end
local function count(n)  -- a size argument as a number to charge (0 when it is not one)
  n = tonumber(n)
  if n == nil or n ~= n or n < 0 then return 0 end
  return n
end
local s_find, s_match, s_gmatch, s_gsub = string.find, string.match, string.gmatch,
  string.gsub
string.find = function(s, p, init, plain)
  check_pattern("string.find", s, p, plain)
  charge(scanned(s, init))
  if plain then return s_find(s, p, init, plain) end
  return charged(clock(), s_find(s, p, init, plain))
end
string.match = function(s, p, init)
  check_pattern("string.match", s, p)
  charge(scanned(s, init))
  return charged(clock(), s_match(s, p, init))
end
string.gmatch = function(s, p, init)
  check_pattern("string.gmatch", s, p)
  charge(scanned(s, init))  -- its steps together scan the subject once
  local step = s_gmatch(s, p, init)
  return function() return charged(clock(), step()) end
end
string.gsub = function(s, p, repl, n)
  check_pattern("string.gsub", s, p)
  charge(scanned(s))
  return bytes_out(charged(clock(), s_gsub(s, p, repl, n)))
end
local s_rep = string.rep
string.rep = function(s, n, sep)  -- charged before it runs: rep(s, 1e12) never starts
  if type(s) == "string" or type(s) == "number" then
    local reps = count(n)
    local each = #tostring(s) + ((type(sep) == "string" or type(sep) == "number")
                                 and #tostring(sep) or 0)
    charge(reps * each)
    if budget < 0 then hook() end
  end
  return s_rep(s, n, sep)
end
for _, name in ipairs({"upper", "lower", "reverse", "sub", "format", "char", "pack"}) do
  local f = string[name]
  string[name] = function(...) return bytes_out(f(...)) end
end
local s_byte, s_len = string.byte, string.len
string.byte = function(s, i, j)  -- one value per byte asked for
  local r = pack(s_byte(s, i, j))
  charge(r.n * ITEM)
  return unpack(r, 1, r.n)
end
local t_sort, t_concat, t_insert, t_remove, t_move, t_unpack = table.sort, table.concat,
  table.insert, table.remove, table.move, table.unpack
table.sort = function(t, comp)
  if type(t) == "table" then
    local n = #t
    if n > 1 then charge(n * math.log(n, 2) * ITEM) end
    if budget < 0 then hook() end
  end
  return t_sort(t, comp)
end
table.concat = function(t, sep, i, j)
  if type(t) == "table" then charge(count((j or #t) - (i or 1) + 1) * ITEM) end
  return bytes_out(t_concat(t, sep, i, j))
end
table.insert = function(t, ...)  -- an insert or removal before the end shifts the rest
  if select("#", ...) == 2 and type(t) == "table" then charge(#t * ITEM) end
  return t_insert(t, ...)
end
table.remove = function(t, ...)
  if select("#", ...) > 0 and type(t) == "table" then charge(#t * ITEM) end
  return t_remove(t, ...)
end
table.move = function(a1, f, e, t, a2)
  charge(count((tonumber(e) or 0) - (tonumber(f) or 0) + 1) * ITEM)
  if budget < 0 then hook() end
  return t_move(a1, f, e, t, a2)
end
table.unpack = function(t, i, j)
  if type(t) == "table" then charge(count((j or #t) - (i or 1) + 1) * ITEM) end
  return t_unpack(t, i, j)
end
local u_len = utf8.len
utf8.len = function(s, ...)
  if type(s) == "string" then charge(s_len(s)) end
  return u_len(s, ...)
end
-- math.random's position cannot be read back (a saved state cannot keep it): count the
-- draws so saving can say the sequence is not kept.
local m_random, random_calls = math.random, 0
math.random = function(...)
  random_calls = random_calls + 1
  return m_random(...)
end
function K.random_calls() return random_calls end
local string_copy = {}
for k, v in pairs(string) do string_copy[k] = v end
string_copy.dump = nil
string.dump = nil
local LIBS = {
  string = string_copy, table = table, math = math, utf8 = utf8, coroutine = co,
  os = {clock = os.clock, time = os.time, date = os.date},
}
-- the shared string metatable must not lead back to the real string table
getmetatable("").__metatable = false

local function copy(t)
  local c = {}
  for k, v in pairs(t) do c[k] = v end
  return c
end
K.copy = copy

-- A fresh environment for one script (or module): private library copies.
function K.new_env(extra)
  local env = {}
  for name, lib in pairs(LIBS) do env[name] = copy(lib) end
  if extra then for k, v in pairs(extra) do env[k] = v end end
  env._G = env
  env.load = function(chunk, name, mode, e)
    if mode ~= nil and mode ~= "t" then
      return nil, "load: only text chunks are allowed (mode 't')"
    end
    if type(chunk) == "string" and sub(chunk, 1, 4) == "\27Lua" then
      return nil, "load: binary chunks are not allowed"
    end
    if type(chunk) == "string" then  -- compiling costs ~30 ns a byte, unseen by the count
      charge(#chunk * COMPILE)
      if budget < 0 then hook() end
    elseif type(chunk) == "function" then
      local read = chunk
      chunk = function()
        local piece = read()
        if type(piece) == "string" then charge(#piece * COMPILE) end
        if budget < 0 then hook() end
        return piece
      end
    end
    return base_load(chunk, name, "t", e or env)
  end
  return setmetatable(env, {__index = SAFE, __metatable = false})
end

-- Compile a script's source in its environment: returns fn or nil, message.
function K.compile(source, chunkname, env)
  local fn, err = base_load(source, chunkname, "t", env)
  return fn, err
end

-- Modules: loaded once per runtime, each in its own environment.
local modules, loading = {}, {}
function K.require_with(read_module, extra)
  return function(name)
    local m = modules[name]
    if m ~= nil then return m end
    if loading[name] then error("require: module '" .. tostring(name) .. "' requires itself", 2) end
    local chunkname, source = read_module(name)
    local env = K.new_env(extra)
    local fn, err = base_load(source, chunkname, "t", env)
    if fn == nil then error(err, 0) end
    loading[name] = true
    local ok, result = pcall(fn, name)
    loading[name] = nil
    if not ok then error(result, 0) end
    if result == nil then result = true end
    modules[name] = result
    return result
  end
end
function K.forget_modules() modules = {} end

-- Saved states (see services.scripting.persist). A script's state is the data in its own
-- globals (those not in `base`, the names it started with) and in the file's local
-- variables its functions use (their upvalues); functions are code, made again when the
-- file runs, so only their names are kept (for timers and handlers).
local OBJECT = "\0object"  -- a handle in captured data: {[OBJECT] = entity id}
K.OBJECT = OBJECT
local MAX_ENTRIES = 100000

local function string_keys(t)
  local names = {}
  for k in next, t do if type(k) == "string" then names[#names + 1] = k end end
  sort(names)
  return names
end

function K.names(env)
  local set = {}
  for k in next, env do set[k] = true end
  return set
end

function K.functions(env)
  local set = {}
  for k, v in next, env do if type(v) == "function" then set[k] = v end end
  return set
end

-- The file's local variables, breadth-first from its global functions (and the functions
-- in its global tables) in name order: an array of {key, fn, index}; a variable is keyed
-- by its name, "name#2" for the second variable of that name.
local function own_cells(env, base, source)
  local queue, seen, cells, count = {}, {}, {}, {}
  local function push_table(t)
    if seen[t] or handle_ids[t] then return end
    seen[t] = true
    for _, k in ipairs(string_keys(t)) do
      if type(rawget(t, k)) == "function" then queue[#queue + 1] = rawget(t, k) end
    end
  end
  for _, name in ipairs(string_keys(env)) do
    local v = rawget(env, name)
    if not base[name] then
      if type(v) == "function" then queue[#queue + 1] = v
      elseif type(v) == "table" then push_table(v) end
    end
  end
  local i = 1
  while i <= #queue do
    local f = queue[i]
    i = i + 1
    if not seen[f] and getinfo(f, "S").source == source then
      seen[f] = true
      local u = 1
      while true do
        local name, value = getupvalue(f, u)
        if name == nil then break end
        if name ~= "_ENV" then
          local id = upvalueid(f, u)
          if not seen[id] then
            seen[id] = true
            count[name] = (count[name] or 0) + 1
            cells[#cells + 1] = {count[name] == 1 and name or name .. "#" .. count[name], f, u}
          end
          if type(value) == "function" then queue[#queue + 1] = value
          elseif type(value) == "table" then push_table(value) end
        end
        u = u + 1
      end
    end
  end
  return cells
end

-- A copy of v holding only data: handles become {[OBJECT] = id}, functions are left out
-- (code), anything else that is not data is reported through skip(path, why).
local function data(v, path, skip, state, depth)
  local t = type(v)
  if t == "number" or t == "string" or t == "boolean" then return v end
  if t ~= "table" then skip(path, "is a " .. t .. ", not data"); return nil end
  local id = handle_ids[v]
  if id ~= nil then return {[OBJECT] = id} end
  if state.open[v] then skip(path, "refers back to a table that holds it"); return nil end
  if depth > 16 then skip(path, "is nested more than 16 tables deep"); return nil end
  state.open[v] = true
  local out = {}
  for k, x in next, v do
    state.entries = state.entries + 1
    if state.entries > MAX_ENTRIES then
      error(format("more than %d values to save", MAX_ENTRIES), 0)
    end
    local kt = type(k)
    if type(x) == "function" then  -- code: the file makes it again
    elseif kt == "string" or kt == "number" or kt == "boolean" then
      out[k] = data(x, path .. "[" .. format("%q", k) .. "]", skip, state, depth + 1)
    else
      skip(path, "has a " .. kt .. " key, not data")
    end
  end
  state.open[v] = nil
  return out
end

-- Fill `out` with the state of a script: globals, locals, the names of `fns` (timer and
-- handler functions; false where a function has no name), and what could not be kept.
function K.capture(env, base, loaded, source, fns, out)
  local skipped = {}
  local function skip(path, why) skipped[#skipped + 1] = path .. " " .. why end
  local state = {open = {}, entries = 0}
  local names = {}
  local globals = {}
  for _, name in ipairs(string_keys(env)) do
    local v = rawget(env, name)
    if not base[name] then
      if type(v) == "function" then
        if loaded[name] == v then names[v] = name
        else skip(name, "holds a function made at run time (not saved: only data is)") end
      else
        globals[name] = data(v, name, skip, state, 1)
      end
    end
  end
  local locals = {}
  for _, cell in ipairs(own_cells(env, base, source)) do
    local _, v = getupvalue(cell[2], cell[3])
    if type(v) == "function" then
      if names[v] == nil then names[v] = cell[1] end
    else
      locals[cell[1]] = data(v, "local " .. cell[1], skip, state, 1)
    end
  end
  local fn_names, fn_lines = {}, {}
  for i = 1, #fns do
    fn_names[i] = names[fns[i]] or false
    fn_lines[i] = getinfo(fns[i], "S").linedefined
  end
  out.globals, out.locals, out.skipped = globals, locals, skipped
  out.fn_names, out.fn_lines = fn_names, fn_lines
end

-- Write saved values back: a table merges into the table the file made (its functions
-- stay, its data becomes the saved data); anything else replaces the value.
local function merge(current, saved)
  if type(saved) ~= "table" or type(current) ~= "table" or handle_ids[saved]
      or handle_ids[current] then
    return saved
  end
  for k, x in next, current do
    if type(x) ~= "function" and saved[k] == nil then current[k] = nil end
  end
  for k, x in next, saved do current[k] = merge(rawget(current, k), x) end
  return current
end

function K.restore(env, base, source, globals, locals)
  for name, v in next, globals do rawset(env, name, merge(rawget(env, name), v)) end
  for _, cell in ipairs(own_cells(env, base, source)) do
    local v = locals[cell[1]]
    if v ~= nil then
      local _, current = getupvalue(cell[2], cell[3])
      setupvalue(cell[2], cell[3], merge(current, v))
    end
  end
end

-- The function a saved timer or handler names (nil when the file has none of that name).
function K.named(env, base, source, name)
  local v = rawget(env, name)
  if type(v) == "function" and not base[name] then return v end
  for _, cell in ipairs(own_cells(env, base, source)) do
    if cell[1] == name then
      local _, f = getupvalue(cell[2], cell[3])
      if type(f) == "function" then return f end
    end
  end
  return nil
end

-- Lock down the global table itself (scripts never see it; defence in depth).
function K.lockdown()
  for _, name in ipairs({"io", "os", "package", "debug", "dofile", "loadfile", "load",
                         "require", "python", "collectgarbage"}) do
    _G[name] = nil
  end
  string.dump = nil
end
return K
"""
