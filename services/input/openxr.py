"""OpenXR (pyopenxr, the ``openxr`` extra): a headset's pose and its controllers.

The headset becomes the tracker ``hmd`` (bind it to a camera with ``Tracker { ID "hmd"
Camera "eye" }``), the controllers' grip poses ``hand_l``/``hand_r``, their select
buttons ``Button(hand_l, "select")``; tracked hands (``XR_EXT_hand_tracking``, where the
runtime's system has them) the HandJoints ``hand_l``/``hand_r``
(:mod:`services.input.openxr_hands`). Poses are read through a headless session
(``XR_MND_headless``: no frames are submitted to the headset; drawing into it is not
this device's job) and converted from OpenXR's frame (y up, looking along -z) to the
engine's (z up, looking along +y) by :func:`services.input.calibration.openxr_to_engine`.

Machines without an OpenXR runtime get one clear message saying so and what to install.
"""

from __future__ import annotations

import ctypes
import logging
import os
import time
from typing import Any

from services.input.calibration import openxr_to_engine
from services.input.device import MONOTONIC, Clock, DeviceError, QueuedDevice
from services.input.events import Button, HandJoints, TrackerPose
from services.input.openxr_hands import HAND_TRACKING, OpenXRHands, hand_event

HEADLESS = "XR_MND_headless"
TIMESPEC = "XR_KHR_convert_timespec_time"
#: Seconds between two samples of a headless session without a frame loop (90 Hz).
HEADLESS_PERIOD = 1.0 / 90.0
HANDS = (("hand_l", "/user/hand/left"), ("hand_r", "/user/hand/right"))
PROFILE = "/interaction_profiles/khr/simple_controller"
NO_RUNTIME = ("no OpenXR runtime found: install one (Monado, SteamVR, or your headset's) "
              "and make it the active runtime (XR_RUNTIME_JSON names its manifest)")
#: XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT (the
#: OpenXR specification's values): a located space is a pose only with both.
POSE_VALID = 0x1 | 0x2


def located_pose(name: str, location: Any, now: float) -> TrackerPose | None:
    """A located space (an ``XrSpaceLocation``: flags and a pose in OpenXR's frame) as
    tracker ``name``'s pose in the engine's frame; None while the runtime does not track
    it (the watchdog reports the tracker lost if it stays so)."""
    if location.location_flags & POSE_VALID != POSE_VALID:
        return None
    p, q = location.pose.position, location.pose.orientation
    position, orientation = openxr_to_engine((p.x, p.y, p.z), (q.w, q.x, q.y, q.z))
    return TrackerPose(name, position, orientation, None, now)


def select_change(name: str, state: Any, was_pressed: bool, now: float) -> Button | None:
    """A controller's select action (an ``XrActionStateBoolean``) as a Button event when
    it changed from ``was_pressed``; None while unchanged or inactive (no controller bound
    to it: nothing is known, so nothing is released either)."""
    if not state.is_active or bool(state.current_state) == was_pressed:
        return None
    return Button(name, "select", bool(state.current_state), now)


def load_openxr() -> Any:
    """pyopenxr, quiet (the loader would print its own errors); DeviceError if missing."""
    os.environ.setdefault("XR_LOADER_DEBUG", "none")
    logging.getLogger("OpenGL").setLevel(logging.WARNING)  # PyOpenGL, which pyopenxr loads
    try:
        import xr
    except ImportError as exc:
        raise DeviceError("openxr: pyopenxr is not installed: pip install 'colosseum[openxr]'"
                          ) from exc
    return xr


