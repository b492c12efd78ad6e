"""OdeBackend as a user of the API sees it: shapes, meshes, queries, errors and faults."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from components import Joint, MaterialProps, Physical, Shape
from engine.physics.backend import BodyState, WorldSettings

ode3d = pytest.importorskip("engine.physics.ode3d")
OdeBackend = ode3d.OdeBackend

I4 = np.array([1.0, 0.0, 0.0, 0.0])


def make(**settings: object) -> OdeBackend:
    settings.setdefault("auto_sleep", False)
    return OdeBackend(WorldSettings(**settings))  # type: ignore[arg-type]


def run(b: OdeBackend, steps: int, dt: float = 1 / 60) -> None:
    for _ in range(steps):
        b.step(dt)


def z_of(b: OdeBackend, key: int) -> float:
    s = b.read_state()
    return float(s.position[int(np.flatnonzero(s.keys == key)[0]), 2])


@pytest.mark.parametrize(("shape", "rest_z"), [
    (Shape("sphere", (0.3,)), 0.3),
    (Shape("box", (0.4, 0.6, 0.8)), 0.4),
    (Shape("capsule", (0.2, 0.6)), 0.5),  # standing on a cap: r + length/2
    (Shape("cylinder", (0.2, 0.6)), 0.3),
])
def test_primitives_rest_on_a_keyless_ground_plane(shape: Shape, rest_z: float) -> None:
    b = make()
    b.add_static_plane()
    b.add_body(1, Physical(shapes=[shape]), np.array([0, 0, rest_z + 0.05]), I4)
    run(b, 120)
    assert z_of(b, 1) == pytest.approx(rest_z, abs=0.003)
    assert set(b.contacts()["b"]) == {-1}


def add_mesh_ground(b: OdeBackend, key: int) -> None:
    """A static 10 m square of two triangles at z = 0."""
    quad = np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], float)
    b.add_body(key, Physical(kind="static", mass=None,
                             shapes=[Shape("mesh", vertices=quad,
                                           faces=np.array([[0, 1, 2], [0, 2, 3]]))]),
               np.zeros(3), I4)


def test_static_trimesh_ground_and_dynamic_trimesh_body() -> None:
    b = make()
    add_mesh_ground(b, 1)
    b.add_body(2, Physical(shapes=[Shape("box", (0.5, 0.5, 0.5))]), np.array([0, 0, 1.0]), I4)
    ico = trimesh.creation.icosphere(subdivisions=2, radius=0.4)
    dense = Physical(mass=None, material=MaterialProps(density=500.0),
                     shapes=[Shape("mesh", vertices=ico.vertices, faces=ico.faces)])
    b.add_body(3, dense, np.array([2.0, 0, 1.0]), I4)
    run(b, 120)
    assert z_of(b, 2) == pytest.approx(0.25, abs=0.01)
    assert z_of(b, 3) == pytest.approx(0.4, abs=0.02)
    # mass from density and the mesh volume: an impulse J gives dv = J / (rho V)
    b2 = make(gravity=(0, 0, 0))
    b2.add_body(3, dense, np.zeros(3), I4)
    b2.add_impulse(3, np.array([1.0, 0, 0]))
    b2.step(1 / 60)
    assert b2.read_state().linear_velocity[0, 0] == pytest.approx(1 / (500 * ico.volume),
                                                                   rel=1e-6)


def test_a_convex_hull_rests_on_a_static_trimesh() -> None:
    """ODE needs the mesh's edge angles for hull-mesh contacts; without them it aborted
    the process the first time the two touched."""
    b = make()
    slab = trimesh.creation.box((2, 2, 0.2)).subdivide().subdivide()  # top face at z = 0
    b.add_body(1, Physical(kind="static", mass=None, shapes=[Shape(
        "mesh", vertices=slab.vertices - [0, 0, 0.1], faces=slab.faces)]), np.zeros(3), I4)
    cube = trimesh.creation.box((0.4, 0.4, 0.4))
    b.add_body(2, Physical(shapes=[Shape("hull", vertices=cube.vertices, faces=cube.faces)]),
               np.array([0, 0, 0.5]), I4)
    run(b, 120)
    assert z_of(b, 2) == pytest.approx(0.2, abs=0.01)


def test_convex_hull_body_settles_on_a_face() -> None:
    b = make()
    b.add_static_plane()
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5)
                        for z in (-0.5, 0.5)])
    inside = np.random.default_rng(0).uniform(-0.4, 0.4, (20, 3))  # dropped by the hull
    hull = Physical(mass=1.0, shapes=[Shape("hull", vertices=np.vstack([corners, inside]))])
    b.add_body(1, hull, np.array([0, 0, 1.0]), I4)
    run(b, 180)
    assert z_of(b, 1) == pytest.approx(0.5, abs=0.01)
    hit = b.raycast(np.array([0, 0, 3.0]), np.array([0, 0, -1.0]), 10)
    assert hit is not None and hit.key == 1 and hit.position[2] == pytest.approx(1.0, abs=0.01)


def test_raycast_ignores_a_body_and_respects_the_mask() -> None:
    b = make(gravity=(0, 0, 0))
    b.add_body(1, Physical(shapes=[Shape("sphere", (0.5,))]), np.array([0, 0, 2.0]), I4)
    low = Physical(shapes=[Shape("box", (1, 1, 1))], category=4)
    b.add_body(2, low, np.array([0, 0, 0.0]), I4)
    down = np.array([0, 0, -1.0])
    assert b.raycast(np.array([0, 0, 5.0]), down, 10).key == 1
    hit = b.raycast(np.array([0, 0, 5.0]), down, 10, ignore=1)
    assert hit.key == 2 and hit.distance == pytest.approx(4.5)
    assert b.raycast(np.array([0, 0, 5.0]), down, 10, ignore=1, mask=~4) is None
    assert b.raycast(np.array([0, 0, 5.0]), down, 2.0) is None  # too short


def test_static_body_can_be_moved_and_geometry_follows() -> None:
    b = make()
    b.add_body(1, Physical(kind="static", mass=None,
                           shapes=[Shape("box", (1, 1, 1), offset=(1.0, 0, 0))]),
               np.zeros(3), I4)
    quarter = np.array([math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)])
    b.set_pose(1, np.array([0, 0, 5.0]), quarter)  # the box now sits at (0, 1, 5)
    hit = b.raycast(np.array([0, 1.0, 10.0]), np.array([0, 0, -1.0]), 20)
    assert hit is not None and hit.key == 1 and hit.position[2] == pytest.approx(5.5)


def test_write_state_accepts_any_key_order_and_rejects_unknown_keys() -> None:
    b = make(gravity=(0, 0, 0))
    for k in (5, 7, 9):
        b.add_body(k, Physical(shapes=[Shape("sphere", (0.1,))]), np.zeros(3), I4)
    keys = np.array([9, 5])
    pos = np.array([[9.0, 0, 0], [5.0, 0, 0]])
    b.write_state(BodyState.from_arrays(keys, pos, np.tile(I4, (2, 1)), np.zeros((2, 3)),
                                        np.array([[0, 0, 1.0], [0, 0, 2.0]])))
    s = b.read_state()
    got = dict(zip(s.keys.tolist(), s.position[:, 0].tolist(), strict=True))
    assert got == {5: 5.0, 7: 0.0, 9: 9.0}
    with pytest.raises(KeyError, match="123"):
        b.write_state(BodyState.from_arrays(np.array([123]), np.zeros((1, 3)), I4[None],
                                            np.zeros((1, 3)), np.zeros((1, 3))))
    out = np.empty((3, 13))
    np.testing.assert_array_equal(b.read_state_into(out), s.keys)
    np.testing.assert_array_equal(out, s.table)


def test_exploding_joint_is_reported_reset_and_disabled_and_the_world_goes_on() -> None:
    b = make()
    b.add_static_plane()
    b.add_body(1, Physical(shapes=[Shape("box", (0.2, 0.2, 0.2))]), np.array([0, 0, 3.0]), I4)
    b.add_body(2, Physical(shapes=[Shape("sphere", (0.1,))]), np.array([1.0, 0, 3.0]), I4)
    b.add_joint(9, Joint(kind="ball", body_a=1, anchor=(0, 0, 3.5)))
    run(b, 10)
    before = b.read_state()
    # teleporting a jointed body 1000 km away: the joint's error correction flings it
    b.set_pose(1, np.array([1e6, 0, 3.0]), I4)
    b.step(1 / 60)
    faults = b.take_faults()
    assert [k for k, _ in faults] == [1] and "runaway" in faults[0][1]
    assert b.take_faults() == []
    after = b.read_state()
    np.testing.assert_array_equal(after.position[0], before.position[0])
    np.testing.assert_array_equal(after.linear_velocity[0], 0.0)
    assert b.is_sleeping(1)
    assert after.position[1, 2] < before.position[1, 2]  # the other body kept falling
    b.remove_joint(9)
    run(b, 60)
    assert b.take_faults() == []
    assert z_of(b, 2) == pytest.approx(0.1, abs=0.01)


def test_loads_and_speeds_that_would_overflow_are_refused() -> None:
    b = make()
    b.add_body(1, Physical(shapes=[Shape("box", (0.2, 0.2, 0.2))]), np.array([0, 0, 3.0]), I4)
    with pytest.raises(ValueError, match="body 1: force or torque"):
        b.add_torque(1, np.array([1e308, 1e308, 1e308]))
    with pytest.raises(ValueError, match="body 1: velocity"):
        b.set_velocity(1, np.zeros(3), np.array([1e300, 0, 0]))
    with pytest.raises(ValueError, match="non-finite"):
        b.write_state(BodyState.from_arrays(np.array([1]), np.array([[np.nan, 0, 0]]),
                                            I4[None], np.zeros((1, 3)), np.zeros((1, 3))))
    b.add_force(1, np.array([0, 0, 1.0]))  # the refused torque was discarded, others work
    run(b, 30)
    assert b.take_faults() == []
    assert np.all(np.isfinite(b.read_state().position))


def test_removing_a_body_removes_its_joints() -> None:
    b = make()
    b.add_body(1, Physical(), np.array([0, 0, 1.0]), I4)
    b.add_body(2, Physical(), np.array([1.0, 0, 1.0]), I4)
    b.add_joint(10, Joint(kind="ball", body_a=1, body_b=2, anchor=(0.5, 0, 1.0)))
    b.remove_body(2)
    assert not b.has_joint(10)
    run(b, 5)
    assert b.body_count() == 1


@pytest.mark.parametrize(("physical", "message"), [
    (Physical(shapes=[Shape("plane", (0, 0, 1, 0))]), "plane"),
    (Physical(shapes=[Shape("blob")]), "unknown shape 'blob'"),
    (Physical(shapes=[Shape("box", (1.0, -1.0, 1.0))]), "positive"),
    (Physical(kind="floating"), "unknown kind 'floating'"),
    (Physical(shapes=[Shape("mesh", vertices=np.zeros((3, 3)), faces=np.array([[0, 1, 5]]))]),
     "out of range"),
    (Physical(shapes=[Shape("hull", vertices=np.zeros((4, 3)))]), "convex hull"),
])
def test_bad_bodies_are_refused_with_a_clear_error(physical: Physical, message: str) -> None:
    b = make()
    with pytest.raises(ValueError, match=message) as err:
        b.add_body(42, physical, np.zeros(3), I4)
    assert "body 42" in str(err.value)
    assert b.body_count() == 0
    b.add_body(42, Physical(), np.zeros(3), I4)  # the key is free again


def test_bad_joints_are_refused() -> None:
    b = make()
    b.add_body(1, Physical(), np.zeros(3), I4)
    with pytest.raises(ValueError, match="unknown kind 'weld'"):
        b.add_joint(1, Joint(kind="weld", body_a=1))
    with pytest.raises(KeyError, match="no body with key 99"):
        b.add_joint(1, Joint(kind="ball", body_a=99))
    with pytest.raises(ValueError, match="has no motor"):
        b.add_joint(2, Joint(kind="ball", body_a=1))
        b.set_motor(2, 1.0, 1.0)
    with pytest.raises(KeyError):
        b.joint_state(77)


def test_closed_backend_refuses_work() -> None:
    b = make()
    b.close()
    with pytest.raises(RuntimeError, match="closed"):
        b.step(1 / 60)


def test_damping_and_per_body_gravity() -> None:
    """ODE damping scales velocity by (1 - d) per step; gravity=False bodies float."""
    b = make()
    b.add_body(1, Physical(shapes=[Shape("sphere", (0.1,))], linear_damping=0.1,
                           angular_damping=0.2, gravity=False), np.zeros(3), I4)
    b.add_body(2, Physical(shapes=[Shape("sphere", (0.1,))]), np.array([5.0, 0, 0]), I4)
    b.set_velocity(1, np.array([1.0, 0, 0]), np.array([0, 0, 1.0]))
    run(b, 10)
    s = b.read_state()
    assert s.linear_velocity[0, 0] == pytest.approx(0.9**10, rel=1e-9)
    assert s.angular_velocity[0, 2] == pytest.approx(0.8**10, rel=1e-9)
    assert s.linear_velocity[0, 2] == 0.0
    assert s.linear_velocity[1, 2] == pytest.approx(-9.81 * 10 / 60)


def test_a_world_with_meshes_steps_on_another_thread() -> None:
    """The physics thread of threaded mode gets ODE's per-thread collision data."""
    import threading

    b = make()
    add_mesh_ground(b, 1)
    ico = trimesh.creation.icosphere(subdivisions=1, radius=0.3)
    b.add_body(2, Physical(shapes=[Shape("mesh", vertices=ico.vertices, faces=ico.faces)]),
               np.array([0, 0, 1.0]), I4)
    worker = threading.Thread(target=run, args=(b, 120))
    worker.start()
    worker.join()
    assert z_of(b, 2) == pytest.approx(0.3, abs=0.02)


