"""Which contacts make a sound, and how loud: impacts ring, resting contacts stay silent.

A physics backend reports every touching pair every step, with the impulse its
solver applied. A stack at rest reports the same impulses (its weight times the
step) forever, so a threshold alone would make it hum. The filter therefore
sounds *changes*, per body pair, in simulated time:

* **Onset.** A pair not seen for ``forget_after`` seconds is a candidate; one
  batch later it sounds only if its impulse then dropped below
  ``1 / spike_ratio`` of the onset impulse (a landing or a bounce: the impact
  spike, then the resting level or nothing) and the onset impulse reached
  ``min_impulse``. A body placed or spawned at rest keeps its impulse and stays
  silent. The decision costs one frame of latency (~17 ms), below what a
  listener notices between sight and sound.
* **Touching pairs** sound when their impulse exceeds ``spike_ratio`` times their
  steady level and ``min_impulse``: something hit the stack. The steady level
  follows a small rise at once and a fall slowly (peak hold), so solver jitter
  never looks like a blow; a spike moves it by ``smoothing`` per batch, so a load
  that stays after its impact becomes the new rest within a few frames.
* **Settling.** For ``settle_time`` seconds after a body is created (see
  :meth:`ContactSoundFilter.settle`) its contacts only teach the filter their
  resting level: a solver pushing a freshly placed stack apart is not a crash.
* **Rate limit.** A pair sounds at most once per ``pair_interval`` seconds.

A pair's impulse is the sum over its contact points in the batch (a batch holds
the steps since the last frame, a constant number at a steady pace).

Gain from impulse ``J`` (N·s): ``gain = min(1, (J / full_impulse) ** exponent)``
for ``J >= min_impulse``; the square root default follows loudness growing
slower than the impact's momentum. With the defaults a 1 kg ball landing at
3 m/s (J ≈ 3 N·s) plays at gain ≈ 0.77 and a gentle 0.2 N·s tap at 0.2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_INF = float("inf")


@dataclass(slots=True)
class ContactSoundSettings:
    """Tuning of the filter; impulses in N·s, times in simulated seconds."""

    min_impulse: float = 0.1
    full_impulse: float = 5.0
    exponent: float = 0.5
    spike_ratio: float = 3.0
    pair_interval: float = 0.08
    forget_after: float = 0.25
    smoothing: float = 0.1
    settle_time: float = 0.15


@dataclass(frozen=True, slots=True)
class ContactSound:
    """A contact that should be heard: bodies, where (engine frame), impulse and gain."""

    a: int
    b: int
    position: tuple[float, float, float]
    impulse: float
    gain: float


@dataclass(slots=True)
class _Pair:
    steady: float
    last_seen: float
    last_sound: float = -_INF


class ContactSoundFilter:
    """Turns batches of contacts (CONTACT_DTYPE) into the few that should sound."""

    def __init__(self, settings: ContactSoundSettings | None = None) -> None:
        self.settings = settings or ContactSoundSettings()
        self._pairs: dict[tuple[int, int], _Pair] = {}
        self._candidates: dict[tuple[int, int], ContactSound] = {}
        self._settling: dict[int, float] = {}
        self._calls = 0

    def gain(self, impulse: float) -> float:
        s = self.settings
        if impulse < s.min_impulse:
            return 0.0
        return min(1.0, (impulse / s.full_impulse) ** s.exponent)

    def settle(self, body: int, now: float) -> None:
        """``body`` was just created: its contacts are settling, not impacts, for a while."""
        self._settling[body] = now + self.settings.settle_time

    def process(self, batch: np.ndarray, now: float) -> list[ContactSound]:
        """The contacts of one frame (any number of steps) that sound; ``now`` is sim time."""
        s = self.settings
        pairs = self._per_pair(batch)
        settling = self._settling
        out: list[ContactSound] = []
        for key, onset in self._candidates.items():
            current = pairs.get(key)
            after = 0.0 if current is None else current.impulse
            if onset.impulse >= s.min_impulse and onset.impulse > s.spike_ratio * after:
                self._emit(key, onset, now, out)
                self._pairs[key].steady = after
            else:  # it was resting weight, not an impact
                self._pairs[key].steady = max(onset.impulse, after)
        candidates = self._candidates
        self._candidates = {}
        for key, hit in pairs.items():
            pair = self._pairs.get(key)
            quiet = bool(settling) and (settling.get(key[0], -_INF) > now
                                        or settling.get(key[1], -_INF) > now)
            if pair is None or now - pair.last_seen > s.forget_after:
                self._pairs[key] = _Pair(steady=hit.impulse, last_seen=now,
                                         last_sound=-_INF if pair is None else pair.last_sound)
                if not quiet:
                    self._candidates[key] = hit
                continue
            pair.last_seen = now
            if key in candidates:
                continue
            spike = hit.impulse > s.spike_ratio * pair.steady
            if spike and not quiet and hit.impulse >= s.min_impulse:
                self._emit(key, hit, now, out)
            if hit.impulse > pair.steady and not spike:  # peak hold against solver jitter
                pair.steady = hit.impulse
            else:  # falls slowly; a load that stays after a blow becomes the new rest
                pair.steady += s.smoothing * (hit.impulse - pair.steady)
        self._calls += 1
        if self._calls % 64 == 0:
            horizon = now - s.forget_after - s.pair_interval
            self._pairs = {k: p for k, p in self._pairs.items()
                           if p.last_seen >= horizon or k in self._candidates}
            self._settling = {b: t for b, t in settling.items() if t > now}
        return out

    def _emit(self, key: tuple[int, int], hit: ContactSound, now: float,
              out: list[ContactSound]) -> None:
        pair = self._pairs[key]
        if now - pair.last_sound < self.settings.pair_interval:
            return
        pair.last_sound = now
        out.append(ContactSound(hit.a, hit.b, hit.position, hit.impulse,
                                self.gain(hit.impulse)))

    @staticmethod
    def _per_pair(batch: np.ndarray) -> dict[tuple[int, int], ContactSound]:
        """Per unordered body pair: the summed impulse of its contact points, heard at
        the strongest one. The sum, unlike any one point, stays steady while a solver
        moves the weight of a resting body between its contact points."""
        if len(batch) == 0:
            return {}
        a, b = batch["a"], batch["b"]
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        order = np.lexsort((-batch["impulse"], hi, lo))
        lo_s, hi_s = lo[order], hi[order]
        first = np.ones(len(order), dtype=bool)
        first[1:] = (lo_s[1:] != lo_s[:-1]) | (hi_s[1:] != hi_s[:-1])
        starts = np.flatnonzero(first)
        totals = np.add.reduceat(batch["impulse"][order], starts)
        rows = order[starts]
        picked = batch[rows]
        return {
            (lo_, hi_): ContactSound(a_, b_, tuple(p), j, 0.0)
            for lo_, hi_, a_, b_, p, j in zip(
                lo[rows].tolist(), hi[rows].tolist(), picked["a"].tolist(),
                picked["b"].tolist(), picked["position"].tolist(), totals.tolist(),
                strict=True)
        }
