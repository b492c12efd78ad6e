"""Orders of conditions: Latin squares, balanced Latin squares (Williams designs), random
orders seeded per participant, and the fixed order.

A row of a square is an order of the conditions ``0 .. n-1``. In a Latin square every
condition stands once in every row and once in every column (position). In a balanced
Latin square (Williams, 1949) every condition also follows every other exactly once
(first-order carry-over balanced); for an odd ``n`` that takes the square and its mirror,
``2n`` rows.

>>> latin_square(3)
[[0, 1, 2], [1, 2, 0], [2, 0, 1]]
>>> balanced_latin_square(4)
[[0, 1, 3, 2], [1, 2, 0, 3], [2, 3, 1, 0], [3, 0, 2, 1]]
>>> len(balanced_latin_square(3))
6
"""

from __future__ import annotations

import numpy as np

#: The orderings an Experiment block's ``Order`` names.
ORDERS = ("random", "latin", "balanced", "fixed")


def latin_square(n: int) -> list[list[int]]:
    """The cyclic Latin square of ``n`` conditions: row ``r`` is ``r, r+1, ...`` mod n."""
    return [[(r + c) % n for c in range(n)] for r in range(n)]


def balanced_latin_square(n: int) -> list[list[int]]:
    """A Williams design: ``n`` rows for even ``n``, ``2n`` (the rows and their mirrors)
    for odd ``n``; every condition in every position equally often and every ordered
    pair of neighbours equally often."""
    first, low, high = [0], 1, n - 1
    for i in range(1, n):  # 0, 1, n-1, 2, n-2, ...
        if i % 2:
            first.append(low)
            low += 1
        else:
            first.append(high)
            high -= 1
    rows = [[(c + r) % n for c in first] for r in range(n)]
    if n % 2:
        rows += [row[::-1] for row in rows]
    return rows


def square(order: str, n: int) -> list[list[int]]:
    """The rows participants take in turn for ``order`` (latin, balanced); fixed: one row."""
    if order == "latin":
        return latin_square(n)
    if order == "balanced":
        return balanced_latin_square(n)
    return [list(range(n))]


def rng_for(seed: int, participant: int, *more: int) -> np.random.Generator:
    """The random generator of one participant (and block): the same numbers every time
    the participant's session is run or resumed, different for every participant."""
    return np.random.default_rng([int(seed) & 0xFFFFFFFF, int(participant), *map(int, more)])


def random_order(n: int, seed: int, participant: int, block: int) -> list[int]:
    """A random order of ``n`` conditions for a participant's block."""
    return [int(i) for i in rng_for(seed, participant, block).permutation(n)]
