"""The conformance scenes of KHR_physics_rigid_bodies (../shared/gltf-physics/khr_tests,
62 files in five families, each family with a README saying what must happen), each run
and checked against what its README says (issue 31; docs/conformance.md has the table).

A README states the expectation per family ("the dynamic rigid body is expected to remain
above the XZ plane, supported by a collision with the static geometry"; "one body should
not penetrate the static geometry, while the other ...") and names what each file varies
("Hinge joint with free rotation axis = 1", "Validate physics material combine mode");
the checks below turn that into numbers. Each scene runs 4 simulated seconds (the
Materials ones 5) on ODE.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine.rotation import quat_to_matrix
from tests.interchange.conformance import SHARED, Trace, run

TESTS = SHARED / "khr_tests"
SCENES = sorted(TESTS.glob("RigidBodies_*/*.gltf"))
SECONDS = 4.0

pytestmark = pytest.mark.skipif(not SCENES, reason=f"{TESTS} is not here")


def scene(family: str, number: int) -> Path:
    return TESTS / f"RigidBodies_{family}" / f"RigidBodies_{family}_{number:02d}.gltf"


@pytest.fixture(scope="module")
def traces(tmp_path_factory: pytest.TempPathFactory):
    cache: dict[Path, Trace] = {}

    def get(path: Path, seconds: float = SECONDS) -> Trace:
        if path not in cache:
            cache[path] = run(path, tmp_path_factory.mktemp(path.stem), seconds)
        return cache[path]

    return get


def at_rest(trace: Trace, i: int, speed: float = 0.05) -> bool:
    return float(np.linalg.norm(trace.velocity(i))) < speed


# -- ColliderTypeMatrix: every static shape x every dynamic shape -------------------------

#: Scenes where the engine does not do what the README says yet, and why.
KNOWN: dict[tuple[str, int], str] = {}


def known(family: str, number: int) -> None:
    why = KNOWN.get((family, number))
    if why:
        pytest.xfail(why)


@pytest.mark.parametrize("number", range(36))
def test_collider_type_matrix(traces, number: int) -> None:
    """The dynamic body comes to rest on the static geometry: its lowest point on the
    static's top (within 3 cm), where it fell (within 25 cm sideways), not moving."""
    known("ColliderTypeMatrix", number)
    trace = traces(scene("ColliderTypeMatrix", number))
    assert trace.errors == 0
    (dyn,), (static,) = trace.dynamic(), trace.static()
    low, _ = trace.z_range(dyn)
    _, top = trace.z_range(static)
    assert abs(low - top) < 0.03, f"lowest point {low:.3f} m, the static's top {top:.3f} m"
    drift = np.linalg.norm(trace.position[-1, dyn, :2] - trace.position[0, dyn, :2])
    assert drift < 0.25, f"slid {drift:.2f} m sideways"
    assert at_rest(trace, dyn)


# -- CollisionFilter -------------------------------------------------------------------

@pytest.mark.parametrize("number", range(4))
def test_collision_filter(traces, number: int) -> None:
    """Two bodies fall onto one static box; their filters differ. 00/01 (one collider
    each): one rests on the box, the other passes through it. 02/03 (two colliders each,
    the second body upside down): each body has one collider that meets the box, so one
    rests on it and the other rests on it partly sunk in (its other collider inside)."""
    known("CollisionFilter", number)
    trace = traces(scene("CollisionFilter", number))
    (static,) = trace.static()
    bottom, top = trace.z_range(static)
    lows = {i: trace.z_range(i)[0] for i in trace.dynamic()}
    resting = [i for i, low in lows.items() if abs(low - top) < 0.03 and at_rest(trace, i)]
    assert len(resting) == 1, {trace.names[i]: round(v, 2) for i, v in lows.items()}
    (other,) = set(lows) - set(resting)
    if number < 2:
        assert trace.z_range(other)[1] < bottom  # through it, falling on
    else:
        assert lows[other] < top - 0.5 and trace.position[-1, other, 2] > bottom
        assert at_rest(trace, other)


# -- Joint -----------------------------------------------------------------------------

def _joint(trace: Trace):
    (joint, a, b), = trace.joints
    return joint, trace.index(a), None if b is None else trace.index(b)


def _rotation_axis(trace: Trace, i: int, frame: int = -1) -> tuple[float, np.ndarray]:
    """How far (degrees) and about which world axis body ``i`` turned since frame 0."""
    r = quat_to_matrix(trace.orientation[frame, i]) @ quat_to_matrix(
        trace.orientation[0, i]).T
    angle = float(np.degrees(np.arccos(np.clip((np.trace(r) - 1) / 2, -1, 1))))
    axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    norm = np.linalg.norm(axis)
    return angle, axis / norm if norm > 1e-12 else axis


def _anchor_gap(trace: Trace, joint, i: int) -> float:
    """How far the joint's anchor, carried by body ``i``, strayed from where it started
    (the most over the run)."""
    rel = quat_to_matrix(trace.orientation[0, i]).T @ (np.asarray(joint.anchor)
                                                       - trace.position[0, i])
    return max(float(np.linalg.norm(trace.position[f, i] + quat_to_matrix(
        trace.orientation[f, i]) @ rel - np.asarray(joint.anchor)))
        for f in range(len(trace.times)))


def _widest(trace: Trace, i: int) -> int:
    """The frame where body ``i`` had turned furthest from its start."""
    return int(np.argmax([trace.turned(i, f) for f in range(len(trace.times))]))


