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
only, with no joint and touching no kinematic body. What the contacts did is read from
pymunk's arbiters in one batch (``_rows.Rows.support``).
"""

from __future__ import annotations

import math

import numpy as np

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

    def forget(self, rows: np.ndarray) -> None:
        """These rows start afresh (moved or pushed by hand: no longer at rest)."""
        rows = rows[rows >= 0]
        self.steps[rows] = 0
        self.ramp[rows] = 0.0
        self.kept[rows] = False
        self.slid[rows] = False

    def update(self, dt: float, down: np.ndarray, weight: np.ndarray, mu: np.ndarray,
               awake: np.ndarray) -> None:
        """The standing after a step, from ``force``, ``friction`` and ``grip`` (filled by
        ``Rows.support``); ``weight`` per row (N; 0: not dynamic), ``mu`` its friction."""
        share = 1.0 - self.applied
        up = -(self.force @ down)
        keep = math.exp(-dt / REST_SMOOTHING)
        self.held *= keep
        self.held += (1.0 - keep) * self.force / share[:, None]
        held_up = -(self.held @ down)
        side = self.held + held_up[:, None] * down
        limit = REST_GRIP * np.where(self.slid, 1.0 - self.beta, 1.0) * mu * held_up
        pushed = np.einsum("ij,ij->i", side, side) > limit * limit
        sliding = self.friction >= REST_SLIDING * self.grip
        self.slid |= (self.applied > 0) & sliding
        self.slid &= pushed
        held_up_enough = up >= REST_SUPPORT * share * weight
        rests = (weight > 0) & awake & ~pushed & held_up_enough & ~sliding
        self.steps = np.where(rests, np.minimum(self.steps + 1, 2), 0).astype(np.int8)
        # preloaded, a body stays so while it is held up at all: chipmunk carries its
        # impulses over, and a preload switched off and on again jolts them
        stays = (weight > 0) & awake & (up >= 0.5 * REST_SUPPORT * share * weight)
        self.kept = (self.applied > 0) & stays

    def eligible(self, speed: np.ndarray, unrest: np.ndarray) -> np.ndarray:
        """Rows to preload before the next step: at rest two steps, slower than REST_SLIP
        (four times that to stay preloaded: chipmunk carries its impulses over, and a
        preload switched off and on jolts them), on a face or level ground, and not
        ``unrest`` (jointed, or touching a kinematic body)."""
        slip = np.where(self.kept, 4 * REST_SLIP, REST_SLIP)
        chosen = (((self.steps >= 2) | self.kept) & (speed < slip) & ~unrest
                  & ((self.points >= 2) | (self.tilted == 0)))
        # off at once where no contact is left (chipmunk keeps no impulse to jolt there)
        self.ramp = np.where(self.points > 0, np.clip(
            self.ramp + np.where(chosen, RAMP, -2 * RAMP), 0.0, 1.0), 0.0)
        return self.ramp > 0
