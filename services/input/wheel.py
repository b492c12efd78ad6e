"""A wheel's angular velocity from encoder counts and their timestamps.

The paper's wheelchair drives its virtual rear wheels from counters on the real ones
(section 5.5). The rate is counts over device time across the last ``window``
seconds — never counts per frame, so a slow or uneven frame rate does not change
it. A counter that wraps (``wrap``: a 16-bit counter wraps at 65536) is unwrapped the
short way; a jump faster than ``max_turns_per_second`` is a counter reset (a device
restarted), not motion: it is reported and the count continues from there. When no
count arrives for a while the wheel is standing (encoders that send only on change).

>>> w = WheelRate(counts_per_turn=100)
>>> for i in range(11):
...     w.add(i * 10, i * 0.01)    # 10 counts every 10 ms: 10 turns/s
>>> round(w.turns_per_second(0.1), 6)
10.0
"""

from __future__ import annotations

import math
from collections import deque

from engine.scene.inputs import WheelSpec

#: Shortest time a counter jump is judged over (s): samples of one packet share a timestamp.
MIN_JUMP_DT = 0.01


class WheelRate:
    """Unwraps a wheel counter and measures its rate over a time window."""

    def __init__(self, counts_per_turn: int = 1024, wrap: int = 0,
                 max_turns_per_second: float = 20.0, invert: bool = False,
                 window: float = 0.1) -> None:
        self.counts_per_turn = counts_per_turn
        self.wrap = wrap
        self.max_turns_per_second = max_turns_per_second
        self.sign = -1.0 if invert else 1.0
        self.window = window
        #: The last raw count, and the unwrapped count (continuous across wraps and resets).
        self.raw: int | None = None
        self.total = 0
        self.resets = 0
        self._samples: deque[tuple[float, int]] = deque()

    @staticmethod
    def of(spec: WheelSpec) -> WheelRate:
        return WheelRate(spec.counts_per_turn, spec.wrap, spec.max_turns_per_second,
                         spec.invert, spec.window)

    def add(self, count: int, t: float) -> str | None:
        """Take a count read at device time ``t``; returns why it was not motion, if so."""
        problem = None
        if self.raw is not None:
            delta = count - self.raw
            if self.wrap:
                delta = (delta + self.wrap // 2) % self.wrap - self.wrap // 2
            last_t = self._samples[-1][0] if self._samples else t
            allowed = self.max_turns_per_second * self.counts_per_turn * max(t - last_t,
                                                                             MIN_JUMP_DT)
            if abs(delta) > allowed:
                problem = (f"count jumped from {self.raw} to {count}: a counter reset, not "
                           f"motion; counting on from here")
                self.resets += 1
                self._samples.clear()
                delta = 0
            self.total += delta
        self.raw = count
        samples = self._samples
        if samples and t < samples[-1][0]:
            t = samples[-1][0]  # timestamps never run backwards within one source
        samples.append((t, self.total))
        while len(samples) > 2 and samples[1][0] <= t - self.window:
            samples.popleft()
        return problem

    def turns_per_second(self, now: float) -> float:
        """Signed turns per second at time ``now`` (0 when the counter has gone quiet)."""
        samples = self._samples
        if len(samples) < 2:
            return 0.0
        (t0, c0), (t1, c1) = samples[0], samples[-1]
        if now - t1 > max(self.window, t1 - t0) or t1 <= t0:
            return 0.0
        return self.sign * (c1 - c0) / (t1 - t0) / self.counts_per_turn

    def angular_velocity(self, now: float) -> float:
        """rad/s at time ``now``."""
        return 2.0 * math.pi * self.turns_per_second(now)

    @property
    def turns(self) -> float:
        """Turns since the first count (unwrapped, resets skipped)."""
        return self.sign * self.total / self.counts_per_turn