def _servo_rig(kind: str = "hinge", gravity: bool = False, mass: float = 1.0) -> OdeBackend:
    """A 1 m rod (centre 0.5 m out along +x) on a joint at the origin to the world:
    a hinge about +y, or a universal (+y on the rod, +z on the world)."""
    b = make()
    b.add_body(1, Physical(mass=mass, shapes=[Shape("box", (1.0, 0.05, 0.05))],
                           gravity=gravity), np.array([0.5, 0.0, 0.0]), I4)
    b.add_joint(2, Joint(kind=kind, body_a=1, anchor=(0, 0, 0), axis=(0, 1, 0),
                         axis2=(0, 0, 1)))
    return b


def _servo(b: OdeBackend, target: tuple[float, float], rate: tuple[float, float],
           torque: float, tau: float = 0.03) -> None:
    b.set_servos(np.array([2]), np.array([[*target, *rate, torque, tau, 30.0]]))


def test_a_servo_brings_a_hinge_to_its_angle_and_follows_a_moving_one() -> None:
    b = _servo_rig()
    _servo(b, (0.5, 0.0), (0.0, 0.0), 50.0)
    run(b, 60, 1 / 120)
    assert b.joint_state(2)[0] == pytest.approx(0.5, abs=1e-3)
    _servo(b, (0.5, 0.0), (1.0, 0.0), 50.0)  # the target moves on at 1 rad/s each step
    run(b, 60, 1 / 120)
    angle, rate = b.joint_state(2)
    assert angle == pytest.approx(1.0, abs=0.01) and rate == pytest.approx(1.0, abs=0.01)


