"""Pose interpolation between the two latest physics states (``--interpolate``).

In threaded mode physics publishes states at its own rate; drawing the latest one makes motion
judder when the rates differ. The interpolator keeps the two latest snapshots and draws poses
between them, ``alpha`` of the way from the older to the newer, where ``alpha`` is the wall time
since the newer one arrived over the interval between their arrivals. Drawing lags physics by
at most one state, in exchange for smooth motion.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from engine.rotation import slerp


def interpolate_states(older: Any, newer: Any, alpha: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(keys, positions, orientations)`` ``alpha`` of the way from ``older`` to ``newer``
    (two ``BodyState``). Bodies only in ``newer`` keep their new pose."""
    alpha = float(np.clip(alpha, 0.0, 1.0))
    keys = newer.keys
    pos = np.array(newer.position, dtype=np.float64)
    quat = np.array(newer.orientation, dtype=np.float64)
    if len(older.keys) == 0 or len(keys) == 0:
        return keys, pos, quat
    if len(older.keys) == len(keys) and np.array_equal(older.keys, keys):
        new_idx = np.arange(len(keys))
        old_idx = new_idx
    else:
        order = np.argsort(older.keys)
        found = np.searchsorted(older.keys, keys, sorter=order)
        found = np.clip(found, 0, len(order) - 1)
        old_idx = order[found]
        match = older.keys[old_idx] == keys
        new_idx = np.nonzero(match)[0]
        old_idx = old_idx[match]
    p0, p1 = older.position[old_idx], newer.position[new_idx]
    pos[new_idx] = p0 + (p1 - p0) * alpha
    quat[new_idx] = slerp(older.orientation[old_idx], newer.orientation[new_idx], alpha)
    return keys, pos, quat


class PoseInterpolator:
    """Keeps the two latest snapshots (anything with ``step`` and ``bodies``) and their
    arrival times; :meth:`poses` gives the poses to draw now."""

    def __init__(self, clock: Callable[[], float] = time.perf_counter) -> None:
        self.clock = clock
        self._older: tuple[Any, float] | None = None
        self._newer: tuple[Any, float] | None = None

    def push(self, snapshot: Any) -> None:
        """Offer the latest snapshot; the same step twice is ignored."""
        if self._newer is not None and self._newer[0].step == snapshot.step:
            return
        self._older, self._newer = self._newer, (snapshot, self.clock())

    def alpha(self) -> float:
        if self._older is None or self._newer is None:
            return 1.0
        interval = self._newer[1] - self._older[1]
        if interval <= 0.0:
            return 1.0
        return float(np.clip((self.clock() - self._newer[1]) / interval, 0.0, 1.0))

    def poses(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Interpolated ``(keys, positions, orientations)``, or None before any snapshot."""
        if self._newer is None:
            return None
        newer = self._newer[0].bodies
        if self._older is None:
            return newer.keys, np.asarray(newer.position), np.asarray(newer.orientation)
        return interpolate_states(self._older[0].bodies, newer, self.alpha())
