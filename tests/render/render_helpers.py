"""Helpers shared by the render tests (pixel probes, a floor)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from components import Shape, Visual
from services.render import Renderer
from services.render.math3d import project

CONTENT = Path(__file__).parent / "content"
W, H = 160, 120


def floor(renderer: Renderer, key: int = 1000, **visual: object) -> None:
    renderer.add(key, Visual(shapes=[Shape("plane", (0.0, 0.0, 1.0, 0.0))], **visual))


def pixel_at(renderer: Renderer, image: np.ndarray, point: tuple[float, float, float]
             ) -> np.ndarray:
    """RGB (float) of the pixel where ``point`` projects with the renderer's camera."""
    h, w = image.shape[:2]
    eye = renderer.camera.eyes(w, h)[0]
    x, y, _ = project(np.asarray(point, float), eye.view, eye.proj, w, h)
    return image[int(y), int(x)].astype(float)
