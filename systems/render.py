"""The render system: draws every entity with a Visual and a Transform, once per frame, in the
RENDER phase; lights from Light components, the view from the active Camera.

Run options come from ``engine.config`` (``headless``, and ``options``: ``screenshot``,
``record_frames``, ``record_every``, ``hud``, ``interpolate``, ``size``, ``stereo``), which
the CLI fills from ``--headless --screenshot --record-frames --record-every --hud
--interpolate --size --stereo``. The visual anomalies that are on (the anomalies plugin's
:class:`engine.anomalies.Anomalies`) are handed to the renderer each frame.
Scripts reach the renderer through the :class:`RenderSystem` resource
(``engine.resource(RenderSystem).set_uniform("toon", "DiffuseColor", (1, 0, 0))``).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Avatar, Camera, Display, Light, Name, Transform, Visual
from engine.animation import Palettes
from engine.anomalies import ANOMALIES, Anomalies
from engine.assets import AssetError, Assets
from engine.events import CustomEvent, KeyEvent
from engine.realtime import CostLog
from engine.services import ShaderControl, SwapGate
from engine.system import Phase, PluginName, System
from services.input import InputState
from services.input.desktop import WindowDevice
from services.render.camera import CameraView, camera_view_of
from services.render.context import create_target
from services.render.hud import hud_line
from services.render.interpolate import PoseInterpolator
from services.render.lights import light_from_component
from services.render.postprocess import PostPass, PostProcessing
from services.render.renderer import FrameStats, Renderer
from services.render.shaders import (
    FragmentShader,
    ShaderLibrary,
    ShaderProgram,
    ShaderState,
    Uniform,
    UniformValue,
    VertexShader,
)
from services.xr.display import XrDisplay

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.render")

#: Key that shows and hides the HUD line.
HUD_KEY = "f1"
#: The distance between the eyes (m) of ``--stereo sbs`` when the camera sets none: an
#: adult's mean interpupillary distance.
EYE_SEPARATION = 0.064


@dataclass(slots=True)
class RenderOptions:
    """How the render system runs; :meth:`from_config` reads the CLI's choices."""

    backend: str = "auto"  # auto | headless | window
    size: tuple[int, int] = (640, 480)
    screenshot: Path | None = None
    record_frames: Path | None = None
    record_every: int = 1
    hud: bool = False
    interpolate: bool = False
    shadow_size: int = 1024
    title: str = "Colosseum"
    #: False for headless runs from the CLI: only frames that are saved get drawn.
    draw_every_frame: bool = True
    #: "sbs": two eyes side by side (the camera's EyeSeparation, else :data:`EYE_SEPARATION`);
    #: "mono": one eye even for a stereo camera; None: as the camera says.
    stereo: str | None = None
    #: The share of the window's resolution the view is drawn at (Renderer.render_scale).
    render_scale: float = 1.0

    @staticmethod
    def from_config(config: Any) -> RenderOptions:
        opts = dict(getattr(config, "options", {}) or {})
        size = opts.get("size") or (640, 480)
        if isinstance(size, str):
            w, _, h = size.lower().partition("x")
            size = (int(w), int(h))
        backend = "headless" if getattr(config, "headless", True) else opts.get("backend", "auto")
        shot, frames = opts.get("screenshot"), opts.get("record_frames")
        return RenderOptions(
            backend=backend, size=(int(size[0]), int(size[1])),
            screenshot=Path(shot) if shot else None,
            record_frames=Path(frames) if frames else None,
            record_every=int(opts.get("record_every") or 1), hud=bool(opts.get("hud")),
            interpolate=bool(opts.get("interpolate")), stereo=opts.get("stereo"),
            render_scale=float(opts.get("render_scale") or 1.0),
            draw_every_frame=backend != "headless" or bool(getattr(config, "render", False)))


def _signature(visual: Visual) -> tuple:
    """What, when changed, makes the renderer rebuild an entity's parts."""
    return (visual.model, visual.texture, visual.shader_state, visual.shadower, visual.shadowed,
            visual.visible, visual.overlay, tuple(visual.color), tuple(visual.scale),
            len(visual.shapes))


