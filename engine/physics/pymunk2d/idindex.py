"""A vectorised lookup from pymunk body ids to table rows.

pymunk's batch API names bodies by ``Body.id``, a pointer-sized number; contacts
need the row (and so the key) of both bodies of every arbiter each step. An
open-addressing hash table in numpy answers thousands of lookups in a fixed handful
of array operations (every probe of every query at once), without a Python loop
per body.
"""

from __future__ import annotations

import numpy as np

_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)


class IdIndex:
    """Maps int64 ids to rows ``0..n-1``; unknown ids map to ``n``."""

    def __init__(self, ids: np.ndarray) -> None:
        ids = np.asarray(ids, dtype=np.int64)
        n = len(ids)
        self.missing = n
        self._bits = max(4, (4 * n).bit_length())
        size = 1 << self._bits
        # linear probing runs past the end instead of wrapping: room for the overflow
        table = np.zeros(size + n + 1, np.int64)  # 0 = empty: pointers are never 0
        rows = np.full(size + n + 1, n, np.intp)
        slot = self._hash(ids)
        pending = np.arange(n)
        probes = 1
        while pending.size:
            s = slot[pending]
            free = table[s] == 0
            taken, first = np.unique(s[free], return_index=True)
            winners = pending[free][first]
            table[taken] = ids[winners]
            rows[taken] = winners
            placed = np.zeros(n, bool)
            placed[winners] = True
            pending = pending[~placed[pending]]
            if pending.size:
                slot[pending] += 1
                probes += 1
        self._ids = table[: size + probes]
        self._rows = rows[: size + probes]
        self._window = np.arange(probes)

    def _hash(self, ids: np.ndarray) -> np.ndarray:
        """splitmix64's finaliser: pointers are evenly spaced, so mix every bit."""
        h = ids.view(np.uint64)
        h = (h ^ (h >> np.uint64(30))) * _M1
        h = (h ^ (h >> np.uint64(27))) * _M2
        h ^= h >> np.uint64(31)
        return (h & np.uint64((1 << self._bits) - 1)).astype(np.intp)

    def rows(self, ids: np.ndarray) -> np.ndarray:
        """Row of each id (``n`` where the id is unknown)."""
        ids = np.asarray(ids, dtype=np.int64)
        slot = self._hash(ids)
        out = self._rows[slot]
        miss = np.flatnonzero(self._ids[slot] != ids)
        if miss.size:  # the few that collided: all their later probes at once
            slots = slot[miss, None] + self._window
            match = self._ids[slots] == ids[miss, None]
            first = match.argmax(axis=1)
            found = match[np.arange(miss.size), first]
            out[miss] = np.where(found, self._rows[slots[np.arange(miss.size), first]],
                                 self.missing)
        return out
