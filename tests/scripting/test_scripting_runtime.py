"""Runtime behaviour authors rely on: error reports, disabling, timers, events, reload."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from services.scripting.runtime import ScriptLoadError, ScriptRuntime


def test_error_names_file_and_line_with_traceback(runtime: ScriptRuntime) -> None:
    script = runtime.load("scripts/door.lua", "local function open(x)\n"
                                              "  return x.hinge + 1\n"
                                              "end\n"
                                              "function onUpdate(dt)\n"
                                              "  open(nil)\n"
                                              "end\n")
    assert not runtime.call(script, "onUpdate", 0.1)
    message = runtime.messages[-1]
    assert message.startswith("scripts/door.lua:2: attempt to index a nil value (local 'x')")
    assert "stack traceback:" in message
    assert "\tscripts/door.lua:5: in function" in message
    assert "colosseum" not in message  # no kernel frames


def test_error_with_non_string_value_gets_a_place(runtime: ScriptRuntime) -> None:
    script = runtime.load("scripts/e.lua", "function onUpdate()\n  error({code = 1})\nend")
    runtime.call(script, "onUpdate")
    assert runtime.messages[-1].startswith("scripts/e.lua:2: error object is a table value")


def test_syntax_error_is_reported_with_line(runtime: ScriptRuntime) -> None:
    with pytest.raises(ScriptLoadError, match=r"scripts/bad.lua:3: .*near"):
        runtime.load("scripts/bad.lua", "x = 1\ny = 2\nfunction (\n")
    assert runtime.scripts == []


def test_repeated_error_disables_the_callback_with_one_message(runtime: ScriptRuntime) -> None:
    script = runtime.load("scripts/flaky.lua", "n = 0\nticks = 0\n"
                                               "function onUpdate(dt)\n"
                                               "  n = n + 1\n"
                                               "  error('broken')\nend\n"
                                               "function onKey(k, p) ticks = ticks + 1 end\n")
    for _ in range(10):
        runtime.update(1 / 60)
    assert script.env.n == 3  # called until the third failure, never again
    assert "onUpdate" in script.disabled
    assert len(runtime.messages) == 3
    assert runtime.messages[-1].endswith("scripts/flaky.lua: onUpdate disabled after 3 errors")
    runtime.broadcast("onKey", "a", True)  # the script's other callbacks still run
    assert script.env.ticks == 1


def test_timers_fire_on_simulated_time(runtime: ScriptRuntime) -> None:
    script = runtime.load("scripts/t.lua",
                          "once, ticks = 0, 0\n"
                          "after(0.5, function() once = once + 1 end)\n"
                          "local h = every(0.25, function() ticks = ticks + 1 end)\n"
                          "after(1.0, function() cancel(h) end)\n")
    for _ in range(150):  # 1.5 s at 100 Hz
        runtime.update(0.01)
    assert script.env.once == 1
    assert script.env.ticks == 4  # at 0.25, 0.5, 0.75, 1.0 (cancelled after the last)


def test_custom_events_between_scripts(runtime: ScriptRuntime) -> None:
    listener = runtime.load("scripts/l.lua", "got = {}\n"
                                             "on('door', function(data, name) "
                                             "got[#got + 1] = name .. ':' .. data.state end)")
    runtime.load("scripts/e.lua", "function onUpdate() emit('door', {state = 'open'}) end")
    runtime.update(0.1)
    assert list(listener.env.got.values()) == ["door:open"]


def test_curly_quotes_are_normalised_with_a_warning(runtime: ScriptRuntime,
                                                     caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, "colosseum.script"):
        script = runtime.load("scripts/q.lua", "x = 1\nname = \u201chello\u201d\n")
    assert script.env.name == "hello"
    assert "scripts/q.lua:2:8: warning: 2 typographic quote(s)" in caplog.text


def test_reload_keeps_state_and_refuses_broken_versions(runtime: ScriptRuntime) -> None:
    script = runtime.load("scripts/r.lua", "count = count or 0\n"
                                           "function onUpdate() count = count + 1 end\n")
    runtime.update(0.1)
    runtime.update(0.1)
    assert runtime.reload(script, "count = count or 0\n"
                                  "function onUpdate() count = count + 10 end\n")
    runtime.update(0.1)
    assert script.env.count == 12
    assert not runtime.reload(script, "function onUpdate( count = 0 end\n")
    assert "scripts/r.lua:1:" in runtime.messages[-1]
    assert "previous version keeps running" in runtime.messages[-1]
    runtime.update(0.1)
    assert script.env.count == 22


def test_reload_restarts_a_stopped_script(runtime: ScriptRuntime) -> None:
    script = runtime.load("scripts/s.lua", "function onUpdate() while true do end end")
    runtime.update(0.1)
    assert script.stopped
    assert runtime.reload(script, "n = 0\nfunction onStart() n = 100 end\n"
                                  "function onUpdate() n = n + 1 end\n")
    runtime.update(0.1)
    assert not script.stopped and script.env.n == 101


def test_script_file_names_are_relative_to_content(runtime: ScriptRuntime,
                                                   content: Path) -> None:
    path = content / "scripts" / "f.lua"
    path.write_text("function onUpdate() local a = nil + 1 end\n")
    script = runtime.load_file(path)
    runtime.call(script, "onUpdate")
    assert runtime.messages[-1].startswith("scripts/f.lua:1: attempt to perform arithmetic")


def test_math_random_follows_the_seed(content: Path) -> None:
    draws = []
    for _ in range(2):
        rt = ScriptRuntime(None, content / "scripts", seed=42)
        draws.append(rt.load("scripts/r.lua", "x = math.random()").env.x)
    assert draws[0] == draws[1]
