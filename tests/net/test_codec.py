"""Poses on the wire: what a node decodes is the server's pose to a quantisation step,
rounding never adds up, missing a frame is noticed, and a broken blob is refused."""

from __future__ import annotations

import numpy as np
import pytest

from engine.rotation import quat_multiply
from services.net.codec import (
    POSITION_STEP,
    ROTATION_SCALE,
    CodecError,
    Gap,
    PoseCoder,
    PoseDecoder,
)


def tumbling(n: int, frames: int, seed: int = 0) -> list[np.ndarray]:
    """Bodies moving and turning at up to 3 m/s and 6 rad/s, one pose set per 1/60 s."""
    rng = np.random.default_rng(seed)
    start = np.zeros((n, 7))
    start[:, :3] = rng.uniform(-50, 50, (n, 3))
    q = rng.normal(size=(n, 4))
    start[:, 3:] = q / np.linalg.norm(q, axis=1, keepdims=True)
    velocity = rng.uniform(-3, 3, (n, 3))
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    spin = rng.uniform(0, 6, (n, 1))
    out = []
    for f in range(frames):
        t = f / 60
        pose = start.copy()
        pose[:, :3] += velocity * t
        half = spin * t / 2
        pose[:, 3:] = quat_multiply(start[:, 3:], np.column_stack([np.cos(half),
                                                                   np.sin(half) * axis]))
        out.append(pose)
    return out


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return 2 * np.arccos(np.clip(np.abs((a * b).sum(axis=1)), 0, 1))


def test_decoded_poses_stay_within_one_step_over_many_frames() -> None:
    ids = np.arange(5, 505, dtype=np.uint32)
    coder, decoder = PoseCoder(), PoseDecoder()
    for pose in tumbling(len(ids), 300):
        decoder.decode(coder.encode(ids, pose))
        # float32 keyframe, then steps: never more than half a step off (plus float32's
        # own rounding of the keyframe), however many frames went by
        assert np.abs(decoder.poses[:, :3] - pose[:, :3]).max() <= POSITION_STEP / 2 + 1e-5
        assert angle_between(decoder.poses[:, 3:], pose[:, 3:]).max() < 4 / ROTATION_SCALE
        assert np.array_equal(decoder.poses, coder.mirror)  # both ends agree to the bit


def test_resting_bodies_cost_nothing_and_a_moved_one_is_named() -> None:
    ids = np.array([1, 2, 7, 40], np.uint32)
    pose = tumbling(4, 1)[0]
    coder, decoder = PoseCoder(), PoseDecoder()
    decoder.decode(coder.encode(ids, pose))
    still = coder.encode(ids, pose)
    moved, _ = decoder.decode(still)
    assert len(moved) == 0 and len(still) < 30
    pose[2, 2] += 0.25
    moved, poses = decoder.decode(coder.encode(ids, pose))
    assert moved.tolist() == [7] and poses[0, 2] == pytest.approx(pose[2, 2], abs=POSITION_STEP)


def test_a_missed_frame_is_a_gap_until_the_next_keyframe() -> None:
    ids = np.arange(10, dtype=np.uint32)
    frames = tumbling(10, 4)
    coder, decoder = PoseCoder(), PoseDecoder()
    decoder.decode(coder.encode(ids, frames[0]))
    coder.encode(ids, frames[1])  # lost on the way
    with pytest.raises(Gap):
        decoder.decode(coder.encode(ids, frames[2]))
    coder.key_wanted = True
    decoder.decode(coder.encode(ids, frames[3]))
    assert np.abs(decoder.poses[:, :3] - frames[3][:, :3]).max() < 1e-5


def test_new_bodies_make_a_keyframe() -> None:
    coder, decoder = PoseCoder(), PoseDecoder()
    pose = tumbling(3, 1)[0]
    decoder.decode(coder.encode(np.array([1, 2], np.uint32), pose[:2]))
    named, _ = decoder.decode(coder.encode(np.array([1, 2, 3], np.uint32), pose))
    assert named.tolist() == [1, 2, 3] and decoder.ids.tolist() == [1, 2, 3]


@pytest.mark.parametrize("damage", ["truncate", "flip", "short", "kind"])
def test_broken_blobs_are_refused(damage: str) -> None:
    ids = np.arange(50, dtype=np.uint32)
    blob = bytearray(PoseCoder().encode(ids, tumbling(50, 1)[0]))
    if damage == "truncate":
        blob = blob[:len(blob) // 2]
    elif damage == "flip":
        blob[20] ^= 0xFF
    elif damage == "short":
        blob = blob[:5]
    else:
        blob[0] = 9
    with pytest.raises(CodecError):
        PoseDecoder().decode(bytes(blob))


def test_a_pose_handed_over_with_its_quaternion_negated_decodes_the_same_turn() -> None:
    """q and -q are one rotation; physics hands either. A change against a quaternion of
    the other sign is the short way round, not the long: every frame here flips the sign
    of the turning bodies' quaternions, and the nodes still follow within a step."""
    ids = np.arange(1, 101, dtype=np.uint32)
    coder, decoder = PoseCoder(), PoseDecoder()
    for f, pose in enumerate(tumbling(len(ids), 120, seed=3)):
        if f % 2:
            pose[:, 3:] *= -1.0
        decoder.decode(coder.encode(ids, pose))
        assert angle_between(decoder.poses[:, 3:], pose[:, 3:]).max() < 4 / ROTATION_SCALE
