"""A body's given centre of mass and inertia, and joint springs, checked against physics on
both backends: a pendulum whose mass sits off its shapes swings with the period its
centre and inertia give, a torque turns a body at torque / I about the axis its
principal moments name, a slider or hinge spring oscillates at sqrt(k / m), damps as
its damping says, pulls at most its max force and stays stable far stiffer than the
step resolves. Scenes move in the X–Z plane, hinge axes along Y."""

from __future__ import annotations

import math

import numpy as np
import pytest

from components import Joint, Physical, Shape
from components.joint import Spring

DTS = [1 / 120, 1 / 240]


def upward_crossings(values: list[float], dt: float) -> np.ndarray:
    """Times (s) at which ``values`` rise through 0, interpolated within the step."""
    v = np.asarray(values)
    k = np.flatnonzero((v[:-1] < 0) & (v[1:] >= 0))
    return (k + v[k] / (v[k] - v[k + 1]) + 1) * dt


def period(values: list[float], dt: float, centre: float | None = None) -> float:
    """The mean period of an oscillation about ``centre`` (default: the middle of its
    range), its upward crossings apart."""
    v = np.asarray(values)
    middle = (v.max() + v.min()) / 2 if centre is None else centre
    times = upward_crossings(list(v - middle), dt)
    assert len(times) >= 3, "fewer than three upward crossings"
    return float(np.diff(times).mean())


@pytest.mark.parametrize("dt", DTS)
def test_a_pendulum_swings_with_the_period_its_given_centre_and_inertia_make(kit, backend,
                                                                             dt) -> None:
    """Its only shape is a small sphere at the pivot (by its shapes it would not swing at
    all); its mass is said to sit 0.5 m below, with 0.02 kg m^2 about it:
    T = 2 pi sqrt((I + m r^2) / (m g r))."""
    mass, reach, inertia = 2.0, 0.5, 0.02
    body = Physical(mass=mass, shapes=[Shape("sphere", (0.05,))], category=0, mask=0,
                    center_of_mass=(0.0, 0.0, -reach), inertia=(inertia, inertia, inertia))
    kit.add(backend, 1, body, (0.0, 0.0, 2.0), kit.quat_y(0.1))
    backend.add_joint(10, kit.hinge(1, (0.0, 0.0, 2.0)))
    angles: list[float] = []
    kit.run(backend, 4.0, dt, lambda _: angles.append(backend.joint_state(10)[0]))
    # the swing's own amplitude (0.1 rad) lengthens it by theta^2 / 16
    expected = 2 * math.pi * math.sqrt((inertia + mass * reach ** 2) / (mass * kit.G * reach))
    assert period(angles, dt) == pytest.approx(expected * (1 + 0.1 ** 2 / 16), rel=0.003)


@pytest.mark.parametrize("offset, tips", [(0.06, False), (0.14, True)])
def test_a_tall_block_tips_only_when_its_centre_of_mass_lies_past_its_base(kit, backend,
                                                                          offset, tips) -> None:
    """A 0.2 m wide block standing on the ground: its centre of mass said to be 0.06 m to
    the side stays over its base; 0.14 m is past the edge (0.1 m), and over it goes."""
    backend.add_body(kit.GROUND, kit.ground_plane(), np.zeros(3), kit.IDENTITY)
    block = Physical(mass=1.0, shapes=[Shape("box", (0.2, 0.2, 1.0))],
                     center_of_mass=(offset, 0.0, 0.0))
    kit.add(backend, 1, block, (0.0, 0.0, 0.5))
    kit.run(backend, 3.0, 1 / 240)
    up = kit.row(backend, 1)["orientation"]
    tilt = 2 * math.degrees(math.acos(min(1.0, abs(float(up[0])))))
    if tips:
        assert tilt > 60, tilt
    else:
        assert tilt < 0.5, tilt
        assert kit.row(backend, 1)["position"][2] == pytest.approx(0.5, abs=2e-3)


