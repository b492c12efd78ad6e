"""User shader states (paper Listings 3 and 4): uniforms at run time, errors with file:line."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from render_helpers import pixel_at

from components import Shape, Visual
from services.render import (
    FragmentShader,
    ShaderLibrary,
    ShaderProgram,
    ShaderState,
    Uniform,
    VertexShader,
)
from services.render.shaders import parse_driver_log

CENTRE = (0.0, 0.0, 0.6)


def _toon_library() -> ShaderLibrary:
    """Listing 3/4 of the paper, as the scene factory hands it over."""
    return ShaderLibrary(
        vertex_shaders=[VertexShader("toon_vertex", "shaders/toon.vert")],
        fragment_shaders=[FragmentShader("toon_fragment", "shaders/toon.frag"),
                          FragmentShader("broken", "shaders/broken.frag"),
                          FragmentShader("tint", "shaders/tint.frag")],
        programs=[ShaderProgram("toon", "toon_vertex", "toon_fragment", enable=True),
                  ShaderProgram("broken", "toon_vertex", "broken"),
                  ShaderProgram("tint", None, "tint")],
        states=[ShaderState("toon", "toon", [Uniform("DiffuseColor", (0.0, 0.25, 1.0)),
                                             Uniform("PhongColor", (0.75, 0.75, 1.0)),
                                             Uniform("Edge", 0.3), Uniform("Phong", 0.98)]),
                ShaderState("broken", "broken", [Uniform("Tint", (1.0, 0.0, 0.0))]),
                ShaderState("tint", "tint", [Uniform("Tint", (1.0, 1.0, 0.0))])],
    )


def _scene(make_renderer, state: str, color=(0.2, 0.9, 0.2, 1.0)):
    r = make_renderer()
    r.load_shaders(_toon_library())
    r.add(1, Visual(shapes=[Shape("sphere", (0.6,))], shader_state=state, color=color),
          position=CENTRE)
    return r


def test_legacy_toon_shader_draws_its_diffuse_colour(make_renderer):
    r = _scene(make_renderer, "toon")
    r.render()
    rgb = pixel_at(r, r.read_pixels(), (0.4, 0.0, 0.6))  # the band between edge and highlight
    assert np.allclose(rgb, (0, 0.25 * 255, 255), atol=3), rgb


def test_uniform_changed_at_run_time_changes_pixels(make_renderer):
    r = _scene(make_renderer, "toon")
    r.render()
    before = pixel_at(r, r.read_pixels(), (0.4, 0.0, 0.6))
    r.set_uniform("toon", "DiffuseColor", (1.0, 0.0, 0.0))  # what Lua's setUniform calls
    r.render()
    after = pixel_at(r, r.read_pixels(), (0.4, 0.0, 0.6))
    assert before[2] > 200 and after[0] > 200 and after[2] < 5


def test_modern_fragment_only_program_uses_the_default_vertex_stage(make_renderer):
    r = _scene(make_renderer, "tint")
    r.render()
    assert np.allclose(pixel_at(r, r.read_pixels(), CENTRE), (255, 255, 0), atol=2)
    r.set_uniform("tint", "Tint", [0.0, 1.0, 1.0])
    r.render()
    assert np.allclose(pixel_at(r, r.read_pixels(), CENTRE), (0, 255, 255), atol=2)


def test_broken_shader_falls_back_and_reports_file_and_line(make_renderer, caplog):
    with caplog.at_level(logging.ERROR, logger="colosseum.render"):
        r = _scene(make_renderer, "broken", color=(0.1, 0.9, 0.1, 1.0))
    r.render()
    report = "\n".join(r.errors)
    assert "broken.frag:6:" in report and "undefined_thing" in report
    assert "falls back to the default material" in report
    assert "broken.frag:6:" in caplog.text
    rgb = pixel_at(r, r.read_pixels(), CENTRE)  # drawn in its own colour, default-lit
    assert rgb[1] > 2 * rgb[0] and rgb[1] > 2 * rgb[2]


def test_unknown_state_and_uniform_are_clear_errors(make_renderer):
    r = _scene(make_renderer, "toon")
    with pytest.raises(KeyError, match="did you mean 'toon'"):
        r.set_uniform("tono", "Edge", 0.1)
    with pytest.raises(ValueError, match="did you mean 'DiffuseColor'"):
        r.set_uniform("toon", "Diffusecolor", (1.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="takes 3 values"):
        r.set_uniform("toon", "DiffuseColor", (1.0, 0.0))


def test_missing_shader_file_is_reported_and_objects_still_draw(make_renderer, tmp_path):
    r = make_renderer(root=tmp_path)
    r.load_shaders(ShaderLibrary(
        fragment_shaders=[FragmentShader("f", "shaders/nope.frag", origin="main.scene:4:3")],
        programs=[ShaderProgram("p", None, "f")], states=[ShaderState("s", "p")]))
    assert any("main.scene:4:3" in e and "nope.frag" in e for e in r.errors)
    r.add(1, Visual(shapes=[Shape("sphere", (0.6,))], shader_state="s", color=(1, 0, 0, 1)),
          position=CENTRE)
    r.render()
    assert pixel_at(r, r.read_pixels(), CENTRE)[0] > 100


def test_driver_logs_of_other_vendors_are_understood():
    files = {"vertex_shader": "a.vert", "fragment_shader": "b.frag"}
    nvidia = "fragment_shader\n===\n0(12) : error C1008: undefined variable \"x\"\n"
    amd = "vertex_shader\n===\nERROR: 0:7: 'y' : undeclared identifier\n"
    assert str(parse_driver_log(nvidia, files)[0]).startswith("b.frag:12:0: error: C1008")
    assert str(parse_driver_log(amd, files)[0]).startswith("a.vert:7:0: error: 'y'")


def test_simple_shader_with_an_mvp_uniform_draws_each_object(make_renderer, tmp_path):
    (tmp_path / "s.vert").write_text(
        "#version 330\nin vec3 in_position;\nuniform mat4 mvp;\n"
        "void main() { gl_Position = mvp * vec4(in_position, 1.0); }\n")
    (tmp_path / "s.frag").write_text(
        "#version 330\nuniform vec3 Colour;\nout vec4 c;\nvoid main() { c = vec4(Colour, 1.0); }\n")
    r = make_renderer(root=tmp_path)
    r.load_shaders(ShaderLibrary([VertexShader("v", "s.vert")], [FragmentShader("f", "s.frag")],
                                 [ShaderProgram("p", "v", "f")],
                                 [ShaderState("s", "p", [Uniform("Colour", (1.0, 0.0, 1.0))])]))
    spots = [(-1.0, 0.0, 0.5), (1.0, 0.0, 0.5)]
    for i, p in enumerate(spots):
        r.add(i, Visual(shapes=[Shape("box", (0.5, 0.5, 0.5))], shader_state="s"), position=p)
    r.render()
    image = r.read_pixels()
    for p in spots:
        assert np.allclose(pixel_at(r, image, p), (255, 0, 255), atol=1)
    assert r.stats.draw_calls == 2


@pytest.mark.parametrize("header", ["", "#version 120\n", "#version 330\nout vec4 c;\n"])
def test_error_line_numbers_are_the_authors_lines(gl_ctx, tmp_path, header):
    from services.render.shaders import ShaderError, compile_program

    body = "void main() {\n    bogus_call();\n}\n"
    source = header + "// comment\n" + body
    line = source.splitlines().index("    bogus_call();") + 1
    with pytest.raises(ShaderError) as info:
        compile_program(gl_ctx, "#version 330\nvoid main() { gl_Position = vec4(0.0); }\n",
                        source, "v.vert", "f.frag")
    assert info.value.diagnostics[0].file == "f.frag"
    assert info.value.diagnostics[0].line == line
