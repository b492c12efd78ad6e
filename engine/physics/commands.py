"""Physics commands: everything the engine asks of a dynamics backend, as data.

The main thread never calls a backend; it makes a command and queues it (see
:class:`engine.physics.driver.PhysicsDriver`), which applies it between two steps
with its one dispatch. A command is a frozen dataclass of plain values, so it

* is **checked when it is made**: a bad value (NaN, a zero axis, a joint on one body)
  raises :class:`CommandError` at the caller's line — a Lua call, a Python system — not
  later on the physics thread;
* **serialises** to a plain dict and back (:func:`to_dict`, :func:`from_dict`), so the
  command stream of a run can be logged, replayed into a fresh backend and sent to
  another process.

>>> c = SetPose(3, (0.0, 0.0, 1.0), (2.0, 0.0, 0.0, 0.0))
>>> c.orientation                                   # normalised when made
(1.0, 0.0, 0.0, 0.0)
>>> from_dict(to_dict(c)) == c
True
>>> ApplyForce(3, (float("nan"), 0.0, 0.0))
Traceback (most recent call last):
...
engine.physics.commands.CommandError: ApplyForce: force must be 3 finite numbers, got (nan, ...)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, ClassVar

import numpy as np

from components import Joint, MaterialProps, Physical, Shape
from components.joint import JointKind
from engine.physics.backend import MaterialPair, SleepState, WorldSettings

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]
_FLOAT = np.dtype(np.float64)


class CommandError(ValueError):
    """A command was made with a value no backend can take; the message says which."""


def _vector(command: str, what: str, value: Any, n: int) -> tuple[float, ...]:
    try:
        # an array of floats is already floats (the per-frame case: kept cheap)
        out = tuple(value.tolist()) if type(value) is np.ndarray and value.dtype == _FLOAT \
            else tuple(map(float, value))
    except (TypeError, ValueError):
        raise CommandError(f"{command}: {what} must be {n} numbers, got {value!r}") from None
    # a sum is finite exactly when every term is (short of overflowing: 1e308 * 2, far
    # outside any world, is refused too)
    if len(out) != n or not math.isfinite(sum(out)):
        raise CommandError(f"{command}: {what} must be {n} finite numbers, got {value!r}")
    return out


def _quaternion(command: str, value: Any) -> Quat:
    w, x, y, z = _vector(command, "orientation", value, 4)
    norm = math.hypot(w, x, y, z)
    if norm == 0.0:
        raise CommandError(f"{command}: orientation must be a non-zero quaternion w, x, y, z")
    return (w, x, y, z) if norm == 1.0 else (w / norm, x / norm, y / norm, z / norm)


def _scalar(command: str, what: str, value: Any, low: float = -math.inf) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise CommandError(f"{command}: {what} must be a number, got {value!r}") from None
    if not math.isfinite(out) or out < low:
        bound = "" if low == -math.inf else f" >= {low:g}"
        raise CommandError(f"{command}: {what} must be a finite number{bound}, got {value!r}")
    return out


def _key(command: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise CommandError(f"{command}: target must be an entity id, got {value!r}")
    return int(value)


class Command:
    """Base of every command: ``key`` names the body or joint (an entity id)."""

    __slots__ = ()
    key: int
    #: Whether the command names a joint (True) or a body (False) by ``key``.
    on_joint: ClassVar[bool] = False

    def _set(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)

    def _check_key(self) -> None:
        self._set("key", _key(type(self).__name__, self.key))


@dataclass(frozen=True, slots=True)
class AddBody(Command):
    """Create the body of entity ``key`` at a pose, moving at the given velocities."""

    key: int
    body: Physical
    position: Vec3 = (0.0, 0.0, 0.0)
    orientation: Quat = (1.0, 0.0, 0.0, 0.0)
    linear_velocity: Vec3 = (0.0, 0.0, 0.0)
    angular_velocity: Vec3 = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        self._check_key()
        name = "AddBody"
        if not isinstance(self.body, Physical):
            raise CommandError(f"{name}: body must be a Physical, got {type(self.body).__name__}")
        if self.body.mass is not None and not (self.body.mass > 0 and math.isfinite(
                self.body.mass)):
            raise CommandError(f"{name}: mass must be a positive number of kg, "
                               f"got {self.body.mass!r}")
        self._set("position", _vector(name, "position", self.position, 3))
        self._set("orientation", _quaternion(name, self.orientation))
        self._set("linear_velocity", _vector(name, "linear velocity", self.linear_velocity, 3))
        self._set("angular_velocity", _vector(name, "angular velocity",
                                              self.angular_velocity, 3))


@dataclass(frozen=True, slots=True)
class RemoveBody(Command):
    """Remove the body of entity ``key`` (and the joints on it)."""

    key: int

    def __post_init__(self) -> None:
        self._check_key()


@dataclass(frozen=True, slots=True)
class AddJoint(Command):
    """Create joint ``key`` between ``joint.body_a`` and ``joint.body_b`` (None: the world)."""

    key: int
    joint: Joint
    on_joint: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._check_key()
        j = self.joint
        name = f"AddJoint {j.id!r}" if j.id else "AddJoint"
        if not isinstance(j, Joint):
            raise CommandError(f"{name}: joint must be a Joint, got {type(j).__name__}")
        if j.kind not in JointKind.__members__.values():
            raise CommandError(f"{name}: unknown kind {j.kind!r} "
                               f"(one of {', '.join(JointKind)})")
        if j.body_b is not None and j.body_a == j.body_b:
            raise CommandError(f"{name}: a joint needs two different bodies, "
                               f"got body {j.body_a} twice")
        _vector(name, "anchor", j.anchor, 3)
        for what, axis in (("axis", j.axis), ("axis2", j.axis2)):
            if not any(_vector(name, what, axis, 3)) and j.kind not in _AXISLESS:
                raise CommandError(f"{name}: {what} must not be zero")


_AXISLESS = frozenset({JointKind.BALL, JointKind.FIXED, JointKind.SIX_DOF})


@dataclass(frozen=True, slots=True)
class RemoveJoint(Command):
    key: int
    on_joint: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._check_key()


@dataclass(frozen=True, slots=True)
class SetMotor(Command):
    """Drive joint ``key``'s motor at ``velocity`` (rad/s or m/s) with at most ``max_force``."""

    key: int
    velocity: float
    max_force: float
    on_joint: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._check_key()
        self._set("velocity", _scalar("SetMotor", "velocity", self.velocity))
        self._set("max_force", _scalar("SetMotor", "maxForce", self.max_force, 0.0))


