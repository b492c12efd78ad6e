"""The wheelchair plugin: a real chair's wheel counters drive a simulated wheelchair.

Paper section 5.5: the user sits in a real wheelchair whose rear wheels turn counters; the
simulated chair's rear wheels follow. An object with a :class:`~components.Wheelchair`
(the scene's ``Object { Wheelchair {...} }``) is the chassis; its ``Axles`` are the rear
wheels' hinge joints and its ``Wheels`` the input layer's counters
(``InputState.wheel(name).angular_velocity``: counts over device time, never over
frames). Each frame, in PRE_PHYSICS, so this frame's counts reach this frame's step:

- ``velocity`` mode (the paper's): each axle's motor turns its wheel at the real wheel's
  rate with at most ``MaxTorque``, plus a servo that makes up the ground the simulated
  wheel is behind the real one's turn (up to :data:`MAX_LAG`), so the wheels turn only as
  the real ones do and the chair never rolls down a slope, nor creeps where the solver
  lets a held wheel slip (a stopped real wheel is a held brake).
- A chair in velocity mode whose real wheels stand still is braked by them: once its
  chassis has been slow (under the world's SleepLinear, and spinning under a few times its
  SleepAngular) for SleepTime,
  the chair and every body jointed to it are put to sleep, as the engine's sleep rule
  would if the casters' solver jitter (their fork and wheel weigh a hundredth of the
  chassis) did not keep them awake; awake, the chair crept sideways about 1 mm/s where
  the iterative solver lets its tyres slip. A motor command (the real wheels turning), a
  mode switch or anything touching it wakes it.
- ``feedback`` mode (the paper's future work): the motors are off and the wheels free.
  A change Δω of the real wheel's rate over the frame is a push: the angular impulse
  ``RimInertia · Δω`` on the simulated wheel (and its reaction on the chassis: the
  user's arms push against the seat), as a torque of at most ``MaxPush`` (a harder push,
  a key pressed on the desktop, is spread over the frames after). Gravity and collisions
  act, so a ramp rolls the chair and a wall stops it; each frame the simulated wheels'
  rates (rad/s) and the pushes (N·m) are published as the output values
  ``wheelchair:ID/left/speed``, ``wheelchair:ID/left/torque`` (and ``right``) for a
  motorized rig that makes the real wheels feel it.

The mode can change at run time: write ``Wheelchair.mode``, or from Lua
``emit("wheelchair", {mode = "feedback"})`` (``object`` names the chair when there are
several); each change is told as :class:`WheelchairModeChanged` (and to Lua as the custom
event ``"wheelchair_mode"``). The plugin's memory (the servo's lag, the last rates, pushes
still to apply) lives on the component, so a saved state continues it. Bad input never stops
the chair: a counter asking more than ``MaxSpeed`` is clamped with a message (the input
layer already turns wraps into motion and counter resets into messages), a wheel that
never reported stands still, axles that are not the chassis's hinges are told once and
that chair is left alone.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Joint, Name, Transform, Wheelchair
from components.joint import JointKind
from components.wheelchair import NavigationMode
from engine.events import CustomEvent
from engine.messages import MessageLog
from engine.physics.commands import ApplyTorque, CommandError, SetMotor, SetSleeping
from engine.rotation import quat_to_matrix
from engine.system import Phase, PluginName, System
from services.input import InputState

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.wheelchair")

SIDES = ("left", "right")
#: Velocity mode servos the ground each wheel covers to what the real one turned: the
#: error (as an angle, rad) closes in this time (s), so the chair does not creep where the
#: solver lets a held wheel turn or slip.
SERVO_TIME = 0.1
#: The largest angle error (rad) the servo makes up; beyond it (a wheel spinning against a
#: wall, slipping) the difference is forgiven instead of caught up later.
MAX_LAG = 0.01
#: An error under this (rad; 0.6 mm at the rim) is left alone: a chair standing still gets
#: no motor commands, so it can fall asleep (a command wakes its bodies).
DEADBAND = 0.002
#: A parked chair's chassis may spin up to this many times the world's SleepAngular: its
#: spin is judged frame by frame, unsmoothed, and jitters to 3 deg/s while the servo
#: holds it on a 1:12 ramp (a turning or toppling chair spins far faster, or moves).
PARK_SPIN = 5.0
#: The joint kinds a rear axle may be: a hinge whose motor the velocity mode sets.
AXLE_KINDS = (JointKind.HINGE, JointKind.MOTORIZED_HINGE)


@dataclass(frozen=True, slots=True)
class WheelchairModeChanged:
    """Wheelchair ``chair`` (its chassis entity) now navigates in ``mode``."""

    chair: int
    mode: str


@dataclass(slots=True, eq=False)
class _Rig:
    """One chair's axles resolved to joints and wheel bodies, and what it did last frame."""

    name: str
    axles: tuple[int, int]
    wheels: tuple[int, int]
    axes: np.ndarray  # each axle's axis in the chassis frame (rows: left, right)
    mode: str | None = None
    #: The real wheels' angles (rad, from their counts) last frame.
    turned: list[float | None] = field(default_factory=lambda: [None, None])
    torque: list[float] = field(default_factory=lambda: [0.0, 0.0])
    outputs: tuple[tuple[str, str], ...] = ()
    #: The chassis and every body jointed to it (wheels, forks, casters): what sleeps.
    bodies: tuple[int, ...] = ()


