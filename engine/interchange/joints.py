"""Generic six-degree-of-freedom joints (what KHR, OMI and Collada describe) as the scene's
joint types.

A file describes a joint by two attachment frames and, for each of the frame's six
degrees of freedom (linear X Y Z, angular X Y Z), whether it is free, locked or limited.
:func:`working_joint` picks the scene type holding the same freedom (Fixed, Hinge, Ball,
Slider, Universal), or the nearest one, telling what is lost.

Conventions, the files' and the engine's: a file measures the connected frame relative
to the joint frame; the engine measures its first body relative to its second. So the
connected side is body 1 and the joint's own side body 2 (or the world); when only the
joint's side moves, it is body 1 and limits and motor turn around. The engine counts a
free axis from where the bodies start, the file from where the frames coincide, so
limits move by the frames' starting offset.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine.interchange.model import JointDecl, Problems, SpringDecl, tidy
from engine.rotation import matrix_to_quat

DOF_NAMES = ("linear X", "linear Y", "linear Z", "angular X", "angular Y", "angular Z")
LINEAR, ANGULAR = (0, 1, 2), (3, 4, 5)
#: ("free" | "locked" | "limited", low, high): m for linear, rad for angular.
Dof = tuple[str, float, float]
FREE: Dof = ("free", -math.inf, math.inf)
LOCKED: Dof = ("locked", 0.0, 0.0)
_ANGULAR_TYPES = ("Hinge", "MotorizedHinge", "Universal")


@dataclass(frozen=True, slots=True)
class Frames:
    """The attachment frames in the engine's world: each a rotation whose columns are the
    frame's axes as the file numbers them (0, 1, 2), and an origin."""

    rotation: np.ndarray
    origin: np.ndarray
    connected_rotation: np.ndarray
    connected_origin: np.ndarray


@dataclass(slots=True)
class WorkingJoint:
    """A joint being worked out: angles in radians until :meth:`decl`."""

    type: str
    bodies: tuple[str, ...]
    anchor: tuple[float, ...]
    axis: tuple[float, ...]
    axis2: tuple[float, ...] | None
    low: float | None
    high: float | None
    free: int | None
    #: 1, or -1 when the joint's own side is body 1 (limits and motor turned around).
    sign: float = 1.0
    #: Where the free axis starts in the file's terms (m or rad): see _start_offset.
    offset: float = 0.0
    motor_velocity: float = 0.0
    motor_max_force: float = 0.0
    #: (stiffness, damping, target, max force or None): per m or rad, the engine's count.
    spring: tuple[float, float, float, float | None] | None = None

    def motor(self, velocity: float, max_force: float) -> None:
        """A velocity motor on the free axis (the file's sense)."""
        if self.type == "Hinge":
            self.type = "MotorizedHinge"
        self.motor_velocity = self.sign * velocity
        self.motor_max_force = max_force

    def pull(self, stiffness: float, damping: float, target: float,
             max_force: float | None) -> None:
        """A spring-damper on the free axis toward ``target`` (the file's count: from where
        the frames coincide, in the file's sense), counted as the engine counts."""
        self.spring = (stiffness, damping, self.sign * target - self.offset, max_force)

    def decl(self, name: str) -> JointDecl:
        """The scene joint: angles in degrees (a spring per degree)."""
        deg = math.degrees if self.type in _ANGULAR_TYPES else float
        spring = None
        if self.spring is not None:
            k, d, target, most = self.spring
            per = math.radians if self.type in _ANGULAR_TYPES else float
            spring = SpringDecl(tidy(per(k)), tidy(per(d)), tidy(deg(target)), most)
        return JointDecl(name, self.type, self.bodies, self.anchor, self.axis, self.axis2,
                         None if self.low is None else tidy(deg(self.low)),
                         None if self.high is None else tidy(deg(self.high)),
                         tidy(deg(self.motor_velocity)), self.motor_max_force, spring)


