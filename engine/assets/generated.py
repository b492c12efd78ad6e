"""Images the engine makes rather than reads: named ``generated:NAME`` where a texture file
would be (a Visual's ``texture``, a scene's ``Texture``: a network server writes the
objects it spawned, hands' markers included, into the state its nodes load), made once
per run by the asset service, so nothing binary is shipped for them.

:data:`MARKER_BALL` is the virtual hands' marker (paper figure 7: a textured ball where
the real hand is): eight gores of longitude by four bands of latitude, light and dark, so
the tracker's turning shows on it as well as its place.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

PREFIX = "generated:"
MARKER_BALL = PREFIX + "marker-ball"
#: The marker's two tones (grey levels; its Visual colour tints them).
LIGHT, DARK = 255, 96


def marker_ball(size: int = 64) -> np.ndarray:
    """RGBA ``(size, size, 4)`` uint8: an 8 x 4 checker in the sphere's (u, v), so each cell
    spans 45 degrees of longitude and of latitude."""
    u = np.arange(size) * 8 // size
    v = np.arange(size) * 4 // size
    light = (v[:, None] + u[None, :]) % 2 == 0
    image = np.full((size, size, 4), 255, np.uint8)
    image[..., :3] = np.where(light, LIGHT, DARK)[..., None]
    return image


#: name -> what makes its RGBA pixels
IMAGES: dict[str, Callable[[], np.ndarray]] = {MARKER_BALL: marker_ball}


def is_generated(name: object) -> bool:
    """Whether ``name`` is an image made here, not a file (no file check, no rebasing)."""
    return str(name) in IMAGES
