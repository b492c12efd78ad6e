"""The ``PostPass`` block, declared on the block registry: a full-screen pass (your GLSL
fragment shader) over the drawn frame, a scene-wide setting (the scene's passes, in order)
that services.render.postprocess runs."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare


@dataclass(slots=True)
class PostPassSpec:
    """A ``PostPass`` block: a full-screen pass (a fragment shader file) over the frame."""

    id: str
    file: str
    uniforms: dict[str, float | tuple[float, ...]]
    enabled: bool
    feedback: bool
    origin: str


def uniforms(ctx: BuildContext) -> dict[str, float | tuple[float, ...]]:
    """A block's ``Uniform`` blocks: name -> number or numbers."""
    found: dict[str, float | tuple[float, ...]] = {}
    for u, _ in ctx.inner("Uniform"):
        value = u["Value"]
        found[u["ID"]] = tuple(map(float, value)) if isinstance(value, tuple) else float(value)
    return found


def build_post_pass(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``PostPass`` block: the next pass over the frame."""
    ctx.scene("post_passes").append(PostPassSpec(
        str(v["ID"]), str(v["File"]), uniforms(ctx), bool(v["Enabled"]), bool(v["Feedback"]),
        ctx.where(None)))
    return []


POST_PASS_BLOCK = declare(BlockDeclaration(
    "PostPass", inside=("Scene",), build=build_post_pass, entity=False,
    doc="a full-screen pass over the drawn frame (your GLSL fragment shader; "
    "services.render.postprocess)", keys=(
        Key("ID", "string", "", "name other declarations use to refer to this "
            "post-processing pass", required=True),
        Key("File", "asset", None, "the fragment shader: it reads u_scene (the frame) at v_uv "
            "and writes one vec4 (see docs/GLSL.md)", required=True),
        Key("Uniform", "struct", None, "a uniform's value", repeat=True, struct="Uniform"),
        Key("Enabled", "bool", 1, "0: declared, switched on later (Lua enablePost)"),
        Key("Feedback", "bool", 0, "1: the pass also reads its own last output (u_previous)"),
    )))