def test_a_servo_pushes_with_no_more_than_its_torque() -> None:
    """A 1 kg rod held level needs 4.9 N·m: 10 hold it at its target, 2 do not."""
    for torque, holds in ((10.0, True), (2.0, False)):
        b = _servo_rig(gravity=True)
        _servo(b, (0.0, 0.0), (0.0, 0.0), torque)
        run(b, 60, 1 / 120)
        assert (abs(b.joint_state(2)[0]) < 0.01) is holds


def test_a_universal_joint_s_servo_turns_both_axes() -> None:
    b = _servo_rig("universal")
    _servo(b, (0.3, -0.2), (0.0, 0.0), 50.0)
    run(b, 120, 1 / 120)
    assert b.joint_state(2)[0] == pytest.approx(0.3, abs=1e-3)
    rod = b.read_state().orientation[0]
    heading = (2.0 * (rod[1] * rod[2] + rod[0] * rod[3]), 1.0 - 2.0 * (rod[2] ** 2 + rod[3] ** 2))
    assert abs(math.atan2(*heading)) == pytest.approx(0.2, abs=1e-3)  # its x about +z


def test_only_hinges_and_universal_joints_take_a_servo() -> None:
    b = make()
    b.add_body(1, Physical(shapes=[Shape("sphere", (0.1,))]), np.zeros(3), I4)
    b.add_joint(2, Joint(kind="ball", body_a=1))
    with pytest.raises(ValueError, match="only a hinge or a universal joint takes a servo"):
        _servo(b, (0.0, 0.0), (0.0, 0.0), 1.0)


