"""OdeBackend: the DynamicsBackend protocol over ODE (3D, double precision).

It turns components into calls on the raw binding (``_ode``), keeps the material
table, runs the sleep rule after each step and wraps batches in :class:`BodyState`.
See ``shapes``, ``materials`` and ``joints`` for how each concept maps onto ODE.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from components import Joint, MaterialProps, Physical
from components.physical import BodyKind
from engine.messages import MessageLog
from engine.physics.backend import (
    CONTACT_DTYPE,
    BackendFailure,
    BackendName,
    BodyState,
    RayHit,
    WorldSettings,
    fault_message,
    locked_inertia,
)
from engine.physics.ode3d import _ode, joints, shapes
from engine.physics.ode3d.materials import MaterialTable
from engine.physics.ode3d.values import check_speed, vec
from engine.physics.sleep import SMOOTHING, SleepRule, SleepState
from engine.rotation import quat_to_matrix, rotation_vector_between

log = logging.getLogger("colosseum.physics.ode")

if CONTACT_DTYPE.itemsize != _ode.CONTACT_RECORD_SIZE:  # pragma: no cover - build mismatch
    raise ImportError("engine.physics.ode3d._ode was built against a different CONTACT_DTYPE; "
                      "rebuild it with `python setup.py build_ext --inplace`")

_BODY_KINDS = {BodyKind.DYNAMIC: _ode.BODY_DYNAMIC, BodyKind.STATIC: _ode.BODY_STATIC,
               BodyKind.KINEMATIC: _ode.BODY_KINEMATIC}
_ALL_BITS = 0xFFFFFFFF
_CAUSES = {_ode.FAULT_NONFINITE: "nonfinite", _ode.FAULT_RUNAWAY: "runaway",
           _ode.FAULT_LEFT_WORLD: "left"}


class OdeBackend:
    """DynamicsBackend over ODE (3D, double precision). One owner thread at a time."""

    name = BackendName.ODE

    def __init__(self, settings: WorldSettings | None = None) -> None:
        self._world = _ode.World()
        self._settings = WorldSettings()
        self._materials = MaterialTable()
        self._faults: list[tuple[int, str]] = []
        self._keys: np.ndarray | None = None  # cached slot order, dropped on add/remove
        self._inert_joints: set[int] = set()
        self._restless: set[int] = set()  # bodies that may not sleep
        self._rule = SleepRule()
        self._bound = -1  # the rule's arrays' generation the world's step is bound to
        self._notes = MessageLog(log)  # ODE's informational messages, told once each
        #: moving bodies' thickness (m: the least half extent of their shapes) and mask,
        #: for the sweep that keeps a fast one from passing through static geometry
        self._thickness: dict[int, tuple[float, int]] = {}
        self._static_keys: set[int] = set()
        #: static bodies with triangle meshes (surfaces of no thickness): only with them
        #: does a step sweep (primitives have inside to push a body out of)
        self._thin_statics: set[int] = set()
        self._thick_rows: np.ndarray | None = None  # per state row: thickness (inf: none)
        #: bodies whose gravity is scaled (Physical.gravity_factor), and by how much
        self._gravity_factors: dict[int, float] = {}
        self._scaled: tuple[np.ndarray, np.ndarray] | None = None
        self._material(MaterialProps())
        self.configure(settings or WorldSettings())

    # -- world -------------------------------------------------------------
    def configure(self, settings: WorldSettings) -> None:
        """Apply gravity, ERP/CFM, iterations, contacts per pair, sleeping and material pairs."""
        settings.check()  # the one range of each setting (WORLD_RANGES)
        self._rule.configure(settings.sleep_time, settings.sleep_linear,
                             settings.sleep_angular)
        self._settings = settings
        self._world.configure(vec(settings.gravity, 3, "gravity"), settings.erp, settings.cfm,
                              settings.iterations, settings.max_contacts, settings.warm_start,
                              settings.contact_softness, settings.exact_rows, settings.extent,
                              settings.contact_iterations)
        if not settings.auto_sleep:  # everyone awake, nothing counted
            _ode.wake_all(self._world)
            self._rule.forget(slice(None))
        if settings.solver_seed is not None:
            self._world.solver_seed = settings.solver_seed
        self._rebuild_pairs()

    @property
    def solver_seed(self) -> int:
        """The solver's random state; saved states restore it so runs continue exactly."""
        return self._world.solver_seed

    def step(self, dt: float) -> None:
        """Collide and solve in C with the GIL released; record contacts and the bodies
        stopped (non-finite, runaway, out of the world; the engine reports them); then let
        the sleep rule put quiet islands to sleep (in the same C call: stepper.h's
        cs_sleep over the rule's arrays, on the islands the step found). Raises
        :class:`BackendFailure` when ODE failed inside the step (the world is abandoned:
        see docs/ODE.md)."""
        sleep = self._settings.auto_sleep
        if sleep:
            self._sleep_rule()  # laid out and bound for the current slots
        if self._gravity_factors:  # gravity x factor: ODE's, plus (factor - 1) of it
            if self._scaled is None:
                self._scaled = (np.fromiter(self._gravity_factors, np.int64),
                                np.fromiter(self._gravity_factors.values(), np.float64))
            _ode.add_scaled_gravity(self._world, *self._scaled, *self._settings.gravity)
        swept = self._sweep(dt) if self._thin_statics and self._thickness else ()
        try:
            bad = self._world.step(dt, sleep)
        except _ode.OdeFailure as exc:
            raise BackendFailure(str(exc)) from None
        if bad:
            extent = self._settings.extent
            self._faults.extend((key, fault_message(_CAUSES[why], extent)) for key, why in bad)
        for key, point, normal, thick in swept:
            self._stop_at(key, point, normal, thick)
        count, note = _ode.take_notes()
        if count:  # one line per kind of message (the log compares them numbers aside)
            self._notes.warn(f"ODE: {note.strip()}")

    def _sweep(self, dt: float) -> list[tuple[int, np.ndarray, np.ndarray, float]]:
        """The moving bodies that this step carries further than half their thickness, and
        the static surface ahead of each along its velocity (a ray from its origin), when
        the step would reach it: a ball faster than its radius per step would pass
        through a floor of no thickness between two steps, which no contact sees."""
        state = self.read_state()
        if self._thick_rows is None or len(self._thick_rows) != len(state.keys):
            self._thick_rows = np.array([self._thickness.get(int(k), (np.inf, 0))[0]
                                         for k in state.keys])
        speed = np.sqrt(np.einsum("ij,ij->i", state.linear_velocity, state.linear_velocity))
        found = []
        for row in np.flatnonzero(speed * dt > 0.5 * self._thick_rows):
            key = int(state.keys[row])
            thick = self._thickness[key]
            v = state.linear_velocity[row]
            reach = float(speed[row]) * dt + thick[0]
            hit = self.raycast(state.position[row], v, reach, ignore=key, mask=thick[1])
            if hit is None or (hit.key >= 0 and hit.key not in self._static_keys):
                continue
            normal = np.asarray(hit.normal, np.float64)
            if normal @ v > 0:  # a face seen from behind: its normal faces the ray
                normal = -normal
            found.append((key, np.asarray(hit.position, np.float64), normal, thick[0]))
        return found

    def _stop_at(self, key: int, point: np.ndarray, normal: np.ndarray, thick: float) -> None:
        """A swept body that went past the surface at ``point`` (or deeper into it than
        half its thickness) is put back on it, its velocity into it taken away; the next
        step's contacts hold it from there."""
        if not _ode.has_body(self._world, key):
            return
        position, orientation = _ode.pose(self._world, key)
        depth = float((position - point) @ normal)
        if depth >= 0.5 * thick:
            return
        position = position + (thick - depth) * normal
        state = self.read_state()
        row = int(np.flatnonzero(state.keys == key)[0])
        v = state.linear_velocity[row].copy()
        v -= min(0.0, float(v @ normal)) * normal
        self.set_pose(key, position, orientation)
        self.set_velocity(key, v, state.angular_velocity[row])

    def close(self) -> None:
        self._world.close()
        self._notes.flush()

    # -- materials ---------------------------------------------------------
    def _material(self, m: MaterialProps) -> int:
        idx, new = self._materials.index(m)
        if new and idx:
            self._rebuild_pairs()
        return idx

    def _rebuild_pairs(self) -> None:
        self._world.set_pairs(self._materials.pair_table(self._settings.erp,
                                                         self._settings.material_pairs))

    # -- bodies ------------------------------------------------------------
    def add_body(self, key: int, body: Physical, position: np.ndarray,
                 orientation: np.ndarray, linear_velocity: np.ndarray | None = None,
                 angular_velocity: np.ndarray | None = None) -> None:
        """Create a body with all its shapes; mass from ``body.mass`` or material density."""
        kind = _BODY_KINDS.get(body.kind)
        if kind is None:
            raise ValueError(f"body {key}: unknown kind {body.kind!r} "
                             f"(expected one of {', '.join(_BODY_KINDS)})")
        if kind == _ode.BODY_DYNAMIC and not body.shapes and not body.mass:
            raise ValueError(f"body {key}: a dynamic body needs shapes or a mass")
        material = self._material(body.material)
        geoms = [shapes.prepare(key, s) for s in body.shapes]
        zero = np.zeros(3)
        _ode.create_body(
            self._world, int(key), kind, vec(position, 3, "position"),
            vec(orientation, 4, "orientation"),
            zero if linear_velocity is None else vec(linear_velocity, 3, "linear velocity"),
            zero if angular_velocity is None else vec(angular_velocity, 3, "angular velocity"),
            float(body.linear_damping), float(body.angular_damping), bool(body.gravity))
        self._keys = None
        try:
            for g in geoms:
                _ode.add_geom(
                    self._world, int(key), g.kind, g.dims, vec(g.offset(), 3, "shape offset"),
                    vec(g.shape.rotation, 4, "shape rotation"), float(body.material.density),
                    material,
                    (body.category if g.shape.category is None else g.shape.category) & _ALL_BITS,
                    (body.mask if g.shape.mask is None else g.shape.mask) & _ALL_BITS,
                    **g.extra)
            mass = float(body.mass) if body.mass else -1.0
            _ode.finish_body(self._world, int(key), mass, *_mass_frame(body))
        except ValueError as exc:
            _ode.remove_body(self._world, int(key))
            raise ValueError(f"body {key}: {exc}") from None
        finally:
            self._tell_printed(key)
        if not body.can_sleep:
            self._restless.add(int(key))
        if kind == _ode.BODY_DYNAMIC and body.shapes and body.mask:
            self._thickness[int(key)] = (_thickness(body), int(body.mask) & _ALL_BITS)
        elif kind == _ode.BODY_STATIC:
            self._static_keys.add(int(key))
            if any(s.kind in ("mesh", "trimesh") for s in body.shapes):
                self._thin_statics.add(int(key))
        self._thick_rows = None
        if body.gravity_factor != 1.0 and kind == _ode.BODY_DYNAMIC:
            self._gravity_factors[int(key)] = float(body.gravity_factor)
            self._scaled = None

    def _tell_printed(self, key: int) -> None:
        """What ODE printed to stdout while the body's shapes were made (dCreateConvex's
        checks of the data it was given), told through the log: once per kind of message,
        its repeats counted (the numbers of bodies and polygons aside)."""
        for line in _ode.take_printed():
            self._notes.warn(f"body {key}: ODE: {line.strip()}")

    def add_static_plane(self, normal: tuple[float, float, float] = (0.0, 0.0, 1.0),
                         offset: float = 0.0, material: MaterialProps | None = None) -> None:
        """Keyless ground plane ``normal · x = offset`` (contacts report it as key -1)."""
        n = vec(normal, 3, "plane normal")
        n /= np.linalg.norm(n)
        idx = self._material(material or MaterialProps())
        _ode.add_static_plane(self._world, n[0], n[1], n[2], float(offset), idx, 1, _ALL_BITS)

    def remove_body(self, key: int) -> None:
        """Remove a body; joints on it are removed with it."""
        _ode.remove_body(self._world, int(key))
        self._restless.discard(int(key))
        self._keys = None
        if self._gravity_factors.pop(int(key), None) is not None:
            self._scaled = None
        self._thickness.pop(int(key), None)
        self._static_keys.discard(int(key))
        self._thin_statics.discard(int(key))
        self._thick_rows = None

    def body_count(self) -> int:
        return _ode.body_count(self._world)

    def set_pose(self, key: int, position: np.ndarray, orientation: np.ndarray) -> None:
        try:  # seven numbers straight to C; anything else the checked way, for its message
            _ode.set_pose_values(self._world, int(key), *position, *orientation)
        except (TypeError, ValueError):
            _ode.set_pose(self._world, int(key), vec(position, 3, "position"),
                          vec(orientation, 4, "orientation"))

    def set_velocity(self, key: int, linear: np.ndarray, angular: np.ndarray) -> None:
        try:
            _ode.set_velocity_values(self._world, int(key), *linear, *angular)
            return
        except (TypeError, ValueError):
            pass
        lin = vec(linear, 3, "linear velocity")
        ang = vec(angular, 3, "angular velocity")
        check_speed(key, lin, ang)
        _ode.set_velocity(self._world, int(key), lin, ang)

    def set_kinematic_target(self, key: int, position: np.ndarray,
                             orientation: np.ndarray, dt: float) -> None:
        """Give the body the velocities that carry it to the target pose in ``dt``; a
        kinematic body stops there (exactly at the target) unless told otherwise first."""
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt}")
        pos, quat = _ode.pose(self._world, int(key))
        target = vec(position, 3, "position")
        q = vec(orientation, 4, "orientation")
        q /= np.linalg.norm(q)
        lin, ang = (target - pos) / dt, rotation_vector_between(quat, q) / dt
        check_speed(key, lin, ang)
        _ode.aim_kinematic(self._world, int(key), target, q, lin, ang, float(dt))

    def add_force(self, key: int, force: np.ndarray, point: np.ndarray | None = None) -> None:
        f = vec(force, 3, "force")
        p = None if point is None else vec(point, 3, "point")
        _ode.add_force(self._world, int(key), f[0], f[1], f[2], p)

    def add_torque(self, key: int, torque: np.ndarray) -> None:
        t = vec(torque, 3, "torque")
        _ode.add_torque(self._world, int(key), t[0], t[1], t[2])

    def add_impulse(self, key: int, impulse: np.ndarray,
                    point: np.ndarray | None = None) -> None:
        """Deliver ``impulse`` (N·s) over the next step, assumed as long as the last one."""
        j = vec(impulse, 3, "impulse")
        p = None if point is None else vec(point, 3, "point")
        _ode.add_impulse(self._world, int(key), j[0], j[1], j[2], p)

    def set_collision_enabled(self, key: int, enabled: bool) -> None:
        _ode.set_collision(self._world, int(key), bool(enabled))

    def set_gravity_enabled(self, key: int, enabled: bool) -> None:
        _ode.set_gravity(self._world, int(key), bool(enabled))

    # -- sleep -------------------------------------------------------------
    def set_sleeping(self, key: int, sleeping: bool) -> None:
        _ode.set_sleeping(self._world, int(key), bool(sleeping))

    def is_sleeping(self, key: int) -> bool:
        return _ode.is_sleeping(self._world, int(key))

    def sleeping_count(self) -> int:
        return _ode.sleeping_count(self._world)

    def _sleep_rule(self) -> SleepRule:
        """The rule, laid out for the current slots and bound to the world's step."""
        keys = self.keys()
        rule = self._rule
        if rule.keys is not keys:
            kinds = _ode.kinds(self._world)
            restless = np.isin(keys, np.fromiter(self._restless, np.int64, len(self._restless)))
            rule.layout(keys, kinds != _ode.BODY_STATIC,
                        (kinds == _ode.BODY_DYNAMIC) & ~restless)
        if self._bound != rule.generation:
            self._world.bind_sleep(*rule.arrays(), rule.time, SMOOTHING)
            self._bound = rule.generation
        return rule

    def sleep_states(self) -> dict[int, SleepState]:
        """Every body asleep, in a quiet stretch or resting on its contacts (see
        :mod:`engine.physics.sleep` and stepper.h's resting preload)."""
        states = self._sleep_rule().states(_ode.sleeping(self._world))
        steps, slid, held, preloaded = _ode.rest_standing(self._world)
        keys = self.keys()
        for i in np.flatnonzero(steps | slid | preloaded | held.any(axis=1)).tolist():
            key = int(keys[i])
            state = states.get(key, SleepState(False))
            states[key] = dataclasses.replace(state, rest_steps=int(steps[i]),
                                              rest_slid=bool(slid[i]),
                                              rest_force=held[i].copy(),
                                              rest_preloaded=bool(preloaded[i]))
        return states

    def set_sleep_state(self, key: int, state: SleepState) -> None:
        """Put a body's sleep back as :meth:`sleep_states` reported it (a saved state)."""
        if not _ode.has_body(self._world, int(key)):
            raise KeyError(f"no body with key {key}")
        rule = self._sleep_rule()
        rule.restore(int(rule.rows(np.array([key]))[0]), state)
        force = np.zeros(3) if state.rest_force is None else vec(state.rest_force, 3,
                                                                 "rest force")
        _ode.set_rest_standing(self._world, int(key), int(state.rest_steps),
                               bool(state.rest_slid), force, bool(state.rest_preloaded))
        _ode.restore_sleeping(self._world, int(key), bool(state.asleep))

    # -- joints ------------------------------------------------------------
    def add_joint(self, key: int, joint: Joint) -> None:
        """Create a joint from its component: anchor and axes are world-frame, with the
        bodies at ``joint.reference`` (the poses when it was first made) or where they are."""
        if joint.kind not in joints.JOINT_KINDS:
            raise ValueError(f"joint {joint.id or key}: unknown kind {joint.kind!r} "
                             f"(expected one of {', '.join(joints.JOINT_KINDS)})")
        if joint.broken:
            self._inert_joints.add(int(key))
            return
        joints.create(self._world, int(key), joint)

    def remove_joint(self, key: int) -> None:
        if int(key) in self._inert_joints:
            self._inert_joints.discard(int(key))
            return
        _ode.remove_joint(self._world, int(key))

    def has_joint(self, key: int) -> bool:
        return _ode.has_joint(self._world, int(key)) or int(key) in self._inert_joints

    def set_motor(self, key: int, velocity: float, max_force: float) -> None:
        _ode.set_motor(self._world, int(key), float(velocity), float(max_force))

    def set_servos(self, keys: np.ndarray, table: np.ndarray) -> None:
        _ode.set_servos(self._world, np.ascontiguousarray(keys, dtype=np.int64),
                        np.ascontiguousarray(table, dtype=np.float64))

    def joint_state(self, key: int) -> tuple[float, float]:
        return _ode.joint_state(self._world, int(key))

    def joint_force(self, key: int) -> np.ndarray:
        return _ode.joint_force(self._world, int(key))

    def set_joint_target(self, key: int, position: np.ndarray, orientation: np.ndarray,
                         max_force: float | None = None,
                         max_torque: float | None = None) -> None:
        """Move a ``six_dof`` joint's target pose (and optionally its force/torque bounds)."""
        _ode.set_target(self._world, int(key), vec(position, 3, "target position"),
                        vec(orientation, 4, "target orientation"),
                        -1.0 if max_force is None else float(max_force),
                        -1.0 if max_torque is None else float(max_torque))

    def set_drive_limits(self, key: int, max_force: float, max_torque: float,
                         time_constant: float | None = None, max_speed: float | None = None,
                         max_spin: float | None = None) -> None:
        """Bound a ``six_dof`` joint's force (N) and torque (N·m), e.g. from a Hand; and its
        response: the time constant (s) its error closes with, the correction's speed
        (m/s) and spin (rad/s) caps. None keeps what it has."""
        _ode.set_drive_limits(self._world, int(key), float(max_force), float(max_torque),
                              *(-1.0 if v is None else float(v)
                                for v in (time_constant, max_speed, max_spin)))

    # -- batches -----------------------------------------------------------
    def read_state(self) -> BodyState:
        """Every body's pose and velocity (static ones included) in fresh arrays."""
        keys, table = _ode.read_state(self._world)
        return BodyState(keys, table)

    def exact_state(self) -> BodyState:
        """The rows that, put back as a saved state loads them, give ODE its numbers to the
        bit (read_state's differ by rounding where the centre of mass is off the origin)."""
        keys, table = _ode.read_state_exact(self._world)
        return BodyState(keys, table)

    def read_state_into(self, out: np.ndarray) -> np.ndarray:
        """Every body's state into ``out``'s first rows, in C; the rows' keys (cached)."""
        _ode.read_state_into(self._world, out)
        return self.keys()

    def keys(self) -> np.ndarray:
        """Body keys in row order (read-only; the same array until bodies come or go)."""
        if self._keys is None:
            self._keys = _ode.keys(self._world)
            self._keys.setflags(write=False)
        return self._keys

    def write_state(self, state: BodyState) -> None:
        """Set poses and velocities of the bodies named in ``state.keys`` (checked: every
        number finite, no body faster than the step allows; a table that passes in one
        go, as every hand's control bodies each frame do, is checked in a few array
        operations, a failing one row by row for its message)."""
        keys = np.asarray(state.keys, dtype=np.int64)
        mine = self.keys()
        if keys.shape == mine.shape and np.array_equal(keys, mine):
            slots = np.arange(len(keys), dtype=np.int64)
        else:
            slots = _ode.slots_for(self._world, keys)
        n = len(keys)
        table = state.table
        # a table that passes in one go: no component over the limit over √3, no speed
        # over it (as SetPoses' limits are checked); others measured below
        if isinstance(table, np.ndarray) and table.shape == (n, 13) and \
                table.dtype == np.float64 and np.isfinite(table).all() and \
                (not n or np.abs(table[:, 7:13]).max() * math.sqrt(3.0) <=
                 _ode.MAX_BODY_SPEED):
            position, orientation, lin, ang = (np.ascontiguousarray(c) for c in state.columns())
            _ode.write_state(self._world, slots, position, orientation, lin, ang)
            return

        def rows(a: np.ndarray, w: int, what: str) -> np.ndarray:
            arr = np.ascontiguousarray(a, dtype=np.float64)
            if arr.shape != (n, w):
                raise ValueError(f"write_state: {what} must have shape ({n}, {w})")
            bad = ~np.isfinite(arr).all(axis=1)
            if bad.any():
                raise ValueError(f"write_state: non-finite {what} for bodies "
                                 f"{keys[bad].tolist()}")
            return arr

        lin = rows(state.linear_velocity, 3, "linear_velocity")
        ang = rows(state.angular_velocity, 3, "angular_velocity")
        with np.errstate(over="ignore"):
            fast = (np.linalg.norm(lin, axis=1) > _ode.MAX_BODY_SPEED) | \
                (np.linalg.norm(ang, axis=1) > _ode.MAX_BODY_SPEED)
        if fast.any():
            raise ValueError(f"write_state: bodies {keys[fast].tolist()} move faster than "
                             f"{_ode.MAX_BODY_SPEED:g} m/s or rad/s")
        _ode.write_state(self._world, slots, rows(state.position, 3, "position"),
                         rows(state.orientation, 4, "orientation"), lin, ang)

    def contacts(self) -> np.ndarray:
        return _ode.contacts(self._world).view(CONTACT_DTYPE)

    def take_faults(self) -> list[tuple[int, str]]:
        """Bodies reset since the last call, as (key, reason); the list is then cleared."""
        faults, self._faults = self._faults, []
        return faults

    # -- queries -----------------------------------------------------------
    def overlapping(self, key: int) -> list[int]:
        """Keys of the bodies (-1: static geometry) the body intersects now, its own
        collisions on or off, as its collision bits allow."""
        return _ode.overlapping(self._world, int(key))

    def raycast(self, origin: np.ndarray, direction: np.ndarray, max_distance: float,
                ignore: int | None = None, mask: int = _ALL_BITS) -> RayHit | None:
        """Closest hit along the ray, skipping body ``ignore`` and categories outside ``mask``."""
        o = vec(origin, 3, "ray origin")
        d = vec(direction, 3, "ray direction")
        norm = float(np.linalg.norm(d))
        if norm == 0 or not max_distance > 0:
            return None
        d = d / norm
        hit = _ode.raycast(self._world, o[0], o[1], o[2], d[0], d[1], d[2],
                           float(max_distance), -1 if ignore is None else int(ignore),
                           mask & _ALL_BITS)
        if hit is None:
            return None
        key, pos, normal, dist = hit
        return RayHit(int(key), pos, normal, float(dist))


