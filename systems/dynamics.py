"""The physics plugin: it owns the dynamics backend and keeps the ECS and the backend in step.

:class:`DynamicsPlugin` creates the backend the configuration names, wraps it in a
:class:`~engine.physics.driver.PhysicsDriver` and makes that the engine's
``physics``; a process without it (a network client) runs scripts and rendering
with no local physics. :class:`DynamicsSystem` then, on the main thread:

* turns Physical and Joint components into commands as soon as they are added
  (a body without a Transform yet waits for the FIXED phase), so commands queued
  after a spawn always find their body;
* detects writes to a physical body's Transform (a Python system moving a box,
  even by rebinding ``t.position``) and turns them into SetPose/SetVelocity
  commands before the step, instead of letting the readback overwrite them;
* steps the backend (serial mode) or picks up the physics thread's latest
  snapshot (threaded mode), and copies it into the pose table with one
  vectorised assignment, with no Python work per body.
"""

from __future__ import annotations

import logging
from collections import deque
from typing import TYPE_CHECKING

import numpy as np

from components import Joint, Name, Physical, Transform
from engine.events import BodyFault, Contacts
from engine.messages import MessageLog
from engine.physics import create_backend
from engine.physics.backend import BodyState, DynamicsBackend
from engine.physics.commands import (
    AddBody,
    AddJoint,
    CommandError,
    RemoveBody,
    RemoveJoint,
    SetPose,
    SetVelocity,
    check_limits,
)
from engine.physics.driver import PhysicsDriver, Snapshot
from engine.physics.naming import SceneNames, backend_loggers
from engine.system import Phase, PluginName, System
from engine.world import PoseTable, row_index
from systems.contacts import ContactEventsSystem

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.dynamics")

#: Frames a removed entity's scene ID is remembered, so late messages can still name it.
NAME_GRACE_FRAMES = 10


