"""The resting warm start (``World { WarmStart }``: engine/physics/ode3d/stepper.h and
engine/physics/pymunk2d/resting.py) held to physics where a body's contacts do not carry
its weight to the ground, on both backends at the default settings; and sleepers that
lose what held them up.

Each case has an answer physics gives without a solver: a crate on a platform a force
holds up stays where it is, a crate lifted by less than its weight stays on the floor,
a crate on a platform that accelerates down at 0.8 g goes down with it, a crate asleep on
a box that is removed falls. Scenes move in the X–Z plane, so the 2D backend simulates
them too.
"""

from __future__ import annotations

import numpy as np
import pytest

CRATE = (0.5, 0.5, 0.5)  # 125 kg at the default density
PLATFORM, PLATFORM_MASS = (2.0, 2.0, 0.2), 100.0


def _platform_with_crate(kit, backend):
    """A 100 kg platform with no floor under it, a 125 kg crate standing on it; returns
    the total weight (N)."""
    kit.add(backend, 1, kit.box(PLATFORM, mass=PLATFORM_MASS), (0.0, 0.0, 1.0))
    kit.add(backend, 2, kit.box(CRATE, mass=None), (0.0, 0.0, 1.35))
    return (PLATFORM_MASS + 125.0) * kit.G


@pytest.mark.parametrize("dt", [0.01, 0.02])
def test_a_crate_on_a_platform_a_force_holds_up_stays_put_then_falls_with_it(
        kit, make_backend, dt) -> None:
    """The force equals the whole weight for 1 s: nothing moves (the crate's preload,
    taken by a platform its contacts do not hold up, lifted both at 5 m/s² on ODE). Then
    the force drops to a fifth: both fall at 0.8 g together, the crate on the platform."""
    backend = make_backend(auto_sleep=True)
    weight = _platform_with_crate(kit, backend)
    for _ in range(round(1.0 / dt)):
        backend.add_force(1, np.array([0.0, 0.0, weight]))
        backend.step(dt)
    platform, crate = kit.row(backend, 1), kit.row(backend, 2)
    assert abs(platform["position"][2] - 1.0) < 2e-3, platform["position"]
    # vertically: a free tray balanced on one force is neutrally stable, and chipmunk's
    # sequential impulses (preload or not) leave it drifting sideways at cm/s
    assert abs(platform["linear"][2]) < 1e-3 and abs(crate["linear"][2]) < 1e-3
    n = round(0.3 / dt)
    for _ in range(n):
        backend.add_force(1, np.array([0.0, 0.0, 0.2 * weight]))
        backend.step(dt)
        gap = kit.row(backend, 2)["position"][2] - kit.row(backend, 1)["position"][2] - 0.35
        assert abs(gap) < 2e-3  # on the platform, never above it
    assert kit.row(backend, 1)["linear"][2] == pytest.approx(-0.8 * kit.G * n * dt, rel=0.01)


def test_a_crate_lifted_by_less_than_its_weight_stays_on_the_floor(kit, make_backend) -> None:
    """A steady upward pull of 0.3 of its weight: the floor carries the rest, the crate
    never leaves it (the preload on top of the pull made it hop on ODE)."""
    backend = make_backend(auto_sleep=True)
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box(CRATE, mass=None), (0.0, 0.0, 0.25))
    kit.run(backend, 1.0, 0.01)
    rest = kit.row(backend, 1)["position"][2]
    highest = rest
    for _ in range(200):
        backend.add_force(1, np.array([0.0, 0.0, 0.3 * 125.0 * kit.G]))
        backend.step(0.01)
        highest = max(highest, kit.row(backend, 1)["position"][2])
    assert highest - rest < 5e-5


@pytest.mark.parametrize("how", ["remove", "move", "collisions off", "woken, removed",
                                 "awake, crate put to sleep, removed"])
def test_a_sleeper_falls_when_what_held_it_up_goes(kit, make_backend, how) -> None:
    """A crate asleep on a box asleep on the floor; the box is removed, moved away or
    made to pass through things: the crate wakes and falls 0.5 m to the floor (ODE only
    wakes a sleeper through a contact made in a step, and left it hanging in the air).
    So too when the box was woken first, or stayed awake while the crate was put to sleep
    by hand (where ODE's binding skips the search for sleepers, an awake box's)."""
    backend = make_backend(auto_sleep=True)
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    box = kit.box(CRATE, mass=None)
    box.can_sleep = not how.startswith("awake")
    kit.add(backend, 1, box, (0.0, 0.0, 0.25))
    kit.add(backend, 2, kit.box((0.3, 0.3, 0.3), mass=10.0), (0.0, 0.0, 0.65))
    kit.run(backend, 2.0, 0.01)
    if how.startswith("awake"):
        assert not backend.is_sleeping(1) and not backend.is_sleeping(2)
        backend.set_sleeping(2, True)
    else:
        assert backend.is_sleeping(1) and backend.is_sleeping(2)
    if how == "woken, removed":
        backend.set_sleeping(1, False)
    if how.endswith("removed") or how == "remove":
        backend.remove_body(1)
    elif how == "move":
        backend.set_pose(1, np.array([5.0, 0.0, 0.25]), kit.IDENTITY)
    else:
        backend.set_collision_enabled(1, False)
    kit.run(backend, 1.0, 0.01)
    assert kit.row(backend, 2)["position"][2] == pytest.approx(0.15, abs=5e-3)


