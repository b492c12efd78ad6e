"""An author's post-processing passes change the image as written and switch at run time."""

from __future__ import annotations

import numpy as np
import pytest
from render_helpers import H, W, floor, pixel_at

from components import Shape, Visual
from services.render import PostPass

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
    from services.render.math3d import project

    eye = r.camera.eyes(W, H)[0]
    x, y, _ = project(np.asarray(point, float), eye.view, eye.proj, W, H)
    return int(x), int(y)


SHIFT = """#version 330
in vec2 v_uv;
uniform sampler2D u_scene;
uniform vec2 u_offset;
uniform float u_mix;
out vec4 f_color;
void main() {
    vec4 base = texture(u_scene, v_uv);
    f_color = mix(base, texture(u_scene, v_uv - u_offset), u_mix);
}
"""

ECHO = """#version 330
in vec2 v_uv;
uniform sampler2D u_scene;
uniform sampler2D u_previous;
uniform int u_first;
out vec4 f_color;
void main() {
    vec4 now = texture(u_scene, v_uv);
    f_color = u_first == 1 ? now : mix(now, texture(u_previous, v_uv), 0.6);
}
"""


def test_pass_switches_off_and_on_and_takes_uniforms_at_run_time(make_renderer):
    r = _spot_scene(make_renderer, [PostPass("shift", source=SHIFT,
                                             uniforms={"u_offset": (0.25, 0.0), "u_mix": 0.5})])
    x, y = _xy(r, SPOT)
    shift = int(0.25 * W)
    r.render()
    image = r.read_pixels().astype(float)
    assert 100 < image[y, x].mean() < 160 and 100 < image[y, x + shift].mean() < 160
    r.enable_post("shift", False)
    r.render()
    assert r.read_pixels()[y, x + shift].mean() < 5
    assert r.read_pixels()[y, x].mean() > 200
    r.enable_post("shift", True)
    r.set_post_uniform("shift", "u_mix", 0.25)
    r.render()
    assert 50 < r.read_pixels()[y, x + shift].mean() < 80


def test_a_feedback_pass_reads_its_own_last_output(make_renderer):
    r = _spot_scene(make_renderer, [PostPass("echo", source=ECHO, feedback=True)])
    x, y = _xy(r, SPOT)
    r.render()
    r.set_pose(1, (1.5, 0.0, 0.5), (1.0, 0.0, 0.0, 0.0))
    r.render()
    trail = r.read_pixels()[y, x].mean()
    assert 0.5 * 255 < trail < 0.7 * 255  # 60% of last frame's white
    r.render()
    assert r.read_pixels()[y, x].mean() == pytest.approx(trail * 0.6, abs=4)


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


def test_floor_pixel_helper_matches_post_free_render(make_renderer):
    r = make_renderer()
    floor(r)
    r.render()
    assert pixel_at(r, r.read_pixels(), (0.0, 0.0, 0.0)).mean() > 50
