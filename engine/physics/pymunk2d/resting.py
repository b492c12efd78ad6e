"""The resting warm start on pymunk: ODE's (engine/physics/ode3d/stepper.h) in the plane.

chipmunk warm-starts each contact from its last impulse, yet 20 iterations leave a
stack of ten crates rocking 2 to 4 cm at 100 Hz and toppling at 50 Hz. As on ODE, a
body at rest on its contacts gets ``warm_start`` of its weight as an upward force
before the step, so the solver finds only the rest of every contact force (for a body
at rest the contacts' whole force is its weight: normal and friction scale alike, and
the motion is the same whenever the solver converges). The rules are stepper.h's, with
its constants: at rest means held up by the contacts (REST_SUPPORT of the weight) for
two steps, not pushed sideways (the force averaged over REST_SMOOTHING seconds, against
REST_GRIP of the friction), friction short of its bound (REST_SLIDING), moving slower
than REST_SLIP, resting on a face (two contact points in the plane) or on level ground
only, with no joint and touching no kinematic body, in an island (bodies touching) with
no jointed, weightless or pushed body: each preloaded weight must reach the ground through
contacts (a platform a force holds up or a wheelchair's seat would take the preload of
what rests on it instead). What the contacts did is read from
pymunk's arbiters in one batch (``_rows.Rows.support``).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from engine.physics.pymunk2d import _rows

#: chipmunk's own warm start carries last step's impulses over: a preload switched on
#: at once would come on top of them for a step and pop a stack apart. It is ramped in by
#: this share of its full size a step, and out by twice that.
RAMP = 0.1
#: stepper.h's constants (tests/physics/test_accuracy.py checks they agree).
REST_SLIP = 0.05
REST_SUPPORT = 0.5
REST_GRIP = 0.5
REST_SLIDING = 0.95
REST_SMOOTHING = 0.2


class RestingSupport:
    """Each row's standing (steps at rest, slid, the averaged force its contacts hold it
    with) and which rows get their weight's share before the next step."""

    def __init__(self, n: int, beta: float) -> None:
        self.beta = beta
        self.steps = np.zeros(n, np.int8)
        self.slid = np.zeros(n, bool)
        self.held = np.zeros((n, 2))  # x, z
        self.applied = np.zeros(n)  # share of its weight it got in the step just taken
        self.ramp = np.zeros(n)  # how much of beta of its weight it gets now (0 to 1)
        self.kept = np.zeros(n, bool)  # preloaded and still held up: may stay preloaded
        self.force = np.zeros((n, 2))
        self.friction = np.zeros(n)
        self.grip = np.zeros(n)
        self.points = np.zeros(n, np.int64)
        self.tilted = np.zeros(n, np.uint8)
        self.chosen = np.zeros(n, bool)  # may be preloaded, islands aside (update's)
        #: each row's island label (rows tied by contacts between moving bodies) when the
        #: last :meth:`eligible` needed it; None: not found (no row preloaded)
        self.islands: np.ndarray | None = None

    def follow(self, old_rows: np.ndarray) -> None:
        """New rows: each keeps the standing of ``old_rows[i]`` (-1: a new body)."""
        had = old_rows >= 0
        for name in ("steps", "slid", "held"):
            now = np.zeros((len(old_rows), *getattr(self, name).shape[1:]),
                           getattr(self, name).dtype)
            now[had] = getattr(self, name)[old_rows[had]]
            setattr(self, name, now)
        n = len(old_rows)
        self.applied = np.zeros(n)
        self.kept = np.zeros(n, bool)
        ramp = np.zeros(n)
        ramp[had] = self.ramp[old_rows[had]]
        self.ramp = ramp
        self.force, self.friction, self.grip = np.zeros((n, 2)), np.zeros(n), np.zeros(n)
        self.points, self.tilted = np.zeros(n, np.int64), np.zeros(n, np.uint8)
        self.chosen = np.zeros(n, bool)
        self.islands = None

    def forget(self, rows: np.ndarray) -> None:
        """These rows start afresh (moved or pushed by hand: no longer at rest), and their
        islands lose the preload for the next step."""
        rows = rows[rows >= 0]
        self.steps[rows] = 0
        self.slid[rows] = False
        if self.islands is not None and len(rows):
            rows = np.flatnonzero(np.isin(self.islands, self.islands[rows]))
        self.ramp[rows] = 0.0
        self.kept[rows] = False

    def update(self, dt: float, down: np.ndarray, weight: np.ndarray, mu: np.ndarray,
               awake: np.ndarray, unrest: np.ndarray, raw: np.ndarray,
               gather: np.ndarray) -> int:
        """The standing after a step, from ``force``, ``friction`` and ``grip`` (filled by
        ``Rows.support``); ``weight`` per row (N; 0: not dynamic), ``mu`` its friction;
        and which rows may be preloaded before the next step, islands aside (into
        ``chosen``; how many, see :meth:`eligible`). ``raw`` is the step's read (row ``i``
        at ``gather[i]``).

        At rest means held up by its contacts (REST_SUPPORT of its weight, the share it
        was preloaded with aside) with its friction short of its bound, not pushed
        sideways (the held force against REST_GRIP of the friction; the grip left by
        the preload if it slid while preloaded), for two steps; preloaded, a body stays
        so while it is held up at all (chipmunk carries its impulses over, and a preload
        switched off and on again jolts them). One pass per row (``_rows.rest_standing``,
        in numpy's order of operations)."""
        return _rows.rest_standing(
            self.force, self.friction, self.grip, self.points, self.tilted, self.applied,
            weight, mu, awake.view(np.uint8), unrest.view(np.uint8), raw, gather, self.held,
            self.steps, self.slid.view(np.uint8), self.kept.view(np.uint8),
            self.chosen.view(np.uint8), float(down[0]), float(down[1]),
            math.exp(-dt / REST_SMOOTHING), 1.0 - self.beta, REST_SUPPORT,
            0.5 * REST_SUPPORT, REST_GRIP, REST_SLIDING, REST_SLIP, 4 * REST_SLIP)

    def eligible(self, chosen: int, moving: np.ndarray, unrest: np.ndarray,
                 weight: np.ndarray, islands: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """Rows to preload before the next step: :meth:`update`'s ``chosen`` (at rest two
        steps, slower than REST_SLIP, four times that to stay preloaded, on a face or
        level ground, not ``unrest``: jointed, or touching a kinematic body), in an
        island (``islands(moving)``: each row's label, called only when some row is
        chosen) with no ``moving`` (dynamic, awake) row that is unrest or weightless.
        The preload ramps in by RAMP a step and out by twice that, and is off at once
        where no contact is left (chipmunk keeps no impulse to jolt there) or the island
        is not at rest (the preload would lift what holds it up). (One pushed by hand
        takes its island's preload off: :meth:`forget`.)"""
        self.islands = islands(moving) if chosen else None
        _rows.rest_ramp(self.points, self.chosen.view(np.uint8), self.islands,
                        moving.view(np.uint8), unrest.view(np.uint8), weight, self.ramp,
                        RAMP, -2 * RAMP)
        return self.ramp > 0


def carried_down(rows_a: np.ndarray, rows_b: np.ndarray, impulse: np.ndarray,
                 normal_up: np.ndarray, load: np.ndarray, rounds: int = 64) -> np.ndarray:
    """Contact impulses with the preloads put back: each preloaded row's share of its weight
    (``load``, N·s upward) goes into the contacts holding it up, in proportion to what each
    carried, and on through the rows under them down to the ground (stepper.h's
    cs_add_preloads in the plane). ``normal_up`` is each contact's normal (from b toward a)
    along the vertical; row -1 is static geometry. What each row passes on is found by
    repeating the pass down the stack until it settles (a stack's height of rounds); the
    passes are one C loop each (``_rows.carried_down``)."""
    return _rows.carried_down(np.ascontiguousarray(rows_a, np.int64),
                              np.ascontiguousarray(rows_b, np.int64),
                              np.asarray(impulse, np.float64),
                              np.ascontiguousarray(normal_up, np.float64),
                              np.ascontiguousarray(load, np.float64), int(rounds))