def working_joint(name: str, dofs: list[Dof], frames: Frames, joint_body: str | None,
                  connected_body: str | None, problems: Problems) -> WorkingJoint | None:
    """The scene joint for ``dofs`` between the body of the joint frame and the body of the
    connected frame (None: the world); None, told, when nothing here can hold it."""
    bodies = tuple(b for b in (connected_body, joint_body) if b is not None)
    made = _classify(name, dofs, frames.rotation, frames.origin, bodies, problems)
    if made is None:
        return None
    made.sign = 1.0 if connected_body is not None else -1.0
    made.offset = _start_offset(frames, made.free)
    if made.low is not None or made.high is not None:
        low, high = made.low, made.high
        if made.sign < 0:
            low, high = (None if high is None else -high), (None if low is None else -low)
        made.low = None if low is None else low - made.offset
        made.high = None if high is None else high - made.offset
    _check_aligned(name, dofs, frames, problems)
    return made


def _classify(name: str, dofs: list[Dof], axes: np.ndarray, anchor: np.ndarray,
              bodies: tuple[str, ...], problems: Problems) -> WorkingJoint | None:
    lin_free = [k for k in LINEAR if dofs[k][0] != "locked"]
    ang_free = [k for k in ANGULAR if dofs[k][0] != "locked"]

    def make(kind: str, free: int | None, axis: int = 5, axis2: int | None = None
             ) -> WorkingJoint:
        low = high = None
        if free is not None and dofs[free][0] == "limited":
            low = dofs[free][1] if math.isfinite(dofs[free][1]) else None
            high = dofs[free][2] if math.isfinite(dofs[free][2]) else None
        return WorkingJoint(kind, bodies, _tuple(anchor), _tuple(axes[:, axis % 3]),
                            None if axis2 is None else _tuple(axes[:, axis2 % 3]), low, high,
                            free)

    if lin_free and ang_free:
        if len(lin_free) == 1 and ang_free == [lin_free[0] + 3]:
            problems.warn(name, "a joint that slides and turns about one axis (cylindrical) is "
                                "a slider here: it does not turn")
            return make("Slider", lin_free[0], lin_free[0])
        problems.warn(name, f"its joint leaves linear axes free ({_axes(lin_free)}) as well as "
                            f"angular ones; here the linear ones are held")
        lin_free = []
    if not lin_free:
        if not ang_free:
            return make("Fixed", None)
        if len(ang_free) == 1:
            return make("Hinge", ang_free[0], ang_free[0])
        if len(ang_free) == 2:
            if dofs[ang_free[1]][0] == "limited":
                problems.warn(name, f"a universal joint's limit on its second axis "
                                    f"({DOF_NAMES[ang_free[1]]}) is left out")
            return make("Universal", ang_free[0], ang_free[0], ang_free[1])
        if any(dofs[k][0] == "limited" for k in ang_free):
            problems.warn(name, "a ball joint's angular limits are left out")
        return make("Ball", None)
    if len(lin_free) == 1:
        return make("Slider", lin_free[0], lin_free[0])
    if any(dofs[k][0] == "limited" for k in lin_free):
        problems.warn(name, f"an Align joint's linear limits ({_axes(lin_free)}) are left "
                            f"out: those axes are free")
    return make("Align", None)


def _axes(dofs: list[int]) -> str:
    return " ".join("XYZ"[k % 3] for k in dofs)


def _start_offset(frames: Frames, free: int | None) -> float:
    """Where the free axis starts: the connected frame's offset from the joint frame
    along it (m), or its angle about it (rad)."""
    if free is None:
        return 0.0
    axis = frames.rotation[:, free % 3]
    if free < 3:
        return float(axis @ (frames.connected_origin - frames.origin))
    q = matrix_to_quat(frames.rotation.T @ frames.connected_rotation)
    return 2.0 * math.atan2(float(q[1 + free % 3]), float(q[0]))


def _check_aligned(name: str, dofs: list[Dof], frames: Frames, problems: Problems) -> None:
    """Locked axes whose frames do not start together are held where they start (the file
    would pull them together): told."""
    gap = frames.rotation.T @ (frames.connected_origin - frames.origin)
    apart = [DOF_NAMES[k] for k in LINEAR if dofs[k][0] == "locked" and abs(gap[k]) > 1e-4]
    if apart:
        problems.warn(name, f"its attachment frames start apart along {', '.join(apart)}; "
                            f"the joint holds them where they start")


def _tuple(v: np.ndarray) -> tuple[float, ...]:
    return tuple(float(x) for x in v)
