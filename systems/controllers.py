"""Controllers: continuous bindings from an input to an actuator, no script needed.

Paper section 3.5 ("Controllers – continuous response of the user's input").
Each frame a Controller's input is read, scaled by ``gain``, clamped to
``[low, high]``, stored in ``Controller.value`` and sent to its actuator.

Inputs (``Controller.input``) are read from the input layer's latest-state table
(:class:`services.input.InputState`), so any device — a key, OSC, LSL, a serial
encoder, a recording — drives a controller the same way:

- ``key:Up/Down`` +1 while the first key is held, -1 while the second is
  (both: 0); ``key:Space`` is 1 while held.
- ``axis:DEVICE/NAME`` an axis's latest value.
- ``button:DEVICE/NAME`` (or ``button:ID`` of an ``Input { Button }``) 1 while held.
- ``wheel:NAME`` the wheel's angular velocity (rad/s) from its counts and the device
  timestamps (``Input { Wheel { CountsPerTurn } }``), not from frame counts.
- ``tracker:NAME`` the tracker's calibrated position; only meaningful with a
  kinematic target. An untracked (lost) tracker holds its target still.

Targets (``Controller.target``):

- ``motor:JOINT`` the joint motor's target velocity (the joint's own
  ``motor_max_force`` is kept), sent when the value changes.
- ``force:OBJECT`` a force (N) along the object's own forward axis (its local
  +X, turned with the body), applied for the next physics step every frame.
- ``kinematic:OBJECT`` a kinematic target: for a tracker the tracked position
  times the gain (clamped per component); for a scalar input the object's start
  position moved by the value along its start forward axis (local +X).

Every actuation is a physics command, so controllers work in serial and threaded
mode. The system runs in PRE_PHYSICS: input read in this frame's INPUT phase acts
in this frame's physics step (new bodies are queued when they are spawned, so a
controller's command always follows its body's creation). A controller naming an
unknown input kind, joint or object is reported once and then ignored.
The input plugin is loaded with this one.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from components import Controller, Joint, Name, Transform
from engine.messages import MessageLog
from engine.physics.commands import (
    ApplyForce,
    Command,
    CommandError,
    SetKinematicTarget,
    SetMotor,
)
from engine.rotation import IDENTITY, local_axis
from engine.system import Phase, PluginName, System
from services.input import Binding, InputState, parse_binding

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.controllers")



@dataclass(eq=False, slots=True)
class _Binding:
    """A parsed Controller: where its input comes from and where its output goes."""

    source: Binding
    target_kind: str
    target: int
    direction: np.ndarray | None = None
    origin: np.ndarray | None = None
    sent: float | None = None


class ControllerSystem(System):
    phase = Phase.PRE_PHYSICS
    reads = (Controller, Joint, Name, Transform)
    writes = (Controller, Joint)

    def __init__(self) -> None:
        self._bindings: dict[int, _Binding | None] = {}
        self._bad: set[int] = set()
        self._messages = MessageLog(log)

    def setup(self, engine: Engine) -> None:
        engine.world.on_remove(Controller, lambda e, c: self._bindings.pop(e, None))

    # -- binding ---------------------------------------------------------------
    def _bind(self, engine: Engine, entity: int, c: Controller) -> _Binding | None:
        try:
            source = parse_binding(c.input)
        except ValueError as exc:
            return self._refuse(entity, c, str(exc))
        target_kind, _, name = c.target.partition(":")
        if target_kind not in ("motor", "force", "kinematic") or not name:
            return self._refuse(entity, c, f"unknown target {c.target!r} (use motor:JOINT, "
                                           "force:OBJECT or kinematic:OBJECT)")
        found = [e for e, n in engine.world.get_component(Name) if n.id == name]
        if target_kind == "motor":
            found = [e for e in found if engine.world.has_component(e, Joint)]
            if not found:
                found = [e for e, j in engine.world.get_component(Joint) if j.id == name]
        if not found:
            return self._refuse(entity, c, f"no {'joint' if target_kind == 'motor' else 'object'}"
                                           f" {name!r} for target {c.target!r}")
        binding = _Binding(source, target_kind, found[0])
        if target_kind == "kinematic":
            t = engine.world.try_component(found[0], Transform)
            binding.origin = np.zeros(3) if t is None else t.position.copy()
            binding.direction = np.array([1.0, 0.0, 0.0]) if t is None else \
                local_axis(t.orientation, 0)
        return binding

    def _refuse(self, entity: int, c: Controller, message: str) -> None:
        if entity not in self._bad:
            self._bad.add(entity)
            log.error("controller %s: %s; it is ignored", entity, message)
        return None

    # -- per frame ---------------------------------------------------------------
    def run(self, engine: Engine, dt: float) -> None:
        physics = engine.physics
        inputs = engine.resource(InputState)
        for entity, c in engine.world.get_component(Controller):
            if entity not in self._bindings:
                self._bindings[entity] = self._bind(engine, entity, c)
            b = self._bindings[entity]
            if b is None:
                continue
            raw = inputs.read(b.source)
            if raw is None:
                continue
            if isinstance(raw, np.ndarray):  # tracker position -> kinematic target
                target = np.clip(raw * c.gain, c.low, c.high)
                c.value = float(np.linalg.norm(target))
            else:
                c.value = float(min(max(raw * c.gain, c.low), c.high))
                target = None
            try:  # made and pushed: the world's limits are checked when it is pushed
                command = self._actuate(engine, b, c, target)
                if command is not None:
                    physics.push(command)
            except CommandError as exc:
                self._messages.warn(f"controller {c.input!r} -> {c.target!r}: {exc}; "
                                    "the value is not applied")

    def _actuate(self, engine: Engine, b: _Binding, c: Controller,
                 target: np.ndarray | None) -> Command | None:
        """The command that sends ``c.value`` (or a tracked ``target``) to the actuator."""
        key = b.target
        if b.target_kind == "motor":
            joint = engine.world.try_component(key, Joint)
            if c.value == b.sent or joint is None:
                return None
            b.sent = c.value
            joint.motor_velocity = c.value
            return SetMotor(key, c.value, joint.motor_max_force)
        t = engine.world.try_component(key, Transform)
        if b.target_kind == "force":
            if c.value == 0.0 or t is None:
                return None
            return ApplyForce(key, local_axis(t.orientation, 0) * c.value)
        if target is None:
            assert b.origin is not None and b.direction is not None
            target = b.origin + b.direction * c.value
        orientation = IDENTITY if t is None else t.orientation
        return SetKinematicTarget(key, target, orientation, engine.config.dt)


class ControllersPlugin:
    """Drives actuators from Controller components (``requestPlugin("controllers")``)."""

    name = PluginName.CONTROLLERS

    def build(self, engine: Engine) -> None:
        from systems.input import InputPlugin

        engine.add_plugin(InputPlugin())  # what controllers read; built once if already in
        engine.add_system(ControllerSystem())
