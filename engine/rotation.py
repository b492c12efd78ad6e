"""Rotations, the one definition the engine uses: unit quaternions ``(w, x, y, z)``.

Scene files write Euler angles in degrees (:func:`euler_to_quat`,
:func:`quat_to_euler`); inside the engine every orientation is a quaternion.
Array functions broadcast over leading axes, so a whole pose table turns in one
call; the scalar helpers (:func:`rotate`) take plain sequences for the scene code.

>>> q = euler_to_quat((0.0, 0.0, 90.0))
>>> [round(c, 12) + 0.0 for c in rotate(q, (1.0, 0.0, 0.0))]
[0.0, 1.0, 0.0]
>>> local_axis(np.array(q), 0).round(12).tolist()
[0.0, 1.0, 0.0]
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

IDENTITY = (1.0, 0.0, 0.0, 0.0)
#: A quaternion whose length is this close to 1 is unit to rounding and is kept to the bit,
#: not divided by its length (a saved state's exact orientation comes back as written).
UNIT_ROUNDING = 1e-12


# -- scene angles ------------------------------------------------------------------
def euler_to_quat(deg: Sequence[float]) -> tuple[float, float, float, float]:
    """Rotation about X, then Y, then Z (extrinsic; R = Rz*Ry*Rx), angles in degrees."""
    if not any(deg):
        return IDENTITY
    rx, ry, rz = deg
    hx, hy, hz = math.radians(rx) * 0.5, math.radians(ry) * 0.5, math.radians(rz) * 0.5
    cx, sx = math.cos(hx), math.sin(hx)
    cy, sy = math.cos(hy), math.sin(hy)
    cz, sz = math.cos(hz), math.sin(hz)
    return (cz * cy * cx + sz * sy * sx,
            cz * cy * sx - sz * sy * cx,
            cz * sy * cx + sz * cy * sx,
            sz * cy * cx - cz * sy * sx)


def quat_to_euler(q: Sequence[float]) -> tuple[float, float, float]:
    """Inverse of :func:`euler_to_quat` (degrees; Y clamped at the gimbal-lock poles)."""
    w, x, y, z = q
    n = math.sqrt(w * w + x * x + y * y + z * z) or 1.0
    w, x, y, z = w / n, x / n, y / n, z / n
    rx = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    ry = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    rz = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return (math.degrees(rx), math.degrees(ry), math.degrees(rz))


def rotate(q: Sequence[float], v: Sequence[float]) -> tuple[float, float, float]:
    """``v`` rotated by the unit quaternion ``q`` (plain floats, no numpy)."""
    w, x, y, z = q
    vx, vy, vz = v
    tx = 2 * (y * vz - z * vy)
    ty = 2 * (z * vx - x * vz)
    tz = 2 * (x * vy - y * vx)
    return (vx + w * tx + y * tz - z * ty,
            vy + w * ty + z * tx - x * tz,
            vz + w * tz + x * ty - y * tx)



def quat_product(p: Sequence[float], q: Sequence[float]) -> tuple[float, float, float, float]:
    """``p ⊗ q`` of plain sequences: :func:`quat_multiply` for one pair, without numpy's
    per-call cost (the input layer turns a thousand tracker samples a second)."""
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return (pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw)


def rotation_vector(q_from: Sequence[float], q_to: Sequence[float]
                    ) -> tuple[float, float, float]:
    """:func:`rotation_vector_between` for one pair of plain sequences."""
    w, x, y, z = quat_product(q_to, (q_from[0], -q_from[1], -q_from[2], -q_from[3]))
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-12:
        return (2.0 * x, 2.0 * y, 2.0 * z)
    scale = 2.0 * math.atan2(s, w) / s
    return (x * scale, y * scale, z * scale)


def quat_from_rotation_vector(v: Sequence[float]) -> tuple[float, float, float, float]:
    """The unit quaternion turning by ``|v|`` radians about ``v`` (inverse of the above)."""
    x, y, z = v
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-12:
        return (1.0, 0.5 * x, 0.5 * y, 0.5 * z)
    s = math.sin(0.5 * angle) / angle
    return (math.cos(0.5 * angle), x * s, y * s, z * s)

# -- quaternion algebra (numpy, broadcasting) -----------------------------------------
def quat_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p ⊗ q`` (apply ``q`` first, then ``p``); broadcasts over rows."""
    pw, px, py, pz = np.moveaxis(np.asarray(p, dtype=np.float64), -1, 0)
    qw, qx, qy, qz = np.moveaxis(np.asarray(q, dtype=np.float64), -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def quat_conjugate(q: np.ndarray) -> np.ndarray:
    """The inverse rotation of a unit quaternion."""
    return np.asarray(q, dtype=np.float64) * np.array([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q: np.ndarray) -> np.ndarray:
    """``q`` scaled to unit length (a zero quaternion stays zero)."""
    q = np.asarray(q, dtype=np.float64)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    return q / np.where(norm == 0.0, 1.0, norm)


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` from quaternions ``(..., 4)`` (normalised first)."""
    q = quat_normalize(q)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(q.shape[:-1] + (3, 3))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - z * w)
    out[..., 0, 2] = 2 * (x * z + y * w)
    out[..., 1, 0] = 2 * (x * y + z * w)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - x * w)
    out[..., 2, 0] = 2 * (x * z - y * w)
    out[..., 2, 1] = 2 * (y * z + x * w)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def compose(position: np.ndarray, orientation: np.ndarray, scale: np.ndarray | None = None
            ) -> np.ndarray:
    """Model matrices ``(..., 4, 4)`` = translate · rotate · scale, batched over leading axes."""
    position = np.asarray(position, dtype=np.float64)
    rot = quat_to_matrix(orientation)
    out = np.zeros(rot.shape[:-2] + (4, 4))
    if scale is not None:
        rot = rot * np.asarray(scale, dtype=np.float64)[..., None, :]
    out[..., :3, :3] = rot
    out[..., :3, 3] = position
    out[..., 3, 3] = 1.0
    return out


def local_axis(q: np.ndarray, index: int) -> np.ndarray:
    """World direction of the body's local X (0), Y (1) or Z (2) axis: a matrix column."""
    return quat_to_matrix(q)[..., :, index]


def matrix_to_quat(m: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a 3x3 rotation matrix."""
    return matrices_to_quats(m)


def matrices_to_quats(m: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` of rotation matrices ``(..., 3, 3)``, batched: each
    from its largest component (w when the trace is positive), so none divides by a
    small number."""
    m = np.asarray(m, dtype=np.float64)
    m00, m11, m22 = m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]
    pick = np.where(m00 + m11 + m22 > 0, 0, np.where((m00 > m11) & (m00 > m22), 1,
                                                      np.where(m11 > m22, 2, 3)))
    square = np.stack([1.0 + m00 + m11 + m22, 1.0 + m00 - m11 - m22,
                       1.0 - m00 + m11 - m22, 1.0 - m00 - m11 + m22], axis=-1)
    s = 2.0 * np.sqrt(np.maximum(np.take_along_axis(square, pick[..., None], -1)[..., 0],
                                 1e-300))
    d21, d02, d10 = m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], \
        m[..., 1, 0] - m[..., 0, 1]
    s01, s02, s12 = m[..., 0, 1] + m[..., 1, 0], m[..., 0, 2] + m[..., 2, 0], \
        m[..., 1, 2] + m[..., 2, 1]
    quarter = 0.25 * s
    candidates = np.stack([
        np.stack([quarter, d21 / s, d02 / s, d10 / s], axis=-1),
        np.stack([d21 / s, quarter, s01 / s, s02 / s], axis=-1),
        np.stack([d02 / s, s01 / s, quarter, s12 / s], axis=-1),
        np.stack([d10 / s, s02 / s, s12 / s, quarter], axis=-1)], axis=-2)
    q = np.take_along_axis(candidates, pick[..., None, None], -2)[..., 0, :]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def slerp(q0: np.ndarray, q1: np.ndarray, t: float | np.ndarray) -> np.ndarray:
    """Spherical interpolation between batches of unit quaternions ``(..., 4)``."""
    q0 = np.asarray(q0, dtype=np.float64)
    q1 = np.asarray(q1, dtype=np.float64).copy()
    t = np.asarray(t, dtype=np.float64)[..., None] if np.ndim(t) else float(t)
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0.0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin_theta = np.sin(theta)
    near = sin_theta < 1e-6
    safe = np.where(near, 1.0, sin_theta)
    w0 = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) / safe)
    w1 = np.where(near, t, np.sin(t * theta) / safe)
    out = w0 * q0 + w1 * q1
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def rotation_vector_between(q_from: np.ndarray, q_to: np.ndarray) -> np.ndarray:
    """World-frame rotation vector (axis · angle, the short way) turning ``q_from`` into
    ``q_to``: what an angular velocity must integrate to over one unit of time."""
    d = quat_multiply(q_to, quat_conjugate(q_from))
    d = np.where(d[..., :1] < 0, -d, d)
    s = np.linalg.norm(d[..., 1:], axis=-1, keepdims=True)
    small = s < 1e-12
    angle = 2.0 * np.arctan2(s, d[..., :1])
    return np.where(small, 2.0 * d[..., 1:], d[..., 1:] / np.where(small, 1.0, s) * angle)


#: Lengths below this are taken as zero when turning one direction into another.
_TINY = 1e-9


def axis_angle_matrices(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(n, 3, 3)`` about unit ``axis`` by ``angle`` (Rodrigues)."""
    x, y, z = axis[:, 0], axis[:, 1], axis[:, 2]
    c, s = np.cos(angle), np.sin(angle)
    k = 1.0 - c
    return np.stack([
        np.stack([c + x * x * k, x * y * k - z * s, x * z * k + y * s], -1),
        np.stack([y * x * k + z * s, c + y * y * k, y * z * k - x * s], -1),
        np.stack([z * x * k - y * s, z * y * k + x * s, c + z * z * k], -1)], axis=1)


def from_to(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The smallest rotations ``(n, 3, 3)`` turning directions ``u`` into ``v``."""
    un = u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), _TINY)
    vn = v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), _TINY)
    cross = np.cross(un, vn)
    s = np.linalg.norm(cross, axis=1)
    angle = np.arctan2(s, np.einsum("ij,ij->i", un, vn))
    fallback = np.cross(un, np.where(np.abs(un[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    axis = np.where((s > _TINY)[:, None], cross, fallback)
    axis /= np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), _TINY)
    return axis_angle_matrices(axis, angle)


def view_problem(forward: Sequence[float]) -> str | None:
    """Why a camera (or listener) looking along ``forward`` has no well-defined view, or
    None. Up is +Z: looking along it leaves the picture's roll, and left and right for
    3D sound, undefined; a zero direction (LookAt at the eye) looks nowhere.

    >>> view_problem((0, 1, 0)) is None, view_problem((0, 0, 0))[:22], view_problem((0, 0, -2))[:21]
    (True, 'it looks at its own po', 'it looks straight dow')
    """
    f = np.asarray(forward, dtype=np.float64)
    length = float(np.linalg.norm(f))
    if not length > 1e-9:
        return "it looks at its own position (LookAt equals where it is), so it looks nowhere"
    if math.hypot(f[0], f[1]) <= 1e-6 * length:
        way = "up" if f[2] > 0 else "down"
        return (f"it looks straight {way}, along the up axis (Z), so which way is up in the "
                "picture, and left and right for 3D sound, is undefined")
    return None
