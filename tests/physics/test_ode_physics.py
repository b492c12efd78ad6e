"""ODE backend checked against physics, beyond the shared contract suite.

Each test states the law it checks; tolerances come from the integrator (ODE is
semi-implicit Euler) or from the solver (QuickStep, iterative), never from
trial and error.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest
from scipy.special import ellipk

from components import Joint, MaterialProps, Physical, Shape
from engine.physics.backend import MaterialPair, WorldSettings

ode3d = pytest.importorskip("engine.physics.ode3d")
OdeBackend = ode3d.OdeBackend

G = 9.81
I4 = np.array([1.0, 0.0, 0.0, 0.0])


def make(**settings: object) -> OdeBackend:
    settings.setdefault("auto_sleep", False)
    return OdeBackend(WorldSettings(**settings))  # type: ignore[arg-type]


def ground(b: OdeBackend, key: int = 1000, **material: object) -> None:
    b.add_body(key, Physical(kind="static", mass=None, shapes=[Shape("plane", (0, 0, 1, 0))],
                             material=MaterialProps(**material)), np.zeros(3), I4)


def ball(radius: float = 0.1, mass: float = 1.0, **material: object) -> Physical:
    return Physical(mass=mass, shapes=[Shape("sphere", (radius,))],
                    material=MaterialProps(**material))


def cube(size: float = 1.0, mass: float | None = 1.0, **kw: object) -> Physical:
    return Physical(mass=mass, shapes=[Shape("box", (size, size, size))], **kw)  # type: ignore


def pos(b: OdeBackend, key: int) -> np.ndarray:
    s = b.read_state()
    return s.position[int(np.flatnonzero(s.keys == key)[0])]


def vel(b: OdeBackend, key: int) -> np.ndarray:
    s = b.read_state()
    return s.linear_velocity[int(np.flatnonzero(s.keys == key)[0])]


def test_free_fall_is_exactly_semi_implicit_euler() -> None:
    """v_n = -g n dt, z_n = z0 - g dt² n(n+1)/2: the discrete form of z0 - g t²/2."""
    b = make()
    dt, n, z0 = 1 / 60, 90, 50.0
    b.add_body(1, ball(), np.array([0, 0, z0]), I4)
    for _ in range(n):
        b.step(dt)
    assert pos(b, 1)[2] == pytest.approx(z0 - G * dt * dt * n * (n + 1) / 2, abs=1e-9)
    assert vel(b, 1)[2] == pytest.approx(-G * n * dt, abs=1e-9)
    t = n * dt
    assert pos(b, 1)[2] == pytest.approx(z0 - G * t * t / 2, abs=G * dt * t)


def test_large_angle_pendulum_period_matches_the_elliptic_integral() -> None:
    """T = 4 sqrt(L/g) K(sin(θ0/2)) for a point mass at 60°, on a hinge to the world."""
    b = make()
    length, amp, dt = 1.0, math.radians(60.0), 1 / 1000
    b.add_body(1, ball(radius=0.01), np.array([length * math.sin(amp), 0,
                                              2 - length * math.cos(amp)]), I4)
    b.add_joint(10, Joint(kind="hinge", body_a=1, anchor=(0, 0, 2), axis=(0, 1, 0)))
    xs = []
    for _ in range(int(5.5 / dt)):
        b.step(dt)
        xs.append(pos(b, 1)[0])
    x = np.array(xs)
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    times = (up + x[up] / (x[up] - x[up + 1])) * dt
    k = math.sin(amp / 2)
    expected = 4 * math.sqrt(length / G) * ellipk(k * k)  # scipy's K takes m = k²
    assert float(np.mean(np.diff(times))) == pytest.approx(expected, rel=0.005)
    # and far from the small-angle value, so the test can tell them apart
    assert abs(expected - 2 * math.pi * math.sqrt(length / G)) > 0.05


def test_bounce_threshold_stops_small_bounces() -> None:
    """Restitution e gives apex e² h; impacts slower than bounce_velocity do not bounce."""
    def apex(h: float, threshold: float) -> float:
        b = make(material_pairs=[MaterialPair("rubber", "floor", bounce=0.7)])
        ground(b, name="floor", bounce_velocity=threshold)
        b.add_body(1, ball(name="rubber", bounce_velocity=threshold), np.array([0, 0, h + 0.1]),
                   I4)
        best, up = 0.0, False
        for _ in range(int(1.2 / (1 / 480))):
            b.step(1 / 480)
            up = up or vel(b, 1)[2] > 0.05
            if up:
                best = max(best, pos(b, 1)[2] - 0.1)
        return best

    assert apex(1.0, 0.1) == pytest.approx(0.49, rel=0.1)
    impact = math.sqrt(2 * G * 0.05)  # ~1 m/s
    assert apex(0.05, 2 * impact) < 0.002


def test_resting_contact_impulse_equals_weight_times_dt() -> None:
    """At rest the ground's contact impulses per step sum to m g dt."""
    b = make()
    ground(b)
    b.add_body(1, cube(0.5, mass=3.0), np.array([0, 0, 0.25]), I4)
    dt = 1 / 120
    for _ in range(120):
        b.step(dt)
    c = b.contacts()
    assert len(c) == 4 and set(c["a"]) == {1} and set(c["b"]) == {1000}
    assert c["impulse"].sum() == pytest.approx(3.0 * G * dt, rel=0.02)


