"""Dynamics backends behind one protocol, picked by name.

>>> sorted(map(str, BACKENDS))
['ballistic', 'ode', 'pymunk']
"""

from __future__ import annotations

import importlib

from engine.physics.backend import (
    CONTACT_DTYPE,
    BackendName,
    BodyState,
    DynamicsBackend,
    MaterialPair,
    RayHit,
    WorldSettings,
)

#: name -> "module:Class". Registered lazily so importing the engine loads no physics library.
BACKENDS: dict[BackendName, str] = {
    BackendName.ODE: "engine.physics.ode3d:OdeBackend",
    BackendName.PYMUNK: "engine.physics.pymunk2d:PymunkBackend",
    BackendName.BALLISTIC: "engine.physics.ballistic:BallisticBackend",
}


class BackendUnavailable(RuntimeError):
    pass


def create_backend(name: str) -> DynamicsBackend:
    """Instantiate the backend registered under ``name``."""
    try:
        target = BACKENDS[name]
    except KeyError:
        raise BackendUnavailable(
            f"unknown dynamics backend {name!r}; choose one of {', '.join(sorted(BACKENDS))}"
        ) from None
    module_name, class_name = target.split(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        hint = " (run `tools/dev setup` to build it)" if name == BackendName.ODE else ""
        raise BackendUnavailable(
            f"dynamics backend {name!r} is not available: {exc}{hint}") from exc
    return getattr(module, class_name)()


__all__ = [
    "BACKENDS",
    "BackendName",
    "CONTACT_DTYPE",
    "BackendUnavailable",
    "BodyState",
    "DynamicsBackend",
    "MaterialPair",
    "RayHit",
    "WorldSettings",
    "create_backend",
]