@pytest.mark.parametrize("number", range(11))
def test_joint(traces, number: int) -> None:
    """The dynamic body hangs from the static one by the joint the README names."""
    known("Joint", number)
    trace = traces(scene("Joint", number))
    assert trace.errors == 0
    (dyn,) = trace.dynamic()
    joint, *_ = _joint(trace)
    moved = trace.position[-1, dyn] - trace.position[0, dyn]
    angle, axis = _rotation_axis(trace, dyn, _widest(trace, dyn))
    free = np.asarray(joint.axis, float)
    free = free / np.linalg.norm(free)
    if number in (0, 7):  # fixed; a stiff spring (limits 0..1 m) holding its rest
        assert np.linalg.norm(moved) < 0.02 and angle < 1.0
    elif number == 1:  # ball and socket: it swings about the anchor, which holds
        assert angle > 5.0 and _anchor_gap(trace, joint, dyn) < 0.02
    elif number in (2, 3, 4, 8):  # hinges: swinging about the joint's axis only
        assert _anchor_gap(trace, joint, dyn) < 0.02
        assert angle > 10.0 and abs(float(axis @ free)) > 0.999, (angle, axis, free)
    elif number in (5, 6, 10):  # prismatic: sliding along the axis, not turning
        assert np.linalg.norm(np.cross(moved, free)) < 0.01 and angle < 1.0
        assert np.linalg.norm(moved) > 0.1
    elif number == 9:  # an angular drive to pi/2 rad/s: it turns, about the axis
        assert angle > 30.0 and abs(float(axis @ free)) > 0.999


# -- Materials -------------------------------------------------------------------------

def _bounce(trace: Trace, i: int) -> float:
    """How high body ``i`` rose after its first fall stopped (m above that lowest point)."""
    z = trace.position[:, i, 2]
    first = int(np.argmax(np.diff(z) > 0)) if np.any(np.diff(z) > 0) else len(z) - 1
    return float(z[first:].max() - z[first])


@pytest.mark.parametrize("number", range(3))
def test_materials(traces, number: int) -> None:
    """Two bodies alike but for their material. 00: the one of restitution 1 bounces
    higher (the other's 0 combined by maximum with the ground's 0.5 bounces too, lower);
    01: restitution 0.5 combined by minimum with the ground's 0 does not bounce, combined
    by maximum it does; 02: on a slope the low-friction body slides away, the other
    stays."""
    known("Materials", number)
    trace = traces(scene("Materials", number), 5.0)
    a, b = trace.index("node0"), trace.index("node1")
    if number == 0:
        assert _bounce(trace, b) > 2 * _bounce(trace, a) > 0.2
    elif number == 1:
        assert _bounce(trace, a) < 0.05 and _bounce(trace, b) > 0.5
    else:
        slid = [np.linalg.norm(trace.position[-1, i] - trace.position[0, i]) for i in (a, b)]
        assert slid[0] > 5.0 and slid[1] < 0.05


# -- MotionProperties ------------------------------------------------------------------

@pytest.mark.parametrize("number", range(8))
def test_motion_properties(traces, number: int) -> None:
    """00: gravity factor 0 (no gravity): it stays; 01/03: a linear velocity, kept (no
    gravity, no damping); 02/04: an angular velocity, kept, in place; 05: kinematic: it
    stays; 06: two collisions, 1 kg and 100 kg at 5 m/s into 1 kg at rest: momentum kept,
    the heavy one hardly slowed; 07: inertia [0 0 0] (infinite): it never turns."""
    known("MotionProperties", number)
    trace = traces(scene("MotionProperties", number))
    assert trace.errors == 0
    bodies = [i for i, k in enumerate(trace.kinds) if k != "static"]
    t = trace.times[-1]
    if number in (0, 5):
        (i,) = bodies
        assert np.linalg.norm(trace.position[-1, i] - trace.position[0, i]) < 1e-6
        assert trace.turned(i) < 1e-3
    elif number in (1, 3):
        (i,) = bodies
        assert np.linalg.norm(trace.position[-1, i] - trace.position[0, i]) == \
            pytest.approx(1.0 * t, rel=1e-3)
        assert trace.turned(i) < 1e-3
    elif number in (2, 4):
        (i,) = bodies
        assert np.linalg.norm(trace.position[-1, i] - trace.position[0, i]) < 1e-6
        angle, _ = _rotation_axis(trace, i)
        expected = np.degrees(1.0 * t) % 360
        assert min(abs(angle - expected), abs(360 - expected - angle)) < 1.0
    elif number == 6:
        mass = {i: float(trace.bodies[i].mass) for i in bodies}
        v = {i: trace.velocity(i)[0] for i in bodies}
        heavy = max(bodies, key=lambda i: mass[i])
        assert sum(mass[i] * v[i] for i in bodies) == pytest.approx(
            5.0 * sum(mass[i] for i in bodies if trace.position[0, i, 0] < -1), rel=0.02)
        assert v[heavy] > 4.8
    elif number == 7:
        (i,) = [i for i in bodies if trace.kinds[i] == "dynamic"]
        assert trace.turned(i) < 0.5
        low, _ = trace.z_range(i)
        _, top = trace.z_range(trace.static()[0])
        assert abs(low - top) < 0.03 and at_rest(trace, i)


@pytest.mark.parametrize("number", [2, 3])
def test_compound_collision_filters_in_2d(number: int, tmp_path: Path) -> None:
    """pymunk keeps each collider's own filter too: of 02/03's two bodies one rests on the
    box, the other 2 m lower (its lower collider inside the box), neither falls through."""
    pytest.importorskip("pymunk")
    trace = run(scene("CollisionFilter", number), tmp_path, 3.0, backend="pymunk")
    (static,) = trace.static()
    bottom, top = trace.z_range(static)
    heights = sorted(float(trace.position[-1, i, 2]) for i in trace.dynamic())
    assert heights[0] > bottom and heights[1] - heights[0] == pytest.approx(2.0, abs=0.05)
    assert all(at_rest(trace, i) for i in trace.dynamic())
