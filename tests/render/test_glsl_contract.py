"""The GLSL contract (docs/GLSL.md) is the renderer's, and a uniform nothing sets is told
(issue 20: an object drawn with ``u_projection`` where the engine sets ``u_proj`` vanished)."""

from __future__ import annotations

import logging
import re
from pathlib import Path

import numpy as np
from render_helpers import pixel_at

from components import Shape, Visual
from services.render import glsl
from services.render.lights import LightInfo
from services.render.shaders import (
    FragmentShader,
    ShaderLibrary,
    ShaderProgram,
    ShaderState,
    Uniform,
    VertexShader,
)
from tools.docs import DOCS, manual_pages

GLSL_PAGE = DOCS / "GLSL.md"


def test_the_page_is_generated_from_the_contract() -> None:
    assert GLSL_PAGE.read_text(encoding="utf-8") == glsl.contract_markdown(), \
        "docs/GLSL.md is stale: run python -m tools.docs"
    assert "GLSL.md" in manual_pages()  # in the manual's navigation (mkdocs.yml)


def test_the_renderer_sets_exactly_the_uniforms_the_contract_names(make_renderer) -> None:
    r = make_renderer()
    eye = r.camera.eyes(64, 48)[0]
    lights = [LightInfo("spot", position=(0.0, 0.0, 5.0)), LightInfo("directional")]
    values = r.frame_uniforms(eye, lights, 0, np.eye(4))
    assert list(values) == list(glsl.ENGINE_UNIFORMS)
    for name, value in values.items():  # each the size its declared type says
        kind = glsl.ENGINE_UNIFORMS[name][0]
        count = int(re.search(r"\[(\d+)\]", kind)[1]) if "[" in kind else 1
        width = {"mat4": 16, "vec3": 3}.get(kind.split("[")[0], 1)
        assert np.size(value) == count * width, name
    assert values["u_light_count"] == 2 and values["u_light_kind"][:2].tolist() == [2, 0]
    # the built-in lit program declares what it reads under these names
    declared = set(re.findall(r"uniform \w+ (\w+)", glsl.LIT_VERTEX + glsl.lit_fragment((0,), 0)))
    assert declared <= set(glsl.ENGINE_UNIFORMS)


WRONG_NAME = """\
#version 330
in vec3 in_position;
in mat4 i_model;
uniform mat4 u_view;
uniform mat4 u_projection;
void main() { gl_Position = u_projection * u_view * i_model * vec4(in_position, 1.0); }
"""
PLAIN = "#version 330\nuniform vec3 Tint;\nout vec4 c;\nvoid main() { c = vec4(Tint, 1.0); }\n"


def _draw(make_renderer, folder: Path, vertex: str) -> tuple[object, np.ndarray]:
    (folder / "v.vert").write_text(vertex)
    (folder / "f.frag").write_text(PLAIN)
    r = make_renderer(root=folder)
    r.load_shaders(ShaderLibrary([VertexShader("v", "v.vert")], [FragmentShader("f", "f.frag")],
                                 [ShaderProgram("p", "v", "f")],
                                 [ShaderState("s", "p", [Uniform("Tint", (1.0, 0.0, 1.0))])]))
    r.add(1, Visual(shapes=[Shape("box", (1.0, 1.0, 1.0))], shader_state="s"),
          position=(0.0, 0.0, 0.5))
    r.render()
    return r, pixel_at(r, r.read_pixels(), (0.0, 0.0, 0.5))


def test_a_uniform_nothing_sets_is_told_with_its_file_and_the_engines_name(
        make_renderer, tmp_path: Path, caplog) -> None:
    with caplog.at_level(logging.WARNING, "colosseum.render"):
        _, vanished = _draw(make_renderer, tmp_path, WRONG_NAME)
    told = [r.getMessage() for r in caplog.records if "never set" in r.getMessage()]
    assert told == [f"{tmp_path / 'v.vert'}:5: uniform 'u_projection' of program 'p' is never "
                    "set: the engine does not supply it and no ShaderState gives it a value, so "
                    "it stays 0 (a zero matrix draws nothing; a script's setUniform is the only "
                    "other way); did you mean 'u_proj', which the engine supplies?"]
    assert not np.allclose(vanished, (255, 0, 255), atol=2)  # what the warning is about
    caplog.clear()
    with caplog.at_level(logging.WARNING, "colosseum.render"):
        _, drawn = _draw(make_renderer, tmp_path, WRONG_NAME.replace("u_projection", "u_proj"))
    assert np.allclose(drawn, (255, 0, 255), atol=2)
    assert not [r for r in caplog.records if "never set" in r.getMessage()]
    caplog.clear()
    one_line = WRONG_NAME.replace("in mat4 i_model;\nuniform mat4 u_view;\nuniform",
                                  "in mat4 i_model; uniform mat4 u_view; uniform")
    with caplog.at_level(logging.WARNING, "colosseum.render"):  # its file, not the other
        _draw(make_renderer, tmp_path, one_line)
    assert [r.getMessage().split(": uniform")[0] for r in caplog.records
            if "never set" in r.getMessage()] == [f"{tmp_path / 'v.vert'}:3"]