class OpenXRDevice(QueuedDevice):
    """Headset and controller poses from the active OpenXR runtime."""

    kind = "openxr"

    def __init__(self, name: str = "openxr", clock: Clock = MONOTONIC) -> None:
        self.clock = clock
        self._xr: Any = None
        self._handles: dict[str, Any] = {}
        self._running = False
        self._hands: OpenXRHands | None = None
        self._enabled: set[str] = set()
        self._last_hands: dict[str, HandJoints] = {}
        super().__init__(name)

    def _open(self) -> None:
        xr = self._xr = load_openxr()
        try:
            extensions = {p.extension_name.decode() if isinstance(p.extension_name, bytes)
                          else p.extension_name
                          for p in xr.enumerate_instance_extension_properties()}
        except xr.exception.RuntimeUnavailableError as exc:
            raise DeviceError(f"{self.describe_name()}: {NO_RUNTIME}") from exc
        if HEADLESS not in extensions:
            raise DeviceError(f"{self.describe_name()}: the OpenXR runtime lacks {HEADLESS}, "
                              "which reading poses without drawing into the headset needs")
        enabled = self._enabled = {HEADLESS, *({HAND_TRACKING, TIMESPEC} & extensions)}
        try:
            self._create_session(xr, enabled)
        except xr.exception.FormFactorUnavailableError as exc:
            raise DeviceError(f"{self.describe_name()}: no headset is connected to the OpenXR "
                              "runtime") from exc
        except xr.exception.XrException as exc:
            raise DeviceError(f"{self.describe_name()}: {exc}") from exc

    def _create_session(self, xr: Any, enabled: set[str]) -> None:
        h = self._handles
        h["instance"] = instance = xr.create_instance(xr.InstanceCreateInfo(
            enabled_extension_names=sorted(enabled)))
        system = xr.get_system(instance, xr.SystemGetInfo(
            form_factor=xr.FormFactor.HEAD_MOUNTED_DISPLAY))
        h["session"] = session = xr.create_session(instance, xr.SessionCreateInfo(
            system_id=system))
        self._hands = OpenXRHands.create(xr, instance, system, session, enabled,
                                         self.describe_name())
        h["stage"] = xr.create_reference_space(session, xr.ReferenceSpaceCreateInfo(
            reference_space_type=xr.ReferenceSpaceType.STAGE))
        h["hmd"] = xr.create_reference_space(session, xr.ReferenceSpaceCreateInfo(
            reference_space_type=xr.ReferenceSpaceType.VIEW))
        actions = xr.create_action_set(instance, xr.ActionSetCreateInfo(
            action_set_name="colosseum", localized_action_set_name="Colosseum"))
        hands = [xr.string_to_path(instance, path) for _, path in HANDS]
        grip = xr.create_action(actions, xr.ActionCreateInfo(
            action_type=xr.ActionType.POSE_INPUT, action_name="grip",
            localized_action_name="Grip", subaction_paths=hands))
        select = xr.create_action(actions, xr.ActionCreateInfo(
            action_type=xr.ActionType.BOOLEAN_INPUT, action_name="select",
            localized_action_name="Select", subaction_paths=hands))
        bindings = [xr.ActionSuggestedBinding(action, xr.string_to_path(instance, f"{p}{part}"))
                    for _, p in HANDS
                    for action, part in ((grip, "/input/grip/pose"),
                                         (select, "/input/select/click"))]
        xr.suggest_interaction_profile_bindings(instance, xr.InteractionProfileSuggestedBinding(
            interaction_profile=xr.string_to_path(instance, PROFILE),
            suggested_bindings=bindings))
        xr.attach_session_action_sets(session, xr.SessionActionSetsAttachInfo(
            action_sets=[actions]))
        h["actions"], h["select"], h["paths"] = actions, select, hands
        h["grips"] = [xr.create_action_space(session, xr.ActionSpaceCreateInfo(
            action=grip, subaction_path=path)) for path in hands]
        h["pressed"] = [False, False]

    def _receive(self) -> None:
        xr, h = self._xr, self._handles
        self._handle_events(xr)
        if not self._running:
            self._stop.wait(0.05)
            return
        session = h["session"]
        frame = xr.wait_frame(session)
        when = int(frame.predicted_display_time)
        # A headless session may have no frame loop (Monado's: xrWaitFrame returns at once
        # with no display time, and xrBeginFrame refuses): poses are then read at the
        # runtime's "now", HEADLESS_PERIOD apart
        framed = when > 0
        if framed:
            xr.begin_frame(session)
        else:
            when = self._runtime_now(xr)
        now = self.clock()
        if when > 0:
            self._sample(xr, when, now)
        if framed:
            xr.end_frame(session, xr.FrameEndInfo(
                display_time=when, environment_blend_mode=xr.EnvironmentBlendMode.OPAQUE,
                layers=[]))
        else:
            self._stop.wait(HEADLESS_PERIOD)

    def _sample(self, xr: Any, when: int, now: float) -> None:
        """The head, the controllers, their select buttons and the hands at ``when``."""
        h = self._handles
        session = h["session"]
        xr.sync_actions(session, xr.ActionsSyncInfo(
            active_action_sets=[xr.ActiveActionSet(h["actions"], xr.NULL_PATH)]))
        self._locate(xr, "hmd", h["hmd"], when, now)
        for i, (name, _) in enumerate(HANDS):
            self._locate(xr, name, h["grips"][i], when, now)
            state = xr.get_action_state_boolean(session, xr.ActionStateGetInfo(
                action=h["select"], subaction_path=h["paths"][i]))
            button = select_change(name, state, h["pressed"][i], now)
            if button is not None:
                h["pressed"][i] = button.pressed
                self.push(button)
        self._locate_hands(when, now)

    def _runtime_now(self, xr: Any) -> int:
        """The runtime's clock now (ns; XR_KHR_convert_timespec_time), 0 without it."""
        if TIMESPEC not in self._enabled:
            return 0
        t = time.clock_gettime_ns(time.CLOCK_MONOTONIC)
        spec = xr.timespec(t // 1_000_000_000, t % 1_000_000_000)
        now = xr.convert_timespec_time_to_time_khr(self._handles["instance"], spec)
        return int(getattr(now, "value", now))

    def _handle_events(self, xr: Any) -> None:
        h = self._handles
        while True:
            try:
                event = xr.poll_event(h["instance"])
            except xr.exception.EventUnavailable:
                return
            if xr.StructureType(event.type) != xr.StructureType.EVENT_DATA_SESSION_STATE_CHANGED:
                continue
            changed = ctypes.cast(ctypes.byref(event),
                                  ctypes.POINTER(xr.EventDataSessionStateChanged))
            state = xr.SessionState(changed.contents.state)
            if state == xr.SessionState.READY:
                xr.begin_session(h["session"], xr.SessionBeginInfo(
                    primary_view_configuration_type=xr.ViewConfigurationType.PRIMARY_STEREO))
                self._running = True
            elif state == xr.SessionState.STOPPING:
                xr.end_session(h["session"])
                self._running = False

    def _locate(self, xr: Any, name: str, space: Any, when: Any, now: float) -> None:
        pose = located_pose(name, xr.locate_space(space, self._handles["stage"], when), now)
        if pose is not None:
            self.push(pose)

    def _locate_hands(self, when: Any, now: float) -> None:
        """Each tracked hand's joints at display time ``when``, in the stage space."""
        if self._hands is None:
            return
        for name, raw in self._hands.locate(self._handles["stage"], when).items():
            hand = hand_event(name, raw, now, self._last_hands.get(name))
            if hand is not None:
                self._last_hands[name] = hand
                self.push(hand)

    def _close(self) -> None:
        xr, h = self._xr, self._handles
        if self._hands is not None:
            self._hands.destroy()
            self._hands = None
        if "session" in h:
            xr.destroy_session(h["session"])
        if "instance" in h:
            xr.destroy_instance(h["instance"])
        h.clear()