class WheelchairSystem(System):
    """PRE_PHYSICS: the counters' rates to motors (velocity) or pushes (feedback)."""

    phase = Phase.PRE_PHYSICS
    reads = (Wheelchair, Joint, Name, Transform)
    writes = (Wheelchair, Joint)

    def __init__(self) -> None:
        self._rigs: dict[int, _Rig | None] = {}
        self.messages = MessageLog(log)

    def setup(self, engine: Engine) -> None:
        engine.world.on_remove(Wheelchair, lambda e, c: self._rigs.pop(e, None))
        engine.events.subscribe(CustomEvent, lambda event: self._on_custom(engine, event))

    def _on_custom(self, engine: Engine, event: CustomEvent) -> None:
        """``emit("wheelchair", {mode = "feedback", object = "wheelchair"})`` from Lua."""
        if event.name != "wheelchair":
            return
        data = event.data if isinstance(event.data, dict) else {"mode": event.data}
        mode, target = data.get("mode"), data.get("object")
        if mode not in tuple(NavigationMode):
            self.messages.error(f"emit('wheelchair', ...): mode {mode!r} is not one of "
                                f"{', '.join(NavigationMode)}; the mode stays")
            return
        chairs = [(e, c) for e, c in engine.world.get_component(Wheelchair)
                  if target is None or _name(engine, e) == target]
        if not chairs:
            self.messages.error(f"emit('wheelchair', ...): no wheelchair {target!r}")
        for _, chair in chairs:
            chair.mode = mode

    # -- binding ------------------------------------------------------------------
    def _bind(self, engine: Engine, chassis: int, chair: Wheelchair) -> _Rig | None:
        name = _name(engine, chassis)
        world = engine.world
        t = world.try_component(chassis, Transform)
        if t is None:
            return self._refuse(name, "it has no pose")
        joints = {j.id: (e, j) for e, j in world.get_component(Joint) if j.id}
        axles, wheels, axes = [], [], []
        for side, joint_id in zip(SIDES, chair.axles, strict=True):
            found = joints.get(joint_id)
            if found is None:
                return self._refuse(name, f"no joint {joint_id!r} for its {side} axle")
            entity, joint = found
            if joint.kind not in AXLE_KINDS or chassis not in (joint.body_a, joint.body_b):
                return self._refuse(name, f"its {side} axle {joint_id!r} must be a hinge "
                                          "between the chassis and the wheel")
            wheel = joint.body_b if joint.body_a == chassis else joint.body_a
            if wheel is None:
                return self._refuse(name, f"its {side} axle {joint_id!r} holds no wheel")
            reference = t.orientation
            if joint.reference is not None:  # the axis is given at the reference poses
                poses = joint.reference
                pose = poses[0] if joint.body_a == chassis else poses[1]
                if pose is not None:
                    reference = np.asarray(pose[3:7])
            axis = np.asarray(joint.axis, float)
            axes.append(quat_to_matrix(np.asarray(reference, float)).T @ axis
                        / np.linalg.norm(axis))
            axles.append(entity)
            wheels.append(wheel)
        outputs = tuple((f"wheelchair:{name}/{side}/speed", f"wheelchair:{name}/{side}/torque")
                        for side in SIDES)
        return _Rig(name, (axles[0], axles[1]), (wheels[0], wheels[1]), np.array(axes),
                    outputs=outputs, bodies=_jointed(engine, chassis))

    def _refuse(self, name: str, why: str) -> None:
        log.error("wheelchair %r: %s; its wheels are not driven", name, why)
        return None

    # -- each frame ---------------------------------------------------------------------
    def run(self, engine: Engine, dt: float) -> None:
        world = engine.world
        inputs = engine.try_resource(InputState)
        outputs = _outputs(engine)
        for entity, chair in world.get_component(Wheelchair):
            if entity not in self._rigs:
                self._rigs[entity] = self._bind(engine, entity, chair)
            rig = self._rigs[entity]
            chassis = world.try_component(entity, Transform)
            if rig is None or chassis is None:
                continue
            rotation = quat_to_matrix(chassis.orientation)
            rates = [self._wheel_rate(engine, rig, i, rotation, chassis) for i in range(2)]
            measured = [self._rate(inputs, chair, rig, i) for i in range(2)]
            self._lags(engine, inputs, chair, rig, rotation, dt)
            if chair.mode != rig.mode:
                self._switch(engine, entity, rig, chair)
            try:
                if chair.mode == NavigationMode.VELOCITY:
                    self._velocity(engine, rig, chair, measured)
                else:
                    self._feedback(engine, entity, rig, chair, rotation, measured, dt)
            except CommandError as exc:  # never NaN (the input layer refuses it); kept safe
                self.messages.error(f"wheelchair {rig.name!r}: {exc}; the wheels hold")
            chair.measured = (measured[0], measured[1])
            self._park(engine, rig, chair, chassis, measured, dt)
            if outputs is not None:
                for i, (speed, torque) in enumerate(rig.outputs):
                    outputs.set(speed, rates[i])
                    outputs.set(torque, rig.torque[i])

    def _rate(self, inputs: InputState | None, chair: Wheelchair, rig: _Rig, i: int) -> float:
        """The real wheel's rate (rad/s), clamped to what MaxSpeed allows (told once)."""
        wheel = None if inputs is None else inputs.wheel(chair.wheels[i])
        rate = 0.0 if wheel is None else float(wheel.angular_velocity)
        limit = chair.max_speed / chair.wheel_radius
        if abs(rate) > limit:
            self.messages.warn(f"wheelchair {rig.name!r}: wheel {chair.wheels[i]!r} asks "
                               f"more than MaxSpeed {chair.max_speed:g} m/s "
                               f"({limit:.3g} rad/s); clamped")
            rate = math.copysign(limit, rate)
        return rate

    def _lags(self, engine: Engine, inputs: InputState | None, chair: Wheelchair, rig: _Rig,
              rotation: np.ndarray, dt: float) -> None:
        """How far each simulated wheel is behind its real one, updated: the real wheel's
        turn since last frame (from its unwrapped counts) less the ground the simulated
        wheel covered over a frame (its centre's speed along the chair's heading after the
        last step), as an angle. Measured on the ground, not at the axle, so it also
        makes up where the solver lets a held wheel slip."""
        forward = rotation[:, 1]
        lag = list(chair.lag)
        for i in range(2):
            wheel = None if inputs is None else inputs.wheel(chair.wheels[i])
            turned = 0.0 if wheel is None else 2.0 * math.pi * wheel.turns
            last = rig.turned[i]
            rig.turned[i] = turned
            hub = engine.world.try_component(rig.wheels[i], Transform)
            rolled = 0.0 if hub is None else float(hub.linear_velocity @ forward) * dt
            lag[i] += (0.0 if last is None else turned - last) - rolled / chair.wheel_radius
            lag[i] = max(-MAX_LAG, min(MAX_LAG, lag[i]))  # beyond: forgiven, not caught up
        chair.lag = (lag[0], lag[1])

    def _switch(self, engine: Engine, entity: int, rig: _Rig, chair: Wheelchair) -> None:
        """Entering feedback frees the wheels (motors off); velocity sets them next, its
        servo starting from where the wheels stand. (A chair's first frame keeps its
        servo's memory: a saved state continues where it stood.)"""
        if rig.mode is not None:
            log.info("wheelchair %r: %s mode", rig.name, chair.mode)
            rig.torque = [0.0, 0.0]
            chair.lag = chair.pending = (0.0, 0.0)
        rig.mode = chair.mode
        engine.events.emit(WheelchairModeChanged(entity, str(chair.mode)))
        engine.events.emit(CustomEvent("wheelchair_mode", {"object": rig.name,
                                                           "mode": str(chair.mode)}))
        if chair.mode == NavigationMode.FEEDBACK:
            for axle in rig.axles:
                self._motor(engine, axle, 0.0, 0.0)

    def _velocity(self, engine: Engine, rig: _Rig, chair: Wheelchair,
                  measured: list[float]) -> None:
        """Each motor turns at the real wheel's rate, plus what makes up the angle the
        simulated wheel is behind (at most MAX_LAG, the rest forgiven)."""
        limit = chair.max_speed / chair.wheel_radius
        for i, axle in enumerate(rig.axles):
            lag = chair.lag[i] if abs(chair.lag[i]) > DEADBAND else 0.0
            target = max(-limit, min(limit, measured[i] + lag / SERVO_TIME))
            self._motor(engine, axle, target, chair.max_torque)

    def _park(self, engine: Engine, rig: _Rig, chair: Wheelchair, chassis: Transform,
              measured: list[float], dt: float) -> None:
        """Velocity mode, real wheels still: once the chassis has been slow (SleepLinear,
        PARK_SPIN times SleepAngular) for the world's SleepTime, the chair is braked where
        it stands (the servo's last millimetre
        forgiven, the motors held) and sleeps. A sleeping body stands at exactly no
        velocity, so this is sent once."""
        world = engine.config.world
        if chair.mode != NavigationMode.VELOCITY or not world.auto_sleep or any(measured):
            chair.still = 0.0
            return
        v, w = chassis.linear_velocity, chassis.angular_velocity
        if not (v.any() or w.any()):  # asleep (or not stepped yet)
            return
        if float(np.linalg.norm(v)) > world.sleep_linear or float(
                np.linalg.norm(w)) > PARK_SPIN * world.sleep_angular:
            chair.still = 0.0
            return
        chair.still += dt
        if chair.still < world.sleep_time:
            return
        chair.still, chair.lag = 0.0, (0.0, 0.0)
        for axle in rig.axles:
            self._motor(engine, axle, 0.0, chair.max_torque)  # (a command wakes: first)
        for body in rig.bodies:
            engine.physics.push(SetSleeping(body, True))

    @staticmethod
    def _motor(engine: Engine, axle: int, velocity: float, max_torque: float) -> None:
        """Set an axle's motor, unless it is so already. The joint keeps what was set (a
        saved state writes it and the backend gets it back): a command repeated after a
        reload would wake a parked chair the uninterrupted run leaves asleep."""
        joint = engine.world.try_component(axle, Joint)
        if joint is not None and (joint.motor_velocity, joint.motor_max_force) == (
                velocity, max_torque):
            return
        engine.physics.push(SetMotor(axle, velocity, max_torque))
        if joint is not None:
            joint.motor_velocity, joint.motor_max_force = velocity, max_torque

    def _feedback(self, engine: Engine, entity: int, rig: _Rig, chair: Wheelchair,
                  rotation: np.ndarray, measured: list[float], dt: float) -> None:
        """Each wheel's push: RimInertia times the real wheel's change of rate is an
        angular impulse, applied as a torque of at most MaxPush; what a stronger push
        holds beyond that is applied over the next frames (nothing is lost). A torque
        lasts one physics step, so the frame's share goes in its first step (scaled by
        the steps per frame)."""
        if dt <= 0.0:
            return
        steps = max(getattr(engine.tick, "substeps", 1), 1)
        pending = list(chair.pending)
        for i, wheel in enumerate(rig.wheels):
            pending[i] += chair.rim_inertia * (measured[i] - chair.measured[i])
            push = max(-chair.max_push, min(chair.max_push, pending[i] / dt))
            pending[i] -= push * dt
            rig.torque[i] = push
            if push == 0.0:
                continue
            torque = rotation @ rig.axes[i] * (push * steps)
            engine.physics.push(ApplyTorque(wheel, torque))
            engine.physics.push(ApplyTorque(entity, -torque))
        chair.pending = (pending[0], pending[1])

    @staticmethod
    def _wheel_rate(engine: Engine, rig: _Rig, i: int, rotation: np.ndarray,
                    chassis: Transform) -> float:
        """The simulated wheel's rate relative to the chassis about its axle (rad/s)."""
        wheel = engine.world.try_component(rig.wheels[i], Transform)
        if wheel is None:
            return 0.0
        spin = wheel.angular_velocity - chassis.angular_velocity
        return float(spin @ (rotation @ rig.axes[i]))


def _name(engine: Engine, entity: int) -> str:
    name = engine.world.try_component(entity, Name)
    return name.id if name is not None else f"entity {entity}"


def _jointed(engine: Engine, chassis: int) -> tuple[int, ...]:
    """The chassis and the bodies joints tie to it, directly or through each other."""
    links: dict[int, set[int]] = {}
    for _, joint in engine.world.get_component(Joint):
        if joint.body_a is not None and joint.body_b is not None:
            links.setdefault(joint.body_a, set()).add(joint.body_b)
            links.setdefault(joint.body_b, set()).add(joint.body_a)
    found, todo = {chassis}, [chassis]
    while todo:
        for other in links.get(todo.pop(), ()):
            if other not in found:
                found.add(other)
                todo.append(other)
    return tuple(sorted(found))


def _outputs(engine: Engine) -> Any:
    from systems.input import Outputs

    return engine.try_resource(Outputs)


class WheelchairPlugin:
    """Wheelchairs driven by wheel counters (``requestPlugin("wheelchair")``)."""

    name = PluginName.WHEELCHAIR

    def build(self, engine: Engine) -> None:
        from systems.input import InputPlugin

        engine.add_plugin(InputPlugin())  # the wheel counters
        engine.add_system(WheelchairSystem())
