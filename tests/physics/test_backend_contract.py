"""The DynamicsBackend contract, checked against physics on every backend that imports.

Every scene moves in the X–Z plane (Z up) with hinge axes along Y, so ODE in 3D and
pymunk in the 2D side view must give the same answers. Sign conventions checked here
(the engine relies on them): a hinge angle is body_a's rotation about the joint axis
relative to body_b (right-handed: about +Y, X turns toward −Z), a slider's position
is ``(p_a − p_b)·axis``, both zero when the joint is made; a contact's ``b`` is the
static side (its key, or −1 for keyless static world), its normal points from b
toward a.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from components import Joint, MaterialProps, Physical, Shape
from engine.physics.backend import (
    CONTACT_DTYPE,
    BodyState,
    DynamicsBackend,
    MaterialPair,
)

# a failing pymunk callback is only printed by cffi: make it fail the test
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")


def test_implements_protocol(any_backend: DynamicsBackend) -> None:
    assert isinstance(any_backend, DynamicsBackend)
    assert isinstance(any_backend.name, str) and any_backend.name


def test_read_state_into_fills_a_callers_table_with_cached_keys(kit, any_backend) -> None:
    backend = any_backend
    for key in (5, 3, 9):
        kit.add(backend, key, kit.sphere(), (float(key), 0.0, 2.0), kit.quat_y(0.1 * key))
    backend.set_velocity(3, np.array([1.0, 0.0, 0.5]), np.array([0.0, 2.0, 0.0]))
    backend.step(1 / 60)
    table = np.full((5, 13), np.nan)  # room to spare: only the first rows are written
    keys = backend.read_state_into(table)
    state = backend.read_state()
    np.testing.assert_array_equal(keys, state.keys)
    np.testing.assert_array_equal(table[:3], state.table)
    assert np.isnan(table[3:]).all()
    backend.step(1 / 60)
    assert backend.read_state_into(table) is keys  # the same array while no body comes or goes
    with pytest.raises(ValueError):
        keys[0] = 1  # read-only: every caller shares it
    kit.add(backend, 7, kit.sphere(), (7.0, 0.0, 2.0))
    assert sorted(backend.read_state_into(table).tolist()) == [3, 5, 7, 9]
    with pytest.raises(ValueError, match="at least"):
        backend.read_state_into(np.zeros((3, 13)))


def test_gravity_off_floats_and_back_on_falls(kit, any_backend) -> None:
    backend, dt = any_backend, 1 / 240
    kit.add(backend, 1, kit.sphere(), (0.0, 0.0, 5.0))
    kit.add(backend, 2, kit.sphere(), (1.0, 0.0, 5.0))
    backend.set_gravity_enabled(1, False)
    kit.run(backend, 0.5, dt)
    assert kit.row(backend, 1)["position"][2] == pytest.approx(5.0, abs=1e-12)
    assert kit.row(backend, 2)["position"][2] < 5.0 - 0.5 * kit.G * 0.25 + kit.G * dt * 0.5
    backend.set_gravity_enabled(1, True)
    kit.run(backend, 0.5, dt)
    assert kit.row(backend, 1)["linear"][2] == pytest.approx(-kit.G * 0.5, rel=1e-6)


def test_a_body_with_collisions_off_falls_through_the_floor(kit, backend) -> None:
    """Still simulated (it falls, rays miss it), colliding with nothing; back on, it lands."""
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((0.2, 0.2, 0.2)), (0.0, 0.0, 0.5))
    kit.add(backend, 2, kit.box((0.2, 0.2, 0.2)), (1.0, 0.0, 0.5))
    kit.add(backend, 3, kit.box((0.2, 0.2, 0.2)), (0.0, 0.0, 1.5))  # above 1, falls onto it
    backend.set_collision_enabled(1, False)
    hit = backend.raycast(np.array([0.0, 0.0, 3.0]), np.array([0.0, 0.0, -1.0]), 5.0,
                          ignore=3)
    assert hit is not None and hit.key == kit.GROUND  # not body 1, which is in the way
    kit.run(backend, 1.0, 1 / 240)
    assert kit.row(backend, 1)["position"][2] < -1.0  # through the floor
    assert kit.row(backend, 3)["position"][2] == pytest.approx(0.1, abs=0.01)  # and through 1
    assert kit.row(backend, 2)["position"][2] == pytest.approx(0.1, abs=0.01)
    assert not [c for c in backend.contacts() if 1 in (c["a"], c["b"])]
    backend.set_collision_enabled(2, False)
    backend.set_collision_enabled(2, True)  # back on: it still rests where it was
    kit.run(backend, 0.5, 1 / 240)
    assert kit.row(backend, 2)["position"][2] == pytest.approx(0.1, abs=0.01)


def test_free_fall_follows_z0_minus_half_g_t_squared(kit, backend: DynamicsBackend) -> None:
    dt, t, z0 = 1 / 240, 1.0, 10.0
    kit.add(backend, 1, kit.sphere(), (0.3, 0.7, z0))
    kit.run(backend, t, dt)
    r = kit.row(backend, 1)
    # semi-implicit Euler lags the parabola by g·dt·t/2; allow that and no more
    assert r["position"][2] == pytest.approx(z0 - kit.G * t * t / 2, abs=kit.G * dt * t)
    assert r["linear"][2] == pytest.approx(-kit.G * t, rel=1e-6)
    assert r["position"][0] == pytest.approx(0.3, abs=1e-9)
    assert r["position"][1] == pytest.approx(0.7, abs=1e-9)


def test_pendulum_period_matches_two_pi_sqrt_l_over_g(kit, backend: DynamicsBackend) -> None:
    length, amp, dt = 1.0, math.radians(5.0), 1 / 480
    pivot = (0.0, 0.0, 2.0)
    kit.add(backend, 1, kit.sphere(radius=0.05), (length * math.sin(amp), 0.0,
                                           pivot[2] - length * math.cos(amp)))
    backend.add_joint(10, kit.hinge(1, pivot))
    xs = []
    kit.run(backend, 6.5, dt, lambda i: xs.append(kit.row(backend, 1)["position"][0]))
    x = np.array(xs)
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))  # upward zero crossings
    frac = x[up] / (x[up] - x[up + 1])
    times = (up + frac) * dt
    period = float(np.mean(np.diff(times)))
    r2 = 0.4 * 0.05**2  # the sphere's own moment, per unit mass
    expected = 2 * math.pi * math.sqrt((length**2 + r2) / (kit.G * length)) * (1 + amp**2 / 16)
    assert len(up) >= 3
    assert period == pytest.approx(expected, rel=0.01)


@pytest.mark.parametrize(("angle_deg", "slides"), [(20.0, False), (35.0, True)])
def test_box_on_incline_slides_only_when_tan_theta_exceeds_mu(kit,
        make_backend, angle_deg: float, slides: bool) -> None:
    mu = 0.5
    backend = make_backend(material_pairs=[MaterialPair("block", "slope", friction=mu)])
    theta = math.radians(angle_deg)
    q = kit.quat_y(theta)  # the slope falls toward +X
    normal = np.array([math.sin(theta), 0.0, math.cos(theta)])
    downhill = np.array([math.cos(theta), 0.0, -math.sin(theta)])
    kit.add(backend, 1, kit.box((6.0, 1.0, 0.2), kind="static", mass=None, material="slope",
                        friction=mu), (0.0, 0.0, 0.0), q)
    start = normal * (0.1 + 0.1 + 0.002)
    kit.add(backend, 2, kit.box((0.2, 0.2, 0.2), material="block", friction=mu), tuple(start), q)
    t = 1.0
    kit.run(backend, t, 1 / 240)
    moved = float(np.dot(kit.row(backend, 2)["position"] - start, downhill))
    if slides:
        expected = 0.5 * kit.G * (math.sin(theta) - mu * math.cos(theta)) * t * t
        assert moved > 0.5 * expected
        assert moved < 1.5 * expected
    else:
        assert abs(moved) < 0.01


def test_bounce_height_is_e_squared_h(kit, make_backend) -> None:
    e, h, r = 0.8, 1.0, 0.1
    backend = make_backend(material_pairs=[MaterialPair("ball", "floor", bounce=e)])
    kit.add(backend, kit.GROUND, kit.ground_plane(material="floor"), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.sphere(radius=r, material="ball"), (0.0, 0.0, h + r))
    heights, bounced = [], [False]

    def watch(i: int) -> None:
        vz = kit.row(backend, 1)["linear"][2]
        if vz > 0:
            bounced[0] = True
        if bounced[0]:
            heights.append(kit.row(backend, 1)["position"][2] - r)

    kit.run(backend, 1.3, 1 / 480, watch)
    assert bounced[0]
    assert max(heights) == pytest.approx(e * e * h, rel=0.1)


def _bar(kit, backend: DynamicsBackend, key: int = 1, mass: float = 2.0) -> tuple[float, ...]:
    """A 1 m bar along +X whose left end sits on the pivot at (0, 0, 2)."""
    kit.add(backend, key, kit.box((1.0, 0.1, 0.1), mass=mass), (0.5, 0.0, 2.0))
    return (0.0, 0.0, 2.0)


def test_motorized_hinge_reaches_target_velocity_under_load(kit, backend: DynamicsBackend) -> None:
    pivot = _bar(kit, backend)  # gravity load: up to m·g·L/2 = 9.8 N·m
    backend.add_joint(10, kit.hinge(1, pivot, kind="motorized_hinge", motor_velocity=2.0,
                                motor_max_force=60.0))
    kit.run(backend, 0.25, 1 / 240)
    tip = kit.row(backend, 1)["position"]
    assert tip[2] < 2.0  # +2 rad/s about +Y swings X toward −Z
    rates = []
    kit.run(backend, 2.0, 1 / 240, lambda i: rates.append(backend.joint_state(10)[1]))
    assert np.mean(rates) == pytest.approx(2.0, rel=0.03)
    assert min(rates) > 1.7
    angle, _ = backend.joint_state(10)
    q = kit.row(backend, 1)["orientation"]
    assert abs(float(np.dot(q, kit.quat_y(angle)))) == pytest.approx(1.0, abs=1e-3)


def test_motor_torque_is_bounded(kit, backend: DynamicsBackend) -> None:
    pivot = _bar(kit, backend)
    backend.add_joint(10, kit.hinge(1, pivot, kind="motorized_hinge", motor_velocity=-2.0,
                                motor_max_force=3.0))  # too weak to lift 9.8 N·m
    kit.run(backend, 3.0, 1 / 240)
    angle, _ = backend.joint_state(10)
    assert angle > 0.5  # it hangs below the horizontal instead of turning upward


def test_set_motor_changes_target(kit, backend: DynamicsBackend) -> None:
    kit.add(backend, 1, kit.box((0.4, 0.4, 0.4), mass=1.0), (0.0, 0.0, 2.0))
    backend.add_joint(10, kit.hinge(1, (0.0, 0.0, 2.0), kind="motorized_hinge",
                                motor_velocity=1.0, motor_max_force=20.0))
    kit.run(backend, 0.5, 1 / 240)
    backend.set_motor(10, -3.0, 20.0)
    kit.run(backend, 0.5, 1 / 240)
    assert backend.joint_state(10)[1] == pytest.approx(-3.0, rel=0.02)


def test_hinge_limits_hold(kit, backend: DynamicsBackend) -> None:
    pivot = _bar(kit, backend)
    backend.add_joint(10, kit.hinge(1, pivot, low=-0.5, high=0.5))
    angles = []
    kit.run(backend, 2.0, 1 / 240, lambda i: angles.append(backend.joint_state(10)[0]))
    assert max(angles) < 0.55
    assert angles[-1] == pytest.approx(0.5, abs=0.05)


def test_slider_limits_hold(kit, backend: DynamicsBackend) -> None:
    kit.add(backend, 1, kit.box((0.2, 0.2, 0.2)), (0.0, 0.0, 2.0))
    backend.add_joint(10, Joint(kind="slider", body_a=1, axis=(0.0, 0.0, 1.0),
                                anchor=(0.0, 0.0, 2.0), low=-0.3, high=0.3))
    kit.run(backend, 1.5, 1 / 240)
    position, _ = backend.joint_state(10)
    r = kit.row(backend, 1)
    assert position == pytest.approx(-0.3, abs=0.02)
    assert r["position"][2] == pytest.approx(1.7, abs=0.02)
    assert r["position"][0] == pytest.approx(0.0, abs=1e-3)


def test_contacts_report_keys_impulse_and_normal(kit, backend: DynamicsBackend) -> None:
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.sphere(radius=0.1), (0.0, 0.0, 0.3))
    kit.add(backend, 2, kit.box((0.2, 0.2, 0.2)), (2.0, 0.0, 0.1005))
    kit.add(backend, 3, kit.box((0.2, 0.2, 0.2)), (2.0, 0.0, 0.302))
    seen: list[np.ndarray] = []
    kit.run(backend, 0.5, 1 / 240, lambda i: seen.append(backend.contacts().copy()))
    allc = np.concatenate(seen)
    assert allc.dtype == CONTACT_DTYPE
    ball = allc[(allc["a"] == 1) | (allc["b"] == 1)]
    assert len(ball) > 0
    assert set(ball["a"]) == {1}
    assert set(ball["b"]) <= {kit.GROUND, -1}
    assert ball["impulse"].max() > 0.0
    assert np.all(ball["normal"][:, 2] > 0.9)  # from the ground toward the ball
    assert np.all(np.abs(ball["position"][:, 2]) < 0.02)
    assert np.all(ball["depth"] >= 0.0)
    stack = allc[((allc["a"] == 2) & (allc["b"] == 3)) | ((allc["a"] == 3) & (allc["b"] == 2))]
    assert len(stack) > 0 and stack["impulse"].max() > 0.0
    # the upper box rests on the lower one: the normal points toward whichever is "a"
    upper_is_a = stack["a"] == 3
    assert np.all(np.where(upper_is_a, stack["normal"][:, 2], -stack["normal"][:, 2]) > 0.9)
    last = backend.contacts()
    assert np.all(last["impulse"] >= 0.0)


def test_kinematic_body_reaches_its_target_and_ignores_gravity(kit,
        backend: DynamicsBackend) -> None:
    kit.add(backend, 1, kit.box((0.5, 0.5, 0.5), kind="kinematic", mass=None), (0.0, 0.0, 1.0))
    target_q = kit.quat_y(0.4)
    backend.set_kinematic_target(1, np.array([1.0, 0.0, 1.5]), target_q, 0.5)
    kit.run(backend, 0.5, 1 / 60)
    r = kit.row(backend, 1)
    np.testing.assert_allclose(r["position"], [1.0, 0.0, 1.5], atol=1e-6)
    assert abs(float(np.dot(r["orientation"], target_q))) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("lead", [3, 2.5], ids=["three steps", "two and a half steps"])
def test_kinematic_body_stops_at_its_target(kit, any_backend: DynamicsBackend,
                                            lead: float) -> None:
    """One target, then many steps (threaded mode takes several a frame): it moves at a
    steady speed, arrives after ``lead`` steps (a part step taken slower) and stays there,
    exactly at the target and at rest; it never passes it."""
    backend, dt = any_backend, 1 / 60
    start = np.array([0.0, 0.0, 1.0])
    kit.add(backend, 1, kit.box((0.5, 0.5, 0.5), kind="kinematic", mass=None), tuple(start))
    target, turn = np.array([0.6, 0.0, 1.3]), kit.quat_y(0.4)
    backend.set_kinematic_target(1, target, turn, lead * dt)
    for k in range(1, 9):
        backend.step(dt)
        r = kit.row(backend, 1)
        if k < lead:
            np.testing.assert_allclose(r["position"], start + (target - start) * k / lead,
                                       atol=1e-9)
            np.testing.assert_allclose(r["linear"], (target - start) / (lead * dt), rtol=1e-9)
            continue
        np.testing.assert_allclose(r["position"], target, rtol=0, atol=1e-12)
        assert abs(float(np.dot(r["orientation"], turn))) == pytest.approx(1.0, abs=1e-12)
        assert not r["linear"].any() and not r["angular"].any(), f"moving after step {k}"
    backend.set_kinematic_target(1, start, kit.IDENTITY, dt)  # and a new target moves it
    backend.step(dt)
    np.testing.assert_allclose(kit.row(backend, 1)["position"], start, rtol=0, atol=1e-12)


def test_kinematic_body_pushes_dynamic_body(kit, backend: DynamicsBackend) -> None:
    kit.add(backend, kit.GROUND, kit.ground_plane(friction=0.0), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((0.5, 1.0, 0.5), kind="kinematic", mass=None), (0.0, 0.0, 0.25))
    kit.add(backend, 2, kit.box((0.5, 1.0, 0.5)), (0.8, 0.0, 0.2501))
    for _ in range(60):
        pos = kit.row(backend, 1)["position"] + np.array([1.0 / 60, 0.0, 0.0])
        backend.set_kinematic_target(1, pos, kit.IDENTITY, 1 / 60)
        backend.step(1 / 60)
    assert kit.row(backend, 2)["position"][0] > 1.2


def _scatter(kit, backend: DynamicsBackend) -> None:
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    for i in range(6):
        kit.add(backend, i + 1, kit.box((0.4, 0.4, 0.4)), (0.3 * i, 0.0, 0.5 + 0.45 * i),
                kit.quat_y(0.1 * i))
    kit.add(backend, 20, kit.sphere(radius=0.2), (-1.0, 0.0, 1.0))
    backend.set_velocity(20, np.array([1.0, 0.0, 0.5]), np.array([0.0, 2.0, 0.0]))


def test_state_round_trip(kit, make_backend) -> None:
    first = make_backend()
    kit.add(first, 1, kit.sphere(), (0.0, 0.5, 5.0))
    kit.add(first, 2, kit.box(), (3.0, -0.5, 5.0), kit.quat_y(0.3))
    first.set_velocity(1, np.array([1.0, 0.0, 2.0]), np.array([0.0, -1.5, 0.0]))
    first.set_velocity(2, np.array([-0.5, 0.0, 0.0]), np.array([0.0, 0.7, 0.0]))
    kit.run(first, 0.25, 1 / 120)
    saved = first.read_state()
    assert isinstance(saved, BodyState)
    assert sorted(saved.keys.tolist()) == [1, 2]
    saved.position[:] = 99.0  # fresh arrays: scribbling on them changes nothing inside
    saved = first.read_state()
    first.write_state(saved)
    again = first.read_state()
    for name in ("keys", "position", "orientation", "linear_velocity", "angular_velocity"):
        np.testing.assert_allclose(getattr(again, name), getattr(saved, name), atol=1e-12)
    kit.run(first, 0.25, 1 / 120)
    expected = first.read_state()

    second = make_backend()
    kit.add(second, 1, kit.sphere(), (0.0, 0.0, 0.0))
    kit.add(second, 2, kit.box(), (0.0, 0.0, 0.0))
    second.write_state(saved)
    kit.run(second, 0.25, 1 / 120)
    got = second.read_state()
    order = np.argsort(got.keys)
    ref = np.argsort(expected.keys)
    for name in ("position", "orientation", "linear_velocity", "angular_velocity"):
        np.testing.assert_allclose(getattr(got, name)[order], getattr(expected, name)[ref],
                                   atol=1e-9)


def test_two_runs_are_bit_identical(kit, make_backend) -> None:
    states, contacts = [], []
    for _ in range(2):
        backend = make_backend()
        _scatter(kit, backend)
        kit.run(backend, 1.5, 1 / 60)
        states.append(backend.read_state())
        contacts.append(backend.contacts())
    for name in ("keys", "position", "orientation", "linear_velocity", "angular_velocity"):
        assert np.array_equal(getattr(states[0], name), getattr(states[1], name)), name
    assert np.array_equal(contacts[0], contacts[1])


def test_bodies_come_and_go(kit, backend: DynamicsBackend) -> None:
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.sphere(), (0.0, 0.0, 0.5))
    kit.add(backend, 2, kit.sphere(), (1.0, 0.0, 0.5))
    backend.add_joint(10, kit.hinge(2, (1.0, 0.0, 1.0)))
    assert backend.body_count() == 3
    kit.run(backend, 0.1, 1 / 60)
    backend.remove_joint(10)
    backend.remove_body(2)
    backend.step(1 / 60)
    assert backend.body_count() == 2
    assert sorted(backend.read_state().keys.tolist()) == [1, kit.GROUND]
    with pytest.raises(KeyError):
        backend.set_pose(2, np.zeros(3), kit.IDENTITY)


def test_forces_torques_and_impulses(kit, make_backend) -> None:
    backend = make_backend(gravity=(0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.sphere(radius=0.1, mass=2.0), (0.0, 0.0, 0.0))
    for _ in range(60):
        backend.add_force(1, np.array([4.0, 0.0, 0.0]))
        backend.step(1 / 60)
    assert kit.row(backend, 1)["linear"][0] == pytest.approx(2.0, rel=1e-6)  # F t / m
    backend.add_impulse(1, np.array([0.0, 0.0, 2.0]))
    backend.step(1 / 60)
    assert kit.row(backend, 1)["linear"][2] == pytest.approx(1.0, rel=1e-6)
    inertia = 0.4 * 2.0 * 0.1**2
    for _ in range(30):
        backend.add_torque(1, np.array([0.0, 0.01, 0.0]))
        backend.step(1 / 60)
    assert kit.row(backend, 1)["angular"][1] == pytest.approx(0.01 * 0.5 / inertia, rel=1e-6)


def test_mass_from_density_when_mass_is_none(kit, make_backend) -> None:
    backend = make_backend(gravity=(0.0, 0.0, 0.0))
    body = Physical(mass=None, shapes=[Shape("box", (0.5, 0.4, 0.2))],
                    material=MaterialProps(density=500.0))
    kit.add(backend, 1, body, (0.0, 0.0, 0.0))
    backend.add_impulse(1, np.array([2.0, 0.0, 0.0]))
    backend.step(1 / 60)
    assert kit.row(backend, 1)["linear"][0] == pytest.approx(2.0 / (500.0 * 0.04), rel=1e-6)


def test_raycast_hits_nearest_body(kit, backend: DynamicsBackend) -> None:
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((1.0, 1.0, 1.0), kind="static", mass=None), (3.0, 0.0, 0.5))
    hit = backend.raycast(np.array([0.0, 0.0, 0.5]), np.array([1.0, 0.0, 0.0]), 10.0)
    assert hit is not None and hit.key == 1
    assert hit.distance == pytest.approx(2.5, abs=1e-6)
    assert hit.normal[0] == pytest.approx(-1.0, abs=1e-6)
    down = backend.raycast(np.array([0.0, 0.0, 2.0]), np.array([0.0, 0.0, -1.0]), 10.0)
    assert down is not None and down.key in (kit.GROUND, -1)
    assert down.position[2] == pytest.approx(0.0, abs=1e-6)
    assert backend.raycast(np.array([0.0, 0.0, 2.0]), np.array([0.0, 0.0, 1.0]), 10.0) is None


def test_collision_filter_and_disabled_pairs(kit, make_backend) -> None:
    backend = make_backend(material_pairs=[MaterialPair("ghost", "floor", collide=False)])
    kit.add(backend, kit.GROUND, kit.ground_plane(material="floor"), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.sphere(material="ghost"), (0.0, 0.0, 0.5))
    masked = kit.sphere()
    masked.category, masked.mask = 2, 0xFFFFFFFF & ~1
    kit.add(backend, 2, masked, (1.0, 0.0, 0.5))
    kit.add(backend, 3, kit.sphere(), (2.0, 0.0, 0.5))
    kit.run(backend, 1.0, 1 / 60)
    state = backend.read_state()
    z = dict(zip(state.keys.tolist(), state.position[:, 2].tolist(), strict=True))
    assert z[1] < -1.0 and z[2] < -1.0  # fell through
    assert z[3] == pytest.approx(0.1, abs=0.01)  # rests on the ground


def test_stack_comes_to_rest_and_sleeps(kit, make_backend) -> None:
    backend = make_backend(auto_sleep=True)
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    for i in range(3):
        kit.add(backend, i + 1, kit.box((0.5, 0.5, 0.5)), (0.0, 0.0, 0.25 + 0.501 * i))
    kit.run(backend, 4.0, 1 / 100)
    state = backend.read_state()
    assert not state.linear_velocity.any()  # asleep: at rest
    np.testing.assert_allclose(np.sort(state.position[state.keys != kit.GROUND, 2]),
                               [0.25, 0.75, 1.25], atol=0.02)
    # beyond the protocol, but both backends offer it
    assert all(backend.is_sleeping(k) for k in (1, 2, 3))
    backend.add_impulse(3, np.array([0.5, 0.0, 0.0]))
    backend.set_sleeping(3, False)
    backend.step(1 / 60)
    assert not backend.is_sleeping(3)


def test_wheel_on_motorized_hinge_rolls_at_omega_r(kit, backend: DynamicsBackend) -> None:
    r, omega = 0.2, 3.0
    along_y = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)  # local Z → world Y
    kit.add(backend, kit.GROUND, kit.ground_plane(friction=1.0), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((1.0, 0.2, 0.1), mass=2.0), (0.0, 0.0, r))
    for key, x in ((2, -0.4), (3, 0.4)):
        wheel = Physical(mass=1.0, shapes=[Shape("cylinder", (r, 0.1), rotation=along_y)],
                         material=MaterialProps(friction=1.0))
        kit.add(backend, key, wheel, (x, 0.0, r + 0.001))
        backend.add_joint(10 + key, kit.hinge(key, (x, 0.0, r + 0.001), b=1,
                                          kind="motorized_hinge", motor_velocity=omega,
                                          motor_max_force=20.0))
    kit.run(backend, 1.0, 1 / 240)
    speeds = []
    kit.run(backend, 1.0, 1 / 240, lambda i: speeds.append(kit.row(backend, 1)["linear"][0]))
    assert np.mean(speeds) == pytest.approx(omega * r, rel=0.05)


def test_a_cup_stands_still_on_a_table(kit, backend: DynamicsBackend) -> None:
    """A cylinder standing on a box (a cup on a table) comes to rest where it was put: its
    contacts must span its whole rim, not one side of it (it would rock and wander)."""
    kit.add(backend, 1, Physical(kind="static", shapes=[Shape("box", (1.2, 1.2, 0.05))]),
            (0.0, 0.0, 0.725))
    kit.add(backend, 2, Physical(mass=0.3, shapes=[Shape("cylinder", (0.08, 0.1))]),
            (0.0, 0.0, 0.8))
    kit.run(backend, 0.5, 1 / 120)
    settled = kit.row(backend, 2)["position"].copy()
    kit.run(backend, 4.5, 1 / 120)
    assert kit.row(backend, 2)["position"] == pytest.approx(settled, abs=1e-4)


def test_fixed_joint_holds_relative_pose(kit, backend: DynamicsBackend) -> None:
    kit.add(backend, 1, kit.box((0.4, 0.4, 0.4)), (0.0, 0.0, 3.0))
    kit.add(backend, 2, kit.sphere(radius=0.1), (0.5, 0.0, 3.0))
    backend.add_joint(10, Joint(kind="fixed", body_a=2, body_b=1, anchor=(0.5, 0.0, 3.0)))
    backend.set_velocity(1, np.array([0.0, 0.0, 1.0]), np.array([0.0, 2.0, 0.0]))
    kit.run(backend, 0.5, 1 / 240)
    box_pose, ball_pose = kit.row(backend, 1), kit.row(backend, 2)
    offset = ball_pose["position"] - box_pose["position"]
    assert float(np.linalg.norm(offset)) == pytest.approx(0.5, abs=0.01)
    assert abs(float(np.dot(box_pose["orientation"], ball_pose["orientation"]))) == \
        pytest.approx(1.0, abs=1e-3)


@pytest.mark.parametrize("to_world", [False, True], ids=["between bodies", "to the world"])
def test_joint_force_is_what_the_joint_carries(kit, backend: DynamicsBackend,
                                               to_world: bool) -> None:
    """A 2 kg ball hanging from a fixed joint: the joint holds it up with m g, and puts
    the opposite on whatever it hangs from; swinging on a hinge at ω it carries
    m (g + ω² L) at the bottom."""
    m, length = 2.0, 0.5
    kit.add(backend, 1, kit.sphere(radius=0.1, mass=m), (0.0, 0.0, 3.0 - length))
    if not to_world:
        kit.add(backend, 2, kit.box((0.2, 0.2, 0.2), kind="kinematic", mass=None),
                (0.0, 0.0, 3.0))
    support = None if to_world else 2
    backend.add_joint(10, Joint(kind="fixed", body_a=1, body_b=support, anchor=(0, 0, 3.0)))
    assert backend.joint_force(10) == pytest.approx([0, 0, 0])  # measured from now on
    kit.run(backend, 0.5, 1 / 240)
    assert backend.joint_force(10) == pytest.approx([0, 0, m * kit.G], rel=1e-3, abs=1e-6)
    backend.remove_joint(10)
    backend.add_joint(11, kit.hinge(1, (0.0, 0.0, 3.0), b=support))
    backend.joint_force(11)
    omega = 2.0
    backend.set_velocity(1, np.array([omega * length, 0.0, 0.0]), np.array([0, -omega, 0]))
    kit.run(backend, 0.01, 1 / 1000)  # (a velocity-level solver needs a step or two to
    # turn the ball: the first only holds its weight) 0.02 rad past the bottom
    expected = m * (kit.G + omega ** 2 * length)
    assert float(np.linalg.norm(backend.joint_force(11))) == pytest.approx(expected, rel=0.02)
    with pytest.raises(KeyError):
        backend.joint_force(99)


def test_six_dof_follows_target_with_bounded_force(kit, backend: DynamicsBackend) -> None:
    hand = kit.box((0.2, 0.2, 0.2), mass=1.0)
    hand.category, hand.mask = 2, 0xFFFFFFFF & ~2  # the hand ignores its own target
    target = kit.box((0.2, 0.2, 0.2), kind="kinematic", mass=None)
    target.category, target.mask = 2, 0
    kit.add(backend, 1, target, (0.0, 0.0, 1.0))
    kit.add(backend, 2, hand, (0.0, 0.0, 1.0))
    kit.add(backend, 3, kit.box((0.2, 1.0, 2.0), kind="static", mass=None), (1.0, 0.0, 1.0))
    backend.add_joint(10, Joint(kind="six_dof", body_a=2, body_b=1, anchor=(0.0, 0.0, 1.0),
                                motor_max_force=60.0))
    x = 0.0
    for _ in range(120):  # the target walks 0.5 m into the wall and stays there
        x = min(x + 0.01, 1.4)
        backend.set_kinematic_target(1, np.array([x, 0.0, 1.0]), kit.IDENTITY, 1 / 60)
        backend.step(1 / 60)
        if x < 0.6:
            assert abs(kit.row(backend, 2)["position"][0] - x) < 0.1
    hand_x = kit.row(backend, 2)["position"][0]
    assert 0.75 < hand_x < 0.85  # held at the wall face (0.9 − 0.1), force bounded
    assert abs(kit.row(backend, 2)["position"][2] - 1.0) < 0.1


def test_a_fixed_joint_holds_a_light_body_pulled_off_a_heavy_one(kit, backend) -> None:
    """A 0.45 kg palm fixed on a 50 kg crate's top, 0.2 m off its middle, pulled up with
    250 N: too little to lift the crate (490 N) or tip it over its far edge (250 N x 0.5 m
    < 490 N x 0.3 m), so it stays on the floor, and the joint keeps the palm where it was
    on it. (ODE carries the joint's offset as a lever on its first body: on the
    palm, 5000 times easier to turn than the crate, QuickStep let it stretch 0.2 m.)"""
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((0.6, 0.4, 0.5), mass=50.0), (0.0, 0.0, 0.25))
    kit.add(backend, 2, kit.box((0.09, 0.18, 0.03), mass=0.45), (0.2, 0.0, 0.515))
    backend.add_joint(10, Joint(kind="fixed", body_a=2, body_b=1, anchor=(0.2, 0.0, 0.515)))
    kit.run(backend, 0.2, 1 / 120)
    start = kit.row(backend, 2)["position"] - kit.row(backend, 1)["position"]
    kit.run(backend, 1.0, 1 / 120,
            lambda i: backend.add_force(2, np.array([0.0, 0.0, 250.0])))
    crate, palm = kit.row(backend, 1), kit.row(backend, 2)
    assert crate["position"][2] == pytest.approx(0.25, abs=2e-3)
    np.testing.assert_allclose(palm["position"] - crate["position"], start, atol=2e-3)


def test_offset_shapes_spin_about_their_centre_of_mass(kit, make_backend) -> None:
    backend = make_backend(gravity=(0.0, 0.0, 0.0))
    dumbbell = Physical(mass=1.0, shapes=[Shape("sphere", (0.1,)),
                                          Shape("sphere", (0.1,), offset=(1.0, 0.0, 0.0))])
    kit.add(backend, 1, dumbbell, (0.0, 0.0, 0.0))
    # apart in X too: in the plane (pymunk) bodies apart only in Y overlap and collide
    kit.add(backend, 2, dumbbell, (5.0, 3.0, 0.0))
    backend.add_impulse(1, np.array([0.0, 0.0, 1.0]))  # at the centre of mass: no spin
    backend.add_impulse(2, np.array([0.0, 0.0, 1.0]), np.array([5.0, 3.0, 0.0]))  # at origin
    backend.step(1 / 60)  # an impulse may be spread over the next step
    still, spun = kit.row(backend, 1), kit.row(backend, 2)
    assert still["angular"][1] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(still["linear"], [0.0, 0.0, 1.0], atol=1e-6)
    inertia = 2 * (0.4 * 0.5 * 0.1**2) + 2 * 0.5 * 0.5**2  # about the centre, 0.5 m out
    omega = 0.5 / inertia  # torque arm 0.5 m; about +Y the push at the origin turns X to −Z
    assert spun["angular"][1] == pytest.approx(omega, rel=1e-3)
    # the origin moves with the centre plus ω × (origin − centre), turned by φ so far
    q = spun["orientation"]
    phi = 2 * math.atan2(q[2], q[0])
    assert phi == pytest.approx(omega / 60, rel=0.05)
    expected = [0.5 * omega * math.sin(phi), 0.0, 1.0 + 0.5 * omega * math.cos(phi)]
    np.testing.assert_allclose(spun["linear"], expected, rtol=1e-3, atol=1e-6)


def test_materials_combine_friction_by_geometric_mean_and_bounce_by_max(kit, backend) -> None:
    kit.add(backend, kit.GROUND, kit.ground_plane(friction=0.8, bounce=0.0), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((0.2, 0.2, 0.2), friction=0.2), (0.0, 0.0, 0.1))
    kit.add(backend, 2, kit.sphere(radius=0.1, bounce=0.7), (3.0, 0.0, 1.1))
    backend.set_velocity(1, np.array([3.0, 0.0, 0.0]), np.zeros(3))
    kit.run(backend, 0.1, 1 / 240)
    v0 = kit.row(backend, 1)["linear"][0]
    heights, up = [], [False]

    def watch(i: int) -> None:
        r = kit.row(backend, 2)
        up[0] = up[0] or r["linear"][2] > 0
        if up[0]:
            heights.append(r["position"][2] - 0.1)

    kit.run(backend, 0.4, 1 / 240, watch)
    decel = (v0 - kit.row(backend, 1)["linear"][0]) / 0.4
    assert decel == pytest.approx(math.sqrt(0.8 * 0.2) * kit.G, rel=0.05)
    kit.run(backend, 0.6, 1 / 240, watch)
    assert max(heights) == pytest.approx(0.49, rel=0.1)  # e = max(0.7, 0): 0.7² · 1 m


def test_six_dof_without_body_b_follows_set_joint_target(kit, backend) -> None:
    """Beyond the protocol, but both backends offer it: the hand's world-pose target."""
    kit.add(backend, 1, kit.box((0.2, 0.2, 0.2), mass=1.0), (0.0, 0.0, 1.0))
    backend.add_joint(10, Joint(kind="six_dof", body_a=1, anchor=(0.0, 0.0, 1.0),
                                motor_max_force=50.0))
    backend.set_joint_target(10, np.array([0.5, 0.0, 1.2]), kit.quat_y(0.3))
    kit.run(backend, 1.5, 1 / 120)
    r = kit.row(backend, 1)
    np.testing.assert_allclose(r["position"], [0.5, 0.0, 1.2], atol=0.02)
    assert abs(float(np.dot(r["orientation"], kit.quat_y(0.3)))) == pytest.approx(1.0, abs=1e-3)
    backend.set_joint_target(10, np.array([0.5, 0.0, 1.2]), kit.quat_y(0.3), max_force=2.0)
    kit.run(backend, 1.0, 1 / 120)  # 2 N cannot hold 1 kg up: it sinks
    assert kit.row(backend, 1)["position"][2] < 0.9
    sinking = kit.row(backend, 1)["linear"][2]
    backend.set_drive_limits(10, 40.0, 40.0)  # far off target: the drive pushes at its bound
    backend.step(1 / 120)
    gained = kit.row(backend, 1)["linear"][2] - sinking
    assert gained == pytest.approx((40.0 - kit.G) / 120, rel=1e-3)
    with pytest.raises(ValueError):
        backend.set_drive_limits(10, -1.0, 1.0)


