"""The headset display (``colosseum run CONTENT --xr``, or a scene's ``Display { Kind
"openxr" }``): the world drawn into an OpenXR headset at the runtime's pace.

What the plugin adds:

* :class:`XrFrameController`, the engine's frame pacing: ``xrWaitFrame`` in place of the
  engine's own sleep. Serial mode takes the fixed physics steps each display frame is
  worth, the remainder carried (:class:`services.xr.timing.StepPlanner`); threaded mode
  leaves physics to its own thread at its own step.
* :class:`XrSystem` (INPUT, before the input system): opens the display; the recenter key.
* :class:`HeadsetControllers`, an input device: head and controllers at the frame's
  predicted display time as ``TrackerPose``/``Button``/``Axis`` (only while FOCUSED),
  recorded and replayed like any device's.
* :class:`HapticSystem` (POST_PHYSICS): a hand's touch, grasp and contacts pulse the
  controller that drives it.

The render system draws into the display's target (``services.xr.display``) when this
plugin has opened it. Failing to open it is one message: the run ends (exit 1), or goes
on in the window where ``Fallback "window"`` or ``--xr-fallback`` says so.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Camera, Hand, Headset
from engine.events import ContactBegan, HandGrasped, HandTouched, KeyEvent
from engine.realtime import Pacing, RealTimeController, Tick
from engine.services import HeadsetControl
from engine.system import Phase, PluginName, System
from services.input.device import DeviceStatus, PluginDevices
from services.input.events import AnyInput
from services.xr.bindings import Rebinding
from services.xr.display import XrDisplay
from services.xr.session import XrError, XrSettings
from services.xr.timing import StepPlanner

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.xr")

#: How long the runtime may take to make the session ready before the run gives up (s).
READY_WITHIN = 20.0
#: A pulse's length (s) for a touch and a grasp; a contact's is as long as a frame.
PULSE = 0.05


class XrFrameController(RealTimeController):
    """Frames paced by the headset: ``begin`` waits for the runtime's next frame."""

    def __init__(self, pacing: Pacing, display: XrDisplay, threaded: bool) -> None:
        super().__init__(pacing)
        self.display = display
        self.threaded = threaded
        self.planner = StepPlanner(pacing.dt, pacing.max_substeps)
        self._paced_by_runtime = False
        self._since: float | None = None
        #: The engine's physics (set by XrSystem once plugins are built): paused with the
        #: headset taken off.
        self.physics: Any = None

    def begin(self) -> Tick:
        period = self.display.wait_frame()
        now = self.clock()
        if self._start is None:
            self._start = self._deadline = now
        self._tick_start = now
        if period is None:  # no frame loop yet (or any more): wait for the runtime
            self._paced_by_runtime = False
            self._waiting(now)
            return Tick(0.0, 0)
        self._paced_by_runtime = True
        paused = self.display.lifecycle.paused
        if self.physics is not None:
            self.physics.paused = paused  # threaded: the physics thread waits too
        if paused:
            return Tick(0.0, 0)
        if self.threaded:
            return Tick(period, 1)
        steps = self.planner.steps(period)
        return Tick(steps * self.dt, steps)

    def _waiting(self, now: float) -> None:
        """Between frames the runtime asks for: poll again shortly; past
        :data:`READY_WITHIN` s with no session running, give up."""
        if self.display.quit:
            return
        if self._since is None:
            self._since = now
        if now - self._since > READY_WITHIN and not self.display.lifecycle.running \
                and self.display.lifecycle.furthest.name in ("UNKNOWN", "IDLE"):
            log.error("the OpenXR session did not become ready in %g s (it is %s): is the "
                      "headset on, and the runtime's compositor running?", READY_WITHIN,
                      self.display.lifecycle.state.name)
            self.display.failed = True
            self.display.quit = True
            return
        self.sleep(0.005)

    def end(self, tick: Tick, physics_seconds: float | None = None) -> None:
        now = self.clock()
        self.tick_costs.add(now - self._tick_start)
        self.sim_time += tick.dt
        if self._paced_by_runtime:
            self._since = None


class HeadsetControllers:
    """The headset's head and controllers as an input device (``headset``)."""

    kind = "openxr"
    watched = False

    def __init__(self, display: XrDisplay) -> None:
        self.name = "headset"
        self.display = display
        self.received = 0

    def open(self) -> None:
        """The display opened the session already."""

    def poll(self, now: float) -> list[AnyInput]:
        events = self.display.sample(now)
        self.received += len(events)
        return events

    def close(self) -> None:
        """The display closes the session."""

    def status(self) -> DeviceStatus:
        state = "open" if self.display.target is not None else "closed"
        return DeviceStatus(self.name, self.kind, state, self.display.session.runtime,
                            self.received, 0)


def settings_of(headset: Headset | None, render_scale: float = 1.0) -> XrSettings:
    """The display's settings from the scene's headset block (None: the defaults)."""
    if headset is None:
        return XrSettings(render_scale=render_scale)
    rebinding = tuple(Rebinding(*b) for b in headset.bindings)
    return XrSettings(reference=headset.space, when_hidden=headset.when_hidden,
                      rebinding=rebinding, refresh_rate=headset.refresh_rate or None,
                      render_scale=headset.render_scale * render_scale, depth=headset.depth)


def scene_headset(engine: Engine) -> Headset | None:
    found = engine.world.get_component(Headset)
    return found[0][1] if found else None


