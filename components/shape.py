"""Geometry shared by bodies and visuals: one primitive or mesh in the owner's frame."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np


class ShapeKind(StrEnum):
    """The shapes every backend and the renderer understand."""

    SPHERE = "sphere"
    BOX = "box"
    CAPSULE = "capsule"
    CYLINDER = "cylinder"
    PLANE = "plane"
    MESH = "mesh"
    HULL = "hull"


@dataclass(slots=True)
class Shape:
    """One collision or visual primitive, in the body's frame.

    ``kind`` is a :class:`ShapeKind`. ``size`` is the full extents for a box,
    ``(radius,)`` for a sphere, ``(radius, length)`` for a capsule or cylinder
    (along local Z), and the plane's normal and offset ``(nx, ny, nz, d)`` for a plane.
    """

    kind: str = ShapeKind.SPHERE
    size: tuple[float, ...] = (0.5,)
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    #: This shape's own collision bits (None: its body's ``category``/``mask``): a body
    #: of several colliders with different filters (KHR_physics_rigid_bodies, per
    #: collider). Both backends honour them.
    category: int | None = None
    mask: int | None = None
