"""3D collision shapes → pymunk shapes in the X–Z plane, with 3D mass properties.

Each shape becomes its side-view silhouette: sphere → circle; box, hull and mesh →
convex polygon of the projected vertices (a mesh loses its concavities); capsule →
rounded segment (a circle when its axis runs along Y); cylinder → rectangle, or a
circle when its axis runs along Y (a wheel); plane → a large static half-space
polygon. Mass properties stay 3D so a body weighs and spins as it does under ODE:
the mass is ``Physical.mass`` (shared among shapes by volume) or the material density
times each shape's 3D volume, and the moment about Y is the 3D one (for polygons, the
prism's: area moment times mass). The centre of mass is the body origin, as in ODE.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pymunk

from components import Shape
from engine.rotation import quat_to_matrix

#: Half-length and depth of the polygon that stands in for an infinite plane (m).
PLANE_HALF_LENGTH = 1.0e4
PLANE_DEPTH = 1.0e2
#: Points per cap circle when a tilted cylinder's silhouette is sampled.
CYLINDER_SAMPLES = 16

Warn = Callable[[str, str], None]


@dataclass(slots=True)
class BuiltShape:
    """A pymunk shape with the 3D volume and Y moment per unit mass it stands for."""

    shape: pymunk.Shape
    volume: float
    inertia_per_mass: float  # about the body origin, around Y, m²


def _box_tensor(sx: float, sy: float, sz: float) -> np.ndarray:
    return np.diag([sy * sy + sz * sz, sx * sx + sz * sz, sx * sx + sy * sy]) / 12.0


def _cylinder_tensor(radius: float, length: float) -> np.ndarray:
    side = (3.0 * radius * radius + length * length) / 12.0
    return np.diag([side, side, radius * radius / 2.0])


def _yy(rotation: np.ndarray, tensor: np.ndarray, offset: np.ndarray) -> float:
    """Moment about the body's Y axis of a unit mass with ``tensor`` at ``offset``."""
    rotated = rotation @ tensor @ rotation.T
    return float(rotated[1, 1] + offset[0] ** 2 + offset[2] ** 2)


def _poly(body: pymunk.Body, points: np.ndarray, depth: float) -> BuiltShape | None:
    pts = [(float(x), float(z)) for x, z in points]
    shape = pymunk.Poly(body, pts)
    hull = shape.get_vertices()
    if len(hull) < 3 or shape.area <= 1e-12:
        return None
    return BuiltShape(shape, shape.area * depth, pymunk.moment_for_poly(1.0, hull))


@dataclass(frozen=True, slots=True)
class _Placed:
    """A shape spec turned into the body's frame: its rotation, offset (3D and in the X–Z
    plane) and size."""

    body: pymunk.Body
    spec: Shape
    rot: np.ndarray
    off: np.ndarray
    off2: tuple[float, float]
    size: tuple[float, ...]
    static: bool


def build_shape(body: pymunk.Body, spec: Shape, rest: np.ndarray, static: bool,
                warn: Warn) -> BuiltShape | None:
    """One pymunk shape for ``spec``, or None (with a warning) when it has no silhouette:
    each kind's builder from :data:`_BUILDERS`."""
    rot = quat_to_matrix(rest) @ quat_to_matrix(np.asarray(spec.rotation, dtype=np.float64))
    off = quat_to_matrix(rest) @ np.asarray(spec.offset, dtype=np.float64)
    placed = _Placed(body, spec, rot, off, (float(off[0]), float(off[2])),
                     tuple(float(s) for s in spec.size), static)
    builder = _BUILDERS.get(spec.kind)
    if builder is None:
        warn(f"shape-{spec.kind}", f"unknown shape kind {spec.kind!r}; skipped")
        return None
    return builder(placed, warn)


def _sphere(p: _Placed, warn: Warn) -> BuiltShape | None:
    r = p.size[0]
    return BuiltShape(pymunk.Circle(p.body, r, p.off2), 4.0 / 3.0 * math.pi * r**3,
                      0.4 * r * r + p.off2[0] ** 2 + p.off2[1] ** 2)


def _box(p: _Placed, warn: Warn) -> BuiltShape | None:
    sx, sy, sz = p.size if len(p.size) == 3 else (p.size[0],) * 3
    corners = np.array([[x, y, z] for x in (-sx / 2, sx / 2) for y in (-sy / 2, sy / 2)
                        for z in (-sz / 2, sz / 2)])
    built = _poly(p.body, (corners @ p.rot.T + p.off)[:, [0, 2]], 1.0)
    if built is None:
        warn("flat-box", "box has no extent in the X–Z plane; skipped")
        return None
    return BuiltShape(built.shape, sx * sy * sz, _yy(p.rot, _box_tensor(sx, sy, sz), p.off))


def _round(p: _Placed) -> tuple[float, float, np.ndarray, bool]:
    """A capsule's or cylinder's radius, length, axis, and whether it points along Y
    (its silhouette a circle)."""
    size = p.size
    r, length = (size[0], size[1]) if len(size) >= 2 else (size[0], 2 * size[0])
    axis = p.rot[:, 2]
    return r, length, axis, abs(axis[1]) > 0.999


