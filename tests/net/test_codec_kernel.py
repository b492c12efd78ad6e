"""The compiled codec passes (services/net/_codec.pyx) against the wire format written in
numpy: the same bytes, the same copies of the poses to the bit, on both ends, whatever
the bodies do (rest, tumble, jump further than a change holds, turn into NaN)."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from engine.rotation import quat_multiply
from services.net import _codec
from services.net.codec import POSITION_STEP, ROTATION_SCALE, CodecError, PoseCoder, PoseDecoder
from tests.net.test_codec import tumbling

CLIP = 2 ** 30


def planes(rows: np.ndarray) -> bytes:
    """Columns of uint32 as little-endian byte planes, column after column."""
    return np.ascontiguousarray(rows, "<u4").view(np.uint8).reshape(len(rows), -1).T.tobytes()


def apply(before: np.ndarray, change: np.ndarray) -> np.ndarray:
    """Poses after integer changes, each operation in the kernel's order."""
    c = change.astype(np.float64)
    x, y, z = (c[:, 3 + k] / ROTATION_SCALE for k in range(3))
    w = np.sqrt(np.clip(1.0 - (x * x + y * y + z * z), 0.0, 1.0))
    after = np.empty_like(before)
    after[:, :3] = before[:, :3] + c[:, :3] * POSITION_STEP
    q = quat_multiply(before[:, 3:], np.column_stack([w, x, y, z]))
    norm = np.sqrt(q[:, 0] * q[:, 0] + q[:, 1] * q[:, 1] + q[:, 2] * q[:, 2] + q[:, 3] * q[:, 3])
    after[:, 3:] = q / norm[:, None]
    return after


def reference_encode(ids: np.ndarray, poses: np.ndarray, mirror: np.ndarray,
                     last: np.ndarray) -> tuple[bytes, np.ndarray, np.ndarray]:
    """A change's body, the nodes' copy after it and each body's change, in numpy."""
    steps = np.rint((poses[:, :3] - mirror[:, :3]) / POSITION_STEP)
    turn = quat_multiply(mirror[:, 3:] * np.array([1.0, -1.0, -1.0, -1.0]), poses[:, 3:])
    turn = turn * np.where(turn[:, :1] < 0, -1.0, 1.0)
    rotation = np.rint(turn[:, 1:] * ROTATION_SCALE)
    change = np.clip(np.nan_to_num(np.column_stack([steps, rotation]), nan=0.0),
                     -CLIP, CLIP).astype(np.int64)
    moved = np.flatnonzero((change != 0).any(axis=1))
    mirror = mirror.copy()
    mirror[moved] = apply(mirror[moved], change[moved])
    residual = ((change[moved] - last[moved]) & 0xFFFFFFFF).astype(np.uint32).view(np.int32)
    zigzag = ((residual << 1) ^ (residual >> 31)).view(np.uint32)
    deltas = np.diff(ids[moved].astype(np.int64), prepend=0).astype(np.uint32)
    now = np.zeros_like(last)
    now[moved] = change[moved]
    return planes(deltas[:, None]) + planes(zigzag), mirror, now


