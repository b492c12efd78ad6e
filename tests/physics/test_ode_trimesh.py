"""Triangle meshes in contact (issue 31): a moving triangle mesh rests on every static
primitive (on a capsule too: libode's capsule-trimesh test threw it off, so the near
callback takes the capsule there as its parts, the cylinder between its caps and the two
cap spheres, each collided with the mesh), and a surface of no thickness (a triangle-mesh
floor) stops bodies that a step carries further than half their thickness (the backend
sweeps them: a ray ahead along their velocity, and a body that went past the surface put
back on it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("engine.physics.ode3d")

from components import Physical, Shape  # noqa: E402
from components.physical import BodyKind  # noqa: E402
from engine.physics.backend import WorldSettings  # noqa: E402
from engine.physics.ode3d.backend import OdeBackend  # noqa: E402
from engine.rotation import quat_to_matrix  # noqa: E402

#: ColliderTypeMatrix's dynamic mesh: a tetrahedron on its base (z 0 to 0.5).
TETRA = (np.array([[-0.5, 0.5, 0.0], [0.0, -0.5, 0.0], [0.0, 0.0, 0.5], [0.5, 0.5, 0.0]]),
         np.array([[0, 1, 2], [3, 0, 2], [1, 3, 2], [1, 0, 3]]))
#: A unit cube of 12 triangles, wound outward.
CUBE = (np.array([[x, y, z] for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)]),
        np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]))
FLAT = (np.array([[-20, -20, 0], [20, -20, 0], [20, 20, 0], [-20, 20, 0]], float),
        np.array([[0, 1, 2], [0, 2, 3]]))
UP = np.array([1.0, 0, 0, 0])
#: A quarter turn about X: a capsule or cylinder lying along Y.
LYING = np.array([np.cos(np.pi / 4), np.sin(np.pi / 4), 0, 0])

#: static shape, its pose, and the height of its top under the falling body
STATICS = {
    "box": (Shape(kind="box", size=(5.0, 5.0, 1.0)), (0, 0, -0.5), UP, 0.0),
    "sphere": (Shape(kind="sphere", size=(10.0,)), (0, 0, -10), UP, 0.0),
    "capsule": (Shape(kind="capsule", size=(10.0, 12.0)), (0, 0, -16), UP, 0.0),
    "capsule lying": (Shape(kind="capsule", size=(1.0, 6.0)), (0, 0, -1), LYING, 0.0),
    "cylinder": (Shape(kind="cylinder", size=(5.0, 2.0)), (0, 0, -1), UP, 0.0),
    "mesh": (Shape(kind="mesh", vertices=FLAT[0], faces=FLAT[1]), (0, 0, 0), UP, 0.0),
    "hull": (Shape(kind="hull", vertices=CUBE[0] * 4, faces=CUBE[1]), (0, 0, -2), UP, 0.0),
}


@pytest.mark.parametrize("static, mesh", [(s, m) for s in STATICS
                                           for m in ("tetrahedron", "cube")])
def test_a_moving_mesh_rests_on_every_static_primitive(static: str, mesh: str) -> None:
    shape, at, turn, top = STATICS[static]
    vertices, faces = TETRA if mesh == "tetrahedron" else CUBE
    world = OdeBackend(WorldSettings(gravity=(0.0, 0.0, -9.81)))
    try:
        world.add_body(1, Physical(kind=BodyKind.STATIC, shapes=[shape]), np.array(at, float),
                       turn)
        world.add_body(2, Physical(mass=1.0, shapes=[Shape(kind="mesh", vertices=vertices,
                                                           faces=faces)]),
                       np.array([0.0, 0.0, 2.0]), UP)
        for _ in range(400):
            world.step(0.01)
        state = world.read_state()
        row = int(np.flatnonzero(state.keys == 2)[0])
        turn = quat_to_matrix(state.orientation[row])
        low = state.position[row, 2] + (vertices @ turn.T)[:, 2].min()
        if static.startswith(("sphere", "capsule")):  # curved: it may tip over the top
            assert low > top - 0.05 and state.position[row, 2] > top - 0.01, low
        else:
            assert abs(low - top) < 0.03, f"lowest point {low:.3f} m on a top at {top} m"
        assert np.linalg.norm(state.position[row, :2]) < 0.25
        assert np.linalg.norm(state.linear_velocity[row]) < 0.1
    finally:
        world.close()


@pytest.mark.parametrize("shape", [Shape(kind="sphere", size=(0.01,)),
                                   Shape(kind="box", size=(0.2, 0.2, 0.02))])
@pytest.mark.parametrize("speed", [1.0, 3.0, 10.0, 30.0])
def test_a_floor_of_no_thickness_stops_fast_bodies(shape: Shape, speed: float) -> None:
    """A 1 cm ball or a 2 cm thin plate thrown down onto two triangles at up to 30 m/s
    (30 cm a step, 30 times the ball's radius) lands on them. Without the sweep every
    one of these passed through."""
    world = OdeBackend(WorldSettings(gravity=(0.0, 0.0, -9.81)))
    try:
        world.add_body(1, Physical(kind=BodyKind.STATIC, shapes=[
            Shape(kind="mesh", vertices=FLAT[0], faces=FLAT[1])]), np.zeros(3), UP)
        world.add_body(2, Physical(mass=0.1, shapes=[shape]), np.array([0.1, 0.2, 0.5]), UP,
                       np.array([0.0, 0.0, -speed]))
        for _ in range(200):
            world.step(0.01)
        state = world.read_state()
        z = float(state.position[int(np.flatnonzero(state.keys == 2)[0]), 2])
        assert 0.0 <= z < 0.02, z
    finally:
        world.close()


def test_many_boxes_rain_on_a_mesh_floor() -> None:
    """300 boxes of 20 cm dropped from up to 20 m onto a floor of two triangles: all end
    on it (before the sweep, 45 % fell through)."""
    rng = np.random.default_rng(0)
    world = OdeBackend(WorldSettings(gravity=(0.0, 0.0, -9.81)))
    try:
        world.add_body(0, Physical(kind=BodyKind.STATIC, shapes=[
            Shape(kind="mesh", vertices=FLAT[0], faces=FLAT[1])]), np.zeros(3), UP)
        for k in range(300):
            at = np.array([*rng.uniform(-10, 10, 2), rng.uniform(0.2, 20)])
            world.add_body(k + 1, Physical(mass=1.0, shapes=[
                Shape(kind="box", size=(0.2, 0.2, 0.2))]), at, UP)
        for _ in range(150):
            world.step(1 / 60)
        state = world.read_state()
        assert int((state.position[:, 2] < -0.02).sum()) == 0
    finally:
        world.close()


SHARED = Path(__file__).resolve().parents[3] / "shared" / "gltf-physics"


@pytest.mark.xfail(strict=True, reason="of WaterWheel's 10 balls, 3 sink slowly (0.4 m/s, "
                   "not tunnelling) through the floor where the tower stands on it, "
                   "squeezed by the tower's mesh; 4 more roll off the floor's edge at "
                   "x = -0.9 m, as a real ball would")
def test_water_wheel_keeps_its_balls_on_the_floor(tmp_path: Path) -> None:
    from tests.interchange.conformance import run

    path = SHARED / "khr" / "WaterWheel" / "WaterWheel.gltf"
    if not path.is_file():
        pytest.skip(f"{path} is not here")
    trace = run(path, tmp_path, 10.0)
    balls = [i for i, n in enumerate(trace.names) if n.startswith("GeoSphere")]
    low, high = trace.bounds(trace.index("GridFloor"), 0)
    lost = []
    for i in balls:
        z = trace.position[:, i, 2]
        if z[-1] < -0.009:
            f = int(np.argmax(z < -0.009))
            p = trace.position[f, i, :2]
            if np.all(p >= low[:2]) and np.all(p <= high[:2]):
                lost.append(trace.names[i])  # through the floor, not off its edge
    assert lost == []
