"""The sandbox: every escape a hostile script might try is refused, and runaway or
memory-hungry scripts are stopped while the runtime and other scripts keep going."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from services.scripting.runtime import ScriptLimits, ScriptLoadError, ScriptRuntime


def run_once(runtime: ScriptRuntime, body: str, name: str = "scripts/evil.lua"):
    """Load a script whose onUpdate runs ``body``; call it once; return (ok, script)."""
    script = runtime.load(name, f"function onUpdate()\n{body}\nend\n")
    ok = runtime.call(script, "onUpdate")
    return ok, script


ESCAPES = {
    "io.open": "return io.open('/etc/passwd')",
    "io via _G": "return _G.io.open('/etc/passwd')",
    "os.execute": "return os.execute('touch /tmp/pwned')",
    "os.remove": "return os.remove('/tmp/x')",
    "os.getenv": "return os.getenv('HOME')",
    "os.exit": "os.exit(1)",
    "package.loadlib": "return package.loadlib('libc.so.6', 'system')",
    "dofile": "return dofile('/etc/passwd')",
    "loadfile": "return loadfile('/etc/passwd')",
    "string.dump": "return string.dump(function() end)",
    "string.dump via metatable": "return ('x').dump(function() end)",
    "debug.getregistry": "return debug.getregistry()",
    "debug.sethook": "debug.sethook()",
    "python.eval": "return python.eval('__import__(\"os\")')",
    "python.builtins": "return python.builtins.open",
    "load bytecode": "return assert(load('\\27Lua\\84\\0'))()",
    "load mode b": "return assert(load('return 1', 'x', 'b'))()",
    "collectgarbage stop": "collectgarbage('stop')",
    "__gc finalizer": "setmetatable({}, {__gc = function() end})",
}


@pytest.mark.parametrize("body", ESCAPES.values(), ids=ESCAPES.keys())
def test_escape_is_refused(runtime: ScriptRuntime, body: str) -> None:
    ok, script = run_once(runtime, body)
    assert not ok
    assert runtime.messages[-1].startswith("scripts/evil.lua:2:")
    assert not Path("/tmp/pwned").exists()


def test_os_keeps_clock_time_date(runtime: ScriptRuntime) -> None:
    script = runtime.load("scripts/t.lua", "c, t, d = os.clock(), os.time(), os.date('%Y')")
    assert isinstance(script.env.c, float) and script.env.t > 1_600_000_000
    assert len(script.env.d) == 4


def test_python_internals_are_unreachable(runtime: ScriptRuntime) -> None:
    """An API error hands the script a Python exception object; its attributes stay shut."""
    runtime_api = runtime.lua.table_from({"fail": _raise})
    script = runtime.load("scripts/p.lua", "function probe(f, attr)\n"
                                           "  local ok, e = pcall(f)\n"
                                           "  return e[attr]\nend\n")
    for attr in ("__class__", "__traceback__", "args", "with_traceback"):
        err = runtime.kernel.dispatch(script.env.probe, runtime_api.fail, attr)
        assert err is not None and "cannot access attributes of Python objects" in err


def _raise() -> None:
    raise ValueError("boom")


def test_require_stays_in_scripts_folder(runtime: ScriptRuntime, content: Path) -> None:
    (content / "scripts" / "lib").mkdir()
    (content / "scripts" / "lib" / "vec.lua").write_text(
        "local base = require('lib.base')\n"
        "print('vec loaded')\n"
        "return {add = function(a, b) return base.zero + a + b end}")
    (content / "scripts" / "lib" / "base.lua").write_text("return {zero = 0}")
    (content / "secret.lua").write_text("return 'secret'")
    script = runtime.load("scripts/r.lua", "v = require('lib.vec').add(2, 3)")
    assert script.env.v == 5
    assert "module: vec loaded" in runtime.messages
    for name in ("../secret", "..secret", "/etc/passwd", "lib/../../secret", "secret"):
        ok, _ = run_once(runtime, f"return require({name!r})")
        assert not ok, name
        assert "require:" in runtime.messages[-1]


def test_scripts_cannot_patch_each_other(runtime: ScriptRuntime) -> None:
    runtime.load("scripts/a.lua", "string.rep = nil; math.sin = nil; print = nil; shared = 1")
    b = runtime.load("scripts/b.lua", "r = string.rep('ab', 2); s = math.sin(0); "
                                      "p = type(print); g = shared; h = ('x'):rep(3)")
    assert (b.env.r, b.env.s, b.env.p, b.env.g, b.env.h) == ("abab", 0, "function", None, "xxx")
    ok, _ = run_once(runtime, "getmetatable('').__index = {}")
    assert not ok


RUNAWAYS = {
    "plain loop": "while true do end",
    "loop in pcall": "while true do pcall(function() while true do end end) end",
    "pcall of a loop, retried": "for i = 1, 1e9 do pcall(function() for j = 1, 1e9 do end end) end",
    "xpcall with a looping handler": "while true do xpcall(function() while true do end end, "
                                     "function(e) while true do end end) end",
    "error handler that catches all": "while true do pcall(error) end",
    "loop in a coroutine": "local co = coroutine.create(function() while true do end end) "
                           "coroutine.resume(co) while true do end",
    "coroutine.wrap in pcall": "local f = coroutine.wrap(function() while true do end end) "
                               "while true do pcall(f) end",
    "nested coroutines": "coroutine.wrap(function() coroutine.wrap(function() "
                         "while true do pcall(function() while true do end end) end end)() end)()",
    "recursion in pcall": "local function f() pcall(f) pcall(f) end f()",
    "string.rep in pcall": "while true do pcall(string.rep, 'x', 1e12) end",
}


@pytest.mark.parametrize("body", RUNAWAYS.values(), ids=RUNAWAYS.keys())
def test_runaway_is_stopped_and_others_continue(runtime: ScriptRuntime, body: str) -> None:
    good = runtime.load("scripts/good.lua", "n = 0\nfunction onUpdate(dt) n = n + 1 end")
    bad = runtime.load("scripts/evil.lua", f"function onUpdate(dt)\n{body}\nend\n")
    runtime.update(1 / 60)
    assert bad.stopped
    stopped = [m for m in runtime.messages if "stopped" in m]
    assert len(stopped) == 1
    assert stopped[0].startswith("scripts/evil.lua:")
    assert "instruction budget" in stopped[0]
    runtime.update(1 / 60)
    runtime.update(1 / 60)
    assert good.env.n == 3
    # the runtime is healthy: new scripts load and run
    later = runtime.load("scripts/later.lua", "x = 0 for i = 1, 1000 do x = x + i end")
    assert later.env.x == 500500


def test_runaway_top_level_refuses_to_load(runtime: ScriptRuntime) -> None:
    with pytest.raises(ScriptLoadError, match="instruction budget"):
        runtime.load("scripts/top.lua", "while true do end")


BOMBS = {  # body, what stops it
    "table growth": ("local x = ('x'):rep(4e6) local t = {} for i = 1, 1e9 do t[i] = x .. i end",
                     "memory cap"),
    "string doubling": ("local s = 'x' while true do s = s .. s end", "memory cap"),
    "global hoard": ("hoard = {} for i = 1, 1e9 do hoard[i] = {i, i, i} end", "memory cap"),
    # each allocation failure is caught by the script's pcall: the budget ends it
    "bomb in pcall": ("while true do pcall(function() local t = {} "
                      "for i = 1, 1e9 do t[i] = {} end end) end", "instruction budget"),
}


@pytest.mark.parametrize(("body", "stopper"), BOMBS.values(), ids=BOMBS.keys())
def test_memory_bomb_is_stopped(content: Path, body: str, stopper: str) -> None:
    from services.scripting.runtime import ScriptLimits

    runtime = ScriptRuntime(ScriptLimits(instructions=10_000_000, memory=24 * 1024 * 1024),
                            content / "scripts")
    good = runtime.load("scripts/good.lua", "n = 0\nfunction onUpdate(dt) n = n + 1 end")
    bad = runtime.load("scripts/evil.lua", f"function onUpdate(dt)\n{body}\nend\n")
    runtime.update(1 / 60)
    assert bad.stopped
    assert len(runtime.messages) == 1
    assert runtime.messages[0].startswith("scripts/evil.lua")
    assert stopper in runtime.messages[0]
    runtime.update(1 / 60)
    assert good.env.n == 2
    assert runtime.memory_kib() < 8 * 1024  # the hoard was released


BACKTRACKING = {
    "find a+b": "return ('a'):rep(1e5):find('a+b')",
    "method call": "local s = ('a'):rep(1e5) return s:match('a*a*b')",
    "gsub": "return string.gsub(('a'):rep(5000), 'a*a*a*b', '')",
    "gmatch": "for w in ('a'):rep(5000):gmatch('a-a-a-b') do end",
    "short subject": "return ('a'):rep(63):find(('a*'):rep(7) .. 'b')",  # a minute unchecked
}


@pytest.mark.parametrize("body", BACKTRACKING.values(), ids=BACKTRACKING.keys())
def test_catastrophic_patterns_are_refused(runtime: ScriptRuntime, body: str) -> None:
    """Pattern matching runs in C where the budget hook cannot reach: refuse it up front."""
    ok, _ = run_once(runtime, body)
    assert not ok
    assert "may backtrack for up to" in runtime.messages[-1]


def test_building_strings_is_charged_by_size(runtime: ScriptRuntime) -> None:
    """string.rep, concat and sort are charged by the work they do, the same in every run:
    a thread busy beside the script (the physics thread, a numeric library's spinning
    workers) costs it nothing, and a call too big for the budget never starts."""
    import threading

    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            sum(range(1000))

    busy = threading.Thread(target=spin)
    busy.start()
    try:
        # ~130,000 instructions charged of the test budget's 200,000, on any machine
        ok, _ = run_once(runtime, "local t = {}\n"
                                  "for i = 1, 1000 do t[i] = ('ab'):rep(10) end\n"
                                  "table.sort(t) local s = table.concat(t)")
    finally:
        stop.set()
        busy.join()
    assert ok, runtime.messages
    started = time.perf_counter()
    ok, script = run_once(runtime, "while true do local s = ('a'):rep(1e6) end",
                          name="scripts/builder.lua")
    # stopped at the first call (uncharged, 40,000 calls of 3 ms each would run)
    assert not ok and time.perf_counter() - started < 5
    assert "scripts/builder.lua:2: script exceeded its instruction budget" in runtime.messages[-1]


def test_work_nothing_counts_is_stopped_by_the_clock(content: Path) -> None:
    """Joining megabyte strings with `..` is one VM instruction each: a loop of them ran for
    a minute inside the default budget. The real-time net stops it within 2 s."""
    runtime = ScriptRuntime(scripts_dir=content / "scripts")  # the default budget
    started = time.perf_counter()
    ok, script = run_once(runtime, "local big = ('a'):rep(1e6)\n"
                                   "for i = 1, 1e9 do local x = big .. big .. big .. i end",
                          name="scripts/joiner.lua")
    assert not ok and script.stopped
    assert time.perf_counter() - started < 4
    assert "scripts/joiner.lua:3: script exceeded its instruction budget (ran over a second" \
        in runtime.messages[-1]


def test_the_clock_judges_only_a_running_callback(content: Path) -> None:
    """A scene whose scripts define no onUpdate ran two seconds, then the kernel's own loop
    over them was stopped as if a callback had run that long (every run of such a scene
    ended there). The net times callbacks, not the gaps between them."""
    runtime = ScriptRuntime(scripts_dir=content / "scripts")
    script = runtime.load("scripts/quiet.lua", "count = 0\nfunction onStart() end\n")
    time.sleep(2.0)  # os.time's whole seconds: two of them have begun since the load
    for _ in range(3000):  # ticks of the count hook land inside the kernel's loop
        runtime.update(1 / 60)
    assert runtime.call(script, "onStart") and not script.stopped, runtime.messages
    assert not runtime.messages


def test_an_overrun_seen_after_the_callback_never_escapes(runtime: ScriptRuntime) -> None:
    """Work charged at a callback's last statement (a big table.concat) is seen at the next
    tick of the count hook; a tick landing in the kernel after the callback returned raised
    the budget error into the engine, and the runtime stayed killed. At every phase of the
    hook: the script is stopped or not, never an exception, and the runtime goes on."""
    for pad in range(1000):  # shifts where the hook's next tick lands
        script = runtime.load(f"scripts/s{pad}.lua", "t = {}\n"
                              "for i = 1, 100 do t[i] = ('x'):rep(1500) end\n"
                              f"function onUpdate()\nfor i = 1, {pad} do end\n"
                              "local a = table.concat(t) local b = table.concat(t)\nend\n")
        runtime.call(script, "onUpdate")
        runtime.unload(script)
    after = runtime.load("scripts/after.lua", "x = 1\nfunction onUpdate() x = 2 end\n")
    assert runtime.call(after, "onUpdate") and after.env.x == 2


@pytest.mark.parametrize("body", [
    "local src = ('a=1 '):rep(2e6) for i = 1, 1e9 do load(src) end",
    "local piece = ('a=1 '):rep(2e5)\nfor i = 1, 1e9 do\n  local n = 0\n"
    "  load(function() n = n + 1 if n < 40 then return piece end end)\nend"],
    ids=["text", "reader"])
def test_compiling_is_charged_by_the_size_of_the_source(content: Path, body: str) -> None:
    """Compiling is C work the count cannot see: 200 compilations of 8 MB of source ran
    between two looks of the hook, 24 s before the clock stopped them."""
    runtime = ScriptRuntime(scripts_dir=content / "scripts")  # the default budget
    started = time.perf_counter()
    ok, script = run_once(runtime, body, name="scripts/compiler.lua")
    assert not ok and script.stopped and time.perf_counter() - started < 2
    assert "instructions per callback" in runtime.messages[-1]
    ok, small = run_once(runtime, "assert(load('return 1 + 1'))()", name="scripts/small.lua")
    assert ok  # a small chunk costs little


def test_ordinary_patterns_still_work(runtime: ScriptRuntime) -> None:
    script = runtime.load("scripts/p.lua", """
