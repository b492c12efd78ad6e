"""Bad input never crashes, hangs or blows up: a short, fixed-seed run of tools/fuzz_scene.py.

Generated and mutated scene text, expressions and includes go through check and fmt;
each must give a report pointing inside the files read, within the fuzz tool's time
and memory limits. The same tool runs for hours by hand (see its docstring); this run
is bounded by time, so how many inputs it reaches depends on the machine (it prints
the count). The shrinker that makes a failure's reproducer small is tested here too.
"""

from __future__ import annotations

from tools.fuzz_scene import Input, run, shrink

CI_SECONDS = 6.0
#: Fewer inputs than this in CI_SECONDS means the run did not really run.
AT_LEAST = 300


def test_fuzz_run_gives_reports_only(capsys):
    result = run(CI_SECONDS, seed=0, hostile_rate=0.001)
    with capsys.disabled():
        print(f"\nfuzz: {result.inputs} inputs in {result.seconds:.1f} s, "
              f"{result.formatted} formatted, slowest {result.slowest_s:.2f} s")
    assert result.failure is None, f"{result.failure}\nreproducer: {result.reproducer}"
    assert result.inputs >= AT_LEAST
    assert result.formatted > 0 and result.diagnostics > 0  # both paths were exercised


def test_shrink_keeps_only_what_the_failure_needs():
    def fails(inp: Input) -> bool:
        return "min(1)" in inp.main and "Object" in inp.part

    small = shrink(Input("a 1\nx 2*min(1) + 3\nb 2\n", "k 1\nObject { ID 1 }\n"), fails)
    assert small == Input("min(1)", "Object")