def _chain_or_stack(chain: bool, **settings: object) -> np.ndarray:
    """Poses after 60 steps: a chain of 14 hinged rods in the air (joints only, 70 rows:
    more than exact_rows), or 3 boxes stacked on a plane (contacts)."""
    b = make(**settings)
    if chain:
        for i in range(14):
            b.add_body(i + 1, Physical(shapes=[Shape("box", (0.1, 0.02, 0.02))]),
                       np.array([0.1 * i + 0.05, 0.0, 2.0]), I4)
            b.add_joint(100 + i, Joint(kind="hinge", body_a=i + 1, body_b=i or None,
                                       anchor=(0.1 * i, 0.0, 2.0), axis=(0, 1, 0)))
    else:
        b.add_body(50, Physical(kind="static", shapes=[Shape("plane", (0, 0, 1, 0))]),
                   np.zeros(3), I4)
        for i in range(3):
            b.add_body(i + 1, Physical(shapes=[Shape("box", (0.2, 0.2, 0.2))]),
                       np.array([0.01 * i, 0.0, 0.1 + 0.2 * i]), I4)
    run(b, 60, 1 / 120)
    return np.hstack([b.read_state().position, b.read_state().orientation])


def test_contact_iterations_solve_islands_with_contacts_and_only_them() -> None:
    """With contact_iterations 40 over the world's 20, a stack is solved as at 40 and a
    chain of joints alone as at 20 (bit for bit: one pass each, the same seed)."""
    more = {"iterations": 20, "contact_iterations": 40, "solver_seed": 7}
    assert (_chain_or_stack(True, **more) ==
            _chain_or_stack(True, iterations=20, solver_seed=7)).all()
    stack = _chain_or_stack(False, **more)
    assert (stack == _chain_or_stack(False, iterations=40, solver_seed=7)).all()
    assert (stack != _chain_or_stack(False, iterations=20, solver_seed=7)).any()
