"""Controllers: continuous bindings from an input to an actuator, no script needed.

Paper section 3.5 ("Controllers – continuous response of the user's input").
Each frame a Controller's input is read, scaled by ``gain``, clamped to
``[low, high]``, stored in ``Controller.value`` and sent to its actuator.

Inputs (``Controller.input``):

- ``key:Up/Down`` +1 while the first key is held, -1 while the second is
  (both: 0); ``key:Space`` is 1 while held. Keys arrive as KeyEvents.
- ``axis:NAME`` the latest InputEvent value of device ``axis:NAME`` (a number).
- ``wheel:NAME`` the rate (counts per second) of the counter InputEvents of
  device ``wheel:NAME`` (a wheelchair's wheel encoder).
- ``tracker:NAME`` the position part of device ``tracker:NAME``'s pose values;
  only meaningful with a kinematic target.

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
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Controller, Joint, Name, Transform
from engine.events import InputEvent, KeyEvent
from engine.messages import MessageLog
from engine.physics.commands import (
    ApplyForce,
    Command,
    CommandError,
    SetKinematicTarget,
    SetMotor,
)
from engine.rotation import IDENTITY, local_axis
from engine.system import Phase, System

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.controllers")



@dataclass(eq=False, slots=True)
class _Binding:
    """A parsed Controller: where its input comes from and where its output goes."""

    input_kind: str
    input_args: tuple[str, ...]
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
        self._keys: set[str] = set()
        self._values: dict[str, Any] = {}
        self._wheels: dict[str, tuple[float, float]] = {}  # device -> (last count, counts/s)
        self._wheel_acc: dict[str, float] = {}
        self._bindings: dict[int, _Binding | None] = {}
        self._bad: set[int] = set()
        self._messages = MessageLog(log)

    def setup(self, engine: Engine) -> None:
        engine.events.subscribe(KeyEvent, self._on_key)
        engine.events.subscribe(InputEvent, self._on_input)
        engine.world.on_remove(Controller, lambda e, c: self._bindings.pop(e, None))

    def _on_key(self, event: KeyEvent) -> None:
        key = event.key.lower()  # bindings are written "key:Up/Down" or "key:up/down"
        if event.pressed:
            self._keys.add(key)
        else:
            self._keys.discard(key)

    def _on_input(self, event: InputEvent) -> None:
        device = event.device
        if device.startswith("wheel:"):
            self._wheel_acc[device] = float(event.value)
        self._values[device] = event.value

    # -- binding ---------------------------------------------------------------
    def _bind(self, engine: Engine, entity: int, c: Controller) -> _Binding | None:
        kind, _, rest = c.input.partition(":")
        if kind not in ("key", "axis", "wheel", "tracker") or not rest:
            return self._refuse(entity, c, f"unknown input {c.input!r} (use key:A/B, axis:N, "
                                           "wheel:NAME or tracker:NAME)")
        args = tuple(rest.lower().split("/")) if kind == "key" else (f"{kind}:{rest}",)
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
        binding = _Binding(kind, args, target_kind, found[0])
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
    def _read(self, b: _Binding, dt: float) -> Any:
        if b.input_kind == "key":
            keys = self._keys
            if len(b.input_args) == 1:
                return 1.0 if b.input_args[0] in keys else 0.0
            up, down = b.input_args[0], b.input_args[1]
            return float(up in keys) - float(down in keys)
        device = b.input_args[0]
        if b.input_kind == "wheel":
            count = self._wheel_acc.get(device)
            if count is None:
                return 0.0
            last, rate = self._wheels.get(device, (count, 0.0))
            if dt > 0:
                rate = (count - last) / dt
            self._wheels[device] = (count, rate)
            return rate
        value = self._values.get(device)
        if value is None:
            return None
        if b.input_kind == "tracker":
            return np.asarray(value, dtype=np.float64).reshape(-1)[:3]
        return float(value)

    def run(self, engine: Engine, dt: float) -> None:
        physics = engine.physics
        seen_wheels: set[str] = set()
        for entity, c in engine.world.get_component(Controller):
            if entity not in self._bindings:
                self._bindings[entity] = self._bind(engine, entity, c)
            b = self._bindings[entity]
            if b is None:
                continue
            if b.input_kind == "wheel" and b.input_args[0] in seen_wheels:
                raw = self._wheels.get(b.input_args[0], (0.0, 0.0))[1]
            else:
                raw = self._read(b, dt)
                if b.input_kind == "wheel":
                    seen_wheels.add(b.input_args[0])
            if raw is None:
                continue
            if isinstance(raw, np.ndarray):  # tracker position -> kinematic target
                target = np.clip(raw * c.gain, c.low, c.high)
                c.value = float(np.linalg.norm(target))
            else:
                c.value = float(min(max(raw * c.gain, c.low), c.high))
                target = None
            try:
                command = self._actuate(engine, b, c, target)
            except CommandError as exc:
                self._messages.warn(f"controller {c.input!r} -> {c.target!r}: {exc}; "
                                    "the value is not applied")
                continue
            if command is not None:
                physics.push(command)

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

    name = "controllers"

    def build(self, engine: Engine) -> None:
        engine.add_system(ControllerSystem())
