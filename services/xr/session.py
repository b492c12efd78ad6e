"""An OpenXR session that draws: instance, system, OpenGL binding, reference space,
swapchains, actions, and the frame calls, through pyopenxr.

Every call into the runtime is in this module; what to do with what it says (the
lifecycle, the timing, the bindings, the projection) lives in the pure modules beside
it, which are tested without a runtime. A failure here is an :class:`XrError` with one
sentence for the user (no runtime, no headset, a refused binding, a lost session).
"""

from __future__ import annotations

import ctypes
import logging
import os
import time
from dataclasses import dataclass, field
from typing import Any

from services.input.device import DeviceError
from services.input.openxr import NO_RUNTIME, POSE_VALID, load_openxr
from services.input.openxr_hands import HAND_TRACKING, OpenXRHands, RawHand
from services.xr.bindings import (
    ACTIONS,
    AXIS_NAMES,
    BUTTON_NAMES,
    HAND_SOURCES,
    LEFT,
    RIGHT,
    Rebinding,
    profile_extensions,
    suggestions,
)
from services.xr.formats import (
    SwapchainFormat,
    choose_color_format,
    choose_depth_format,
    format_name,
)
from services.xr.gl_binding import BindingError, current_egl, current_glx
from services.xr.lifecycle import Action, Lifecycle, SessionState
from services.xr.projection import Fov

log = logging.getLogger("colosseum.xr")

OPENGL = "XR_KHR_opengl_enable"
EGL = "XR_MNDX_egl_enable"
DEPTH = "XR_KHR_composition_layer_depth"
TIMESPEC = "XR_KHR_convert_timespec_time"
REFRESH = "XR_FB_display_refresh_rate"
LOCAL_FLOOR = "XR_EXT_local_floor"
REFERENCES = ("stage", "local_floor", "local")
#: The HUD's quad: 1 m ahead of the eyes, 0.25 m below them, 0.8 m wide.
HUD_SIZE = (1024, 128)
HUD_POSE = ((0.0, -0.25, -1.0), 0.8)


class XrError(RuntimeError):
    """The headset cannot be used; the message says why and what to do."""


@dataclass(slots=True)
class XrSettings:
    """What a scene's ``Display { Kind "openxr" }`` and the command line choose."""

    reference: str = "stage"
    when_hidden: str = "run"
    rebinding: tuple[Rebinding, ...] = ()
    refresh_rate: float | None = None
    render_scale: float = 1.0
    depth: bool = True
    near: float = 0.05
    far: float = 500.0


@dataclass(slots=True)
class LocatedView:
    """One eye at a display time: its pose in the reference space (OpenXR axes) and
    field of view."""

    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]  # w, x, y, z
    fov: Fov


@dataclass(slots=True)
class Images:
    """The swapchain images acquired for this frame (GL texture names)."""

    color: int
    depth: int | None
    hud: int | None


@dataclass(slots=True)
class InputSample:
    """What the controllers said at one display time (reference space, OpenXR axes)."""

    poses: dict[str, tuple[tuple[float, float, float], tuple[float, float, float, float]]] = \
        field(default_factory=dict)
    buttons: dict[tuple[str, str], bool] = field(default_factory=dict)
    axes: dict[tuple[str, str], float] = field(default_factory=dict)
    #: Each tracked hand's 26 joints (``hand_l``, ``hand_r``), as the runtime located them.
    hands: dict[str, RawHand] = field(default_factory=dict)


def _name(value: Any) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


