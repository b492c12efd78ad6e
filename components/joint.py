"""Constraints between bodies, and the one list of joint kinds."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from components.blocks import BlockDeclaration, BuildContext, Key, declare
from components.exact import exact_degrees


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


#: Kinds that turn about two axes, which ODE needs independent (it aborts the process on
#: parallel hinge2 axes; a universal's fail its step).
TWO_AXES = frozenset({JointKind.UNIVERSAL, JointKind.HINGE2})
#: Why a hinge2 needs two bodies (ODE aborts the process on one alone).
HINGE2_BODIES = ("a hinge2 joint joins two bodies, the wheel (a) to its chassis (b); it "
                 "cannot join one to the world or to a static object")
#: The axes a joint kind turns or slides along (a zero one is an error).
AXES_NEEDED = {
    JointKind.HINGE: ("Axis",), JointKind.MOTORIZED_HINGE: ("Axis",),
    JointKind.SLIDER: ("Axis",), JointKind.UNIVERSAL: ("Axis", "Axis2"),
    JointKind.HINGE2: ("Axis", "Axis2"),
}


def parallel(a: Any, b: Any) -> bool:
    """Whether two non-zero axes point along one line (within a millionth of a radian)."""
    u, v = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return bool(np.linalg.norm(np.cross(u, v)) <= 1e-6 * np.linalg.norm(u) * np.linalg.norm(v))


def _floats(values: Any) -> tuple[float, ...]:
    return tuple(float(x) for x in values)


def _bodies_usable(j: Mapping[str, Any], ctx: BuildContext, a: str, b: str | None) -> bool:
    """Whether the joint's bodies can be joined (each has a body, two differ), told."""
    for name in j["Bodies"]:
        body = ctx.body(name)
        if body is None or (not body.physical and body.here):
            ctx.error("Bodies", f"joint body '{name}' has no PhysicalAttributes")
            return False
    if b is not None and a == b:
        ctx.error("Bodies", f"a joint needs two different bodies, got '{a}' twice (one body "
                  f"alone: Bodies [\"{a}\"] joins it to the world)")
        return False
    return True


def _axes_usable(j: Mapping[str, Any], ctx: BuildContext, kind: JointKind,
                 bodies: tuple[str, str | None]) -> None:
    """Tell axes the kind cannot turn about, and a hinge2 without two moving bodies."""
    for key in AXES_NEEDED.get(kind, ()):
        if ctx.given(key) and not any(j[key]):
            ctx.error(key, f"{key} must not be zero: a {j['Type']} joint turns or slides "
                      "along it")
    if kind in TWO_AXES and any(j["Axis"]) and any(j["Axis2"]) and \
            parallel(j["Axis"], j["Axis2"]):
        key, other = ("Axis2", "Axis") if ctx.given("Axis2") else ("Axis", "Axis2")
        given = " ".join(f"{x:g}" for x in j[other])
        ctx.error(key, f"{key} must not be parallel to {other} [{given}]"
                  f"{'' if ctx.given(other) else ' (its default)'}: a {j['Type']} joint "
                  "turns about two different axes")
    a, b = bodies
    static = [body for body in (ctx.body(a), None if b is None else ctx.body(b))
              if body is not None and body.static]
    if kind == JointKind.HINGE2 and (b is None or static):
        ctx.error("Bodies", f'{HINGE2_BODIES} (Bodies ["wheel" "chassis"], both dynamic)')


def build_joint(j: Mapping[str, Any], ctx: BuildContext) -> list[Any] | None:
    """A ``Joint`` block: a joint between objects by ID, made once they exist. Its
    reference poses are the file's or, when this scene makes both bodies, their poses
    now (where they are when the joint is made)."""
    jid, kind = ctx.owner, SCENE_JOINT_TYPES[j["Type"]]
    names = list(j["Bodies"])
    a, b = names[0], names[1] if len(names) > 1 else None
    left_out = [name for name in names if ctx.left_out(name)]
    if left_out:
        ctx.problem("Bodies", f"joint '{jid}' is left out: its body '{left_out[0]}' was "
                    "(see its error)")
        ctx.join(Joint(kind=kind, id=jid), (a, b), skipped=True)
        return []
    if not _bodies_usable(j, ctx, a, b):
        return []
    _axes_usable(j, ctx, kind, (a, b))
    for key in ("Anchor", "ReferencePose1", "ReferencePose2"):
        ctx.within_world(key)
    conv = (lambda x: x) if kind in LINEAR_KINDS else math.radians
    body_a, body_b = ctx.body(a), None if b is None else ctx.body(b)
    assert body_a is not None

    def pose(key: str, body: Any) -> tuple[float, ...]:
        return _floats(j[key]) if ctx.given(key) else (*body.pose[0], *body.pose[1])

    reference = None
    if ctx.given("ReferencePose1") or ctx.given("ReferencePose2") or (
            body_a.here and (body_b is None or body_b.here)):
        reference = (pose("ReferencePose1", body_a),
                     None if body_b is None else pose("ReferencePose2", body_b))
    low, high = j["Low"], j["High"]
    joint = Joint(kind=kind, anchor=_floats(j["Anchor"]) if ctx.given("Anchor")
                  else body_a.pose[0], axis=_floats(j["Axis"]), axis2=_floats(j["Axis2"]),
                  low=None if low is None else conv(low),
                  high=None if high is None else conv(high),
                  motor_velocity=conv(j["MotorVelocity"]),
                  motor_max_force=float(j["MotorMaxForce"]), id=jid, reference=reference,
                  spring=_spring(j, ctx, kind))
    ctx.join(joint, (a, b))
    return []


