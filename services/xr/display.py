"""The headset as the engine's display: a render target the renderer draws both eyes
into, side by side, and the frame loop the runtime paces.

Each frame: :meth:`XrDisplay.wait_frame` (``xrWaitFrame``, in place of the engine's own
sleep) says when the frame will be shown; the controllers are read at that time
(:meth:`XrDisplay.sample`); the render system asks for the eyes at that time
(:meth:`XrDisplay.camera`) and draws into :class:`XrTarget`'s framebuffer, whose
``present`` copies the eyes (colour, depth) into the runtime's swapchain images and
ends the frame with a projection layer and the HUD as a head-locked quad. A frame the
runtime says not to draw is ended empty, not drawn. An optional mirror window shows the
experimenter one eye or both.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from engine.scene.inputs import DESKTOP_GLOVES, DESKTOP_TRACKERS
from services.input.events import AnyInput, Axis, Button, HandJoints, TrackerPose
from services.input.openxr_hands import hand_event
from services.render.camera import CameraView, HeadsetEye
from services.render.context import has_display, libgl
from services.xr.lifecycle import Action
from services.xr.projection import XrOrigin, fov_projection
from services.xr.session import (
    HUD_SIZE,
    InputSample,
    LocatedView,
    XrError,
    XrSession,
    XrSettings,
)
from services.xr.timing import FrameCounts, seconds

log = logging.getLogger("colosseum.xr")

MIRRORS = ("none", "left", "both")
#: A controller's squeeze is also the pinch of the glove the desktop emulation names for
#: that hand, so content made for gloves (``Hand { Glove "glove_r" }``) grasps with it.
SQUEEZE_PINCHES = dict(zip(DESKTOP_TRACKERS, DESKTOP_GLOVES, strict=True))

#: Copies the drawn eyes into a swapchain image: colour decoded to linear light for a
#: linear image (see services.xr.formats), depth as it is.
COPY_FRAGMENT = """
#version 330
in vec2 v_uv;
uniform sampler2D u_color;
uniform sampler2D u_depth;
uniform bool u_decode;
uniform bool u_with_depth;
out vec4 f_color;
vec3 to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c));
}
void main() {
    vec4 c = texture(u_color, v_uv);
    f_color = u_decode ? vec4(to_linear(c.rgb), c.a) : c;
    gl_FragDepth = u_with_depth ? texture(u_depth, v_uv).r : 0.0;
}
"""


class XrTarget:
    """Both eyes side by side in one offscreen framebuffer (what the renderer draws into)
    and the HUD's own; ``present`` hands them to the runtime."""

    kind = "openxr"

    def __init__(self, display: XrDisplay, ctx: Any, eye_size: tuple[int, int]) -> None:
        self.display = display
        self.ctx = ctx
        self.size = (2 * eye_size[0], eye_size[1])
        self.color = ctx.texture(self.size, 4)
        self.depth = ctx.depth_texture(self.size)
        for texture in (self.color, self.depth):
            texture.repeat_x = texture.repeat_y = False
        self.fbo = ctx.framebuffer(color_attachments=[self.color], depth_attachment=self.depth)
        self.hud_size = HUD_SIZE
        self.hud_color = ctx.texture(HUD_SIZE, 4)
        self.hud_fbo = ctx.framebuffer(color_attachments=[self.hud_color])
        self.hud_shown = False
        #: The depth texture the renderer left this frame's depth in (None: ``depth``).
        self.frame_depth: Any = None
        self.input: Any = None
        from services.render import glsl

        self._copy = ctx.program(vertex_shader=glsl.FULLSCREEN_VERTEX,
                                 fragment_shader=COPY_FRAGMENT)
        self._copy_vao = ctx.vertex_array(self._copy, [])
        self._wrapped: dict[tuple[int, int | None], Any] = {}

    @property
    def renderer_name(self) -> str:
        return str(self.ctx.info.get("GL_RENDERER", "?"))

    @property
    def is_closing(self) -> bool:
        return self.display.quit

    def resize(self, size: tuple[int, int]) -> None:
        """The runtime owns the eyes' size."""

    def present(self) -> None:
        self.display.submit(self)

    def copy_into(self, color_gl: int, depth_gl: int | None, decode: bool) -> None:
        """Draw the eyes into the swapchain images named (GL texture names)."""
        ctx = self.ctx
        key = (color_gl, depth_gl)
        fbo = self._wrapped.get(key)
        if fbo is None:
            color = ctx.external_texture(color_gl, self.size, 4, 0, "f1")
            fbo = self._wrapped[key] = ctx.framebuffer(color_attachments=[color])
            if depth_gl is not None:
                _attach_depth(fbo, depth_gl, self.display.session.depth_format)
        fbo.use()
        fbo.viewport = (0, 0, *self.size)
        ctx.disable(ctx.BLEND)
        if depth_gl is not None:
            ctx.enable(ctx.DEPTH_TEST)
            ctx.depth_func = "1"  # always: depth copied as it is
        else:
            ctx.disable(ctx.DEPTH_TEST)
        self.color.use(0)
        (self.frame_depth or self.depth).use(1)
        self._copy["u_color"].value = 0
        self._copy["u_depth"].value = 1
        self._copy["u_decode"].value = decode
        self._copy["u_with_depth"].value = depth_gl is not None
        self._copy_vao.render(vertices=3)
        ctx.depth_func = "<"
        ctx.disable(ctx.DEPTH_TEST)

    def read_image(self, color_gl: int) -> np.ndarray:
        """A swapchain image as the runtime will read it: ``(height, width, 4)`` uint8,
        first row at the top (tests check what reached the runtime with it)."""
        fbo = next(f for (c, _), f in self._wrapped.items() if c == color_gl)
        data = fbo.read(viewport=(0, 0, *self.size), components=4, alignment=1)
        return np.flipud(np.frombuffer(data, np.uint8).reshape(self.size[1], self.size[0], 4))

    def copy_hud(self, hud_gl: int) -> None:
        ctx = self.ctx
        fbo = self._wrapped.get((hud_gl, -1))
        if fbo is None:
            texture = ctx.external_texture(hud_gl, HUD_SIZE, 4, 0, "f1")
            fbo = self._wrapped[(hud_gl, -1)] = ctx.framebuffer(color_attachments=[texture])
        ctx.copy_framebuffer(fbo, self.hud_fbo)

    def close(self) -> None:
        for fbo in self._wrapped.values():
            fbo.release()
        for obj in (self.fbo, self.color, self.depth, self.hud_fbo, self.hud_color,
                    self._copy_vao, self._copy):
            obj.release()


