"""PymunkBackend: the DynamicsBackend protocol over pymunk, in the world's X–Z plane.

See :mod:`engine.physics.pymunk2d.planar` for the axis mapping, ``shapes`` for how
3D shapes and masses become 2D, ``joints`` for the constraints. Materials combine as
in the ODE backend: friction is the geometric mean of the two materials' (each
shape carries √μ and pymunk multiplies them), bounce the larger of the two (a
pre-solve callback, registered only for materials that bounce); a
:class:`MaterialPair` in the settings overrides both for that pair, or makes the
pair pass through each other (``collide=False``). Softness has no pymunk
counterpart and is ignored (reported once); pymunk bounces at any impact speed, so
``bounce_velocity`` is ignored too.

Sleeping is :mod:`engine.physics.sleep`'s rule, as under ODE. chipmunk's own sleeping
stays on with a timer that never runs out (:data:`NEVER`), so chipmunk keeps its islands
and wakes a sleeping group that an awake body touches, but only the rule puts bodies to
sleep: each island as one chipmunk group, so they wake together (a step in which no body
sleeps is taken with the timer off, :data:`QUIET`: chipmunk's islands would do nothing
then). The rule reads the state through ``batch`` (compiled passes over chipmunk), which
also tells who sleeps.

A step longer than MAX_SUBSTEP (0.01 s) is taken as equal substeps of at most that, each
as below (chipmunk's solver leaves a stack rocking at 1/60 s and 0.02 s; docs/PHYSICS.md).

Cost: a step (a substep) is the space's own step plus a few compiled passes that read
and write chipmunk directly (the functions pymunk's cffi library exports, those
``pymunk.batch`` calls, and the arbiter fields it declares: ``_rows``' ``_chipmunk.pxi``),
no Python per body: before it, the preloaded rows' forces read and written
(``_rows.Resting.preload``); after it, one pass (``_rows.Resting.after``) that reads the
bodies (the read the sleep rule and a state read right after the step take too; any
public method that may change the space drops it first) and the step's arbiters, once,
and writes the velocities of the rows it holds still (into an awake body straight, as
the preload its forces: chipmunk's setters walk the body's arbiters to reset idle times
that decide nothing here); then the sleep rule (``sleep.h``'s pass; islands, when some
body is ready, by a union-find over the same arbiters and the joints). A substep before
a step's last hands its arbiter read over (no copy): its contacts are made only when
:meth:`contacts` asks (or before anything changes the space). Against bare pymunk taking
the same substeps (``python -m app.bench.physics2d``, docs/PHYSICS.md): 1.16 to 1.18 of
its time at 100 to 2,000 boxes (1.17 to 1.21 with the sleep rule on), 1.08 to 1.11 of its
instructions (1.10 to 1.14), where the arbiter read is 2.5 % of chipmunk's step's
instructions and more of its time (the arbiters, their contacts and bodies, after a step
whose cache holds little of them).

Whatever the plane cannot represent is reported once per object on the logger
``colosseum.physics.pymunk`` with the approximation used, never raised. Bad calls
(unknown keys, unknown body or joint kinds) raise KeyError or ValueError naming them.
"""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from types import FunctionType
from typing import Any

import numpy as np
import pymunk

from components import Joint, MaterialProps, Physical, Shape
from components.joint import JointKind
from components.physical import BodyKind
from engine.physics.backend import (
    ARRIVE_SLACK,
    CONTACT_DTYPE,
    MAX_SPEED,
    WORLD_EXTENT,
    BackendName,
    BodyState,
    MaterialPair,
    RayHit,
    WorldSettings,
    fault_message,
    locked_inertia,
)
from engine.physics.pymunk2d import _rows
from engine.physics.pymunk2d.batch import SpaceReader
from engine.physics.pymunk2d.joints import JointRecord, build_joint
from engine.physics.pymunk2d.planar import split_orientation
from engine.physics.pymunk2d.resting import RestingSupport, carried_down
from engine.physics.pymunk2d.shapes import BuiltShape, build_shape
from engine.physics.sleep import SleepRule, SleepState
from engine.rotation import quat_to_matrix

log = logging.getLogger("colosseum.physics.pymunk")

#: Overlap allowed between shapes (m); pymunk's default 0.1 is meant for pixels.
COLLISION_SLOP = 1e-3
#: The longest step chipmunk is given (s): a longer one is taken as equal substeps. At
#: 1/60 s and 0.02 s its solver (sequential impulses, no block solve of a face's two
#: contact points) leaves a 10-crate stack rocking ±55 mm and ±96 mm however it is
#: preloaded, tuned or given twice the iterations; at 0.01 s (the default step) and below
#: the stack stands within 2 mm (docs/PHYSICS.md). Box2D v3 substeps for the same reason.
MAX_SUBSTEP = 0.01
#: chipmunk's sleep timer while auto-sleep is on: chipmunk keeps its islands and wakes
#: what an awake body touches, but never decides on its own (the sleep rule does).
NEVER = 1e300
#: chipmunk's sleep timer for a step taken while auto-sleep is on and no body sleeps
#: (known from the last substep's body read, nothing changed since): off, so chipmunk
#: skips its islands and idle times, which would decide nothing (none to wake, NEVER
#: reached by none); NEVER again right after the step (a body can only be put to sleep
#: with a timer on). The same trajectory to the bit (docs/PHYSICS.md).
QUIET = math.inf
#: A shape filter that collides with nothing (``set_collision_enabled(key, False)``).
NOTHING = pymunk.ShapeFilter(categories=0, mask=0)

_KINDS = {
    BodyKind.DYNAMIC: pymunk.Body.DYNAMIC,
    BodyKind.STATIC: pymunk.Body.STATIC,
    BodyKind.KINEMATIC: pymunk.Body.KINEMATIC,
}


def substeps(dt: float) -> int:
    """How many equal substeps a step of ``dt`` takes: the fewest of at most MAX_SUBSTEP
    (to a part in a million: 0.01 s is one step, 0.02 s two, 1/60 s two)."""
    return max(1, math.ceil(dt / MAX_SUBSTEP * (1.0 - 1e-6)))


@dataclass(slots=True)
class _BodyRecord:
    key: int
    body: pymunk.Body
    shapes: list[pymunk.Shape]
    physical: Physical
    y: float
    rest: np.ndarray
    joints: set[int] = field(default_factory=set)
    #: (x, z, θ) where it was made: its last good pose until a read has seen it
    made_at: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: each shape's collision filter (its own bits, else the body's)
    filters: list[pymunk.ShapeFilter] = field(default_factory=list)


@dataclass(slots=True)
class _Aim:
    """A kinematic body on its way to a target in the plane, due in ``left`` s."""

    x: float
    z: float
    angle: float
    left: float


