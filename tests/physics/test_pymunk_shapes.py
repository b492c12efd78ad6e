"""pymunk backend: 3D shapes as side-view silhouettes with 3D mass properties."""

from __future__ import annotations

import logging
import math

import numpy as np
import pymunk
import pytest

from components import MaterialProps, Physical, Shape
from engine.physics.backend import WorldSettings
from engine.physics.pymunk2d import PymunkBackend

LOGGER = "colosseum.physics.pymunk"
ALONG_Y = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)  # local Z → world Y
ALONG_X = (math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0)  # local Z → world X

# a failing pymunk callback is only printed by cffi: make it fail the test
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")


@pytest.fixture
def backend() -> PymunkBackend:
    b = PymunkBackend()
    b.configure(WorldSettings(auto_sleep=False))
    return b


def _shapes(backend: PymunkBackend, key: int) -> list[pymunk.Shape]:
    return backend._bodies[key].shapes


def _body(backend: PymunkBackend, key: int) -> pymunk.Body:
    return backend._bodies[key].body


@pytest.mark.parametrize(("kind", "rotation", "expected"), [
    ("capsule", ALONG_Y, pymunk.Circle),
    ("capsule", ALONG_X, pymunk.Segment),
    ("cylinder", ALONG_Y, pymunk.Circle),
    ("cylinder", ALONG_X, pymunk.Poly),
])
def test_round_shapes_pick_the_silhouette(kit, backend: PymunkBackend, kind: str,
                                          rotation: tuple, expected: type) -> None:
    kit.add(backend, 1, Physical(shapes=[Shape(kind, (0.2, 1.0), rotation=rotation)]),
        (0.0, 0.0, 0.0))
    (shape,) = _shapes(backend, 1)
    assert isinstance(shape, expected)
    bb = shape.cache_bb()
    width = bb.right - bb.left
    assert width == pytest.approx(0.4 if rotation is ALONG_Y else
                                  (1.4 if kind == "capsule" else 1.0), abs=1e-6)


def test_box_rotated_in_its_frame_and_offset(kit, backend: PymunkBackend) -> None:
    spec = Shape("box", (2.0, 1.0, 0.5), offset=(1.0, 3.0, 0.5),
                 rotation=(math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0))
    kit.add(backend, 1, Physical(kind="static", mass=None, shapes=[spec]), (0.0, 0.0, 0.0))
    bb = _shapes(backend, 1)[0].cache_bb()
    # turned a quarter about Y: 2 m along X becomes 2 m along Z, centred on (1, 0.5)
    assert (bb.left, bb.right) == pytest.approx((0.75, 1.25))
    assert (bb.bottom, bb.top) == pytest.approx((-0.5, 1.5))


def test_mesh_collides_as_convex_hull_and_warns(kit, backend: PymunkBackend,
                                                caplog: pytest.LogCaptureFixture) -> None:
    # an L-shaped prism: its hull fills the notch
    outline = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    verts = np.array([(x, y, z) for x, z in outline for y in (-0.5, 0.5)], dtype=float)
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        kit.add(backend, 1, Physical(mass=None, shapes=[Shape("mesh", vertices=verts)],
                                 material=MaterialProps(density=100.0)), (0.0, 0.0, 0.0))
    (shape,) = _shapes(backend, 1)
    assert shape.area == pytest.approx(3.5)
    assert _body(backend, 1).mass == pytest.approx(100.0 * 3.5 * 1.0)
    assert any("convex hull" in r.getMessage() for r in caplog.records)


def test_mass_from_density_uses_3d_volume_and_moment(kit, backend: PymunkBackend) -> None:
    kit.add(backend, 1, Physical(mass=None, shapes=[Shape("sphere", (0.5,))],
                             material=MaterialProps(density=1000.0)), (0.0, 0.0, 0.0))
    body = _body(backend, 1)
    mass = 1000.0 * 4 / 3 * math.pi * 0.125
    assert body.mass == pytest.approx(mass)
    assert body.moment == pytest.approx(0.4 * mass * 0.25)


def test_given_mass_is_shared_by_volume(kit, backend: PymunkBackend) -> None:
    shapes = [Shape("box", (1.0, 1.0, 1.0), offset=(-1.0, 0.0, 0.0)),
              Shape("box", (1.0, 1.0, 1.0), offset=(1.0, 0.0, 0.0))]
    kit.add(backend, 1, Physical(mass=4.0, shapes=shapes), (0.0, 0.0, 0.0))
    body = _body(backend, 1)
    assert body.mass == pytest.approx(4.0)
    assert body.moment == pytest.approx(2 * (2.0 * 2 / 12 + 2.0 * 1.0))


def test_plane_is_a_half_space(kit, backend: PymunkBackend) -> None:
    slope = math.radians(30)
    plane = Physical(kind="static", mass=None, shapes=[
        Shape("plane", (-math.sin(slope), 0.0, math.cos(slope), 0.0))])
    kit.add(backend, 1, plane, (0.0, 0.0, 0.0))
    assert backend._space.point_query_nearest((0.0, -5.0), 0.0, pymunk.ShapeFilter())
    assert backend._space.point_query_nearest((0.0, 1.0), 0.0, pymunk.ShapeFilter()) is None
    ball = Physical(shapes=[Shape("sphere", (0.1,))], material=MaterialProps(friction=0.0))
    kit.add(backend, 2, ball, (0.0, 0.0, 0.1 / math.cos(slope) + 0.001))
    for _ in range(60):
        backend.step(1 / 60)
    v = kit.row(backend, 2)["linear"]
    # frictionless: it slides down toward −X with a = g sin θ along the slope
    assert float(np.hypot(v[0], v[2])) == pytest.approx(9.81 * math.sin(slope), rel=0.02)
    assert v[0] < 0.0


@pytest.mark.parametrize("spec", [
    Shape("torus", (1.0,)),
    Shape("mesh", vertices=None),
    Shape("plane", (0.0, 1.0, 0.0, 0.0)),
])
def test_unrepresentable_shapes_warn_and_never_crash(kit, backend: PymunkBackend, spec: Shape,
                                                     caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        kit.add(backend, 3, Physical(kind="static", mass=None, shapes=[spec]), (0.0, 0.0, 0.0))
        kit.add(backend, 4, Physical(mass=2.0, shapes=[spec]), (0.0, 0.0, 1.0))
        backend.step(1 / 60)
    assert backend.body_count() == 2
    assert _body(backend, 4).mass == 2.0
    assert {r.getMessage().split(":")[0] for r in caplog.records} >= {"body 3", "body 4"}


def test_friction_is_the_geometric_mean(kit, backend: PymunkBackend) -> None:
    kit.add(backend, 1, kit.ground_plane(friction=0.5), (0.0, 0.0, 0.0))
    cube = Physical(shapes=[Shape("box", (0.2, 0.2, 0.2))], material=MaterialProps(friction=0.4))
    kit.add(backend, 2, cube, (0.0, 0.0, 0.1))
    backend.set_velocity(2, np.array([4.0, 0.0, 0.0]), np.zeros(3))
    for _ in range(10):
        backend.step(1 / 60)
    v0 = kit.row(backend, 2)["linear"][0]
    for _ in range(30):
        backend.step(1 / 60)
    decel = (v0 - kit.row(backend, 2)["linear"][0]) / 0.5
    assert decel == pytest.approx(math.sqrt(0.5 * 0.4) * 9.81, rel=0.02)
