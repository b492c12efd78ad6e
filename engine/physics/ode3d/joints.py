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
re-creates a saved joint bit for bit.
"""

from __future__ import annotations

import numpy as np

from components import Joint
from engine.physics.ode3d import _ode
from engine.physics.ode3d.values import vec

JOINT_KINDS = {"hinge": _ode.JOINT_HINGE, "motorized_hinge": _ode.JOINT_HINGE,
               "ball": _ode.JOINT_BALL, "slider": _ode.JOINT_SLIDER,
               "universal": _ode.JOINT_UNIVERSAL, "hinge2": _ode.JOINT_HINGE2,
               "fixed": _ode.JOINT_FIXED, "angular_motor": _ode.JOINT_AMOTOR,
               "linear_motor": _ode.JOINT_LMOTOR, "six_dof": _ode.JOINT_SIX_DOF}
#: Kinds with no axis of their own.
AXISLESS = (_ode.JOINT_BALL, _ode.JOINT_FIXED, _ode.JOINT_SIX_DOF)


def create(world: _ode.World, key: int, joint: Joint) -> None:
    """Make ``joint`` in ``world``; ValueError or KeyError naming the joint."""
    name = joint.id or key
    kind = JOINT_KINDS.get(joint.kind)
    if kind is None:
        raise ValueError(f"joint {name}: unknown kind {joint.kind!r} "
                         f"(expected one of {', '.join(JOINT_KINDS)})")
    axis = vec(joint.axis, 3, "joint axis")
    axis2 = vec(joint.axis2, 3, "joint axis2")
    if kind not in AXISLESS and not np.linalg.norm(axis) > 0:
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
                          float(joint.motor_max_force), ref_a, ref_b)
    except KeyError as exc:
        raise KeyError(f"joint {name}: {exc.args[0]}") from None
