"""The experiments' fixture: a test run in its own working directory."""

from __future__ import annotations

import os
from pathlib import Path

import pytest


@pytest.fixture
def in_tmp(tmp_path: Path):
    """Run with tmp_path as the working directory (sessions/ lands there)."""
    here = Path.cwd()
    os.chdir(tmp_path)
    try:
        yield tmp_path
    finally:
        os.chdir(here)