def _capsule(p: _Placed, warn: Warn) -> BuiltShape | None:
    r, length, axis, along_y = _round(p)
    volume = math.pi * r * r * length + 4.0 / 3.0 * math.pi * r**3
    tensor = _cylinder_tensor(r, length + 4.0 * r / 3.0)
    if along_y:
        shape: pymunk.Shape = pymunk.Circle(p.body, r, p.off2)
    else:
        half = axis * length / 2.0
        off = p.off
        shape = pymunk.Segment(p.body, (off[0] - half[0], off[2] - half[2]),
                               (off[0] + half[0], off[2] + half[2]), r)
    return BuiltShape(shape, volume, _yy(p.rot, tensor, p.off))


def _cylinder(p: _Placed, warn: Warn) -> BuiltShape | None:
    r, length, axis, along_y = _round(p)
    volume = math.pi * r * r * length
    tensor = _cylinder_tensor(r, length)
    if along_y:
        return BuiltShape(pymunk.Circle(p.body, r, p.off2), volume, _yy(p.rot, tensor, p.off))
    if abs(axis[1]) > 1e-6:
        warn("tilted-cylinder", "cylinder tilted out of the X–Z plane; "
             f"its silhouette is a {2 * CYLINDER_SAMPLES}-point polygon")
    a = np.linspace(0.0, 2.0 * math.pi, CYLINDER_SAMPLES, endpoint=False)
    ring = np.stack([r * np.cos(a), r * np.sin(a), np.zeros_like(a)], axis=1)
    caps = np.concatenate([ring + [0, 0, length / 2], ring - [0, 0, length / 2]])
    built = _poly(p.body, (caps @ p.rot.T + p.off)[:, [0, 2]], 1.0)
    if built is None:
        return None
    return BuiltShape(built.shape, volume, _yy(p.rot, tensor, p.off))


def _vertices(p: _Placed, warn: Warn) -> BuiltShape | None:
    """A mesh or hull: the convex hull of its X–Z projection, as deep as it is in Y."""
    kind, spec = p.spec.kind, p.spec
    if spec.vertices is None or len(spec.vertices) < 3:
        warn(f"{kind}-no-vertices", f"{kind} shape has no vertices; skipped")
        return None
    verts = np.asarray(spec.vertices, dtype=np.float64).reshape(-1, 3) @ p.rot.T + p.off
    if kind == "mesh":
        warn("mesh-hull", "mesh collides as the convex hull of its X–Z projection")
    depth = float(np.ptp(verts[:, 1])) or 1.0
    built = _poly(p.body, verts[:, [0, 2]], depth)
    if built is None:
        warn(f"{kind}-flat", f"{kind} has no area in the X–Z plane; skipped")
    return built


def _static_plane(p: _Placed, warn: Warn) -> BuiltShape | None:
    if not p.static:
        warn("dynamic-plane", "a plane can only be static; skipped on this body")
        return None
    return _plane(p.body, p.size, p.rot, p.off, warn)


def _plane(body: pymunk.Body, size: tuple[float, ...], rot: np.ndarray, off: np.ndarray,
           warn: Warn) -> BuiltShape | None:
    n = np.asarray(size[:3], dtype=np.float64)
    d = float(size[3]) if len(size) > 3 else 0.0
    length = float(np.linalg.norm(n))
    if length == 0.0:
        warn("plane-normal", "plane has a zero normal; skipped")
        return None
    n, d = rot @ (n / length), d / length + float(np.dot(rot @ (n / length), off))
    n2 = np.array([n[0], n[2]])
    k = float(np.linalg.norm(n2))
    if k < 1e-9:
        warn("plane-parallel", "plane is parallel to the X–Z plane; skipped")
        return None
    if abs(n[1]) > 1e-9:
        warn("plane-tilted", "plane is not perpendicular to the X–Z plane; its trace at y=0 "
             "is used")
    n2 /= k
    q0 = n2 * (d / k)
    t = np.array([-n2[1], n2[0]])
    pts = np.array([q0 + PLANE_HALF_LENGTH * t, q0 - PLANE_HALF_LENGTH * t,
                    q0 - PLANE_HALF_LENGTH * t - PLANE_DEPTH * n2,
                    q0 + PLANE_HALF_LENGTH * t - PLANE_DEPTH * n2])
    shape = pymunk.Poly(body, [(float(x), float(z)) for x, z in pts])
    return BuiltShape(shape, 0.0, 0.0)


#: One builder per shape kind (as the ODE binding's table).
_BUILDERS: dict[str, Callable[[_Placed, Warn], BuiltShape | None]] = {
    "sphere": _sphere, "box": _box, "capsule": _capsule, "cylinder": _cylinder,
    "mesh": _vertices, "hull": _vertices, "plane": _static_plane,
}
