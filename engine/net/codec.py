"""Poses on the wire: keyframes in float32, the frames between as small changes.

A *keyframe* carries every replicated body's pose as float32 (position, orientation
``w x y z``). Each frame after it carries only the bodies that moved since the frame
before, each as its change: the position in steps of :data:`POSITION_STEP` m and the
rotation ``conj(q_before) ⊗ q`` as three components in steps of 1/:data:`ROTATION_SCALE`
(``w`` implied, >= 0) — sent as the difference from the body's change the frame before,
which a body moving or spinning steadily makes nearly 0.
The server encodes every change from what the nodes will have decoded (it keeps their
copy, :attr:`PoseCoder.mirror`), so rounding never adds up over frames, and a body that
came to rest is sent until the nodes hold its exact resting pose (to a step).

A change applies only on top of the message before it (``ref``): a node that missed one
cannot decode the next (:class:`Gap`) and waits for a keyframe, which it asks for. The
set of bodies changing (a spawn, a removal) always makes a keyframe.

Changes over a frame are small numbers whose high bytes are mostly 0x00 or 0xFF, so the
arrays are split into byte planes (all first bytes, then all second bytes, ...) before
zlib, which then squeezes them well; ids go as differences of the sorted ids.

>>> import numpy as np
>>> ids = np.array([3, 4, 9], np.uint32)
>>> poses = np.array([[0, 0, 1, 1, 0, 0, 0]] * 3, np.float64)
>>> coder, decoder = PoseCoder(), PoseDecoder()
>>> decoder.decode(coder.encode(ids, poses))[0].tolist()
[3, 4, 9]
>>> poses[0, 0] = 0.5                                     # one body moved
>>> moved, now = decoder.decode(coder.encode(ids, poses))
>>> moved.tolist(), bool(abs(now[0, 0] - 0.5) <= POSITION_STEP / 2)
([3], True)
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

from engine.rotation import quat_multiply

#: Position resolution of a delta (m): 2**-13, about 0.12 mm; int32 holds +-262 km.
POSITION_STEP = 2.0 ** -13
#: Rotation resolution of a delta: int16 units of a quaternion component.
ROTATION_SCALE = 32767.0

_KEY, _DELTA = 1, 2
_HEAD = struct.Struct("<BIII")  # kind, sequence number, the one it builds on, count


class CodecError(ValueError):
    """A pose blob that cannot be decoded (truncated, corrupt, or of an unknown keyframe)."""


def _planes(array: np.ndarray) -> bytes:
    """The bytes of ``array`` (little-endian rows) as byte planes: byte 0 of every row, ..."""
    if not len(array):
        return b""
    raw = np.ascontiguousarray(array).view(np.uint8).reshape(len(array), -1)
    return raw.T.tobytes()


def _unplanes(data: memoryview, n: int, dtype: np.dtype, width: int) -> np.ndarray:
    row = np.dtype(dtype).itemsize * width
    planes = np.frombuffer(data, np.uint8, count=n * row).reshape(row, n)
    return np.ascontiguousarray(planes.T).view(dtype).reshape(n, width)


def _id_deltas(ids: np.ndarray) -> np.ndarray:
    out = np.empty(len(ids), np.uint32)
    if len(ids):
        out[0] = ids[0]
        np.subtract(ids[1:], ids[:-1], out=out[1:], casting="unsafe")
    return out


class Gap(CodecError):
    """A change whose message before it was not decoded here: wait for a keyframe."""


def _turn(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Rotations ``conj(before) ⊗ after``, w made >= 0 (the same rotation)."""
    turn = quat_multiply(before * _CONJ, after)
    turn *= np.where(turn[:, :1] < 0, -1.0, 1.0)
    return turn


