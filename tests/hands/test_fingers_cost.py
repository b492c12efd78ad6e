"""The fingered hand's per-frame shortcuts (issue 29's cost) give what the general
routines give: fingertips from quaternions without matrices, ghost capsules turned from the half-way
vector, a sample's joints made arrays once and shared read-only, fingertips read from the
pose table in one go, and a hidden ghost left where it is."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from app.bench import fingers as bench
from components import Transform
from engine.rotation import from_to, matrices_to_quats, quat_to_matrix
from services.input.hand_pose import pose_hand
from systems import _fingers, hand_fingers, hand_ghost
from systems.hands import Hands

FINGERS = ("thumb", "index", "middle", "ring", "little")


def _unit_quats(n: int, seed: int = 3) -> np.ndarray:
    q = np.random.default_rng(seed).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_far_ends_lie_along_each_pose_s_x_axis():
    """The compiled far ends against the quaternions' matrices, for all rows and for some
    rows picked out of a larger table (the distal bones' rows of the pose table)."""
    q = _unit_quats(64)
    poses = np.hstack([np.random.default_rng(4).normal(size=(64, 3)), q,
                       np.zeros((64, 6))])
    lengths = np.linspace(0.01, 0.05, 64)
    want = poses[:, :3] + quat_to_matrix(q)[:, :, 0] * (lengths / 2)[:, None]
    np.testing.assert_allclose(_fingers.far_ends(poses, lengths), want, atol=1e-12)
    rows = np.arange(64, dtype=np.int64)[5::7]
    np.testing.assert_allclose(_fingers.far_ends(poses, lengths[5::7], rows), want[5::7],
                               atol=1e-12)


def test_ghost_capsules_turn_z_onto_each_bone_the_shortest_way():
    hand = pose_hand("right", (0.1, -0.2, 1.1), tuple(_unit_quats(1)[0]),
                     dict.fromkeys(FINGERS, 0.6))
    centres, quats, sizes = hand_ghost.bone_capsules(hand)
    p, r = np.asarray(hand.positions), np.asarray(hand.radii)
    along = p[hand_ghost._B] - p[hand_ghost._A]
    lengths = np.linalg.norm(along, axis=1)
    np.testing.assert_allclose(centres, (p[hand_ghost._A] + p[hand_ghost._B]) / 2, atol=1e-15)
    np.testing.assert_allclose(sizes[:, 1], lengths, atol=1e-15)
    np.testing.assert_allclose(sizes[:, 0], (r[hand_ghost._A] + r[hand_ghost._B]) / 2)
    shortest = matrices_to_quats(from_to(np.tile([0.0, 0.0, 1.0], (len(along), 1)), along))
    same = np.minimum(np.abs(quats - shortest).max(axis=1),
                      np.abs(quats + shortest).max(axis=1))
    assert same.max() < 1e-12
    down = hand_ghost._up_to(np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]))
    np.testing.assert_allclose(quat_to_matrix(down)[:, :, 2], [[0, 0, -1], [0, 0, 1]],
                               atol=1e-12)


def test_a_sample_s_joint_arrays_are_made_once_and_cannot_be_changed():
    hand = pose_hand("left", (0.0, 0.0, 1.0), (1.0, 0.0, 0.0, 0.0),
                     dict.fromkeys(FINGERS, 0.2), left=True)
    p, q = hand_fingers.joint_arrays(hand)
    assert hand_fingers.joint_arrays(hand)[0] is p
    np.testing.assert_array_equal(p, np.asarray(hand.positions))
    np.testing.assert_array_equal(q, np.asarray(hand.orientations))
    with pytest.raises(ValueError):
        p[0, 0] = 1.0
    other = pose_hand("left", (0.0, 0.0, 1.0), (1.0, 0.0, 0.0, 0.0),
                      dict.fromkeys(FINGERS, 0.2), left=True)
    assert hand_fingers.joint_arrays(other)[0] is not p  # equal, but another sample


def test_fingertips_from_the_pose_table_are_the_distal_bones_far_ends(tmp_path: Path):
    """Read in the running engine, each frame, against the bones' own Transforms."""
    feed = bench._waving("right", 0)
    seen: list[float] = []

    def note(engine, ids) -> None:
        fingers = engine.resource(Hands).rigs[ids["hand_r"]].fingers
        if fingers is None:
            return
        ends = []
        for f in range(5):
            t = engine.world.component_for_entity(fingers.bones[3 * f + 2], Transform)
            ends.append(t.position + quat_to_matrix(t.orientation)[:, 0]
                        * fingers.lengths[3 * f + 2] / 2)
        seen.append(float(np.abs(hand_fingers.tips_now(engine, fingers) - ends).max()))

    bench.run(bench.TABLE + bench.hand("hand_r", "right", (-0.6, -0.3, 1.1)), tmp_path,
              {"right": feed}, 0.3, note, settle=0.0)
    assert len(seen) > 30 and max(seen) < 1e-12


