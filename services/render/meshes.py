"""CPU-side meshes: primitives generated here, model parts from :mod:`engine.assets`.

Every mesh uses one interleaved vertex layout (position, normal, uv, rgba colour), so any
mesh can be drawn by any program. A model is several :class:`MeshData` parts, one per
material (:func:`from_part`), each with its base colour and texture pixels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine.assets import MeshPart

#: Side of the quad drawn for an infinite plane, in metres.
PLANE_EXTENT = 200.0

#: Floats per vertex: position 3, normal 3, uv 2, colour 4.
VERTEX_FLOATS = 12
VERTEX_FORMAT = "3f 3f 2f 4f"
VERTEX_ATTRIBUTES = ("in_position", "in_normal", "in_uv", "in_color")


class ModelError(ValueError):
    """A shape that cannot be drawn (files that cannot are :class:`AssetError`)."""


@dataclass(slots=True)
class MeshData:
    """Interleaved vertices ``(N, 12)`` float32 and triangle indices ``(M,)`` uint32."""

    vertices: np.ndarray
    indices: np.ndarray
    color: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    texture: np.ndarray | None = None  # RGBA pixels of the model's material, if any
    name: str = ""

    @property
    def positions(self) -> np.ndarray:
        return self.vertices[:, 0:3]


def _pack(positions: np.ndarray, normals: np.ndarray, uvs: np.ndarray | None = None,
          colors: np.ndarray | None = None) -> np.ndarray:
    n = len(positions)
    out = np.empty((n, VERTEX_FLOATS), dtype=np.float32)
    out[:, 0:3] = positions
    out[:, 3:6] = normals
    out[:, 6:8] = 0.0 if uvs is None else uvs
    out[:, 8:12] = 1.0 if colors is None else colors
    return out


def box(size: tuple[float, ...]) -> MeshData:
    """Box with full extents ``size`` centred on the origin, flat-shaded (24 vertices)."""
    hx, hy, hz = (0.5 * float(s) for s in size)
    positions, normals, uvs, indices = [], [], [], []
    corners_uv = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    for axis in range(3):
        for sign in (1.0, -1.0):
            normal = np.zeros(3)
            normal[axis] = sign
            u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3
            if sign < 0:
                u_axis, v_axis = v_axis, u_axis
            base = len(positions)
            for cu, cv in corners_uv:
                p = np.zeros(3)
                p[axis] = sign
                p[u_axis] = cu * 2 - 1
                p[v_axis] = cv * 2 - 1
                positions.append(p * (hx, hy, hz))
                normals.append(normal)
                uvs.append((cu, cv))
            indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    return MeshData(_pack(np.array(positions), np.array(normals), np.array(uvs)),
                    np.array(indices, dtype=np.uint32), name="box")


def _grid_indices(rows: int, cols: int, flip: bool = False) -> list[int]:
    out = []
    for r in range(rows):
        for c in range(cols):
            a = r * (cols + 1) + c
            b = a + cols + 1
            out += [a, a + 1, b, a + 1, b + 1, b] if flip else [a, b, a + 1, a + 1, b, b + 1]
    return out


def sphere(radius: float, segments: int = 32, rings: int = 16) -> MeshData:
    """UV sphere of ``radius``; poles on the Z axis."""
    theta = np.linspace(0.0, math.pi, rings + 1)  # from +Z down
    phi = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    normals = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)
    uvs = np.stack([p / (2 * math.pi), 1.0 - t / math.pi], -1)
    normals = normals.reshape(-1, 3)
    return MeshData(_pack(normals * radius, normals, uvs.reshape(-1, 2)),
                    np.array(_grid_indices(rings, segments), dtype=np.uint32), name="sphere")


def _lathe(profile: list[tuple[float, float, float, float]], segments: int) -> MeshData:
    """Surface of revolution about Z from (radius, z, normal_r, normal_z) profile points."""
    phi = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    positions, normals, uvs = [], [], []
    for i, (r, z, nr, nz) in enumerate(profile):
        for j, a in enumerate(phi):
            c, s = math.cos(a), math.sin(a)
            positions.append((r * c, r * s, z))
            normals.append((nr * c, nr * s, nz))
            uvs.append((j / segments, i / max(len(profile) - 1, 1)))
    indices = _grid_indices(len(profile) - 1, segments, flip=True)
    return MeshData(_pack(np.array(positions), np.array(normals), np.array(uvs)),
                    np.array(indices, dtype=np.uint32))


def cylinder(radius: float, length: float, segments: int = 32) -> MeshData:
    """Capped cylinder along Z, centred on the origin."""
    h = 0.5 * length
    profile = [(0.0, -h, 0.0, -1.0), (radius, -h, 0.0, -1.0), (radius, -h, 1.0, 0.0),
               (radius, h, 1.0, 0.0), (radius, h, 0.0, 1.0), (0.0, h, 0.0, 1.0)]
    mesh = _lathe(profile, segments)
    mesh.name = "cylinder"
    return mesh


def capsule(radius: float, length: float, segments: int = 32, rings: int = 8) -> MeshData:
    """Capsule along Z: a cylinder of ``length`` between two hemispheres of ``radius``."""
    h = 0.5 * length
    profile = []
    for i in range(rings + 1):  # bottom hemisphere, pole to equator
        a = -math.pi / 2 + (math.pi / 2) * i / rings
        profile.append((radius * math.cos(a), -h + radius * math.sin(a), math.cos(a), math.sin(a)))
    for i in range(rings + 1):  # top hemisphere, equator to pole
        a = (math.pi / 2) * i / rings
        profile.append((radius * math.cos(a), h + radius * math.sin(a), math.cos(a), math.sin(a)))
    mesh = _lathe(profile, segments)
    mesh.name = "capsule"
    return mesh


def plane(size: tuple[float, ...], extent: float = PLANE_EXTENT) -> MeshData:
    """Square quad of side ``extent`` on the plane ``n·p = d``, UVs in metres (tiles textures)."""
    n = np.asarray(size[:3], dtype=np.float64)
    n /= np.linalg.norm(n) or 1.0
    d = float(size[3]) if len(size) > 3 else 0.0
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    centre = n * d
    half = 0.5 * extent
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    positions = np.array([centre + half * (a * u + b * v) for a, b in corners])
    uvs = np.array([(a * half, b * half) for a, b in corners])
    # wind counter-clockwise seen from the normal side
    if np.dot(np.cross(positions[1] - positions[0], positions[2] - positions[0]), n) < 0:
        indices = [0, 2, 1, 0, 3, 2]
    else:
        indices = [0, 1, 2, 0, 2, 3]
    return MeshData(_pack(positions, np.tile(n, (4, 1)), uvs),
                    np.array(indices, dtype=np.uint32), name="plane")


def primitive(kind: str, size: tuple[float, ...]) -> MeshData:
    """Mesh of a :class:`components.Shape` primitive (sizes as the Shape docstring says)."""
    size = tuple(float(s) for s in size)
    if kind == "box":
        return box(size if len(size) == 3 else (size[0],) * 3)
    if kind == "sphere":
        return sphere(size[0])
    if kind == "cylinder":
        return cylinder(size[0], size[1] if len(size) > 1 else 1.0)
    if kind == "capsule":
        return capsule(size[0], size[1] if len(size) > 1 else 1.0)
    if kind == "plane":
        return plane(size if len(size) >= 3 else (0.0, 0.0, 1.0, 0.0))
    raise ModelError(f"unknown primitive {kind!r}; expected box, sphere, capsule, cylinder, plane")


def mesh_from_arrays(vertices: np.ndarray, faces: np.ndarray) -> MeshData:
    """Flat-shaded mesh from raw triangles (a Shape of kind mesh or hull): each triangle
    its own three vertices, with the triangle's normal."""
    corners = np.asarray(vertices, np.float64)[np.asarray(faces, np.int64).reshape(-1, 3)]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    return MeshData(_pack(corners.reshape(-1, 3), np.repeat(normal, 3, axis=0)),
                    np.arange(3 * len(corners), dtype=np.uint32))


def from_part(part: MeshPart) -> MeshData:
    """A model part in the interleaved layout, with its colour and texture."""
    return MeshData(_pack(part.vertices, part.normals, part.uv, part.colors),
                    np.asarray(part.faces, dtype=np.uint32).reshape(-1), color=part.color,
                    texture=part.texture, name=part.name)