def _apply_change(before: np.ndarray, steps: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Poses after a change: the arithmetic both ends do, so they agree to the bit."""
    xyz = rotation / ROTATION_SCALE
    w = np.sqrt(np.clip(1.0 - (xyz ** 2).sum(axis=1), 0.0, 1.0))
    after = np.empty_like(before)
    after[:, :3] = before[:, :3] + steps * POSITION_STEP
    q = quat_multiply(before[:, 3:], np.column_stack([w, xyz]))
    after[:, 3:] = q / np.linalg.norm(q, axis=1, keepdims=True)
    return after


_CONJ = np.array([1.0, -1.0, -1.0, -1.0])


def _from_key(exact: np.ndarray) -> np.ndarray:
    """A keyframe's float32 poses as both ends hold them: float64, unit quaternions."""
    poses = exact.astype(np.float64)
    poses[:, 3:] /= np.linalg.norm(poses[:, 3:], axis=1, keepdims=True)
    return poses


def _predicted(last: np.ndarray, moved: np.ndarray, change: np.ndarray) -> np.ndarray:
    """What is sent of each moved body's change: its difference from the body's change the
    frame before (0 for a body that did not move then), which is about 0 for anything
    moving steadily. ``last`` becomes this frame's changes."""
    residual = change - last[moved]
    last[:] = 0.0
    last[moved] = change
    return residual


class PoseCoder:
    """The server side: encodes each frame's poses against what the nodes hold."""

    def __init__(self) -> None:
        self.seq = 0
        #: The replicated bodies' ids (sorted) and poses as the nodes decode them.
        self.ids = np.zeros(0, np.uint32)
        self.mirror = np.zeros((0, 7))
        self.last = np.zeros((0, 6))
        self.key_wanted = True

    def encode(self, ids: np.ndarray, poses: np.ndarray) -> bytes:
        """This frame's message: a keyframe when one is wanted (:attr:`key_wanted`) or the
        set of bodies changed, else the changes of the bodies that moved. ``ids`` sorted
        uint32, ``poses`` (n, 7) float64."""
        ids = np.asarray(ids, np.uint32)
        self.seq += 1
        if self.key_wanted or len(ids) != len(self.ids) or (ids != self.ids).any():
            self.key_wanted = False
            exact = np.asarray(poses, np.float32)
            self.ids, self.mirror = ids.copy(), _from_key(exact)
            self.last = np.zeros((len(ids), 6))
            body = _planes(_id_deltas(ids)[:, None]) + exact.tobytes()
            return _HEAD.pack(_KEY, self.seq, 0, len(ids)) + zlib.compress(body, 1)
        mirror = self.mirror
        steps = np.rint((poses[:, :3] - mirror[:, :3]) / POSITION_STEP)
        turn = _turn(mirror[:, 3:], poses[:, 3:7])
        rotation = np.rint(turn[:, 1:] * ROTATION_SCALE)
        moved = np.flatnonzero((steps != 0).any(axis=1) | (rotation != 0).any(axis=1))
        change = np.column_stack([np.clip(steps[moved], -2**30, 2**30), rotation[moved]])
        mirror[moved] = _apply_change(mirror[moved], change[:, :3], change[:, 3:])
        residual = _predicted(self.last, moved, change)
        body = _planes(_id_deltas(ids[moved])[:, None]) + _planes(residual.astype("<i4"))
        return _HEAD.pack(_DELTA, self.seq, self.seq - 1, len(moved)) + zlib.compress(body, 1)


class PoseDecoder:
    """The node side: every replicated body's pose as the server's messages say."""

    def __init__(self) -> None:
        self.seq = -1
        self.ids = np.zeros(0, np.uint32)
        self.poses = np.zeros((0, 7))
        self.last = np.zeros((0, 6))

    def decode(self, blob: bytes | memoryview) -> tuple[np.ndarray, np.ndarray]:
        """The ids the message names and their poses now (float64). Raises :class:`Gap`
        for a change on top of a message not decoded here, CodecError for a blob that
        does not decode."""
        if len(blob) < _HEAD.size:
            raise CodecError("pose blob shorter than its header")
        kind, seq, ref, n = _HEAD.unpack_from(blob)
        if kind == _DELTA and ref != self.seq:
            raise Gap(f"change {seq} is on top of {ref}; this node holds {self.seq}")
        row = 4 + (28 if kind == _KEY else 24)
        if kind not in (_KEY, _DELTA) or n > (1 << 24):
            raise CodecError(f"pose blob of unknown kind {kind} or size {n}")
        try:
            body = memoryview(zlib.decompressobj().decompress(bytes(blob[_HEAD.size:]),
                                                              n * row + 1))
        except zlib.error as exc:
            raise CodecError(f"pose blob does not decompress: {exc}") from None
        if len(body) != n * row:
            raise CodecError(f"pose blob holds {len(body)} bytes, not {n} bodies")
        ids = np.cumsum(_unplanes(body, n, np.dtype("<u4"), 1)[:, 0], dtype=np.uint32)
        if kind == _KEY:
            poses = _from_key(np.frombuffer(body[4 * n:], "<f4").reshape(n, 7))
            self.seq, self.ids, self.poses = seq, ids, poses
            self.last = np.zeros((n, 6))
            return ids, poses.copy()
        where = np.searchsorted(self.ids, ids)
        if len(ids) and (where.max() >= len(self.ids) or (self.ids[where] != ids).any()):
            raise CodecError("a change names bodies its keyframe does not hold")
        residual = _unplanes(body[4 * n:], n, np.dtype("<i4"), 6).astype(np.float64)
        change = residual + self.last[where]
        self.last[:] = 0.0
        self.last[where] = change
        after = _apply_change(self.poses[where], change[:, :3], change[:, 3:])
        self.poses[where] = after
        self.seq = seq
        return ids, after
