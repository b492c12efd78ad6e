"""Joint components → pymunk constraints.

hinge → PivotJoint (+ RotaryLimitJoint for limits); motorized_hinge → the same +
SimpleMotor whose ``max_force`` is the motor torque; slider → GrooveJoint + GearJoint
(no relative turning), its motor a bounded force applied before each step; fixed →
PivotJoint + GearJoint; six_dof → PivotJoint + GearJoint whose ``max_force`` is
``motor_max_force`` (N and N·m), holding body_a at its pose relative to body_b (a
kinematic target, carried along as it moves) or, without body_b, at a world pose
that ``set_target`` moves, with bounded force.

Approximations, each reported once: ball and universal → pivot (out-of-plane freedom
dropped); hinge2 → pivot about the wheel axle (steering and suspension dropped: its
motor drives the wheel; its limits and joint state belong to the steering, so they
are dropped and 0); a hinge axis off ±Y → treated as ±Y.

A hinge's or slider's spring is a force (torque) applied before each step from the
joint's position and rate (:meth:`JointRecord.drive_spring`).

Joint angles follow ODE: a hinge's angle is body_a's rotation relative to body_b about
the joint axis, zero when the joint is made; a slider's position is
``(p_a − p_b)·axis`` minus its value when made. Jointed bodies do not collide.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pymunk

from components import Joint
from components.joint import JointKind

#: Groove half-length for a slider without limits (m).
FREE_GROOVE = 1.0e3
#: Share of a six_dof's pose error corrected per second (pymunk error_bias).
SIX_DOF_ERROR_BIAS = (1.0 - 0.5) ** 60

Warn = Callable[[str, str], None]

#: Kinds made as a pivot about Y (their out-of-plane freedom dropped); fixed and six_dof
#: pin the bodies, a slider slides; the motors of their own ODE has are not made here.
PIVOTS = frozenset({JointKind.HINGE, JointKind.MOTORIZED_HINGE, JointKind.BALL,
                    JointKind.UNIVERSAL, JointKind.HINGE2})
#: Kinds whose axis is turned onto ±Y (the one axis the plane has).
ON_AXIS = frozenset({JointKind.HINGE, JointKind.MOTORIZED_HINGE, JointKind.HINGE2})
SUPPORTED = PIVOTS | {JointKind.SLIDER, JointKind.FIXED, JointKind.SIX_DOF, JointKind.ALIGN}


@dataclass(slots=True)
class JointRecord:
    """A joint as pymunk constraints, with what is needed to read and drive it."""

    spec: Joint
    a: pymunk.Body
    b: pymunk.Body
    constraints: list[pymunk.Constraint] = field(default_factory=list)
    sign: float = 1.0  # +1 when the joint axis is +Y, −1 when −Y
    zero: float = 0.0  # relative angle (θb−θa) or slider position when made
    axis: tuple[float, float] = (1.0, 0.0)  # slider axis in the plane
    motor: pymunk.SimpleMotor | None = None
    slider_velocity: float = 0.0
    slider_max_force: float = 0.0

    def state(self) -> tuple[float, float]:
        """Position (angle or distance) and rate of the first axis, ODE's sign."""
        if self.spec.kind == JointKind.HINGE2:
            return 0.0, 0.0  # the first axis is the steering, held straight in the plane
        if self.spec.kind == JointKind.SLIDER:
            ax, az = self.axis
            dp = self.a.position - self.b.position
            dv = self.a.velocity - self.b.velocity
            return dp.x * ax + dp.y * az - self.zero, dv.x * ax + dv.y * az
        rel = self.b.angle - self.a.angle
        return self.sign * (rel - self.zero), self.sign * (self.b.angular_velocity
                                                           - self.a.angular_velocity)

    def set_motor(self, velocity: float, max_force: float, space: pymunk.Space) -> None:
        if self.spec.kind == JointKind.SLIDER:
            self.slider_velocity, self.slider_max_force = velocity, max_force
            return
        if self.motor is None:
            self.motor = pymunk.SimpleMotor(self.a, self.b, 0.0)
            self.motor.collide_bodies = False
            self.constraints.append(self.motor)
            space.add(self.motor)
        # SimpleMotor holds ω_a − ω_b = rate; ODE's rate is sign·(ω_b − ω_a).
        self.motor.rate = -self.sign * velocity
        self.motor.max_force = max(0.0, max_force)

    def set_target(self, position: tuple[float, float], angle: float,
                   max_force: float | None, max_torque: float | None) -> None:
        """A six_dof's new target: body_a's origin at ``position``, turned to ``angle``."""
        pivot, gear = self.constraints[0], self.constraints[1]
        pivot.anchor_b = self.b.world_to_local(position)
        gear.phase = self.b.angle - angle
        self.set_drive_limits(max_force, max_torque)

    def set_drive_limits(self, max_force: float | None, max_torque: float | None) -> None:
        """A six_dof's force (N) and torque (N·m) bounds; None keeps one as it is."""
        pivot, gear = self.constraints[0], self.constraints[1]
        if max_force is not None:
            pivot.max_force = max_force
        if max_torque is not None:
            gear.max_force = max_torque

    def set_drive_response(self, time_constant: float | None, max_speed: float | None,
                           max_spin: float | None) -> None:
        """A six_dof's response: its error closes with ``time_constant`` (s; chipmunk's
        ``error_bias`` is the share left after a second, e^(-1/τ)), the correcting speed
        (m/s) and spin (rad/s) capped (``max_bias``); None keeps one as it is. The
        control body's own velocity is matched by the constraints: the feed-forward."""
        pivot, gear = self.constraints[0], self.constraints[1]
        if time_constant is not None:
            bias = math.exp(-1.0 / time_constant) if time_constant > 0.0 else 0.0
            pivot.error_bias = gear.error_bias = bias
        if max_speed is not None:
            pivot.max_bias = max_speed
        if max_spin is not None:
            gear.max_bias = max_spin

    def before_step(self, dt: float) -> None:
        """What acts on the bodies as forces this step: a slider's motor, a spring."""
        if self.spec.kind == JointKind.SLIDER:
            self.drive_slider(dt)
        if self.spec.spring is not None:
            self.drive_spring(dt)

    def _inverse(self) -> float:
        """The bodies' inverse mass (a slider) or moment (a hinge) along the free axis."""
        linear = self.spec.kind == JointKind.SLIDER
        return sum(1.0 / (body.mass if linear else body.moment) for body in (self.a, self.b)
                   if body.body_type == pymunk.Body.DYNAMIC)

    def _push(self, force: float) -> None:
        """``force`` along the free axis (N, or N·m about it), ODE's sense: on body_a
        toward a larger position or angle, on body_b the other way."""
        if self.spec.kind == JointKind.SLIDER:
            ax, az = self.axis
            for body, f in ((self.a, force), (self.b, -force)):
                if body.body_type == pymunk.Body.DYNAMIC:
                    body.apply_force_at_local_point((f * ax, f * az), body.center_of_gravity)
            return
        # the angle is sign (θb − θa): a positive force turns a back, b on
        for body, t in ((self.a, -self.sign * force), (self.b, self.sign * force)):
            if body.body_type == pymunk.Body.DYNAMIC:
                body.torque += t

    def drive_slider(self, dt: float) -> None:
        """The slider motor: the force that reaches the target rate this step, bounded."""
        if self.slider_max_force <= 0.0:
            return
        inv = self._inverse()
        if inv == 0.0:
            return
        _, rate = self.state()
        force = (self.slider_velocity - rate) / (inv * dt)
        self._push(max(-self.slider_max_force, min(self.slider_max_force, force)))

    def drive_spring(self, dt: float) -> None:
        """The spring's pull ``-k (x − target)`` and its damping as the impulse that takes
        ``1 − e^(−d h / m)`` of the rate away this step (chipmunk's damped springs' rule,
        stable at any damping; ``d v`` when that is small), at most its max force. The
        pull is the one at ``x + h v``, where the step puts the joint before it turns
        forces into velocity (chipmunk moves bodies first): symplectic, so an undamped
        spring keeps its energy (at ``x`` it would gain ``ω² h²`` of it a step). A spring
        too stiff for the step (``k h² / m > 1``, m the bodies' mass, or moment about their
        own centres, along the axis) pulls as at the end of the step, implicitly, as under
        ODE: stable at any stiffness."""
        sp = self.spec.spring
        inv = self._inverse()
        if sp is None or inv == 0.0:
            return
        x, rate = self.state()
        pull = -sp.stiffness * (x + dt * rate - sp.target)
        if sp.stiffness * dt * dt * inv > 1.0:
            soft = dt * sp.stiffness + sp.damping
            force = (pull - soft * rate) / (1.0 + soft * dt * inv)
        else:
            force = pull - rate * -math.expm1(-sp.damping * dt * inv) / (inv * dt)
        self._push(max(-sp.max_force, min(sp.max_force, force)))


