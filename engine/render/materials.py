"""Textures for materials: image files through pillow, with a loud placeholder for missing ones.

A texture that cannot be read is replaced by a magenta/black checker so the author sees at a
glance which surface lost its image, and a warning names the file; the simulation goes on.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

log = logging.getLogger("colosseum.render")

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


def image_rgba(image: object) -> np.ndarray:
    """RGBA uint8 array of a PIL image or array, rows top to bottom."""
    from PIL import Image

    if isinstance(image, Image.Image):
        return np.asarray(image.convert("RGBA"), dtype=np.uint8)
    arr = np.asarray(image)
    if arr.dtype != np.uint8:
        arr = np.clip(arr * 255.0, 0, 255).astype(np.uint8)
    if arr.ndim == 2:
        arr = np.repeat(arr[:, :, None], 3, axis=2)
    if arr.shape[2] == 3:
        arr = np.concatenate([arr, np.full(arr.shape[:2] + (1,), 255, np.uint8)], axis=2)
    return arr


def load_texture_image(path: str | Path) -> tuple[np.ndarray, bool]:
    """Pixels of an image file, or the checker placeholder and a warning when unreadable.

    Returns ``(rgba, ok)``; ``ok`` is False when the placeholder stands in.
    """
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as img:
            return image_rgba(img), True
    except FileNotFoundError:
        log.warning("%s: texture file not found; drawing a checker placeholder", path)
    except (UnidentifiedImageError, OSError) as exc:
        log.warning("%s: cannot read texture (%s); drawing a checker placeholder", path, exc)
    return checker_image(), False
