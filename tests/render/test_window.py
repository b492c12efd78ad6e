"""The window backend (moderngl-window with pyglet); runs where a display exists, e.g. under
``xvfb-run``, and is skipped on headless machines."""

from __future__ import annotations

import pytest

from components import Shape, Visual
from services.render import Renderer, create_target, has_display

pytestmark = pytest.mark.skipif(not has_display(), reason="no display (try xvfb-run)")


def test_window_opens_draws_and_reads_back():
    target = create_target("auto", (160, 120))
    try:
        assert target.kind == "window"
        renderer = Renderer(target)
        renderer.add(1, Visual(shapes=[Shape("box", (1, 1, 1))], color=(1, 0, 0, 1)),
                     position=(0.0, 0.0, 0.5))
        renderer.render()
        centre = renderer.read_pixels()[60, 80]
        assert centre[0] > 100 and centre[1] < 40
        assert not target.is_closing
        assert target.key_names[target.window.keys.F1] == "f1"
        renderer.release()
    finally:
        target.close()