def test_max_contacts_per_pair() -> None:
    b = make(max_contacts=2)
    ground(b)
    b.add_body(1, cube(0.5), np.array([0, 0, 0.25]), I4)
    b.step(1 / 60)
    assert len(b.contacts()) == 2


def test_softness_lets_a_body_sink_deeper() -> None:
    def depth(softness: float) -> float:
        b = make()
        ground(b, softness=softness)
        b.add_body(1, cube(0.5, mass=10.0, material=MaterialProps(softness=softness)),
                   np.array([0, 0, 0.25]), I4)
        for _ in range(240):
            b.step(1 / 120)
        return 0.25 - pos(b, 1)[2]

    assert depth(1e-2) > depth(0.0) + 0.005


def test_stack_of_ten_comes_to_rest_and_every_box_sleeps() -> None:
    """Ten 1 m crates of 1000 kg (a 1 kg one is ten times lighter than balsa: QuickStep
    leaves a stack of those wobbling at cm/s) at the scene's default step."""
    b = make(auto_sleep=True)
    ground(b)
    for i in range(10):
        b.add_body(i, cube(1.0, mass=1000.0), np.array([0, 0, 0.5 + 1.001 * i]), I4)
    dt, world = 1 / 100, WorldSettings()  # the default world
    for _ in range(400):
        b.step(dt)
    assert b.sleeping_count() == 10
    # each contact layer sinks in by the surface layer (1 mm) and where the soft contact
    # holds its share of the load: at rest ERP·depth = CFM·λ·dt on 4 contacts, with the
    # contact's CFM softness·dt·(1/m1 + 1/m2) and λ the solver's share, (1 - warm start)
    # of the load once the stack rests
    load = 1000.0 * G * (10 - np.arange(10))  # weight on the contact under box k
    cfm = world.contact_softness * dt * np.where(np.arange(10) == 0, 1, 2) / 1000.0
    depth = 0.001 + cfm * (1 - world.warm_start) * load / 4 * dt / world.erp
    expected = 0.5 + np.arange(10) - np.cumsum(depth)
    np.testing.assert_allclose(np.sort(b.read_state().position[:, 2])[1:], expected,
                               atol=1e-3)
    assert len(b.contacts()) == 0  # sleeping pairs are not collided