@pytest.mark.parametrize("left", [False, True])
def test_compiled_joint_angles_are_the_flexions_and_spreads(left: bool):
    """Every joint's flexion as :func:`services.input.hand_pose.flexion` reads it, and each
    base's spread, seen along its axis, as a plain numpy atan2 gives it: random turns,
    curls and spread axes, a right and a left hand."""
    from services.input.hand_pose import flexion

    rng = np.random.default_rng(11 + left)
    for trial in range(5):
        curls = dict(zip(FINGERS, rng.uniform(0.0, 0.9, 5), strict=True))
        hand = pose_hand("h", tuple(rng.normal(size=3)), tuple(_unit_quats(1, trial)[0]),
                         curls, left=left)
        p, q = hand_fingers.joint_arrays(hand)
        axes = rng.normal(size=(5, 3))
        axes /= np.linalg.norm(axes, axis=1, keepdims=True)
        got = hand_fingers.joint_angles(p, q, hand_fingers.angle_forms(p, q, axes))
        np.testing.assert_allclose(got[:, 0], np.ravel([flexion(hand)[f] for f in FINGERS]),
                                   atol=1e-9)
        wrist = quat_to_matrix(q[1])
        thumb = wrist @ hand_fingers.THUMB_REST[int(left)]
        for k, i in enumerate(hand_fingers.BASES):
            a = thumb if i == 0 else p[hand_fingers.PARENT_B[i]] - p[hand_fingers.PARENT_A[i]]
            b = p[hand_fingers.ENDS[i]] - p[hand_fingers.STARTS[i]]
            s = axes[k]
            want = np.arctan2(np.cross(a, b) @ s, a @ b - (a @ s) * (b @ s))
            assert abs(got[i, 1] - want) < 1e-9
        assert not got[np.setdiff1d(np.arange(15), hand_fingers.BASES), 1].any()


def test_joints_through_a_frame_and_the_palm_s_motion():
    """A sample read through a frame (a wheelchair) is ``R p + t`` and ``f ⊗ q``; the
    palm's velocities are finite differences, the turn the short way round, kept while
    no newer sample comes and zero once the samples are stale."""
    from engine.rotation import quat_multiply, rotation_vector

    hand = pose_hand("h", (0.1, 0.2, 1.0), tuple(_unit_quats(1, 5)[0]),
                     dict.fromkeys(FINGERS, 0.3))
    frame = Transform(np.array([1.0, -2.0, 0.5]), _unit_quats(1, 6)[0] * 2.0)  # unnormalised
    p, q = hand_fingers.world_joints(hand, frame)
    raw_p, raw_q = np.asarray(hand.positions), np.asarray(hand.orientations)
    np.testing.assert_allclose(p, raw_p @ quat_to_matrix(frame.orientation).T + frame.position,
                               atol=1e-12)
    np.testing.assert_allclose(q, quat_multiply(frame.orientation, raw_q), atol=1e-12)
    later = pose_hand("h", (0.13, 0.18, 1.02), tuple(_unit_quats(1, 7)[0]),
                      dict.fromkeys(FINGERS, 0.3), timestamp=0.02)
    first = hand_fingers.palm_pose(None, hand, None, 0.0, 0.1)
    assert not first[3].any() and not first[4].any()
    t, p1, q1, v, w = hand_fingers.palm_pose(first, later, None, 0.02, 0.1)
    np.testing.assert_allclose(v, (np.asarray(later.positions[0]) - first[1]) / 0.02,
                               atol=1e-9)
    np.testing.assert_allclose(w, np.array(rotation_vector(first[2].tolist(), q1.tolist()))
                               / 0.02, atol=1e-9)
    kept = hand_fingers.palm_pose((t, p1, q1, v, w), later, None, 0.03, 0.1)
    np.testing.assert_array_equal(kept[3], v)
    stale = hand_fingers.palm_pose((t, p1, q1, v, w), later, None, 0.5, 0.1)
    assert not stale[3].any() and not stale[4].any()