def input_events(sample: InputSample, origin: XrOrigin, pressed: dict[tuple[str, str], bool],
                 axes: dict[tuple[str, str], float], now: float,
                 hands: dict[str, HandJoints] | None = None) -> list[AnyInput]:
    """What the controllers said as the engine's input events: every pose (and tracked
    hand joint) placed in the world by ``origin``; a button or a value only when it changed
    since the last sample (``pressed`` and ``axes`` keep the last, and are updated, as
    ``hands`` keeps each hand's last joints)."""
    events: list[AnyInput] = []
    for name, (p, q) in sample.poses.items():
        position, orientation = origin.place_xr(p, q)
        events.append(TrackerPose(name, tuple(position.tolist()), tuple(orientation.tolist()),
                                  None, now))
    last = {} if hands is None else hands
    for name, raw in sample.hands.items():
        hand = hand_event(name, raw, now, last.get(name), origin.place_joints)
        if hand is not None:
            last[name] = hand
            events.append(hand)
    for key, down in sample.buttons.items():
        if pressed.get(key, False) != down:
            pressed[key] = down
            events.append(Button(key[0], key[1], down, now))
            if key[1] == "squeeze" and key[0] in SQUEEZE_PINCHES:  # a glove's pinch too
                events.append(Button(SQUEEZE_PINCHES[key[0]], "pinch", down, now))
    for key, value in sample.axes.items():
        if axes.get(key) != value:
            axes[key] = value
            events.append(Axis(key[0], key[1], value, now))
    return events


