"""The DynamicsBackend protocol: what the engine asks of a physics library.

Backends (``ode`` in 3D, ``pymunk`` in 2D) are picked by name through
:func:`engine.physics.create_backend`. Bodies and joints are addressed by an
integer *key* the caller chooses (the engine uses entity ids). State moves in
batches of numpy arrays so no Python runs per body per frame.

Threading: a backend is owned by exactly one thread at a time (the physics
thread in threaded mode). Nothing here is thread-safe; the engine's
:class:`engine.physics.driver.PhysicsDriver` serialises access.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, Protocol, runtime_checkable

import numpy as np

from components import Joint, Physical
from components.blocks import BlockDeclaration, BuildContext, Key, declare
from engine.physics.sleep import SLEEP_ANGULAR, SLEEP_LINEAR, SLEEP_TIME, SleepState

#: Half the side of the cube every body stays in (m), by default (``World { Extent }``).
#: ODE's hash space turns bounding boxes into integer cells and aborts the process on one
#: past integer range (about 4.5e15 m); a thousand kilometres is far beyond any scene
#: and keeps positions exact to a nanometre.
WORLD_EXTENT = 1e6
#: The largest World Extent (m): ODE's hash space needs every bounding box within about
#: 4.5e15 m, and past 1e12 m doubles no longer place a body to the millimetre.
MAX_EXTENT = 1e12
#: Speed (m/s) and spin (rad/s) past which a body counts as runaway: one step further
#: and its numbers overflow.
MAX_SPEED = 1e5
#: The heaviest body (kg) and densest material (kg/m³) any body may have: far above
#: anything real, and far below where the solver's products of masses overflow (ODE's
#: step fails on a 1e160 kg sphere resting on the ground; pymunk's overflow warns).
MAX_MASS = 1e12
MAX_DENSITY = 1e6


@dataclass(frozen=True, slots=True)
class Limits:
    """What every backend can take, shared through the protocol: values are checked
    against these once, where a command is made and pushed
    (:func:`engine.physics.commands.check_limits`), and a body that passes them while
    stepping (leaves the world, runs away) is stopped by its backend and reported."""

    extent: float = WORLD_EXTENT
    max_speed: float = MAX_SPEED

    def __post_init__(self) -> None:
        for name in ("extent", "max_speed"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"{name} must be a positive number, got {value!r}")


#: A principal moment of 0 means infinite (KHR_physics_rigid_bodies: the body never turns
#: about that axis). A backend takes it as this many times the largest finite moment (or
#: the mass, in kg m^2, when every moment is 0): its inverse is then 1e-6 of the others',
#: which no torque the solver meets makes a visible turn of, and the solver stays well
#: conditioned (a true 0 inverse is not what ODE's mass takes).
LOCKED_INERTIA_RATIO = 1e6


def locked_inertia(moments: tuple[float, ...] | np.ndarray, mass: float = 0.0) -> np.ndarray:
    """Principal moments with each 0 (infinite: a locked axis) made finite and very large
    (:data:`LOCKED_INERTIA_RATIO`)."""
    m = np.asarray(moments, dtype=np.float64).copy()
    if np.all(m > 0):
        return m
    scale = float(m.max()) if np.any(m > 0) else (mass if mass and mass > 0 else 1.0)
    m[m <= 0] = LOCKED_INERTIA_RATIO * scale
    return m


class BackendFailure(RuntimeError):
    """The backend's library failed inside a step and cannot step again (ODE's internal
    errors, see docs/ODE.md); the message says what it reported. The driver stops
    physics with one message and the rest of the run goes on."""


def metres(extent: float) -> str:
    """An extent as messages write it: ``±1e6 m`` (not ``±1e+06``)."""
    text = f"{extent:g}".replace("e+0", "e").replace("e+", "e")
    return f"±{text} m"


def fault_message(cause: str, extent: float = WORLD_EXTENT) -> str:
    """What a backend reports (``take_faults``) for a body it stopped after a step:
    ``cause`` is "nonfinite", "runaway" or "left" (the world of ``extent``)."""
    if cause == "left":
        return (f"it left the world ({metres(extent)}); stopped at its last pose inside, "
                "at rest, and disabled")
    what = "its state turned non-finite" if cause == "nonfinite" else \
        f"it became a runaway (faster than {MAX_SPEED:g} m/s or rad/s)"
    return f"{what}; put back at its last good pose, at rest, and disabled"


class BackendName(StrEnum):
    """The dynamics backends, by the name a scene (``World { Dynamics ... }``) or
    ``--backend`` picks them."""

    ODE = "ode"
    PYMUNK = "pymunk"
    BALLISTIC = "ballistic"


#: A kinematic target this close to its time (a share of the step) is reached in this
#: step: steps sum to a target's ``dt`` only to rounding (the ODE binding has its own).
ARRIVE_SLACK = 1e-6

#: One contact between two bodies in one step. ``b`` is -1 for the static world
#: (ground planes and static geometry without a key).
CONTACT_DTYPE = np.dtype(
    [
        ("a", np.int64),
        ("b", np.int64),
        ("position", np.float64, (3,)),
        ("normal", np.float64, (3,)),
        ("depth", np.float64),
        ("impulse", np.float64),
    ]
)


class BodyState:
    """Poses and velocities of many bodies, row ``i`` belonging to ``keys[i]``.

    One (N, 13) ``table`` of rows ``x y z  qw qx qy qz  vx vy vz  wx wy wz`` (m,
    quaternion, m/s, rad/s); ``position``, ``orientation``, ``linear_velocity`` and
    ``angular_velocity`` are its column views, made when first asked for. A pose
    table laid out the same way (``engine.world.PoseTable``) takes a state in one copy.
    """

    __slots__ = ("keys", "table", "_columns")

    def __init__(self, keys: np.ndarray, table: np.ndarray) -> None:
        self.keys = keys  # (N,) int64
        self.table = table  # (N, 13)
        self._columns: tuple[np.ndarray, ...] | None = None

    @staticmethod
    def from_arrays(keys: np.ndarray, position: np.ndarray, orientation: np.ndarray,
                    linear_velocity: np.ndarray, angular_velocity: np.ndarray) -> BodyState:
        """A state from its four parts, (N, 3), (N, 4), (N, 3) and (N, 3)."""
        keys = np.asarray(keys, np.int64)
        table = np.empty((len(keys), 13))
        table[:, 0:3] = position
        table[:, 3:7] = orientation
        table[:, 7:10] = linear_velocity
        table[:, 10:13] = angular_velocity
        return BodyState(keys, table)

    @staticmethod
    def empty() -> BodyState:
        return BodyState(np.zeros(0, np.int64), np.zeros((0, 13)))

    def columns(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(position, orientation, linear_velocity, angular_velocity), views of the table."""
        if self._columns is None:
            t = self.table
            self._columns = (t[:, 0:3], t[:, 3:7], t[:, 7:10], t[:, 10:13])
        return self._columns  # type: ignore[return-value]

    @property
    def position(self) -> np.ndarray:
        return self.columns()[0]

    @property
    def orientation(self) -> np.ndarray:
        """(N, 4) w, x, y, z."""
        return self.columns()[1]

    @property
    def linear_velocity(self) -> np.ndarray:
        return self.columns()[2]

    @property
    def angular_velocity(self) -> np.ndarray:
        return self.columns()[3]

    def freeze(self) -> BodyState:
        """Make it read-only (a published snapshot); views made later are read-only too."""
        self.keys.setflags(write=False)
        self.table.setflags(write=False)
        for column in self._columns or ():
            column.setflags(write=False)
        return self


