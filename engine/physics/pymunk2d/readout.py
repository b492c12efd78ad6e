"""One pymunk batch read → the arrays of a BodyState, in a fixed handful of numpy calls.

Right after a step the CPU caches hold the solver's data, not the interpreter's, so
each numpy call costs microseconds whatever its size: the read is planned to make
few. A :class:`Readout` owns a reusable source buffer laid out as

    x z −θ/2 vx vz −ω   per batch row (m rows, in pymunk's order: the read, scaled)
    cos(−θ/2)           per batch row
    sin(−θ/2)           per batch row
    Y                   per keyed row (n rows, as authored)
    0.0

and each BodyState array is one ``take`` from it with indices planned when the
bodies or their order change: that one call reorders the rows into key-row order,
fills the constant columns and hands out a fresh array (snapshots are immutable).
"""

from __future__ import annotations

import math

import numpy as np

#: Scales a batch row (x, z, θ, vx, vz, ω): θ to the half-angle about Y, ω to the Y rate.
_SCALE = np.array([1.0, 1.0, -0.5, 1.0, 1.0, -1.0])
#: Undoes :data:`_SCALE` (exactly: both scale by powers of two).
_UNSCALE = np.array([1.0, 1.0, -2.0, 1.0, 1.0, -1.0])


class Readout:
    """The read plan for ``m`` batch rows; keyed row ``i`` has Y ``y[i]``, batch row ``at[i]``."""

    def __init__(self, m: int, y: np.ndarray, at: np.ndarray) -> None:
        n = len(y)
        self.m, self.n = m, n
        src = np.zeros(8 * m + n + 1)
        src[8 * m:8 * m + n] = y
        self.source = src
        #: Y per keyed row then 0.0 for the keyless world; the backend writes Y here.
        self.y_ext = src[8 * m:]
        self._head = src[:6 * m]
        self._scale = np.tile(_SCALE, m)
        self._half = src[2:6 * m:6]
        self._cos = src[6 * m:7 * m]
        self._sin = src[7 * m:8 * m]
        self.place(at)

    def place(self, at: np.ndarray) -> None:
        """Plan the takes for keyed row ``i`` sitting at batch row ``at[i]``."""
        m, n = self.m, self.n
        self.at = at = np.asarray(at, np.intp)
        row, zero = 6 * at, np.full(n, 8 * m + n, np.intp)
        self._pos = np.stack([row, np.arange(8 * m, 8 * m + n), row + 1], axis=1)
        self._ori = np.stack([6 * m + at, zero, 7 * m + at, zero], axis=1)
        self._lin = np.stack([row + 3, zero, row + 4], axis=1)
        self._ang = np.stack([zero, row + 5, zero], axis=1)

    def load(self, floats: np.ndarray) -> bool:
        """Take a batch read (x, z, θ, vx, vz, ω rows) in; False if a value is not finite."""
        np.multiply(floats, self._scale, out=self._head)
        finite = math.isfinite(self._head.sum())
        if finite:
            self._derive()
        else:  # the caller resets what broke; meanwhile cos(inf) is NaN, not a warning
            with np.errstate(invalid="ignore"):
                self._derive()
        return finite

    def _derive(self) -> None:
        np.cos(self._half, out=self._cos)
        np.sin(self._half, out=self._sin)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Fresh (position, orientation about Y, linear velocity, angular velocity)."""
        take = self.source.take
        return take(self._pos), take(self._ori), take(self._lin), take(self._ang)

    def rows(self) -> np.ndarray:
        """The loaded batch rows (x, z, θ, vx, vz, ω) in keyed-row order."""
        return self._head.reshape(self.m, 6)[self.at] * _UNSCALE
