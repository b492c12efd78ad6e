"""Shapes derived from a model for physics: its convex hull.

Through scipy's Qhull directly, without the joggle retry trimesh falls back to, so
points on one plane are refused with a reason instead of becoming a hull of no volume
(a body that falls through the floor, or an ODE error later).
"""

from __future__ import annotations

import numpy as np

#: A hull whose volume is below this share of its bounding cube's is flat.
FLAT_VOLUME_SHARE = 1e-9


def convex_hull(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The hull's vertices ``(N, 3)`` and outward-wound triangles ``(M, 3)``; raises
    ValueError when the points enclose no volume."""
    from scipy.spatial import ConvexHull, QhullError

    pts = np.unique(np.asarray(points, dtype=np.float64).reshape(-1, 3), axis=0)
    if len(pts) < 4:
        raise ValueError(f"it has {len(pts)} distinct points; a convex hull needs at least 4 "
                         f"that are not on one plane")
    side = float(np.ptp(pts, axis=0).max())
    flat = ValueError(f"its {len(pts)} points lie on one plane (or line) and enclose no "
                      f"volume; a flat model needs ParseMethod \"TriangleMesh\" or a "
                      f"primitive")
    try:
        hull = ConvexHull(pts)
    except QhullError:
        raise flat from None
    if hull.volume <= FLAT_VOLUME_SHARE * side ** 3:
        raise flat
    used = np.unique(hull.simplices)
    index = np.zeros(len(pts), dtype=np.int64)
    index[used] = np.arange(len(used))
    vertices = pts[used]
    faces = index[hull.simplices]
    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    inward = (normals * hull.equations[:, :3]).sum(axis=1) < 0  # Qhull's normals face out
    faces[inward] = faces[inward][:, ::-1]
    return vertices, faces