@dataclass(frozen=True, slots=True)
class ApplyForce(Command):
    """A force (N) for the next step, at a world point (None: the centre of mass)."""

    key: int
    force: Vec3
    point: Vec3 | None = None

    def __post_init__(self) -> None:
        self._check_key()
        self._set("force", _vector("ApplyForce", "force", self.force, 3))
        if self.point is not None:
            self._set("point", _vector("ApplyForce", "point", self.point, 3))


@dataclass(frozen=True, slots=True)
class ApplyTorque(Command):
    key: int
    torque: Vec3

    def __post_init__(self) -> None:
        self._check_key()
        self._set("torque", _vector("ApplyTorque", "torque", self.torque, 3))


@dataclass(frozen=True, slots=True)
class ApplyImpulse(Command):
    """An impulse (N·s) delivered over the next step, at a world point (None: the centre)."""

    key: int
    impulse: Vec3
    point: Vec3 | None = None

    def __post_init__(self) -> None:
        self._check_key()
        self._set("impulse", _vector("ApplyImpulse", "impulse", self.impulse, 3))
        if self.point is not None:
            self._set("point", _vector("ApplyImpulse", "point", self.point, 3))


@dataclass(frozen=True, slots=True)
class SetPose(Command):
    """Teleport a body: its origin to ``position``, turned to ``orientation``; with
    velocities (m/s, rad/s), moving at those from there (a kinematic body carried along a
    tracked path in one command)."""

    key: int
    position: Vec3
    orientation: Quat
    linear: Vec3 | None = None
    angular: Vec3 | None = None

    def __post_init__(self) -> None:
        self._check_key()
        self._set("position", _vector("SetPose", "position", self.position, 3))
        self._set("orientation", _quaternion("SetPose", self.orientation))
        if (self.linear is None) != (self.angular is None):
            raise CommandError("SetPose: give both velocities or neither")
        if self.linear is not None:
            self._set("linear", _vector("SetPose", "linear velocity", self.linear, 3))
            self._set("angular", _vector("SetPose", "angular velocity", self.angular, 3))


