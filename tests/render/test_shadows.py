"""Shadow mapping: a Shadower darkens the floor under it; Shadowed controls who receives."""

from __future__ import annotations

from render_helpers import floor, pixel_at

from components import Shape, Visual
from services.render import LightInfo

UNDER = (0.0, 0.0, 0.0)  # floor point straight below the box (the light shines down)


def _floor_under_box(make_renderer, shadower: bool, shadowed: bool = True) -> float:
    r = make_renderer()
    r.lights = [LightInfo("directional", direction=(0.0, 0.0, -1.0), shadows=True)]
    r.camera = r.camera.looking_at((0.0, -3.0, 4.0), (0.0, 0.0, 0.0))
    floor(r, shadowed=shadowed)
    r.add(1, Visual(shapes=[Shape("box", (0.5, 0.5, 0.5))], shadower=shadower),
          position=(0.0, 0.6, 1.2))  # hangs above a point the camera sees past it
    r.render()
    return pixel_at(r, r.read_pixels(), (0.0, 0.6, 0.0)).mean()


def test_shadower_darkens_the_floor_below_it(make_renderer):
    lit = _floor_under_box(make_renderer, shadower=False)
    shaded = _floor_under_box(make_renderer, shadower=True)
    assert shaded < 0.6 * lit, (shaded, lit)


def test_floor_that_is_not_shadowed_receives_no_shadow(make_renderer):
    lit = _floor_under_box(make_renderer, shadower=False)
    unshadowed = _floor_under_box(make_renderer, shadower=True, shadowed=False)
    assert abs(unshadowed - lit) < 2


def test_shadow_falls_along_the_light_direction(make_renderer):
    """A slanted light moves the shadow off the spot right below the caster."""
    r = make_renderer()
    r.lights = [LightInfo("directional", direction=(1.0, 0.0, -1.0))]
    r.camera = r.camera.looking_at((0.0, -4.0, 5.0), (0.5, 0.0, 0.0))
    floor(r)
    r.add(1, Visual(shapes=[Shape("sphere", (0.3,))]), position=(0.0, 0.0, 1.0))
    r.render()
    image = r.read_pixels()
    beside = pixel_at(r, image, (1.0, 0.0, 0.0)).mean()  # light travels +X as it falls 1 m
    far = pixel_at(r, image, (-1.0, 0.0, 0.0)).mean()
    assert beside < 0.6 * far


def test_spot_light_casts_a_shadow_too(make_renderer):
    r = make_renderer()
    r.lights = [LightInfo("spot", position=(0.0, 0.6, 4.0), direction=(0.0, 0.0, -1.0),
                          cutoff=40.0, intensity=2.0)]
    r.camera = r.camera.looking_at((0.0, -3.0, 4.0), (0.0, 0.0, 0.0))
    floor(r)
    r.add(1, Visual(shapes=[Shape("box", (0.5, 0.5, 0.5))]), position=(0.0, 0.6, 1.2))
    r.render()
    image = r.read_pixels()
    under = pixel_at(r, image, (0.0, 0.6, 0.0)).mean()
    beside = pixel_at(r, image, (0.8, 0.6, 0.0)).mean()
    assert under < 0.6 * beside
