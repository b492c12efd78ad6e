"""Physics commands: everything the engine asks of a dynamics backend, as data.

The main thread never calls a backend; it makes a command and queues it (see
:class:`engine.physics.driver.PhysicsDriver`), which applies it between two steps
with its one dispatch. A command is a frozen dataclass of plain values, so it

* is **checked when it is made**: a bad value (NaN, a zero axis, a joint on one body, a
  size or mass not positive) raises :class:`CommandError` at the caller's line — a Lua
  call, a Python system — not later on the physics thread; what depends on the world it
  goes to (a position outside its extent, a speed past its limit:
  :class:`~engine.physics.backend.Limits`) is checked by :func:`check_limits` when it is
  pushed, in the same call;
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
>>> check_limits(SetPose(3, (1e30, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)), Limits())
Traceback (most recent call last):
...
engine.physics.commands.CommandError: SetPose: x = 1e+30 is outside the world (±1e6 m)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, ClassVar

import numpy as np

from components import Joint, MaterialProps, Physical, Shape
from components.joint import (  # noqa: F401  (HINGE2_BODIES: the scripting API's too)
    AXISLESS_KINDS,
    HINGE2_BODIES,
    SPRING_KINDS,
    TWO_AXES,
    JointKind,
    Spring,
    parallel,
)
from engine.physics.backend import (
    MAX_DENSITY,
    MAX_MASS,
    Limits,
    MaterialPair,
    SleepState,
    WorldSettings,
    metres,
)
from engine.rotation import UNIT_ROUNDING

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]
_FLOAT = np.dtype(np.float64)
_IDENTITY = (1.0, 0.0, 0.0, 0.0)


class CommandError(ValueError):
    """A command was made with a value no backend can take; the message says which."""


def _number(value: Any) -> float:
    """A number, never a boolean (``float(True)`` is 1.0: a mistake, not a value)."""
    if isinstance(value, bool | np.bool_):
        raise TypeError("a boolean is not a number")
    return float(value)


def _vector(command: str, what: str, value: Any, n: int) -> tuple[float, ...]:
    try:
        # floats are floats already (the per-frame and scene-loading cases: kept cheap)
        if type(value) is tuple and all(type(x) is float for x in value):
            out = value
        elif type(value) is np.ndarray and value.dtype == _FLOAT:
            out = tuple(value.tolist())
        else:
            out = tuple(map(_number, value))
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
    return (w, x, y, z) if abs(norm - 1.0) <= UNIT_ROUNDING else (w / norm, x / norm,
                                                                  y / norm, z / norm)


def _scalar(command: str, what: str, value: Any, low: float = -math.inf) -> float:
    if type(value) is float and value >= low and math.isfinite(value):  # the common case
        return value
    try:
        out = _number(value)
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
    #: Fields holding world points, checked against the world's extent when pushed.
    points: ClassVar[tuple[str, ...]] = ()
    #: Fields holding velocities (m/s or rad/s), checked against the speed limit.
    speeds: ClassVar[tuple[str, ...]] = ()

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
    points: ClassVar[tuple[str, ...]] = ("position",)
    speeds: ClassVar[tuple[str, ...]] = ("linear_velocity", "angular_velocity")

    def __post_init__(self) -> None:
        self._check_key()
        name = "AddBody"
        if not isinstance(self.body, Physical):
            raise CommandError(f"{name}: body must be a Physical, got {type(self.body).__name__}")
        if self.body.mass is not None and not (
                0 < _scalar(name, "mass", self.body.mass) <= MAX_MASS):
            raise CommandError(f"{name}: mass must be a positive number of kg up to "
                               f"{MAX_MASS:g}, got {self.body.mass!r}")
        _check_material(name, self.body.material)
        for shape in self.body.shapes:
            _check_shape(name, shape)
        _check_mass_frame(name, self.body)
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
            raise CommandError(f"{name}: a joint needs two different bodies, got one body "
                               "twice")
        _vector(name, "anchor", j.anchor, 3)
        for what in ("low", "high"):
            if getattr(j, what) is not None:
                _scalar(name, what, getattr(j, what))
        _scalar(name, "motor velocity", j.motor_velocity)
        _scalar(name, "motor max force", j.motor_max_force, 0.0)
        if j.spring is not None:
            _check_spring(name, j)
        for what, axis in (("axis", j.axis), ("axis2", j.axis2)):
            if not any(_vector(name, what, axis, 3)) and j.kind not in AXISLESS_KINDS:
                raise CommandError(f"{name}: {what} must not be zero")
        if j.kind in TWO_AXES and parallel(j.axis, j.axis2):
            raise CommandError(f"{name}: axis and axis2 must not be parallel: a {j.kind} "
                               "joint turns about two different axes")
        if j.kind == JointKind.HINGE2 and j.body_b is None:
            raise CommandError(f"{name}: {HINGE2_BODIES}")
        for pose in j.reference or ():
            if pose is not None:
                _vector(name, "reference pose", pose, 7)


def _check_material(command: str, material: MaterialProps) -> None:
    """A body's material: friction, bounce and softness finite and not negative (ODE's
    contact solver takes them as they are), density positive up to MAX_DENSITY (ODE's
    mass setters abort on one not positive)."""
    if not isinstance(material, MaterialProps):
        raise CommandError(f"{command}: material must be MaterialProps, got "
                           f"{type(material).__name__}")
    for what in ("friction", "bounce", "bounce_velocity", "softness"):
        _scalar(command, f"material {what}", getattr(material, what), 0.0)
    if not (0 < _scalar(command, "material density", material.density) <= MAX_DENSITY):
        raise CommandError(f"{command}: material density must be a positive number of "
                           f"kg/m³ up to {MAX_DENSITY:g}, got {material.density!r}")


def _check_spring(command: str, joint: Joint) -> None:
    """A spring on a joint with one free axis, its stiffness and damping finite, not
    negative and not both 0 (ODE's soft row divides by them), its force bound positive."""
    sp = joint.spring
    if not isinstance(sp, Spring):
        raise CommandError(f"{command}: spring must be a Spring, got {type(sp).__name__}")
    if joint.kind not in SPRING_KINDS:
        raise CommandError(f"{command}: a {joint.kind} joint takes no spring (only "
                           f"{', '.join(sorted(SPRING_KINDS))})")
    stiffness = _scalar(command, "spring stiffness", sp.stiffness, 0.0)
    damping = _scalar(command, "spring damping", sp.damping, 0.0)
    if stiffness == 0.0 and damping == 0.0:
        raise CommandError(f"{command}: a spring needs a stiffness or a damping above 0")
    _scalar(command, "spring target", sp.target)
    if not (isinstance(sp.max_force, int | float) and sp.max_force > 0):
        raise CommandError(f"{command}: spring max force must be above 0, got "
                           f"{sp.max_force!r}")


def _check_mass_frame(command: str, body: Physical) -> None:
    """A given centre of mass finite, principal moments 0 or more (0: infinite, made a
    large finite moment by the backend: ODE aborts the process on an inertia that is not
    positive definite), their axes' turn a quaternion."""
    if body.center_of_mass is not None:
        _vector(command, "centre of mass", body.center_of_mass, 3)
    if body.inertia is not None:
        moments = _vector(command, "inertia", body.inertia, 3)
        if not min(moments) >= 0:
            raise CommandError(f"{command}: inertia must be 3 moments of 0 or more (kg m^2; "
                               f"0: infinite), got {body.inertia!r}")
    if body.inertia_rotation != _IDENTITY:
        _quaternion(command, body.inertia_rotation)
    factor = body.gravity_factor
    if factor != 1.0 and not (isinstance(factor, (int, float)) and math.isfinite(factor)):
        raise CommandError(f"{command}: gravity factor must be a finite number, got {factor!r}")


def _check_shape(command: str, shape: Shape) -> None:
    """A shape's sizes finite, none negative and not all zero (ODE aborts the process on a
    negative one); a plane's normal and offset finite."""
    if not isinstance(shape, Shape):
        raise CommandError(f"{command}: shapes must be Shape, got {type(shape).__name__}")
    if shape.kind == "plane":
        _vector(command, "plane", shape.size, 4)
        return
    if shape.kind in ("mesh", "hull"):
        v = shape.vertices
        if v is None or not np.isfinite(v).all():
            raise CommandError(f"{command}: a {shape.kind} shape needs finite vertices")
    else:
        size = _vector(command, f"{shape.kind} size", shape.size, len(shape.size))
        if not size or min(size) < 0 or max(size) == 0:
            raise CommandError(f"{command}: {shape.kind} size must be positive, "
                               f"got {shape.size!r}")
    _vector(command, "shape offset", shape.offset, 3)


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


def keyed_table(command: str, keys: Any, table: Any, width: int, kind: str
                ) -> tuple[np.ndarray, np.ndarray]:
    """A batch command's ``keys`` and ``table`` as arrays, a row of ``width`` numbers per
    key; a CommandError names the command and what is wrong."""
    try:
        ids = np.array(keys, dtype=np.int64, ndmin=1)
        rows = np.array(table, dtype=np.float64, ndmin=2)
    except (TypeError, ValueError):
        raise CommandError(f"{command}: keys must be {kind} ids and table rows of {width} "
                           "numbers") from None
    if ids.ndim != 1 or rows.shape != (len(ids), width):
        raise CommandError(f"{command}: {len(ids)} keys need a table of shape "
                           f"({len(ids)}, {width}), got {rows.shape}")
    return ids, rows


@dataclass(frozen=True, slots=True, eq=False)
class SetServos(Command):
    """Aim hinges' and universal joints' own motors at moving angles, in one command (a
    fingered hand's fifteen joints, every frame): row ``i`` of ``table`` is joint
    ``keys[i]``'s target angles (rad, as the joint counts them: 0 where it was made; a
    hinge's second unused), their rates (rad/s, fed forward), its torque bound (N·m), the
    time constant its error closes with (s) and the cap on the correcting spin (rad/s).
    The backend aims each motor every step from the joint's angle then; ``key`` is the
    first joint's, for messages about the whole command."""

    keys: np.ndarray
    table: np.ndarray
    on_joint: ClassVar[bool] = True

    def __post_init__(self) -> None:
        keys, table = keyed_table("SetServos", self.keys, self.table, 7, "joint")
        if not (np.isfinite(table).all() and (table[:, 4:] >= 0.0).all()):  # which row:
            bad = ~np.isfinite(table).all(axis=1) | ~(table[:, 4:] >= 0.0).all(axis=1)
            raise CommandError(f"SetServos: joint {keys[bad][0]}'s row must be 7 finite "
                               "numbers, its torque bound, time constant and spin cap >= 0; "
                               f"got {table[bad][0].tolist()}")
        self._set("keys", keys)
        self._set("table", table)

    @property
    def key(self) -> int:  # type: ignore[override]
        return int(self.keys[0]) if len(self.keys) else -1


@dataclass(frozen=True, slots=True)
class ApplyForce(Command):
    """A force (N) for the next step, at a world point (None: the centre of mass)."""

    key: int
    force: Vec3
    point: Vec3 | None = None
    points: ClassVar[tuple[str, ...]] = ("point",)

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
    points: ClassVar[tuple[str, ...]] = ("point",)

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
    points: ClassVar[tuple[str, ...]] = ("position",)
    speeds: ClassVar[tuple[str, ...]] = ("linear", "angular")

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
    speeds: ClassVar[tuple[str, ...]] = ("linear", "angular")

    def __post_init__(self) -> None:
        self._check_key()
        self._set("linear", _vector("SetVelocity", "linear velocity", self.linear, 3))
        self._set("angular", _vector("SetVelocity", "angular velocity", self.angular, 3))


@dataclass(frozen=True, slots=True, eq=False)
class SetPoses(Command):
    """Teleport several bodies in one command, each moving on at its velocities: row ``i``
    of ``table`` (BodyState's layout: x y z, qw qx qy qz, vx vy vz, wx wy wz) is body
    ``keys[i]``'s. Checked in one pass over the rows (every hand's control body, each
    frame, costs one command, not one per body); ``key`` is the first body's, for
    messages about the whole command."""

    keys: np.ndarray
    table: np.ndarray

    def __post_init__(self) -> None:
        keys, table = keyed_table("SetPoses", self.keys, self.table, 13, "entity")
        if not np.isfinite(table).all():  # which row:
            bad = ~np.isfinite(table).all(axis=1)
            raise CommandError(f"SetPoses: body {keys[bad][0]}'s row is not 13 finite "
                               f"numbers: {table[bad][0].tolist()}")
        norm = np.sqrt(np.einsum("ij,ij->i", table[:, 3:7], table[:, 3:7]))
        if (norm == 0.0).any():
            raise CommandError(f"SetPoses: body {keys[norm == 0.0][0]}'s orientation must "
                               "be a non-zero quaternion w, x, y, z")
        if np.abs(norm - 1.0).max(initial=0.0) > UNIT_ROUNDING:  # unit to rounding: as it is
            off = np.abs(norm - 1.0) > UNIT_ROUNDING
            table[off, 3:7] /= norm[off, None]
        self._set("keys", keys)
        self._set("table", table)

    @property
    def key(self) -> int:  # type: ignore[override]
        return int(self.keys[0]) if len(self.keys) else -1


@dataclass(frozen=True, slots=True)
class SetKinematicTarget(Command):
    """Move a kinematic body so it reaches the pose after ``dt`` seconds and stays there,
    at rest, however many steps follow before the next command."""

    key: int
    position: Vec3
    orientation: Quat
    dt: float
    points: ClassVar[tuple[str, ...]] = ("position",)

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
    points: ClassVar[tuple[str, ...]] = ("position",)

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


# -- the world's limits ---------------------------------------------------------------
_AXES = "xyz"
_SPEED_WORDS = {"linear_velocity": "linear velocity", "angular_velocity": "angular velocity",
                "linear": "linear velocity", "angular": "angular velocity"}


def _inside(command: str, what: str, point: tuple[float, ...], extent: float) -> None:
    for axis, value in zip(_AXES, point, strict=False):
        if abs(value) > extent:
            name = axis if what == "position" else f"{what} {axis}"
            raise CommandError(f"{command}: {name} = {value:g} is outside the world "
                               f"({metres(extent)})")


def check_limits(command: Command, limits: Limits) -> None:
    """Refuse a command whose points leave the world or whose velocities pass the speed
    limit (``limits``: the world it goes to). Raises :class:`CommandError`, with the
    same ``Command: what`` form as the checks made when a command is made."""
    name = type(command).__name__
    extent = limits.extent
    for field_name in command.points:
        point = getattr(command, field_name)
        if point is not None:
            _inside(name, field_name, point, extent)
    for field_name in command.speeds:
        velocity = getattr(command, field_name)
        speed = 0.0 if velocity is None else math.hypot(*velocity)
        if speed > limits.max_speed:
            unit = "rad/s" if "angular" in field_name else "m/s"
            raise CommandError(f"{name}: {_SPEED_WORDS[field_name]} {speed:g} {unit} is over "
                               f"the limit of {limits.max_speed:g} {unit}")
    if isinstance(command, SetPoses):
        _rows_inside(command, limits)
    if isinstance(command, SetServos) and len(command.keys) and \
            np.abs(command.table[:, 2:4]).max() > limits.max_speed:
        fast = np.abs(command.table[:, 2:4]).max(axis=1) > limits.max_speed
        if fast.any():
            row = int(np.flatnonzero(fast)[0])
            raise CommandError(f"SetServos: joint {command.keys[row]}: rate "
                               f"{np.abs(command.table[row, 2:4]).max():g} rad/s is over "
                               f"the limit of {limits.max_speed:g} rad/s")
    if isinstance(command, SetMotor) and abs(command.velocity) > limits.max_speed:
        raise CommandError(f"{name}: velocity {command.velocity:g} is over the limit of "
                           f"{limits.max_speed:g} (rad/s or m/s)")
    if isinstance(command, AddBody):
        _body_inside(name, command.body, extent)
    elif isinstance(command, AddJoint):
        _inside(name, "anchor", command.joint.anchor, extent)
        if abs(command.joint.motor_velocity) > limits.max_speed:
            raise CommandError(f"{name}: motor velocity {command.joint.motor_velocity:g} is "
                               f"over the limit of {limits.max_speed:g} (rad/s or m/s)")
        for pose in command.joint.reference or ():
            if pose is not None:
                _inside(name, "reference pose", pose[:3], extent)


def _rows_inside(command: SetPoses, limits: Limits) -> None:
    """:func:`check_limits` for every row of a :class:`SetPoses` at once: positions in
    the world, speeds under the limit (the first row that is not is told, by its body)."""
    table = command.table
    if not len(table) or (np.abs(table[:, 0:3]).max() <= limits.extent and
                          np.abs(table[:, 7:13]).max() * math.sqrt(3.0) <= limits.max_speed):
        return  # (no component past the limit over √3: no speed past it)
    out = (np.abs(table[:, 0:3]) > limits.extent).any(axis=1)
    if out.any():
        row = int(np.flatnonzero(out)[0])
        _inside(f"SetPoses: body {command.keys[row]}", "position",
                tuple(table[row, 0:3].tolist()), limits.extent)
    for what, columns, unit in (("linear", slice(7, 10), "m/s"),
                                ("angular", slice(10, 13), "rad/s")):
        speed = np.sqrt(np.einsum("ij,ij->i", table[:, columns], table[:, columns]))
        fast = speed > limits.max_speed
        if fast.any():
            row = int(np.flatnonzero(fast)[0])
            raise CommandError(f"SetPoses: body {command.keys[row]}: {_SPEED_WORDS[what]} "
                               f"{speed[row]:g} {unit} is over the limit of "
                               f"{limits.max_speed:g} {unit}")


def _body_inside(name: str, body: Physical, extent: float) -> None:
    """A body's shapes no larger than the world (ODE's bounding boxes must stay in range)."""
    for shape in body.shapes:
        if shape.kind == "plane":
            if abs(shape.size[3]) > extent:
                raise CommandError(f"{name}: the plane lies {shape.size[3]:g} m from the "
                                   f"origin, outside the world ({metres(extent)})")
            continue
        _inside(name, "shape offset", shape.offset, extent)
        if shape.vertices is not None and len(shape.vertices):
            reach = float(np.abs(shape.vertices).max())
            if reach > extent:
                raise CommandError(f"{name}: a {shape.kind} vertex lies {reach:g} m out, "
                                   f"larger than the world ({metres(extent)})")
        elif shape.size and max(shape.size) > extent:
            raise CommandError(f"{name}: {shape.kind} size {max(shape.size):g} m is larger "
                               f"than the world ({metres(extent)})")


#: Every command type by name: the serialised form's ``"command"`` field.
COMMANDS: dict[str, type] = {cls.__name__: cls for cls in (
    AddBody, RemoveBody, AddJoint, RemoveJoint, SetMotor, SetServos, ApplyForce, ApplyTorque,
    ApplyImpulse, SetPose, SetPoses, SetVelocity, SetKinematicTarget, SetCollisionEnabled,
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
