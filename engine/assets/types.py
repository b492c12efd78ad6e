"""What loaders return: a model's triangle parts and an image's pixels (sounds are
:class:`engine.assets.sound.SoundInfo` and :class:`~engine.assets.sound.Clip`).

Plain arrays, no library objects, so render, physics and sound can share one cached copy
and a user's loader only has to fill in numbers.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

WHITE = (1.0, 1.0, 1.0, 1.0)


@dataclass(frozen=True, slots=True)
class MeshPart:
    """One material's triangles of a model, in metres, Z up.

    ``vertices`` and ``normals`` ``(N, 3)`` float64, ``faces`` ``(M, 3)`` int64 indices,
    ``uv`` ``(N, 2)`` or None (v = 0 at the texture's bottom row, as OpenGL and trimesh
    have it; glTF's v runs down from the top), ``colors`` per-vertex RGBA ``(N, 4)`` in
    0..1 or None, ``color`` the material's base colour, ``texture`` its RGBA uint8 image
    ``(H, W, 4)`` (rows top to bottom) or None.
    """

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray
    uv: np.ndarray | None = None
    colors: np.ndarray | None = None
    color: tuple[float, float, float, float] = WHITE
    texture: np.ndarray | None = None
    name: str = ""


@dataclass(frozen=True, slots=True)
class ModelAsset:
    """A model file as drawable parts; :meth:`triangles` is the whole of it for physics."""

    path: Path
    parts: tuple[MeshPart, ...]

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """All parts as one triangle soup, equal positions merged: ``(vertices, faces)``."""
        vertices = np.concatenate([p.vertices for p in self.parts])
        offsets = np.cumsum([0] + [len(p.vertices) for p in self.parts[:-1]])
        faces = np.concatenate([p.faces + o for p, o in zip(self.parts, offsets, strict=True)])
        unique, inverse = np.unique(vertices, axis=0, return_inverse=True)
        return unique, inverse.reshape(-1)[faces]

    @property
    def bounds(self) -> np.ndarray:
        """``[[min x y z], [max x y z]]`` over every part."""
        vertices = np.concatenate([p.vertices for p in self.parts])
        return np.stack([vertices.min(axis=0), vertices.max(axis=0)])


@dataclass(frozen=True, slots=True)
class ImageAsset:
    """An image's pixels: RGBA uint8 ``(height, width, 4)``, rows top to bottom."""

    path: Path
    rgba: np.ndarray

    @property
    def size(self) -> tuple[int, int]:
        """``(width, height)`` in pixels."""
        return int(self.rgba.shape[1]), int(self.rgba.shape[0])


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Smooth per-vertex normals: the area-weighted sum of the faces around each vertex
    (for loaders whose format has none)."""
    tri = vertices[faces]
    face_n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals = np.zeros_like(vertices, dtype=np.float64)
    for corner in range(3):
        np.add.at(normals, faces[:, corner], face_n)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)


def mesh_part(vertices: object, faces: object, name: str = "") -> MeshPart:
    """A plain part from raw triangles, normals computed: what a simple loader returns."""
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    return MeshPart(v, f, vertex_normals(v, f) if len(f) and len(v) else np.zeros_like(v),
                    name=name)
