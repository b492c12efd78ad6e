"""The fingered hand's per-frame shortcuts (issue 29's cost) give what the general
routines give: fingertip axes without matrices, ghost capsules turned from the half-way
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
from systems import hand_fingers, hand_ghost
from systems.hands import Hands

FINGERS = ("thumb", "index", "middle", "ring", "little")


def _unit_quats(n: int, seed: int = 3) -> np.ndarray:
    q = np.random.default_rng(seed).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_x_axes_are_the_first_columns_of_the_quaternions_matrices():
    q = _unit_quats(64)
    np.testing.assert_allclose(hand_fingers.x_axes(q), quat_to_matrix(q)[:, :, 0],
                               atol=1e-12)
    np.testing.assert_allclose(hand_fingers.x_axes(q[2::3]), quat_to_matrix(q[2::3])[:, :, 0],
                               atol=1e-12)  # strided rows, as the distal bones are read


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
