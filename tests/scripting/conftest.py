"""Fixtures for the scripting tests: a small-budget runtime and engines with scripting."""

from __future__ import annotations

from pathlib import Path

import pytest

from services.scripting.runtime import ScriptLimits, ScriptRuntime

#: Small enough that a runaway loop is stopped in a few milliseconds.
TEST_LIMITS = ScriptLimits(instructions=200_000, memory=48 * 1024 * 1024, max_failures=3)


@pytest.fixture
def content(tmp_path: Path) -> Path:
    (tmp_path / "scripts").mkdir()
    return tmp_path


@pytest.fixture
def runtime(content: Path) -> ScriptRuntime:
    return ScriptRuntime(TEST_LIMITS, content / "scripts")