class DynamicsSystem(System):
    phase = Phase.FIXED
    reads = (Physical, Joint, Name)
    writes = (Transform,)

    def __init__(self, driver: PhysicsDriver) -> None:
        self.driver = driver
        self._new_bodies: list[tuple[int, Physical]] = []
        #: The snapshot the Transforms reflect now (newer ones may already exist in
        #: threaded mode; systems wanting a consistent view read this one).
        self.snapshot: Snapshot | None = None
        self._copy: PoseCopy | None = None
        self._names: dict[int, str] = {}
        self._forget: deque[tuple[int, int]] = deque()
        self._moved: set[int] = set()  # entities already told their Transform write is taken
        #: Teleports on their way to the physics thread: entity -> (the driver's pushed
        #: count once sent, the row written); a snapshot older than that keeps the row.
        self._in_flight: dict[int, tuple[int, np.ndarray]] = {}
        #: Bodies sent but in no snapshot yet: entity -> the row they were sent with (a
        #: Transform written before the first readback is a teleport too).
        self._unsynced: dict[int, np.ndarray] = {}
        self.messages = MessageLog(log)
        driver.names = self._names
        self._scene_names = SceneNames(self._names)  # backends' "body 7" -> "object 'crate'"

    @property
    def contacts_total(self) -> int:
        """Contacts reported since the start (every step's, in either mode)."""
        return self.driver.contacts_total

    def setup(self, engine: Engine) -> None:
        world = engine.world
        names = self._names
        world.on_add(Name, lambda e, n: names.__setitem__(e, n.id))
        world.on_remove(Name, lambda e, n: self._forget.append((engine.frame, e)))
        world.on_add(Physical, lambda e, c: self._add_body(engine, e, c))
        world.on_add(Joint, lambda e, c: self._push_joint(e, c))
        world.on_remove(Physical, lambda e, c: self._remove_body(e))
        world.on_remove(Joint, lambda e, c: self.driver.push(RemoveJoint(e)))
        for entity, name in world.get_component(Name):
            names[entity] = name.id
        self._scene_names.install(backend_loggers())
        # in the order they were made (esper's sets iterate in hash order), so a solver
        # that depends on constraint order sees the same world however it was built
        for entity, physical in sorted(world.get_component(Physical), key=_first):
            self._add_body(engine, entity, physical)
        for entity, joint in sorted(world.get_component(Joint), key=_first):
            self._push_joint(entity, joint)

    def shutdown(self, engine: Engine) -> None:
        self.messages.flush()
        self._scene_names.uninstall()

    # -- ECS -> backend ---------------------------------------------------------
    def _add_body(self, engine: Engine, entity: int, physical: Physical,
                  waited: bool = False) -> None:
        """Queue the body at once, so commands queued after the spawn find it."""
        t = engine.world.try_component(entity, Transform)
        if t is None and not waited:  # a Transform may follow with add_component: wait
            self._new_bodies.append((entity, physical))
            return
        t = t or Transform()
        try:
            self.driver.push(AddBody(entity, physical, t.position, t.orientation,
                                     t.linear_velocity, t.angular_velocity))
        except CommandError as exc:
            self.messages.error(f"{self.driver.describe(entity)} has no body: {exc}")
            return
        self._unsynced[entity] = np.concatenate([t.position, t.orientation,
                                                 t.linear_velocity, t.angular_velocity])

    def _push_joint(self, entity: int, joint: Joint) -> None:
        try:
            self.driver.push(AddJoint(entity, joint))
        except CommandError as exc:
            self.messages.error(f"{self.driver.describe(entity, joint=True)} is not made: {exc}")

    def _remove_body(self, entity: int) -> None:
        self._unsynced.pop(entity, None)
        self._in_flight.pop(entity, None)
        if any(pair[0] == entity for pair in self._new_bodies):  # never reached the backend
            self._new_bodies = [pair for pair in self._new_bodies if pair[0] != entity]
            return
        self.driver.push(RemoveBody(entity))

    def _send_new(self, engine: Engine) -> None:
        bodies, self._new_bodies = self._new_bodies, []
        for entity, physical in bodies:
            self._add_body(engine, entity, physical, waited=True)

    # -- per frame ----------------------------------------------------------------
    def run(self, engine: Engine, dt: float) -> None:
        driver = self.driver
        self._send_new(engine)
        self._forget_names(engine.frame)
        if self._unsynced:
            self._take_unsynced_writes(engine)
        if self._copy is not None and len(self._copy.synced_keys):
            self._take_transform_writes(engine)
        driver.teleported.clear()
        if engine.config.mode == "serial":  # the frame's dt, in its substeps
            engine.physics_seconds = driver.step(dt, engine.tick.substeps)
        else:
            driver.start()  # after the first bodies are queued; no-op once running
        snapshot = driver.snapshot
        if snapshot is not self.snapshot:
            self._sync(engine, snapshot)
        contacts = driver.take_contacts()
        if len(contacts):
            engine.events.emit(Contacts(contacts))
        for key, message in driver.take_faults():
            self.messages.warn(f"{driver.describe(key)}: {message}")
            engine.events.emit(BodyFault(key, message))

    def _take_transform_writes(self, engine: Engine) -> None:
        """Transforms of bodies written since the last sync become teleports."""
        assert self._copy is not None
        copy, driver = self._copy, self.driver
        written = copy.changed()
        keys = copy.synced_keys
        for i in written.tolist():
            entity = int(keys[i])
            row = copy.row(i)
            if entity in driver.teleported or self._teleport(engine, entity, row,
                                                             copy.synced[i]):
                copy.taken[i] = row.copy()
                self._in_flight[entity] = (driver.pushed, copy.taken[i])

    def _take_unsynced_writes(self, engine: Engine) -> None:
        """Transforms written between a body's AddBody and its first readback."""
        table, row_of = engine.world.poses.table, engine.world.poses.row_of
        for entity, sent in self._unsynced.items():
            at = row_of.get(entity)
            if at is None or (table[at] == sent).all():
                continue
            row = table[at]
            if entity in self.driver.teleported or self._teleport(engine, entity, row, sent):
                self._unsynced[entity] = row.copy()
                self._in_flight[entity] = (self.driver.pushed, self._unsynced[entity])

    def _teleport(self, engine: Engine, entity: int, row: np.ndarray,
                  before: np.ndarray) -> bool:
        """Push what was written; a value physics cannot take is undone (returns False)."""
        driver = self.driver
        try:
            commands = [SetPose(entity, row[0:3], row[3:7])] if (row[:7] != before[:7]).any() \
                else []
            if (row[7:] != before[7:]).any():
                commands.append(SetVelocity(entity, row[7:10], row[10:13]))
            for command in commands:
                check_limits(command, driver.limits)
        except CommandError as exc:
            self.messages.error(f"{driver.describe(entity)}: its Transform was given a value "
                                f"physics cannot take ({exc}); the write is undone",
                                f"frame {engine.frame}: ")
            row[...] = before
            return False
        for command in commands:
            driver.push(command)
        if entity not in self._moved:
            self._moved.add(entity)
            log.info("frame %d: the Transform of %s was written; the body is moved there "
                     "(engine.physics.set_pose does this explicitly)", engine.frame,
                     driver.describe(entity))
        return True

    def _forget_names(self, frame: int) -> None:
        forget = self._forget
        while forget and forget[0][0] + NAME_GRACE_FRAMES <= frame:
            _, entity = forget.popleft()
            self._names.pop(entity, None)
            self._moved.discard(entity)

    def _sync(self, engine: Engine, snapshot: Snapshot) -> None:
        self.snapshot = snapshot
        bodies = snapshot.bodies
        poses = engine.world.poses
        if self._copy is None or not self._copy.fits(poses, bodies.keys):
            self._copy = PoseCopy(poses, bodies.keys)
        self._copy(bodies)
        if self._unsynced:
            unsynced = np.fromiter(self._unsynced, np.int64, len(self._unsynced))
            for entity in unsynced[np.isin(unsynced, bodies.keys)].tolist():
                del self._unsynced[entity]
        if self._in_flight:
            self._keep_in_flight(snapshot.applied)

    def _keep_in_flight(self, applied: int) -> None:
        """Rows written since this snapshot's step began (threaded: the physics thread was
        mid-step) stay as written until a snapshot holds their teleport, instead of
        showing the body where it was for a frame."""
        assert self._copy is not None
        copy = self._copy
        index = {int(k): i for i, k in enumerate(copy.synced_keys.tolist())}
        for entity, (sent, row) in list(self._in_flight.items()):
            i = index.get(entity)
            if sent <= applied or i is None:
                del self._in_flight[entity]
                continue
            copy.row(i)[...] = row
            copy.taken[i] = row