class XrSession:
    """The runtime's side of the headset display (see the module's docstring)."""

    def __init__(self, settings: XrSettings | None = None) -> None:
        self.settings = settings or XrSettings()
        self.lifecycle = Lifecycle(when_hidden=self.settings.when_hidden)
        self.runtime = ""
        self.reference = ""
        self.eye_size = (0, 0)
        self.color_format: SwapchainFormat | None = None
        self.depth_format: SwapchainFormat | None = None
        self.extensions: set[str] = set()
        self.system_name = ""
        self.refresh_rate: float | None = None
        self._xr: Any = None
        self._h: dict[str, Any] = {}
        self._images: dict[str, list[int]] = {}
        self._frame: Any = None
        self._haptic_told = False
        self._hands: OpenXRHands | None = None

    @property
    def errors(self) -> tuple[type[BaseException], ...]:
        """The exceptions a runtime call raises (pyopenxr's), once it is loaded."""
        return () if self._xr is None else (self._xr.exception.XrException,)

    # -- opening -------------------------------------------------------------------
    def open(self, binding: str) -> None:
        """Create the instance and a session bound to the current GL context
        (``binding``: ``egl`` or ``glx``); XrError with the reason when it cannot."""
        try:
            self._xr = load_openxr()
        except DeviceError as exc:
            raise XrError(str(exc).removeprefix("openxr: ")) from exc
        xr = self._xr
        try:
            offered = {_name(p.extension_name)
                       for p in xr.enumerate_instance_extension_properties()}
        except xr.exception.RuntimeUnavailableError as exc:
            named = os.environ.get("XR_RUNTIME_JSON")
            if named:
                raise XrError(f"the OpenXR runtime XR_RUNTIME_JSON names ({named}) cannot be "
                              "loaded: is the file there, and the library it names?") from exc
            raise XrError(NO_RUNTIME) from exc
        except xr.exception.XrException as exc:
            raise XrError(f"the OpenXR runtime cannot be loaded: {exc}") from exc
        needed = [OPENGL] + ([EGL] if binding == "egl" else [])
        missing = [e for e in needed if e not in offered]
        if missing:
            raise XrError(f"the OpenXR runtime lacks {', '.join(missing)}, which drawing "
                          f"into the headset with OpenGL ({binding.upper()}) needs")
        wanted = [DEPTH, TIMESPEC, REFRESH, LOCAL_FLOOR, HAND_TRACKING, *profile_extensions()]
        self.extensions = {*needed, *(e for e in wanted if e in offered)}
        try:
            self._create(binding)
        except xr.exception.FormFactorUnavailableError as exc:
            self.close()
            raise XrError("no headset is connected to the OpenXR runtime "
                          f"({self.runtime or 'unknown'})") from exc
        except (xr.exception.XrException, BindingError) as exc:
            self.close()
            raise XrError(f"the OpenXR runtime {self.runtime or ''} refused the session: "
                          f"{exc}".replace("  ", " ")) from exc
        except Exception as exc:  # pyopenxr's own errors: still one message, no traceback
            self.close()
            raise XrError(f"opening the OpenXR session failed ({type(exc).__name__}: "
                          f"{exc})") from exc

    def _create(self, binding: str) -> None:
        xr, h = self._xr, self._h
        h["instance"] = instance = xr.create_instance(xr.InstanceCreateInfo(
            application_info=xr.ApplicationInfo(
                application_name="Colosseum", application_version=1,
                engine_name="Colosseum", engine_version=1,
                api_version=xr.Version(1, 0, 0)),
            enabled_extension_names=sorted(self.extensions)))
        props = xr.get_instance_properties(instance)
        version = xr.Version(props.runtime_version)
        self.runtime = f"{_name(props.runtime_name)} {version.major}.{version.minor}." \
                       f"{version.patch}"
        h["system"] = system = xr.get_system(instance, xr.SystemGetInfo(
            form_factor=xr.FormFactor.HEAD_MOUNTED_DISPLAY))
        self.system_name = _name(xr.get_system_properties(instance, system).system_name)
        views = xr.enumerate_view_configuration_views(
            instance, system, xr.ViewConfigurationType.PRIMARY_STEREO)
        scale = self.settings.render_scale
        self.eye_size = (max(16, round(views[0].recommended_image_rect_width * scale)),
                         max(16, round(views[0].recommended_image_rect_height * scale)))
        # the OpenGL requirements must be asked for before a session, whatever the binding
        xr.get_opengl_graphics_requirements_khr(instance, system)
        h["session"] = session = xr.create_session(instance, xr.SessionCreateInfo(
            system_id=system, next=self._binding(binding)))
        self._spaces(session)
        self._swapchains(session)
        self._actions(instance, session)
        self._refresh(session)
        self._hands = OpenXRHands.create(xr, instance, system, session, self.extensions,
                                         "the headset")
        log.info("OpenXR: %s, %s, %dx%d per eye, %s, %s space", self.runtime,
                 self.system_name, *self.eye_size, self.color_format.name
                 if self.color_format else "?", self.reference)

    def _binding(self, binding: str) -> Any:
        """The graphics binding of the current context (kept referenced until the session
        exists: the create info only points to it). pyopenxr types its handle fields as
        PyOpenGL's opaque pointers, so the integers are cast to them."""
        from xr.platform import linux as xr_linux

        xr = self._xr
        if binding == "egl":
            egl = current_egl()
            self._h["binding"] = xr.GraphicsBindingEGLMNDX(
                get_proc_address=xr.PFN_xrEglGetProcAddressMNDX(egl.get_proc_address),
                display=ctypes.cast(ctypes.c_void_p(egl.display), xr_linux.EGLDisplay),
                config=ctypes.cast(ctypes.c_void_p(egl.config), xr_linux.EGLConfig),
                context=ctypes.cast(ctypes.c_void_p(egl.context), xr_linux.EGLContext))
            return self._h["binding"]
        glx = current_glx()
        fields = dict(xr_linux.GraphicsBindingOpenGLXlibKHR._fields_)
        self._h["binding"] = xr.GraphicsBindingOpenGLXlibKHR(
            x_display=ctypes.cast(ctypes.c_void_p(glx.x_display), fields["x_display"]),
            visualid=glx.visual_id,
            glx_fbconfig=ctypes.cast(ctypes.c_void_p(glx.fb_config), fields["glx_fbconfig"]),
            glx_drawable=glx.drawable,
            glx_context=ctypes.cast(ctypes.c_void_p(glx.context), fields["glx_context"]))
        return self._h["binding"]

    def _spaces(self, session: Any) -> None:
        xr, h = self._xr, self._h
        kinds = {int(k) for k in xr.enumerate_reference_spaces(session)}
        by_name = {"stage": xr.ReferenceSpaceType.STAGE, "local": xr.ReferenceSpaceType.LOCAL,
                   "local_floor": getattr(xr.ReferenceSpaceType, "LOCAL_FLOOR_EXT",
                                          getattr(xr.ReferenceSpaceType, "LOCAL_FLOOR", None))}
        order = list(REFERENCES[REFERENCES.index(self.settings.reference):])
        for name in order:
            kind = by_name.get(name)
            if kind is not None and int(kind) in kinds:
                h["space"] = xr.create_reference_space(session, xr.ReferenceSpaceCreateInfo(
                    reference_space_type=kind))
                self.reference = name
                break
        else:
            raise XrError(f"the OpenXR runtime offers none of the spaces {', '.join(order)}")
        if self.reference != self.settings.reference:
            log.warning("OpenXR: no %s space; using %s (the floor %s)",
                        self.settings.reference.upper(), self.reference.upper(),
                        "is at z = 0" if self.floor else "is not known: the origin is at "
                        "the head where the session began")
        h["view"] = xr.create_reference_space(session, xr.ReferenceSpaceCreateInfo(
            reference_space_type=xr.ReferenceSpaceType.VIEW))

    @property
    def floor(self) -> bool:
        """Whether the reference space's origin is on the floor (z = 0 in the world)."""
        return self.reference in ("stage", "local_floor")

    def _swapchain(self, session: Any, fmt: int, size: tuple[int, int], depth: bool
                   ) -> tuple[Any, list[int]]:
        xr = self._xr
        usage = (xr.SwapchainUsageFlags.DEPTH_STENCIL_ATTACHMENT_BIT if depth
                 else xr.SwapchainUsageFlags.COLOR_ATTACHMENT_BIT)
        swapchain = xr.create_swapchain(session, xr.SwapchainCreateInfo(
            usage_flags=usage | xr.SwapchainUsageFlags.SAMPLED_BIT, format=fmt,
            sample_count=1, width=size[0], height=size[1], face_count=1, array_size=1,
            mip_count=1))
        images = xr.enumerate_swapchain_images(swapchain, xr.SwapchainImageOpenGLKHR)
        return swapchain, [int(image.image) for image in images]

    def _swapchains(self, session: Any) -> None:
        xr, h = self._xr, self._h
        offered = [int(f) for f in xr.enumerate_swapchain_formats(session)]
        self.color_format = choose_color_format(offered)
        log.info("OpenXR swapchain formats: %s; drawing in %s",
                 ", ".join(format_name(f) for f in offered), self.color_format.name)
        w, height = self.eye_size
        h["color"], self._images["color"] = self._swapchain(
            session, self.color_format.gl_format, (2 * w, height), False)
        if self.settings.depth and DEPTH in self.extensions:
            self.depth_format = choose_depth_format(offered)
            if self.depth_format is not None:
                h["depth"], self._images["depth"] = self._swapchain(
                    session, self.depth_format.gl_format, (2 * w, height), True)
        h["hud"], self._images["hud"] = self._swapchain(
            session, self.color_format.gl_format, HUD_SIZE, False)

    def _actions(self, instance: Any, session: Any) -> None:
        xr, h = self._xr, self._h
        hands = [xr.string_to_path(instance, p) for p in (LEFT, RIGHT)]
        h["hands"] = hands
        h["set"] = action_set = xr.create_action_set(instance, xr.ActionSetCreateInfo(
            action_set_name="colosseum", localized_action_set_name="Colosseum", priority=0))
        types = {"pose": xr.ActionType.POSE_INPUT, "boolean": xr.ActionType.BOOLEAN_INPUT,
                 "float": xr.ActionType.FLOAT_INPUT, "vector2": xr.ActionType.VECTOR2F_INPUT,
                 "haptic": xr.ActionType.VIBRATION_OUTPUT}
        actions = h["actions"] = {}
        for spec in ACTIONS:
            actions[spec.name] = xr.create_action(action_set, xr.ActionCreateInfo(
                action_type=types[spec.kind], action_name=spec.name,
                localized_action_name=spec.localized, subaction_paths=hands))
        for profile, pairs in suggestions(self.extensions, self.settings.rebinding).items():
            bindings = [xr.ActionSuggestedBinding(actions[action],
                                                  xr.string_to_path(instance, path))
                        for action, path in pairs]
            try:
                xr.suggest_interaction_profile_bindings(
                    instance, xr.InteractionProfileSuggestedBinding(
                        interaction_profile=xr.string_to_path(instance, profile),
                        suggested_bindings=bindings))
            except xr.exception.XrException as exc:
                log.warning("OpenXR: the runtime refused the bindings for %s: %s", profile, exc)
        xr.attach_session_action_sets(session, xr.SessionActionSetsAttachInfo(
            action_sets=[action_set]))
        h["poses"] = {
            (kind, HAND_SOURCES[path]): xr.create_action_space(session, xr.ActionSpaceCreateInfo(
                action=actions[kind], subaction_path=hand))
            for kind in ("grip", "aim") for path, hand in zip((LEFT, RIGHT), hands, strict=True)}

    def _refresh(self, session: Any) -> None:
        """The display's refresh rate, set to the scene's choice where the runtime can."""
        if REFRESH not in self.extensions:
            return
        xr = self._xr
        try:
            rates = list(xr.enumerate_display_refresh_rates_fb(session))
            wanted = self.settings.refresh_rate
            if wanted is not None and rates:
                best = min(rates, key=lambda r: abs(r - wanted))
                xr.request_display_refresh_rate_fb(session, best)
            rate = xr.get_display_refresh_rate_fb(session)
            self.refresh_rate = float(getattr(rate, "value", rate))
        except (xr.exception.XrException, AttributeError, TypeError, ValueError) as exc:
            log.warning("OpenXR: the display's refresh rate cannot be set: %s", exc)

    # -- events --------------------------------------------------------------------
    def poll(self) -> list[Action]:
        """Take the runtime's events; begin or end the session as they say; the actions
        taken (``QUIT``: the run should end)."""
        xr, h = self._xr, self._h
        taken: list[Action] = []
        while "instance" in h:
            try:
                event = xr.poll_event(h["instance"])
            except xr.exception.EventUnavailable:
                break
            kind = xr.StructureType(event.type)
            if kind == xr.StructureType.EVENT_DATA_INSTANCE_LOSS_PENDING:
                actions = self.lifecycle.instance_lost()
            elif kind == xr.StructureType.EVENT_DATA_SESSION_STATE_CHANGED:
                changed = ctypes.cast(ctypes.byref(event),
                                      ctypes.POINTER(xr.EventDataSessionStateChanged)).contents
                state = SessionState(int(changed.state))
                log.info("OpenXR session %s", state.name)
                actions = self.lifecycle.change(state)
            else:
                continue
            for action in actions:
                self._act(action)
            taken.extend(actions)
        return taken

    def _act(self, action: Action) -> None:
        xr, h = self._xr, self._h
        if action == Action.BEGIN:
            xr.begin_session(h["session"], xr.SessionBeginInfo(
                primary_view_configuration_type=xr.ViewConfigurationType.PRIMARY_STEREO))
        elif action == Action.END:
            try:
                xr.end_session(h["session"])
            except xr.exception.XrException as exc:  # a lost session may refuse
                log.debug("xrEndSession: %s", exc)

    # -- the frame -----------------------------------------------------------------
    def wait(self) -> Any:
        """``xrWaitFrame``: blocks until the runtime wants the next frame; its frame state
        (predicted display time and period, whether to draw)."""
        self._frame = self._xr.wait_frame(self._h["session"])
        return self._frame

    def now(self) -> int | None:
        """The runtime's clock (ns), where it can say (XR_KHR_convert_timespec_time)."""
        if TIMESPEC not in self.extensions:
            return None
        xr = self._xr
        t = time.clock_gettime_ns(time.CLOCK_MONOTONIC)
        spec = xr.timespec(t // 1_000_000_000, t % 1_000_000_000)
        now = xr.convert_timespec_time_to_time_khr(self._h["instance"], spec)
        return int(getattr(now, "value", now))

    def sample_input(self, when: int) -> InputSample:
        """Sync the actions and read the controllers at display time ``when``."""
        xr, h = self._xr, self._h
        session, actions = h["session"], h["actions"]
        xr.sync_actions(session, xr.ActionsSyncInfo(
            active_action_sets=[xr.ActiveActionSet(h["set"], xr.NULL_PATH)]))
        sample = InputSample()
        for (kind, source), space in h["poses"].items():
            location = xr.locate_space(space, h["space"], when)
            if location.location_flags & POSE_VALID == POSE_VALID:
                p, q = location.pose.position, location.pose.orientation
                name = source if kind == "grip" else f"{source}_aim"
                sample.poses[name] = ((p.x, p.y, p.z), (q.w, q.x, q.y, q.z))
        for hand, source in zip(h["hands"], (HAND_SOURCES[LEFT], HAND_SOURCES[RIGHT]),
                                strict=True):
            info = {name: xr.ActionStateGetInfo(action=actions[name], subaction_path=hand)
                    for name in (*BUTTON_NAMES, *AXIS_NAMES, "thumbstick")}
            for name, button in BUTTON_NAMES.items():
                state = xr.get_action_state_boolean(session, info[name])
                if state.is_active:
                    sample.buttons[(source, button)] = bool(state.current_state)
            for name, axis in AXIS_NAMES.items():
                state = xr.get_action_state_float(session, info[name])
                if state.is_active:
                    sample.axes[(source, axis)] = float(state.current_state)
            state = xr.get_action_state_vector2f(session, info["thumbstick"])
            if state.is_active:
                sample.axes[(source, "thumbstick_x")] = float(state.current_state.x)
                sample.axes[(source, "thumbstick_y")] = float(state.current_state.y)
        if self._hands is not None:
            sample.hands = self._hands.locate(h["space"], when)
        return sample

    def locate_views(self, when: int) -> list[LocatedView]:
        """Both eyes at display time ``when`` in the reference space."""
        xr, h = self._xr, self._h
        _, views = xr.locate_views(h["session"], xr.ViewLocateInfo(
            view_configuration_type=xr.ViewConfigurationType.PRIMARY_STEREO,
            display_time=when, space=h["space"]))
        self._views = views
        out = []
        for view in views:
            p, q, f = view.pose.position, view.pose.orientation, view.fov
            out.append(LocatedView((p.x, p.y, p.z), (q.w, q.x, q.y, q.z),
                                   Fov(f.angle_left, f.angle_right, f.angle_up, f.angle_down)))
        return out

    def locate_head(self, when: int) -> tuple[tuple, tuple] | None:
        """The head (VIEW space) in the reference space at ``when``; None: not tracked."""
        xr, h = self._xr, self._h
        location = xr.locate_space(h["view"], h["space"], when)
        if location.location_flags & POSE_VALID != POSE_VALID:
            return None
        p, q = location.pose.position, location.pose.orientation
        return (p.x, p.y, p.z), (q.w, q.x, q.y, q.z)

    def begin(self) -> None:
        self._xr.begin_frame(self._h["session"])

    def acquire(self) -> Images:
        """The swapchain images to draw this frame into (waited for)."""
        xr, h = self._xr, self._h
        got = {}
        for name in ("color", "depth", "hud"):
            if name in h:
                index = xr.acquire_swapchain_image(h[name])
                xr.wait_swapchain_image(h[name], xr.SwapchainImageWaitInfo(
                    timeout=xr.INFINITE_DURATION))
                got[name] = self._images[name][index]
        return Images(got["color"], got.get("depth"), got.get("hud"))

    def release(self) -> None:
        xr, h = self._xr, self._h
        for name in ("color", "depth", "hud"):
            if name in h:
                xr.release_swapchain_image(h[name])

    def end(self, views: list[LocatedView] | None, hud: bool = False) -> None:
        """``xrEndFrame``: the eyes drawn from ``views`` (None: nothing drawn, a skipped
        frame), with depth where submitted and the HUD as a head-locked quad."""
        xr, h = self._xr, self._h
        layers = []
        if views is not None:
            layers.append(ctypes.byref(self._projection(views)))
            if hud:
                layers.append(ctypes.byref(self._hud_quad()))
        xr.end_frame(h["session"], xr.FrameEndInfo(
            display_time=self._frame.predicted_display_time,
            environment_blend_mode=xr.EnvironmentBlendMode.OPAQUE, layers=layers))

    @staticmethod
    def _fill(sub: Any, swapchain: Any, eye: int, size: tuple[int, int]) -> None:
        """Point a ``XrSwapchainSubImage`` at eye ``eye``'s half of ``swapchain``."""
        sub.swapchain = swapchain
        sub.image_rect.offset.x, sub.image_rect.offset.y = eye * size[0], 0
        sub.image_rect.extent.width, sub.image_rect.extent.height = size
        sub.image_array_index = 0

    def _projection(self, views: list[LocatedView]) -> Any:
        xr, h = self._xr, self._h
        s = self.settings
        located = self._views
        out = (xr.CompositionLayerProjectionView * len(views))()
        depths = (xr.CompositionLayerDepthInfoKHR * len(views))()
        for eye in range(len(views)):
            view = out[eye]
            view.type = xr.StructureType.COMPOSITION_LAYER_PROJECTION_VIEW
            view.next = None
            view.pose, view.fov = located[eye].pose, located[eye].fov
            self._fill(view.sub_image, h["color"], eye, self.eye_size)
            if "depth" in h:
                depth = depths[eye]
                depth.type = xr.StructureType.COMPOSITION_LAYER_DEPTH_INFO_KHR
                depth.next = None
                self._fill(depth.sub_image, h["depth"], eye, self.eye_size)
                depth.min_depth, depth.max_depth = 0.0, 1.0
                depth.near_z, depth.far_z = s.near, s.far
                view.next = ctypes.cast(ctypes.pointer(depth), ctypes.c_void_p)
        self._keep = (out, depths)  # the layer points into these until xrEndFrame returns
        self._layer = xr.CompositionLayerProjection(space=h["space"], views=out)
        return self._layer

    def _hud_quad(self) -> Any:
        xr = self._xr
        (x, y, z), width = HUD_POSE
        quad = xr.CompositionLayerQuad(
            layer_flags=xr.CompositionLayerFlags.BLEND_TEXTURE_SOURCE_ALPHA_BIT,
            space=self._h["view"], eye_visibility=xr.EyeVisibility.BOTH,
            pose=xr.Posef(position=xr.Vector3f(x, y, z)),
            size=xr.Extent2Df(width, width * HUD_SIZE[1] / HUD_SIZE[0]))
        self._fill(quad.sub_image, self._h["hud"], 0, HUD_SIZE)
        self._quad = quad
        return quad

    def haptic(self, source: str, amplitude: float, seconds: float,
               frequency: float = 0.0) -> bool:
        """Pulse the controller of hand ``source`` (``hand_l``/``hand_r``); False where
        there is no such hand or the session does not run."""
        xr, h = self._xr, self._h
        hands = {HAND_SOURCES[LEFT]: 0, HAND_SOURCES[RIGHT]: 1}
        if source not in hands or not self.lifecycle.running:
            return False
        vibration = xr.HapticVibration(
            duration=max(1, int(seconds * 1e9)), frequency=frequency,
            amplitude=min(max(amplitude, 0.0), 1.0))
        try:
            xr.apply_haptic_feedback(h["session"], xr.HapticActionInfo(
                action=h["actions"]["haptic"], subaction_path=h["hands"][hands[source]]),
                vibration)  # pyopenxr passes it by reference as the base header
        except xr.exception.XrException as exc:
            if not self._haptic_told:
                self._haptic_told = True
                log.warning("OpenXR: the runtime refused a haptic pulse: %s", exc)
            return False
        return True

    # -- closing -------------------------------------------------------------------
    def request_exit(self, wait: float = 1.0) -> None:
        """Ask the runtime to end the session and follow it to its end (EXITING), for at
        most ``wait`` seconds; frames asked for meanwhile are ended empty."""
        xr, h = self._xr, self._h
        if "session" not in h or not self.lifecycle.running:
            return
        try:
            xr.request_exit_session(h["session"])
        except xr.exception.XrException as exc:
            log.debug("xrRequestExitSession: %s", exc)
            return
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline and self.lifecycle.ended is None:
            self.poll()
            if self.lifecycle.running:
                frame = self.wait()
                self._frame = frame
                self.begin()
                self.end(None)
            else:
                time.sleep(0.005)

    def close(self) -> None:
        """Destroy what was made, newest first; safe after any failure."""
        xr, h = self._xr, self._h
        if xr is None:
            return
        if self._hands is not None:
            try:
                self._hands.destroy()
            except xr.exception.XrException as exc:
                log.debug("destroying the hand trackers: %s", exc)
            self._hands = None
        for name in ("hud", "depth", "color"):
            if name in h:
                xr.destroy_swapchain(h.pop(name))
        for name in ("session", "instance"):
            if name in h:
                try:
                    (xr.destroy_session if name == "session" else xr.destroy_instance)(
                        h.pop(name))
                except xr.exception.XrException as exc:
                    log.debug("destroying the %s: %s", name, exc)
        h.clear()