def _spring(j: Mapping[str, Any], ctx: BuildContext, kind: JointKind) -> Spring | None:
    """The joint's ``Spring`` block in the engine's units (per radian), or None (told
    when it cannot act: a joint without one free axis, nothing to pull with)."""
    found = ctx.inner("Spring")
    if not found:
        return None
    s, at = found[-1]
    if kind not in SPRING_KINDS:
        at.error(None, f"a {j['Type']} joint takes no Spring (Hinge, MotorizedHinge and "
                 "Slider do: one free axis)")
        return None
    bad = False
    for key in ("Stiffness", "Damping"):
        if not 0 <= s[key] < math.inf:
            at.error(key, f"Spring {key} must be 0 or more, got {s[key]:g}")
            bad = True
    most = s["MaxForce"]
    if most is not None and not most > 0:
        at.error("MaxForce", f"Spring MaxForce must be above 0, got {most:g}")
        bad = True
    if not bad and s["Stiffness"] == 0 and s["Damping"] == 0:
        at.error(None, "a Spring needs a Stiffness or a Damping above 0")
        bad = True
    if bad:
        return None
    per = 1.0 if kind in LINEAR_KINDS else math.degrees(1.0)  # per degree -> per radian
    return Spring(float(s["Stiffness"]) * per, float(s["Damping"]) * per,
                  float(s["Target"]) if kind in LINEAR_KINDS else math.radians(s["Target"]),
                  math.inf if most is None else float(most))


def save_joint(joint: Joint) -> dict[str, Any]:
    """A joint as made at first (anchor, axes, where its bodies were) and its motor now,
    in file units that read back to the bit (what a saved state sets on its block)."""
    conv = (lambda x: x) if joint.kind in LINEAR_KINDS else exact_degrees
    keys: dict[str, Any] = {"Anchor": tuple(joint.anchor), "Axis": tuple(joint.axis),
                            "Axis2": tuple(joint.axis2)}
    if joint.reference is not None:
        pose_a, pose_b = joint.reference
        keys["ReferencePose1"] = tuple(pose_a)
        if pose_b is not None:
            keys["ReferencePose2"] = tuple(pose_b)
    keys["MotorVelocity"] = conv(float(joint.motor_velocity))
    keys["MotorMaxForce"] = float(joint.motor_max_force)
    return keys


def _values_only(values: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A block whose values the block around it reads (it builds nothing itself)."""
    return []


_ANGLE = "degrees, or m for a slider"
JOINT_BLOCK = declare(BlockDeclaration(
    "Joint", inside=("Scene",), build=build_joint, entity=False, saves=Joint, save=save_joint,
    doc="a constraint between bodies", keys=(
        Key("ID", "string", "", "name other declarations use to refer to this joint",
            example='"pivot"'),
        Key("Type", "enum", None, "the kind of constraint", required=True,
            allowed=tuple(SCENE_JOINT_TYPES), example='"Hinge"'),
        Key("Bodies", "stringvector", None, "one object (jointed to the world) or two",
            required=True, ref="Object", lengths=(1, 2), example='["lid" "box"]'),
        Key("Anchor", "vec3", None, "world frame, with the bodies at their reference poses "
            "(default: first body's position)", unit="m", example="[0.5 2.5 1.5]"),
        Key("Axis", "vec3", (0.0, 0.0, 1.0), "hinge, slider or first axis, world frame"),
        Key("Axis2", "vec3", (0.0, 1.0, 0.0), "second axis (Universal, Hinge2), world frame"),
        Key("Low", "float", None, "lower limit: " + _ANGLE, example="-30"),
        Key("High", "float", None, "upper limit: " + _ANGLE, example="45"),
        Key("MotorVelocity", "float", 0.0, "deg/s, or m/s for a slider"),
        Key("MotorMaxForce", "float", 0.0, "N*m, or N for a slider"),
        Key("ReferencePose1", "vector", None, "[x y z qw qx qy qz] (m, quaternion): the first "
            "body's pose when the joint was first made; Anchor and axes are as they were "
            "then (default: the body's own pose)", lengths=(7,), example="[0 0 1 1 0 0 0]"),
        Key("ReferencePose2", "vector", None, "the same for the second body", lengths=(7,),
            example="[1 0 1 1 0 0 0]"),
    )))
SPRING_BLOCK = declare(BlockDeclaration(
    "Spring", inside=("Joint",), build=_values_only,
    doc="a spring-damper on a Hinge's, MotorizedHinge's or Slider's free axis (beside its "
    "limits and motor)", keys=(
        Key("Stiffness", "float", 0.0, "N*m per degree, or N/m for a slider: its pull toward "
            "Target"),
        Key("Damping", "float", 0.0, "N*m per deg/s, or N per m/s: how it resists the "
            "joint's rate (alone, without Stiffness: a damper)"),
        Key("Target", "float", 0.0, "degrees, or m for a slider, counted as Low and High are "
            "(0: where the joint was made)"),
        Key("MaxForce", "float", None, "N*m, or N: the most it pulls with (default: no "
               "bound)"),
    )))
