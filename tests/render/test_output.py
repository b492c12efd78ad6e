"""Screenshots, the HUD line, instancing and lights."""

from __future__ import annotations

import numpy as np
from PIL import Image
from render_helpers import H, W, floor, pixel_at

from components import Shape, Visual
from services.render import LightInfo
from services.render.hud import hud_line


def test_screenshot_is_a_readable_png_of_the_frame(make_renderer, tmp_path):
    r = make_renderer()
    floor(r)
    r.add(1, Visual(shapes=[Shape("box", (1, 1, 1))], color=(1, 0, 0, 1)), position=(0, 0, 0.5))
    r.render()
    path = r.screenshot(tmp_path / "shots" / "frame.png")
    with Image.open(path) as img:
        assert img.format == "PNG" and img.size == (W, H)
        assert np.array_equal(np.asarray(img.convert("RGB")), r.read_pixels())


def test_hud_line_shows_and_hides(make_renderer):
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    r.hud.text = hud_line(59.9, 1.25, 0.98)
    assert "59.9 fps" in r.hud.text and "1.25 ms" in r.hud.text and "x0.98" in r.hud.text
    r.render()
    assert r.read_pixels()[:20, :80].max() == 0  # off by default
    r.hud.toggle()
    r.render()
    assert r.read_pixels()[:20, :80].max() > 200  # white text in the top-left corner


def test_thousand_boxes_are_one_instanced_draw(make_renderer):
    r = make_renderer()
    rng = np.random.default_rng(3)
    for i in range(1000):
        r.add(i, Visual(shapes=[Shape("box", (0.1, 0.1, 0.1))],
                        color=(*rng.uniform(0.2, 1.0, 3), 1.0)),
              position=(*rng.uniform(-2, 2, 2), rng.uniform(0.0, 1.0)))
    floor(r)
    r.render()
    assert r.stats.instances == 1001
    assert r.stats.draw_calls == 2  # all boxes in one call, the floor in another
    assert r.stats.shadow_draw_calls == 1  # planes cast no shadow
    r.instancing = False  # the benchmark's reference: one draw call per box
    r.render()
    assert r.stats.draw_calls == 1001


def test_instanced_boxes_keep_their_own_colours(make_renderer):
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    colours = [(1, 0, 0, 1), (0, 1, 0, 1)]
    spots = [(-1.0, 0.0, 0.5), (1.0, 0.0, 0.5)]
    for i, (c, p) in enumerate(zip(colours, spots, strict=True)):
        r.add(i, Visual(shapes=[Shape("box", (0.5, 0.5, 0.5))], color=c), position=p)
    r.render()
    assert r.stats.draw_calls == 1
    image = r.read_pixels()
    left, right = pixel_at(r, image, spots[0]), pixel_at(r, image, spots[1])
    assert left[0] > 2 * left[1] and right[1] > 2 * right[0]


def test_point_and_spot_lights_light_what_they_face(make_renderer):
    r = make_renderer()
    floor(r)
    r.ambient = (0.0, 0.0, 0.0)
    r.lights = [LightInfo("spot", position=(-1.5, 0.0, 3.0), direction=(0.0, 0.0, -1.0),
                          cutoff=20.0, intensity=3.0, shadows=False)]
    r.render()
    image = r.read_pixels()
    inside = pixel_at(r, image, (-1.5, 0.0, 0.0)).mean()
    outside = pixel_at(r, image, (1.5, 0.0, 0.0)).mean()
    assert inside > 60 and outside < 5
    r.lights = [LightInfo("point", position=(1.5, 0.0, 1.0), intensity=2.0, shadows=False)]
    r.render()
    image = r.read_pixels()
    near = pixel_at(r, image, (1.5, 0.0, 0.0)).mean()
    far = pixel_at(r, image, (-1.5, 0.0, 0.0)).mean()
    assert near > 2 * far


def test_invisible_and_removed_objects_are_not_drawn(make_renderer):
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    r.add(1, Visual(shapes=[Shape("box", (1, 1, 1))], visible=False), position=(0, 0, 0.5))
    r.add(2, Visual(shapes=[Shape("box", (1, 1, 1))]), position=(1.5, 0, 0.5))
    r.remove(2)
    r.render()
    assert r.read_pixels().max() == 0
