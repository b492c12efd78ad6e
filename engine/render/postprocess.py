"""Post-processing: a chain of full-screen passes run over the rendered frame.

A pass is a fragment shader that reads ``u_scene`` (the frame so far, sampler2D), and may use
``u_depth`` (scene depth), ``u_previous`` (this pass's own output last frame, for effects that
accumulate), ``u_resolution`` (vec2 pixels), ``u_time`` (seconds) and its own uniforms; it gets
``v_uv`` and writes one ``vec4``. Passes are declared as :class:`PostPass` (from the scene file
or code), switched on and off and retuned at run time, and a broken one is skipped with an
error naming its file and line.

Built-ins (name → uniforms), made for the stroke simulator:

* ``double_vision``: a shifted copy over the image (diplopia). ``u_offset`` vec2 in UV units
  (default (0.04, 0)), ``u_mix`` weight of the copy (0.5).
* ``motion_blur``: mixes the previous output into the new frame. ``u_strength`` (0.6).
* ``perspective_distortion``: radial (barrel > 0, pincushion < 0) distortion about
  ``u_centre`` (0.5, 0.5) with ``u_strength`` (0.3); ``u_aspect_stretch`` scales x (1.0).
* ``unilateral_neglect``: one side of the view fades to ``u_fill`` (black). ``u_side`` -1 left,
  +1 right; ``u_extent`` how far from that edge, 0..1 of the width (0.5); ``u_softness`` (0.1).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from engine.render import glsl
from engine.render.shaders import ShaderError, UniformValue, compile_program, write_uniform

log = logging.getLogger("colosseum.render")

_HEADER = """#version 330
in vec2 v_uv;
uniform sampler2D u_scene;
uniform sampler2D u_depth;
uniform sampler2D u_previous;
uniform vec2 u_resolution;
uniform float u_time;
out vec4 f_color;
"""

BUILTIN_PASSES: dict[str, tuple[str, dict[str, UniformValue]]] = {
    "double_vision": (_HEADER + """
uniform vec2 u_offset;
uniform float u_mix;
void main() {
    vec4 base = texture(u_scene, v_uv);
    vec2 src = v_uv - u_offset;
    vec4 copy = (src.x < 0.0 || src.x > 1.0 || src.y < 0.0 || src.y > 1.0)
        ? base : texture(u_scene, src);
    f_color = mix(base, copy, u_mix);
}
""", {"u_offset": (0.04, 0.0), "u_mix": 0.5}),
    "motion_blur": (_HEADER + """
uniform float u_strength;
uniform int u_first;
void main() {
    vec4 now = texture(u_scene, v_uv);
    f_color = u_first == 1 ? now : mix(now, texture(u_previous, v_uv), u_strength);
}
""", {"u_strength": 0.6}),
    "perspective_distortion": (_HEADER + """
uniform float u_strength;
uniform vec2 u_centre;
uniform float u_aspect_stretch;
void main() {
    vec2 d = v_uv - u_centre;
    d.x /= u_aspect_stretch;
    float r2 = dot(d, d);
    vec2 src = u_centre + d * (1.0 + u_strength * r2);  // > 0: content pulled inward
    if (src.x < 0.0 || src.x > 1.0 || src.y < 0.0 || src.y > 1.0) f_color = vec4(0, 0, 0, 1);
    else f_color = texture(u_scene, src);
}
""", {"u_strength": 0.3, "u_centre": (0.5, 0.5), "u_aspect_stretch": 1.0}),
    "unilateral_neglect": (_HEADER + """
