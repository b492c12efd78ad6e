"""The sandbox: every escape a hostile script might try is refused, and runaway or
memory-hungry scripts are stopped while the runtime and other scripts keep going."""

from __future__ import annotations

from pathlib import Path

import pytest

from engine.scripting.runtime import ScriptLoadError, ScriptRuntime


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
    "table growth": ("local t = {} for i = 1, 1e9 do t[i] = ('x'):rep(4e6) .. i end",
                     "memory cap"),
    "string doubling": ("local s = 'x' while true do s = s .. s end", "memory cap"),
    "global hoard": ("hoard = {} for i = 1, 1e9 do hoard[i] = {i, i, i} end", "memory cap"),
    # each allocation failure is caught by the script's pcall: the budget ends it
    "bomb in pcall": ("while true do pcall(function() local t = {} "
                      "for i = 1, 1e9 do t[i] = {} end end) end", "instruction budget"),
}


@pytest.mark.parametrize(("body", "stopper"), BOMBS.values(), ids=BOMBS.keys())
def test_memory_bomb_is_stopped(content: Path, body: str, stopper: str) -> None:
    from engine.scripting.runtime import ScriptLimits

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
}


@pytest.mark.parametrize("body", BACKTRACKING.values(), ids=BACKTRACKING.keys())
def test_catastrophic_patterns_are_refused(runtime: ScriptRuntime, body: str) -> None:
    """Pattern matching runs in C where the budget hook cannot reach: refuse it up front."""
    ok, _ = run_once(runtime, body)
    assert not ok
    assert "may backtrack for up to" in runtime.messages[-1]


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


def test_time_in_c_functions_counts_against_the_budget(runtime: ScriptRuntime) -> None:
    """Many individually allowed slow matches in a loop still exhaust the budget."""
    ok, script = run_once(runtime, "local s = ('a'):rep(3000)\n"
                                   "while true do s:find('a+b') end")
    assert not ok and script.stopped
    assert "instruction budget" in runtime.messages[-1]