def library_from_scene_spec(spec: Any) -> ShaderLibrary:
    """A ShaderLibrary from the scene factory's ``shader_programs``/``shader_states`` (which
    hold file paths per program rather than shader IDs)."""
    lib = ShaderLibrary()
    for pid, prog in getattr(spec, "shader_programs", {}).items():
        vid = fid = None
        if prog.vertex:
            vid = f"{pid}.vertex"
            lib.vertex_shaders.append(VertexShader(vid, file=str(prog.vertex)))
        if prog.fragment:
            fid = f"{pid}.fragment"
            lib.fragment_shaders.append(FragmentShader(fid, file=str(prog.fragment)))
        lib.programs.append(ShaderProgram(pid, vid, fid, enable=bool(prog.enabled)))
    for sid, state in getattr(spec, "shader_states", {}).items():
        lib.states.append(ShaderState(sid, state.program,
                                      [Uniform(k, v) for k, v in state.uniforms.items()]))
    return lib


class RenderSystem(System):
    """Keeps a :class:`Renderer` in step with the world and draws a frame per engine frame."""

    phase = Phase.RENDER
    reads = (Visual, Transform, Camera, Light, Avatar, Display, Name)
    writes = ()

    def __init__(self, options: RenderOptions | None = None) -> None:
        self.options = options
        self.renderer: Renderer | None = None
        self._target: Any = None
        self._signatures: dict[int, tuple] = {}
        self._visuals: dict[int, Visual] = {}
        self._keys = np.zeros(0, np.int64)
        self._rows_cache: tuple[int, np.ndarray] | None = None
        self._interpolator = PoseInterpolator()
        self._last_wall: float | None = None
        self._fps = 0.0
        self.frames_written = 0
        self.frames_drawn = 0
        #: CPU cost of each frame drawn (s), the --screenshot one at shutdown included.
        self.render_costs = CostLog()
        self._last = FrameStats()  # what the last frame drawn cost (kept after shutdown)
        self._errors: list[str] = []
        self._told_displays: set[str] = set()
        self._drawn = False  # whether the last frame was drawn (headless runs skip frames)
        self._palette_version = -1
        self._engine_anomalies: Anomalies | None = None
        self._headset: XrDisplay | None = None

    # -- API for scripts and tools --------------------------------------------
    def set_uniform(self, state_id: str, name: str, value: UniformValue) -> None:
        """Change a shader state's uniform (Lua's ``setUniform``); errors say what exists."""
        self._require().set_uniform(state_id, name, value)

    def enable_post(self, name: str, enabled: bool = True) -> None:
        """Switch an author's pass (a ``PostPass``) on or off; an anomaly's name or ID
        switches that anomaly (they were built-in passes once)."""
        anomalies = self._engine_anomalies
        if anomalies is not None and (name in anomalies.states or name in ANOMALIES):
            anomalies.switch(name, enabled, "python")
            return
        self._require().enable_post(name, enabled)

    def set_post_uniform(self, name: str, uniform: str, value: UniformValue) -> None:
        self._require().set_post_uniform(name, uniform, value)

    def toggle_hud(self) -> None:
        self._require().hud.toggle()

    def screenshot(self, path: str | Path) -> Path:
        return self._require().screenshot(path)

    @property
    def closing(self) -> bool:
        """True when the user closed the window (the run should stop)."""
        return bool(self._target is not None and self._target.is_closing)

    def _require(self) -> Renderer:
        if self.renderer is None:
            raise RuntimeError("the renderer is not running yet (it starts with the engine)")
        return self.renderer

    # -- lifecycle ------------------------------------------------------------
    def setup(self, engine: Engine) -> None:
        if self.options is None:
            self.options = RenderOptions.from_config(engine.config)
        opts = self.options
        headset = engine.try_resource(XrDisplay)
        self._headset = headset if headset is not None and headset.target is not None else None
        self._target = (self._headset.target if self._headset is not None
                        else create_target(opts.backend, opts.size, opts.title))
        root = engine.config.content_dir or Path(".")
        self.renderer = Renderer(self._target, root=root, shadow_size=opts.shadow_size,
                                 assets=Assets.of(engine))
        self.renderer.hud.enabled = opts.hud
        self.renderer.render_scale = opts.render_scale
        log.info("rendering with %s (%s) at %dx%d", self._target.kind,
                 self._target.renderer_name, *self._target.size)
        library = engine.try_resource(ShaderLibrary) or self._scene_shaders(engine)
        if library is not None:
            self.renderer.load_shaders(library)
        post = engine.try_resource(PostProcessing) or self._scene_post(engine)
        if post is not None:
            self.renderer.set_post_passes(post.passes)
        self._target.input = engine.try_resource(WindowDevice)  # keys and mouse: input layer
        engine.events.subscribe(KeyEvent, self._on_key)
        engine.events.subscribe(CustomEvent, self._on_custom)
        engine.world.on_remove(Visual, lambda entity, _: self._forget(entity))
        self._engine_anomalies = engine.try_resource(Anomalies)
        engine.insert_resource(self)
        engine.insert_resource(self, as_type=ShaderControl)
        engine.stat_sources["render"] = self._stats

    @staticmethod
    def _scene_shaders(engine: Engine) -> ShaderLibrary | None:
        try:
            from engine.scene.factory import SceneIds
        except ImportError:
            return None
        ids = engine.try_resource(SceneIds)
        return None if ids is None else library_from_scene_spec(ids.spec)

    @staticmethod
    def _scene_post(engine: Engine) -> PostProcessing | None:
        """The scene's ``PostPass`` blocks as an author's post-processing chain."""
        from engine.scene.factory import SceneIds

        ids = engine.try_resource(SceneIds)
        if ids is None or not ids.spec.post_passes:
            return None
        return PostProcessing([PostPass(p.id, file=p.file, uniforms=dict(p.uniforms),
                                        enabled=p.enabled, feedback=p.feedback,
                                        origin=p.origin) for p in ids.spec.post_passes])

    def _on_key(self, event: KeyEvent) -> None:
        if event.key == HUD_KEY and event.pressed and self.renderer is not None:
            self.renderer.hud.toggle()

    def _on_custom(self, event: CustomEvent) -> None:
        """``emit("hud", text)``: the HUD's status line (task progress), shown while not
        empty."""
        if event.name == "hud" and self.renderer is not None:
            self.renderer.hud.status = "" if event.data is None else str(event.data)

    def _forget(self, entity: int) -> None:
        self._signatures.pop(entity, None)
        self._visuals.pop(entity, None)
        if self.renderer is not None:
            self.renderer.remove(entity)

    def _stats(self) -> dict[str, Any]:
        """The ``render`` section of ``--stats`` (see engine.stats.STATS_SCHEMA); also after
        shutdown, so the frame a --screenshot draws then is counted."""
        if self._target is None:
            return {}
        errors = list(self.renderer.errors) if self.renderer is not None else self._errors
        return {"backend": self._target.kind, "gl_renderer": self._target.renderer_name,
                "draw_calls": self._last.draw_calls, "instances": self._last.instances,
                "render_ms_last": self._last.frame_ms,
                "render_ms_mean": self.render_costs.mean() * 1e3,
                "render_ms_p99": self.render_costs.percentile(99) * 1e3, "fps": self._fps,
                "frames_drawn": self.frames_drawn, "frames_written": self.frames_written,
                "errors": errors}

    def run(self, engine: Engine, dt: float) -> None:
        if self.closing:
            engine.request_quit()
        headset = self._headset
        if headset is not None:  # the runtime says when to draw
            if headset.frame is None:
                return
            if not headset.should_render:
                headset.skip()
                return
            self._draw(engine, dt)
            self._drawn = True
            return
        opts = self.options or RenderOptions()
        record = opts.record_frames is not None and engine.frame % max(opts.record_every, 1) == 0
        self._drawn = opts.draw_every_frame or self._target.kind == "window" or record
        if not self._drawn:  # headless and nobody looking this frame: skip the GPU work
            return
        self._draw(engine, dt)
        if record:
            self._require().screenshot(opts.record_frames / f"frame_{engine.frame:06d}.png")
            self.frames_written += 1

    def _draw(self, engine: Engine, dt: float, gated: bool = True) -> None:
        """Draw a frame; ``gated``: through the engine's :class:`SwapGate`, if it has one
        (it is swapped once the gate lets it)."""
        renderer = self._require()
        world = engine.world
        start = time.perf_counter()
        self._sync_visuals(engine)
        self._sync_poses(engine)
        self._sync_palettes(engine)
        active = self._active_camera(engine)
        renderer.camera = self._camera(engine, active)
        if self._headset is not None:  # its wearer rides along what the camera follows
            carried = active is not None and active[1].follow is not None
            renderer.camera = self._headset.camera(renderer.camera, carried)
        anomalies = engine.try_resource(Anomalies)
        renderer.anomalies = anomalies.active() if anomalies is not None else []
        lights = []
        for entity, (light,) in world.get_components(Light):
            row = world.poses.row_of.get(entity)
            pos = None if row is None else world.poses.position[row]
            quat = None if row is None else world.poses.orientation[row]
            lights.append(light_from_component(light, pos, quat))
        renderer.lights = lights
        now = time.perf_counter()
        if self._last_wall is not None and now > self._last_wall:
            inst = 1.0 / (now - self._last_wall)
            self._fps = inst if self._fps == 0.0 else 0.9 * self._fps + 0.1 * inst
        self._last_wall = now
        if renderer.hud.enabled:
            steps = engine.physics.controller.step_costs
            renderer.hud.text = hud_line(self._fps, steps.mean() * 1e3,
                                         engine.real_time_factor)
        scene_ms = (time.perf_counter() - start) * 1e3
        gate = engine.try_resource(SwapGate) if gated else None  # type: ignore[type-abstract]
        renderer.before_present = None if gate is None else gate.before_swap
        renderer.render(dt)
        renderer.stats.scene_ms = scene_ms
        self.frames_drawn += 1
        self._last = replace(renderer.stats)
        self.render_costs.add(renderer.stats.frame_ms / 1e3)

    def _sync_visuals(self, engine: Engine) -> None:
        renderer = self._require()
        world = engine.world
        seen = set()
        changed = False
        for entity, visual in world.get_component(Visual):
            seen.add(entity)
            sig = _signature(visual)
            if self._visuals.get(entity) is not visual or self._signatures.get(entity) != sig:
                row = world.poses.row_of.get(entity)
                pos = (0.0, 0.0, 0.0) if row is None else world.poses.position[row]
                quat = (1.0, 0.0, 0.0, 0.0) if row is None else world.poses.orientation[row]
                renderer.add(entity, visual, pos, quat, skin=self._skin(engine, entity))
                self._visuals[entity] = visual
                self._signatures[entity] = sig
                changed = True
        for entity in [e for e in self._visuals if e not in seen]:
            self._forget(entity)
            changed = True
        if changed:
            self._keys = np.fromiter(self._visuals, dtype=np.int64, count=len(self._visuals))
            self._rows_cache = None

    @staticmethod
    def _skin(engine: Engine, entity: int) -> Any:
        """The skinned model an avatar is drawn with (None: not an avatar, or its model
        cannot be read, which the scene loader told; then it is drawn as a plain model)."""
        avatar = engine.world.try_component(entity, Avatar)
        if avatar is None:
            return None
        try:
            return Assets.of(engine).skinned(avatar.model)
        except AssetError:
            return None

    def _sync_palettes(self, engine: Engine) -> None:
        palettes = engine.try_resource(Palettes)
        if palettes is not None and palettes.version != self._palette_version:
            self._require().set_palettes(palettes.matrices, palettes.offsets)
            self._palette_version = palettes.version

    def _sync_poses(self, engine: Engine) -> None:
        renderer = self._require()
        poses = engine.world.poses
        if self._rows_cache is None or self._rows_cache[0] != poses.version:
            self._rows_cache = (poses.version, poses.rows(self._keys))
        rows = self._rows_cache[1]
        has = rows >= 0
        if has.any():
            renderer.set_poses(self._keys[has], poses.position[rows[has]],
                               poses.orientation[rows[has]])
        opts = self.options
        if opts is not None and opts.interpolate and engine.config.mode == "threaded":
            self._interpolator.push(engine.physics.snapshot)
            interpolated = self._interpolator.poses()
            if interpolated is not None and len(interpolated[0]):
                renderer.set_poses(*interpolated)

    def _camera(self, engine: Engine, active: tuple[int, Camera] | None) -> CameraView:
        world = engine.world
        poses = world.poses
        wall = engine.config.options.get("display")
        if wall:
            view = self._display_view(engine, wall)
            if view is not None:
                return view
        if active is None:
            return self._stereo(CameraView())
        return self._stereo(camera_view_of(active[1], active[0], poses))

    @staticmethod
    def _active_camera(engine: Engine) -> tuple[int, Camera] | None:
        """The camera drawn from: the first active one (None: there is none)."""
        return next(((entity, camera) for entity, (camera,) in
                     engine.world.get_components(Camera) if camera.active), None)

    def _stereo(self, view: CameraView) -> CameraView:
        """The view with ``--stereo`` applied."""
        stereo = self.options.stereo if self.options is not None else None
        if stereo == "mono":
            view.eye_separation = 0.0
        elif stereo == "sbs" and view.eye_separation <= 0.0:
            view.eye_separation = EYE_SEPARATION
        return view

    def _display_view(self, engine: Engine, name: str) -> CameraView | None:
        """The off-axis view of the scene's Display ``name`` from the viewer's eye."""
        world = engine.world
        for entity, display in world.get_component(Display):
            named = world.try_component(entity, Name)
            if named is None or named.id != name:
                continue
            eye = np.asarray(display.eye, dtype=np.float64)
            row = None if display.head is None else world.poses.row_of.get(display.head)
            tracked = None if display.tracker is None or engine.try_resource(
                InputState) is None else engine.resource(InputState).tracker(display.tracker)
            if row is not None:
                eye = world.poses.position[row].copy()
            elif tracked is not None and tracked.tracked:
                eye = np.asarray(tracked.position, dtype=np.float64)
            corners = tuple(np.asarray(c, dtype=np.float64) for c in (
                display.lower_left, display.lower_right, display.upper_left))
            return CameraView(eye, np.array([1.0, 0, 0, 0]), near=display.near,
                              far=display.far, screen=corners)  # type: ignore[arg-type]
        if name not in self._told_displays:
            self._told_displays.add(name)
            names = sorted(n.id for e, (_, n) in world.get_components(Display, Name))
            log.error("no Display %r in the scene (displays: %s); drawing its camera", name,
                      ", ".join(names) or "none")
        return None

    def shutdown(self, engine: Engine) -> None:
        renderer = self.renderer
        if renderer is None:
            return
        opts = self.options
        try:
            if opts is not None and opts.screenshot is not None:
                if not self._drawn:  # drawn for the file: no wall waits to swap it
                    self._draw(engine, engine.tick.dt, gated=False)
                path = renderer.screenshot(opts.screenshot)
                log.info("screenshot written to %s", path)
        finally:
            self._errors = list(renderer.errors)
            renderer.release()
            if self._headset is None:  # the headset's target is the display's to close
                self._target.close()
            self.renderer = None


class RenderPlugin:
    """Adds the render system (``requestPlugin("osg")`` in the paper's Lua)."""

    name = PluginName.RENDER

    def __init__(self, options: RenderOptions | None = None) -> None:
        self.options = options

    def build(self, engine: Engine) -> None:
        engine.add_system(RenderSystem(self.options))
