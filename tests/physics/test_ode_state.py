"""OdeBackend state that saved scenes carry: joints re-made from their reference poses,
the sleep rule's state read and restored, and the entity-origin velocity of off-centre
bodies.

Each test copies a running world into a fresh one (poses, velocities, solver state,
joints, sleep) and checks the copy goes on exactly as the original.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from components import Joint, Physical, Shape
from engine.physics.backend import WorldSettings
from engine.physics.sleep import SleepState

ode3d = pytest.importorskip("engine.physics.ode3d")
OdeBackend = ode3d.OdeBackend

DT = 1 / 100
I4 = (1.0, 0.0, 0.0, 0.0)
TILT = (0.9659258262890683, 0.0, 0.25881904510252074, 0.0)  # 30 degrees about Y


def box(size: tuple[float, float, float] = (0.6, 0.1, 0.1), **kw: object) -> Physical:
    return Physical(mass=1.0, shapes=[Shape("box", size)], **kw)  # type: ignore[arg-type]


#: Two bodies (key 1 at x = 0.5, key 2 at x = 1.5; both spun and pushed) and a joint.
JOINTS = {
    "hinge to the world": Joint("hinge", 1, None, (0.0, 0.0, 2.0), (0.0, 1.0, 0.0)),
    "hinge between bodies": Joint("hinge", 1, 2, (1.0, 0.0, 2.0), (0.3, 1.0, 0.0)),
    "motorized hinge on its limit": Joint("motorized_hinge", 1, None, (0.0, 0.0, 2.0),
                                          (0.0, -1.0, 0.0), low=-0.5, high=0.3,
                                          motor_velocity=2.0, motor_max_force=30.0),
    "ball": Joint("ball", 1, 2, (1.0, 0.0, 2.1)),
    "slider with limits": Joint("slider", 1, None, axis=(1.0, 0.0, -1.0), low=-0.1,
                                high=0.2),
    "slider between bodies": Joint("slider", 2, 1, axis=(1.0, 0.2, 0.0), low=-0.3, high=0.3),
    "universal": Joint("universal", 2, 1, (1.0, 0.0, 2.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "hinge2": Joint("hinge2", 2, 1, (1.5, 0.0, 2.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0),
                    low=-0.3, high=0.3, motor_velocity=5.0, motor_max_force=2.0),
    "fixed": Joint("fixed", 1, 2),
    "angular motor": Joint("angular_motor", 1, 2, axis=(0.0, 0.0, 1.0), motor_velocity=3.0,
                           motor_max_force=0.5),
    "linear motor": Joint("linear_motor", 1, None, axis=(1.0, 0.0, 0.0), motor_velocity=1.0,
                          motor_max_force=4.0),
    "six_dof following a body": Joint("six_dof", 2, 1, motor_max_force=5.0),
}
START = {1: ((0.5, 0.0, 2.0), TILT, (0.3, 0.5, 1.0), (1.0, -2.0, 3.0)),
         2: ((1.5, 0.0, 2.0), I4, (0.0, -1.0, 0.5), (0.0, 2.0, -1.0))}


def world(sleep: bool = False) -> OdeBackend:
    return OdeBackend(WorldSettings(auto_sleep=sleep))


def add(b: OdeBackend, key: int, body: Physical, pose, lin=(0.0, 0.0, 0.0),
        ang=(0.0, 0.0, 0.0)) -> None:
    b.add_body(key, body, np.array(pose[0]), np.array(pose[1]), np.array(lin), np.array(ang))


def copy(src: OdeBackend, bodies: dict[int, Physical], joints: dict[int, Joint],
         sleep: bool = False, plane: bool = False) -> OdeBackend:
    """A fresh world with ``src``'s bodies where they are now and its joints as first made
    (and the ground plane first, as the original made it)."""
    state = src.read_state()
    dst = OdeBackend(WorldSettings(auto_sleep=sleep, solver_seed=src.solver_seed))
    if plane:
        dst.add_static_plane()
    for i, key in enumerate(state.keys.tolist()):
        add(dst, key, bodies[key], (state.position[i], state.orientation[i]),
            state.linear_velocity[i], state.angular_velocity[i])
    for key, joint in joints.items():
        dst.add_joint(key, joint)
    for key, s in src.sleep_states().items():
        dst.set_sleep_state(key, s)
    return dst


def steps(b: OdeBackend, n: int) -> np.ndarray:
    for _ in range(n):
        b.step(DT)
    s = b.read_state()
    return np.hstack([s.position, s.orientation, s.linear_velocity, s.angular_velocity])


@pytest.mark.parametrize("name", list(JOINTS))
def test_a_joint_made_from_its_reference_poses_continues_exactly(name: str) -> None:
    bodies = {1: box(), 2: box((0.3, 0.3, 0.3))}
    original = world()
    for key, (pos, quat, lin, ang) in START.items():
        add(original, key, bodies[key], (pos, quat), lin, ang)
    joint = dataclasses.replace(JOINTS[name])
    original.add_joint(10, joint)  # no reference: made where the bodies start
    before = steps(original, 120)
    reference = tuple((*START[k][0], *START[k][1]) if k is not None else None
                      for k in (joint.body_a, joint.body_b))
    again = copy(original, bodies, {10: dataclasses.replace(joint, reference=reference)})
    np.testing.assert_allclose(steps(again, 100), steps(original, 100), atol=1e-9, rtol=0)
    moved = np.abs(steps(original, 0) - before)[:, :3].max()
    assert moved > 0.01, f"{name}: nothing moved ({moved})"


def test_a_reference_at_the_bodies_own_pose_changes_nothing() -> None:
    """First creation passes the spawn poses as the reference: bit-identical to none."""
    runs = []
    for reference in (None, ((*START[1][0], *START[1][1]), (*START[2][0], *START[2][1]))):
        b = world()
        for key, (pos, quat, lin, ang) in START.items():
            add(b, key, box(), (pos, quat), lin, ang)
        b.add_joint(10, Joint("hinge", 1, 2, (1.0, 0.0, 2.0), reference=reference))
        runs.append(steps(b, 100))
    assert np.array_equal(runs[0], runs[1])


def test_bad_reference_poses_are_refused_and_move_nothing() -> None:
    b = world()
    add(b, 1, box(), START[1][:2])
    add(b, 2, box(), START[2][:2])
    before = b.read_state().position.copy()
    with pytest.raises(ValueError, match="reference pose of body_b"):
        b.add_joint(10, Joint("hinge", 1, 2, reference=((0.0,) * 7, (1.0, 2.0))))
    assert not b.has_joint(10)
    np.testing.assert_array_equal(b.read_state().position, before)


def test_sleep_state_restored_in_a_copy_sleeps_on_the_same_step() -> None:
    """Boxes settling at different times (one slides a while), copied while they are
    quiet, asleep or still moving: the copy goes on step for step the same."""
    bodies = {k: box((0.5, 0.5, 0.5)) for k in range(1, 5)}
    src = world(sleep=True)
    src.add_static_plane()
    for k in range(1, 5):
        add(src, k, bodies[k], ((2.0 * k, 0.0, 0.25 + 0.1 * k), I4),
            (1.5 if k == 4 else 0.0, 0.0, 0.0))
    for at in (30, 25, 15, 20, 40):
        steps(src, at)
        dst = copy(src, bodies, {}, sleep=True, plane=True)
        for _ in range(40):
            # a sleeper's quaternion, normalised again when it is re-made, may differ by
            # an ulp: ODE leaves a sleeper as it is
            np.testing.assert_allclose(steps(src, 1), steps(dst, 1), atol=1e-12, rtol=0)
            assert src.sleeping_count() == dst.sleeping_count()
    assert src.sleeping_count() == 4


def test_sleep_states_report_and_restore_the_rules_state() -> None:
    b = world(sleep=True)
    b.add_static_plane()
    add(b, 1, box((0.5, 0.5, 0.5)), ((0.0, 0.0, 0.25), I4))
    add(b, 2, box(), ((5.0, 0.0, 9.0), I4))  # falling: nothing to keep
    assert b.sleep_states() == {}  # fresh
    steps(b, 10)
    s = b.sleep_states()[1]
    assert not s.asleep and s.reference.shape == (6,)
    assert s.smoothed is None  # at rest: its average just follows its velocity
    assert s.timer == pytest.approx(9 * DT) and 2 not in b.sleep_states()  # from step 1
    steps(b, 60)
    s = b.sleep_states()[1]
    assert s.asleep and s.smoothed is None and s.reference is None
    b.set_sleep_state(1, SleepState(False, np.full(6, 2e-3), 0.25, np.full(6, 1e-4)))
    again = b.sleep_states()[1]
    assert (again.asleep, again.timer) == (False, 0.25) and not b.is_sleeping(1)
    np.testing.assert_array_equal(again.smoothed, np.full(6, 2e-3))
    np.testing.assert_array_equal(again.reference, np.full(6, 1e-4))
    with pytest.raises(ValueError, match="body 1: a smoothed velocity is 6 finite numbers"):
        b.set_sleep_state(1, SleepState(False, np.zeros(5)))
    with pytest.raises(KeyError, match="no body with key 7"):
        b.set_sleep_state(7, SleepState(True))


def test_an_explicit_wake_restarts_the_quiet_stretch() -> None:
    """A force (any explicit wake) starts the stretch over at the next step."""
    b = world(sleep=True)
    b.add_static_plane()
    add(b, 1, box((0.5, 0.5, 0.5)), ((0.0, 0.0, 0.25), I4))
    steps(b, 30)
    quiet = b.sleep_states()[1].timer
    assert quiet > 0.1
    b.add_force(1, np.array([0.0, 0.0, 1e-9]))
    steps(b, 1)
    s = b.sleep_states()[1]  # kept for its resting standing (the box still rests)
    assert (s.timer, s.smoothed, s.reference) == (0.0, None, None)  # afresh: no stretch
