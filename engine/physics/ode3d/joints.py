"""Joints for the ODE backend: component joints checked and turned into joint arguments.

``hinge2`` limits act on axis 1 (steering) and its motor on axis 2 (the wheel);
``joint_state`` reports axis 1. ``six_dof`` joints drive ``body_a`` toward a target
pose with a linear and an angular motor on the three world axes (dJointTypeLMotor +
AMotor), whose target velocities are set in C before each step to ``pose error / dt``
and whose force is bounded by ``motor_max_force`` (force and torque; change them with
``set_drive_limits``). With a ``body_b`` (the tracked, usually kinematic, target) the
target is ``body_a``'s pose relative to ``body_b`` at creation, carried along as
``body_b`` moves; without one it is a world pose set by ``set_joint_target``. The
solver applies at most the bounded force, so a blocked hand pushes but never tunnels
or explodes, and the constraint is implicit (stable at any gain, unlike an explicit PD
force). A joint with a ``reference`` (its bodies' poses when it was first made) is
made as if its bodies stood there, then they are put back: ODE keeps anchors, axes and
the reference rotation in the bodies' frames, fixed when the joint is made, so this
re-creates a saved joint bit for bit. A hinge's or slider's ``spring`` is an angular or
linear motor beside it whose row is the implicit spring-damper (``_Spring`` in
``_joints.pxi``), so the joint keeps its limits and motor.
"""

from __future__ import annotations

import numpy as np

from components import Joint
from components.joint import AXISLESS_KINDS, JointKind
from engine.physics.ode3d import _ode
from engine.physics.ode3d.values import vec

JOINT_KINDS = {JointKind.HINGE: _ode.JOINT_HINGE, JointKind.MOTORIZED_HINGE: _ode.JOINT_HINGE,
               JointKind.BALL: _ode.JOINT_BALL, JointKind.SLIDER: _ode.JOINT_SLIDER,
               JointKind.UNIVERSAL: _ode.JOINT_UNIVERSAL, JointKind.HINGE2: _ode.JOINT_HINGE2,
               JointKind.FIXED: _ode.JOINT_FIXED, JointKind.ANGULAR_MOTOR: _ode.JOINT_AMOTOR,
               JointKind.LINEAR_MOTOR: _ode.JOINT_LMOTOR, JointKind.SIX_DOF: _ode.JOINT_SIX_DOF,
               JointKind.ALIGN: _ode.JOINT_ALIGN}


def create(world: _ode.World, key: int, joint: Joint) -> None:
    """Make ``joint`` in ``world``; ValueError or KeyError naming the joint."""
    name = joint.id or key
    kind = JOINT_KINDS.get(joint.kind)
    if kind is None:
        raise ValueError(f"joint {name}: unknown kind {joint.kind!r} "
                         f"(expected one of {', '.join(JOINT_KINDS)})")
    axis = vec(joint.axis, 3, "joint axis")
    axis2 = vec(joint.axis2, 3, "joint axis2")
    if joint.kind not in AXISLESS_KINDS and not np.linalg.norm(axis) > 0:
        raise ValueError(f"joint {name}: axis is zero")
    ref_a = ref_b = None
    if joint.reference is not None:
        pose_a, pose_b = joint.reference
        ref_a = vec(pose_a, 7, "joint reference pose of body_a")
        if pose_b is not None and joint.body_b is not None:
            ref_b = vec(pose_b, 7, "joint reference pose of body_b")
    try:
        _ode.create_joint(world, int(key), kind, int(joint.body_a),
                          None if joint.body_b is None else int(joint.body_b),
                          vec(joint.anchor, 3, "joint anchor"), axis, axis2, joint.low,
                          joint.high, float(joint.motor_velocity),
                          float(joint.motor_max_force), ref_a, ref_b, _spring(joint))
    except KeyError as exc:
        raise KeyError(f"joint {name}: {exc.args[0]}") from None


def _spring(joint: Joint) -> tuple[float, float, float, float] | None:
    """The joint's spring as the binding takes it (a motorized hinge is ODE's hinge)."""
    sp = joint.spring
    if sp is None:
        return None
    return (float(sp.stiffness), float(sp.damping), float(sp.target), float(sp.max_force))