def test_can_sleep_false_keeps_a_body_awake() -> None:
    b = make(auto_sleep=True)
    ground(b)
    b.add_body(1, cube(1.0), np.array([0, 0, 0.5]), I4)
    b.add_body(2, cube(1.0, can_sleep=False), np.array([3, 0, 0.5]), I4)
    for _ in range(240):
        b.step(1 / 60)
    assert b.is_sleeping(1) and not b.is_sleeping(2)
    b.add_force(1, np.array([100.0, 0, 0]))  # a force wakes a sleeper
    assert not b.is_sleeping(1)


def test_offset_shapes_put_the_centre_of_mass_between_them() -> None:
    """A dumbbell whose balls sit at x = 0 and x = 1 spins about x = 0.5 with no gravity."""
    b = make(gravity=(0, 0, 0))
    dumbbell = Physical(mass=2.0, shapes=[Shape("sphere", (0.1,)),
                                          Shape("sphere", (0.1,), offset=(1.0, 0, 0))])
    b.add_body(1, dumbbell, np.zeros(3), I4)
    # the entity origin's velocity w x (origin - com) keeps the COM still
    b.set_velocity(1, np.array([0, -1.0, 0]), np.array([0, 0, 2.0]))
    for _ in range(200):
        b.step(1 / 200)
    s = b.read_state()
    q = s.orientation[0]
    # rotation of 2 rad about z through the COM (0.5, 0, 0) carries the origin with it
    expected = np.array([0.5 - 0.5 * math.cos(2.0), -0.5 * math.sin(2.0), 0.0])
    # (ODE integrates the quaternion to first order: ~1e-5 rad over this spin)
    np.testing.assert_allclose(s.position[0], expected, atol=1e-4)
    assert 2 * math.atan2(q[3], q[0]) == pytest.approx(2.0, abs=1e-4)
    np.testing.assert_allclose(s.linear_velocity[0],
                               np.cross([0, 0, 2.0], expected - [0.5, 0, 0]), atol=1e-4)


def test_wheel_on_hinge2_rolls_at_omega_r() -> None:
    r, omega = 0.3, 4.0
    b = make()
    ground(b, friction=1.0)
    b.add_body(1, cube(0.2, mass=5.0), np.array([0, 0, r]), I4)
    along_y = np.array([math.cos(math.pi / 4), math.sin(math.pi / 4), 0, 0])
    b.add_body(2, Physical(mass=1.0, shapes=[Shape("sphere", (r,))],
                           material=MaterialProps(friction=1.0)), np.array([0, 0, r]), along_y)
    b.add_body(3, Physical(mass=1.0, shapes=[Shape("sphere", (r,))],
                           material=MaterialProps(friction=1.0)), np.array([1, 0, r]), along_y)
    for key, x in ((2, 0.0), (3, 1.0)):
        b.add_joint(key * 10, Joint(kind="hinge2", body_a=key, body_b=1, anchor=(x, 0, r),
                                    axis=(0, 0, 1), axis2=(0, 1, 0), low=0.0, high=0.0,
                                    motor_velocity=omega, motor_max_force=50.0))
    for _ in range(240):
        b.step(1 / 240)
    speeds = []
    for _ in range(240):
        b.step(1 / 240)
        speeds.append(vel(b, 1)[0])
    assert float(np.mean(speeds)) == pytest.approx(omega * r, rel=0.05)


def test_slider_motor_and_ball_and_universal_joints() -> None:
    b = make()
    b.add_body(1, cube(0.2), np.array([0, 0, 2.0]), I4)
    b.add_joint(1, Joint(kind="slider", body_a=1, axis=(1, 0, 0), motor_velocity=0.5,
                         motor_max_force=100.0))
    b.add_body(2, ball(), np.array([2, 0, 1.0]), I4)
    b.add_joint(2, Joint(kind="ball", body_a=2, anchor=(2, 0, 2.0)))
    b.add_body(3, ball(), np.array([4, 0, 1.0]), I4)
    b.add_joint(3, Joint(kind="universal", body_a=3, anchor=(4, 0, 2.0), axis=(1, 0, 0),
                         axis2=(0, 1, 0)))
    b.set_velocity(2, np.array([0, 1.0, 0]), np.zeros(3))
    for _ in range(120):
        b.step(1 / 120)
    p = b.joint_state(1)
    assert p[0] == pytest.approx(0.5, abs=0.01) and p[1] == pytest.approx(0.5, abs=1e-3)
    assert pos(b, 1)[2] == pytest.approx(2.0, abs=1e-3)  # slider holds it up
    assert float(np.linalg.norm(pos(b, 2) - [2, 0, 2])) == pytest.approx(1.0, abs=1e-3)
    assert float(np.linalg.norm(pos(b, 3) - [4, 0, 2])) == pytest.approx(1.0, abs=1e-3)


