"""Numbers checked at the binding's door: ODE aborts the process on a non-finite rotation,
so nothing non-finite or runaway gets through to it."""

from __future__ import annotations

import math

import numpy as np

from engine.physics.backend import MAX_SPEED


def vec(value: object, n: int, what: str) -> np.ndarray:
    """``n`` finite floats as a contiguous array, or ValueError naming ``what``."""
    arr = np.ascontiguousarray(value, dtype=np.float64).reshape(-1)
    # for a few numbers, Python's isfinite is several times faster than numpy's
    if len(arr) != n or not all(map(math.isfinite, arr.tolist())):
        raise ValueError(f"{what} must be {n} finite numbers, got {value!r}")
    return arr


def check_speed(key: int, linear: np.ndarray, angular: np.ndarray) -> None:
    """Refuse velocities beyond the protocol's ``MAX_SPEED`` (the next step would
    overflow): what a kinematic target asks for, known only against the body's pose."""
    # hypot scales instead of overflowing; an infinite component gives inf, refused
    if max(math.hypot(*linear.tolist()), math.hypot(*angular.tolist())) > MAX_SPEED:
        raise ValueError(f"body {key}: velocity beyond {MAX_SPEED:g} m/s or rad/s")
