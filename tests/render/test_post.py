"""Post-processing passes change the image as specified and switch at run time."""

from __future__ import annotations

import numpy as np
import pytest
from render_helpers import H, W, floor, pixel_at

from components import Shape, Visual
from engine.render import BUILTIN_PASSES, PostPass

SPOT = (0.0, 0.0, 0.5)


def _spot_scene(make_renderer, passes):
    """A white sphere on black, no lighting variation to speak of."""
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    r.ambient = (1.0, 1.0, 1.0)
    r.add(1, Visual(shapes=[Shape("sphere", (0.25,))], color=(1, 1, 1, 1)), position=SPOT)
    r.set_post_passes(passes)
    return r


def _xy(r, point):
    from engine.render.math3d import project

    eye = r.camera.eyes(W, H)[0]
    x, y, _ = project(np.asarray(point, float), eye.view, eye.proj, W, H)
    return int(x), int(y)


def test_double_vision_adds_a_shifted_copy(make_renderer):
    r = _spot_scene(make_renderer, [PostPass("double_vision",
                                             uniforms={"u_offset": (0.25, 0.0), "u_mix": 0.5})])
    r.render()
    image = r.read_pixels().astype(float)
    x, y = _xy(r, SPOT)
    shift = int(0.25 * W)
    original, copy = image[y, x].mean(), image[y, x + shift].mean()
    assert 100 < original < 160 and 100 < copy < 160  # each image at half strength
    assert image[y, x - shift].mean() < 5  # nothing on the other side


def test_pass_switches_off_and_on_at_run_time(make_renderer):
    r = _spot_scene(make_renderer, [PostPass("double_vision", uniforms={"u_offset": (0.25, 0)})])
    x, y = _xy(r, SPOT)
    r.enable_post("double_vision", False)
    r.render()
    assert r.read_pixels()[y, x + int(0.25 * W)].mean() < 5
    assert r.read_pixels()[y, x].mean() > 200
    r.enable_post("double_vision", True)
    r.set_post_uniform("double_vision", "u_mix", 0.25)
    r.render()
    assert 50 < r.read_pixels()[y, x + int(0.25 * W)].mean() < 80


def test_unilateral_neglect_hides_one_side(make_renderer):
    r = make_renderer()
    floor(r)
    r.render()
    plain = r.read_pixels().astype(float)
    r.set_post_passes([PostPass("unilateral_neglect", uniforms={"u_side": -1.0})])
    r.render()
    neglect = r.read_pixels().astype(float)
    assert neglect[:, : W // 4].max() < 3  # the left quarter is gone
    assert np.abs(neglect[:, 3 * W // 4:] - plain[:, 3 * W // 4:]).max() < 2  # right intact


def test_motion_blur_leaves_a_trail(make_renderer):
    r = _spot_scene(make_renderer, [PostPass("motion_blur", uniforms={"u_strength": 0.6})])
    x, y = _xy(r, SPOT)
    r.render()
    r.set_pose(1, (1.5, 0.0, 0.5), (1.0, 0.0, 0.0, 0.0))
    r.render()
    trail = r.read_pixels()[y, x].mean()
    assert 0.5 * 255 < trail < 0.7 * 255  # 60% of last frame's white
    r.render()
    assert r.read_pixels()[y, x].mean() == pytest.approx(trail * 0.6, abs=4)


def test_perspective_distortion_bends_the_image_but_not_its_centre(make_renderer):
    r = make_renderer()
    floor(r)
    r.add(1, Visual(shapes=[Shape("box", (0.5, 0.5, 0.5))], color=(1, 0, 0, 1)),
          position=(1.5, 0.0, 0.25))
    r.render()
    plain = r.read_pixels().astype(float)
    r.set_post_passes([PostPass("perspective_distortion", uniforms={"u_strength": 0.8})])
    r.render()
    bent = r.read_pixels().astype(float)
    assert np.abs(bent[H // 2, W // 2] - plain[H // 2, W // 2]).max() < 3
    assert np.abs(bent - plain).mean() > 3
    red = lambda img: np.nonzero((img[..., 0] > 120) & (img[..., 1] < 60))[1].mean()  # noqa: E731
    assert red(bent) < red(plain)  # barrel distortion pulls the off-centre box inward


def test_custom_pass_from_file_and_broken_pass_reported(make_renderer, tmp_path):
    (tmp_path / "invert.frag").write_text(
        "#version 330\nin vec2 v_uv;\nuniform sampler2D u_scene;\nout vec4 f_color;\n"
        "void main() { f_color = vec4(1.0 - texture(u_scene, v_uv).rgb, 1.0); }\n")
    (tmp_path / "bad.frag").write_text("#version 330\nout vec4 f_color;\n\nvoid main() { oops; }\n")
    r = make_renderer(root=tmp_path)
    r.background = (0.0, 0.0, 0.0)
    r.set_post_passes([PostPass("invert", file="invert.frag"), PostPass("bad", file="bad.frag")])
    assert any("bad.frag:4:" in e and "skipped" in e for e in r.errors)
    r.render()
    assert r.read_pixels().min() > 250  # black inverted to white; the bad pass left out
    with pytest.raises(KeyError, match="invert"):
        r.enable_post("bda", True)


def test_builtins_are_the_stroke_simulator_set():
    assert set(BUILTIN_PASSES) == {"double_vision", "motion_blur", "perspective_distortion",
                                   "unilateral_neglect"}


def test_floor_pixel_helper_matches_post_free_render(make_renderer):
    r = make_renderer()
    floor(r)
    r.render()
    assert pixel_at(r, r.read_pixels(), (0.0, 0.0, 0.0)).mean() > 50
