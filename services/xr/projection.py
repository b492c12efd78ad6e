"""A headset's eyes as engine views: OpenXR's per-eye field of view (four angles, never
symmetric on a real headset) as an off-axis projection, and its eye poses in the world.

OpenXR gives each eye an ``XrFovf`` (left, right, up, down angles in radians; left and
down negative) and a pose in the session's reference space, whose frame has y up and
looks along -z. The engine's world has z up and a camera looks along its local +y;
:data:`services.input.calibration.OPENXR` converts the one to the other, and
:class:`XrOrigin` places the reference space in the world (where the player stands).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from engine.rotation import quat_multiply, quat_to_matrix
from services.input.calibration import openxr_to_engine
from services.render import math3d


@dataclass(frozen=True, slots=True)
class Fov:
    """An eye's field of view: the angles (rad) of its frustum's four sides from the
    eye's forward axis, as OpenXR's ``XrFovf`` (left and down are negative)."""

    left: float
    right: float
    up: float
    down: float

    @staticmethod
    def symmetric(horizontal_deg: float, vertical_deg: float) -> Fov:
        h, v = math.radians(horizontal_deg) / 2.0, math.radians(vertical_deg) / 2.0
        return Fov(-h, h, v, -v)

    def problem(self) -> str | None:
        """What makes this field of view unusable (None: it is fine)."""
        limit = math.pi / 2.0
        for name in ("left", "right", "up", "down"):
            value = getattr(self, name)
            if not math.isfinite(value) or abs(value) >= limit:
                return f"the {name} angle {value!r} rad is not within ±90°"
        if self.right <= self.left or self.up <= self.down:
            return (f"an empty field of view (left {self.left:g}, right {self.right:g}, "
                    f"up {self.up:g}, down {self.down:g} rad)")
        return None


def fov_projection(fov: Fov, near: float, far: float) -> np.ndarray:
    """The OpenGL projection of ``fov`` (off-axis where the angles are not symmetric).

    >>> p = fov_projection(Fov(-0.5, 1.0, 0.8, -0.3), 0.1, 100.0)
    >>> clip = p @ np.array([math.tan(1.0), math.tan(0.8), -1.0, 1.0])  # the upper right
    >>> [round(float(c), 9) for c in clip[:2] / clip[3]]
    [1.0, 1.0]
    """
    problem = fov.problem()
    if problem is not None:
        raise ValueError(problem)
    if not 0.0 < near < far:
        raise ValueError(f"need 0 < near < far, got near {near:g} and far {far:g}")
    return math3d.frustum(near * math.tan(fov.left), near * math.tan(fov.right),
                          near * math.tan(fov.down), near * math.tan(fov.up), near, far)


def yaw_of(orientation: np.ndarray) -> float:
    """The heading (rad about world z) of an engine camera's forward axis (+y)."""
    forward = quat_to_matrix(np.asarray(orientation, dtype=np.float64))[:, 1]
    return math.atan2(-forward[0], forward[1])


def yaw_quat(yaw: float) -> np.ndarray:
    return np.array([math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0)])


@dataclass(slots=True)
class XrOrigin:
    """Where the headset's reference space lies in the world: a position and a turn
    about z (a tracking space is level). A point ``p`` of the space (already in engine
    axes) is at ``position + Rz(yaw) p`` in the world."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    yaw: float = 0.0

    def place(self, position: np.ndarray, orientation: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
        """A pose in the space (engine axes) as a world pose."""
        turn = yaw_quat(self.yaw)
        world = self.position + quat_to_matrix(turn) @ np.asarray(position, np.float64)
        return world, quat_multiply(turn, np.asarray(orientation, np.float64))

    def place_joints(self, positions: np.ndarray, frames: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
        """Positions (n, 3) and rotation matrices (n, 3, 3) of the space (engine axes) in
        the world: a tracked hand's joints, all at once."""
        turn = quat_to_matrix(yaw_quat(self.yaw))
        return self.position + positions @ turn.T, turn @ frames

    def place_xr(self, position: tuple[float, float, float],
                 orientation: tuple[float, float, float, float]
                 ) -> tuple[np.ndarray, np.ndarray]:
        """A pose in OpenXR's axes (y up, -z forward; quaternion w, x, y, z) in the world."""
        p, q = openxr_to_engine(position, orientation)
        return self.place(np.asarray(p), np.asarray(q))

    @staticmethod
    def under(camera_position: np.ndarray, camera_orientation: np.ndarray,
              floor: bool) -> XrOrigin:
        """The origin that puts the player where a scene's camera is, facing the way it
        faces: on a floor-level space (STAGE, LOCAL_FLOOR) at the floor below the camera
        (z = 0, the person's own height then decides the eyes'); on LOCAL (origin at the
        head when the session started) at the camera itself."""
        position = np.asarray(camera_position, np.float64).copy()
        if floor:
            position[2] = 0.0
        return XrOrigin(position, yaw_of(camera_orientation))

    def recentered(self, head_position: np.ndarray, head_orientation: np.ndarray,
                   target_position: np.ndarray, target_orientation: np.ndarray,
                   floor: bool) -> XrOrigin:
        """The origin that moves the head (``head_*``: a pose in the space, engine axes)
        over ``target`` and turns it to face the target's heading; on a floor-level space
        the height stays the person's own."""
        yaw = yaw_of(target_orientation) - yaw_of(head_orientation)
        turned = quat_to_matrix(yaw_quat(yaw)) @ np.asarray(head_position, np.float64)
        position = np.asarray(target_position, np.float64) - turned
        if floor:
            position[2] = self.position[2]
        return XrOrigin(position, yaw)

    def relative_to(self, position: np.ndarray, orientation: np.ndarray) -> XrOrigin:
        """This origin in the frame of an anchor at a pose (its position and heading)."""
        yaw = yaw_of(orientation)
        back = quat_to_matrix(yaw_quat(-yaw))
        return XrOrigin(back @ (self.position - np.asarray(position, np.float64)),
                        self.yaw - yaw)

    def carried_by(self, position: np.ndarray, orientation: np.ndarray) -> XrOrigin:
        """The origin whose place in an anchor's frame is this one (``relative_to``'s
        inverse): the player carried along by what the camera follows (a wheelchair)."""
        yaw = yaw_of(orientation)
        return XrOrigin(np.asarray(position, np.float64) + quat_to_matrix(yaw_quat(yaw))
                        @ self.position, self.yaw + yaw)
