"""Shared fixtures: engines on every dynamics backend that is built here."""

from __future__ import annotations

import importlib.util
import os

import pytest

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")


def available_backends() -> list[str]:
    names = ["ballistic", "pymunk"]
    if importlib.util.find_spec("engine.physics.ode3d") is not None:
        try:
            importlib.import_module("engine.physics.ode3d")
            names.append("ode")
        except ImportError:
            pass
    return names


import importlib  # noqa: E402


@pytest.fixture(params=available_backends())
def backend_name(request: pytest.FixtureRequest) -> str:
    return request.param
