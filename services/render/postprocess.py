"""Post-processing: full-screen passes run over the drawn frame — an author's own passes,
then the visual anomalies that are on (engine.anomalies, drawn by services.render.anomalies).

An author's pass is a fragment shader that reads ``u_scene`` (the frame so far, sampler2D),
and may use ``u_depth`` (scene depth), ``u_previous`` (this pass's own output last frame,
with ``feedback``), ``u_resolution`` (vec2 pixels), ``u_time`` (seconds) and its own
uniforms; it gets ``v_uv`` (0..1 across the frame) and writes one ``vec4``. Passes are
declared as :class:`PostPass` (a scene's ``PostPass`` blocks, or code), switched on and off
and retuned at run time, and a broken one is skipped with an error naming its file and line.
They run over the whole frame, both eyes of a stereo view at once.

Anomalies run after them, each pass once per eye in that eye's viewport, so each eye can
have its own (an anomaly drawn in one eye only copies the other eye's view through). The
last pass writes straight into the output framebuffer: a frame with passes costs no copy.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from engine.anomalies import ActiveAnomaly
from services.render import glsl
from services.render.anomalies import COPY, MEAN, MEAN_TEXELS, STAGES, EyeGeometry, Stage
from services.render.shaders import ShaderError, UniformValue, compile_program, write_uniform

log = logging.getLogger("colosseum.render")


@dataclass(slots=True)
class PostPass:
    """One pass of an author's chain: ``file`` (a .frag relative to the content folder) or
    ``source`` (inline GLSL); ``feedback`` gives the pass its own previous output as
    ``u_previous``."""

    name: str
    file: str | None = None
    source: str | None = None
    uniforms: dict[str, UniformValue] = field(default_factory=dict)
    enabled: bool = True
    feedback: bool = False
    origin: str = ""


@dataclass(slots=True)
class PostProcessing:
    """An author's passes, in order (the render system builds them)."""

    passes: list[PostPass] = field(default_factory=list)


class _LivePass:
    """A compiled pass of an author's chain (GL objects live here, not in the declaration)."""

    def __init__(self, decl: PostPass, program: Any, vao: Any) -> None:
        self.decl = decl
        self.program = program
        self.vao = vao
        self.uniforms = dict(decl.uniforms)
        self.fresh = True


#: Where a pass draws: an eye's (or the whole frame's) geometry and viewport in pixels.
Region = tuple[EyeGeometry, tuple[int, int, int, int]]


@dataclass(slots=True)
class _Step:
    """One full-screen pass to run this frame: its uniforms in each region it draws (None:
    the region is copied through), and the history it keeps when it feeds back."""

    program: Any
    vao: Any
    draws: list[tuple[dict[str, Any] | None, Region]]
    history: str | None = None
    fresh: bool = False
    mean: bool = False


