"""Fixtures of the sound tests (helpers live in sound_helpers.py)."""

from __future__ import annotations

import pytest
from sound_helpers import Clock


@pytest.fixture
def clock() -> Clock:
    return Clock()
