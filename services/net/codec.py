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

The wire format (little-endian): a header ``kind (u8), seq (u32), ref (u32), count n
(u32)`` (kind 1 keyframe, ref 0; kind 2 change, ref = seq - 1), then a zlib stream of:

* keyframe (stored, zlib level 0: float32 noise hardly compresses, and level 1 took a
  millisecond of the sender's time for 2,000 bodies): the ids' differences (the first id,
  then each id minus the one before; ids ascending) as uint32 in byte planes (byte 0 of
  every id, then byte 1, ...), then the ``n`` poses as float32 rows ``x y z qw qx qy qz``;
* change: the moved bodies' id differences, then their six residuals (``dx dy dz`` in
  steps, ``rx ry rz`` in rotation units, each the change minus the body's change the
  frame before, wrapping in 32 bits) zigzagged to uint32 (``(r << 1) ^ (r >> 31)``: 0,
  -1, 1, -2 ... become 0, 1, 2, 3 ...), each column in byte planes: the residuals are
  small, so all but the first plane are nearly all zero bytes, which zlib (level 1)
  squeezes fast.

Both ends' per-frame arithmetic is compiled (``services/net/_codec.pyx``, without the GIL);
after quantisation it is integers, and the server's copy and a node's agree to the bit.

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

from services.net import _codec

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


def _from_key(exact: np.ndarray) -> np.ndarray:
    """A keyframe's float32 poses as both ends hold them: float64, unit quaternions."""
    poses = exact.astype(np.float64)
    poses[:, 3:] /= np.linalg.norm(poses[:, 3:], axis=1, keepdims=True)
    return poses


class PoseCoder:
    """The server side: encodes each frame's poses against what the nodes hold."""

    def __init__(self) -> None:
        self.seq = 0
        #: The replicated bodies' ids (sorted) and poses as the nodes decode them.
        self.ids = np.zeros(0, np.uint32)
        self.mirror = np.zeros((0, 7))
        #: Each body's change the frame before (steps and rotation units).
        self.last = np.zeros((0, 6), np.int32)
        self.key_wanted = True
        self._out = np.zeros(0, np.uint8)  # the body of a change, reused

    def encode(self, ids: np.ndarray, poses: np.ndarray) -> bytes:
        """This frame's message: a keyframe when one is wanted (:attr:`key_wanted`) or the
        set of bodies changed, else the changes of the bodies that moved. ``ids`` sorted
        uint32, ``poses`` (n, 7) float64."""
        ids = np.ascontiguousarray(ids, np.uint32)
        self.seq += 1
        if self.key_wanted or not np.array_equal(ids, self.ids):
            self.key_wanted = False
            exact = np.asarray(poses, np.float32)
            self.ids, self.mirror = ids.copy(), _from_key(exact)
            self.last = np.zeros((len(ids), 6), np.int32)
            body = _planes(_id_deltas(ids)[:, None]) + exact.tobytes()
            return _HEAD.pack(_KEY, self.seq, 0, len(ids)) + zlib.compress(body, 0)
        poses = np.ascontiguousarray(poses, np.float64)
        if len(self._out) < _codec.ROW * len(ids):
            self._out = np.empty(_codec.ROW * len(ids), np.uint8)
        moved = _codec.encode_changes(ids, poses, self.mirror, self.last, self._out)
        body = memoryview(self._out)[:_codec.ROW * moved]
        return _HEAD.pack(_DELTA, self.seq, self.seq - 1, moved) + zlib.compress(body, 1)


class PoseDecoder:
    """The node side: every replicated body's pose as the server's messages say."""

    def __init__(self) -> None:
        self.seq = -1
        self.ids = np.zeros(0, np.uint32)
        self.poses = np.zeros((0, 7))
        self.last = np.zeros((0, 6), np.int32)

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
        if kind == _KEY:
            ids = np.cumsum(_unplanes(body, n, np.dtype("<u4"), 1)[:, 0], dtype=np.uint32)
            poses = _from_key(np.frombuffer(body[4 * n:], "<f4").reshape(n, 7))
            self.seq, self.ids, self.poses = seq, ids, poses
            self.last = np.zeros((n, 6), np.int32)
            return ids, poses.copy()
        ids, after = np.empty(n, np.uint32), np.empty((n, 7))
        if not _codec.decode_changes(body, self.ids, self.poses, self.last, ids, after):
            raise CodecError("a change names bodies its keyframe does not hold")
        self.seq = seq
        return ids, after
