"""Convex shapes as ODE wants them, and what libode prints (issue 31).

libode's dCreateConvex checks the data it is given and prints "WARNING: Polygon N is not
defined counterclockwise" / "Plane N does not contain the origin" to stdout (not through
a handler). The engine builds every hull relative to a point inside it (so both checks
hold: its collision tests assume them), and whatever ODE prints while shapes are made goes
through the backend's log, counted and de-duplicated, never to the process's stdout.
"""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("engine.physics.ode3d")

from components import Physical, Shape  # noqa: E402
from components.physical import BodyKind  # noqa: E402
from engine.physics.ode3d import _ode, shapes  # noqa: E402
from engine.physics.ode3d.backend import OdeBackend  # noqa: E402

SHARED = Path(__file__).resolve().parents[3] / "shared" / "gltf-physics"
ROBOT = SHARED / "khr" / "Robot_skinned"


def hull_shapes(folder: Path) -> list[tuple[str, Shape]]:
    """(object ID, shape) of every hull collider of the scene in ``folder``."""
    from app.scene_loading import content_engine
    from components import Name

    engine = content_engine(folder)
    try:
        return [(name.id, s) for _, (name, body) in engine.world.get_components(Name, Physical)
                for s in body.shapes if s.kind == "hull"]
    finally:
        engine.close()


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if not (ROBOT / "Robot_skinned.gltf").is_file():
        pytest.skip(f"{ROBOT} is not here (../shared/gltf-physics)")
    folder = tmp_path_factory.mktemp("robot")
    for f in ROBOT.iterdir():
        shutil.copy(f, folder / f.name)
    (folder / "main.scene").write_text('Model { File "Robot_skinned.gltf" }\n')
    return folder


def test_the_robots_hulls_are_what_ode_checks_for(robot: Path) -> None:
    """Every hull of Robot_skinned: planes through the hull's interior (positive offset
    from the geom's origin, a point inside), polygons counter-clockwise seen from it, and
    the same solid as the shape's vertices (the centre added back)."""
    found = hull_shapes(robot)
    assert len(found) >= 10
    for name, shape in found:
        h = shapes.hull(shape.vertices)
        assert shapes.convex_problems(h.planes, h.points, h.polygons) == [], name
        assert np.all(h.planes[:, 3] > 0), name
        original = np.asarray(shape.vertices, float).reshape(-1, 3)
        lo, hi = original.min(axis=0), original.max(axis=0)
        np.testing.assert_allclose((h.points + h.center).min(axis=0), lo, atol=1e-12)
        np.testing.assert_allclose((h.points + h.center).max(axis=0), hi, atol=1e-12)
        # every plane holds the hull's points on its inner side, some of them on it
        side = h.points @ h.planes[:, :3].T - h.planes[:, 3]
        assert side.max() < 1e-9 and np.all(np.abs(side).min(axis=0) < 1e-9), name


def test_the_robot_runs_without_printing_to_stdout(robot: Path,
                                                   capfd: pytest.CaptureFixture[str]) -> None:
    from app.scene_loading import content_engine

    capfd.readouterr()
    engine = content_engine(robot)
    try:
        engine.run(frames=30)
    finally:
        engine.close()
    out = capfd.readouterr().out
    assert "WARNING" not in out and "Polygon" not in out, out[:2000]


def test_a_hull_off_its_origin_keeps_its_place_and_mass() -> None:
    """A hull far from its shape's origin: the geom sits at its centre, so the body's
    mass, centre of mass and contacts are where the vertices say."""
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    backend = OdeBackend()
    try:
        body = Physical(mass=2.0, shapes=[Shape(kind="hull", vertices=cube + [4.0, 0.0, 0.0])])
        backend.add_body(1, body, np.array([0.0, 0.0, 5.0]), np.array([1.0, 0, 0, 0]))
        backend.add_static_plane()
        for _ in range(300):
            backend.step(1 / 100)
        state = backend.read_state()
        z = float(state.position[0][2])
        # resting on its face: the body's origin (not the hull) 0 to 1 m above the ground
        # (cube z 0..1 relative to the origin: origin at the ground), x where it started
        assert abs(z) < 0.02, z
        assert abs(float(state.position[0][0])) < 0.02
    finally:
        backend.close()


def _bad_convex() -> dict[str, np.ndarray]:
    """A unit cube 4 m from the origin, as dCreateConvex takes it but not relative to a
    point inside: every plane misses the origin, half the polygons turn the wrong way."""
    from scipy.spatial import ConvexHull

    pts = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float) + 4.0
    found = ConvexHull(pts)
    tris = found.simplices.astype(np.uint32)
    planes = np.column_stack([found.equations[:, :3], -found.equations[:, 3]])
    polygons = np.column_stack([np.full(len(tris), 3), tris]).astype(np.uint32).ravel()
    return {"vertices": pts, "faces": tris, "planes": planes, "polygons": polygons}


def test_what_ode_prints_goes_through_the_log_counted(
        capfd: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture) -> None:
    """Data ODE complains about (made by hand: the engine's hulls never are): its lines are
    taken from stdout and told through the backend's log, one line per kind of message,
    the rest counted when the backend closes."""
    bad = _bad_convex()
    assert shapes.convex_problems(bad["planes"], bad["vertices"], bad["polygons"])
    backend = OdeBackend()
    capfd.readouterr()
    with caplog.at_level(logging.WARNING, logger="colosseum.physics.ode"):
        for key in (1, 2):
            backend.add_body(key, Physical(kind=BodyKind.STATIC, shapes=[Shape(kind="box")]),
                             np.zeros(3), np.array([1.0, 0, 0, 0]))  # static: no mass
            _ode.add_geom(backend._world, key, _ode.GEOM_HULL, np.zeros(1), np.zeros(3),
                          np.array([1.0, 0, 0, 0]), 1000.0, 0, 1, 0xFFFFFFFF, **bad)
            backend._tell_printed(key)
        backend.close()
    out = capfd.readouterr().out
    assert "WARNING" not in out, out
    messages = [r.getMessage() for r in caplog.records]
    planes = [m for m in messages if "does not contain the origin" in m]
    assert planes[0].startswith("body 1: ODE: WARNING: Plane 0 does not contain the origin")
    assert len(planes) == 2 and "repeated" in planes[1], messages
