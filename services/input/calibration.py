"""Calibration: a device's frame to the scene's, per tracker.

A raw position ``p`` becomes ``C · (s · M · p) + offset`` and a raw orientation
``R`` becomes ``C · M R Mᵀ``, where ``M`` is the axis map (``Axes "x -z y"``: which
device axis is engine X, Y, Z, with signs), ``s`` the scale (device units to metres),
and ``C`` the rotation (``Rotation``, Euler degrees) turning the remapped frame into the
scene's. ``M R Mᵀ`` is a rotation even when ``M`` mirrors (a left-handed device), so
orientations stay proper.

>>> openxr_to_engine((0.0, 1.6, -2.0), (1.0, 0.0, 0.0, 0.0))[0]
(0.0, 2.0, 1.6)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from engine.rotation import IDENTITY, matrix_to_quat, quat_product, quat_to_matrix
from engine.scene.inputs import IDENTITY_AXES, Axes, TrackerSpec, axes_map

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]


def axes_matrix(axes: Axes) -> np.ndarray:
    """The signed permutation matrix ``M`` with ``engine = M · device``."""
    m = np.zeros((3, 3))
    for row, (column, sign) in enumerate(axes):
        m[row, column] = sign
    return m


class Calibration:
    """Offset, rotation, scale and axis map of one tracker (identity by default).

    Works on plain tuples: a thousand samples a second, where numpy's per-call cost
    would be most of the time.
    """

    __slots__ = ("offset", "rotation", "scale", "axes", "is_identity", "_linear", "_before",
                 "_after")

    def __init__(self, offset: Vec3 = (0.0, 0.0, 0.0), rotation: Quat = IDENTITY,
                 scale: float = 1.0, axes: Axes = IDENTITY_AXES) -> None:
        self.offset, self.rotation, self.scale, self.axes = offset, rotation, scale, axes
        self.is_identity = (offset == (0.0, 0.0, 0.0) and rotation == IDENTITY
                            and scale == 1.0 and axes == IDENTITY_AXES)
        m = axes_matrix(axes)
        linear = quat_to_matrix(np.asarray(rotation, dtype=np.float64)) @ (scale * m)
        self._linear = tuple(tuple(float(v) for v in row) for row in linear)
        # M R Mᵀ is the conjugation by M's rotation (by -M's when M mirrors: same result)
        turn = matrix_to_quat(m if np.linalg.det(m) > 0 else -m)
        self._before = quat_product(rotation, tuple(float(v) for v in turn))
        self._after = (float(turn[0]), -float(turn[1]), -float(turn[2]), -float(turn[3]))

    @staticmethod
    def of(spec: TrackerSpec) -> Calibration:
        return Calibration(spec.offset, spec.rotation, spec.scale, spec.axes)

    def position(self, p: Sequence[float]) -> Vec3:
        (a, b, c), (d, e, f), (g, h, i) = self._linear
        x, y, z = p
        ox, oy, oz = self.offset
        return (a * x + b * y + c * z + ox, d * x + e * y + f * z + oy,
                g * x + h * y + i * z + oz)

    def velocity(self, v: Sequence[float]) -> Vec3:
        (a, b, c), (d, e, f), (g, h, i) = self._linear
        x, y, z = v
        return (a * x + b * y + c * z, d * x + e * y + f * z, g * x + h * y + i * z)

    def orientation(self, q: Sequence[float]) -> Quat:
        return quat_product(quat_product(self._before, q), self._after)


#: OpenXR's stage frame (x right, y up, -z forward) to the engine's (x right, y forward, z up).
OPENXR = Calibration(axes=axes_map("x -z y"))


def openxr_to_engine(position: Vec3, orientation: Quat) -> tuple[Vec3, Quat]:
    """An OpenXR pose (y up, looking along -z) as an engine pose (z up, looking along +y).

    A headset with identity orientation looks along OpenXR's -z; the engine's camera with
    identity orientation looks along +y: the same direction after conversion.
    """
    return OPENXR.position(position), OPENXR.orientation(orientation)
