"""Bad input never crashes, hangs or blows up: a short, fixed-seed run of each target of
tools/fuzz.py (scenes here; models, images, sounds, Lua and input streams beside their
code's tests).

Each run is a fixed count of inputs (the time it takes is printed); the same tool runs
for hours by hand (see its docstring). The shrinker that makes a failure's reproducer
small is tested here too.
"""

from __future__ import annotations

from tools.fuzz_core import shrink
from tools.fuzz_scene import TARGET, Input

#: Scenes the suite fuzzes (a few seconds on the 2-core dev machine).
CI_INPUTS = 400


def test_fuzz_run_gives_reports_only(fuzz_briefly):
    fuzz_briefly(TARGET, CI_INPUTS)


def test_shrink_keeps_only_what_the_failure_needs():
    def fails(inp: Input) -> bool:
        return "min(1)" in inp.main and "Object" in inp.part

    small = shrink(Input("a 1\nx 2*min(1) + 3\nb 2\n", "k 1\nObject { ID 1 }\n"), fails)
    assert small == Input("min(1)", "Object")


def test_a_failure_that_does_not_come_back_is_reported_not_raised(tmp_path):
    """An input over the time limit once (a loaded machine) but not when hypothesis tries
    it again ended a campaign with an exception-group traceback after 36 minutes."""
    from dataclasses import replace

    from tools.fuzz_core import run

    calls = []

    def exercise(inp: Input, folder) -> str:
        calls.append(inp)
        if len(calls) == 3:
            raise TimeoutError("slow once")
        return "ok"

    result = run([replace(TARGET, exercise=exercise, prepare=None)], 2.0, seed=0,
                 out_dir=tmp_path)
    assert "TimeoutError: slow once" in result.failure
    assert "did not fail again when retried" in result.failure
    assert result.reproducer and result.reproducer[0].exists()
