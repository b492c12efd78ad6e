"""Overlays (a virtual hand pushed into a table) are drawn over everything, see-through."""

from __future__ import annotations

import numpy as np
from render_helpers import pixel_at

from components import Shape, Visual
from services.render import CameraView

RED = (1.0, 0.1, 0.1)


def scene(renderer, overlay: bool, alpha: float) -> np.ndarray:
    """A grey slab between the camera and a red box; returns the frame."""
    renderer.camera = CameraView.looking_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
    renderer.add(1, Visual(shapes=[Shape("box", (3.0, 3.0, 0.1))], color=(0.5, 0.5, 0.5, 1)),
                 (0.0, 0.0, 1.0))
    renderer.add(2, Visual(shapes=[Shape("box", (0.6, 0.6, 0.2))], color=(*RED, alpha),
                           overlay=overlay), (0.0, 0.0, 0.0))
    renderer.render()
    return renderer.read_pixels()


def test_an_overlay_shows_through_what_covers_it_blended_by_its_alpha(make_renderer):
    hidden = scene(make_renderer(), overlay=False, alpha=1.0)
    solid = scene(make_renderer(), overlay=True, alpha=1.0)
    through = scene(make_renderer(), overlay=True, alpha=0.45)
    centre = (0.0, 0.0, 1.05)  # the slab's top, straight above the box
    r = make_renderer()
    r.camera = CameraView.looking_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
    grey, red, mix = (pixel_at(r, image, centre) for image in (hidden, solid, through))
    assert abs(grey[0] - grey[1]) < 8  # the slab hides the box when it is no overlay
    assert red[0] > 4 * max(red[1], 1.0)  # drawn over the slab (red, in the slab's shadow)
    # blended: between the slab's grey and the box's red, by its alpha
    expected = 0.45 * red + 0.55 * grey
    assert np.allclose(mix, expected, atol=4)
