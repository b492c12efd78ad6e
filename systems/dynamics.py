"""The dynamics system: Physical and Joint components ↔ the dynamics backend.

New bodies and joints are sent to the backend through the command queue as
soon as they are spawned (a body without a Transform yet waits for the FIXED
phase), so commands queued after a spawn always find their body. In serial
mode this system steps the backend; in threaded mode the physics thread does
and this system only picks up the latest snapshot. Either way, every Transform
is updated by one vectorised numpy assignment per array, with no Python work
per body.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import numpy as np

from components import Joint, Physical, Transform
from engine.events import BodyFault, Contacts
from engine.physics.backend import BodyState, DynamicsBackend
from engine.physics.driver import Snapshot
from engine.system import Phase, System
from engine.world import PoseTable, row_index

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.dynamics")


class DynamicsSystem(System):
    phase = Phase.FIXED
    reads = (Physical, Joint)
    writes = (Transform,)

    def __init__(self) -> None:
        self._new_bodies: list[tuple[int, Physical]] = []
        #: The snapshot the Transforms reflect now (newer ones may already exist in
        #: threaded mode; systems wanting a consistent view read this one).
        self.snapshot: Snapshot | None = None
        self._copy: PoseCopy | None = None
        self.contacts_total = 0

    def setup(self, engine: Engine) -> None:
        world = engine.world
        world.on_add(Physical, lambda e, c: self._add_body(engine, e, c))
        world.on_add(Joint, lambda e, c: engine.physics.push(_add_joint(e, c)))
        world.on_remove(Physical, lambda e, c: self._remove_body(engine, e))
        world.on_remove(Joint, lambda e, c: engine.physics.push(_remove_joint(e)))
        # in the order they were made (esper's sets iterate in hash order), so a solver
        # that depends on constraint order sees the same world however it was built
        for entity, physical in sorted(world.get_component(Physical), key=_first):
            self._add_body(engine, entity, physical)
        for entity, joint in sorted(world.get_component(Joint), key=_first):
            engine.physics.push(_add_joint(entity, joint))

    def _add_body(self, engine: Engine, entity: int, physical: Physical,
                  waited: bool = False) -> None:
        """Queue the body at once, so commands queued after the spawn find it."""
        t = engine.world.try_component(entity, Transform)
        if t is None and not waited:  # a Transform may follow with add_component: wait
            self._new_bodies.append((entity, physical))
        else:
            engine.physics.push(_add_body(entity, physical, t or Transform()))

    def _remove_body(self, engine: Engine, entity: int) -> None:
        if any(pair[0] == entity for pair in self._new_bodies):  # never reached the backend
            self._new_bodies = [pair for pair in self._new_bodies if pair[0] != entity]
            return
        engine.physics.push(_remove_body(entity))

    def _send_new(self, engine: Engine) -> None:
        bodies, self._new_bodies = self._new_bodies, []
        for entity, physical in bodies:
            self._add_body(engine, entity, physical, waited=True)

    def run(self, engine: Engine, dt: float) -> None:
        self._send_new(engine)
        physics = engine.physics
        if engine.config.mode == "serial":
            tick = engine.tick
            engine.physics_seconds = physics.step(tick.dt, tick.substeps)
        else:
            physics.start()  # after the first bodies are queued; no-op once running
        snapshot = physics.snapshot
        if snapshot is not self.snapshot:
            self._sync(engine, snapshot)
        contacts = physics.take_contacts()
        if len(contacts):
            self.contacts_total += len(contacts)
            engine.events.emit(Contacts(contacts))
        for key, message in physics.take_faults():
            log.warning("body %s: %s", key, message)
            engine.events.emit(BodyFault(key, message))

    def _sync(self, engine: Engine, snapshot: Snapshot) -> None:
        self.snapshot = snapshot
        bodies = snapshot.bodies
        poses = engine.world.poses
        if self._copy is None or not self._copy.fits(poses, bodies.keys):
            self._copy = PoseCopy(poses, bodies.keys)
        self._copy(bodies)


def _first(pair: tuple[int, object]) -> int:
    return pair[0]


class PoseCopy:
    """Writes state reads into the pose table, planned once per layout of bodies.

    A layout is the bodies' keys (in a state read's row order) and the table's
    version. Both tables share one row layout, so a copy is one assignment: into a
    kept view where the rows are one run and every body has a Transform.
    """

    def __init__(self, poses: PoseTable, keys: np.ndarray) -> None:
        self.keys, self.version = keys, poses.version
        rows = poses.rows(keys)
        valid = rows >= 0
        self._valid = None if valid.all() else valid  # None: every body has a Transform
        self._rows = row_index(rows[valid])
        self._poses = poses
        self._view = poses.table[self._rows] if (
            self._valid is None and isinstance(self._rows, slice)) else None

    def fits(self, poses: PoseTable, keys: np.ndarray) -> bool:
        """Whether this plan still holds (a backend may hand out the same key array)."""
        return self.version == poses.version and self._poses is poses and (
            self.keys is keys or np.array_equal(self.keys, keys))

    def __call__(self, bodies: BodyState) -> None:
        """Body ``i`` (of those with a Transform) → its row."""
        if self._view is not None:
            self._view[...] = bodies.table
        elif self._valid is None:
            self._poses.table[self._rows] = bodies.table
        else:
            self._poses.table[self._rows] = bodies.table[self._valid]


def _add_body(entity: int, physical: Physical, t: Transform):
    position = t.position.copy()
    orientation = t.orientation.copy()
    linear = t.linear_velocity.copy()
    angular = t.angular_velocity.copy()

    def add_body(backend: DynamicsBackend) -> None:
        backend.add_body(entity, physical, position, orientation, linear, angular)

    return add_body


def _remove_body(entity: int):
    def remove_body(backend: DynamicsBackend) -> None:
        backend.remove_body(entity)

    return remove_body


def _add_joint(entity: int, joint: Joint):
    def add_joint(backend: DynamicsBackend) -> None:
        backend.add_joint(entity, joint)

    return add_joint


def _remove_joint(entity: int):
    def remove_joint(backend: DynamicsBackend) -> None:
        backend.remove_joint(entity)

    return remove_joint


class DynamicsPlugin:
    name = "physics"

    def build(self, engine: Engine) -> None:
        system = DynamicsSystem()
        engine.insert_resource(system)
        engine.add_system(system)
