"""Cameras: where the viewer is, and the one or two eyes (stereo) rendered from it.

An engine camera looks along its local +Y axis with local +Z up. A stereo camera
(``eye_separation`` > 0) renders two eyes side by side, each shifted half the separation
along the camera's right (+X) axis — the layout an HMD's compositor expects.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine.rotation import quat_to_matrix
from services.render import math3d


@dataclass(slots=True)
class CameraView:
    """A camera pose and lens in world space."""

    position: np.ndarray = field(default_factory=lambda: np.array([0.0, -8.0, 3.0]))
    orientation: np.ndarray = field(
        default_factory=lambda: math3d.look_at_orientation((0.0, -8.0, 3.0), (0.0, 0.0, 0.5)))
    fov: float = 60.0
    near: float = 0.05
    far: float = 500.0
    eye_separation: float = 0.0
    #: A fixed screen (lower left, lower right, upper left corners, world frame) drawn
    #: off-axis from ``position`` (a wall of a cluster); None: an ordinary camera.
    screen: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    #: A headset's eyes, each its own world pose and (off-axis) projection, drawn side by
    #: side; None: eyes from ``position`` and ``eye_separation``.
    headset: list[HeadsetEye] | None = None

    @staticmethod
    def looking_at(eye: tuple[float, float, float], target: tuple[float, float, float],
                   **lens: float) -> CameraView:
        return CameraView(np.asarray(eye, dtype=np.float64),
                          math3d.look_at_orientation(eye, target), **lens)

    def view(self) -> np.ndarray:
        return math3d.camera_view(self.position, self.orientation)

    def projection(self, aspect: float) -> np.ndarray:
        return math3d.perspective(self.fov, aspect, self.near, self.far)

    def eyes(self, width: int, height: int) -> list[Eye]:
        """One eye filling the viewport, or two side by side when stereo."""
        if self.headset is not None:
            half = width // len(self.headset)
            return [Eye(math3d.camera_view(e.position, e.orientation), e.projection,
                        np.asarray(e.position, np.float64), (i * half, 0, half, height))
                    for i, e in enumerate(self.headset)]
        if self.screen is not None:
            view, proj = math3d.off_axis(self.position, *self.screen, self.near, self.far)
            return [Eye(view, proj, self.position, (0, 0, width, height))]
        if self.eye_separation <= 0.0:
            return [Eye(self.view(), self.projection(width / max(height, 1)), self.position,
                        (0, 0, width, height))]
        right = quat_to_matrix(self.orientation)[:, 0]
        half = width // 2
        proj = self.projection(half / max(height, 1))
        out = []
        for i, sign in enumerate((-1.0, 1.0)):
            pos = self.position + right * (sign * self.eye_separation / 2.0)
            out.append(Eye(math3d.camera_view(pos, self.orientation), proj, pos,
                           (i * half, 0, half, height)))
        return out


@dataclass(slots=True)
class HeadsetEye:
    """One eye of a headset: its world pose and its projection (the runtime's field of
    view, see :mod:`services.xr.projection`)."""

    position: np.ndarray
    orientation: np.ndarray
    projection: np.ndarray


@dataclass(slots=True)
class Eye:
    """One rendered view: matrices, eye position and viewport ``(x, y, w, h)``."""

    view: np.ndarray
    proj: np.ndarray
    position: np.ndarray
    viewport: tuple[int, int, int, int]


def camera_from_component(camera: object, position: np.ndarray, orientation: np.ndarray,
                          target: tuple[np.ndarray, np.ndarray] | None = None) -> CameraView:
    """A :class:`CameraView` from a ``components.Camera`` on an entity at a pose.

    With ``follow`` set, ``target`` is the followed entity's (position, orientation): the
    camera sits at ``offset`` in the target's frame and takes its orientation (a tracked head)
    unless ``look_at`` is set, which is then a point in the target's frame. Without follow,
    ``look_at`` is a world point.
    """
    cam = camera  # components.Camera
    pos = np.asarray(position, dtype=np.float64)
    quat = np.asarray(orientation, dtype=np.float64)
    look_at = cam.look_at  # type: ignore[attr-defined]
    if target is not None:
        t_pos, t_quat = (np.asarray(x, dtype=np.float64) for x in target)
        rot = quat_to_matrix(t_quat)
        pos = t_pos + rot @ np.asarray(cam.offset, dtype=np.float64)  # type: ignore[attr-defined]
        quat = t_quat
        if look_at is not None:
            look_at = t_pos + rot @ np.asarray(look_at, dtype=np.float64)
    if look_at is not None and np.linalg.norm(np.asarray(look_at) - pos) > 1e-9:
        quat = math3d.look_at_orientation(pos, look_at)
    return CameraView(pos, quat, fov=float(cam.fov), near=float(cam.near),  # type: ignore[attr-defined]
                      far=float(cam.far),  # type: ignore[attr-defined]
                      eye_separation=float(cam.eye_separation))  # type: ignore[attr-defined]


def camera_view_of(camera: object, entity: int, poses: object) -> CameraView:
    """The view of the ``components.Camera`` on ``entity`` as drawn, from the pose table
    ``poses`` (at its offset from the object it follows)."""
    row_of = poses.row_of  # type: ignore[attr-defined]
    row = row_of.get(entity)
    pos = poses.position[row] if row is not None else np.zeros(3)  # type: ignore[attr-defined]
    quat = poses.orientation[row] if row is not None else \
        np.array([1.0, 0, 0, 0])  # type: ignore[attr-defined]
    target = None
    follow = camera.follow  # type: ignore[attr-defined]
    if follow is not None and follow in row_of:
        t_row = row_of[follow]
        target = (poses.position[t_row], poses.orientation[t_row])  # type: ignore[attr-defined]
    return camera_from_component(camera, pos, quat, target)