def test_angular_and_linear_motors() -> None:
    b = make(gravity=(0, 0, 0))
    b.add_body(1, cube(0.2), np.zeros(3), I4)
    b.add_joint(1, Joint(kind="angular_motor", body_a=1, axis=(0, 0, 1), motor_velocity=3.0,
                         motor_max_force=10.0))
    b.add_body(2, cube(0.2), np.array([5.0, 0, 0]), I4)
    b.add_joint(2, Joint(kind="linear_motor", body_a=2, axis=(0, 1, 0), motor_velocity=-1.0,
                         motor_max_force=10.0))
    for _ in range(60):
        b.step(1 / 60)
    s = b.read_state()
    assert s.angular_velocity[0, 2] == pytest.approx(3.0, rel=1e-3)
    assert s.linear_velocity[1, 1] == pytest.approx(-1.0, rel=1e-3)


def test_joint_broken_and_reattached_at_run_time() -> None:
    b = make()
    b.add_body(1, ball(), np.array([0, 0, 2.0]), I4)
    b.add_joint(5, Joint(kind="ball", body_a=1, anchor=(0, 0, 2.5)))
    for _ in range(60):
        b.step(1 / 60)
    assert pos(b, 1)[2] == pytest.approx(2.0, abs=1e-3)
    b.remove_joint(5)
    for _ in range(30):
        b.step(1 / 60)
    z = pos(b, 1)[2]
    assert z < 1.0
    b.set_velocity(1, np.zeros(3), np.zeros(3))
    b.add_joint(5, Joint(kind="fixed", body_a=1))
    for _ in range(60):
        b.step(1 / 60)
    assert pos(b, 1)[2] == pytest.approx(z, abs=1e-3)


def test_six_dof_world_target_moves_body_with_bounded_force() -> None:
    b = make()
    b.add_body(1, cube(0.2, mass=2.0), np.array([0, 0, 1.0]), I4)
    b.add_joint(9, Joint(kind="six_dof", body_a=1, motor_max_force=100.0))
    for _ in range(60):
        b.step(1 / 60)
    assert pos(b, 1)[2] == pytest.approx(1.0, abs=1e-3)  # holds against gravity
    q = np.array([math.cos(0.3), 0, 0, math.sin(0.3)])
    b.set_joint_target(9, np.array([0.5, 0, 1.0]), q)
    for _ in range(60):
        b.step(1 / 60)
    s = b.read_state()
    np.testing.assert_allclose(s.position[0], [0.5, 0, 1.0], atol=1e-3)
    assert abs(float(np.dot(s.orientation[0], q))) == pytest.approx(1.0, abs=1e-5)
    b.set_drive_limits(9, max_force=5.0, max_torque=1.0)  # 5 N < m g: it sags
    for _ in range(60):
        b.step(1 / 60)
    assert pos(b, 1)[2] < 0.5