def _attach_depth(fbo: Any, depth_gl: int, depth_format: Any) -> None:
    """Attach a runtime's depth image to ``fbo`` (moderngl takes no external depth
    texture as an attachment, so GL is asked directly)."""
    stencil = depth_format is not None and "STENCIL" in depth_format.name
    gl = libgl()
    gl.glBindFramebuffer(0x8D40, fbo.glo)  # GL_FRAMEBUFFER
    gl.glFramebufferTexture2D(0x8D40, 0x821A if stencil else 0x8D00,  # (DEPTH_)STENCIL_ATTACHMENT
                              0x0DE1, depth_gl, 0)  # GL_TEXTURE_2D


class XrDisplay:
    """The headset display: the session, its target, where the player stands, and what
    ``--stats`` reports (``xr.*``)."""

    def __init__(self, settings: XrSettings | None = None, mirror: str = "none") -> None:
        if mirror not in MIRRORS:
            raise ValueError(f"mirror must be one of {', '.join(MIRRORS)}, not {mirror!r}")
        self.settings = settings or XrSettings()
        self.session = XrSession(self.settings)
        self.mirror_mode = mirror
        self.counts = FrameCounts()
        self.origin: XrOrigin | None = None
        self._relative: XrOrigin | None = None  # the origin in the camera's frame
        self.target: XrTarget | None = None
        self.quit = False
        #: The headset could not be used, or its session was lost: the run exits 1.
        self.failed = False
        #: It could not be opened and the run went on in the window (the fallback).
        self.unavailable = False
        self.frame: Any = None
        self.views: list[LocatedView] = []
        #: The display time the eyes drawn last were located at (ns, the runtime's clock).
        self.views_time: int | None = None
        self._ctx: Any = None
        self._window: Any = None
        self._owns_ctx = False
        self._render_start = 0.0
        self._last_shown: int | None = None
        self._drew = False
        #: Read each submitted image back before it is released (``captured``; tests).
        self.capture = False
        self.captured: np.ndarray | None = None
        self._pressed: dict[tuple[str, str], bool] = {}
        self._axes: dict[tuple[str, str], float] = {}
        self._hands: dict[str, HandJoints] = {}

    @property
    def lifecycle(self) -> Any:
        return self.session.lifecycle

    def open(self) -> XrTarget:
        """Make the GL context (EGL without a display; a GLX window, the mirror, with
        one), open the session bound to it and the target the renderer draws into."""
        import moderngl

        binding = "egl"
        if self.mirror_mode != "none" and has_display():
            from services.render.context import WindowTarget

            self._window = WindowTarget((640, 360), "Colosseum: headset mirror")
            self._ctx, binding = self._window.ctx, "glx"
        else:
            try:
                self._ctx = moderngl.create_context(standalone=True, backend="egl", require=330)
            except Exception as exc:  # glcontext raises plain Exceptions with the EGL reason
                raise XrError(f"no EGL context for the headset: {exc}") from exc
            self._owns_ctx = True
            if self.mirror_mode != "none":
                log.warning("no display for the headset's mirror window: running without it")
        self.session.open(binding)
        self.target = XrTarget(self, self._ctx, self.session.eye_size)
        return self.target

    # -- pacing ----------------------------------------------------------------------
    def wait_frame(self) -> float | None:
        """Take the runtime's events and, while the session runs, wait for the next
        frame; the display period (s), or None when no frame is due (not running yet,
        or ending)."""
        with self._runtime("xrPollEvent"):
            actions = self.session.poll()
        for action in actions if not self.quit else ():
            if action == Action.QUIT:
                self.quit = True
                if self.lifecycle.ended == "lost":
                    self.failed = True
                    log.error("the OpenXR session was lost (the runtime or the headset went "
                              "away); the run ends")
                else:
                    log.info("the OpenXR session ended (the runtime asked to exit)")
        if not self.lifecycle.running or self.quit:
            self.frame = None
            return None
        start = time.perf_counter()
        with self._runtime("xrWaitFrame"):
            self.frame = self.session.wait()
        if self.quit:
            self.frame = None
            return None
        self.counts.wait.add(time.perf_counter() - start)
        shown = int(self.frame.predicted_display_time)
        last, self._last_shown = self._last_shown, shown
        if last is None or shown <= last:
            return seconds(int(self.frame.predicted_display_period))
        return seconds(shown - last)  # the headset's own clock: a missed frame counts too

    @property
    def display_time(self) -> int | None:
        return None if self.frame is None else int(self.frame.predicted_display_time)

    @property
    def should_render(self) -> bool:
        return self.frame is not None and bool(self.frame.should_render)

    # -- input -----------------------------------------------------------------------
    def place(self, anchor: tuple[np.ndarray, np.ndarray], carried: bool = False) -> None:
        """Put the player where ``anchor`` (the scene camera's world pose) is, the first
        time; ``carried``: the camera follows something (a wheelchair), and the player
        rides along with it, keeping their place relative to it."""
        if self.origin is None:
            self.origin = XrOrigin.under(anchor[0], anchor[1], self.session.floor)
            self._relative = self.origin.relative_to(*anchor)
        elif carried and self._relative is not None:
            self.origin = self._relative.carried_by(*anchor)

    def recenter(self, anchor: tuple[np.ndarray, np.ndarray]) -> None:
        """Move the origin so the head is over ``anchor`` and faces its way."""
        when = self.display_time
        head = None
        with self._runtime("xrLocateSpace"):
            head = None if when is None else self.session.locate_head(when)
        if head is None:
            log.warning("recentering: the headset is not tracked now")
            return
        from services.input.calibration import openxr_to_engine

        p, q = openxr_to_engine(*head)
        current = self.origin or XrOrigin()
        self.origin = current.recentered(np.asarray(p), np.asarray(q), anchor[0], anchor[1],
                                         self.session.floor)
        self._relative = self.origin.relative_to(*anchor)
        log.info("recentered the headset over the camera")

    def sample(self, now: float) -> list[AnyInput]:
        """The controllers and head at this frame's display time as input events in the
        world (only while the session has the input focus)."""
        when = self.display_time
        if when is None or self.origin is None or not self.lifecycle.focused:
            return []
        with self._runtime("xrSyncActions"):
            sample = self.session.sample_input(when)
            head = self.session.locate_head(when)
        if self.quit:
            return []
        if head is not None:
            sample.poses["hmd"] = head
        return input_events(sample, self.origin, self._pressed, self._axes, now, self._hands)

    # -- drawing ---------------------------------------------------------------------
    def camera(self, base: CameraView, carried: bool = False) -> CameraView:
        """The eyes at this frame's display time, as a camera the renderer draws (``base``
        gives the clip planes and where the player stands: the first time, or every frame
        when ``carried``, see :meth:`place`)."""
        self._render_start = time.perf_counter()
        self.place((base.position, base.orientation), carried)
        when = self.display_time
        if when is None or not self.should_render:
            return base
        self.views = []
        with self._runtime("xrLocateViews"):
            located = self.session.locate_views(when)
            problems = [p for p in (v.fov.problem() for v in located) if p is not None]
            if problems:  # a runtime going away may answer with empty fields of view
                log.warning("the runtime gave eyes that cannot be drawn (%s); frame skipped",
                            problems[0])
                return base
            self.views = located
        if not self.views:
            return base
        self.views_time = when
        near, far = base.near, base.far
        self.settings.near, self.settings.far = near, far
        assert self.origin is not None
        eyes = []
        for view in self.views:
            position, orientation = self.origin.place_xr(view.position, view.orientation)
            eyes.append(HeadsetEye(position, orientation, fov_projection(view.fov, near, far)))
        return CameraView(eyes[0].position, eyes[0].orientation, near=near, far=far,
                          headset=eyes)

    def submit(self, target: XrTarget) -> None:
        """End this frame: the eyes drawn into the swapchains, or empty when the runtime
        said not to draw."""
        if self.frame is None:
            return
        drawn = self.should_render and bool(self.views)
        ended = False
        with self._runtime("xrEndFrame"):
            self._hand_over(target, drawn)
            self.counts.ended(drawn, self.session.now(), int(self.frame.predicted_display_time))
            ended = True
        if drawn and ended:
            self.counts.hud += int(target.hud_shown)
            self.counts.render.add(time.perf_counter() - self._render_start)
            self._mirror(target)
        self.frame = None

    def _hand_over(self, target: XrTarget, drawn: bool) -> None:
        """Begin the frame, copy the eyes (and the HUD) into the swapchains, end it."""
        session = self.session
        session.begin()
        if drawn:
            images = session.acquire()
            target.copy_into(images.color, images.depth, session.color_format.decode)
            if self.capture:
                self.captured = target.read_image(images.color)
            if images.hud is not None and target.hud_shown:
                target.copy_hud(images.hud)
            target.ctx.finish()
            session.release()
        session.end(self.views if drawn else None, hud=drawn and target.hud_shown)

    @contextmanager
    def _runtime(self, call: str) -> Iterator[None]:
        """Calls into the runtime: an OpenXR error there means the runtime or the headset
        went away; the run ends with one message (and exit status 1)."""
        try:
            yield
        except self.session.errors as exc:
            if not self.quit:
                log.error("the OpenXR runtime went away (%s in %s); the run ends",
                          type(exc).__name__.removesuffix("Error") or exc, call)
            self.lifecycle.instance_lost()
            self.quit = self.failed = True

    def skip(self) -> None:
        """End a frame the runtime said not to draw."""
        if self.frame is not None and self.target is not None:
            self.views = []
            self.submit(self.target)

    def _mirror(self, target: XrTarget) -> None:
        window = self._window
        if window is None:
            return
        w, h = target.size
        src = (0, 0, w // 2, h) if self.mirror_mode == "left" else (0, 0, w, h)
        ww, wh = window.size
        window.ctx.copy_framebuffer(window.fbo, target.fbo) if (ww, wh) == (w, h) else \
            _blit(target, window.fbo, src, (0, 0, ww, wh))
        window.present()

    def haptic(self, source: str, amplitude: float, seconds: float) -> bool:
        if self.target is None:
            return False
        return self.session.haptic(source, amplitude, seconds)

    def stats(self) -> dict[str, Any]:
        """The ``xr`` section of ``--stats``."""
        c = self.counts
        return {"runtime": self.session.runtime, "system": self.session.system_name,
                "reference_space": self.session.reference,
                "eye_size": list(self.session.eye_size),
                "color_format": self.session.color_format.name
                if self.session.color_format else None,
                "depth_submitted": self.session.depth_format is not None,
                "refresh_rate": self.session.refresh_rate,
                "frames_submitted": c.submitted, "frames_skipped": c.skipped,
                "frames_late": c.late, "frames_with_hud": c.hud,
                "session_state_max": self.lifecycle.furthest.name,
                "session_end": self.lifecycle.ended,
                "render_ms": c.render.mean() * 1e3, "render_ms_p99": c.render.percentile(99) * 1e3,
                "wait_ms": c.wait.mean() * 1e3}

    def close(self) -> None:
        """End the session cleanly (the runtime is asked to exit first), then free it."""
        try:
            if self.session.lifecycle.running and not self.quit:
                self.session.request_exit()
        except Exception as exc:  # a runtime gone mid-run: nothing more to end
            log.debug("ending the OpenXR session: %s", exc)
        finally:
            if self.target is not None:
                self.target.close()
                self.target = None
            self.session.close()
            if self._window is not None:
                self._window.close()
            elif self._owns_ctx and self._ctx is not None:
                self._ctx.release()
            self._ctx = None


def _blit(target: XrTarget, fbo: Any, src: tuple[int, int, int, int],
          dst: tuple[int, int, int, int]) -> None:
    """Scale part of the eyes' image into a window (glBlitFramebuffer)."""
    gl = libgl()
    target.fbo.use()
    read = target.fbo.glo
    gl.glBindFramebuffer(0x8CA8, read)  # GL_READ_FRAMEBUFFER
    gl.glBindFramebuffer(0x8CA9, fbo.glo)  # GL_DRAW_FRAMEBUFFER
    gl.glBlitFramebuffer(*src, *dst, 0x4000, 0x2601)  # colour, linear