uniform float u_side;
uniform float u_extent;
uniform float u_softness;
uniform vec3 u_fill;
void main() {
    vec4 c = texture(u_scene, v_uv);
    float from_edge = u_side < 0.0 ? v_uv.x : 1.0 - v_uv.x;
    float hidden = 1.0 - smoothstep(u_extent - u_softness, u_extent + u_softness, from_edge);
    f_color = vec4(mix(c.rgb, u_fill, hidden), c.a);
}
""", {"u_side": -1.0, "u_extent": 0.5, "u_softness": 0.1, "u_fill": (0.0, 0.0, 0.0)}),
}


@dataclass(slots=True)
class PostPass:
    """One pass of the chain. ``shader`` is a built-in name or ``None`` with ``file`` (a .frag
    relative to the content folder) or ``source`` (inline GLSL). ``feedback`` gives the pass
    its own previous output as ``u_previous`` (built-in motion_blur sets it itself)."""

    name: str
    shader: str | None = None
    file: str | None = None
    source: str | None = None
    uniforms: dict[str, UniformValue] = field(default_factory=dict)
    enabled: bool = True
    feedback: bool = False
    origin: str = ""


@dataclass(slots=True)
class PostProcessing:
    """A scene's post-processing chain, in order; the scene factory inserts it as an engine
    resource and the render system builds it."""

    passes: list[PostPass] = field(default_factory=list)


class _LivePass:
    """A compiled pass with its textures (GL objects live here, not in the declaration)."""

    def __init__(self, decl: PostPass, program: Any, vao: Any, uniforms: dict[str, UniformValue],
                 feedback: bool) -> None:
        self.decl = decl
        self.program = program
        self.vao = vao
        self.uniforms = uniforms
        self.feedback = feedback
        self.history: Any = None  # (texture, framebuffer) of last frame's output
        self.spare: Any = None  # the other feedback target, written this frame
        self.fresh = True


class PostChain:
    """Runs enabled passes in order over a colour texture, ping-ponging between targets."""

    def __init__(self, ctx: Any, root: str | Path = ".") -> None:
        self.ctx = ctx
        self.root = Path(root)
        self.errors: list[str] = []
        self._passes: list[_LivePass] = []
        self._targets: list[tuple[Any, Any]] = []
        self._size: tuple[int, int] | None = None

    @property
    def names(self) -> list[str]:
        return [p.decl.name for p in self._passes]

    def active(self) -> bool:
        return any(p.decl.enabled for p in self._passes)

    def set_passes(self, passes: list[PostPass]) -> None:
        """Replace the chain; passes that fail to compile are reported and left out."""
        self.release()
        for decl in passes:
            try:
                self._passes.append(self._compile(decl))
            except (ShaderError, KeyError, OSError) as exc:
                msg = f"{exc}\n  (post pass {decl.name!r} is skipped)"
                self.errors.append(msg)
                log.error("%s", msg)

    def _compile(self, decl: PostPass) -> _LivePass:
        uniforms: dict[str, UniformValue] = {}
        feedback = decl.feedback
        if decl.source is not None:
            source, name = decl.source, decl.file or f"<post {decl.name}>"
        elif decl.file is not None:
            path = self.root / decl.file
            source, name = path.read_text(), str(path)
        else:
            builtin = decl.shader or decl.name
            if builtin not in BUILTIN_PASSES:
                raise KeyError(f"{decl.origin or decl.name}: unknown built-in post pass "
                               f"{builtin!r}; built-ins: {', '.join(sorted(BUILTIN_PASSES))}")
            source, defaults = BUILTIN_PASSES[builtin]
            uniforms.update(defaults)
            name = f"<built-in {builtin}>"
            feedback = feedback or builtin == "motion_blur"
        uniforms.update(decl.uniforms)
        program = compile_program(self.ctx, glsl.FULLSCREEN_VERTEX, source,
                                  "<fullscreen vertex>", name)
        vao = self.ctx.vertex_array(program, [])
        return _LivePass(decl, program, vao, uniforms, feedback)

    def _pass(self, name: str) -> _LivePass:
        for p in self._passes:
            if p.decl.name == name:
                return p
        raise KeyError(f"unknown post pass {name!r}; chain: {', '.join(self.names) or '(empty)'}")

    def enable(self, name: str, enabled: bool = True) -> None:
        """Switch a pass on or off at run time (a re-enabled accumulating pass starts fresh)."""
        p = self._pass(name)
        p.decl.enabled = bool(enabled)
        p.fresh = True

    def set_uniform(self, name: str, uniform: str, value: UniformValue) -> None:
        p = self._pass(name)
        if p.program.get(uniform, None) is None:
            raise ValueError(f"post pass {name!r} has no uniform {uniform!r}")
        write_uniform(p.program, uniform, value)
        p.uniforms[uniform] = value

    def _ensure_targets(self, size: tuple[int, int]) -> None:
        if self._size == size:
            return
        for tex, fbo in self._targets:
            fbo.release()
            tex.release()
        self._targets = [self._target(size) for _ in range(2)]
        for p in self._passes:
            if p.history is not None:
                p.history[1].release()
                p.history[0].release()
                p.history = None
            p.fresh = True
        self._size = size

    def _target(self, size: tuple[int, int]) -> tuple[Any, Any]:
        tex = self.ctx.texture(size, 4)
        tex.filter = (self.ctx.LINEAR, self.ctx.LINEAR)
        tex.repeat_x = tex.repeat_y = False
        return tex, self.ctx.framebuffer(color_attachments=[tex])

    def run(self, scene: Any, depth: Any, size: tuple[int, int], time: float) -> Any:
        """Apply enabled passes to texture ``scene``; returns the framebuffer holding the result
        (None when no pass ran)."""
        self._ensure_targets(size)
        src = scene
        out_fbo = None
        ping = 0
        for p in self._passes:
            if not p.decl.enabled:
                continue
            if p.feedback:
                if p.history is None:
                    p.history = self._target(size)
                target_tex, target_fbo = self._target_for_feedback(p, size)
            else:
                target_tex, target_fbo = self._targets[ping]
                if target_tex is src:
                    ping ^= 1
                    target_tex, target_fbo = self._targets[ping]
                ping ^= 1
            for name, value in p.uniforms.items():
                write_uniform(p.program, name, value)
            write_uniform(p.program, "u_resolution", (float(size[0]), float(size[1])))
            write_uniform(p.program, "u_time", time)
            write_uniform(p.program, "u_first", 1 if p.fresh else 0)
            src.use(0)
            write_uniform(p.program, "u_scene", 0)
            if depth is not None:
                depth.use(1)
                write_uniform(p.program, "u_depth", 1)
            if p.feedback:
                p.history[0].use(2)
                write_uniform(p.program, "u_previous", 2)
            target_fbo.use()
            target_fbo.viewport = (0, 0, *size)
            p.vao.render(vertices=3)
            if p.feedback:  # this output becomes next frame's history
                p.history, p.spare = (target_tex, target_fbo), p.history
            p.fresh = False
            src, out_fbo = target_tex, target_fbo
        return out_fbo

    def _target_for_feedback(self, p: _LivePass, size: tuple[int, int]) -> tuple[Any, Any]:
        spare = p.spare
        if spare is None or spare[0].size != size:
            spare = self._target(size)
        p.spare = None
        return spare

    def release(self) -> None:
        for p in self._passes:
            p.vao.release()
            p.program.release()
        self._passes = []
