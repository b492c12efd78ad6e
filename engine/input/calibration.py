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

import numpy as np

from engine.rotation import IDENTITY, matrix_to_quat, quat_multiply, quat_to_matrix
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
    """Offset, rotation, scale and axis map of one tracker (identity by default)."""

    __slots__ = ("offset", "rotation", "scale", "axes", "is_identity", "_offset", "_rotation",
                 "_axes", "_linear")

    def __init__(self, offset: Vec3 = (0.0, 0.0, 0.0), rotation: Quat = IDENTITY,
                 scale: float = 1.0, axes: Axes = IDENTITY_AXES) -> None:
        self.offset, self.rotation, self.scale, self.axes = offset, rotation, scale, axes
        self.is_identity = (offset == (0.0, 0.0, 0.0) and rotation == IDENTITY
                            and scale == 1.0 and axes == IDENTITY_AXES)
        self._offset = np.asarray(offset, dtype=np.float64)
        self._rotation = np.asarray(rotation, dtype=np.float64)
        self._axes = axes_matrix(axes)
        self._linear = quat_to_matrix(self._rotation) @ (scale * self._axes)

    @staticmethod
    def of(spec: TrackerSpec) -> Calibration:
        return Calibration(spec.offset, spec.rotation, spec.scale, spec.axes)

    def position(self, p: np.ndarray) -> np.ndarray:
        return self._linear @ p + self._offset

    def velocity(self, v: np.ndarray) -> np.ndarray:
        return self._linear @ v

    def orientation(self, q: np.ndarray) -> np.ndarray:
        if self.axes == IDENTITY_AXES:
            return quat_multiply(self._rotation, q)
        m = self._axes
        return matrix_to_quat(quat_to_matrix(self._rotation) @ m @ quat_to_matrix(q) @ m.T)


#: OpenXR's stage frame (x right, y up, -z forward) to the engine's (x right, y forward, z up).
OPENXR = Calibration(axes=axes_map("x -z y"))


def openxr_to_engine(position: Vec3, orientation: Quat) -> tuple[Vec3, Quat]:
    """An OpenXR pose (y up, looking along -z) as an engine pose (z up, looking along +y).

    A headset with identity orientation looks along OpenXR's -z; the engine's camera with
    identity orientation looks along +y: the same direction after conversion.
    """
    p = OPENXR.position(np.asarray(position, dtype=np.float64))
    q = OPENXR.orientation(np.asarray(orientation, dtype=np.float64))
    return ((float(p[0]), float(p[1]), float(p[2])),
            (float(q[0]), float(q[1]), float(q[2]), float(q[3])))
