"""Generated and mutated scripts, runaways included, end in a running script or a message
within the sandbox's limits: a short fixed-seed run of tools/fuzz.py's Lua target."""

from __future__ import annotations

from tools.fuzz_lua import TARGET


def test_fuzzed_scripts_run_or_are_told(fuzz_briefly):
    fuzz_briefly(TARGET, 150)
