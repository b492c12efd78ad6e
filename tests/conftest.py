"""Shared fixtures: engines on every dynamics backend that is built here."""

from __future__ import annotations

import importlib
import importlib.util
import os

import pytest
from hypothesis import settings

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
# Every engine in the tests checks that systems touch only what they declare.
os.environ.setdefault("COLOSSEUM_DEBUG", "1")

# CI replays the same examples every run (no wall-clock deadlines on a shared machine);
# a developer's run explores new ones.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")


def available_backends() -> list[str]:
    names = ["ballistic", "pymunk"]
    if importlib.util.find_spec("engine.physics.ode3d") is not None:
        try:
            importlib.import_module("engine.physics.ode3d")
            names.append("ode")
        except ImportError:
            pass
    return names


@pytest.fixture(params=available_backends())
def backend_name(request: pytest.FixtureRequest) -> str:
    return request.param