def test_gil_is_released_while_stepping() -> None:
    """A Python thread keeps running while another thread is inside a long step."""
    b = make(iterations=1000)  # a step of ~0.1 s, far longer than a GIL switch interval
    ground(b)
    for i in range(600):
        b.add_body(i, cube(1.0), np.array([1.2 * (i // 10 % 8), 1.2 * (i // 80),
                                           0.49 + 0.98 * (i % 10)]), I4)  # touching
    b.step(1 / 60)

    def count_for(seconds: float) -> int:
        n, end = 0, time.perf_counter() + seconds
        while time.perf_counter() < end:
            n += 1
        return n

    t0 = time.perf_counter()
    b.step(1 / 60)
    step_s = time.perf_counter() - t0
    alone = count_for(step_s)
    done = threading.Event()

    def stepper() -> None:
        b.step(1 / 60)  # one long step: holding the GIL would freeze the counter below
        done.set()

    worker = threading.Thread(target=stepper)
    beside = 0
    worker.start()
    while not done.is_set():
        beside += 1
    worker.join()
    # with the GIL held the counter could not move at all while the step runs
    assert beside > 0.2 * alone


def test_two_runs_of_a_toppling_pile_are_bit_identical() -> None:
    def once() -> tuple[np.ndarray, np.ndarray]:
        b = make(auto_sleep=True)
        ground(b)
        rng = np.random.default_rng(3)
        for i in range(40):
            q = rng.normal(size=4)
            b.add_body(i, cube(0.5), np.array([*(rng.random(2) * 2), 0.5 + 0.6 * i]),
                       q / np.linalg.norm(q))
        for _ in range(200):
            b.step(1 / 60)
        s = b.read_state()
        return np.hstack([s.position, s.orientation, s.linear_velocity]), b.contacts()

    (s1, c1), (s2, c2) = once(), once()
    assert np.array_equal(s1, s2) and np.array_equal(c1, c2)


def test_hinge2_steering_angle_and_limits_follow_the_hinge_convention() -> None:
    """Axis 1 reads body_a's turn relative to body_b; [low, high] holds it."""
    b = make(gravity=(0, 0, 0))
    b.add_body(1, Physical(kind="kinematic", mass=None, shapes=[Shape("box", (0.2, 0.2, 0.2))]),
               np.zeros(3), I4)
    b.add_body(2, ball(radius=0.3), np.array([1.0, 0, 0]), I4)
    b.add_joint(5, Joint(kind="hinge2", body_a=2, body_b=1, anchor=(1, 0, 0), axis=(0, 0, 1),
                         axis2=(0, 1, 0), low=-0.1, high=0.2))
    for _ in range(120):
        b.add_torque(2, np.array([0, 0, 0.5]))  # turns the wheel +z about the steering axis
        b.step(1 / 60)
    assert b.joint_state(5)[0] == pytest.approx(0.2, abs=0.01)
    for _ in range(120):
        b.add_torque(2, np.array([0, 0, -0.5]))
        b.step(1 / 60)
    assert b.joint_state(5)[0] == pytest.approx(-0.1, abs=0.01)


@pytest.mark.parametrize(("angle_deg", "slides"), [(25.0, False), (28.0, True)])
def test_incline_threshold_is_sharp_at_tan_theta_equals_mu(angle_deg: float,
                                                           slides: bool) -> None:
    """μ = 0.5 holds a box at 25° (tan 0.466) and lets it go at 28° (tan 0.532)."""
    theta = math.radians(angle_deg)
    q = np.array([math.cos(theta / 2), 0, math.sin(theta / 2), 0])
    normal = np.array([math.sin(theta), 0, math.cos(theta)])
    downhill = np.array([math.cos(theta), 0, -math.sin(theta)])
    b = make()
    b.add_body(1, Physical(kind="static", mass=None, shapes=[Shape("box", (8, 2, 0.2))],
                           material=MaterialProps(friction=0.5)), np.zeros(3), q)
    start = normal * 0.201
    b.add_body(2, cube(0.2, material=MaterialProps(friction=0.5)), start, q)
    t, dt = 1.5, 1 / 240
    for _ in range(round(t / dt)):
        b.step(dt)
    moved = float(np.dot(pos(b, 2) - start, downhill))
    if slides:
        expected = 0.5 * G * (math.sin(theta) - 0.5 * math.cos(theta)) * t * t
        assert moved == pytest.approx(expected, rel=0.15)
    else:
        assert abs(moved) < 0.005