def test_a_torque_turns_a_body_at_torque_over_its_given_principal_moment(kit, backend) -> None:
    """Principal moments (1, 2, 4) kg m^2, their axes turned a quarter about X: the body's
    Y axis then carries the moment 4 (the third axis turned onto -Y), so a torque of 2
    N m about Y turns it at 0.5 rad/s^2."""
    quarter = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
    body = Physical(mass=3.0, shapes=[Shape("box", (0.3, 0.3, 0.3))], gravity=False,
                    inertia=(1.0, 2.0, 4.0), inertia_rotation=quarter)
    kit.add(backend, 1, body, (0.0, 0.0, 2.0))
    dt, seconds = 1 / 240, 0.5
    for _ in range(round(seconds / dt)):
        backend.add_torque(1, np.array([0.0, 2.0, 0.0]))
        backend.step(dt)
    spin = kit.row(backend, 1)["angular"]
    assert spin[1] == pytest.approx(2.0 / 4.0 * seconds, rel=1e-6)


def test_ode_turns_a_body_by_its_whole_given_inertia_tensor(make_backend, kit) -> None:
    """In 3D a torque off the principal axes turns a body by I^-1 torque: moments (1, 2,
    4) turned 30 degrees about Z, a torque of 1 N m along X."""
    backend = make_backend()
    if backend.name != "ode":
        pytest.skip("the plane has one axis to turn about")
    c, s = math.cos(math.radians(15)), math.sin(math.radians(15))
    body = Physical(mass=1.0, shapes=[Shape("box", (0.3, 0.3, 0.3))], gravity=False,
                    inertia=(1.0, 2.0, 4.0), inertia_rotation=(c, 0.0, 0.0, s))
    kit.add(backend, 1, body, (0.0, 0.0, 2.0))
    for _ in range(10):
        backend.add_torque(1, np.array([1.0, 0.0, 0.0]))
        backend.step(1 / 1000)
    turn = np.array([[math.cos(math.radians(30)), -math.sin(math.radians(30)), 0],
                     [math.sin(math.radians(30)), math.cos(math.radians(30)), 0], [0, 0, 1]])
    tensor = turn @ np.diag([1.0, 2.0, 4.0]) @ turn.T
    expected = np.linalg.solve(tensor, [1.0, 0.0, 0.0]) * 0.01
    np.testing.assert_allclose(kit.row(backend, 1)["angular"], expected, rtol=2e-3, atol=1e-7)


def slider(kit, backend, spring: Spring, mass: float = 2.0) -> int:
    """A cart on a rail along X (no gravity), its spring as given; the joint's key."""
    cart = Physical(mass=mass, shapes=[Shape("box", (0.2, 0.2, 0.2))], gravity=False)
    kit.add(backend, 1, cart, (0.0, 0.0, 1.0))
    backend.add_joint(10, Joint(kind="slider", body_a=1, anchor=(0.0, 0.0, 1.0),
                                axis=(1.0, 0.0, 0.0), spring=spring))
    return 10


@pytest.mark.parametrize("dt", DTS)
def test_a_slider_spring_oscillates_at_sqrt_k_over_m_and_keeps_its_energy(kit, backend,
                                                                          dt) -> None:
    stiffness, mass, target = 50.0, 2.0, 0.3
    joint = slider(kit, backend, Spring(stiffness, 0.0, target), mass)
    offsets: list[float] = []
    kit.run(backend, 4.0, dt, lambda _: offsets.append(backend.joint_state(joint)[0] - target))
    assert period(offsets, dt) == pytest.approx(2 * math.pi * math.sqrt(mass / stiffness),
                                                rel=2e-3)
    # it starts 0.3 m from its target, at rest: it swings 0.3 m either side, undamped
    last = offsets[-round(1.3 / dt):]
    assert max(last) == pytest.approx(target, rel=0.01)
    assert min(last) == pytest.approx(-target, rel=0.01)