def test_keyless_static_plane_is_key_minus_one(kit, backend) -> None:
    """Beyond the protocol, but both backends offer it: ground without an entity."""
    backend.add_static_plane((0.0, 0.0, 1.0), 0.0)
    kit.add(backend, 1, kit.sphere(radius=0.1), (0.0, 0.0, 0.3))
    seen = []
    kit.run(backend, 0.5, 1 / 240, lambda i: seen.append(backend.contacts().copy()))
    allc = np.concatenate(seen)
    assert len(allc) and set(allc["a"]) == {1} and set(allc["b"]) == {-1}
    assert kit.row(backend, 1)["position"][2] == pytest.approx(0.1, abs=0.01)
    assert backend.body_count() == 1
    hit = backend.raycast(np.array([0.0, 0.0, 2.0]), np.array([0.0, 0.0, -1.0]), 5.0,
                          ignore=1)
    assert hit is not None and hit.key == -1


def test_raycast_skips_ignored_body_and_masked_categories(kit, backend) -> None:
    near = kit.box((0.5, 0.5, 0.5), kind="static", mass=None)
    near.category = 4
    kit.add(backend, 1, near, (1.0, 0.0, 0.0))
    kit.add(backend, 2, kit.box((0.5, 0.5, 0.5), kind="static", mass=None), (3.0, 0.0, 0.0))
    origin, right = np.zeros(3), np.array([1.0, 0.0, 0.0])
    assert backend.raycast(origin, right, 10.0).key == 1
    assert backend.raycast(origin, right, 10.0, ignore=1).key == 2
    assert backend.raycast(origin, right, 10.0, mask=0xFFFFFFFF & ~4).key == 2
    assert backend.raycast(origin, right, 2.0, ignore=1) is None