@dataclass(frozen=True, slots=True)
class SetVelocity(Command):
    key: int
    linear: Vec3
    angular: Vec3

    def __post_init__(self) -> None:
        self._check_key()
        self._set("linear", _vector("SetVelocity", "linear velocity", self.linear, 3))
        self._set("angular", _vector("SetVelocity", "angular velocity", self.angular, 3))


@dataclass(frozen=True, slots=True)
class SetKinematicTarget(Command):
    """Move a kinematic body so it reaches the pose after ``dt`` seconds and stays there,
    at rest, however many steps follow before the next command."""

    key: int
    position: Vec3
    orientation: Quat
    dt: float

    def __post_init__(self) -> None:
        self._check_key()
        self._set("position", _vector("SetKinematicTarget", "position", self.position, 3))
        self._set("orientation", _quaternion("SetKinematicTarget", self.orientation))
        self._set("dt", _scalar("SetKinematicTarget", "dt", self.dt, 0.0))
        if self.dt == 0.0:
            raise CommandError("SetKinematicTarget: dt must be positive")


class _Switch(Command):
    """A command turning one thing of a body on or off: its one flag field, named by
    ``flag``, is taken as a bool."""

    __slots__ = ()
    flag: ClassVar[str]

    def __post_init__(self) -> None:
        self._check_key()
        self._set(self.flag, bool(getattr(self, self.flag)))


@dataclass(frozen=True, slots=True)
class SetCollisionEnabled(_Switch):
    """Let a body collide with the world or pass through everything (still simulated)."""

    flag: ClassVar[str] = "enabled"
    key: int
    enabled: bool


@dataclass(frozen=True, slots=True)
class SetGravityEnabled(_Switch):
    flag: ClassVar[str] = "enabled"
    key: int
    enabled: bool


@dataclass(frozen=True, slots=True)
class SetSleeping(_Switch):
    flag: ClassVar[str] = "sleeping"
    key: int
    sleeping: bool


@dataclass(frozen=True, slots=True)
class SetSleepState(Command):
    """Restore a body's standing with auto-sleep (a saved state's counters)."""

    key: int
    state: SleepState

    def __post_init__(self) -> None:
        self._check_key()


@dataclass(frozen=True, slots=True)
class SetJointTarget(Command):
    """Move a six_dof joint's target pose (and optionally its force and torque bounds)."""

    key: int
    position: Vec3
    orientation: Quat
    max_force: float | None = None
    max_torque: float | None = None
    on_joint: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._check_key()
        self._set("position", _vector("SetJointTarget", "position", self.position, 3))
        self._set("orientation", _quaternion("SetJointTarget", self.orientation))
        for name in ("max_force", "max_torque"):
            value = getattr(self, name)
            if value is not None:
                self._set(name, _scalar("SetJointTarget", name, value, 0.0))


@dataclass(frozen=True, slots=True)
class SetDriveLimits(Command):
    """Bound a six_dof joint's force (N) and torque (N·m), and set how it responds: the
    time constant (s) its error closes with, caps on the correcting speed (m/s) and spin
    (rad/s); None keeps what the joint has."""

    key: int
    max_force: float
    max_torque: float
    time_constant: float | None = None
    max_speed: float | None = None
    max_spin: float | None = None
    on_joint: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._check_key()
        self._set("max_force", _scalar("SetDriveLimits", "max_force", self.max_force, 0.0))
        self._set("max_torque", _scalar("SetDriveLimits", "max_torque", self.max_torque, 0.0))
        for name in ("time_constant", "max_speed", "max_spin"):
            value = getattr(self, name)
            if value is not None:
                self._set(name, _scalar("SetDriveLimits", name, value, 0.0))


