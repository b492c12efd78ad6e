"""The sleep rule (engine.physics.sleep) on both backends: what swings keeps swinging,
what rests falls asleep, sleepers report zero velocity and wake when hit; and the rule's
islands and bookkeeping. (A copied sleep state resuming exactly: test_ode_state.)

Scenes move in the X–Z plane, so the 2D backend simulates them too.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from components import Joint
from engine.physics.backend import DynamicsBackend
from engine.physics.sleep import SLEEP_LINEAR, SLEEP_TIME, SMOOTHING, SleepRule, SleepState

STEPS = (0.0005, 0.001, 0.01, 0.02)
AMPLITUDES = (0.5, 2.0, 5.0, 30.0)  # degrees


def _pendulums(kit, backend: DynamicsBackend) -> list[int]:
    """A 1 m hinge pendulum and a 1 m ball-joint pendulum per amplitude, each released
    from rest, 3 m apart; their bob keys."""
    keys = []
    for i, (kind, amp) in enumerate((k, a) for k in ("hinge", "ball") for a in AMPLITUDES):
        key, pivot, a = 1 + i, (3.0 * i, 0.0, 2.0), math.radians(amp)
        kit.add(backend, key, kit.sphere(radius=0.05),
                (pivot[0] + math.sin(a), 0.0, pivot[2] - math.cos(a)))
        backend.add_joint(100 + i, Joint(kind=kind, body_a=key, anchor=pivot,
                                         axis=(0.0, 1.0, 0.0)))
        keys.append(key)
    return keys


@pytest.mark.filterwarnings("ignore")
@pytest.mark.parametrize("dt", STEPS)
def test_pendulums_keep_swinging_at_any_amplitude_and_step(kit, make_backend, dt) -> None:
    """Released from rest at 0.5° to 30°, for 10 s: with sleeping on, every bob moves
    exactly as with sleeping off (nothing ever slept), and it still swings."""
    runs = []
    for sleep in (True, False):
        backend = make_backend(auto_sleep=sleep)
        keys = _pendulums(kit, backend)
        xs = []

        def watch(i: int, backend=backend, xs=xs) -> None:
            if i >= round(8.0 / dt):  # the last two seconds: a full swing
                state = backend.read_state()
                xs.append(state.position[np.argsort(state.keys)][:, 0].copy())

        kit.run(backend, 10.0, dt, watch)
        runs.append(np.array(xs))
        assert not any(backend.is_sleeping(k) for k in keys)
    np.testing.assert_array_equal(runs[0], runs[1])
    swing = (runs[0].max(axis=0) - runs[0].min(axis=0)) / 2  # amplitude, m
    start = np.sin(np.radians(np.tile(AMPLITUDES, 2)))
    assert (swing > 0.5 * start).all(), swing / start  # damped by the integrator at most


@pytest.mark.parametrize("dt", STEPS)
def test_a_crate_on_the_floor_sleeps_within_a_second_of_settling(kit, make_backend,
                                                                 dt) -> None:
    backend = make_backend(auto_sleep=True)
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((0.5, 0.5, 0.5)), (0.0, 0.0, 0.55))  # dropped from 30 cm
    landed = settled = asleep = None
    for i in range(round(3.0 / dt)):
        backend.step(dt)
        r = kit.row(backend, 1)
        landed = landed or ((i + 1) * dt if r["position"][2] < 0.26 else None)
        at_rest = abs(r["position"][2] - 0.25) < 2e-3 and np.linalg.norm(r["linear"]) < 1e-3
        if at_rest and settled is None:
            settled = (i + 1) * dt
        elif not at_rest:
            settled = None  # a bounce: it settles later
        if backend.is_sleeping(1):
            asleep = (i + 1) * dt
            break
    assert landed is not None and settled is not None and asleep is not None
    assert asleep - settled < 1.0
    assert asleep - landed >= SLEEP_TIME - dt  # quiet for SleepTime first, never sooner
    backend.step(dt)
    r = kit.row(backend, 1)
    assert backend.is_sleeping(1)
    assert not r["linear"].any() and not r["angular"].any()  # a sleeper is at rest


def test_a_stack_sleeps_whole_and_wakes_whole_when_hit(kit, make_backend) -> None:
    dt = 0.005
    backend = make_backend(auto_sleep=True)
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    stack = [kit.add(backend, 1 + i, kit.box((0.5, 0.5, 0.5)), (0.0, 0.0, 0.25 + 0.501 * i))
             for i in range(3)]
    slept = set()

    def watch(i: int) -> None:
        now = {k for k in stack if backend.is_sleeping(k)}
        assert now in (set(), set(stack))  # an island sleeps whole, never part of it
        slept.update(now)

    kit.run(backend, 5.0, dt, watch)
    assert slept == set(stack)
    state = backend.read_state()
    assert not state.linear_velocity.any() and not state.angular_velocity.any()
    heights = np.sort(state.position[state.keys != kit.GROUND, 2])
    np.testing.assert_allclose(heights, [0.25, 0.75, 1.25], atol=0.02)
    # a box dropped on the top one wakes the whole stack (the backend's island wake-up)
    kit.add(backend, 9, kit.box((0.3, 0.3, 0.3), mass=2.0), (0.05, 0.0, 2.5))
    woke = []
    kit.run(backend, 1.0, dt, lambda i: woke.append(not any(map(backend.is_sleeping, stack))))
    assert any(woke)
    kit.run(backend, 10.0, dt)  # QuickStep leaves four boxes wobbling at mm/s for a while
    assert all(backend.is_sleeping(k) for k in (*stack, 9))  # and it all sleeps again


def test_a_body_that_may_not_sleep_keeps_what_it_carries_awake(kit, make_backend) -> None:
    backend = make_backend(auto_sleep=True)
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    restless = kit.box((0.5, 0.5, 0.5))
    restless.can_sleep = False
    kit.add(backend, 1, restless, (0.0, 0.0, 0.25))
    kit.add(backend, 2, kit.box((0.3, 0.3, 0.3)), (0.0, 0.0, 0.651))  # on top of it
    kit.add(backend, 3, kit.box((0.3, 0.3, 0.3)), (3.0, 0.0, 0.15))  # alone
    kit.run(backend, 3.0, 0.01)
    assert backend.is_sleeping(3)
    assert not backend.is_sleeping(1) and not backend.is_sleeping(2)


def test_a_joint_ties_an_island_as_a_contact_does(kit, make_backend) -> None:
    """Two crates resting apart on the floor, one that may not sleep: joined by a ball
    joint, the other stays awake with it (ODE finds its islands in the step, pymunk with
    the rule's own; both from the joints as well as the contacts); apart, or joined to
    one that may sleep, it sleeps."""
    asleep = []
    for joined, restless in ((True, True), (False, True), (True, False)):
        backend = make_backend(auto_sleep=True)
        kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
        first = kit.box((0.5, 0.5, 0.5))
        first.can_sleep = not restless
        kit.add(backend, 1, first, (0.0, 0.0, 0.25))
        kit.add(backend, 2, kit.box((0.5, 0.5, 0.5)), (1.0, 0.0, 0.25))
        if joined:
            backend.add_joint(10, kit.hinge(1, (0.5, 0.0, 0.25), 2, kind="ball"))
        kit.run(backend, 3.0, 0.01)
        asleep.append((backend.is_sleeping(1), backend.is_sleeping(2)))
    assert asleep == [(False, False), (False, True), (True, True)]


def test_a_push_restarts_the_quiet_stretch(kit, make_backend) -> None:
    """Every explicit wake starts the stretch over, so a body nudged every few steps,
    however gently, never sleeps."""
    backend = make_backend(auto_sleep=True)
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((0.5, 0.5, 0.5)), (0.0, 0.0, 0.25))
    kit.add(backend, 2, kit.box((0.5, 0.5, 0.5)), (3.0, 0.0, 0.25))

    def nudge(i: int) -> None:
        if i % 20 == 0:
            backend.add_force(1, np.array([0.0, 0.0, 1e-6]))

    kit.run(backend, 3.0, 0.01, nudge)
    assert backend.is_sleeping(2) and not backend.is_sleeping(1)


# -- the rule itself ---------------------------------------------------------------------
def _rule(n: int) -> SleepRule:
    rule = SleepRule()
    rule.layout(np.arange(10, 10 + n), np.ones(n, bool), np.ones(n, bool))
    rule.awake[:] = True
    return rule


def test_an_island_sleeps_only_when_all_of_it_is_ready() -> None:
    rule = _rule(4)
    rule.velocity[0, 3] = 0.5  # body 13 keeps moving
    edges = np.array([[0, 1], [2, 3]])  # 10-11 touch; 12 touches the moving 13
    slept: list[int] = []
    for _ in range(round(SLEEP_TIME / 0.01) + 2):
        rows, _ = rule.update(0.01, None, lambda: edges)
        slept += rows.tolist()
        rule.awake[rows] = False
    assert sorted(slept) == [0, 1]


def test_counters_follow_their_keys_when_rows_change() -> None:
    rule = _rule(3)
    rule.velocity[:] = 0.001  # slow and steady
    for _ in range(10):
        rule.update(0.01, None, lambda: np.zeros((0, 2)))
    timers = dict(zip(rule.keys.tolist(), rule.timer.tolist(), strict=True))
    rule.layout(np.array([12, 99, 10]), np.ones(3, bool), np.ones(3, bool))
    assert rule.timer.tolist() == [timers[12], 0.0, timers[10]]
    assert rule.started.tolist() == [True, False, True]


def test_a_bad_saved_sleep_state_is_refused_with_its_body() -> None:
    rule = _rule(1)
    with pytest.raises(ValueError, match="body 10: sleep timer"):
        rule.restore(0, SleepState(False, None, -1.0))
    with pytest.raises(ValueError, match="body 10: a reference velocity is 6 finite"):
        rule.restore(0, SleepState(False, np.zeros(6), 0.1, np.full(6, np.nan)))


def test_islands_follow_the_contacts_of_each_step() -> None:
    """Body 10 is ready, 11 keeps moving: touching, 10 is held; apart, 10 sleeps."""
    rule = _rule(2)
    rule.velocity[0, 1] = 0.5
    for _ in range(round(SLEEP_TIME / 0.01) + 2):
        rows, _ = rule.update(0.01, None, lambda: np.array([[0, 1]]))
        assert not len(rows)
    rows, _ = rule.update(0.01, None, lambda: np.zeros((0, 2), np.int64))
    assert rows.tolist() == [0]


def _numpy_advance(rule: SleepRule, dt: float, woken: np.ndarray | None) -> bool:
    """The rule's per-body step as it was written in numpy before it was compiled
    (engine/physics/_sleep.pyx): the oracle the compiled pass must match to the bit."""
    s, d, v = rule._stack
    np.subtract(v, s, out=d)
    d *= rule.smoothing * math.exp(-dt / SMOOTHING)
    np.subtract(v, d, out=s)
    np.subtract(s, rule.reference, out=d)
    bounds = rule._bounds.reshape(3, 2, 1)
    halves = rule._stack.reshape(3, 2, 3, -1)
    under = np.einsum("...kij,...kij->...kj", halves, halves) < bounds
    calm, steady, rest = under[:, 0] & under[:, 1]
    calm &= rule.awake
    rule.smoothing[:] = calm > rest
    slow = calm & rule.eligible
    if woken is not None:
        slow &= ~woken
    steady &= slow & rule.started
    rule.timer += dt
    rule.timer *= steady
    d *= slow ^ steady
    rule.reference += d
    rule.started[:] = slow
    return bool((rule.timer >= rule.time).any())


@pytest.mark.parametrize("seed", range(4))
def test_the_compiled_step_is_the_numpy_formulation_to_the_bit(seed: int) -> None:
    """Bodies at every speed around the limits (slow, steady, at rest, woken, asleep,
    ineligible), stepped through both: every state array equal, step after step (the
    drift row of the stack is scratch, not state)."""
    rng = np.random.default_rng(seed)
    n, dt = 300, 0.01
    rules = [_rule(n), _rule(n)]
    eligible = rng.random(n) < 0.9
    for rule in rules:
        rule.eligible[:] = eligible
        rule.configure(0.05, SLEEP_LINEAR, math.radians(2.0))  # short: timers run out
    scale = SLEEP_LINEAR * np.array([10.0, 1.0, 0.1, 0.01, 0.001])[rng.integers(0, 5, n)]
    base = rng.normal(0.0, 1.0, (6, n)) * scale
    for step in range(40):
        velocity = base + rng.normal(0.0, 0.02, (6, n)) * scale * (step % 3 == 0)
        awake = rng.random(n) < 0.95
        woken = rng.random(n) < 0.05 if step % 4 == 0 else None
        ready = []
        for rule, advance in ((rules[0], None), (rules[1], _numpy_advance)):
            rule.velocity[:] = velocity
            rule.awake[:] = awake
            if advance is None:
                ready.append(rule._pass.advance(dt, math.exp(-dt / SMOOTHING), rule.time,
                                                None if woken is None else woken.view(np.uint8)))
            else:
                ready.append(advance(rule, dt, woken))
        assert ready[0] == ready[1]
        for name in ("smoothed", "velocity", "smoothing", "timer", "reference", "started"):
            np.testing.assert_array_equal(getattr(rules[0], name), getattr(rules[1], name),
                                          err_msg=f"{name} at step {step}")
    assert rules[0].started.any() and (rules[0].timer > 0).any()  # the tests had work


def _numpy_settle(rule: SleepRule, labels: np.ndarray) -> np.ndarray:
    """The islands' say as SleepRule.update wrote it in numpy before it ran sleep.h's
    sr_settle (which ODE's step runs too): the oracle the compiled one must match."""
    ready = rule.timer >= rule.time
    blocked = rule.movable & rule.awake & ~ready  # awake and not ready: keeps it awake
    held = np.zeros(len(ready), bool)
    held[labels[blocked]] = True
    rows = np.flatnonzero(ready & ~held[labels])
    rule.forget(rows)
    rule.awake[rows] = False
    return rows


@pytest.mark.parametrize("seed", range(4))
def test_the_islands_say_is_the_numpy_formulation(seed: int) -> None:
    """Random islands of ready, unready, asleep and immovable rows: the same rows sleep
    and every state array ends the same through both."""
    rng = np.random.default_rng(seed)
    n = 200
    rules = [_rule(n), _rule(n)]
    labels = rng.integers(0, 40, n)  # 40 islands, labels in [0, n)
    movable = rng.random(n) < 0.9
    awake = rng.random(n) < 0.9
    timer = np.where(rng.random(n) < 0.8, 0.6, 0.1) * SLEEP_TIME / 0.5
    for rule in rules:
        rule.layout(rule.keys, movable, np.ones(n, bool))
        rule.awake[:] = awake
        rule.timer[:] = timer
        rule.smoothing[:] = 1.0
        rule.started[:] = True
    compiled = rules[0]._pass.settle(rules[0].time, labels.astype(np.intc))
    oracle = _numpy_settle(rules[1], labels)
    assert compiled.tolist() == oracle.tolist() and 0 < len(oracle) < n
    for name in ("smoothed", "smoothing", "timer", "started", "awake"):
        np.testing.assert_array_equal(getattr(rules[0], name), getattr(rules[1], name),
                                      err_msg=name)


@pytest.mark.parametrize("ramp, sleeps", [(0.0, True), (0.02, False)])
def test_a_slow_body_that_is_being_accelerated_stays_awake(ramp: float, sleeps: bool) -> None:
    """Slow all along (under SleepLinear for the whole second), but speeding up at
    0.02 m/s²: its velocity leaves the steady band, so it is not quiet and stays awake;
    the same body at a constant slow speed falls asleep after SleepTime."""
    rule = _rule(1)
    slept = False
    for i in range(100):  # 1 s at 0.01 s
        rule.velocity[0, 0] = 0.005 + ramp * i * 0.01
        assert rule.velocity[0, 0] < SLEEP_LINEAR
        rows, _ = rule.update(0.01, None, lambda: np.zeros((0, 2), np.int64))
        slept |= bool(len(rows))
    assert slept is sleeps