@dataclass(frozen=True, slots=True)
class RayHit:
    key: int  # -1 for static world geometry
    position: tuple[float, float, float]
    normal: tuple[float, float, float]
    distance: float


@dataclass(slots=True)
class MaterialPair:
    """Contact parameters used when material ``a`` meets material ``b``."""

    a: str
    b: str
    friction: float | None = None
    bounce: float | None = None
    softness: float | None = None
    collide: bool = True


def _optional(value: Any) -> float | None:
    return None if value is None else float(value)


def build_material_pair(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``MaterialPair`` block: contact parameters the world's settings carry."""
    ctx.scene("material_pairs").append(MaterialPair(
        str(v["Material1"]), str(v["Material2"]), _optional(v["Friction"]),
        _optional(v["Bounce"]), _optional(v["Softness"]), bool(v["Collide"])))
    return []


MATERIAL_PAIR_BLOCK = declare(BlockDeclaration(
    "MaterialPair", inside=("Scene",), build=build_material_pair, entity=False,
    doc="contact parameters for two materials", keys=(
        Key("Material1", "ref", None, "one material", required=True, ref="Material",
            example='"rubber"'),
        Key("Material2", "ref", None, "the other material", required=True, ref="Material",
            example='"wood"'),
        Key("Friction", "float", None, "Coulomb coefficient for this pair", example="0.9"),
        Key("Bounce", "float", None, "restitution for this pair, 0..1", example="0.6"),
        Key("Softness", "float", None, "contact softness for this pair", example="0.001"),
        Key("Collide", "bool", 1, "0: the two materials pass through each other"),
    )))


@dataclass(slots=True)
class WorldSettings:
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    erp: float = 0.2
    cfm: float = 1e-5
    iterations: int = 20
    max_contacts: int = 4
    #: Share of a resting contact's normal force carried over to the next step (the
    #: solver's warm start; 0: off). See engine/physics/ode3d/stepper.h.
    warm_start: float = 0.9
    #: Contact softness: its constraint force mixing as a share of its own stiffness,
    #: the same for every mass and step (a bouncing contact is always rigid).
    contact_softness: float = 1e-3
    #: Islands held by joints alone with up to this many constraint rows are solved
    #: exactly (ODE's dWorldStep); 0: every island by the iterative solver.
    exact_rows: int = 60
    #: Islands with contacts are solved with at least this many iterations, the others
    #: with ``iterations`` (0: all with ``iterations``): hands pressing on things need
    #: more than the fingers of a hand in the air (systems/hands.py).
    contact_iterations: int = 0
    auto_sleep: bool = True
    #: The sleep rule's limits (see :mod:`engine.physics.sleep`): seconds quiet, m/s, rad/s.
    sleep_time: float = SLEEP_TIME
    sleep_linear: float = SLEEP_LINEAR
    sleep_angular: float = SLEEP_ANGULAR
    material_pairs: list[MaterialPair] = field(default_factory=list)
    #: The solver's random state to start from (a saved state restores it); None: fresh.
    solver_seed: int | None = None
    #: Half the side of the cube bodies stay in (m; see :data:`WORLD_EXTENT`).
    extent: float = WORLD_EXTENT

    @property
    def limits(self) -> Limits:
        return Limits(extent=self.extent)

    def problems(self) -> list[tuple[str, str]]:
        """(field, message) for each setting outside its range in :data:`WORLD_RANGES`:
        every backend refuses such settings, and the scene reports them at their key."""
        found = []
        for name, allowed in WORLD_RANGES.items():
            value = getattr(self, name)
            if value not in allowed:
                found.append((name, f"{name} must be {allowed.text()}, got {value:g}"))
        return found

    def check(self) -> None:
        """Raise ValueError naming every setting outside its range."""
        problems = self.problems()
        if problems:
            raise ValueError("; ".join(message for _, message in problems))


@dataclass(frozen=True, slots=True)
class Range:
    """The values one setting may take: from ``low`` to ``high`` (None: no bound), an end
    left out when ``open``; never NaN nor infinite."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    def __contains__(self, value: float) -> bool:
        v = float(value)
        if not math.isfinite(v):
            return False
        if self.low is not None and (v < self.low or (self.low_open and v == self.low)):
            return False
        return self.high is None or (v < self.high or (not self.high_open and v == self.high))

    def text(self) -> str:
        """The range in words: ``from 0 to 0.99``, ``at least 1``, ``more than 0``."""
        low = None if self.low is None else \
            f"{'more than' if self.low_open else 'at least'} {self.low:g}"
        high = None if self.high is None else \
            f"{'less than' if self.high_open else 'at most'} {self.high:g}"
        if low and high and not self.low_open and not self.high_open:
            return f"from {self.low:g} to {self.high:g}"
        return " and ".join(t for t in (low, high) if t) or "a number"


#: The one range of each bounded world setting (its one default is WorldSettings'); the
#: scene checks its World keys against these and every backend's configure refuses what
#: lies outside. Sleep limits are in the settings' units (s, m/s, rad/s).
WORLD_RANGES: dict[str, Range] = {
    "erp": Range(0.0, 1.0),
    "cfm": Range(0.0),
    "iterations": Range(1),
    "max_contacts": Range(1),
    "warm_start": Range(0.0, 0.99),
    "contact_softness": Range(0.0),
    "exact_rows": Range(0),
    "contact_iterations": Range(0),
    "sleep_time": Range(0.0, low_open=True),
    "sleep_linear": Range(0.0, low_open=True),
    "sleep_angular": Range(0.0, low_open=True),
    "extent": Range(0.0, MAX_EXTENT, low_open=True),
}


@runtime_checkable
class DynamicsBackend(Protocol):
    """What every dynamics backend implements. All vectors are world-frame, SI."""

    name: str

    # -- world -------------------------------------------------------------
    def configure(self, settings: WorldSettings) -> None: ...
    def step(self, dt: float) -> None:
        """Advance by ``dt`` seconds: collide, solve, integrate; record contacts."""

    def close(self) -> None: ...

    # -- bodies ------------------------------------------------------------
    def add_body(self, key: int, body: Physical, position: np.ndarray,
                 orientation: np.ndarray, linear_velocity: np.ndarray | None = None,
                 angular_velocity: np.ndarray | None = None) -> None: ...
    def remove_body(self, key: int) -> None: ...
    def body_count(self) -> int: ...
    def set_pose(self, key: int, position: np.ndarray, orientation: np.ndarray) -> None: ...
    def set_velocity(self, key: int, linear: np.ndarray, angular: np.ndarray) -> None: ...
    def set_kinematic_target(self, key: int, position: np.ndarray,
                             orientation: np.ndarray, dt: float) -> None:
        """Move a kinematic body so it reaches the target pose after ``dt`` of stepping
        (at least one step) and stops there, exactly at it and at rest, until the next
        target (or pose, or velocity) comes: however many steps a frame takes, it never
        overshoots. A dynamic body only gets the velocities that would carry it there."""

    def add_force(self, key: int, force: np.ndarray, point: np.ndarray | None = None) -> None: ...
    def add_torque(self, key: int, torque: np.ndarray) -> None: ...
    def add_impulse(self, key: int, impulse: np.ndarray,
                    point: np.ndarray | None = None) -> None: ...
    def set_sleeping(self, key: int, sleeping: bool) -> None:
        """Put a dynamic body to sleep (at zero velocity) or wake it."""

    def set_collision_enabled(self, key: int, enabled: bool) -> None:
        """While disabled the body collides with nothing (no contacts, no ray hits) but is
        still simulated: gravity, joints and forces move it (a virtual hand reaching
        through a table). Wakes the body."""

    def set_gravity_enabled(self, key: int, enabled: bool) -> None:
        """Whether world gravity acts on the body. Wakes the body."""

    # -- joints ------------------------------------------------------------
    def add_joint(self, key: int, joint: Joint) -> None: ...
    def remove_joint(self, key: int) -> None: ...
    def set_motor(self, key: int, velocity: float, max_force: float) -> None: ...
    def set_servos(self, keys: np.ndarray, table: np.ndarray) -> None:
        """Aim hinges' and universal joints' motors at moving angles, each step from the
        joint's angle then (:class:`~engine.physics.commands.SetServos`' rows)."""

    def joint_state(self, key: int) -> tuple[float, float]:
        """Position (angle or distance) and rate of a joint's first axis."""

    def joint_force(self, key: int) -> np.ndarray:
        """The force (N, world frame) the joint's constraint put on its body_a in the last
        step (a hand's grip breaks beyond its BreakForce). A backend may start measuring a
        joint when first asked: zero until a step has run since."""

    def set_joint_target(self, key: int, position: np.ndarray, orientation: np.ndarray,
                         max_force: float | None = None,
                         max_torque: float | None = None) -> None:
        """Move a ``six_dof`` joint's target pose (world frame; the virtual hand), and
        optionally its force (N) and torque (N·m) bounds."""

    def set_drive_limits(self, key: int, max_force: float, max_torque: float,
                         time_constant: float | None = None, max_speed: float | None = None,
                         max_spin: float | None = None) -> None:
        """Bound a ``six_dof`` joint's force (N) and torque (N·m), and set how it responds:
        the time constant (s) its pose error closes with (at least the step), and caps on
        the correcting speed (m/s) and spin (rad/s). None keeps what it has. With a
        ``body_b`` the target moves with that body, whose velocity is fed forward."""

    # -- batches -----------------------------------------------------------
    def read_state(self) -> BodyState:
        """Every body's pose and velocity, in fresh arrays (safe to publish)."""

    def read_state_into(self, out: np.ndarray) -> np.ndarray:
        """Write every body's state into the first N rows of ``out`` (C-contiguous
        float64, at least (N, 13), :class:`BodyState`'s row layout) and return the keys of
        those rows: the same read-only array until a body is added or removed, so a
        caller can plan its copy once per layout."""

    def write_state(self, state: BodyState) -> None: ...
    def contacts(self) -> np.ndarray:
        """Contacts of the last step as a CONTACT_DTYPE array."""

    # -- queries -----------------------------------------------------------
    def overlapping(self, key: int) -> list[int]:
        """Keys of the bodies (-1: static geometry) body ``key`` intersects now, whether its
        own collisions are on or off (a body that passed through things asks before it
        collides again), as collision categories and masks allow."""

    def raycast(self, origin: np.ndarray, direction: np.ndarray, max_distance: float,
                ignore: int | None = None, mask: int = 0xFFFFFFFF) -> RayHit | None:
        """Closest hit along the ray, skipping body ``ignore`` and categories not in ``mask``."""


@runtime_checkable
class SupportsExactState(Protocol):
    """Backends whose state read (:meth:`DynamicsBackend.read_state`) is a conversion that
    rounds (a centre of mass off the origin, orientations normalised on the way back in),
    and that can give instead the rows which, put back, restore their numbers to the bit:
    what a saved state writes, so its continuation is the uninterrupted run's."""

    def exact_state(self) -> BodyState: ...


@runtime_checkable
class SupportsFaults(Protocol):
    """Backends that detect bodies gone non-finite, running away or leaving the world
    (:class:`Limits`), stop them, and report them."""

    def take_faults(self) -> list[tuple[int, str]]: ...


@runtime_checkable
class SupportsSleepState(Protocol):
    """Backends that run the sleep rule (:mod:`engine.physics.sleep`) and can hand its
    counters over, so a saved state falls asleep exactly when the uninterrupted run would."""

    def sleep_states(self) -> dict[int, SleepState]:
        """Every body that is asleep or in a quiet stretch."""

    def set_sleep_state(self, key: int, state: SleepState) -> None:
        """Restore one body's state, after the saved state's bodies and joints are made:
        the wakes that making them caused are dropped (they are no wakes of the run the
        saved state continues)."""