@dataclass(frozen=True, slots=True)
class ConfigureWorld(Command):
    """The world's settings from the next step on (a plugin needing more solver
    iterations, a script turning gravity); the backend checks them as at the start. It
    names the world, not a body: ``key`` is -1."""

    settings: WorldSettings
    key: int = -1

    def __post_init__(self) -> None:
        if not isinstance(self.settings, WorldSettings):
            raise CommandError(f"ConfigureWorld: settings must be WorldSettings, got "
                               f"{type(self.settings).__name__}")
        if self.key != -1:
            raise CommandError("ConfigureWorld: names the world (key -1), not an entity")


@dataclass(frozen=True, slots=True)
class Step:
    """Not a request but a record: the backend stepped by ``dt`` (a command log's clock)."""

    dt: float


#: Every command type by name: the serialised form's ``"command"`` field.
COMMANDS: dict[str, type] = {cls.__name__: cls for cls in (
    AddBody, RemoveBody, AddJoint, RemoveJoint, SetMotor, ApplyForce, ApplyTorque,
    ApplyImpulse, SetPose, SetVelocity, SetKinematicTarget, SetCollisionEnabled,
    SetGravityEnabled, SetSleeping, SetSleepState, SetJointTarget, SetDriveLimits,
    ConfigureWorld, Step)}

#: Plain-data types a command may hold, by name (tagged in the serialised form).
_DATA: dict[str, type] = {cls.__name__: cls for cls in (
    Physical, Shape, MaterialProps, Joint, SleepState, WorldSettings, MaterialPair)}


# -- plain dicts ---------------------------------------------------------------------
def to_dict(command: Command | Step) -> dict[str, Any]:
    """A command as JSON-ready plain data (floats round-trip exactly through ``json``)."""
    return {"command": type(command).__name__, **{
        f.name: _encode(getattr(command, f.name)) for f in dataclasses.fields(command)}}


def from_dict(data: dict[str, Any]) -> Command | Step:
    """The command :func:`to_dict` made (checked again, as if made here)."""
    fields = dict(data)
    try:
        cls = COMMANDS[fields.pop("command")]
    except KeyError as exc:
        raise CommandError(f"not a physics command: {data!r}") from exc
    return cls(**{k: _decode(v) for k, v in fields.items()})


def _encode(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return {"ndarray": value.tolist(), "dtype": str(value.dtype)}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {"data": type(value).__name__, **{
            f.name: _encode(getattr(value, f.name)) for f in dataclasses.fields(value)}}
    if isinstance(value, list | tuple):
        return [_encode(v) for v in value]
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, float | int | str | bool) or value is None:
        return value
    raise CommandError(f"cannot serialise {type(value).__name__} {value!r}")


def _decode(value: Any, as_list: bool = False) -> Any:
    if isinstance(value, list):
        items = [_decode(v) for v in value]
        return items if as_list else tuple(items)
    if isinstance(value, dict):
        if "ndarray" in value:
            return np.array(value["ndarray"], dtype=value["dtype"])
        fields = dict(value)
        cls = _DATA[fields.pop("data")]
        lists = {f.name for f in dataclasses.fields(cls) if str(f.type).startswith("list[")}
        return cls(**{k: _decode(v, k in lists) for k, v in fields.items()})
    return value


@dataclass(slots=True)
class CommandLog:
    """What reached a backend, in order: commands and the steps between them.

    ``entries`` are plain dicts (:func:`to_dict`), so a log can be written as JSON lines,
    sent elsewhere, and :meth:`replay`-ed into a fresh backend to reproduce the run.
    """

    entries: list[dict[str, Any]] = field(default_factory=list)

    def record(self, command: Command | Step) -> None:
        self.entries.append(to_dict(command))

    def replay(self, apply: Any, step: Any) -> None:
        """Feed the log to ``apply(command)`` and ``step(dt)`` in the order recorded."""
        for entry in self.entries:
            command = from_dict(entry)
            if isinstance(command, Step):
                step(command.dt)
            else:
                apply(command)
