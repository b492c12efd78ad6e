"""Auto-sleep: one rule for every backend, run with numpy over the state table each step.

A body falls asleep when it has been *quiet* for ``SleepTime`` seconds in a row, and
its island (the bodies it touches or is jointed to, through moving bodies) with it.
Quiet is judged on the body's *smoothed* velocity (centre of mass, linear and
angular): an exponential average over ``SMOOTHING`` seconds. It averages only while
the body is calm (its average under the slow limits) and not at rest (its velocity
under a hundredth of them); otherwise the next step it snaps to the velocity itself:
after an impact or a throw there is nothing to smooth, and at rest the average would
only replay how the body got there. A body is quiet at the end of a step when it is

* slow: smoothed speed under ``SleepLinear`` and spin under ``SleepAngular``, and
* steady: its smoothed velocity is still within a tenth of those limits of the one it
  had when the quiet stretch began (the *reference*): it is not being accelerated.

Why these two tests. A pendulum at its turning point is slow, but the velocity it
gains while it swings back leaves the steady band within a fraction of a swing, so it
never stays quiet for long, at any amplitude, while a crate at rest, whose velocity
stopped changing, is quiet from the step it settles. The band is measured against one
reference, not from step to step, so the test reads the same at any Δt: a finite
difference ``Δv / Δt`` amplifies solver noise as Δt shrinks, and a count of steps
(ODE's own rule waits 20 steps with the mean of 5 samples under 0.05 m/s) waits less
the smaller Δt is and freezes a swing at its turning point. The smoothing is there
because an iterative solver never leaves a stack quite still: ODE's QuickStep makes a
stack of three 0.5 m boxes at Δt = 0.02 s jitter at up to 4 cm/s, which on raw
velocities is as lively as a 0.5° swing of a 1 m pendulum; the jitter is a few hertz,
the swing half a hertz, and averaging over a tenth of a second tells them apart.
Measured (the quietest half second of each, the smoothed velocity's largest change in
it): that stack 0.3 to 1.9 mm/s at Δt 0.02 to 0.01 s, the 0.5° pendulum 4.9 to
5.2 mm/s at any Δt from 0.001 to 0.02 s on both backends; the band is 3 mm/s.

The anchors, and why these defaults: Box2D sleeps an island after 0.5 s with every
body under 0.01 m/s and 2°/s; Jolt after 0.5 s with every point of a body staying
within 0.03 m/s × 0.5 s of where it was; Bullet after 2 s under 0.8 m/s and 1 rad/s;
PhysX when a mass-normalised kinetic energy stays low while a 0.4 s wake counter runs
out. None looks at acceleration, so each freezes a slow enough pendulum at its turning
point. We keep Box2D's and Jolt's half second (Bullet's 2 s keeps piles awake four
times longer for nothing), Jolt's 0.03 m/s (Box2D's 0.01 m/s is below the jitter of
QuickStep stacks) and Box2D's 2°/s.

Islands: a body never sleeps apart from what it touches, or it would be frozen
(velocity zeroed) while an awake neighbour still pushes it. Islands are found only on
steps where some body has been quiet long enough, from the step's contacts and the
joints; a kinematic body or one that may not sleep keeps its island awake, and
sleeping members count as ready. Waking is the backend's own island wake-up (ODE
enables a disabled body a contact or joint ties to an enabled one; chipmunk wakes a
sleeping component an awake body touches), and every explicit wake (a force, a pose,
a motor...) restarts the body's quiet stretch. A sleeping body has zero velocity.

The per-body state is the smoothed velocity (where it is averaging), the quiet time
(seconds) and the reference; a saved state carries them (``SleepVelocity``,
``SleepTimer``, ``SleepReference``), so a loaded state falls asleep on the very step
the uninterrupted run would.

Cost: the per-body part of a step (smoothing, the two tests, the quiet time and the
reference) is one compiled pass over the bodies (``engine/physics/sleep.h``, the
same arithmetic in the same order as the numpy formulation it replaced, to the bit):
a few microseconds for 500 bodies right after a step, where twenty numpy calls over
(6, N) columns took some 90 with the caches cold (``colosseum bench physics`` measures
it). :meth:`SleepRule.update` runs it through ``_sleep.pyx`` and finds the islands with
scipy (contacts to rows, connected components: far dearer, so only on steps where some
body is ready, and reused while the contacts are the same); that is the pymunk backend's
path. The ODE backend runs the whole update inside its step instead, in C on the same
arrays (:meth:`SleepRule.arrays`), with the islands the step itself found
(``ode3d/stepper.h``'s ``cs_sleep``), and so does the plain-C reference of the benchmark.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from engine.physics import _sleep

#: Seconds a body must stay quiet before it (and its island) falls asleep.
SLEEP_TIME = 0.5
#: Smoothed centre-of-mass speed (m/s) under which a body counts as slow.
SLEEP_LINEAR = 0.03
#: Smoothed spin (rad/s) under which a body counts as slow (2°/s).
SLEEP_ANGULAR = math.radians(2.0)
#: The steady band, as a share of the slow limits.
STEADY_SHARE = 0.1
#: Time constant (s) of the velocity smoothing.
SMOOTHING = 0.1


@dataclass(frozen=True, slots=True)
class SleepState:
    """A body's standing with the sleep rule: what a saved state needs to sleep on time.

    Velocities are (6,) arrays: centre of mass, m/s then rad/s, world frame.
    """

    asleep: bool
    #: The smoothed velocity of a body that goes on smoothing (awake, under the slow
    #: limits, not at rest); None for others, whose average snaps to their velocity at
    #: the next step.
    smoothed: np.ndarray | None = None
    #: Seconds the body has been quiet so far.
    timer: float = 0.0
    #: The smoothed velocity its quiet stretch began with; None when none is under way.
    reference: np.ndarray | None = None
    #: Its standing with the resting preload (ODE: engine/physics/ode3d/stepper.h), which
    #: carries a resting body's weight from step to step: steps it has been held up at
    #: rest (0 to 2), whether it slid while preloaded, the force its contacts hold it
    #: with (averaged; (3,), N; None: none), and whether it was preloaded at the last step
    #: (a preloaded body stays so up to a faster drift than it may enter at).
    rest_steps: int = 0
    rest_slid: bool = False
    rest_force: np.ndarray | None = None
    rest_preloaded: bool = False


class KeyIndex:
    """Rows of keys in a key array (any order): one sorted search, no Python per key."""

    __slots__ = ("_order", "_sorted")

    def __init__(self, keys: np.ndarray) -> None:
        self._order = np.argsort(keys, kind="stable")
        self._sorted = keys[self._order]

    def rows(self, keys: np.ndarray) -> np.ndarray:
        """Row of each key; -1 where a key is not in the array."""
        keys = np.asarray(keys, np.int64)
        if not len(self._sorted):
            return np.full(keys.shape, -1, np.int64)
        at = np.minimum(np.searchsorted(self._sorted, keys), len(self._sorted) - 1)
        return np.where(self._sorted[at] == keys, self._order[at], -1)


class SleepRule:
    """The rule's state for a backend's rows, and the step that advances it.

    The backend calls :meth:`layout` whenever its rows change (the state follows the
    keys), fills :attr:`velocity` and :attr:`awake` after each step, and calls
    :meth:`update`, which says which rows to put to sleep. Velocities are kept as
    columns, (6, N): centre-of-mass linear then angular velocity, world frame (numpy
    is several times faster on six long rows than on N short ones).
    """

    def __init__(self) -> None:
        self.time = SLEEP_TIME
        self._bounds = _bounds(SLEEP_LINEAR, SLEEP_ANGULAR)
        self.keys = np.zeros(0, np.int64)
        self._index = KeyIndex(self.keys)
        self.movable = np.zeros(0, bool)  # dynamic or kinematic: may belong to an island
        self.eligible = np.zeros(0, bool)  # dynamic and allowed to sleep
        self.awake = np.zeros(0, bool)
        self._stack = np.zeros((3, 6, 0))
        self.smoothed, self.velocity = self._stack[0], self._stack[2]
        # 1.0 where the next step averages, 0.0 where it snaps (floats: they scale)
        self.smoothing = np.zeros(0)
        self.timer = np.zeros(0)
        self.reference = np.zeros((6, 0))
        self.started = np.zeros(0, bool)  # a quiet stretch is under way (reference set)
        self._islands_of: tuple[np.ndarray, np.ndarray] | None = None
        self.generation = 0  # counts the times the arrays were replaced (bound anew)
        self._pass = self._bind()

    def configure(self, time: float, linear: float, angular: float) -> None:
        """Set the limits (s, m/s, rad/s)."""
        for what, value in (("sleep time", time), ("sleep linear", linear),
                            ("sleep angular", angular)):
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"{what} must be a positive number, got {value}")
        self.time = float(time)
        self._bounds = _bounds(linear, angular)
        self._pass = self._bind()

    def layout(self, keys: np.ndarray, movable: np.ndarray, eligible: np.ndarray) -> None:
        """New rows (bodies came or went): the state follows its keys."""
        old = self._index.rows(keys)
        had = np.flatnonzero(old >= 0)
        n = len(keys)
        # the smoothed velocity, its drift from the reference and the velocity, stacked
        # as the compiled pass (_sleep.advance) takes them
        stack = np.zeros((3, 6, n))
        moved = {"smoothed": stack[0]}
        for name, shape in (("smoothing", (n,)), ("timer", (n,)), ("reference", (6, n)),
                            ("started", (n,))):
            moved[name] = np.zeros(shape, getattr(self, name).dtype)
        for name, now in moved.items():
            now[..., had] = getattr(self, name)[..., old[had]]
            setattr(self, name, now)
        self._stack = stack
        self.velocity = stack[2]
        self.keys, self._index = keys, KeyIndex(keys)
        self.movable = np.ascontiguousarray(movable, bool)
        self.eligible = np.ascontiguousarray(eligible, bool)
        self.awake = np.zeros(n, bool)
        self._islands_of = None  # the last edges and their island labels
        self._pass = self._bind()

    def _bind(self) -> _sleep.Pass:
        """The compiled pass over the current arrays (they are written in place from then
        on, so the pass is made again only when they are replaced)."""
        self.generation += 1
        return _sleep.Pass(*self.arrays()[:7], self._bounds, self.movable.view(np.uint8))

    def arrays(self) -> tuple[np.ndarray, ...]:
        """The arrays a compiled pass works on in place, as ``sleep.h``'s SrRule holds
        them: the (3, 6, N) stack (smoothed, drift, velocity), smoothing, timer, reference,
        started, awake, eligible, movable (bytes), the squared bounds. A backend stepping
        the rule in C binds them again whenever :attr:`generation` changes."""
        return (self._stack, self.smoothing, self.timer, self.reference,
                self.started.view(np.uint8), self.awake.view(np.uint8),
                self.eligible.view(np.uint8), self.movable.view(np.uint8), self._bounds)

    def rows(self, keys: np.ndarray) -> np.ndarray:
        return self._index.rows(keys)

    def forget(self, rows: np.ndarray | slice | int) -> None:
        """Start these rows afresh (put to sleep, or sleeping turned off)."""
        self.smoothed[:, rows] = 0.0
        self.smoothing[rows] = 0.0
        self.timer[rows] = 0.0
        self.started[rows] = False

    def update(self, dt: float, woken: np.ndarray | None,
               edges: Callable[[], np.ndarray] | None = None,
               islands: Callable[[], np.ndarray] | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
        """Advance the state by a step of ``dt``; the rows to put to sleep now, and every
        row's island label when some were (rows of one island share a label).

        ``woken``: a bool mask of rows explicitly woken since the last update (or None).
        Called only when some body is ready, one of: ``islands``, each row's island
        label (rows tied by the step's contacts and joints through movable rows), as a
        backend finds them itself; or ``edges``, (M, 2) row pairs of the step's contacts
        and joints (-1: not a body of ours), made into islands here.
        """
        if not self._pass.advance(dt, math.exp(-dt / SMOOTHING), self.time,
                                  None if woken is None else woken.view(np.uint8)):
            return _NONE, _NONE
        if islands is not None:
            labels = islands()
        elif edges is not None:
            labels = self._islands(edges)
        else:
            raise ValueError("SleepRule.update needs the islands or the edges")
        # the islands' say, sleep.h's sr_settle (as ODE's step runs it): an awake movable
        # row that is not ready keeps its island awake; the others' ready rows sleep
        rows = self._pass.settle(self.time, np.ascontiguousarray(labels, np.intc))
        return rows, labels

    def _islands(self, edges: Callable[[], np.ndarray]) -> np.ndarray:
        """Each row's island label: rows tied by contacts or joints through moving bodies
        share one (a static body ties nothing together)."""
        # scipy only for scenes that sleep, and only once something is about to
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        n = len(self.timer)
        pairs = np.asarray(edges(), np.int64).reshape(-1, 2)
        a, b = pairs[:, 0], pairs[:, 1]
        inside = (a >= 0) & (b >= 0)  # -1: the world, or no body of ours
        inside[inside] = self.movable[a[inside]] & self.movable[b[inside]]
        pairs = pairs[inside]
        known = self._islands_of
        if known is not None and np.array_equal(known[0], pairs):
            return known[1]  # the same contacts as last time (a pile at rest): same islands
        if not len(pairs):
            labels = np.arange(n)
        else:
            graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                               shape=(n, n))
            labels = connected_components(graph, directed=False)[1]
        self._islands_of = (pairs, labels)
        return labels

    # -- saved states ----------------------------------------------------------
    def states(self, asleep: np.ndarray) -> dict[int, SleepState]:
        """Every moving body that is asleep, smoothing or in a quiet stretch. The rest
        start afresh: their average snaps to their velocity on the next step whatever it
        was."""
        busy = np.flatnonzero(self.movable & (asleep | (self.smoothing > 0) | self.started))
        return {int(self.keys[i]): SleepState(
                    bool(asleep[i]), self.smoothed[:, i].copy() if self.smoothing[i] else None,
                    float(self.timer[i]),
                    self.reference[:, i].copy() if self.started[i] else None)
                for i in busy.tolist()}

    def restore(self, row: int, state: SleepState) -> None:
        """Put a row's state back as a saved state had it."""
        if not (state.timer >= 0 and math.isfinite(state.timer)):
            raise ValueError(f"body {self.keys[row]}: sleep timer must be >= 0 s, "
                             f"got {state.timer}")
        for name, value in (("smoothed", state.smoothed), ("reference", state.reference)):
            if value is None:
                continue
            value = np.asarray(value, np.float64).reshape(-1)
            if value.shape != (6,) or not np.isfinite(value).all():
                raise ValueError(f"body {self.keys[row]}: a {name} velocity is 6 finite "
                                 f"numbers, got {value.tolist()}")
        self.forget(row)
        if state.asleep:
            return
        if state.smoothed is not None:
            self.smoothed[:, row] = state.smoothed
            self.smoothing[row] = 1.0
        if state.reference is not None:
            self.reference[:, row] = state.reference
            self.started[row] = True
        self.timer[row] = state.timer


#: :meth:`SleepRule.update`'s rows and labels on a step where no body is ready (most
#: steps): one read-only empty array, not two new ones each step.
_NONE = np.zeros(0, np.int64)
_NONE.setflags(write=False)


def _bounds(linear: float, angular: float) -> np.ndarray:
    """Squared (linear, angular) bounds, flat: slow, steady, at rest."""
    return np.array([limit * limit * share**2
                     for share in (1.0, STEADY_SHARE, STEADY_SHARE**2)
                     for limit in (linear, angular)])