def reference_decode(body: bytes, held: np.ndarray, poses: np.ndarray,
                     last: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What a node makes of a change's body, in numpy: (ids, poses, changes)."""
    m = len(body) // 28
    rows = np.frombuffer(body, np.uint8).reshape(28, m).T.copy().view("<u4").reshape(m, 7)
    ids = np.cumsum(rows[:, 0], dtype=np.uint32)
    where = np.searchsorted(held, ids)
    zigzag = rows[:, 1:].astype(np.int64)
    residual = (zigzag >> 1) ^ -(zigzag & 1)
    change = ((residual + last[where]) & 0xFFFFFFFF).astype(np.uint32).view(np.int32)
    poses = poses.copy()
    poses[where] = apply(poses[where], change)
    now = np.zeros_like(last)
    now[where] = change
    return ids, poses, now


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and bool((a.view(np.uint64) == b.view(np.uint64)).all())


def scenes(n: int, frames: int) -> list[np.ndarray]:
    """Tumbling bodies, a third of them at rest, one jumping 300 km and back, one turning
    into NaN and then infinite, one at a pose from the far end of float64."""
    out = []
    for f, pose in enumerate(tumbling(n, frames, seed=3)):
        pose[::3] = out[0][::3] if out else pose[::3]
        if f % 7 == 3:
            pose[1, :3] += 3e5 * (1 if f % 2 else -1)
        if f >= frames // 2:
            pose[2, 0] = np.nan if f % 2 else np.inf
            pose[4, 3:] = np.nan
        out.append(pose)
    return out


def test_both_passes_match_the_numpy_format_to_the_bit() -> None:
    n = 60
    ids = np.cumsum(np.random.default_rng(5).integers(1, 2 ** 20, n)).astype(np.uint32)
    frames = scenes(n, 40)
    coder, decoder = PoseCoder(), PoseDecoder()
    decoder.decode(coder.encode(ids, frames[0]))
    mirror, last = coder.mirror.copy(), coder.last.astype(np.int64)
    held, shown, shown_last = decoder.ids.copy(), decoder.poses.copy(), last.copy()
    for pose in frames[1:]:
        blob = coder.encode(ids, pose)
        body, mirror, last = reference_encode(ids, pose, mirror, last)
        assert zlib.decompress(blob[13:]) == body
        assert same_bits(coder.mirror, mirror) and (coder.last == last).all()
        named, now = decoder.decode(blob)
        expect_ids, shown, shown_last = reference_decode(body, held, shown, shown_last)
        assert (named == expect_ids).all() and same_bits(decoder.poses, shown)
        assert same_bits(now, shown[np.searchsorted(held, named)])
        assert (decoder.last == shown_last).all()
        assert same_bits(decoder.poses, coder.mirror)  # both ends agree to the bit


def test_a_jump_further_than_a_change_holds_arrives_over_frames() -> None:
    ids = np.array([7], np.uint32)
    pose = np.array([[0.0, 0, 0, 1, 0, 0, 0]])
    coder, decoder = PoseCoder(), PoseDecoder()
    decoder.decode(coder.encode(ids, pose))
    pose[0, 0] = 3 * CLIP * POSITION_STEP  # three changes' worth
    for _ in range(3):
        decoder.decode(coder.encode(ids, pose))
    assert decoder.poses[0, 0] == pose[0, 0] and same_bits(decoder.poses, coder.mirror)
    pose[0, 0] = 0.0  # and back: a residual of -2**31, wrapping
    for _ in range(3):
        decoder.decode(coder.encode(ids, pose))
    assert decoder.poses[0, 0] == 0.0


@pytest.mark.parametrize("names", [[3, 9], [3, 3], [40]])
def test_a_change_naming_bodies_not_held_changes_nothing(names: list[int]) -> None:
    held = np.array([3, 5, 9], np.uint32)
    poses = np.tile([1.0, 2, 3, 1, 0, 0, 0], (3, 1))
    last = np.zeros((3, 6), np.int32)
    m = len(names)
    deltas = np.diff(np.array(names, np.int64), prepend=0).astype(np.uint32)
    body = planes(np.column_stack([deltas, np.full((m, 6), 2, np.uint32)]))
    ids, moved = np.empty(m, np.uint32), np.empty((m, 7))
    known = _codec.decode_changes(body, held, poses, last, ids, moved)
    assert known is (names == [3, 9])
    if known:
        assert poses[1, 0] == 1.0 and poses[0, 0] == 1.0 + POSITION_STEP
    else:
        assert (poses == np.tile([1.0, 2, 3, 1, 0, 0, 0], (3, 1))).all() and not last.any()


def test_arrays_that_disagree_are_refused_with_a_message() -> None:
    coder = PoseCoder()
    coder.encode(np.arange(3, dtype=np.uint32), np.tile([0.0, 0, 0, 1, 0, 0, 0], (3, 1)))
    with pytest.raises(ValueError, match="do not agree"):
        _codec.encode_changes(np.arange(3, dtype=np.uint32), np.zeros((2, 7)), coder.mirror,
                              coder.last, np.zeros(100, np.uint8))
    blob = bytearray(coder.encode(np.arange(3, dtype=np.uint32), np.zeros((3, 7))))
    blob[9:13] = (2).to_bytes(4, "little")  # a count the body does not hold
    decoder = PoseDecoder()
    decoder.ids, decoder.poses = np.arange(3, dtype=np.uint32), np.zeros((3, 7))
    decoder.last, decoder.seq = np.zeros((3, 6), np.int32), coder.seq - 1
    with pytest.raises(CodecError, match="not 2 bodies"):
        decoder.decode(bytes(blob))
