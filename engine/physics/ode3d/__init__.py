"""The 3D dynamics backend: ODE 0.16 through our own Cython extension (``_ode``).

This module is the typed layer: it turns components (:class:`Physical`,
:class:`Shape`, :class:`Joint`, :class:`MaterialProps`) into calls on the raw
world, keeps the material pair table, and wraps batches in :class:`BodyState`.
Everything per step or per body (collision callback, contact joints, contact
impulses, the non-finite check, batch reads and writes) runs in C inside
``_ode``, with the GIL released around collision and QuickStep.

Conventions beyond the protocol:

* Contacts: ``a`` is always a moving body; ``normal`` points from ``b`` into
  ``a`` (moving ``a`` along it by ``depth`` separates them); ``impulse`` is
  ``|f|·dt`` from the contact joint's feedback. Pairs where every body sleeps
  are not collided, so resting stacks report no contacts.
* Friction is Coulomb (``dContactApprox1``): ``mu`` is a coefficient. A pair's
  friction is the geometric mean of the two materials', bounce and bounce
  velocity the larger ones, softness the larger one. ``softness`` is the
  contact's constraint force mixing (ODE ``soft_cfm``; 0 = rigid, 1e-3 to 1e-2
  visibly soft), used with the world ERP. :class:`MaterialPair` overrides any
  of them, or disables the pair (``collide=False``).
* Capsule and cylinder ``size`` is ``(radius, length)`` along local Z, the
  length excluding a capsule's caps (ODE's convention). A ``plane`` shape is
  infinite, belongs to static bodies only and is given in world coordinates
  (the body's pose does not move it). ``mesh`` shapes (vertices + triangle
  faces, e.g. from trimesh) work on static and dynamic bodies; ``hull`` shapes
  take the convex hull of their vertices.
* A body's ODE frame sits at its centre of mass; poses and velocities in and
  out of the backend are those of the entity origin, converted in C.
* ``six_dof`` joints drive ``body_a`` toward a target pose with a linear motor
  and an angular motor on the three world axes (dJointTypeLMotor + AMotor),
  whose target velocities are set in C before each step to ``pose error / dt``
  and whose force is bounded by ``motor_max_force`` (force and torque; change
  them with :meth:`OdeBackend.set_drive_limits`). With a ``body_b`` (the
  tracked, usually kinematic, target) the target is ``body_a``'s pose relative
  to ``body_b`` at creation, carried along as ``body_b`` moves; without one it is
  a world pose set by :meth:`OdeBackend.set_joint_target`. The solver applies at
  most the bounded force, so a blocked hand pushes but never tunnels or explodes,
  and the constraint is implicit (stable at any gain, unlike an explicit PD force).
* A body whose state turns non-finite in a step, or whose speed or spin passes
  ``_ode.MAX_BODY_SPEED`` (an exploding joint or motor), is put back at its last
  good pose, at rest, and disabled; it is reported by
  :meth:`OdeBackend.take_faults` and the world steps on. Inputs that would
  cause that (velocities past the limit, a force or torque that would reach it
  in one step) are refused with ``ValueError`` before they reach ODE, which
  aborts the process on a non-finite rotation.
* ``hinge2`` limits act on axis 1 (steering) and its motor on axis 2 (the
  wheel); :meth:`OdeBackend.joint_state` reports axis 1, as the protocol says.
* A joint with a ``reference`` (its bodies' poses when it was first made) is made
  as if its bodies stood there, then they are put back: ODE keeps anchors, axes
  and the reference rotation in the bodies' frames, fixed when the joint is made,
  so this re-creates a saved joint bit for bit.
* Auto-sleep is ODE's auto-disable rule, run in ``_ode`` on counters of its own
  (see its module doc): :meth:`OdeBackend.sleep_states` and
  :meth:`OdeBackend.set_sleep_state` read and restore them for saved states.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from components import Joint, MaterialProps, Physical, Shape
from engine.physics.backend import (
    CONTACT_DTYPE,
    BodyState,
    RayHit,
    SleepState,
    WorldSettings,
)
from engine.physics.ode3d import _ode
from engine.rotation import rotation_vector_between

log = logging.getLogger("colosseum.physics.ode")

if CONTACT_DTYPE.itemsize != _ode.CONTACT_RECORD_SIZE:  # pragma: no cover - build mismatch
    raise ImportError("engine.physics.ode3d._ode was built against a different CONTACT_DTYPE; "
                      "rebuild it with `python setup.py build_ext --inplace`")

_BODY_KINDS = {"dynamic": _ode.BODY_DYNAMIC, "static": _ode.BODY_STATIC,
               "kinematic": _ode.BODY_KINEMATIC}
_GEOM_KINDS = {"sphere": _ode.GEOM_SPHERE, "box": _ode.GEOM_BOX, "capsule": _ode.GEOM_CAPSULE,
               "cylinder": _ode.GEOM_CYLINDER, "plane": _ode.GEOM_PLANE,
               "mesh": _ode.GEOM_MESH, "trimesh": _ode.GEOM_MESH, "hull": _ode.GEOM_HULL}
_SIZES = {"sphere": 1, "box": 3, "capsule": 2, "cylinder": 2, "plane": 4}
_JOINT_KINDS = {"hinge": _ode.JOINT_HINGE, "motorized_hinge": _ode.JOINT_HINGE,
                "ball": _ode.JOINT_BALL, "slider": _ode.JOINT_SLIDER,
                "universal": _ode.JOINT_UNIVERSAL, "hinge2": _ode.JOINT_HINGE2,
                "fixed": _ode.JOINT_FIXED, "angular_motor": _ode.JOINT_AMOTOR,
                "linear_motor": _ode.JOINT_LMOTOR, "six_dof": _ode.JOINT_SIX_DOF}
_ALL_BITS = 0xFFFFFFFF


@dataclass(frozen=True, slots=True)
class _HullData:
    planes: np.ndarray  # (F, 4) outward normal and offset
    points: np.ndarray  # (V, 3)
    polygons: np.ndarray  # flat [3, i, j, k, 3, ...]
    triangles: np.ndarray  # (F, 3), wound counter-clockwise seen from outside


def _hull(vertices: np.ndarray) -> _HullData:
    """Convex hull of a point cloud in the form dCreateConvex wants (planes + polygons)."""
    from scipy.spatial import ConvexHull  # only scenes with hulls pay for importing scipy

    pts = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    hull = ConvexHull(pts)
    points = pts[hull.vertices]
    remap = np.full(len(pts), -1, np.int64)
    remap[hull.vertices] = np.arange(len(hull.vertices))
    tris = remap[hull.simplices]
    normals = hull.equations[:, :3]
    p0, p1, p2 = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(p1 - p0, p2 - p0), normals) < 0
    tris[flip] = tris[flip][:, ::-1]
    planes = np.column_stack([normals, -hull.equations[:, 3]])
    polygons = np.column_stack([np.full(len(tris), 3), tris]).astype(np.uint32).ravel()
    return _HullData(planes, points, polygons, tris.astype(np.uint32))


def _vec(value: object, n: int, what: str) -> np.ndarray:
    arr = np.ascontiguousarray(value, dtype=np.float64).reshape(-1)
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} must be {n} finite numbers, got {value!r}")
    return arr


def _check_speed(key: int, linear: np.ndarray, angular: np.ndarray) -> None:
    """ODE aborts on a non-finite quaternion, so runaway speeds never get in."""
    with np.errstate(over="ignore"):  # an overflowing norm is inf, which is refused
        speed = max(float(np.linalg.norm(linear)), float(np.linalg.norm(angular)))
    if speed > _ode.MAX_BODY_SPEED:
        raise ValueError(f"body {key}: velocity beyond {_ode.MAX_BODY_SPEED:g} m/s or rad/s")


class OdeBackend:
    """DynamicsBackend over ODE (3D, double precision). One owner thread at a time."""

    name = "ode"

    def __init__(self, settings: WorldSettings | None = None) -> None:
        self._world = _ode.World()
        self._settings = WorldSettings()
        self._materials: list[MaterialProps] = []
        self._material_index: dict[tuple, int] = {}
        self._faults: list[tuple[int, str]] = []
        self._keys: np.ndarray | None = None  # cached slot order, dropped on add/remove
        self._inert_joints: set[int] = set()
        self._material(MaterialProps())
        self.configure(settings or WorldSettings())

    # -- world -------------------------------------------------------------
    def configure(self, settings: WorldSettings) -> None:
        """Apply gravity, ERP/CFM, iterations, contacts per pair, sleeping and material pairs."""
        if settings.iterations < 1:
            raise ValueError(f"iterations must be at least 1, got {settings.iterations}")
        self._settings = settings
        self._world.configure(_vec(settings.gravity, 3, "gravity"), settings.erp, settings.cfm,
                              settings.iterations, settings.max_contacts, settings.auto_sleep)
        if settings.solver_seed is not None:
            self._world.solver_seed = settings.solver_seed
        self._rebuild_pairs()

    @property
    def solver_seed(self) -> int:
        """The solver's random state; saved states restore it so runs continue exactly."""
        return self._world.solver_seed

    def step(self, dt: float) -> None:
        """Collide and solve in C with the GIL released; record contacts and faults."""
        bad = self._world.step(dt)
        if bad:
            self._faults.extend(
                (key, "non-finite or runaway state; reset to its last good pose and disabled")
                for key in bad)
            for key in bad:
                log.warning("body %d went non-finite or ran away; reset and disabled", key)

    def close(self) -> None:
        self._world.close()

    # -- materials ---------------------------------------------------------
    def _material(self, m: MaterialProps) -> int:
        sig = (m.name, m.friction, m.bounce, m.bounce_velocity, m.softness)
        idx = self._material_index.get(sig)
        if idx is None:
            for what, value in (("friction", m.friction), ("bounce", m.bounce),
                                ("bounce_velocity", m.bounce_velocity),
                                ("softness", m.softness)):
                if not value >= 0:
                    raise ValueError(f"material {m.name!r}: {what} must be >= 0, got {value}")
            idx = len(self._materials)
            self._materials.append(m)
            self._material_index[sig] = idx
            if idx:
                self._rebuild_pairs()
        return idx

    def _rebuild_pairs(self) -> None:
        mats = self._materials
        fr = np.array([m.friction for m in mats])
        bo = np.array([m.bounce for m in mats])
        bv = np.array([m.bounce_velocity for m in mats])
        so = np.array([m.softness for m in mats])
        with np.errstate(invalid="ignore"):
            mu = np.sqrt(np.outer(fr, fr))
        mu[np.isnan(mu)] = 0.0  # 0 * inf: frictionless wins
        table = np.empty((len(mats), len(mats), 7))
        table[..., 0] = 1.0
        table[..., 2] = mu
        table[..., 3] = np.maximum.outer(bo, bo)
        table[..., 4] = np.maximum.outer(bv, bv)
        table[..., 5] = self._settings.erp
        table[..., 6] = np.maximum.outer(so, so)
        names = [m.name for m in mats]
        for pair in self._settings.material_pairs:
            ia = [i for i, n in enumerate(names) if n == pair.a]
            ib = [i for i, n in enumerate(names) if n == pair.b]
            for i in ia:
                for k in ib:
                    for r, c in ((i, k), (k, i)):
                        table[r, c, 0] = float(pair.collide)
                        if pair.friction is not None:
                            table[r, c, 2] = pair.friction
                        if pair.bounce is not None:
                            table[r, c, 3] = pair.bounce
                        if pair.softness is not None:
                            table[r, c, 6] = pair.softness
        mode = np.full(table.shape[:2], _ode.MODE_APPROX1, np.float64)
        mode += np.where(table[..., 3] > 0, _ode.MODE_BOUNCE, 0)
        mode += np.where(table[..., 6] > 0, _ode.MODE_SOFT, 0)
        table[..., 1] = mode
        self._world.set_pairs(np.ascontiguousarray(table))

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
        shapes = [self._prepare_shape(key, s) for s in body.shapes]
        zero = np.zeros(3)
        self._world.create_body(
            int(key), kind, _vec(position, 3, "position"), _vec(orientation, 4, "orientation"),
            zero if linear_velocity is None else _vec(linear_velocity, 3, "linear velocity"),
            zero if angular_velocity is None else _vec(angular_velocity, 3, "angular velocity"),
            float(body.linear_damping), float(body.angular_damping), bool(body.gravity),
            bool(body.can_sleep))
        self._keys = None
        try:
            for shape, gkind, dims, extra in shapes:
                self._world.add_geom(
                    int(key), gkind, dims, _vec(shape.offset, 3, "shape offset"),
                    _vec(shape.rotation, 4, "shape rotation"), float(body.material.density),
                    material, body.category & _ALL_BITS, body.mask & _ALL_BITS, **extra)
            mass = float(body.mass) if body.mass else -1.0
            self._world.finish_body(int(key), mass)
        except ValueError as exc:
            self._world.remove_body(int(key))
            raise ValueError(f"body {key}: {exc}") from None

    def _prepare_shape(self, key: int, shape: Shape) -> tuple[Shape, int, np.ndarray, dict]:
        gkind = _GEOM_KINDS.get(shape.kind)
        if gkind is None:
            raise ValueError(f"body {key}: unknown shape {shape.kind!r} "
                             f"(expected one of {', '.join(sorted(set(_GEOM_KINDS)))})")
        extra: dict = {}
        if shape.kind in _SIZES:
            n = _SIZES[shape.kind]
            dims = np.ascontiguousarray(shape.size, dtype=np.float64).reshape(-1)
            if shape.kind == "box" and dims.size == 1:
                dims = np.repeat(dims, 3)
            if dims.size < n or not np.all(np.isfinite(dims[:n])):
                raise ValueError(f"body {key}: a {shape.kind} needs {n} size values, "
                                 f"got {shape.size!r}")
            dims = np.ascontiguousarray(dims[:n])
            if shape.kind != "plane" and not np.all(dims > 0):
                raise ValueError(f"body {key}: {shape.kind} size must be positive, "
                                 f"got {shape.size!r}")
            if shape.kind == "plane":
                norm = float(np.linalg.norm(dims[:3]))
                if norm == 0:
                    raise ValueError(f"body {key}: plane normal is zero")
                dims = dims / norm
            return shape, gkind, dims, extra
        if shape.vertices is None:
            raise ValueError(f"body {key}: a {shape.kind} shape needs vertices")
        verts = np.ascontiguousarray(shape.vertices, dtype=np.float64).reshape(-1, 3)
        if not np.all(np.isfinite(verts)):
            raise ValueError(f"body {key}: {shape.kind} vertices must be finite")
        if gkind == _ode.GEOM_MESH:
            if shape.faces is None:
                raise ValueError(f"body {key}: a mesh shape needs faces")
            faces = np.ascontiguousarray(shape.faces, dtype=np.int64).reshape(-1, 3)
            if faces.size and (faces.min() < 0 or faces.max() >= len(verts)):
                raise ValueError(f"body {key}: mesh face index out of range "
                                 f"(0..{len(verts) - 1})")
            extra.update(vertices=verts, faces=faces.astype(np.uint32))
        else:
            try:
                hull = _hull(verts)
            except Exception as exc:  # scipy's QhullError for flat or too few points
                raise ValueError(f"body {key}: cannot build a convex hull: {exc}") from None
            extra.update(vertices=hull.points, faces=hull.triangles, planes=hull.planes,
                         polygons=hull.polygons)
        return shape, gkind, np.zeros(1), extra

    def add_static_plane(self, normal: tuple[float, float, float] = (0.0, 0.0, 1.0),
                         offset: float = 0.0, material: MaterialProps | None = None) -> None:
        """Keyless ground plane ``normal · x = offset`` (contacts report it as key -1)."""
        n = _vec(normal, 3, "plane normal")
        n /= np.linalg.norm(n)
        idx = self._material(material or MaterialProps())
        self._world.add_static_plane(n[0], n[1], n[2], float(offset), idx, 1, _ALL_BITS)

    def remove_body(self, key: int) -> None:
        """Remove a body; joints on it are removed with it."""
        self._world.remove_body(int(key))
        self._keys = None

    def body_count(self) -> int:
        return self._world.body_count()

    def set_pose(self, key: int, position: np.ndarray, orientation: np.ndarray) -> None:
        self._world.set_pose(int(key), _vec(position, 3, "position"),
                             _vec(orientation, 4, "orientation"))

    def set_velocity(self, key: int, linear: np.ndarray, angular: np.ndarray) -> None:
        lin = _vec(linear, 3, "linear velocity")
        ang = _vec(angular, 3, "angular velocity")
        _check_speed(key, lin, ang)
        self._world.set_velocity(int(key), lin, ang)

    def set_kinematic_target(self, key: int, position: np.ndarray,
                             orientation: np.ndarray, dt: float) -> None:
        """Give the body the velocities that carry it to the target pose in ``dt``."""
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt}")
        pos, quat = self._world.pose(int(key))
        target = _vec(position, 3, "position")
        q = _vec(orientation, 4, "orientation")
        q /= np.linalg.norm(q)
        lin, ang = (target - pos) / dt, rotation_vector_between(quat, q) / dt
        _check_speed(key, lin, ang)
        self._world.set_velocity(int(key), lin, ang)

    def add_force(self, key: int, force: np.ndarray, point: np.ndarray | None = None) -> None:
        f = _vec(force, 3, "force")
        p = None if point is None else _vec(point, 3, "point")
        self._world.add_force(int(key), f[0], f[1], f[2], p)

    def add_torque(self, key: int, torque: np.ndarray) -> None:
        t = _vec(torque, 3, "torque")
        self._world.add_torque(int(key), t[0], t[1], t[2])

    def add_impulse(self, key: int, impulse: np.ndarray,
                    point: np.ndarray | None = None) -> None:
        """Deliver ``impulse`` (N·s) over the next step, assumed as long as the last one."""
        j = _vec(impulse, 3, "impulse")
        p = None if point is None else _vec(point, 3, "point")
        self._world.add_impulse(int(key), j[0], j[1], j[2], p)

    def set_sleeping(self, key: int, sleeping: bool) -> None:
        self._world.set_sleeping(int(key), bool(sleeping))

    def is_sleeping(self, key: int) -> bool:
        return self._world.is_sleeping(int(key))

    def sleeping_count(self) -> int:
        return self._world.sleeping_count()

    def sleep_states(self) -> dict[int, SleepState]:
        """Auto-sleep state of every moving body that is not fresh (awake, nothing counted)."""
        keys, asleep, idle, counts, samples = self._world.sleep_states()
        busy = np.flatnonzero(asleep | (idle != 0) | (counts != 0))
        return {int(keys[i]): SleepState(bool(asleep[i]), int(idle[i]),
                                         samples[i, :counts[i]].copy())
                for i in busy.tolist()}

    def set_sleep_state(self, key: int, asleep: bool, idle_steps: int = 0,
                        samples: np.ndarray | None = None) -> None:
        """Restore a body's auto-sleep state, as :meth:`sleep_states` reported it."""
        rows = np.zeros((0, 6)) if samples is None else \
            np.ascontiguousarray(samples, dtype=np.float64).reshape(-1, 6)
        if not np.isfinite(rows).all():
            raise ValueError(f"body {key}: non-finite velocity samples")
        self._world.set_sleep_state(int(key), bool(asleep), int(idle_steps), rows)

    # -- joints ------------------------------------------------------------
    def add_joint(self, key: int, joint: Joint) -> None:
        """Create a joint from its component: anchor and axes are world-frame, with the
        bodies at ``joint.reference`` (the poses when it was first made) or where they are."""
        kind = _JOINT_KINDS.get(joint.kind)
        if kind is None:
            raise ValueError(f"joint {joint.id or key}: unknown kind {joint.kind!r} "
                             f"(expected one of {', '.join(_JOINT_KINDS)})")
        if joint.broken:
            self._inert_joints.add(int(key))
            return
        axis = _vec(joint.axis, 3, "joint axis")
        axis2 = _vec(joint.axis2, 3, "joint axis2")
        if kind not in (_ode.JOINT_BALL, _ode.JOINT_FIXED, _ode.JOINT_SIX_DOF) and \
                not np.linalg.norm(axis) > 0:
            raise ValueError(f"joint {joint.id or key}: axis is zero")
        ref_a = ref_b = None
        if joint.reference is not None:
            pose_a, pose_b = joint.reference
            ref_a = _vec(pose_a, 7, "joint reference pose of body_a")
            if pose_b is not None and joint.body_b is not None:
                ref_b = _vec(pose_b, 7, "joint reference pose of body_b")
        try:
            self._world.create_joint(
                int(key), kind, int(joint.body_a),
                None if joint.body_b is None else int(joint.body_b),
                _vec(joint.anchor, 3, "joint anchor"), axis, axis2,
                joint.low, joint.high, float(joint.motor_velocity),
                float(joint.motor_max_force), ref_a, ref_b)
        except KeyError as exc:
            raise KeyError(f"joint {joint.id or key}: {exc.args[0]}") from None

    def remove_joint(self, key: int) -> None:
        if int(key) in self._inert_joints:
            self._inert_joints.discard(int(key))
            return
        self._world.remove_joint(int(key))

    def has_joint(self, key: int) -> bool:
        return self._world.has_joint(int(key)) or int(key) in self._inert_joints

    def set_motor(self, key: int, velocity: float, max_force: float) -> None:
        self._world.set_motor(int(key), float(velocity), float(max_force))

    def joint_state(self, key: int) -> tuple[float, float]:
        return self._world.joint_state(int(key))

    def set_joint_target(self, key: int, position: np.ndarray, orientation: np.ndarray,
                         max_force: float | None = None,
                         max_torque: float | None = None) -> None:
        """Move a ``six_dof`` joint's target pose (and optionally its force/torque bounds)."""
        self._world.set_target(int(key), _vec(position, 3, "target position"),
                               _vec(orientation, 4, "target orientation"),
                               -1.0 if max_force is None else float(max_force),
                               -1.0 if max_torque is None else float(max_torque))

    def set_drive_limits(self, key: int, max_force: float, max_torque: float) -> None:
        """Bound a ``six_dof`` joint's force (N) and torque (N·m), e.g. from a Hand."""
        self._world.set_drive_limits(int(key), float(max_force), float(max_torque))

    # -- batches -----------------------------------------------------------
    def read_state(self) -> BodyState:
        """Every body's pose and velocity (static ones included) in fresh arrays."""
        keys, table = self._world.read_state()
        return BodyState(keys, table)

    def read_poses(self, out: np.ndarray) -> None:
        """Fill ``out`` (N, 7) with x y z w x y z per body, in :meth:`keys` order, in C."""
        self._world.read_poses(out)

    def keys(self) -> np.ndarray:
        """Body keys in the row order of :meth:`read_state` and :meth:`read_poses`."""
        if self._keys is None:
            self._keys = self._world.keys()
        return self._keys

    def write_state(self, state: BodyState) -> None:
        """Set poses and velocities of the bodies named in ``state.keys``."""
        keys = np.asarray(state.keys, dtype=np.int64)
        mine = self.keys()
        if keys.shape == mine.shape and np.array_equal(keys, mine):
            slots = np.arange(len(keys), dtype=np.int64)
        else:
            slots = self._world.slots_for(keys)
        n = len(keys)

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
        self._world.write_state(slots, rows(state.position, 3, "position"),
                                rows(state.orientation, 4, "orientation"), lin, ang)

    def contacts(self) -> np.ndarray:
        return self._world.contacts().view(CONTACT_DTYPE)

    def take_faults(self) -> list[tuple[int, str]]:
        """Bodies reset since the last call, as (key, reason); the list is then cleared."""
        faults, self._faults = self._faults, []
        return faults

    # -- queries -----------------------------------------------------------
    def raycast(self, origin: np.ndarray, direction: np.ndarray, max_distance: float,
                ignore: int | None = None, mask: int = _ALL_BITS) -> RayHit | None:
        """Closest hit along the ray, skipping body ``ignore`` and categories outside ``mask``."""
        o = _vec(origin, 3, "ray origin")
        d = _vec(direction, 3, "ray direction")
        norm = float(np.linalg.norm(d))
        if norm == 0 or not max_distance > 0:
            return None
        d = d / norm
        hit = self._world.raycast(o[0], o[1], o[2], d[0], d[1], d[2], float(max_distance),
                                  -1 if ignore is None else int(ignore), mask & _ALL_BITS)
        if hit is None:
            return None
        key, pos, normal, dist = hit
        return RayHit(int(key), pos, normal, float(dist))


__all__ = ["OdeBackend"]