class XrSystem(System):
    """Opens the headset display before the input system starts; the recenter key."""

    phase = Phase.INPUT
    before = ("InputSystem",)
    reads = (Headset, Camera)
    writes = ()

    def __init__(self, display: XrDisplay) -> None:
        self.display = display
        self.recenter_key = "f8"
        self.fallback = False

    def setup(self, engine: Engine) -> None:
        if isinstance(engine.controller, XrFrameController):  # physics is attached by now
            engine.controller.physics = engine.physics
        headset = scene_headset(engine)
        options = engine.config.options
        display = self.display
        display.settings = settings_of(headset, float(options.get("render_scale") or 1.0))
        display.session.settings = display.settings
        display.session.lifecycle.when_hidden = display.settings.when_hidden
        mirror = options.get("xr_mirror") or (headset.mirror if headset else "none")
        display.mirror_mode = "none" if engine.config.headless and mirror != "none" and \
            not options.get("xr_mirror") else mirror
        self.recenter_key = headset.recenter_key if headset else "f8"
        self.fallback = bool(options.get("xr_fallback")) or (
            headset is not None and headset.fallback == "window")
        try:
            display.open()
        except XrError as exc:
            display.failed = True
            if self.fallback:
                log.error("headset: %s; running without the headset (the fallback asked "
                          "for)", exc)
                display.unavailable = True
                engine.controller = RealTimeController(engine.config.pacing(), engine.clock)
                return
            log.error("headset: %s", exc)
            display.quit = True
            engine.request_quit()
            return
        engine.insert_resource(display)
        engine.insert_resource(self, as_type=HeadsetControl)
        engine.stat_sources["xr"] = display.stats
        engine.events.subscribe(KeyEvent, self._on_key)
        self._engine = engine

    def _on_key(self, event: KeyEvent) -> None:
        if event.pressed and event.key == self.recenter_key:
            self.recenter()

    def recenter(self) -> None:
        anchor = _camera_pose(self._engine)
        self.display.recenter(anchor)

    def haptic(self, source: str, amplitude: float, seconds: float) -> bool:
        return self.display.haptic(source, amplitude, seconds)

    def run(self, engine: Engine, dt: float) -> None:
        if self.display.quit:
            engine.request_quit()

    def shutdown(self, engine: Engine) -> None:
        self.display.close()


def _camera_pose(engine: Engine) -> tuple[np.ndarray, np.ndarray]:
    """The active camera's world pose (where the player is put)."""
    poses = engine.world.poses
    for entity, camera in engine.world.get_component(Camera):
        if camera.active and entity in poses.row_of:
            row = poses.row_of[entity]
            return poses.position[row].copy(), poses.orientation[row].copy()
    return np.array([0.0, -8.0, 0.0]), np.array([1.0, 0.0, 0.0, 0.0])


class HapticSystem(System):
    """A hand's touch, grasp and contacts pulse the controller whose tracker drives it."""

    phase = Phase.POST_PHYSICS
    reads = (Hand, Headset)
    writes = ()

    def __init__(self, display: XrDisplay) -> None:
        self.display = display
        self.pulses = 0
        #: The pulses the last frame asked for: controller -> (amplitude, seconds).
        self.last: dict[str, tuple[float, float]] = {}
        self._pending: list[tuple[int, float, float]] = []

    def setup(self, engine: Engine) -> None:
        headset = scene_headset(engine) or Headset()
        self.headset = headset
        if headset.haptic_touch > 0:
            engine.events.subscribe(HandTouched, lambda e: self._pending.append(
                (e.hand, headset.haptic_touch, PULSE)))
        if headset.haptic_grasp > 0:
            engine.events.subscribe(HandGrasped, lambda e: self._pending.append(
                (e.hand, headset.haptic_grasp, 2 * PULSE)))
        if headset.haptic_impulse > 0:
            engine.events.subscribe(ContactBegan, self._on_contact)

    def _on_contact(self, event: ContactBegan) -> None:
        amplitude = min(1.0, event.impulse * self.headset.haptic_impulse)
        if amplitude > 0.02:
            for body in (event.a, event.b):
                self._pending.append((body, amplitude, PULSE))

    def run(self, engine: Engine, dt: float) -> None:
        pending, self._pending = self._pending, []
        self.last = self.strongest(engine, pending)
        for source, (amplitude, seconds) in self.last.items():
            if self.display.haptic(source, amplitude, seconds):
                self.pulses += 1

    @staticmethod
    def strongest(engine: Engine, pending: list[tuple[int, float, float]]
                  ) -> dict[str, tuple[float, float]]:
        """Per controller (a hand's tracker), the strongest pulse this frame asks for."""
        world = engine.world
        out: dict[str, tuple[float, float]] = {}
        for entity, amplitude, seconds in pending:
            hand = world.try_component(entity, Hand) if entity >= 0 else None
            if hand is None or not hand.tracker:
                continue
            out[hand.tracker] = max(out.get(hand.tracker, (0.0, 0.0)), (amplitude, seconds))
        return out


class XrPlugin:
    """The headset display (see the module's docstring)."""

    name = PluginName.XR

    def __init__(self) -> None:
        self.display = XrDisplay()

    def build(self, engine: Engine) -> None:
        display = self.display
        engine.controller = XrFrameController(engine.config.pacing(), display,
                                              engine.config.mode == "threaded")
        devices = engine.try_resource(PluginDevices)
        if devices is None:
            devices = PluginDevices()
            engine.insert_resource(devices)
        devices.append(HeadsetControllers(display))
        engine.add_system(XrSystem(display))
        engine.add_system(HapticSystem(display))