class PymunkBackend:
    """A 2D side-view world: pymunk space in X–Z, Y kept per body as authored."""

    name = BackendName.PYMUNK

    def __init__(self) -> None:
        self._step_dt = 0.0  # the last substep's, for contact impulses (carried_down)
        #: the contacts (and their rows) of the last step's substeps before its last
        self._earlier: list[tuple[np.ndarray, np.ndarray]] = []
        #: those substeps' arbiters as read, not yet made contacts (:meth:`_substep_read`)
        self._pending: list[tuple[np.ndarray, np.ndarray, bool, np.ndarray, float]] = []
        #: substeps the step under way takes (the bodies' damping, per step, reads it)
        self._parts = [1]
        self._gravity = (0.0, 0.0)  # the space's, as configured (x, z)
        #: the step's body read, while nothing has changed the space since (a state read
        #: right after the step takes it instead of reading again); None: read afresh
        self._step_read: np.ndarray | None = None
        self._space = pymunk.Space()
        self._space.collision_slop = COLLISION_SLOP
        # joints asked for their force -> that force on body_a after the last step
        self._strained: dict[int, np.ndarray | None] = {}
        # the world's own static body (joints to the world, keyless planes), made now so
        # pymunk lists it among the static bodies from the first read on
        self._ground = self._space.static_body
        self._bodies: dict[int, _BodyRecord] = {}
        self._joints: dict[int, JointRecord] = {}
        self._material_types: dict[str, int] = {}
        self._bouncy_types: set[int] = set()
        self._pairs: dict[tuple[int, int], MaterialPair] = {}
        self._warned: set[tuple[str, str]] = set()
        self._contacts: np.ndarray | None = np.zeros(0, CONTACT_DTYPE)
        self._contacts_rows = np.zeros((0, 2), np.int64)  # their rows (a, b)
        self._dirty = True
        self._keys = np.zeros(0, np.int64)
        self._records: list[_BodyRecord] = []  # by row
        self._row: dict[int, int] = {}
        self._y = np.zeros(0)
        # per row, as the reader was planned: fixed tilt, centre of mass, static or not
        self._rests = np.zeros((0, 4))
        self._cogs = np.zeros((0, 2))
        self._masses = np.zeros(0)  # kg, dynamic rows (0 for the others)
        self._static = np.zeros(0, bool)
        self._reader: SpaceReader | None = None
        self._rows: _rows.Rows | None = None  # the reader's compiled rows
        self._sleep_on = True
        self._resting = RestingSupport(0, WorldSettings().warm_start)
        self._preloaded = False  # some row got a preload in the step just taken
        self._rule = SleepRule()
        self._woken: set[int] = set()  # keys woken explicitly since the rule last looked
        #: bodies given a force or torque since the last step (by key): it lasts the step
        self._pushed: dict[int, pymunk.Body] = {}
        self._joint_pairs: np.ndarray | None = None  # (M, 2) rows the joints tie (-1: none)
        #: the resting rule has each row's friction, mass under gravity, joints and kind
        #: (False: to be gathered again)
        self._rest_rows = False
        self._driven: dict[int, JointRecord] = {}  # sliders and springs: forces each step
        self._aims: dict[int, _Aim] = {}  # kinematic bodies on their way to a target
        #: The last read that was all finite: keys, and each row's (x, z, θ, vx, vz, ω).
        self._last_good = (np.zeros(0, np.int64), np.zeros((0, 6)))
        self._read_rows = np.zeros((0, 6))  # the next read's rows, swapped in when good
        self._faults: list[tuple[int, str]] = []
        self._extent = WORLD_EXTENT
        self.configure(WorldSettings())

    # -- reporting ---------------------------------------------------------
    def _warn(self, obj: str, topic: str, message: str) -> None:
        """Log ``message`` once per (object, topic)."""
        if (obj, topic) in self._warned:
            return
        self._warned.add((obj, topic))
        log.warning("%s: %s", obj, message)

    # -- world -------------------------------------------------------------
    def configure(self, settings: WorldSettings) -> None:
        """Gravity, solver iterations, error correction, sleeping and material pairs."""
        settings.check()  # the one range of each setting (WORLD_RANGES)
        space = self._space
        self._extent = float(settings.extent)
        gx, _, gz = settings.gravity
        if settings.gravity[1] != 0.0:
            self._warn("world", "gravity", "gravity's Y component dropped (not in the X–Z plane)")
        space.gravity = self._gravity = (float(gx), float(gz))
        # one space, one count: the more of the two the settings ask for
        space.iterations = max(1, int(settings.iterations), int(settings.contact_iterations))
        if not 0.0 <= settings.warm_start < 1.0:
            raise ValueError(f"warm start must be in [0, 1), got {settings.warm_start}")
        self._resting.beta = float(settings.warm_start)
        # ODE's ERP is the share of penetration fixed per step at 60 Hz; pymunk's bias is
        # the share left after one second.
        erp = min(max(settings.erp, 0.0), 0.99)
        space.collision_bias = (1.0 - erp) ** 60
        self._rule.configure(settings.sleep_time, settings.sleep_linear,
                             settings.sleep_angular)
        if self._sleep_on and not settings.auto_sleep:  # everyone awake, nothing counted
            for rec in self._bodies.values():
                if rec.body.body_type == pymunk.Body.DYNAMIC:
                    rec.body.activate()
            self._rule.forget(slice(None))
        space.sleep_time_threshold = NEVER if settings.auto_sleep else math.inf
        self._sleep_on = bool(settings.auto_sleep)
        self._pairs.clear()
        for pair in settings.material_pairs:
            ta, tb = self._material_type(pair.a), self._material_type(pair.b)
            if pair.softness:
                self._warn(f"material pair {pair.a}/{pair.b}", "softness",
                           "softness is not supported by pymunk; ignored")
            self._pairs[ta, tb] = self._pairs[tb, ta] = pair
            space.on_collision(ta, tb, begin=_pair_begin, pre_solve=_material_pre_solve,
                               data=self._pairs)  # data: the live table of pairs
        for rec in self._bodies.values():
            ctype = self._material_types.get(rec.physical.material.name, 0)
            for shape in rec.shapes:
                shape.collision_type = ctype

    def _material_type(self, name: str) -> int:
        return self._material_types.setdefault(name, len(self._material_types) + 1)

    def _bouncy(self, name: str) -> int:
        """Collision type of a bouncing material, whose contacts take the larger bounce."""
        ctype = self._material_type(name)
        if ctype not in self._bouncy_types:
            self._bouncy_types.add(ctype)
            self._space.on_collision(ctype, None, pre_solve=_material_pre_solve,
                                     data=self._pairs)
        return ctype

    def step(self, dt: float) -> None:
        """Advance by ``dt``: in :func:`substeps` equal steps of at most MAX_SUBSTEP, each
        a whole step of the space with the resting warm start and the sleep rule."""
        n = substeps(dt)
        self._parts[0] = n
        held = self._held_forces() if n > 1 and self._pushed else None
        self._earlier, self._pending = [], []
        if self._rows is not None:
            self._rows.reuse()  # the last step's substeps' arbiters are no longer held
        for i in range(n):
            if i and held:
                self._hold_forces(held)
            self._substep(dt / n)
            if i < n - 1:  # read now: the next substep replaces chipmunk's arbiters
                self._pending.append(self._substep_read())
        self._pushed.clear()

    def _substep_read(self) -> tuple[np.ndarray, np.ndarray, bool, np.ndarray, float]:
        """What a substep's contacts are made of, kept for :meth:`contacts` (a copy of
        its arbiters as read, its preloads): made into contacts only when asked for, or
        before anything changes the space (:func:`_dropping_the_step_read`)."""
        # the substep's body read stands where none fell asleep: who is awake was seen;
        # the read is handed over (the next substep reads into other buffers) until the
        # next step
        ints, floats = self._rows.keep_arbiters(self._step_read is not None)
        return (ints, floats, self._preloaded, self._resting.arrays["lifted"].copy(),
                self._step_dt)

    def _made_contacts(self, ints: np.ndarray, floats: np.ndarray, preloaded: bool,
                       lifted: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """A substep's contacts from its arbiters (and their rows), with the impulses of
        its preloads carried down (:func:`carried_down`)."""
        c, pairs = self._rows.contacts(ints, floats)
        gx, gz = self._gravity
        g = math.hypot(gx, gz)
        if preloaded and len(c) and g > 0.0 and len(lifted) == len(self._records):
            up = np.array([-gx / g, 0.0, -gz / g])
            c["impulse"] = carried_down(pairs[:, 0], pairs[:, 1], c["impulse"],
                                        c["normal"] @ up, lifted * dt)
        return c, pairs

    def _make_pending(self) -> None:
        """The earlier substeps' contacts made now, while the space is as they left it."""
        for read in self._pending:
            self._earlier.append(self._made_contacts(*read))
        self._pending = []

    def _held_forces(self) -> list[tuple[int, pymunk.Body, pymunk.Vec2d, float]]:
        """The forces and torques added for this step (pymunk clears them as it steps),
        to be given again for each substep after the first."""
        return [(key, body, body.force, body.torque) for key, body in self._pushed.items()
                if body.body_type == pymunk.Body.DYNAMIC]

    def _hold_forces(self, held: list[tuple[int, pymunk.Body, pymunk.Vec2d, float]]) -> None:
        """Each pushed body's force and torque again, and again pushed (not at rest)."""
        for key, body, force, torque in held:
            body.force = force
            body.torque = torque
            self._woken.add(key)
        self._step_read = None  # the forces are no longer all zero

    def _substep(self, dt: float) -> None:
        """Step the space (resting bodies given their weight's share first, see
        :mod:`resting`); then let the sleep rule put quiet islands to sleep."""
        if self._driven:
            for rec in self._driven.values():
                rec.before_step(dt)
        if self._aims:
            self._lead_aims(dt)
        self._step_dt = dt
        self._preload_weights()
        # after the preload: it is an outside force to a joint's momentum balance
        strained = self._strain_before(dt) if self._strained else None
        quiet = self._sleep_on and self._step_read is not None and not self._rows.sleepers
        if quiet:
            self._space.sleep_time_threshold = QUIET
        try:
            self._space.step(dt)
        finally:
            if quiet:
                self._space.sleep_time_threshold = NEVER
        rows = self._rows
        rows.new_step()
        if strained:
            self._strain_after(strained, dt)
        if self._aims:
            self._arrive(dt)
        self._contacts = None
        self._step_read = None
        rest = self._resting.beta > 0.0
        if rest or self._sleep_on:
            # one body read for both rules and the state read (the resting pass makes it)
            if rest:
                self._rest(dt)
            else:
                rows.read()
            raw = rows.bodies_read
            if not (self._sleep_on and self._apply_sleep(dt, raw, rows.bodies_awake)):
                self._step_read = raw  # none fell asleep: the read is the space as it is
        if not self._sleep_on:
            self._woken.clear()  # the wakes were for the resting rule alone

    def _preload_weights(self) -> None:
        """Give the rows whose ramp is on their weight's share (an upward force for this
        step, on top of the forces they have), in one compiled pass over those rows
        (:meth:`RestingSupport.preload`)."""
        if self._dirty:
            self._reindex()
        resting = self._resting
        if self._woken and resting.on:  # moved, pushed or woken by hand: not at rest
            resting.forget(self._rule.rows(np.fromiter(self._woken, np.int64)))
        if not resting.on or resting.beta <= 0.0:
            if self._preloaded:
                resting.no_preload()
                self._preloaded = False
            return
        self._preloaded = True
        resting.preload(self._rows, self._gravity)

    def _rest(self, dt: float) -> None:
        """The resting rule after a step, in one compiled pass: the step's body read (the
        rows' :attr:`~_rows.Rows.bodies_read`), what the contacts did, each row's
        standing, the rows to preload before the next step and the rows held still (their
        velocities written back)."""
        resting = self._resting
        if resting.n != len(self._records):
            resting.follow(np.full(len(self._records), -1))
            self._rest_rows = False
        if not self._rest_rows:
            self._rest_bodies()
        resting.after(self._rows, dt, self._gravity)

    def _rest_bodies(self) -> None:
        """Per row, for the resting rule: friction coefficient, mass under gravity (0: not
        dynamic or gravity off), centre of gravity (whether it stands over its base),
        jointed, a kinematic body with shapes (what it touches is not at rest; a hand's
        control body has none and touches nothing), dynamic."""
        recs = self._records
        n = len(recs)
        dynamic = np.fromiter((r.body.body_type == pymunk.Body.DYNAMIC for r in recs), bool, n)
        self._resting.bodies(
            np.fromiter((r.physical.material.friction for r in recs), float, n),
            np.fromiter((r.body.mass if d and r.physical.gravity else 0.0
                         for r, d in zip(recs, dynamic.tolist(), strict=True)), float, n),
            self._cogs,
            np.fromiter((bool(r.joints) for r in recs), bool, n),
            np.fromiter((r.body.body_type == pymunk.Body.KINEMATIC and bool(r.physical.shapes)
                         for r in recs), bool, n),
            dynamic)
        self._rest_rows = True

    def _strain_before(self, dt: float) -> list[tuple[int, pymunk.Body, float, pymunk.Vec2d]]:
        """For each measured joint, its moving body and the velocity the step would give
        it with no contact or constraint (its own velocity callback, run and undone)."""
        out = []
        for key in list(self._strained):
            rec = self._joints.get(key)
            if rec is None:
                del self._strained[key]
                continue
            body, sign = (rec.b, -1.0) if rec.b.body_type == pymunk.Body.DYNAMIC else \
                (rec.a, 1.0)
            v, w = body.velocity, body.angular_velocity
            body.velocity_func(body, self._space.gravity, self._space.damping, dt)
            out.append((key, body, sign, body.velocity))
            body.velocity, body.angular_velocity = v, w
        return out

    def _strain_after(self, strained: list[tuple[int, pymunk.Body, float, pymunk.Vec2d]],
                      dt: float) -> None:
        for key, body, sign, free in strained:
            rec = self._joints[key]
            impulse = (body.velocity - free) * body.mass - _contact_impulse(body)
            size = sum(c.impulse for c in rec.constraints
                       if isinstance(c, pymunk.PivotJoint | pymunk.GrooveJoint))
            length = impulse.length
            f = impulse * (sign * size / (length * dt)) if length > 0.0 else \
                pymunk.Vec2d(0.0, 0.0)
            self._strained[key] = np.array([f.x, 0.0, f.y])

    def _lead_aims(self, dt: float) -> None:
        """Bodies whose target is due within this step slow down to arrive with it."""
        for key, aim in self._aims.items():
            if aim.left < dt * (1.0 - ARRIVE_SLACK):
                body = self._bodies[key].body
                body.velocity = body.velocity * (aim.left / dt)
                body.angular_velocity *= aim.left / dt

    def _arrive(self, dt: float) -> None:
        """Bodies whose target was due in this step: exactly at it, at rest."""
        for key, aim in list(self._aims.items()):
            aim.left -= dt
            if aim.left > dt * ARRIVE_SLACK:
                continue
            del self._aims[key]
            body = self._bodies[key].body
            body.angle = aim.angle
            body.position = (aim.x, aim.z)
            body.velocity = (0.0, 0.0)
            body.angular_velocity = 0.0

    def close(self) -> None:
        for key in list(self._joints):
            self.remove_joint(key)
        for key in list(self._bodies):
            self.remove_body(key)

    # -- bodies ------------------------------------------------------------
    def add_body(self, key: int, body: Physical, position: np.ndarray,
                 orientation: np.ndarray, linear_velocity: np.ndarray | None = None,
                 angular_velocity: np.ndarray | None = None) -> None:
        key = int(key)
        if key in self._bodies:
            raise KeyError(f"body {key} already exists")
        if body.kind not in _KINDS:
            raise ValueError(f"body {key}: kind {body.kind!r} is not one of "
                             f"{', '.join(_KINDS)}")
        obj = f"body {key}"
        if not np.all(np.isfinite(position)):
            raise ValueError(f"{obj}: position {np.asarray(position).tolist()} is not finite")
        theta, rest, planar = split_orientation(orientation)
        if not planar:
            self._warn(obj, "tilt", "orientation tilts out of the X–Z plane; the tilt is "
                       "baked into its 2D silhouette")
        pbody = pymunk.Body(body_type=_KINDS[body.kind])
        static = body.kind != BodyKind.DYNAMIC
        made = [(spec, b) for spec in body.shapes
                if (b := build_shape(pbody, spec, rest, body.kind == BodyKind.STATIC,
                                     lambda t, m: self._warn(obj, t, m))) is not None]
        built = [b for _, b in made]
        filters = [self._filter(body, spec) for spec, _ in made]
        if body.kind == BodyKind.DYNAMIC:
            pbody.mass, pbody.moment, pbody.center_of_gravity = self._mass_properties(
                obj, body, built, rest)
        pbody.angle = theta  # before the position: pymunk turns a body about its centre
        pbody.position = (float(position[0]), float(position[2]))
        mat = body.material
        if mat.softness:
            self._warn(f"material {mat.name}", "softness",
                       "softness is not supported by pymunk; ignored")
        ctype = (self._bouncy(mat.name) if mat.bounce > 0
                 else self._material_types.get(mat.name, 0))
        shapes = [b.shape for b in built]
        for shape, filt in zip(shapes, filters, strict=True):
            # pymunk multiplies the two frictions: √μ each gives the geometric mean, as ODE
            shape.friction = math.sqrt(min(float(mat.friction), 1e12))
            shape.elasticity = float(mat.bounce)
            shape.filter = filt
            shape.collision_type = ctype
        if not static and (not body.gravity or body.gravity_factor != 1.0
                           or body.linear_damping or body.angular_damping):
            pbody.velocity_func = _velocity_func(body.gravity * body.gravity_factor,
                                                 body.linear_damping,
                                                 body.angular_damping, self._parts)
        self._space.add(pbody, *shapes)
        rec = _BodyRecord(key, pbody, shapes, body, float(position[1]), rest,
                          made_at=(pbody.position.x, pbody.position.y, pbody.angle),
                          filters=filters)
        self._bodies[key] = rec
        self._dirty = True
        if linear_velocity is not None or angular_velocity is not None:
            self.set_velocity(key, np.zeros(3) if linear_velocity is None else linear_velocity,
                              np.zeros(3) if angular_velocity is None else angular_velocity)

    def _mass_properties(self, obj: str, body: Physical, built: list[BuiltShape],
                         rest: np.ndarray) -> tuple[float, float, tuple[float, float]]:
        """Mass, moment about the centre of mass, and that centre in the body frame (a
        given centre and principal moments, seen in the plane, win over the shapes')."""
        mass, moment, centre = self._shape_mass(obj, body, built)
        turn = quat_to_matrix(rest)
        if body.center_of_mass is not None:
            c = turn @ np.asarray(body.center_of_mass, np.float64)
            centre = (float(c[0]), float(c[2]))
        if body.inertia is not None:
            axes = turn @ quat_to_matrix(np.asarray(body.inertia_rotation, np.float64))
            moments = locked_inertia(body.inertia, float(body.mass or 0.0))
            moment = float((axes @ np.diag(moments) @ axes.T)[1, 1])
        return mass, moment, centre

    def _shape_mass(self, obj: str, body: Physical,
                    built: list[BuiltShape]) -> tuple[float, float, tuple[float, float]]:
        """Mass, moment about the centre of mass, and that centre, from the shapes."""
        volume = sum(b.volume for b in built)
        if body.mass is not None and body.mass > 0.0:
            shares = ([b.volume / volume for b in built] if volume > 0.0
                      else [1.0 / len(built)] * len(built)) if built else []
            masses = [body.mass * s for s in shares]
        else:
            masses = [body.material.density * b.volume for b in built]
        mass = sum(masses)
        if mass <= 0.0:
            self._warn(obj, "mass", "dynamic body has no mass (no shapes with volume and no "
                       "Mass); using 1 kg")
            mass = body.mass if body.mass is not None and body.mass > 0.0 else 1.0
            return mass, mass * 0.01, (0.0, 0.0)
        cx = sum(m * b.shape.center_of_gravity.x for m, b in zip(masses, built, strict=True))
        cz = sum(m * b.shape.center_of_gravity.y for m, b in zip(masses, built, strict=True))
        cx, cz = cx / mass, cz / mass
        moment = sum(m * b.inertia_per_mass for m, b in zip(masses, built, strict=True))
        moment -= mass * (cx * cx + cz * cz)  # parallel axes: origin → centre of mass
        return mass, max(moment, mass * 1e-9), (cx, cz)

    def _record(self, key: int) -> _BodyRecord:
        try:
            return self._bodies[int(key)]
        except KeyError:
            raise KeyError(f"no body with key {key}") from None

    def remove_body(self, key: int) -> None:
        rec = self._record(key)
        if self._contacts is None:  # the last step's, while the reader still knows the body
            self.contacts()
        for jkey in list(rec.joints):
            log.info("joint %s removed with body %s", jkey, key)
            self.remove_joint(jkey)
        # what it touches wakes (chipmunk wakes a sleeper only through a step's contact: one
        # put to sleep by hand on an awake body, taken away before a step, hung in the air)
        rec.body.each_arbiter(_wake_others, rec.body)
        self._space.remove(rec.body, *rec.shapes)
        del self._bodies[rec.key]
        self._aims.pop(rec.key, None)
        self._pushed.pop(rec.key, None)
        self._dirty = True

    def body_count(self) -> int:
        return len(self._bodies)

    def is_sleeping(self, key: int) -> bool:
        return self._record(key).body.is_sleeping

    def _set_orientation(self, rec: _BodyRecord, orientation: np.ndarray) -> float:
        theta, rest, _ = split_orientation(orientation)
        if max(abs(a - b) for a, b in zip(rest.tolist(), rec.rest.tolist(), strict=True)) > 1e-6:
            self._warn(f"body {rec.key}", "retilt", "new orientation tilts differently out of "
                       "the X–Z plane; only its turn about Y is applied")
        return theta

    def set_pose(self, key: int, position: np.ndarray, orientation: np.ndarray) -> None:
        rec = self._record(key)
        if not np.all(np.isfinite(position)):
            raise ValueError(f"body {key}: position {np.asarray(position).tolist()} is not finite")
        rec.body.angle = self._set_orientation(rec, orientation)
        rec.body.position = (float(position[0]), float(position[2]))
        self._set_y(rec, float(position[1]))
        if rec.body.body_type == pymunk.Body.STATIC:
            self._space.reindex_shapes_for_body(rec.body)
        self._woken.add(rec.key)
        self._aims.pop(rec.key, None)

    def _set_y(self, rec: _BodyRecord, y: float) -> None:
        rec.y = y
        if not self._dirty:
            self._y[self._row[rec.key]] = y

    def set_velocity(self, key: int, linear: np.ndarray, angular: np.ndarray) -> None:
        rec = self._record(key)
        if rec.body.body_type == pymunk.Body.STATIC:
            return
        self._check_planar(rec.key, "velocity", linear, angular)
        _set_origin_velocity(rec.body, float(linear[0]), float(linear[2]), -float(angular[1]))
        self._woken.add(rec.key)
        self._aims.pop(rec.key, None)

    def _check_planar(self, key: int, what: str, linear: np.ndarray | None,
                      angular: np.ndarray | None) -> None:
        if (linear is not None and linear[1] != 0.0) or (
                angular is not None and (angular[0] != 0.0 or angular[2] != 0.0)):
            self._warn(f"body {key}", f"planar-{what}",
                       f"{what} out of the X–Z plane; only its in-plane part is applied")

    def set_kinematic_target(self, key: int, position: np.ndarray,
                             orientation: np.ndarray, dt: float) -> None:
        """Give the body the velocities that carry it to the target in ``dt`` (Y jumps); a
        kinematic body stops there (exactly at the target) unless told otherwise first."""
        rec = self._record(key)
        if dt <= 0.0 or rec.body.body_type == pymunk.Body.STATIC:
            self.set_pose(key, position, orientation)
            return
        body = rec.body
        theta = self._set_orientation(rec, orientation)
        turn = math.remainder(theta - body.angle, 2.0 * math.pi)
        x, z = float(position[0]), float(position[2])
        _set_origin_velocity(body, (x - body.position.x) / dt, (z - body.position.y) / dt,
                             turn / dt)
        self._set_y(rec, float(position[1]))
        self._woken.add(rec.key)
        if body.body_type == pymunk.Body.KINEMATIC:
            self._aims[rec.key] = _Aim(x, z, body.angle + turn, float(dt))
        else:
            self._aims.pop(rec.key, None)

    def add_force(self, key: int, force: np.ndarray, point: np.ndarray | None = None) -> None:
        rec = self._record(key)
        self._check_planar(rec.key, "force", force, None)
        f = (float(force[0]), float(force[2]))
        if point is None:  # at the centre of mass: no torque
            rec.body.apply_force_at_local_point(f, rec.body.center_of_gravity)
        else:
            rec.body.apply_force_at_world_point(f, (float(point[0]), float(point[2])))
        self._woken.add(rec.key)
        self._pushed[rec.key] = rec.body

    def add_torque(self, key: int, torque: np.ndarray) -> None:
        rec = self._record(key)
        self._check_planar(rec.key, "torque", None, torque)
        rec.body.torque -= float(torque[1])
        self._woken.add(rec.key)
        self._pushed[rec.key] = rec.body

    def add_impulse(self, key: int, impulse: np.ndarray,
                    point: np.ndarray | None = None) -> None:
        rec = self._record(key)
        self._check_planar(rec.key, "impulse", impulse, None)
        j = (float(impulse[0]), float(impulse[2]))
        if point is None:
            rec.body.apply_impulse_at_local_point(j, rec.body.center_of_gravity)
        else:
            rec.body.apply_impulse_at_world_point(j, (float(point[0]), float(point[2])))
        self._woken.add(rec.key)

    def set_sleeping(self, key: int, sleeping: bool) -> None:
        """Put a dynamic body to sleep at rest (alone: what it touches wakes it; one touching
        an awake body is stopped but stays awake, as that touch would wake it), or wake it."""
        rec = self._record(key)
        if rec.body.body_type != pymunk.Body.DYNAMIC:
            return
        if not sleeping:
            rec.body.activate()
            self._woken.add(rec.key)
        elif not self._sleep_on:
            self._warn(f"body {key}", "sleep", "cannot sleep while auto_sleep is off; ignored")
        else:
            _stop(rec.body)
            if _may_sleep_alone(rec.body):
                rec.body.sleep()

    def _apply_sleep(self, dt: float, raw: np.ndarray, awake: np.ndarray) -> bool:
        """The sleep rule after a step (``raw``: the step's body read): quiet islands go
        to sleep, each as one chipmunk group (woken together), at rest. Whether some
        did."""
        rule = self._rule
        self._rows.motion(raw, rule.velocity, awake, rule.awake)
        woken = None
        if self._woken:
            woken = np.zeros(len(rule.keys), bool)
            rows = rule.rows(np.fromiter(self._woken, np.int64, len(self._woken)))
            woken[rows[rows >= 0]] = True
            self._woken.clear()
        rows, labels = rule.update(dt, woken, islands=self._islands)
        if not len(rows):
            return False
        asleep = rule.movable & ~awake
        for label in np.unique(labels[rows]).tolist():
            group = [self._records[i].body for i in rows[labels[rows] == label].tolist()]
            sleeping = np.flatnonzero(asleep & (labels == label))
            root = self._records[sleeping[0]].body if len(sleeping) else None
            for body in group:
                _stop(body)
                if root is None:
                    body.sleep()
                    root = body
                else:
                    body.sleep_with_group(root)
        return True

    def _islands(self) -> np.ndarray:
        """Each row's island for the sleep rule: rows tied by the step's contacts and the
        joints through moving bodies (a union-find over the arbiters, in C)."""
        if self._joint_pairs is None:
            pairs = np.array(
                [(rec.spec.body_a, -1 if rec.spec.body_b is None else rec.spec.body_b)
                 for rec in self._joints.values()], np.int64).reshape(-1, 2)
            self._joint_pairs = self._rule.rows(pairs.ravel()).reshape(-1, 2)
        return self._reader.islands(self._rule.movable, self._joint_pairs)

    def sleep_states(self) -> dict[int, SleepState]:
        """Every body asleep or in a quiet stretch (see :mod:`engine.physics.sleep`)."""
        self._space_reader()
        asleep = np.fromiter((r.body.is_sleeping for r in self._records), bool,
                             len(self._records))
        return self._rule.states(asleep)

    def set_sleep_state(self, key: int, state: SleepState) -> None:
        """Put a body's sleep back as :meth:`sleep_states` reported it (a saved state)."""
        rec = self._record(key)
        self._space_reader()
        self._rule.restore(self._row[rec.key], state)
        # not a wake, and neither were the wakes that making the saved state's bodies and
        # joints caused
        self._woken.clear()
        if rec.body.body_type != pymunk.Body.DYNAMIC:
            return
        if state.asleep and self._sleep_on:
            _stop(rec.body)
            if _may_sleep_alone(rec.body):
                rec.body.sleep()
        elif not state.asleep:
            rec.body.activate()

    def set_collision_enabled(self, key: int, enabled: bool) -> None:
        """Off: the body's shapes filter out every other shape (and every ray)."""
        rec = self._record(key)
        for shape, filt in zip(rec.shapes, rec.filters or [self._filter(rec.physical)] *
                               len(rec.shapes), strict=True):
            shape.filter = filt if enabled else NOTHING
        self._wake(rec)

    def set_gravity_enabled(self, key: int, enabled: bool) -> None:
        """Through the body's velocity callback (pymunk has no per-body gravity switch)."""
        rec = self._record(key)
        if rec.body.body_type == pymunk.Body.STATIC:
            return
        phys = rec.physical
        rec.body.velocity_func = _velocity_func(bool(enabled) * phys.gravity_factor,
                                                phys.linear_damping,
                                                phys.angular_damping, self._parts)
        self._wake(rec)

    def _wake(self, rec: _BodyRecord) -> None:
        """An explicit wake: awake now, and its quiet stretch starts over."""
        if rec.body.body_type == pymunk.Body.DYNAMIC:
            rec.body.activate()
        self._woken.add(rec.key)

    @staticmethod
    def _filter(body: Physical, shape: Shape | None = None) -> pymunk.ShapeFilter:
        """The collision filter of ``shape`` (its own bits where it has them, else its
        body's; KHR colliders of one body may filter apart)."""
        category = body.category if shape is None or shape.category is None else shape.category
        mask = body.mask if shape is None or shape.mask is None else shape.mask
        return pymunk.ShapeFilter(categories=category & 0xFFFFFFFF, mask=mask & 0xFFFFFFFF)

    # -- joints ------------------------------------------------------------
    def add_joint(self, key: int, joint: Joint) -> None:
        """Constraints for ``joint``, anchored as if its bodies were at ``joint.reference``
        (their poses when it was first made: a saved joint comes back exactly) or where
        they are."""
        key = int(key)
        if key in self._joints:
            raise KeyError(f"joint {key} already exists")
        a = self._record(joint.body_a)
        b = self._record(joint.body_b) if joint.body_b is not None else None
        if b is a:
            raise ValueError(f"joint {joint.id or key}: body_a and body_b are the same body")
        obj = f"joint {joint.id or key}"
        moved = [] if joint.reference is None else [
            (side.body, pose) for side, pose in zip((a, b), joint.reference, strict=True)
            if side is not None and pose is not None]
        now = [(body, body.angle, body.position) for body, _ in moved]
        for body, pose in moved:  # made where the bodies were when it was first made
            if len(pose) != 7 or not all(map(math.isfinite, pose)):
                raise ValueError(f"{obj}: reference pose {tuple(pose)} is not 7 finite numbers")
            body.angle = split_orientation(np.asarray(pose[3:], np.float64))[0]
            body.position = (float(pose[0]), float(pose[2]))
        try:
            rec = build_joint(joint, a.body, b.body if b else self._ground,
                              lambda t, m: self._warn(obj, t, m))
        finally:
            for body, angle, position in now:
                body.angle, body.position = angle, position
        self._space.add(*rec.constraints)
        self._joints[key] = rec
        self._joint_pairs, self._rest_rows = None, False
        if joint.kind == JointKind.SLIDER or joint.spring is not None:
            self._driven[key] = rec
        a.joints.add(key)
        if b is not None:
            b.joints.add(key)

    def remove_joint(self, key: int) -> None:
        try:
            rec = self._joints.pop(int(key))
        except KeyError:
            raise KeyError(f"no joint with key {key}") from None
        self._driven.pop(int(key), None)
        self._space.remove(*rec.constraints)
        self._joint_pairs, self._rest_rows = None, False
        self._wake_joint(rec)
        for body_key in (rec.spec.body_a, rec.spec.body_b):
            if body_key is not None and body_key in self._bodies:
                self._bodies[body_key].joints.discard(int(key))

    def _wake_joint(self, rec: JointRecord) -> None:
        for body_key in (rec.spec.body_a, rec.spec.body_b):
            if body_key is not None and body_key in self._bodies:
                self._wake(self._bodies[body_key])

    def _joint(self, key: int) -> JointRecord:
        try:
            return self._joints[int(key)]
        except KeyError:
            raise KeyError(f"no joint with key {key}") from None

    def set_motor(self, key: int, velocity: float, max_force: float) -> None:
        rec = self._joint(key)
        rec.set_motor(float(velocity), float(max_force), self._space)
        self._wake_joint(rec)

    def set_servos(self, keys: np.ndarray, table: np.ndarray) -> None:
        """Each joint's motor aimed once, now, from its angle now (a pivot has one axis:
        the second of each row is not used; the 2D hand aims its own motors each frame)."""
        for key, row in zip(np.asarray(keys).tolist(), np.asarray(table).tolist(),
                            strict=True):
            angle = self.joint_state(key)[0]
            fix = (row[0] - angle) / row[5] if row[5] > 0.0 else 0.0
            self.set_motor(key, row[2] + max(-row[6], min(row[6], fix)), row[4])

    def joint_state(self, key: int) -> tuple[float, float]:
        return self._joint(key).state()

    def joint_force(self, key: int) -> np.ndarray:
        """pymunk keeps only the size of a constraint's impulse: its direction comes from
        the momentum balance of the joint's moving body over the step (what its velocity
        changed by beyond gravity, damping and forces, less its contacts' impulses; with
        other joints on that body, theirs mixes in). Measured from the first time asked."""
        self._joint(key)  # KeyError naming an unknown one
        force = self._strained.setdefault(int(key), None)
        return np.zeros(3) if force is None else force.copy()

    def has_joint(self, key: int) -> bool:
        return int(key) in self._joints

    def set_joint_target(self, key: int, position: np.ndarray, orientation: np.ndarray,
                         max_force: float | None = None,
                         max_torque: float | None = None) -> None:
        """Move a ``six_dof`` joint's target pose (world) and optionally its bounds.

        The same call as on the ODE backend, so a hand drives either one.
        """
        rec = self._six_dof(key, "set_joint_target")
        theta, _, planar = split_orientation(orientation)
        if not planar:
            self._warn(f"joint {rec.spec.id or key}", "target-tilt",
                       "target orientation tilts out of the X–Z plane; only its turn about Y "
                       "is followed")
        rec.set_target((float(position[0]), float(position[2])), theta, max_force, max_torque)
        self._wake_joint(rec)

    def set_drive_limits(self, key: int, max_force: float, max_torque: float,
                         time_constant: float | None = None, max_speed: float | None = None,
                         max_spin: float | None = None) -> None:
        """Bound a ``six_dof`` joint's force (N) and torque (N·m), e.g. from a Hand, and its
        response (see :meth:`JointRecord.set_drive_response`); None keeps what it has."""
        rec = self._six_dof(key, "set_drive_limits")
        if not (max_force >= 0.0 and max_torque >= 0.0):
            raise ValueError("six_dof force and torque bounds must be >= 0")
        rec.set_drive_limits(float(max_force), float(max_torque))
        rec.set_drive_response(time_constant, max_speed, max_spin)
        self._wake_joint(rec)

    def _six_dof(self, key: int, what: str) -> JointRecord:
        rec = self._joint(key)
        if rec.spec.kind != JointKind.SIX_DOF:
            raise ValueError(f"joint {rec.spec.id or key}: {what} needs a six_dof joint, "
                             f"not {rec.spec.kind!r}")
        return rec

    # -- state and contacts ---------------------------------------------
    def _reindex(self) -> None:
        """Rows, and the reader planned for them; rebuilt only as bodies come or go.

        Rows are in key order, so the contacts sort by row and a table filled by key
        takes the state in one slice.
        """
        recs = sorted(self._bodies.values(), key=lambda r: r.key)
        n = len(recs)
        old_rows = np.fromiter((self._row.get(r.key, -1) for r in recs), np.int64, n)
        if self._resting.n == len(self._records):
            self._resting.follow(old_rows)
        else:
            self._resting.follow(np.full(n, -1))
        self._rest_rows = False
        self._joint_pairs = None
        self._records = recs
        self._keys = np.fromiter((r.key for r in recs), np.int64, n)
        self._keys.setflags(write=False)  # every state read hands out this same array
        self._row = {r.key: i for i, r in enumerate(recs)}
        self._y = np.fromiter((r.y for r in recs), np.float64, n)
        kind = np.array([r.body.body_type for r in recs], np.int64).reshape(n)
        static = self._static = kind == pymunk.Body.STATIC
        self._rests = np.array([r.rest for r in recs], np.float64).reshape(-1, 4)
        self._cogs = np.array([tuple(r.body.center_of_gravity) for r in recs],
                              np.float64).reshape(-1, 2)
        self._masses = np.fromiter((r.body.mass if k == pymunk.Body.DYNAMIC else 0.0
                                    for r, k in zip(recs, kind.tolist(), strict=True)),
                                   np.float64, n)
        self._reader = SpaceReader(self._space, [r.body for r in recs], self._keys, self._y,
                                   self._rests, self._cogs, static)
        self._rows = self._reader.rows
        self._rule.layout(self._keys, ~static, (kind == pymunk.Body.DYNAMIC) & np.fromiter(
            (r.physical.can_sleep for r in recs), bool, n))
        self._dirty = False

    def _space_reader(self) -> SpaceReader:
        if self._dirty:
            self._reindex()
        return self._reader

    def read_state(self) -> BodyState:
        """Every body's pose and velocity, in fresh arrays; a body gone non-finite is reset
        first."""
        table = np.empty((len(self._bodies), 13))
        return BodyState(self.read_state_into(table), table)

    def read_state_into(self, out: np.ndarray) -> np.ndarray:
        """Every body's state into ``out``'s first rows; the rows' keys (cached)."""
        reader = self._space_reader()
        n = len(self._keys)
        if out.shape[0] < n or out.shape[1:] != (13,) or out.dtype != np.float64:
            raise ValueError(f"read_state_into needs a float64 array of at least ({n}, 13), "
                             f"got {out.dtype} {out.shape}")
        raw = self._step_read
        if raw is None:
            raw, _ = reader.read()
        keep = self._read_rows
        if len(keep) != n:
            keep = self._read_rows = np.empty((n, 6))
        if not self._rows.table(raw, out, keep, self._extent, MAX_SPEED):  # gone, escaped
            self._reset_broken(keep)
            self._step_read = None
            raw, _ = reader.read()
            self._rows.table(raw, out, keep)
        # this read is the last good one now: swap buffers rather than copy
        self._read_rows, last = self._last_good[1], keep
        self._last_good = (self._keys, last)
        return self._keys

    def _reset_broken(self, planar: np.ndarray) -> None:
        """Put bodies gone non-finite, runaway or out of the world back at their last good
        pose (one that left stops at its last pose inside), at rest; the engine reports
        them (:meth:`take_faults`).

        ``planar`` is a read, a row per body: (x, z, θ, vx, vz, ω).
        """
        last_keys, last = self._last_good
        with np.errstate(invalid="ignore"):
            causes = {"nonfinite": ~np.isfinite(planar).all(axis=1),
                      "runaway": (np.abs(planar[:, 3:]) > MAX_SPEED).any(axis=1),
                      "left": (np.abs(planar[:, :2]) > self._extent).any(axis=1)}
        told: set[int] = set()
        for cause, rows in causes.items():
            for i in np.flatnonzero(rows).tolist():
                if i in told:
                    continue
                told.add(i)
                key = int(self._keys[i])
                rec = self._bodies[key]
                body = rec.body
                seen = np.flatnonzero(last_keys == key)
                x, z, angle = last[seen[0], :3] if seen.size else rec.made_at
                body.angle = float(angle)  # before the position: pymunk turns about the centre
                body.position = (float(x), float(z))
                _stop(body)
                if self._sleep_on and body.body_type == pymunk.Body.DYNAMIC:
                    body.sleep()  # disabled, as under ODE, until something wakes it
                self._faults.append((key, fault_message(cause, self._extent)))

    def take_faults(self) -> list[tuple[int, str]]:
        """Bodies reset since the last call, with why (the engine reports them)."""
        faults, self._faults = self._faults, []
        return faults

    def keys(self) -> np.ndarray:
        """Body keys in row order (read-only; the same array until bodies come or go)."""
        if self._dirty:
            self._reindex()
        return self._keys

    def write_state(self, state: BodyState) -> None:
        """Poses and velocities of the bodies ``state.keys`` names, each as set_pose and
        set_velocity set it (once-per-body warnings included), the rows turned into the
        plane in one pass (:func:`_rows.planar_poses`): the hands' control bodies, every
        frame, pay only pymunk's own setters."""
        keys = np.asarray(state.keys).tolist()
        self._space_reader()  # rows planned for the bodies there are now
        where = self._row
        missing = [k for k in keys if k not in where]
        if missing:
            raise KeyError(f"write_state: no bodies with keys {missing[:10]}")
        rows = [where[k] for k in keys]
        planar = np.empty((len(rows), 7))
        flags = np.empty(len(rows), np.uint8)
        flagged = _rows.planar_poses(np.ascontiguousarray(state.table, np.float64),
                                     self._rests[rows], self._cogs[rows], planar, flags)
        if flagged < 0:
            bad = -flagged - 1
            raise ValueError(f"body {keys[bad]}: pose {state.table[bad].tolist()} is not "
                             "finite, or its orientation not a rotation quaternion")
        if flagged:
            self._tell_off_plane(keys, flags)
        records, static, y_rows, space = self._records, self._static, self._y, self._space
        for row, key, (x, z, theta, vx, vz, spin, y) in zip(rows, keys, planar.tolist(),
                                                            strict=True):
            rec = records[row]
            body = rec.body
            _SET_ANGLE(body, theta)
            _SET_POSITION(body, (x, z))
            rec.y = y_rows[row] = y
            if static[row]:
                space.reindex_shapes_for_body(body)
            else:
                _SET_SPIN(body, spin)
                _SET_VELOCITY(body, (vx, vz))
            self._aims.pop(key, None)
        self._woken.update(keys)

    def _tell_off_plane(self, keys: list[int], flags: np.ndarray) -> None:
        """The warnings set_pose and set_velocity give, for the rows :func:`planar_poses`
        flagged."""
        for i in np.flatnonzero(flags).tolist():
            if flags[i] & _rows.RETILT:
                self._warn(f"body {keys[i]}", "retilt", "new orientation tilts differently "
                           "out of the X–Z plane; only its turn about Y is applied")
            if flags[i] & _rows.OFF_PLANE and not self._static[self._row[keys[i]]]:
                self._warn(f"body {keys[i]}", "planar-velocity", "velocity out of the X–Z "
                           "plane; only its in-plane part is applied")

    def contacts(self) -> np.ndarray:
        """The last step's contacts, with the whole impulses: what the solver found plus
        the preloads it stood in for, carried down to the ground (:func:`carried_down`);
        a step taken as substeps reports theirs merged (:func:`_merge_contacts`)."""
        if self._contacts is None:
            reader = self._space_reader()
            self._make_pending()
            c, pairs = self._made_contacts(*reader.arbiters(), self._preloaded,
                                           self._resting.arrays["lifted"], self._step_dt)
            if self._earlier:
                c, pairs = _merge_contacts([*self._earlier, (c, pairs)])
                self._earlier = []
            self._contacts, self._contacts_rows = c, pairs
        return self._contacts

    def _contact_pairs(self) -> np.ndarray:
        """Row pairs of the step's contacts (-1: static geometry), as rows were then."""
        self.contacts()
        return self._contacts_rows

    # -- queries -----------------------------------------------------------
    def overlapping(self, key: int) -> list[int]:
        """Keys of the bodies (-1: static geometry) the body's shapes intersect now, its own
        collisions on or off, as its collision bits allow."""
        rec = self._record(key)
        found: set[int] = set()
        wanted = rec.filters or [self._filter(rec.physical)] * len(rec.shapes)
        for shape, filt in zip(rec.shapes, wanted, strict=True):
            own, shape.filter = shape.filter, filt
            try:
                hits = self._space.shape_query(shape)
            finally:
                shape.filter = own
            for hit in hits:
                if hit.shape is not None and hit.shape.body is not rec.body:
                    found.add(next((r.key for r in self._bodies.values()
                                    if r.body is hit.shape.body), -1))
        return sorted(found)

    def raycast(self, origin: np.ndarray, direction: np.ndarray, max_distance: float,
                ignore: int | None = None, mask: int = 0xFFFFFFFF) -> RayHit | None:
        """Closest hit along the ray (skipping body ``ignore`` and categories outside
        ``mask``); what is cast is the ray's projection on the X–Z plane."""
        d = np.asarray(direction, dtype=np.float64)
        norm = float(np.linalg.norm(d))
        if norm == 0.0 or not max_distance > 0.0:
            return None
        d = d / norm
        if math.hypot(d[0], d[2]) < 1e-12:
            return None  # a ray along Y stays on one point of the plane
        o = np.asarray(origin, dtype=np.float64)
        end = o + d * max_distance
        query = pymunk.ShapeFilter(mask=mask & 0xFFFFFFFF)
        skip = self._bodies[int(ignore)].body if ignore is not None and int(
            ignore) in self._bodies else None
        hits = [h for h in self._space.segment_query((o[0], o[2]), (end[0], end[2]), 0.0, query)
                if h.shape is not None and h.shape.body is not skip]
        if not hits:
            return None
        hit = min(hits, key=lambda h: h.alpha)
        dist = float(hit.alpha) * max_distance
        pos = o + d * dist
        key = next((r.key for r in self._bodies.values() if r.body is hit.shape.body), -1)
        return RayHit(key, (float(pos[0]), float(pos[1]), float(pos[2])),
                      (float(hit.normal.x), 0.0, float(hit.normal.y)), dist)

    def add_static_plane(self, normal: tuple[float, float, float] = (0.0, 0.0, 1.0),
                         offset: float = 0.0, material: MaterialProps | None = None) -> None:
        """Keyless ground plane ``normal · x = offset`` (contacts report it as key −1)."""
        mat = material or MaterialProps()
        built = build_shape(self._ground, Shape("plane", (*normal, offset)),
                            np.array([1.0, 0.0, 0.0, 0.0]), True,
                            lambda t, m: self._warn("static plane", t, m))
        if built is None:
            return
        built.shape.friction = math.sqrt(min(float(mat.friction), 1e12))
        built.shape.elasticity = float(mat.bounce)
        built.shape.collision_type = (self._bouncy(mat.name) if mat.bounce > 0
                                      else self._material_types.get(mat.name, 0))
        self._space.add(built.shape)


def _pair_begin(arbiter: pymunk.Arbiter, space: pymunk.Space,
                pairs: dict[tuple[int, int], MaterialPair]) -> None:
    sa, sb = arbiter.shapes
    pair = pairs.get((sa.collision_type, sb.collision_type))
    if pair is not None and not pair.collide:
        arbiter.process_collision = False


def _material_pre_solve(arbiter: pymunk.Arbiter, space: pymunk.Space,
                        pairs: dict[tuple[int, int], MaterialPair]) -> None:
    """Bounce is the larger of the two materials' (as ODE), unless a pair says otherwise."""
    sa, sb = arbiter.shapes
    arbiter.restitution = max(sa.elasticity, sb.elasticity)
    pair = pairs.get((sa.collision_type, sb.collision_type))
    if pair is not None:
        if pair.friction is not None:
            arbiter.friction = pair.friction
        if pair.bounce is not None:
            arbiter.restitution = pair.bounce


def _contact_impulse(body: pymunk.Body) -> pymunk.Vec2d:
    """The impulse ``body``'s contacts gave it in the last step."""
    arbiters: list[pymunk.Arbiter] = []
    body.each_arbiter(arbiters.append)
    total = pymunk.Vec2d(0.0, 0.0)
    for arb in arbiters:
        total += arb.total_impulse if arb.shapes[0].body is body else -arb.total_impulse
    return total


#: pymunk.Body's own property setters, called straight (its __setattr__ hook, there for
#: type checkers, would double the cost of the four a moved body takes per frame).
_SET_ANGLE = pymunk.Body.angle.fset
_SET_POSITION = pymunk.Body.position.fset
_SET_SPIN = pymunk.Body.angular_velocity.fset
_SET_VELOCITY = pymunk.Body.velocity.fset
_SET_FORCE = pymunk.Body.force.fset


def _velocity_func(gravity: float, linear_damping: float, angular_damping: float,
                   parts: list[int]):
    """Per-body gravity (0: off; a factor: scaled) and ODE-style damping (velocity ×
    (1 − damping) per step: per substep, its ``parts[0]``-th root)."""
    keep_v = 1.0 - min(max(linear_damping, 0.0), 1.0)
    keep_w = 1.0 - min(max(angular_damping, 0.0), 1.0)
    scale = float(gravity)

    def update(body: pymunk.Body, g: tuple[float, float], damping: float, dt: float) -> None:
        pymunk.Body.update_velocity(body, (g[0] * scale, g[1] * scale), damping, dt)
        root = 1.0 / parts[0]
        if keep_v != 1.0:
            body.velocity = body.velocity * keep_v**root
        if keep_w != 1.0:
            body.angular_velocity = body.angular_velocity * keep_w**root

    return update


def _merge_contacts(parts: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray,
                                                                          np.ndarray]:
    """A step's contacts from its substeps' (each: contacts and their rows): each pair of
    bodies with the points it had in the last substep it touched in, and the impulses of
    all its substeps (shared among those points as that substep shared its own; equally
    where it had none), so an impact in an early substep is reported whole. One compiled
    pass (:func:`_rows.merge_substeps`)."""
    return _rows.merge_substeps(parts, CONTACT_DTYPE)


def _may_sleep_alone(body: pymunk.Body) -> bool:
    """Whether chipmunk may put ``body`` to sleep by itself: it touches no awake dynamic
    body. One that does would be woken by that touch at the next step anyway (as on
    ODE), and chipmunk (pymunk 7.3) corrupts its arbiter lists when a body between awake
    ones is put to sleep: the process aborts in ``free()`` a step or two later."""
    touching: list[pymunk.Arbiter] = []
    body.each_arbiter(touching.append)
    return not any(other is not body and other.body_type == pymunk.Body.DYNAMIC
                   and not other.is_sleeping
                   for arbiter in touching for other in arbiter.bodies)


def _stop(body: pymunk.Body) -> None:
    """At rest (before it sleeps: a sleeping body reports zero velocity)."""
    body.velocity = (0.0, 0.0)
    body.angular_velocity = 0.0


def _set_origin_velocity(body: pymunk.Body, vx: float, vz: float, w: float) -> None:
    """Velocities given at the body's origin; pymunk keeps its centre of mass's."""
    r = body.rotation_vector.cpvrotate(body.center_of_gravity)
    body.angular_velocity = w
    body.velocity = (vx - w * r.y, vz + w * r.x)


def _wake_others(arbiter: pymunk.Arbiter, body: pymunk.Body) -> None:
    """Wake the dynamic body on the other side of one of ``body``'s contacts."""
    for other in arbiter.bodies:
        if other is not body and other.body_type == pymunk.Body.DYNAMIC:
            other.activate()



#: The backend's methods that change nothing in the space: every other public method
#: may (a pose, a velocity, a wake, a body or joint come or gone...) and so drops the
#: step's body read (``PymunkBackend._step_read``) before it runs.
_READS_ONLY = frozenset({
    "step", "read_state", "read_state_into", "body_count", "is_sleeping", "keys",
    "sleep_states", "joint_state", "joint_force", "has_joint", "take_faults", "contacts",
    "overlapping", "raycast", "name"})


def _dropping_the_step_read(method: Callable[..., Any]) -> Callable[..., Any]:
    @functools.wraps(method)
    def run(self: PymunkBackend, *args: Any, **kwargs: Any) -> Any:
        self._step_read = None
        if self._pending:
            self._make_pending()
        return method(self, *args, **kwargs)
    return run


for _name, _method in list(vars(PymunkBackend).items()):
    if not _name.startswith("_") and _name not in _READS_ONLY and isinstance(_method,
                                                                             FunctionType):
        setattr(PymunkBackend, _name, _dropping_the_step_read(_method))
