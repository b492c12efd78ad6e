"""A collision-free backend: rigid bodies as free particles under gravity.

It implements the whole DynamicsBackend protocol with plain numpy and no
contacts or joints (each joint is refused once, with a warning, and calls that
drive it do nothing), which makes it
the cheapest deterministic backend for scheduler and tooling tests, and a
useful ``--backend ballistic`` for scenes of projectiles and flying objects.
"""

from __future__ import annotations

import logging

import numpy as np

from components import Joint, Physical
from components.physical import BodyKind
from engine.physics.backend import (
    ARRIVE_SLACK,
    CONTACT_DTYPE,
    BackendName,
    BodyState,
    RayHit,
    WorldSettings,
)
from engine.rotation import quat_multiply, quat_normalize, rotation_vector_between

log = logging.getLogger("colosseum.physics.ballistic")


def _integrate_orientation(q: np.ndarray, w: np.ndarray, dt: float) -> np.ndarray:
    """q' = q + dt/2 * (0, w) ⊗ q, renormalised; vectorised over rows."""
    spin = np.concatenate([np.zeros((len(w), 1)), w], axis=1)
    return quat_normalize(q + 0.5 * dt * quat_multiply(spin, q))


class BallisticBackend:
    name = BackendName.BALLISTIC

    def __init__(self) -> None:
        self.settings = WorldSettings()
        self._keys: list[int] = []
        self._index: dict[int, int] = {}
        self._pos = np.zeros((0, 3))
        self._quat = np.zeros((0, 4))
        self._vel = np.zeros((0, 3))
        self._ang = np.zeros((0, 3))
        self._force = np.zeros((0, 3))
        self._torque = np.zeros((0, 3))
        self._inv_mass = np.zeros(0)
        self._gravity_on = np.zeros(0)
        self._dynamic = np.zeros(0, bool)
        #: kinematic bodies on their way: key -> target position, orientation, s left
        self._targets: dict[int, tuple[np.ndarray, np.ndarray, float]] = {}
        self._refused_joints: set[int] = set()
        self._keys_array: np.ndarray | None = None  # cached, dropped on add/remove

    def configure(self, settings: WorldSettings) -> None:
        self.settings = settings

    def close(self) -> None:
        self._keys.clear()
        self._index.clear()

    # -- bodies ------------------------------------------------------------
    def add_body(self, key: int, body: Physical, position: np.ndarray, orientation: np.ndarray,
                 linear_velocity: np.ndarray | None = None,
                 angular_velocity: np.ndarray | None = None) -> None:
        if key in self._index:
            raise ValueError(f"body {key} already exists")
        dynamic = body.kind == BodyKind.DYNAMIC
        mass = body.mass if body.mass else 1.0
        self._index[key] = len(self._keys)
        self._keys.append(key)
        self._pos = np.vstack([self._pos, np.asarray(position, float).reshape(1, 3)])
        self._quat = np.vstack([self._quat, np.asarray(orientation, float).reshape(1, 4)])
        zero = np.zeros(3)
        lin = zero if linear_velocity is None else linear_velocity
        ang = zero if angular_velocity is None else angular_velocity
        self._vel = np.vstack([self._vel, np.asarray(lin, float).reshape(1, 3)])
        self._ang = np.vstack([self._ang, np.asarray(ang, float).reshape(1, 3)])
        self._force = np.vstack([self._force, np.zeros((1, 3))])
        self._torque = np.vstack([self._torque, np.zeros((1, 3))])
        self._inv_mass = np.append(self._inv_mass, 1.0 / mass if dynamic else 0.0)
        self._gravity_on = np.append(self._gravity_on, 1.0 if dynamic and body.gravity else 0.0)
        self._dynamic = np.append(self._dynamic, dynamic)
        self._keys_array = None
        if body.kind == BodyKind.STATIC:
            self._vel[-1] = 0.0
            self._ang[-1] = 0.0

    def remove_body(self, key: int) -> None:
        i = self._index.pop(key)
        self._keys.pop(i)
        for name in ("_pos", "_quat", "_vel", "_ang", "_force", "_torque",
                     "_inv_mass", "_gravity_on", "_dynamic"):
            setattr(self, name, np.delete(getattr(self, name), i, axis=0))
        self._index = {k: j for j, k in enumerate(self._keys)}
        self._targets.pop(key, None)
        self._keys_array = None

    def body_count(self) -> int:
        return len(self._keys)

    def set_pose(self, key: int, position: np.ndarray, orientation: np.ndarray) -> None:
        i = self._index[key]
        self._pos[i] = position
        self._quat[i] = orientation
        self._targets.pop(key, None)

    def set_velocity(self, key: int, linear: np.ndarray, angular: np.ndarray) -> None:
        i = self._index[key]
        self._vel[i] = linear
        self._ang[i] = angular
        self._targets.pop(key, None)

    def set_kinematic_target(self, key: int, position: np.ndarray, orientation: np.ndarray,
                             dt: float) -> None:
        """Velocities that carry the body to the target in ``dt``; a kinematic one stops
        there (exactly at it) unless told otherwise first."""
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt}")
        i = self._index[key]
        target = np.asarray(position, float)
        turn = np.asarray(orientation, float)
        turn = turn / np.linalg.norm(turn)
        self.set_velocity(key, (target - self._pos[i]) / dt,
                          rotation_vector_between(self._quat[i], turn) / dt)
        if not self._dynamic[i]:
            self._targets[key] = (target, turn, float(dt))

    def add_force(self, key: int, force: np.ndarray, point: np.ndarray | None = None) -> None:
        i = self._index[key]
        self._force[i] += force
        if point is not None:
            self._torque[i] += np.cross(np.asarray(point) - self._pos[i], force)

    def add_torque(self, key: int, torque: np.ndarray) -> None:
        self._torque[self._index[key]] += torque

    def add_impulse(self, key: int, impulse: np.ndarray, point: np.ndarray | None = None) -> None:
        i = self._index[key]
        self._vel[i] += np.asarray(impulse) * self._inv_mass[i]

    def set_sleeping(self, key: int, sleeping: bool) -> None:
        if sleeping:
            self.set_velocity(key, np.zeros(3), np.zeros(3))

    def set_collision_enabled(self, key: int, enabled: bool) -> None:
        """Particles collide with nothing either way; an unknown key is still refused."""
        if key not in self._index:
            raise KeyError(f"no body with key {key}")

    def set_gravity_enabled(self, key: int, enabled: bool) -> None:
        i = self._index[key]
        self._gravity_on[i] = 1.0 if enabled and self._dynamic[i] else 0.0

    # -- joints ------------------------------------------------------------
    def add_joint(self, key: int, joint: Joint) -> None:
        log.warning("joint %s (%s) ignored: the ballistic backend has no constraints",
                    joint.id or key, joint.kind)
        self._refused_joints.add(key)

    def remove_joint(self, key: int) -> None:
        self._refused(key)
        self._refused_joints.discard(key)

    def _refused(self, key: int) -> None:
        """Calls on a refused joint do nothing; on an unknown one they fail as elsewhere."""
        if key not in self._refused_joints:
            raise KeyError(f"no joint with key {key}")

    def set_motor(self, key: int, velocity: float, max_force: float) -> None:
        self._refused(key)

    def set_servos(self, keys: np.ndarray, table: np.ndarray) -> None:
        for key in np.asarray(keys).tolist():
            self._refused(key)

    def joint_state(self, key: int) -> tuple[float, float]:
        self._refused(key)
        return (0.0, 0.0)

    def joint_force(self, key: int) -> np.ndarray:
        self._refused(key)
        return np.zeros(3)

    def set_joint_target(self, key: int, position: np.ndarray, orientation: np.ndarray,
                         max_force: float | None = None,
                         max_torque: float | None = None) -> None:
        self._refused(key)

    def set_drive_limits(self, key: int, max_force: float, max_torque: float,
                         time_constant: float | None = None, max_speed: float | None = None,
                         max_spin: float | None = None) -> None:
        self._refused(key)

    # -- stepping ----------------------------------------------------------
    def step(self, dt: float) -> None:
        if not self._keys:
            return
        for key, (_, _, left) in self._targets.items():  # due within this step: slow down
            if left < dt * (1.0 - ARRIVE_SLACK):
                i = self._index[key]
                self._vel[i] *= left / dt
                self._ang[i] *= left / dt
        g = np.asarray(self.settings.gravity, float)
        accel = self._force * self._inv_mass[:, None] + g * self._gravity_on[:, None]
        self._vel += accel * dt
        self._pos += self._vel * dt
        self._quat = _integrate_orientation(self._quat, self._ang, dt)
        self._force[:] = 0.0
        self._torque[:] = 0.0
        for key, (position, orientation, left) in list(self._targets.items()):
            left -= dt
            if left > dt * ARRIVE_SLACK:
                self._targets[key] = (position, orientation, left)
                continue
            del self._targets[key]  # due in this step: exactly there, at rest
            i = self._index[key]
            self._pos[i] = position
            self._quat[i] = orientation
            self._vel[i] = 0.0
            self._ang[i] = 0.0

    # -- batches -----------------------------------------------------------
    def read_state(self) -> BodyState:
        return BodyState.from_arrays(np.array(self._keys, np.int64), self._pos, self._quat,
                                     self._vel, self._ang)

    def read_state_into(self, out: np.ndarray) -> np.ndarray:
        n = len(self._keys)
        if out.shape[0] < n or out.shape[1:] != (13,):
            raise ValueError(f"read_state_into needs an array of at least ({n}, 13), "
                             f"got {out.shape}")
        out[:n, 0:3] = self._pos
        out[:n, 3:7] = self._quat
        out[:n, 7:10] = self._vel
        out[:n, 10:13] = self._ang
        if self._keys_array is None:
            self._keys_array = np.array(self._keys, np.int64)
            self._keys_array.setflags(write=False)
        return self._keys_array

    def write_state(self, state: BodyState) -> None:
        rows = np.array([self._index[int(k)] for k in state.keys], np.int64)
        for key in np.asarray(state.keys).tolist():  # put where it says: no longer on its way
            self._targets.pop(key, None)
        self._pos[rows] = state.position
        self._quat[rows] = state.orientation
        self._vel[rows] = state.linear_velocity
        self._ang[rows] = state.angular_velocity

    def contacts(self) -> np.ndarray:
        return np.zeros(0, CONTACT_DTYPE)

    def overlapping(self, key: int) -> list[int]:
        """Particles have no extent: nothing ever overlaps."""
        if key not in self._index:
            raise KeyError(f"no body with key {key}")
        return []

    def raycast(self, origin: np.ndarray, direction: np.ndarray, max_distance: float,
                ignore: int | None = None, mask: int = 0xFFFFFFFF) -> RayHit | None:
        return None  # particles have no extent: a ray never hits one
