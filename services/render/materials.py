"""The placeholder drawn for a texture or model that cannot be read.

A magenta/black checker, so the author sees at a glance which surface lost its image
(the asset layer tells which file, and why); the simulation goes on.
"""

from __future__ import annotations

import numpy as np

#: Placeholder colours: magenta and black, impossible to mistake for real content.
CHECKER_A = (255, 0, 255, 255)
CHECKER_B = (0, 0, 0, 255)


def checker_image(size: int = 64, cells: int = 8) -> np.ndarray:
    """RGBA ``(size, size, 4)`` uint8 checkerboard used in place of a missing texture."""
    idx = (np.arange(size) * cells // size)
    mask = (idx[:, None] + idx[None, :]) % 2 == 0
    img = np.empty((size, size, 4), dtype=np.uint8)
    img[mask] = CHECKER_A
    img[~mask] = CHECKER_B
    return img
