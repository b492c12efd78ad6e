"""The real-time controller (paper section 3.7).

A *tick* advances the simulation by Δts. When the work of a tick takes less
wall time than Δts, the controller sleeps the rest (``early="sleep"``) or
spends it on more, smaller substeps next tick (``early="substep"``). When the
work takes longer, the simulation runs in slow motion (``late="slowmo"``) or Δts
grows toward the measured cost, bounded by ``max_dt`` (``late="grow"``). An
unpaced controller (``--fast``) never sleeps and never changes Δts. The
real-time factor and per-step costs are always measured.

The clock and sleep functions are injectable so pacing can be tested exactly.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


def advance(clock: float, dt: float) -> float:
    """``clock + dt``, kept on the step grid: a clock stepping a fixed ``dt`` reads ``k*dt``
    (one rounding) rather than the noise of k additions (3.9999999999999587 after 400
    steps of 0.01), so times print and save as 4.0, and a run resumed from a saved time
    reads the same times as the run that never stopped. Off the grid (a grown step) it is
    the plain sum.

    >>> t = 0.0
    >>> for _ in range(400):
    ...     t = advance(t, 0.01)
    >>> t, sum([0.01] * 400)
    (4.0, 3.9999999999999587)
    """
    total = clock + dt
    on_grid = round(total / dt) * dt
    return on_grid if abs(total - on_grid) <= 4 * math.ulp(total) else total


@dataclass(slots=True)
class Pacing:
    dt: float = 1.0 / 60.0
    paced: bool = True
    early: str = "sleep"  # "sleep" | "substep"
    late: str = "slowmo"  # "slowmo" | "grow"
    max_dt: float = 1.0 / 20.0
    substeps: int = 1
    max_substeps: int = 8

    def __post_init__(self) -> None:
        if self.early not in ("sleep", "substep"):
            raise ValueError(f"early policy must be 'sleep' or 'substep', not {self.early!r}")
        if self.late not in ("slowmo", "grow"):
            raise ValueError(f"late policy must be 'slowmo' or 'grow', not {self.late!r}")
        if not self.dt > 0 or self.max_dt < self.dt:
            raise ValueError("need 0 < dt <= max_dt")


@dataclass(frozen=True, slots=True)
class Tick:
    dt: float  # simulated seconds this tick advances
    substeps: int

    @property
    def substep_dt(self) -> float:
        return self.dt / self.substeps


class CostLog:
    """A growable float log with cheap mean and percentiles."""

    def __init__(self) -> None:
        self._data = np.zeros(1024)
        self.count = 0

    def add(self, value: float) -> None:
        if self.count == len(self._data):
            self._data = np.concatenate([self._data, np.zeros(len(self._data))])
        self._data[self.count] = value
        self.count += 1

    def mean(self) -> float:
        return float(self._data[: self.count].mean()) if self.count else 0.0

    def percentile(self, q: float) -> float:
        return float(np.percentile(self._data[: self.count], q)) if self.count else 0.0


class RealTimeController:
    """Paces ticks against a wall clock and measures the real-time factor."""

    def __init__(self, pacing: Pacing, clock: Callable[[], float] = time.perf_counter,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        self.pacing = pacing
        self.clock = clock
        self.sleep = sleep
        self.dt = pacing.dt
        self.substeps = pacing.substeps
        self.sim_time = 0.0
        self.step_costs = CostLog()  # seconds per physics substep
        self.tick_costs = CostLog()  # seconds of work per tick
        self.slept = 0.0
        self._start: float | None = None
        self._tick_start = 0.0
        self._deadline = 0.0

    def begin(self) -> Tick:
        now = self.clock()
        if self._start is None:
            self._start = now
            self._deadline = now
        self._tick_start = now
        return Tick(self.dt, self.substeps)

    def record_step(self, seconds: float) -> None:
        """Report the wall time of one physics substep."""
        self.step_costs.add(seconds)

    def end(self, tick: Tick, physics_seconds: float | None = None) -> None:
        """Close a tick: account simulated time, then sleep or adapt."""
        now = self.clock()
        work = now - self._tick_start
        self.tick_costs.add(work)
        self.sim_time += tick.dt
        p = self.pacing
        if not p.paced:
            return
        self._deadline += tick.dt
        if work > tick.dt:
            if p.late == "grow":
                self.dt = min(p.max_dt, work)
            self._deadline = now  # slow motion: never try to catch up a debt
            return
        if p.late == "grow" and self.dt > p.dt:
            self.dt = max(p.dt, work)
        if p.early == "substep" and physics_seconds is not None and physics_seconds > 0:
            per_step = physics_seconds / tick.substeps
            other = work - physics_seconds
            fit = int((tick.dt - other) / per_step)
            self.substeps = max(p.substeps, min(p.max_substeps, fit))
        wait = self._deadline - now
        if wait > 0:
            self.sleep(wait)
            self.slept += wait
        else:
            self._deadline = now

    @property
    def wall_time(self) -> float:
        return 0.0 if self._start is None else self.clock() - self._start

    @property
    def real_time_factor(self) -> float:
        wall = self.wall_time
        return self.sim_time / wall if wall > 0 else 0.0
