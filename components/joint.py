"""Constraints between bodies, and the one list of joint kinds."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum


class JointKind(StrEnum):
    """Every joint kind; backends, the scene format and Lua all name joints by these."""

    HINGE = "hinge"
    MOTORIZED_HINGE = "motorized_hinge"
    BALL = "ball"
    SLIDER = "slider"
    UNIVERSAL = "universal"
    HINGE2 = "hinge2"
    FIXED = "fixed"
    SIX_DOF = "six_dof"
    ANGULAR_MOTOR = "angular_motor"
    LINEAR_MOTOR = "linear_motor"
    #: Holds the bodies' relative orientation, leaves them free to move apart (a joint of
    #: KHR_physics_rigid_bodies locking its angular axes only).
    ALIGN = "align"


#: The scene format's ``Joint { Type ... }`` names (the paper's spelling) and their kinds.
SCENE_JOINT_TYPES: dict[str, JointKind] = {
    "Hinge": JointKind.HINGE, "MotorizedHinge": JointKind.MOTORIZED_HINGE,
    "Ball": JointKind.BALL, "Slider": JointKind.SLIDER, "Universal": JointKind.UNIVERSAL,
    "Hinge2": JointKind.HINGE2, "Fixed": JointKind.FIXED, "SixDOF": JointKind.SIX_DOF,
    "Align": JointKind.ALIGN,
}

#: Kinds whose limits and motor act along a line (metres, m/s, N) rather than an angle.
LINEAR_KINDS = frozenset({JointKind.SLIDER, JointKind.LINEAR_MOTOR})
#: Kinds with no axis of their own (a zero ``axis`` is no mistake for them).
AXISLESS_KINDS = frozenset({JointKind.BALL, JointKind.FIXED, JointKind.SIX_DOF,
                            JointKind.ALIGN})


@dataclass(frozen=True, slots=True)
class Spring:
    """A spring-damper pulling a hinge's or slider's free axis toward ``target`` (rad or
    m, counted as the joint's angle or position: from where the joint was made):
    ``-stiffness (x - target) - damping v`` (N·m/rad and N·m·s/rad, or N/m and N·s/m),
    at most ``max_force`` (N·m or N). Stiffness 0 is a damper alone (a drive toward a
    velocity of 0)."""

    stiffness: float = 0.0
    damping: float = 0.0
    target: float = 0.0
    max_force: float = math.inf


#: Kinds a Spring can act on (one free axis).
SPRING_KINDS = frozenset({JointKind.HINGE, JointKind.MOTORIZED_HINGE, JointKind.SLIDER})


@dataclass(slots=True)
class Joint:
    """A constraint between two bodies (``body_b`` None means the static world).

    ``kind`` is a :class:`JointKind`. ``anchor``/``axis`` are in world
    coordinates at creation. Limits are in radians (angular) or metres (slider).
    A motor drives ``motor_velocity`` (rad/s or m/s) with at most
    ``motor_max_force`` (N·m or N). For six_dof, ``body_b`` is the tracked target
    (or None: the target is set with ``set_joint_target``) and ``motor_max_force``
    caps both force and torque until ``set_drive_limits`` changes them.

    ``reference`` is the pose (x, y, z, qw, qx, qy, qz) of ``body_a`` and of
    ``body_b`` (None for the world) when the joint was first made, with ``anchor``
    and ``axis`` as they were then; a backend makes the joint as if the bodies
    were there, which re-creates a saved joint exactly. None: where they are now.
    ``spring`` (a hinge's or slider's) pulls the free axis toward a target.
    """

    kind: str = JointKind.HINGE
    body_a: int = -1
    body_b: int | None = None
    anchor: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    axis2: tuple[float, float, float] = (0.0, 1.0, 0.0)
    low: float | None = None
    high: float | None = None
    motor_velocity: float = 0.0
    motor_max_force: float = 0.0
    id: str = ""
    broken: bool = False
    reference: tuple[tuple[float, ...], tuple[float, ...] | None] | None = None
    spring: Spring | None = None