def _axis_sign(spec: Joint, axis: tuple[float, float, float], warn: Warn) -> float:
    v = np.asarray(axis, dtype=np.float64)
    n = float(np.linalg.norm(v))
    if n == 0.0 or abs(v[1]) < 0.999 * n:
        warn("axis", f"{spec.kind} axis {tuple(axis)} is not along ±Y; treated as +Y"
             if n == 0.0 or v[1] >= 0 else
             f"{spec.kind} axis {tuple(axis)} is not along ±Y; treated as −Y")
    return -1.0 if n > 0.0 and v[1] < 0.0 else 1.0


def _limits(rec: JointRecord, spec: Joint) -> None:
    if spec.low is None and spec.high is None:
        return
    low = spec.low if spec.low is not None else -math.inf
    high = spec.high if spec.high is not None else math.inf
    lo, hi = (low, high) if rec.sign > 0 else (-high, -low)
    lo = rec.zero + lo if math.isfinite(lo) else -1e9
    hi = rec.zero + hi if math.isfinite(hi) else 1e9
    rec.constraints.append(pymunk.RotaryLimitJoint(rec.a, rec.b, lo, hi))


def build_joint(spec: Joint, a: pymunk.Body, b: pymunk.Body, warn: Warn) -> JointRecord:
    """Constraints for ``spec`` between ``a`` and ``b`` (b may be the space's static body):
    each kind's builder from :data:`_BUILDERS`."""
    kind = spec.kind
    rec = JointRecord(spec, a, b)
    rec.zero = b.angle - a.angle
    builder = next((f for kinds, f in _BUILDERS if kind in kinds), None)
    if builder is None:
        what = "has no 2D form" if kind in JointKind.__members__.values() else "unknown kind"
        raise ValueError(f"joint {spec.id or '?'}: {what} {kind!r}; pymunk makes "
                         f"{', '.join(k for k in JointKind if k in SUPPORTED)}")
    builder(rec, warn)
    for c in rec.constraints:
        c.collide_bodies = False
    return rec


