"""The physics driver: owns a dynamics backend and enforces the threading contract.

Serial mode: the main thread calls :meth:`PhysicsDriver.step` in the FIXED
phase. Threaded mode: a physics thread owns the backend and loops
*apply commands → step → publish snapshot* under its own real-time controller;
the main thread only :meth:`push`-es commands and reads :attr:`snapshot`.

A :class:`Snapshot` is built from fresh arrays, frozen, and published by one
reference assignment, so every pose in it comes from the same step and readers
never see it change. Contacts accumulate between frames and are handed over
whole by :meth:`take_contacts`.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any

import numpy as np

from engine.physics.backend import CONTACT_DTYPE, BodyState, DynamicsBackend, SupportsFaults
from engine.realtime import Pacing, RealTimeController

log = logging.getLogger("colosseum.physics")

Command = Callable[[DynamicsBackend], Any]


@dataclass(frozen=True, slots=True)
class Snapshot:
    """Physics state after one step; immutable once published."""

    step: int
    time: float
    bodies: BodyState


EMPTY_SNAPSHOT = Snapshot(0, 0.0, BodyState.empty().freeze())


class PhysicsThreadError(RuntimeError):
    pass


class PhysicsDriver:
    def __init__(self, backend: DynamicsBackend, mode: str = "serial",
                 pacing: Pacing | None = None,
                 clock: Callable[[], float] = time.perf_counter) -> None:
        if mode not in ("serial", "threaded"):
            raise ValueError(f"mode must be 'serial' or 'threaded', not {mode!r}")
        self.backend = backend
        self._reports_faults = isinstance(backend, SupportsFaults)
        self.mode = mode
        self.clock = clock
        self.snapshot: Snapshot = EMPTY_SNAPSHOT
        self.steps = 0
        self.time = 0.0
        self.controller = RealTimeController(pacing or Pacing(), clock=clock)
        self._commands: deque[tuple[Command, Future | None]] = deque()
        self._contacts: list[np.ndarray] = []
        self._faults: list[tuple[int, str]] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        #: Simulated time at which the physics thread stops stepping (None: never).
        self.stop_at: float | None = None
        self.error: BaseException | None = None
        self.closed = False

    # -- commands (any thread) ---------------------------------------------
    def push(self, command: Command) -> None:
        """Queue a call on the backend, applied between two steps."""
        self._commands.append((command, None))

    def request(self, command: Command) -> Future:
        """Queue a call whose result is wanted (e.g. a ray cast); serial runs it now."""
        future: Future = Future()
        if self.mode == "serial" or self._thread is None:
            self._apply_pending()
            self._run(command, future)
        else:
            self._commands.append((command, future))
        return future

    def _run(self, command: Command, future: Future | None) -> None:
        try:
            result = command(self.backend)
        except Exception as exc:  # a bad command must not take the physics down
            if future is not None:
                future.set_exception(exc)
            else:
                log.error("physics command %s failed: %s", getattr(command, "__qualname__",
                                                                    command), exc)
            return
        if future is not None:
            future.set_result(result)

    def _apply_pending(self) -> None:
        commands = self._commands
        while commands:
            command, future = commands.popleft()
            self._run(command, future)

    # -- stepping (owner thread) -------------------------------------------
    def step(self, dt: float, substeps: int = 1) -> float:
        """Apply queued commands, take ``substeps`` steps of ``dt/substeps``, publish.

        Returns the wall seconds spent stepping.
        """
        self._apply_pending()
        backend = self.backend
        h = dt / substeps
        spent = 0.0
        for _ in range(substeps):
            t0 = self.clock()
            backend.step(h)
            cost = self.clock() - t0
            spent += cost
            self.controller.record_step(cost)
            contacts = backend.contacts()
            self.steps += 1
            self.time += h
            faults = backend.take_faults() if self._reports_faults else ()
            if len(contacts) or faults:
                with self._lock:
                    if len(contacts):
                        self._contacts.append(contacts)
                    self._faults.extend(faults)
        self.snapshot = Snapshot(self.steps, self.time, backend.read_state().freeze())
        return spent

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
                if self.stop_at is not None and self.time >= self.stop_at - 1e-9:
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
    def close(self, timeout: float = 5.0) -> None:
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

    def _close_backend(self) -> None:
        try:
            self.backend.close()
        except Exception:
            log.exception("closing the %s backend failed", getattr(self.backend, "name", "?"))
