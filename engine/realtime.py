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
from bisect import bisect_right
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


#: The fixed physics step (s): the one default, for a scene that names none (its
#: ``World { TimeStep }``) and an engine made without a scene alike.
TIME_STEP = 0.01
#: The steps a scene or ``--dt`` may ask for (s): past the upper one a step jumps whole
#: seconds (``TimeStep 10`` ran 3,000 simulated seconds in 300 frames); above
#: ``STEP_WARNING`` contacts and joints lose accuracy, which is told as a warning.
STEP_RANGE = (0.0, 1.0)
STEP_WARNING = 0.05


@dataclass(slots=True)
class Pacing:
    dt: float = TIME_STEP
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


def _linear_percentile(values: np.ndarray, q: float) -> float:
    """``np.percentile`` (its linear method) by a sort: the first np.percentile of a process
    imports numpy.ma, tens of milliseconds a one-frame run would spend on its statistics.

    >>> data = np.array([3.0, 1.0, 4.0, 1.0, 5.0])
    >>> [_linear_percentile(data, q) == float(np.percentile(data, q)) for q in (0, 37.5, 99, 100)]
    [True, True, True, True]
    """
    ordered = np.sort(values)
    rank = q / 100.0 * (len(ordered) - 1)
    below = min(int(rank), len(ordered) - 1)
    a, b = float(ordered[below]), float(ordered[min(below + 1, len(ordered) - 1)])
    share = rank - below
    # numpy's lerp: from the nearer end, so 100 % gives the largest value to the bit
    return b - (b - a) * (1.0 - share) if share >= 0.5 else a + (b - a) * share


class CostLog:
    """Costs (s) with a cheap mean and percentiles, in memory that does not grow.

    The first :attr:`EXACT` values are kept as they are (percentiles exact); after
    that every value is counted in a histogram of log-spaced bins, 100 a decade from
    1 ns to 1000 s (a percentile within 2.3 %), and the mean stays exact. A run of a
    week holds as much as a run of a minute.

    >>> log = CostLog()
    >>> for ms in range(1, 10_001):
    ...     log.add(ms / 1000)
    >>> round(log.mean(), 4), abs(log.percentile(50) / 5.0 - 1) < 0.023
    (5.0005, True)
    """

    #: Values kept exactly before the histogram takes over.
    EXACT = 4096
    #: The histogram's bin edges (s): 100 a decade.
    EDGES = np.geomspace(1e-9, 1e3, 1201)
    _EDGE_LIST = EDGES.tolist()

    def __init__(self) -> None:
        self._data = np.zeros(self.EXACT)
        self._bins: np.ndarray | None = None
        self.count = 0
        self.total = 0.0

    def add(self, value: float) -> None:
        if self.count < self.EXACT:
            self._data[self.count] = value
        else:
            if self._bins is None:
                self._bins = np.bincount(np.searchsorted(self.EDGES, self._data, "right"),
                                         minlength=len(self.EDGES) + 1)
            self._bins[bisect_right(self._EDGE_LIST, value)] += 1
        self.count += 1
        self.total += value

    def mean(self) -> float:
        return self.total / self.count if self.count else 0.0

    def percentile(self, q: float) -> float:
        if not self.count:
            return 0.0
        if self._bins is None:
            return _linear_percentile(self._data[: self.count], q)
        rank = q / 100.0 * (self.count - 1)
        cumulative = np.cumsum(self._bins)
        i = int(np.searchsorted(cumulative, rank, "right"))
        edges = self.EDGES
        if i == 0:
            return float(edges[0])
        if i >= len(edges):
            return float(edges[-1])
        below = cumulative[i - 1]
        share = (rank - below) / self._bins[i]  # where in the bin, by rank
        return float(edges[i - 1] * (edges[i] / edges[i - 1]) ** share)


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
