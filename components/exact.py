"""Numbers a saved file writes so that its reader gets them back to the bit: the file says
degrees (or per degree) where the engine holds radians, and the save functions of blocks
(components.blocks) and engine.scene.snapshot write through these.

>>> import math
>>> math.radians(exact_degrees(0.1)) == 0.1
True
"""

from __future__ import annotations

import math
from collections.abc import Callable


def exact_degrees(rad: float) -> float:
    """Degrees ``d`` with ``math.radians(d) == rad`` when such a float exists (nearest else).

    A saved state writes angular velocities in degrees; this keeps the reload bit-exact
    for most values and within one ulp for the rest.
    """
    return exact_preimage(math.radians, rad, math.degrees(rad))


def exact_preimage(forward: Callable[[float], float], value: float, guess: float) -> float:
    """A float ``x`` within four ulps of ``guess`` with ``forward(x) == value`` (``guess``
    when there is none): what a saved file writes for a value its reader converts (degrees
    to radians, per degree to per radian), so the reload gives the value to the bit."""
    up = down = guess
    for _ in range(4):
        if forward(up) == value:
            return up
        if forward(down) == value:
            return down
        up, down = math.nextafter(up, math.inf), math.nextafter(down, -math.inf)
    return guess