_NONE = np.zeros(0, np.intp)
_NO_ROWS = np.zeros((0, 13))


def _first(pair: tuple[int, object]) -> int:
    return pair[0]


class PoseCopy:
    """Writes state reads into the pose table, planned once per layout of bodies.

    A layout is the bodies' keys (in a state read's row order) and the table's
    version. Both tables share one row layout, so a copy is one assignment: into a
    kept view where the rows are one run. :attr:`synced` is what was written (the
    snapshot's rows), so :meth:`changed` finds the rows someone wrote since; rows whose
    writes were already taken (:attr:`taken`) count only if written again.
    """

    def __init__(self, poses: PoseTable, keys: np.ndarray) -> None:
        self.keys, self.version = keys, poses.version
        rows = poses.rows(keys)
        valid = rows >= 0
        self._valid = None if valid.all() else valid  # None: every body has a Transform
        self.synced_keys = keys if self._valid is None else keys[valid]
        self.synced: np.ndarray = _NO_ROWS  # set by the first copy, right after planning
        #: Synced-body index -> the row as last taken as a write (until the next copy).
        self.taken: dict[int, np.ndarray] = {}
        self._rows = row_index(rows[valid])
        self._poses = poses
        self._view = poses.table[self._rows] if isinstance(self._rows, slice) else None
        self._rows_now: tuple[int, np.ndarray] = (self.version, rows[valid])

    def fits(self, poses: PoseTable, keys: np.ndarray) -> bool:
        """Whether this plan still holds (a backend may hand out the same key array)."""
        return self.version == poses.version and self._poses is poses and (
            self.keys is keys or np.array_equal(self.keys, keys))

    def rows_now(self) -> np.ndarray:
        """Table rows of the synced bodies now (-1: no Transform any more); they move when
        entities come and go between a copy and the next."""
        version = self._poses.version
        if self._rows_now[0] != version:
            self._rows_now = (version, self._poses.rows(self.synced_keys))
        return self._rows_now[1]

    def changed(self) -> np.ndarray:
        """Indices (into :attr:`synced_keys`) of the rows written since the last copy."""
        if self._view is not None and self.version == self._poses.version:
            written = self._view != self.synced
            if not written.any():
                return _NONE
            found = np.flatnonzero(written.any(axis=1))
        else:
            rows = self.rows_now()
            kept = np.flatnonzero(rows >= 0)
            found = kept[(self._poses.table[rows[kept]] != self.synced[kept]).any(axis=1)]
        taken = self.taken
        if taken:
            found = np.array([i for i in found.tolist() if i not in taken
                              or (taken[i] != self.row(i)).any()], np.intp)
        return found

    def row(self, i: int) -> np.ndarray:
        """Synced body ``i``'s row of the table (a view)."""
        return self._poses.table[self.rows_now()[i]]

    def __call__(self, bodies: BodyState) -> None:
        """Body ``i`` (of those with a Transform) → its row."""
        source = bodies.table if self._valid is None else bodies.table[self._valid]
        self.synced = source
        self.taken.clear()
        if self._view is not None:
            self._view[...] = source
        else:
            self._poses.table[self._rows] = source


class DynamicsPlugin:
    """Physics: the backend named by ``config.backend`` (or the one given), its driver and
    the system that keeps the ECS in step with it."""

    name = PluginName.PHYSICS

    def __init__(self, backend: DynamicsBackend | None = None) -> None:
        self.backend = backend

    def build(self, engine: Engine) -> None:
        cfg = engine.config
        backend = self.backend or create_backend(cfg.backend)
        backend.configure(cfg.world)
        driver = PhysicsDriver(backend, cfg.mode, cfg.pacing(), clock=engine.clock,
                               limits=cfg.world.limits)
        engine.attach_physics(driver)
        system = DynamicsSystem(driver)
        engine.insert_resource(system)
        engine.add_system(system)
        engine.add_system(ContactEventsSystem())  # ContactBegan / ContactEnded
