"""What the camera can see, for all objects at once in numpy: bounding spheres against the
view frustum, and which level of detail each one is drawn with.

A CPU rasteriser (Mesa llvmpipe) transforms every vertex it is given on the thread that
draws, seen or not, so an object behind the viewer costs as much as one in front of it:
leaving it out of the instance data is the saving. The frustum's planes come from the
eye's ``proj @ view`` (Gribb and Hartmann's row sums), so culling agrees with the GPU's
clipping by construction.

>>> import numpy as np
>>> from services.render import math3d
>>> view = math3d.look_at_view(np.array([0.0, -5.0, 0.0]), np.array([0.0, 0.0, 0.0]))
>>> planes = frustum_planes(math3d.perspective(60, 1.0, 0.1, 100) @ view)
>>> in_frustum(planes, np.array([[0.0, 0.0, 0.0], [0.0, -10.0, 0.0]]), np.array([0.5, 0.5]))
array([ True, False])
"""

from __future__ import annotations

import numpy as np

#: Levels of detail: a mesh with levels is drawn with level ``i`` while its projected radius
#: is under ``LOD_PIXELS[i - 1]`` pixels (level 0 is the finest; see :func:`lod_levels`).
LOD_PIXELS = (24.0, 8.0)
#: The level shadow casters are drawn at. A coarser level's vertices are a subset of a
#: finer one's, so it lies inside it: a caster at this level never shadows the level-0 and
#: level-1 surfaces drawn over it; a level-2 surface (a few pixels across) lies within
#: 0.06 radii of it, inside the shadow test's depth bias.
SHADOW_LEVEL = 1


def frustum_planes(view_proj: np.ndarray) -> np.ndarray:
    """The six planes ``(6, 4)`` (left, right, bottom, top, near, far) of a clip matrix, each
    ``(a, b, c, d)`` with ``a x + b y + c z + d >= 0`` inside and ``(a, b, c)`` of unit
    length."""
    m = np.asarray(view_proj, dtype=np.float64)
    rows = np.array([m[3] + m[0], m[3] - m[0], m[3] + m[1], m[3] - m[1], m[3] + m[2],
                     m[3] - m[2]])
    return rows / np.linalg.norm(rows[:, :3], axis=1, keepdims=True)


def in_frustum(planes: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Which spheres ``(N, 3)``, ``(N,)`` reach into the frustum (conservative: a sphere
    near a corner outside every face-plane pair may be kept)."""
    distances = centres @ planes[:, :3].T + planes[:, 3]
    return np.all(distances >= -radii[:, None], axis=1)


def pixels_per_unit(proj: np.ndarray, viewport_height: int) -> float:
    """How many pixels one metre spans, seen face-on at one metre (the vertical focal
    length in pixels)."""
    return float(proj[1, 1]) * viewport_height / 2.0


def lod_levels(radii: np.ndarray, distances: np.ndarray, focal_pixels: float,
               levels: int = len(LOD_PIXELS) + 1) -> np.ndarray:
    """The level of detail of each sphere: 0 up close, coarser as its projected radius
    shrinks past :data:`LOD_PIXELS` (int8, at most ``levels - 1``)."""
    projected = radii * focal_pixels / np.maximum(distances, 1e-6)
    level = np.zeros(len(radii), np.int8)
    for i, limit in enumerate(LOD_PIXELS[: levels - 1]):
        level[projected < limit] = i + 1
    return level


def sphere_segments(level: int) -> tuple[int, int]:
    """Segments and rings of the sphere drawn at ``level`` (32x16, 16x8, 8x4)."""
    segments = 32 >> level
    return segments, max(segments // 2, 2)


def world_radii(world: np.ndarray, local_radii: np.ndarray) -> np.ndarray:
    """Bounding radii in the world: a mesh's radius times its matrix's largest axis scale."""
    scale = np.sqrt(np.max(np.einsum("nij,nij->nj", world[:, :3, :3], world[:, :3, :3]),
                           axis=1))
    return local_radii * scale