def _thickness(body: Physical) -> float:
    """How thin a body is (m): the least half extent of its shapes (a sphere's or a
    capsule's radius, half a box's or a mesh's thinnest side), the distance a step may
    carry it before a surface of no thickness can slip between two of its poses."""
    thin = []
    for s in body.shapes:
        size = np.asarray(s.size, np.float64).reshape(-1)
        if s.kind in ("sphere", "capsule", "cylinder"):
            thin.append(float(size[0]) if s.kind != "cylinder" else
                        float(min(size[0], size[1] / 2)))
        elif s.kind == "box":
            thin.append(float(np.min(np.abs(size[:3]))) / 2)
        elif s.vertices is not None and len(s.vertices):
            v = np.asarray(s.vertices, np.float64).reshape(-1, 3)
            thin.append(float(np.min(v.max(axis=0) - v.min(axis=0))) / 2)
    return max(min(thin, default=0.0), 1e-6)


def _mass_frame(body: Physical) -> tuple[np.ndarray | None, np.ndarray | None]:
    """A body's given centre of mass and its inertia tensor about it in the body frame,
    row-major (R diag(I) R^T, R the principal axes' turn); None where the shapes say."""
    com = None if body.center_of_mass is None else vec(body.center_of_mass, 3,
                                                       "centre of mass")
    if body.inertia is None:
        return com, None
    turn = quat_to_matrix(vec(body.inertia_rotation, 4, "inertia rotation"))
    moments = locked_inertia(vec(body.inertia, 3, "inertia"), float(body.mass or 0.0))
    tensor = turn @ np.diag(moments) @ turn.T
    return com, np.ascontiguousarray((tensor + tensor.T) / 2).reshape(9)
