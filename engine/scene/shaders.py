"""The shader blocks, declared on the block registry: ``VertexShader`` and
``FragmentShader`` name GLSL files, a ``ShaderProgram`` links two of them, and a
``ShaderState`` gives a program's uniforms values; an object's ``Visual { ShaderState }``
draws with one (services.render; docs/GLSL.md). Declared in this order: a program names
its shaders, so they are built first."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare
from engine.scene.postpass import uniforms


@dataclass(slots=True)
class ShaderStateSpec:
    program: str
    uniforms: dict[str, float | tuple[float, ...]]


@dataclass(slots=True)
class ShaderProgramSpec:
    vertex: str | None  # file path of the vertex shader
    fragment: str | None
    enabled: bool


def shader_file(kind: str) -> Callable[[Mapping[str, Any], BuildContext], list[Any]]:
    """The build of a ``VertexShader`` or ``FragmentShader`` block: its file, by
    (block, ID), for the programs that name it."""
    def build(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
        ctx.scene("shader_files")[(kind, str(v["ID"]))] = v["File"]
        return []
    return build


def build_shader_program(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``ShaderProgram`` block: the files of the two shaders it links."""
    files = ctx.scene("shader_files")
    ctx.scene("shader_programs")[v["ID"]] = ShaderProgramSpec(
        files.get(("VertexShader", v["VertexShader"])),
        files.get(("FragmentShader", v["FragmentShader"])), bool(v["Enable"]))
    return []


def build_shader_state(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``ShaderState`` block: a program and its uniforms' values."""
    ctx.scene("shader_states")[v["ID"]] = ShaderStateSpec(v["ShaderProgram"], uniforms(ctx))
    return []


def _shader_file(kind: str, stage: str, doc: str) -> BlockDeclaration:
    return declare(BlockDeclaration(
        f"{kind}Shader", inside=("Scene",), build=shader_file(f"{kind}Shader"), entity=False,
        doc=doc,
        keys=(Key("ID", "string", "", f"name other declarations use to refer to this {stage} "
                  "shader", required=True, example=f'"toon_{stage}"'),
              Key("File", "asset", None, "GLSL source file", required=True,
                  example=f'"shaders/toon.{stage[:4]}"'))))


VERTEX_SHADER_BLOCK = _shader_file("Vertex", "vertex",
                                   "a GLSL vertex shader file (see docs/GLSL.md)")
FRAGMENT_SHADER_BLOCK = _shader_file("Fragment", "fragment", "a GLSL fragment shader file")
SHADER_PROGRAM_BLOCK = declare(BlockDeclaration(
    "ShaderProgram", inside=("Scene",), build=build_shader_program, entity=False,
    doc="a vertex and a fragment shader linked together", keys=(
        Key("ID", "string", "", "name other declarations use to refer to this shader program",
            required=True, example='"toon"'),
        Key("VertexShader", "ref", None, "vertex shader ID (default: the engine's vertex "
            "stage)", ref="VertexShader", example='"toon_vertex"'),
        Key("FragmentShader", "ref", None, "fragment shader ID", ref="FragmentShader",
            example='"toon_fragment"'),
        Key("Enable", "bool", 1, "0 draws its objects with the default material"),
    )))
SHADER_STATE_BLOCK = declare(BlockDeclaration(
    "ShaderState", inside=("Scene",), build=build_shader_state, entity=False,
    doc="a program and values for its uniforms; objects draw with it", keys=(
        Key("ID", "string", "", "name other declarations use to refer to this shader state",
            required=True, example='"toon"'),
        Key("ShaderProgram", "ref", None, "the program whose uniforms it sets", required=True,
            ref="ShaderProgram", example='"toon"'),
        Key("Uniform", "struct", None, "a uniform's value", repeat=True, struct="Uniform"),
    )))
