"""Linear-blend skinning on the CPU: the reference the GPU path (the renderer's transform
feedback pass) is checked against, and what tools use to pose a mesh without a GPU."""

from __future__ import annotations

import numpy as np


def skin(vertices: np.ndarray, normals: np.ndarray, joints: np.ndarray, weights: np.ndarray,
         palette: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Posed positions and unit normals ``(N, 3)``: each vertex moved by the weighted sum
    of its joints' matrices (``palette`` ``(J, 4, 4)``); normals by that matrix's
    inverse transpose (its cofactor matrix: the same direction, no inverse needed)."""
    blended = np.einsum("nk,nkij->nij", np.asarray(weights, np.float64),
                        np.asarray(palette, np.float64)[np.asarray(joints)])
    positions = np.einsum("nij,nj->ni", blended[:, :3, :3], vertices) + blended[:, :3, 3]
    m = blended[:, :3, :3]
    c0, c1, c2 = m[:, :, 0], m[:, :, 1], m[:, :, 2]
    cofactor = np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], axis=2)
    n = np.einsum("nij,nj->ni", cofactor, normals)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return positions, np.divide(n, length, out=np.zeros_like(n), where=length > 0)