local text = ("key = value\\n"):rep(200)
count = 0
for k, v in text:gmatch("(%w+) = (%w+)") do count = count + 1 end
first = text:match("^(%w+)%s*=%s*(%w+)")
cleaned = select(2, ("a  b   c"):gsub("%s+", " "))
plain = ("a+b"):rep(10000):find("a+b", 1, true)
""")
    assert (script.env.count, script.env.first, script.env.cleaned, script.env.plain) == \
        (200, "key", 2, 1)


def test_a_kill_by_a_charge_names_the_script_and_line_whatever_the_hooks_phase(
        runtime: ScriptRuntime) -> None:
    """A budget run out by what a C call is charged stops the script from the charging
    wrapper; a hook tick landing while the kill was being worked out raised the message
    of the kill before (another script's file and line), or nil in a fresh runtime ("error
    object is a nil value"). Every phase of the hook's count is tried by padding the
    script with one more instruction each time."""
    for pad in range(0, 600):
        name = f"scripts/pad{pad}.lua"
        ok, _ = run_once(runtime, f"local x = 0\nfor i = 1, {pad} do x = x + 1 end\n"
                                  "while true do local s = ('a'):rep(40000) end", name=name)
        assert not ok
        assert runtime.messages[-1].startswith(
            f"{name}:4: script exceeded its instruction budget (200000 instructions per "
            "callback)"), runtime.messages[-1]


def test_small_matches_cost_the_bytes_they_scan_not_the_clock(runtime: ScriptRuntime) -> None:
    """Matching is charged the bytes it may scan, and CPU time only past a tenth of a
    millisecond a call: 1,000 matches on a short line fit a 200,000-instruction budget in
    every run (charged by the clock, reading it alone cost more than the budget)."""
    for i in range(20):
        ok, _ = run_once(runtime, """
local line, n = "key = value", 0
for i = 1, 500 do
  if line:find("=") and line:match("^(%w+)") then n = n + 1 end
end
for k in line:gmatch("%w+") do n = n + 1 end
""", name=f"scripts/match{i}.lua")
        assert ok, runtime.messages[-1]


def test_time_in_c_functions_counts_against_the_budget(runtime: ScriptRuntime) -> None:
    """Many individually allowed slow matches in a loop still exhaust the budget."""
    ok, script = run_once(runtime, "local s = ('a'):rep(3000)\n"
                                   "while true do s:find('a+b') end")
    assert not ok and script.stopped
    assert "instruction budget" in runtime.messages[-1]


def test_the_engines_own_lua_work_between_callbacks_is_never_charged() -> None:
    """Only script callbacks are counted and timed. Kernel work the engine asks for
    between them (the names of a reloaded script, garbage collection) used to run under
    the last callback's budget and clock: a scene whose scripts had been idle for a second
    was killed with a LuaError traceback when a script was edited (hot reload)."""
    runtime = ScriptRuntime(ScriptLimits(instructions=5_000))
    script = runtime.load("scripts/calm.lua", "n = 0\nfunction onUpdate() n = n + 1 end\n")
    big = runtime.lua.table_from({f"k{i}": i for i in range(20_000)})  # ~100,000 instructions
    for _ in range(3):
        assert sum(1 for _ in runtime.kernel.names(big)) == 20_000
        runtime.kernel.collect()
    assert runtime.call(script, "onUpdate") and script.env.n == 1 and not script.stopped
    ok, runaway = run_once(runtime, "while true do end", name="scripts/runaway.lua")
    assert not ok and runaway.stopped  # callbacks are still counted