def _pivot(rec: JointRecord, warn: Warn) -> None:
    """A pin about Y (what the plane keeps of a hinge, ball, universal or hinge2), its
    limits and motor."""
    spec, a, b, kind = rec.spec, rec.a, rec.b, rec.spec.kind
    if kind == JointKind.BALL:
        warn("ball", "ball joint: out-of-plane rotation dropped; pivot about Y")
    elif kind == JointKind.UNIVERSAL:
        warn("universal", "universal joint: second axis dropped; pivot about Y")
    elif kind == JointKind.HINGE2:
        warn("hinge2", "hinge2: steering and suspension dropped; pivot about the axle")
    axis = spec.axis2 if kind == JointKind.HINGE2 else spec.axis
    rec.sign = _axis_sign(spec, axis, warn) if kind in ON_AXIS else 1.0
    rec.constraints.append(pymunk.PivotJoint(a, b, (float(spec.anchor[0]),
                                                    float(spec.anchor[2]))))
    if kind != JointKind.HINGE2:  # a hinge2's limits are its steering's (dropped)
        _limits(rec, spec)
    if kind == JointKind.MOTORIZED_HINGE or spec.motor_max_force > 0.0:
        motor = pymunk.SimpleMotor(a, b, -rec.sign * spec.motor_velocity)
        motor.max_force = max(0.0, spec.motor_max_force)
        rec.motor = motor
        rec.constraints.append(motor)


def _slider(rec: JointRecord, warn: Warn) -> None:
    """A groove along the axis projected on the plane, the angle held by a gear."""
    spec, a, b = rec.spec, rec.a, rec.b
    v = np.array([spec.axis[0], spec.axis[2]], dtype=np.float64)
    n = float(np.linalg.norm(v))
    if n < 1e-9:
        raise ValueError(f"joint {spec.id or '?'}: slider axis {tuple(spec.axis)} "
                         "has no component in the X–Z plane")
    if abs(spec.axis[1]) > 1e-9:
        warn("axis", f"slider axis {tuple(spec.axis)} leaves the X–Z plane; projected")
    ax, az = v / n
    rec.axis = (float(ax), float(az))
    dp = a.position - b.position
    rec.zero = dp.x * ax + dp.y * az
    low = spec.low if spec.low is not None else -FREE_GROOVE
    high = spec.high if spec.high is not None else FREE_GROOVE
    pa = a.position
    g1 = b.world_to_local((pa.x + low * ax, pa.y + low * az))
    g2 = b.world_to_local((pa.x + high * ax, pa.y + high * az))
    rec.constraints.append(pymunk.GrooveJoint(b, a, g1, g2, (0.0, 0.0)))
    rec.constraints.append(pymunk.GearJoint(a, b, b.angle - a.angle, 1.0))
    rec.slider_velocity = spec.motor_velocity
    rec.slider_max_force = spec.motor_max_force


def _align(rec: JointRecord, warn: Warn) -> None:
    """The angle between them held, nothing else."""
    rec.constraints.append(pymunk.GearJoint(rec.a, rec.b, rec.b.angle - rec.a.angle, 1.0))


def _weld(rec: JointRecord, warn: Warn) -> None:
    """Fixed (a pin where they are and the angle held), or the six-DOF drive: the same
    pair with bounded force and the drive's error bias."""
    spec, a, b = rec.spec, rec.a, rec.b
    pivot = pymunk.PivotJoint(a, b, (0.0, 0.0), b.world_to_local(a.position))
    gear = pymunk.GearJoint(a, b, b.angle - a.angle, 1.0)
    if spec.kind == JointKind.SIX_DOF:
        limit = spec.motor_max_force if spec.motor_max_force > 0.0 else math.inf
        for c in (pivot, gear):
            c.max_force = limit
            c.error_bias = SIX_DOF_ERROR_BIAS
    rec.constraints += [pivot, gear]


#: One builder per group of joint kinds.
_BUILDERS: tuple[tuple[Any, Callable[[JointRecord, Warn], None]], ...] = (
    (PIVOTS, _pivot), ((JointKind.SLIDER,), _slider), ((JointKind.ALIGN,), _align),
    ((JointKind.FIXED, JointKind.SIX_DOF), _weld))