def test_a_crate_riding_a_sliding_box_leaves_the_floor_its_friction(kit, make_backend) -> None:
    """A 10 kg board sliding at 2 m/s on ice (μ √(5 · 0.02) against it) carries a 125 kg
    crate that sticks to it (μ 5): the pair stops after v²/2μg. The crate's contacts do
    not slide, but it is not at rest: preloaded, its weight was off the ice's friction
    and the pair slid six times too far on ODE."""
    backend = make_backend(auto_sleep=True)
    kit.add(backend, kit.GROUND, kit.ground_plane(material="ice", friction=0.02),
            (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((1.0, 1.0, 0.2), mass=10.0, material="sticky", friction=5.0),
            (0.0, 0.0, 0.1))
    kit.add(backend, 2, kit.box(CRATE, mass=None, material="sticky", friction=5.0),
            (0.0, 0.0, 0.45))
    kit.run(backend, 1.0, 0.01)
    start = kit.row(backend, 1)["position"][0]
    for key in (1, 2):
        backend.set_velocity(key, np.array([2.0, 0.0, 0.0]), np.zeros(3))
    kit.run(backend, 3.0, 0.01)
    travelled = kit.row(backend, 1)["position"][0] - start
    assert travelled == pytest.approx(2.0**2 / (2 * np.sqrt(5 * 0.02) * kit.G), rel=0.03)


def test_a_crate_on_a_swing_seat_swings_with_the_seat_s_period(kit, make_backend) -> None:
    """A 20 kg crate on a 10 kg seat hung 1 m below a hinge, released at 5°: one compound
    pendulum, T = 2π√(I / M g d) (I about the pivot, d its centre of mass below it). The
    seat is jointed, so its island is not preloaded (on pymunk the crate was, and the
    joint took 0.9 of its weight: the swing ran 52 % slow)."""
    backend = make_backend(auto_sleep=True)
    a = np.radians(5.0)
    tilt = kit.quat_y(-a)
    seat, crate = kit.box((0.6, 0.6, 0.1), mass=10.0), kit.box((0.2, 0.2, 0.2), mass=20.0)
    kit.add(backend, 1, seat, (np.sin(a), 0.0, 2.0 - np.cos(a)), tilt)
    backend.add_joint(10, kit.hinge(1, (0.0, 0.0, 2.0)))
    kit.add(backend, 2, crate, (0.85 * np.sin(a), 0.0, 2.0 - 0.85 * np.cos(a)), tilt)
    inertia = 10.0 * (0.37 / 12 + 1.0) + 20.0 * (0.08 / 12 + 0.85**2)
    period = 2 * np.pi * np.sqrt(inertia / ((10.0 + 20.0 * 0.85) * kit.G))
    xs = []
    kit.run(backend, 6.0, 0.01, lambda i: xs.append(kit.row(backend, 1)["position"][0]))
    x = np.array(xs)
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    assert len(up) >= 2
    assert np.diff(up).mean() * 0.01 == pytest.approx(period, rel=0.01)


def _pair_impulses(backend) -> dict[tuple[int, int], float]:
    """The step's contact impulses summed per body pair (N·s)."""
    out: dict[tuple[int, int], float] = {}
    c = backend.contacts()
    for a, b, impulse in zip(c["a"].tolist(), c["b"].tolist(), c["impulse"].tolist(),
                             strict=True):
        key = (min(a, b), max(a, b))
        out[key] = out.get(key, 0.0) + impulse
    return out


def _stack_then_one_more(kit, make_backend, dt: float, **settings) -> tuple[dict, list[float]]:
    """Five 2 kg crates stacked on the floor for 2 s (their pair impulses then), then a
    sixth set on top: the floor's contact over the next 0.5 s, in six crates' weights."""
    backend = make_backend(auto_sleep=False, **settings)
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    for i in range(5):
        kit.add(backend, i + 1, kit.box(CRATE, mass=2.0), (0.0, 0.0, 0.25 + 0.5 * i))
    for _ in range(round(2.0 / dt)):
        backend.step(dt)
    carried = _pair_impulses(backend)
    kit.add(backend, 6, kit.box(CRATE, mass=2.0), (0.0, 0.0, 2.75))
    floor = []
    for _ in range(round(0.5 / dt)):
        backend.step(dt)
        floor.append(_pair_impulses(backend).get((1, kit.GROUND), 0.0) / (12.0 * kit.G * dt))
    return carried, floor


@pytest.mark.parametrize("dt", [0.01, 0.001])
def test_a_resting_stack_reports_the_weight_each_contact_carries(kit, make_backend, dt):
    """Five 2 kg crates on the floor, most of their weight carried over by the preload:
    each contact still reports the weight above it times the step (the preload put back
    through the contacts down to the floor). A crate set on top, not yet preloaded, makes
    the floor's contact ring no more than the solver alone makes it (WarmStart 0), and
    then carry six crates: scaled by 1 / (1 - WarmStart), every contact under a body not
    preloaded reported up to ten times its load, which a contact sound played as a blow."""
    carried, floor = _stack_then_one_more(kit, make_backend, dt)
    for i in range(5):
        below = kit.GROUND if i == 0 else i
        key = (min(below, i + 1), max(below, i + 1))
        assert carried[key] == pytest.approx((5 - i) * 2.0 * kit.G * dt, rel=0.02), key
    _, solver_alone = _stack_then_one_more(kit, make_backend, dt, warm_start=0.0)
    assert max(floor) <= 1.1 * max(solver_alone)
    assert floor[-1] == pytest.approx(1.0, rel=0.02)
