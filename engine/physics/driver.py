"""The physics driver: owns a dynamics backend and enforces the threading contract.

Serial mode: the main thread calls :meth:`PhysicsDriver.step` in the FIXED
phase. Threaded mode: a physics thread owns the backend and loops
*apply commands → step → publish snapshot* under its own real-time controller;
the main thread only :meth:`push`-es commands and reads :attr:`snapshot`.

Commands are data (:mod:`engine.physics.commands`), applied by the one dispatch
:func:`apply`. A command whose body or joint does not exist yet waits a few steps
(a body spawned without a Transform reaches the backend in the next FIXED phase),
then is dropped with a message naming the object's scene ID. With :attr:`log`
set, everything applied and every step is recorded, so the run can be replayed
into a fresh backend or sent elsewhere.

A :class:`Snapshot` is built from fresh arrays, frozen, and published by one
reference assignment, so every pose in it comes from the same step and readers
never see it change. Contacts accumulate between frames and are handed over
whole by :meth:`take_contacts`.

A process without local physics (a network client) has no driver: the engine's
``physics`` is then a :class:`DetachedPhysics`, which keeps what is pushed for
whoever forwards it.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from engine.memory import paused_gc
from engine.messages import MessageLog
from engine.physics import commands as cmd
from engine.physics.backend import (
    CONTACT_DTYPE,
    BackendFailure,
    BodyState,
    DynamicsBackend,
    Limits,
    SupportsFaults,
)
from engine.physics.naming import named
from engine.realtime import Pacing, RealTimeController, advance

log = logging.getLogger("colosseum.physics")

R = TypeVar("R")

#: Steps a command waits for its body or joint to appear in the backend before it is dropped.
WAIT_STEPS = 3
#: Queued commands from which they are applied with the cyclic GC paused: a scene's bodies
#: made at once (10,000 of them met a full collection as often as not).
GC_BURST = 1000


def _vec(values: tuple[float, ...] | None) -> np.ndarray | None:
    return None if values is None else np.array(values)


#: The one dispatch: command type -> what it asks of the backend.
_APPLY: dict[type, Callable[[DynamicsBackend, Any], Any]] = {
    cmd.AddBody: lambda b, c: b.add_body(c.key, c.body, np.array(c.position),
                                         np.array(c.orientation), np.array(c.linear_velocity),
                                         np.array(c.angular_velocity)),
    cmd.RemoveBody: lambda b, c: b.remove_body(c.key),
    cmd.AddJoint: lambda b, c: b.add_joint(c.key, c.joint),
    cmd.RemoveJoint: lambda b, c: b.remove_joint(c.key),
    cmd.SetMotor: lambda b, c: b.set_motor(c.key, c.velocity, c.max_force),
    cmd.SetServos: lambda b, c: b.set_servos(c.keys, c.table),
    cmd.ApplyForce: lambda b, c: b.add_force(c.key, np.array(c.force), _vec(c.point)),
    cmd.ApplyTorque: lambda b, c: b.add_torque(c.key, np.array(c.torque)),
    cmd.ApplyImpulse: lambda b, c: b.add_impulse(c.key, np.array(c.impulse), _vec(c.point)),
    cmd.SetPose: lambda b, c: _set_pose(b, c),
    cmd.SetPoses: lambda b, c: b.write_state(BodyState(c.keys, c.table)),
    cmd.SetVelocity: lambda b, c: b.set_velocity(c.key, np.array(c.linear),
                                                 np.array(c.angular)),
    cmd.SetKinematicTarget: lambda b, c: b.set_kinematic_target(
        c.key, np.array(c.position), np.array(c.orientation), c.dt),
    cmd.SetCollisionEnabled: lambda b, c: b.set_collision_enabled(c.key, c.enabled),
    cmd.SetGravityEnabled: lambda b, c: b.set_gravity_enabled(c.key, c.enabled),
    cmd.SetSleeping: lambda b, c: b.set_sleeping(c.key, c.sleeping),
    cmd.SetSleepState: lambda b, c: _restore_sleep(b, c.key, c.state),
    cmd.SetJointTarget: lambda b, c: b.set_joint_target(
        c.key, np.array(c.position), np.array(c.orientation), c.max_force, c.max_torque),
    cmd.SetDriveLimits: lambda b, c: b.set_drive_limits(c.key, c.max_force, c.max_torque,
                                                         c.time_constant, c.max_speed,
                                                         c.max_spin),
    cmd.ConfigureWorld: lambda b, c: b.configure(c.settings),
}


def _set_pose(backend: DynamicsBackend, c: cmd.SetPose) -> None:
    backend.set_pose(c.key, np.array(c.position), np.array(c.orientation))
    if c.linear is not None:
        backend.set_velocity(c.key, np.array(c.linear), np.array(c.angular))


def apply(command: cmd.Command, backend: DynamicsBackend) -> Any:
    """Carry out one command on ``backend`` (the owner thread's job)."""
    return _APPLY[type(command)](backend, command)


def _restore_sleep(backend: DynamicsBackend, key: int, state: Any) -> None:
    """A saved auto-sleep state; a backend keeping no counters of its own just sleeps."""
    from engine.physics.backend import SupportsSleepState

    if isinstance(backend, SupportsSleepState):
        backend.set_sleep_state(key, state)
    elif state.asleep:
        backend.set_sleeping(key, True)


class _Tables:
    """Buffers for published states, each reused only once nothing refers to it any more.

    A published snapshot is therefore never written again, yet the steady state allocates
    nothing: two or three buffers take turns, and the backend writes its rows straight
    into one (``read_state_into``), warm in the cache, instead of into fresh memory.
    """

    #: Buffers kept; more are let go (a consumer held on to several snapshots).
    KEEP = 4

    def __init__(self) -> None:
        self._buffers: list[np.ndarray] = []

    def take(self, n: int) -> np.ndarray:
        """A writable (n, 13) table no published snapshot refers to."""
        for buf in self._buffers:
            # the list, this loop's name and getrefcount's argument: nobody else holds it
            if buf.shape[0] == n and sys.getrefcount(buf) == 3:
                buf.setflags(write=True)
                return buf
        # the layout changed, or every buffer is still held: keep the newest of this size
        self._buffers = [b for b in self._buffers if b.shape[0] == n][-(self.KEEP - 1):]
        fresh = np.empty((n, 13))
        self._buffers.append(fresh)
        return fresh


@dataclass(frozen=True, slots=True)
class Snapshot:
    """Physics state after one step; immutable once published."""

    step: int
    time: float
    bodies: BodyState
    #: Commands applied before this state (of those pushed: :attr:`PhysicsDriver.pushed`),
    #: so the main thread knows which of its teleports a snapshot already holds.
    applied: int = 0


EMPTY_SNAPSHOT = Snapshot(0, 0.0, BodyState.empty().freeze())


class PhysicsThreadError(RuntimeError):
    pass


class PhysicsUnavailable(RuntimeError):
    """A query needs a dynamics backend and this process runs none."""


class PhysicsPort:
    """What ``engine.physics`` offers the main thread, with or without a local backend."""

    mode = "serial"
    snapshot: Snapshot = EMPTY_SNAPSHOT
    steps = 0
    time = 0.0
    #: The main thread's frame number, stamped on messages (set by the engine each frame).
    frame = 0
    contacts_total = 0
    #: Simulated time at which a physics thread stops stepping (None: never).
    stop_at: float | None = None
    #: A physics thread waits while this is set (a headset taken off, as the scene says).
    paused = False
    controller: RealTimeController
    #: Scene IDs of entities, for messages (kept by the physics system).
    names: Mapping[int, str]
    #: Entities teleported through :meth:`set_pose` this frame (the physics system treats
    #: their Transform writes as done, not as writes to detect).
    teleported: set[int]
    #: The world's extent and speed limit every pushed command is checked against.
    limits: Limits = Limits()

    @property
    def backend_name(self) -> str:
        """The dynamics backend's name ("none" without local physics)."""
        backend = getattr(self, "backend", None)
        return getattr(backend, "name", "none") if backend is not None else "none"

    def push(self, command: cmd.Command) -> None:
        """Check ``command`` against this world's :attr:`limits` and queue it; a value the
        world cannot take raises :class:`~engine.physics.commands.CommandError` here, at
        the caller, with the checks made when the command was made."""
        if not isinstance(command, cmd.Command):
            raise TypeError(f"physics.push takes a command from engine.physics.commands, "
                            f"got {type(command).__name__}")
        cmd.check_limits(command, self.limits)
        self._enqueue(command)

    def _enqueue(self, command: cmd.Command) -> None:
        raise NotImplementedError

    def set_pose(self, entity: int, position: Any, orientation: Any) -> None:
        """Teleport a body (checked now: a bad value raises :class:`CommandError` here).

        This is the documented way to move a physical body; a plain write to its
        Transform does the same, detected before the next step.
        """
        self.push(cmd.SetPose(entity, position, orientation))
        self.teleported.add(entity)

    def set_velocity(self, entity: int, linear: Any, angular: Any) -> None:
        """Set a body's velocities (m/s, rad/s), checked now."""
        self.push(cmd.SetVelocity(entity, linear, angular))
        self.teleported.add(entity)

    def request(self, query: Callable[[DynamicsBackend], R]) -> Future:
        raise NotImplementedError

    def take_contacts(self) -> np.ndarray:
        return np.zeros(0, CONTACT_DTYPE)

    def take_faults(self) -> list[tuple[int, str]]:
        return []

    def check(self) -> None:
        """Raise on the main thread if physics failed elsewhere."""

    @property
    def running(self) -> bool:
        return False

    def close(self) -> None:
        """Stop physics; safe to call twice."""


class DetachedPhysics(PhysicsPort):
    """``engine.physics`` of a process without a dynamics backend (a network client, a
    tool): commands are checked and kept in :attr:`outbox` for whoever forwards them; a
    physics plugin loaded later takes them over."""

    #: Commands kept at most; older ones are dropped (and counted) when nobody drains them.
    LIMIT = 100_000

    def __init__(self, limits: Limits | None = None) -> None:
        self.controller = RealTimeController(Pacing())
        self.limits = limits or Limits()
        self.names: dict[int, str] = {}
        self.teleported: set[int] = set()
        self.outbox: deque[cmd.Command] = deque(maxlen=self.LIMIT)
        self.dropped = 0

    def _enqueue(self, command: cmd.Command) -> None:
        if len(self.outbox) == self.LIMIT:
            self.dropped += 1
        self.outbox.append(command)

    def request(self, query: Callable[[DynamicsBackend], R]) -> Future:
        future: Future = Future()
        future.set_exception(PhysicsUnavailable(
            "this engine runs no physics (the physics plugin is not loaded)"))
        return future


class PhysicsDriver(PhysicsPort):
    """Owns one backend; the engine's ``physics`` when the physics plugin is loaded."""

    def __init__(self, backend: DynamicsBackend, mode: str = "serial",
                 pacing: Pacing | None = None,
                 clock: Callable[[], float] = time.perf_counter,
                 names: Mapping[int, str] | None = None, limits: Limits | None = None) -> None:
        if mode not in ("serial", "threaded"):
            raise ValueError(f"mode must be 'serial' or 'threaded', not {mode!r}")
        self.backend = backend
        self.limits = limits or Limits()
        self._reports_faults = isinstance(backend, SupportsFaults)
        self.mode = mode
        self.clock = clock
        self.snapshot = EMPTY_SNAPSHOT
        self.steps = 0
        self.time = 0.0
        self.frame = 0
        self.controller = RealTimeController(pacing or Pacing(), clock=clock)
        self.names = names if names is not None else {}
        self.teleported = set()
        #: When set, every command applied and every step are recorded here.
        self.log: cmd.CommandLog | None = None
        self.messages = MessageLog(log)
        self.contacts_total = 0
        #: Commands and queries queued and applied (by the owner thread) so far.
        self.pushed = 0
        self.applied = 0
        self._commands: deque[tuple[cmd.Command | Callable[[DynamicsBackend], Any],
                                    Future | None]] = deque()
        self._waiting: list[tuple[cmd.Command, int]] = []
        self._tables = _Tables()
        self._contacts: list[np.ndarray] = []
        self._faults: list[tuple[int, str]] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.stop_at = None
        self.error: BaseException | None = None
        #: Why the backend cannot step any more (its library failed inside a step); the
        #: world is then frozen at its last state while the clock and the run go on.
        self.failed: str | None = None
        self.closed = False

    # -- commands (any thread) ---------------------------------------------
    def _enqueue(self, command: cmd.Command) -> None:
        """Queue a checked command; it is applied between two steps, in the order pushed."""
        self.pushed += 1
        self._commands.append((command, None))

    def request(self, query: Callable[[DynamicsBackend], R]) -> Future:
        """Run a read-only ``query(backend)`` on the owner thread (e.g. a ray cast); serial
        mode runs it now. Queries are not commands: they are not logged and must not change
        the world."""
        future: Future = Future()
        if self.failed is not None:
            future.set_exception(PhysicsUnavailable(f"physics stopped: {self.failed}"))
        elif self.mode == "serial" or self._thread is None:
            self._apply_pending()
            self._query(query, future)
        else:
            self.pushed += 1
            self._commands.append((query, future))
        return future

    def describe(self, key: int, joint: bool = False) -> str:
        """How messages name a body or joint: its scene ID when it has one."""
        if key < 0:
            return "the world"
        name = self.names.get(key)
        what = "joint" if joint else "object"
        return f"{what} {name!r}" if name else f"{what} (entity {key})"

    def _query(self, query: Callable[[DynamicsBackend], Any], future: Future) -> None:
        try:
            future.set_result(query(self.backend))
        except Exception as exc:
            future.set_exception(exc)

    def _run(self, command: cmd.Command, waited: int = 0) -> None:
        try:
            apply(command, self.backend)
        except KeyError:
            if waited < WAIT_STEPS:
                self._waiting.append((command, waited + 1))
            else:
                self.messages.warn(
                    f"{type(command).__name__} dropped: no "
                    f"{self.describe(command.key, command.on_joint)} in the physics world "
                    f"(not created yet, or removed)", f"frame {self.frame}: ")
            return
        except Exception as exc:  # a bad command must not take the physics down
            target = self.describe(command.key, command.on_joint)
            why = named(str(exc), self.names).removeprefix(f"{target}: ")
            self.messages.error(f"{type(command).__name__} on {target} failed: {why}",
                                f"frame {self.frame}: ")
            return
        if self.log is not None:
            self.log.record(command)

    def _apply_pending(self) -> None:
        commands = self._commands
        if len(commands) >= GC_BURST:  # a scene's bodies at once: long-lived, GC paused
            with paused_gc():
                self._apply(commands)
        else:
            self._apply(commands)

    def _apply(self, commands: deque) -> None:
        while commands:
            item, future = commands.popleft()
            self.applied += 1
            if future is None:
                self._run(item)  # type: ignore[arg-type]
            else:
                self._query(item, future)  # type: ignore[arg-type]

    def _retry_waiting(self) -> None:
        waiting, self._waiting = self._waiting, []
        for command, waited in waiting:
            self._run(command, waited)

    # -- stepping (owner thread) -------------------------------------------
    def step(self, dt: float, substeps: int = 1) -> float:
        """Apply queued commands, take ``substeps`` steps of ``dt/substeps``, publish.

        Returns the wall seconds spent stepping.
        """
        if self.failed is not None:
            return self._frozen(dt)
        self._apply_pending()
        if self._waiting:
            self._retry_waiting()
        backend = self.backend
        h = dt / substeps
        record = self.log.record if self.log is not None else None
        spent = 0.0
        for _ in range(substeps):
            t0 = self.clock()
            try:
                backend.step(h)
            except BackendFailure as exc:
                self._stop_physics(exc)
                return spent
            cost = self.clock() - t0
            if record is not None:
                record(cmd.Step(h))
            spent += cost
            self.controller.record_step(cost)
            contacts = backend.contacts()
            self.steps += 1
            self.time = advance(self.time, h)
            faults = backend.take_faults() if self._reports_faults else ()
            if len(contacts) or faults:
                with self._lock:
                    if len(contacts):
                        self._contacts.append(contacts)
                        self.contacts_total += len(contacts)
                    self._faults.extend(faults)
        table = self._tables.take(backend.body_count())
        keys = backend.read_state_into(table)
        self.snapshot = Snapshot(self.steps, self.time, BodyState(keys, table).freeze(),
                                 self.applied)
        return spent

    def _stop_physics(self, exc: BackendFailure) -> None:
        """The backend failed inside a step: say so once and freeze the world there."""
        self.failed = str(exc)
        self.messages.error(
            f"physics stopped at t = {self.time:.6g} s: the {self.backend_name} library "
            f"failed inside a step ({exc}). The world stays as it was; scripts, drawing and "
            "sound go on. The engine's checks should have kept this from the library: "
            "please report it with the scene", f"frame {self.frame}: ")

    def _frozen(self, dt: float) -> float:
        """A step of a stopped physics: the clock moves on, the world does not; commands
        are dropped (counted in one message) and queries fail."""
        dropped = 0
        while self._commands:
            item, future = self._commands.popleft()
            self.applied += 1
            if future is None:
                dropped += 1
            else:
                future.set_exception(PhysicsUnavailable(f"physics stopped: {self.failed}"))
        self._waiting.clear()
        if dropped:
            self.messages.warn("commands to the stopped physics are dropped")
        self.time = advance(self.time, dt)
        return 0.0

    # -- threaded mode ------------------------------------------------------
    def start(self) -> None:
        """Start the physics thread (threaded mode); it idles once ``stop_at`` is reached."""
        if self.mode != "threaded" or self._thread is not None:
            return
        self._thread = threading.Thread(target=self._loop, name="colosseum-physics",
                                        daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        ctl = self.controller
        try:
            while not self._stop.is_set():
                if self.paused or (self.stop_at is not None
                                   and self.time >= self.stop_at - 1e-9):
                    self._apply_pending()
                    self._stop.wait(0.001)
                    continue
                tick = ctl.begin()
                spent = self.step(tick.dt, tick.substeps)
                ctl.end(tick, spent)
                if not ctl.pacing.paced:
                    time.sleep(0)  # hand the GIL over between steps; the main thread needs it
        except BaseException as exc:
            self.error = exc
            log.exception("the physics thread stopped")
        finally:
            self._close_backend()

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def check(self) -> None:
        """Raise on the main thread if the physics thread died."""
        if self.error is not None:
            raise PhysicsThreadError(f"physics thread failed: {self.error!r}") from self.error

    # -- hand-over to the main thread ---------------------------------------
    def take_contacts(self) -> np.ndarray:
        with self._lock:
            batches, self._contacts = self._contacts, []
        if not batches:
            return np.zeros(0, CONTACT_DTYPE)
        return batches[0] if len(batches) == 1 else np.concatenate(batches)

    def take_faults(self) -> list[tuple[int, str]]:
        with self._lock:
            faults, self._faults = self._faults, []
        return faults

    # -- shutdown ----------------------------------------------------------
    def close(self, timeout: float = 5.0) -> None:  # type: ignore[override]
        if self.closed:
            return
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
            if self._thread.is_alive():
                log.error("the physics thread did not stop within %.1f s", timeout)
                return
        else:
            self._close_backend()
        self.closed = True
        self.messages.flush()

    def _close_backend(self) -> None:
        try:
            self.backend.close()
        except Exception:
            log.exception("closing the %s backend failed", getattr(self.backend, "name", "?"))
