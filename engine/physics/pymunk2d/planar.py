"""The side-view mapping between the 3D world and pymunk's plane.

pymunk's ``(x, y)`` is the world's ``(X, Z)``: Z is up and gravity points along −Z.
A pymunk angle θ turns X toward Z (counter-clockwise in the side view); in 3D that
is a rotation by φ = −θ about +Y, because a positive turn about +Y takes X toward −Z.
So an orientation about Y is the quaternion ``(cos φ/2, 0, sin φ/2, 0)`` with φ = −θ,
and an angular velocity ω (pymunk) is ``(0, −ω, 0)`` in 3D.

An authored orientation with an out-of-plane part is split as ``q = q_y(φ) ⊗ q_rest``:
φ goes to pymunk, ``q_rest`` (a fixed tilt) is baked into the body's 2D silhouette and
put back on every orientation read, so what the renderer shows stays what the author
wrote. Y positions are kept per body as authored.
"""

from __future__ import annotations

import math

import numpy as np

#: Quaternions closer than this to ``q_y(φ)`` count as purely in-plane.
PLANAR_TOLERANCE = 1e-9


def split_orientation(q: np.ndarray) -> tuple[float, np.ndarray, bool]:
    """Split ``q`` into the pymunk angle θ and the out-of-plane rest ``q_rest``.

    Returns ``(theta, q_rest, planar)``; ``planar`` is False when ``q`` has a tilt
    that the plane cannot represent (it is then kept in ``q_rest``). Plain floats: it
    runs for every pose set (each tracked hand's control body, every frame), where numpy's
    per-call cost was most of a hand's.
    """
    w, x, y, z = (float(c) for c in np.asarray(q, dtype=np.float64).reshape(4))
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    if not math.isfinite(norm) or norm == 0.0:
        raise ValueError(f"orientation {[w, x, y, z]} is not a rotation quaternion")
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    twist_norm = math.hypot(w, y)
    if twist_norm < 1e-12:  # a half turn about a horizontal axis: no Y twist to speak of
        tw, ty = 1.0, 0.0
    else:
        tw, ty = w / twist_norm, y / twist_norm
    # rest = conj(twist) q, twist = (tw, 0, ty, 0)
    rest = (tw * w + ty * y, tw * x - ty * z, tw * y - ty * w, tw * z + ty * x)
    if rest[0] < 0.0:
        rest = (-rest[0], -rest[1], -rest[2], -rest[3])
    phi = 2.0 * math.atan2(ty, tw)
    planar = abs(rest[0] - 1.0) < PLANAR_TOLERANCE
    return -phi, np.array((1.0, 0.0, 0.0, 0.0) if planar else rest), planar
