"""Matrix math the renderer and its tests share, so a test projects a point with the same
numbers the GPU uses.

Matrices are float64 numpy ``(4, 4)`` arrays in the usual column-vector convention
(``clip = P @ V @ M @ p``); they are transposed only when uploaded to GLSL.

Engine camera convention: a camera looks along its local +Y axis with local +Z up, so an
identity-oriented camera looks toward world +Y with Z up. OpenGL's eye space looks down -Z
with +Y up; :data:`ENGINE_TO_GL_EYE` converts one to the other.
"""

from __future__ import annotations

import math

import numpy as np

from engine.rotation import compose as compose  # the renderer's model matrices
from engine.rotation import matrix_to_quat

#: Rotation taking camera-local engine axes (forward +Y, up +Z, right +X) to GL eye axes
#: (forward -Z, up +Y, right +X).
ENGINE_TO_GL_EYE = np.array(
    [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
)


def perspective(fov_y_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL perspective projection (vertical field of view in degrees)."""
    f = 1.0 / math.tan(math.radians(fov_y_deg) / 2.0)
    return np.array(
        [
            [f / aspect, 0.0, 0.0, 0.0],
            [0.0, f, 0.0, 0.0],
            [0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far)],
            [0.0, 0.0, -1.0, 0.0],
        ]
    )


def orthographic(left: float, right: float, bottom: float, top: float, near: float, far: float
                 ) -> np.ndarray:
    """OpenGL orthographic projection."""
    return np.array(
        [
            [2.0 / (right - left), 0.0, 0.0, -(right + left) / (right - left)],
            [0.0, 2.0 / (top - bottom), 0.0, -(top + bottom) / (top - bottom)],
            [0.0, 0.0, -2.0 / (far - near), -(far + near) / (far - near)],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def frustum(left: float, right: float, bottom: float, top: float, near: float, far: float
            ) -> np.ndarray:
    """OpenGL perspective projection of an asymmetric frustum (glFrustum's bounds)."""
    return np.array(
        [
            [2 * near / (right - left), 0.0, (right + left) / (right - left), 0.0],
            [0.0, 2 * near / (top - bottom), (top + bottom) / (top - bottom), 0.0],
            [0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far)],
            [0.0, 0.0, -1.0, 0.0],
        ]
    )


def off_axis(eye: np.ndarray, lower_left: np.ndarray, lower_right: np.ndarray,
             upper_left: np.ndarray, near: float, far: float) -> tuple[np.ndarray, np.ndarray]:
    """View and projection of a fixed screen seen from ``eye`` (Kooima's generalised
    perspective projection): the screen's corners land on the viewport's corners wherever
    the eye is, so walls side by side join up for a tracked viewer.

    >>> view, proj = off_axis(np.array([0.3, -2.0, 0.2]), np.array([-1.0, 0, -1]),
    ...                       np.array([1.0, 0, -1]), np.array([-1.0, 0, 1]), 0.1, 100)
    >>> [round(c, 6) for c in project(np.array([1.0, 0, 1]), view, proj, 2, 2)[:2]]
    [2.0, 0.0]
    """
    eye = np.asarray(eye, dtype=np.float64)
    ll, lr, ul = (np.asarray(c, dtype=np.float64) for c in (lower_left, lower_right,
                                                              upper_left))
    right = (lr - ll) / np.linalg.norm(lr - ll)
    up = (ul - ll) / np.linalg.norm(ul - ll)
    normal = np.cross(right, up)
    normal /= np.linalg.norm(normal)  # toward the viewer
    to_ll, to_lr, to_ul = ll - eye, lr - eye, ul - eye
    distance = -float(to_ll @ normal)
    if distance <= 1e-9:
        raise ValueError("the eye is behind the screen (or on its plane)")
    scale = near / distance
    proj = frustum(float(right @ to_ll) * scale, float(right @ to_lr) * scale,
                   float(up @ to_ll) * scale, float(up @ to_ul) * scale, near, far)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = right, up, normal
    view[:3, 3] = -view[:3, :3] @ eye
    return view, proj


def camera_view(position: np.ndarray, orientation: np.ndarray) -> np.ndarray:
    """View matrix of an engine camera (forward local +Y, up local +Z) at a world pose."""
    world = compose(position, orientation)
    return ENGINE_TO_GL_EYE @ np.linalg.inv(world)


def look_at_orientation(eye: np.ndarray, target: np.ndarray,
                        up: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> np.ndarray:
    """Orientation (w, x, y, z) of an engine camera at ``eye`` looking at ``target``, Z up."""
    forward = np.asarray(target, dtype=np.float64) - np.asarray(eye, dtype=np.float64)
    forward /= np.linalg.norm(forward) or 1.0
    right = np.cross(forward, up)
    if np.linalg.norm(right) < 1e-9:  # looking straight up or down: any right will do
        right = np.cross(forward, (0.0, 1.0, 0.0))
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, forward)
    return matrix_to_quat(np.column_stack([right, forward, cam_up]))


def look_at_view(eye: np.ndarray, target: np.ndarray,
                 up: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> np.ndarray:
    """View matrix looking from ``eye`` at ``target`` (used for light views)."""
    return camera_view(np.asarray(eye, dtype=np.float64), look_at_orientation(eye, target, up))


def project(point: np.ndarray, view: np.ndarray, proj: np.ndarray, width: int, height: int
            ) -> tuple[float, float, float]:
    """Window coordinates ``(x, y_from_top, depth)`` of a world point (pixel centres)."""
    p = proj @ view @ np.append(np.asarray(point, dtype=np.float64), 1.0)
    ndc = p[:3] / p[3]
    x = (ndc[0] * 0.5 + 0.5) * width
    y = (1.0 - (ndc[1] * 0.5 + 0.5)) * height
    return float(x), float(y), float(ndc[2])
