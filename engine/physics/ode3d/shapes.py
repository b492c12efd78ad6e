"""Shapes for the ODE backend: component shapes checked and turned into geom arguments.

Capsule and cylinder ``size`` is ``(radius, length)`` along local Z, the length
excluding a capsule's caps (ODE's convention). A ``plane`` is infinite, belongs to
static bodies only and is given in world coordinates. ``mesh`` shapes (vertices and
triangle faces) work on static and dynamic bodies; ``hull`` shapes take the convex
hull of their vertices (ODE has no convex mass, so a hull's mass comes from the same
triangles as a mesh).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from components import Shape
from engine.physics.ode3d import _ode

GEOM_KINDS = {"sphere": _ode.GEOM_SPHERE, "box": _ode.GEOM_BOX, "capsule": _ode.GEOM_CAPSULE,
              "cylinder": _ode.GEOM_CYLINDER, "plane": _ode.GEOM_PLANE,
              "mesh": _ode.GEOM_MESH, "trimesh": _ode.GEOM_MESH, "hull": _ode.GEOM_HULL}
#: Size values each primitive takes.
SIZES = {"sphere": 1, "box": 3, "capsule": 2, "cylinder": 2, "plane": 4}


@dataclass(frozen=True, slots=True)
class Hull:
    """A convex hull as dCreateConvex wants it: in a frame whose origin is ``center``, a
    point inside the hull, so every plane's offset is positive (the plane "contains the
    origin") and every polygon's first three points, seen from that origin, turn
    counter-clockwise (ODE checks both and prints to stdout when they do not hold; its
    convex-convex and convex-primitive tests assume them)."""

    planes: np.ndarray  # (F, 4) outward normal and offset, relative to center
    points: np.ndarray  # (V, 3), relative to center
    polygons: np.ndarray  # flat [3, i, j, k, 3, ...]
    triangles: np.ndarray  # (F, 3), wound counter-clockwise seen from outside
    center: np.ndarray  # (3,) the frame's origin in the shape's frame: the vertices' mean


@dataclass(frozen=True, slots=True)
class Geom:
    """One shape as ``_ode.add_geom`` takes it."""

    shape: Shape
    kind: int
    dims: np.ndarray
    extra: dict
    #: Where the geom's own origin lies in the shape's frame (a hull's inner point).
    center: np.ndarray | None = None

    def offset(self) -> np.ndarray:
        """The geom's offset in the body's frame: the shape's, plus its centre turned by
        the shape's rotation."""
        offset = np.asarray(self.shape.offset, dtype=np.float64).reshape(-1)
        if self.center is None or not np.any(self.center):
            return offset
        from engine.rotation import rotate

        return offset + np.asarray(rotate(self.shape.rotation, self.center))


def hull(vertices: np.ndarray) -> Hull:
    """Convex hull of a point cloud in the form dCreateConvex wants (planes + polygons),
    relative to a point inside it (:class:`Hull`)."""
    from scipy.spatial import ConvexHull  # only scenes with hulls pay for importing scipy

    pts = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    center = pts[ConvexHull(pts).vertices].mean(axis=0)  # inside: the corners' mean
    pts = pts - center
    found = ConvexHull(pts)
    points = pts[found.vertices]
    remap = np.full(len(pts), -1, np.int64)
    remap[found.vertices] = np.arange(len(found.vertices))
    tris = remap[found.simplices]
    normals = found.equations[:, :3]
    p0, p1, p2 = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(p1 - p0, p2 - p0), normals) < 0
    tris[flip] = tris[flip][:, ::-1]
    planes = np.column_stack([normals, -found.equations[:, 3]])
    polygons = np.column_stack([np.full(len(tris), 3), tris]).astype(np.uint32).ravel()
    return Hull(planes, points, polygons, tris.astype(np.uint32), center)


def convex_problems(planes: np.ndarray, points: np.ndarray,
                    polygons: np.ndarray) -> list[str]:
    """What ODE's dCreateConvex would warn about (libode 0.16 ``dxConvex``'s checks, which
    it prints to stdout): a polygon whose first three points do not turn counter-clockwise
    seen from the origin, a plane that does not contain the origin (negative offset)."""
    problems = []
    flat = np.asarray(polygons, dtype=np.int64).ravel()
    at = 0
    for i in range(len(planes)):
        count = int(flat[at])
        a, b, c = points[flat[at + 1:at + 4]]
        if float(np.dot(a, np.cross(b, c))) < 0:
            problems.append(f"polygon {i} is not defined counterclockwise")
        if planes[i][3] < 0:
            problems.append(f"plane {i} does not contain the origin")
        at += count + 1
    return problems


def prepare(key: int, shape: Shape) -> Geom:
    """Check a shape and work out its geom arguments; ValueError names the body."""
    kind = GEOM_KINDS.get(shape.kind)
    if kind is None:
        raise ValueError(f"body {key}: unknown shape {shape.kind!r} "
                         f"(expected one of {', '.join(sorted(set(GEOM_KINDS)))})")
    if shape.kind in SIZES:
        return Geom(shape, kind, _primitive_dims(key, shape), {})
    if shape.vertices is None:
        raise ValueError(f"body {key}: a {shape.kind} shape needs vertices")
    verts = np.ascontiguousarray(shape.vertices, dtype=np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(verts)):
        raise ValueError(f"body {key}: {shape.kind} vertices must be finite")
    if kind == _ode.GEOM_MESH:
        if shape.faces is None:
            raise ValueError(f"body {key}: a mesh shape needs faces")
        faces = np.ascontiguousarray(shape.faces, dtype=np.int64).reshape(-1, 3)
        if faces.size and (faces.min() < 0 or faces.max() >= len(verts)):
            raise ValueError(f"body {key}: mesh face index out of range "
                             f"(0..{len(verts) - 1})")
        return Geom(shape, kind, np.zeros(1), {"vertices": verts,
                                               "faces": faces.astype(np.uint32)})
    try:
        found = hull(verts)
    except Exception as exc:  # scipy's QhullError for flat or too few points
        raise ValueError(f"body {key}: cannot build a convex hull: {exc}") from None
    return Geom(shape, kind, np.zeros(1), {"vertices": found.points, "faces": found.triangles,
                                           "planes": found.planes,
                                           "polygons": found.polygons},
                found.center)


def _primitive_dims(key: int, shape: Shape) -> np.ndarray:
    n = SIZES[shape.kind]
    size = shape.size
    if shape.kind != "plane" and type(size) is tuple and len(size) == n and all(
            type(x) is float and 0.0 < x < math.inf for x in size):
        return np.array(size)  # the common case, checked in plain Python: 4 times faster
    dims = np.ascontiguousarray(shape.size, dtype=np.float64).reshape(-1)
    if shape.kind == "box" and dims.size == 1:
        dims = np.repeat(dims, 3)
    if dims.size < n or not np.all(np.isfinite(dims[:n])):
        raise ValueError(f"body {key}: a {shape.kind} needs {n} size values, "
                         f"got {shape.size!r}")
    dims = np.ascontiguousarray(dims[:n])
    if shape.kind != "plane" and not np.all(dims > 0):
        raise ValueError(f"body {key}: {shape.kind} size must be positive, "
                         f"got {shape.size!r}")
    if shape.kind == "plane":
        norm = float(np.linalg.norm(dims[:3]))
        if norm == 0:
            raise ValueError(f"body {key}: plane normal is zero")
        dims = dims / norm
    return dims
