"""Backends and scene builders shared by the physics tests.

Scenes move in the X–Z plane with hinge axes along Y, so the same scene means the
same thing to the 3D backend (ODE) and the 2D side-view one (pymunk). The builders
reach tests through the ``kit`` fixture, so no test imports this file.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from types import SimpleNamespace

import numpy as np
import pytest

from components import Joint, MaterialProps, Physical, Shape
from engine.physics import BackendUnavailable, create_backend
from engine.physics.backend import DynamicsBackend, WorldSettings

BACKENDS = ["pymunk", "ode"]
#: Every backend, for what even the collision-free one must do.
ALL_BACKENDS = [*BACKENDS, "ballistic"]
G = 9.81
IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])
GROUND = 1000


def quat_y(phi: float) -> np.ndarray:
    """Rotation by ``phi`` about +Y (takes X toward −Z)."""
    return np.array([math.cos(phi / 2), 0.0, math.sin(phi / 2), 0.0])


def sphere(radius: float = 0.1, mass: float | None = 1.0, material: str = "default",
           friction: float = 0.5, bounce: float = 0.0, kind: str = "dynamic") -> Physical:
    return Physical(kind=kind, mass=mass, shapes=[Shape("sphere", (radius,))],
                    material=MaterialProps(name=material, friction=friction, bounce=bounce))


def box(size: tuple[float, float, float] = (1.0, 1.0, 1.0), mass: float | None = 1.0,
        kind: str = "dynamic", material: str = "default", friction: float = 0.5) -> Physical:
    return Physical(kind=kind, mass=mass, shapes=[Shape("box", size)],
                    material=MaterialProps(name=material, friction=friction))


def ground_plane(material: str = "default", friction: float = 0.5,
                 bounce: float = 0.0) -> Physical:
    return Physical(kind="static", mass=None, shapes=[Shape("plane", (0.0, 0.0, 1.0, 0.0))],
                    material=MaterialProps(name=material, friction=friction, bounce=bounce))


def hinge(a: int, anchor: tuple[float, float, float], b: int | None = None,
          **kw: object) -> Joint:
    return Joint(kind=kw.pop("kind", "hinge"), body_a=a, body_b=b, anchor=anchor,
                 axis=(0.0, 1.0, 0.0), **kw)  # type: ignore[arg-type]


def add(backend: DynamicsBackend, key: int, physical: Physical,
        position: tuple[float, float, float], orientation: np.ndarray = IDENTITY) -> int:
    backend.add_body(key, physical, np.array(position, dtype=np.float64),
                     np.asarray(orientation, dtype=np.float64))
    return key


def row(backend: DynamicsBackend, key: int) -> dict[str, np.ndarray]:
    """One body's pose and velocity from ``read_state``."""
    state = backend.read_state()
    (i,) = np.flatnonzero(state.keys == key)
    return {"position": state.position[i], "orientation": state.orientation[i],
            "linear": state.linear_velocity[i], "angular": state.angular_velocity[i]}


def run(backend: DynamicsBackend, seconds: float, dt: float,
        each: Callable[[int], None] | None = None) -> None:
    for i in range(round(seconds / dt)):
        backend.step(dt)
        if each is not None:
            each(i)


def _create(name: str) -> DynamicsBackend:
    try:
        return create_backend(name)
    except BackendUnavailable as exc:
        pytest.skip(f"{name} backend not importable here: {exc}")


def _factory(name: str) -> Iterator[Callable[..., DynamicsBackend]]:
    made: list[DynamicsBackend] = []

    def make(**settings: object) -> DynamicsBackend:
        backend = _create(name)
        settings.setdefault("auto_sleep", False)
        backend.configure(WorldSettings(**settings))  # type: ignore[arg-type]
        made.append(backend)
        return backend

    yield make
    for backend in made:
        backend.close()


@pytest.fixture(params=BACKENDS)
def make_backend(request: pytest.FixtureRequest) -> Iterator[
        Callable[..., DynamicsBackend]]:
    """Factory: a fresh, configured backend of the parametrised kind (closed afterwards)."""
    yield from _factory(request.param)


@pytest.fixture(params=ALL_BACKENDS)
def any_backend(request: pytest.FixtureRequest) -> Iterator[DynamicsBackend]:
    """A fresh backend of every kind, the collision-free one included."""
    for make in _factory(request.param):
        yield make()


@pytest.fixture
def backend(make_backend: Callable[..., DynamicsBackend]) -> DynamicsBackend:
    return make_backend()


@pytest.fixture
def kit() -> SimpleNamespace:
    """The scene builders and constants above, for tests to use as ``kit.add(...)``."""
    return SimpleNamespace(G=G, GROUND=GROUND, IDENTITY=IDENTITY, quat_y=quat_y, sphere=sphere,
                           box=box, ground_plane=ground_plane, hinge=hinge, add=add, row=row,
                           run=run)