@pytest.mark.parametrize("dt", DTS)
def test_a_hinge_spring_oscillates_at_sqrt_k_over_i(kit, backend, dt) -> None:
    """A 1 m rod hinged at one end, no gravity: I = m L^2 / 3 about the hinge."""
    mass, length, stiffness = 1.5, 1.0, 3.0
    rod = Physical(mass=mass, shapes=[Shape("box", (length, 0.05, 0.05))], gravity=False)
    kit.add(backend, 1, rod, (length / 2, 0.0, 1.0))
    backend.add_joint(10, kit.hinge(1, (0.0, 0.0, 1.0), spring=Spring(stiffness, 0.0, 0.2)))
    offsets: list[float] = []
    kit.run(backend, 6.0, dt, lambda _: offsets.append(backend.joint_state(10)[0] - 0.2))
    inertia = mass * (length ** 2 + 0.05 ** 2) / 12 + mass * (length / 2) ** 2
    assert period(offsets, dt) == pytest.approx(2 * math.pi * math.sqrt(inertia / stiffness),
                                                rel=3e-3)


def test_a_damped_spring_decays_as_its_damping_ratio_says(kit, backend) -> None:
    """x(t) = A e^(-zeta w t) cos(w_d t): successive peaks one damped period apart shrink
    by e^(-zeta w T_d)."""
    stiffness, mass, damping, dt = 50.0, 2.0, 2.0, 1 / 240
    joint = slider(kit, backend, Spring(stiffness, damping, 0.3), mass)
    offsets: list[float] = []
    kit.run(backend, 4.0, dt, lambda _: offsets.append(backend.joint_state(joint)[0] - 0.3))
    w = math.sqrt(stiffness / mass)
    zeta = damping / (2 * math.sqrt(stiffness * mass))
    damped = 2 * math.pi / (w * math.sqrt(1 - zeta ** 2))
    assert period(offsets, dt, centre=0.0) == pytest.approx(damped, rel=3e-3)
    v = np.asarray(offsets)
    peaks = [k for k in range(1, len(v) - 1) if v[k] <= v[k - 1] and v[k] < v[k + 1]]
    ratio = v[peaks[1]] / v[peaks[0]]
    assert ratio == pytest.approx(math.exp(-zeta * w * damped), rel=0.02)


def test_a_damper_alone_slows_its_joint_as_e_to_the_minus_d_t_over_m(kit, backend) -> None:
    joint = slider(kit, backend, Spring(0.0, 4.0, 0.0), mass=2.0)
    backend.set_velocity(1, np.array([1.0, 0.0, 0.0]), np.zeros(3))
    kit.run(backend, 1.0, 1 / 240)
    assert backend.joint_state(joint)[1] == pytest.approx(math.exp(-4.0 / 2.0), rel=0.01)


def test_a_spring_pulls_at_most_its_max_force(kit, backend) -> None:
    """50 N/m pulling from 1 m away would be 50 N; bounded to 1 N, the 2 kg cart
    accelerates at 0.5 m/s^2."""
    joint = slider(kit, backend, Spring(50.0, 0.0, 1.0, max_force=1.0), mass=2.0)
    kit.run(backend, 0.5, 1 / 240)
    assert backend.joint_state(joint)[1] == pytest.approx(0.5 * 0.5, rel=0.01)


@pytest.mark.parametrize("dt", [1 / 60, 1 / 120])
def test_a_spring_far_stiffer_than_the_step_settles_at_its_target(kit, backend, dt) -> None:
    """k h^2 / m of 50 or more: an explicit spring would fling the cart away; this one
    comes to its target and stays."""
    joint = slider(kit, backend, Spring(4e5, 0.0, 0.3), mass=2.0)
    kit.run(backend, 2.0, dt)
    position, rate = backend.joint_state(joint)
    assert position == pytest.approx(0.3, abs=1e-3) and abs(rate) < 1e-2


def test_a_spring_past_the_joint_limit_holds_the_joint_at_the_limit(kit, backend) -> None:
    """The spring pulls to 60 degrees; the hinge stops at 20: it rests there (the spring
    acts beside the limit, not instead of it)."""
    rod = Physical(mass=1.0, shapes=[Shape("box", (1.0, 0.05, 0.05))], gravity=False)
    kit.add(backend, 1, rod, (0.5, 0.0, 1.0))
    backend.add_joint(10, kit.hinge(1, (0.0, 0.0, 1.0), low=-0.1, high=math.radians(20),
                                    spring=Spring(5.0, 1.0, math.radians(60))))
    kit.run(backend, 4.0, 1 / 240)
    assert backend.joint_state(10)[0] == pytest.approx(math.radians(20), abs=2e-3)
