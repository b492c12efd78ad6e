"""When a scene has settled and when it is asleep: the measure both backends' settling
tests share (tests/physics/test_resting_steps.py on ODE, test_pymunk_settling.py)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from engine.physics.sleep import SLEEP_ANGULAR, SLEEP_LINEAR


def settled_and_asleep(awake: Any, sleeping: Any, dt: float,
                       all_asleep: Callable[[Any], bool], seconds: float = 8.0
                       ) -> tuple[float, float | None]:
    """Step the same scene with sleeping off (``awake``) and on (``sleeping``) for
    ``seconds``: when the awake one settled (from then to the end every body moves and
    turns slower than the sleep limits) and when every body of the sleeping one was first
    asleep (None: never). Both backends are closed."""
    steps = round(seconds / dt)
    fast = np.zeros(steps, bool)
    asleep_at = None
    for i in range(steps):
        awake.step(dt)
        sleeping.step(dt)
        state = awake.read_state()
        fast[i] = (np.linalg.norm(state.linear_velocity, axis=1).max() >= SLEEP_LINEAR or
                   np.linalg.norm(state.angular_velocity, axis=1).max() >= SLEEP_ANGULAR)
        if asleep_at is None and all_asleep(sleeping):
            asleep_at = (i + 1) * dt
    awake.close()
    sleeping.close()
    settled_at = (np.flatnonzero(fast).max() + 1) * dt if fast.any() else 0.0
    return settled_at, asleep_at