def test_joints_break_and_reattach_at_run_time(kit, backend) -> None:
    kit.add(backend, 1, kit.sphere(), (0.0, 0.0, 1.0))
    backend.add_joint(10, kit.hinge(1, (0.0, 0.0, 2.0)))
    kit.run(backend, 0.5, 1 / 120)
    assert kit.row(backend, 1)["position"][2] == pytest.approx(1.0, abs=0.01)
    backend.remove_joint(10)  # let go: it falls
    kit.run(backend, 0.3, 1 / 120)
    z = kit.row(backend, 1)["position"][2]
    assert z < 0.7
    backend.set_velocity(1, np.zeros(3), np.zeros(3))
    backend.add_joint(10, kit.hinge(1, (0.0, 0.0, z + 1.0)))  # grab it again, same key
    kit.run(backend, 0.5, 1 / 120)
    assert kit.row(backend, 1)["position"][2] == pytest.approx(z, abs=0.01)
    with pytest.raises(KeyError):
        backend.joint_state(11)


def test_both_backends_tell_the_same_side_view_story(kit) -> None:
    """The same content on ODE and pymunk: a bouncing ball, a sliding box, a pendulum."""
    from engine.physics import BackendUnavailable, create_backend
    from engine.physics.backend import WorldSettings

    tracks = {}
    for name in ("pymunk", "ode"):
        try:
            backend = create_backend(name)
        except BackendUnavailable as exc:
            pytest.skip(f"{name} backend not importable here: {exc}")
        backend.configure(WorldSettings(auto_sleep=False))
        kit.add(backend, kit.GROUND, kit.ground_plane(friction=0.5), (0.0, 0.0, 0.0))
        kit.add(backend, 1, kit.sphere(radius=0.25, bounce=0.6), (0.0, 0.0, 3.0))
        kit.add(backend, 2, kit.box((0.5, 0.5, 0.5), friction=0.4), (3.0, 0.0, 0.25))
        backend.set_velocity(2, np.array([3.0, 0.0, 0.0]), np.zeros(3))
        kit.add(backend, 3, kit.sphere(radius=0.05), (-2.0, 0.0, 2.0))
        backend.add_joint(10, kit.hinge(3, (-3.0, 0.0, 2.0)))
        samples = []

        def sample(i: int, backend=backend, samples=samples) -> None:
            state = backend.read_state()
            samples.append(state.position[np.argsort(state.keys)][:3].copy())

        # a fine step: at 1/120 s both integrators still drift from the exact swing,
        # ODE's by 0.14 m and pymunk's by 0.04 m, so a coarse step compares their errors
        kit.run(backend, 2.0, 1 / 480, sample)
        tracks[name] = np.array(samples)
        backend.close()
    diff = np.abs(tracks["pymunk"] - tracks["ode"])
    assert diff[:, 0, 2].max() < 0.1  # ball height
    assert diff[:, 1, 0].max() < 0.05  # box slide
    assert diff[:, 2].max() < 0.03  # pendulum bob