class PostChain:
    """Runs an author's enabled passes, then the anomalies' passes, ping-ponging between
    two targets; passes that feed back keep their own last output."""

    def __init__(self, ctx: Any, root: str | Path = ".") -> None:
        self.ctx = ctx
        self.root = Path(root)
        self.errors: list[str] = []
        self._passes: list[_LivePass] = []
        self._programs: dict[str, tuple[Any, Any]] = {}  # built-in stage -> program, vao
        self._targets: list[tuple[Any, Any]] = []
        self._history: dict[str, tuple[Any, Any]] = {}  # feedback key -> its last output
        self._spare: dict[str, tuple[Any, Any]] = {}
        self._was_active: set[str] = set()
        self._mean: tuple[Any, Any] | None = None  # each eye's mean colour, a texel each
        self._size: tuple[int, int] | None = None

    @property
    def names(self) -> list[str]:
        return [p.decl.name for p in self._passes]

    def set_passes(self, passes: list[PostPass]) -> None:
        """Replace the author's chain; passes that fail to compile are reported and left
        out."""
        self._release_passes()
        for decl in passes:
            try:
                self._passes.append(self._compile(decl))
            except (ShaderError, OSError) as exc:
                msg = f"{exc}\n  (post pass {decl.name!r} is skipped)"
                self.errors.append(msg)
                log.error("%s", msg)

    def _compile(self, decl: PostPass) -> _LivePass:
        if decl.source is not None:
            source, name = decl.source, decl.file or f"<post {decl.name}>"
        elif decl.file is not None:
            path = self.root / decl.file
            source, name = path.read_text(), str(path)
        else:
            raise ShaderError(f"{decl.origin or decl.name}: post pass {decl.name!r} names no "
                              "file or source")
        program = compile_program(self.ctx, glsl.FULLSCREEN_VERTEX, source,
                                  "<fullscreen vertex>", name)
        return _LivePass(decl, program, self.ctx.vertex_array(program, []))

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

    def _stage_program(self, stage: Stage) -> tuple[Any, Any]:
        found = self._programs.get(stage.name)
        if found is None:
            program = compile_program(self.ctx, glsl.FULLSCREEN_VERTEX, stage.source,
                                      "<fullscreen vertex>", f"<anomaly {stage.name}>")
            found = self._programs[stage.name] = (program, self.ctx.vertex_array(program, []))
        return found

    def steps(self, anomalies: Sequence[ActiveAnomaly], eyes: Sequence[Region],
              size: tuple[int, int]) -> list[_Step]:
        """This frame's passes: the author's enabled ones over the whole frame, then every
        stage of every anomaly on (whose parameters change the image) in each eye."""
        out = []
        frame: Region = (EyeGeometry((0.0, 0.0, 1.0, 1.0), size, (1.0, 1.0)), (0, 0, *size))
        for p in self._passes:
            if p.decl.enabled:
                out.append(_Step(p.program, p.vao, [(dict(p.uniforms), frame)],
                                 f"pass:{p.decl.name}" if p.decl.feedback else None, p.fresh))
                p.fresh = False
        active = set()
        for anomaly in anomalies:
            for stage in STAGES[anomaly.kind]:
                if stage.skip(anomaly.values):
                    continue
                key = f"{anomaly.id}:{stage.name}"
                active.add(key)
                draws = [(stage.uniforms(anomaly.values, eye[0])
                          if len(eyes) == 1 or anomaly.eye in ("both", ("left", "right")[i])
                          else None, eye) for i, eye in enumerate(eyes)]
                program, vao = self._stage_program(stage)
                out.append(_Step(program, vao, draws, key if stage.feedback else None,
                                 key not in self._was_active, stage.mean))
        self._was_active = active
        for key in [k for k in self._history if k not in active and not k.startswith("pass:")]:
            for obj in (*self._history.pop(key), *self._spare.pop(key, ())):
                obj.release()
        return out

    def run(self, steps: list[_Step], scene: Any, depth: Any, size: tuple[int, int],
            time: float, output: Any) -> None:
        """Run ``steps`` (from :meth:`steps`) over texture ``scene``; the last one writes
        into framebuffer ``output``."""
        self._ensure_targets(size)
        self.ctx.disable(self.ctx.DEPTH_TEST)  # the output may have a depth buffer
        copy_program, copy_vao = self._copy()
        src = scene
        ping = 0
        for index, step in enumerate(steps):
            last = index == len(steps) - 1
            if step.history is not None:
                target_tex, target_fbo = self._feedback_target(step.history, size)
            elif last:
                target_tex, target_fbo = None, output
            else:
                target_tex, target_fbo = self._targets[ping]
                if target_tex is src:
                    ping ^= 1
                    target_tex, target_fbo = self._targets[ping]
                ping ^= 1
            if step.mean:
                self._means(src, [eye for _, (eye, _) in step.draws])
            target_fbo.use()
            for index, (uniforms, (eye, viewport)) in enumerate(step.draws):
                program, vao = (step.program, step.vao) if uniforms is not None else (
                    copy_program, copy_vao)
                for name, value in (uniforms or {}).items():
                    write_uniform(program, name, value)
                write_uniform(program, "u_resolution", (float(size[0]), float(size[1])))
                write_uniform(program, "u_time", time)
                write_uniform(program, "u_first", 1 if step.fresh else 0)
                write_uniform(program, "u_eye", eye.rect)
                write_uniform(program, "u_tan_half", eye.tan_half)
                src.use(0)
                write_uniform(program, "u_scene", 0)
                if depth is not None:
                    depth.use(1)
                    write_uniform(program, "u_depth", 1)
                if step.history is not None:
                    self._history[step.history][0].use(2)
                    write_uniform(program, "u_previous", 2)
                if step.mean:
                    self._mean[0].use(3)
                    write_uniform(program, "u_mean", 3)
                    write_uniform(program, "u_eye_index", index)
                target_fbo.viewport = viewport
                vao.render(vertices=3)
            if step.history is not None:  # this output becomes next frame's history
                self._spare[step.history] = self._history[step.history]
                self._history[step.history] = (target_tex, target_fbo)
                if last:
                    self.ctx.copy_framebuffer(output, target_fbo)
            src = target_tex

    def _means(self, texture: Any, eyes: list[EyeGeometry]) -> None:
        """Each eye's mean colour of ``texture`` into :attr:`_mean` (one texel per eye)."""
        texture.build_mipmaps()
        level = max(0, math.ceil(math.log2(max(texture.size[0] / MEAN_TEXELS, 1.0))))
        program, vao = self._stage_program(Stage("mean", MEAN, lambda values, eye: {}))
        if self._mean is None:
            tex = self.ctx.texture((2, 1), 4, dtype="f4")
            self._mean = (tex, self.ctx.framebuffer(color_attachments=[tex]))
        rects = [eye.rect for eye in eyes] + [eyes[0].rect] * (2 - len(eyes))
        self._mean[1].use()
        self._mean[1].viewport = (0, 0, len(eyes), 1)
        texture.use(0)
        write_uniform(program, "u_scene", 0)
        write_uniform(program, "u_level", level)
        program["u_rects"].write(np.asarray(rects, np.float32).tobytes())
        vao.render(vertices=3)

    def _copy(self) -> tuple[Any, Any]:
        return self._stage_program(Stage("copy", COPY, lambda values, eye: {}))

    def _feedback_target(self, key: str, size: tuple[int, int]) -> tuple[Any, Any]:
        """The target a feeding-back pass writes this frame (not the one it reads)."""
        if key not in self._history:
            self._history[key] = self._target(size)
        spare = self._spare.pop(key, None)
        if spare is None or spare[0].size != size:
            spare = self._target(size)
        return spare

    def _ensure_targets(self, size: tuple[int, int]) -> None:
        if self._size == size:
            return
        for tex, fbo in [*self._targets, *self._history.values(), *self._spare.values()]:
            fbo.release()
            tex.release()
        self._history.clear()
        self._spare.clear()
        self._targets = [self._target(size) for _ in range(2)]
        self._size = size

    def _target(self, size: tuple[int, int]) -> tuple[Any, Any]:
        tex = self.ctx.texture(size, 4)
        tex.filter = (self.ctx.LINEAR, self.ctx.LINEAR)
        tex.repeat_x = tex.repeat_y = False
        return tex, self.ctx.framebuffer(color_attachments=[tex])

    def _release_passes(self) -> None:
        for p in self._passes:
            p.vao.release()
            p.program.release()
        self._passes = []

    def release(self) -> None:
        self._release_passes()
        for program, vao in self._programs.values():
            vao.release()
            program.release()
        self._programs.clear()
        for tex, fbo in [*self._targets, *self._history.values(), *self._spare.values()]:
            fbo.release()
            tex.release()
        self._targets, self._size = [], None
        self._history.clear()
        self._spare.clear()
        if self._mean is not None:
            self._mean[1].release()
            self._mean[0].release()
            self._mean = None
