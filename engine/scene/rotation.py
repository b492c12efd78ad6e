"""Euler degrees (the scene format's orientation) <-> unit quaternions (w, x, y, z)."""

from __future__ import annotations

import math
from collections.abc import Sequence


def euler_to_quat(deg: Sequence[float]) -> tuple[float, float, float, float]:
    """Rotation about X, then Y, then Z (extrinsic; R = Rz*Ry*Rx), angles in degrees."""
    if not any(deg):
        return (1.0, 0.0, 0.0, 0.0)
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
    """``v`` rotated by the unit quaternion ``q``."""
    w, x, y, z = q
    vx, vy, vz = v
    tx = 2 * (y * vz - z * vy)
    ty = 2 * (z * vx - x * vz)
    tz = 2 * (x * vy - y * vx)
    return (vx + w * tx + y * tz - z * ty,
            vy + w * ty + z * tx - x * tz,
            vz + w * tz + x * ty - y * tx)


def exact_degrees(rad: float) -> float:
    """Degrees ``d`` with ``math.radians(d) == rad`` when such a float exists (nearest else).

    A saved state writes angular velocities in degrees; this keeps the reload bit-exact
    for most values and within one ulp for the rest.
    """
    d = math.degrees(rad)
    up = down = d
    for _ in range(4):
        if math.radians(up) == rad:
            return up
        if math.radians(down) == rad:
            return down
        up, down = math.nextafter(up, math.inf), math.nextafter(down, -math.inf)
    return d
