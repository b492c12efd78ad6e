"""The input plugin: one INPUT-phase system drains every device; outputs go out each frame.

:class:`InputSystem` builds the devices the scene's ``Input`` block and ``--input``
options name (plus the render window's keyboard and mouse), and each frame asks the
:class:`InputHub` for the frame's input — calibrated, filtered, the latest-state table
(:class:`InputState`, a resource) updated — and emits every event on the bus, so
what a device sent is visible to every later system of the same frame. A tracker bound
to an object or a camera (``Tracker { Object "cursor" }``, ``Tracker { Camera "eye" }``)
moves its Transform; a camera bound so takes the tracker's orientation (a headset). The
desktop device looks through the active camera; when its hands are tracked relative to
an object (``Hand { Frame }``, a wheelchair) it reports their poses in that object's
frame, as a tracker on it would.

:class:`OutputSystem` sends the ``Output`` blocks' values at the end of each frame, and
task markers: Lua's ``emit("marker", text)`` or ``engine.resource(Outputs).marker(text)``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Camera, Controller, Hand, Name, Physical, Transform
from engine.events import CustomEvent
from engine.rotation import quat_conjugate, quat_multiply, quat_to_matrix
from engine.scene.inputs import DESKTOP_TRACKERS, DeviceSpec, InputSpec
from engine.system import Phase, PluginName, System
from services.input import (
    DeviceError,
    InputHub,
    InputState,
    make_device,
    merge_devices,
    parse_input_option,
)
from services.input.desktop import DesktopDevice, WindowDevice
from services.input.device import PluginDevices
from services.input.output import Publisher, make_publisher

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.input")


def _scene_input(engine: Engine) -> InputSpec:
    from engine.scene import SceneIds

    ids = engine.try_resource(SceneIds)
    return InputSpec() if ids is None else ids.spec.input


def _named(engine: Engine, name: str) -> int | None:
    """The entity whose Name is ``name`` (scene objects, cameras, controllers)."""
    for entity, n in engine.world.get_component(Name):
        if n.id == name:
            return entity
    return None


class InputSystem(System):
    """Drains all devices once per frame and publishes what they said."""

    phase = Phase.INPUT
    reads = (Name, Physical, Camera, Transform, Hand)
    writes = (Transform, Camera)

    def __init__(self, devices: Sequence[DeviceSpec | str] = ()) -> None:
        self.extra_devices = devices
        self.hub: InputHub | None = None
        self.window = WindowDevice()
        self._desktops: list[DesktopDevice] = []
        self._bound: dict[str, int] = {}  # tracker ID -> entity its pose moves

    def setup(self, engine: Engine) -> None:
        spec = _scene_input(engine)
        extra = [*self.extra_devices, *engine.config.options.get("input", ())]
        specs = merge_devices(spec.devices, [parse_input_option(d) if isinstance(d, str)
                                             else d for d in extra])
        devices: list[Any] = []
        for device_spec in specs:
            try:
                devices.append(make_device(device_spec, self.window))
            except (DeviceError, ValueError) as exc:
                log.error("input device %r: %s; the run goes on without it", device_spec.id,
                          exc)
        devices.extend(engine.try_resource(PluginDevices) or ())
        self._desktops = [d for d in devices if isinstance(d, DesktopDevice)]
        if not self._desktops:
            devices.append(self.window)  # the window's keys, as they are
        timeouts = {s.id: s.timeout for s in specs if s.timeout is not None}
        self.hub = hub = InputHub(spec, devices, timeouts=timeouts)
        engine.insert_resource(hub)
        engine.insert_resource(hub.state)
        engine.insert_resource(self.window)
        engine.stat_sources["input"] = hub.stats
        self._bind_objects(engine, spec)

    def _bind_objects(self, engine: Engine, spec: InputSpec) -> None:
        for tracker in spec.trackers:
            if tracker.object is None:
                continue
            entity = _named(engine, tracker.object)
            if entity is None:
                log.error("tracker %r: no object %r to move", tracker.id, tracker.object)
            elif engine.world.has_component(entity, Physical):
                log.error("tracker %r: object %r has physics; drive bodies with a Controller "
                          "(kinematic:%s) or a Hand, not by moving their pose", tracker.id,
                          tracker.object, tracker.object)
            else:
                self._bound[tracker.id] = entity
                camera = engine.world.try_component(entity, Camera)
                if camera is not None:
                    camera.look_at = None  # the tracker turns it (a headset)

    def run(self, engine: Engine, dt: float) -> None:
        hub = self.hub
        assert hub is not None
        for desktop in self._desktops:
            self._update_view(engine, desktop)
        emit = engine.events.emit
        for event in hub.step(engine.frame):
            emit(event)
        self._move_bound(engine, hub.state)

    def _move_bound(self, engine: Engine, state: InputState) -> None:
        world = engine.world
        for tracker_id, entity in self._bound.items():
            tracker = state.tracker(tracker_id)
            transform = world.try_component(entity, Transform)
            if tracker is None or transform is None or not tracker.tracked:
                continue
            transform.position[:] = tracker.position
            transform.orientation[:] = tracker.orientation

    @staticmethod
    def _update_view(engine: Engine, desktop: DesktopDevice) -> None:
        """Point the desktop emulation at the active camera, as the renderer sees it."""
        from services.render.camera import camera_from_component

        world = engine.world
        poses = world.poses
        for entity, camera in world.get_component(Camera):
            if not camera.active or entity not in poses.row_of:
                continue
            row = poses.row_of[entity]
            target = None
            if camera.follow is not None and camera.follow in poses.row_of:
                t_row = poses.row_of[camera.follow]
                target = (poses.position[t_row], poses.orientation[t_row])
            view = camera_from_component(camera, poses.position[row], poses.orientation[row],
                                         target)
            position = np.asarray(view.position, dtype=np.float64)
            orientation = np.asarray(view.orientation, dtype=np.float64)
            frame = _desktop_hands_frame(engine)
            if frame is not None:  # hands tracked relative to a wheelchair: so is the mouse
                position = quat_to_matrix(frame.orientation).T @ (position - frame.position)
                orientation = quat_multiply(quat_conjugate(frame.orientation), orientation)
            desktop.view.position = position
            desktop.view.orientation = orientation
            desktop.view.fov = view.fov
            width, _, height = str(engine.config.options.get("size") or "640x480").partition("x")
            desktop.view.aspect = int(width) / max(int(height), 1)
            return

    def shutdown(self, engine: Engine) -> None:
        if self.hub is not None:
            self.hub.close()


def _desktop_hands_frame(engine: Engine) -> Transform | None:
    """The object the desktop device's hands are tracked relative to (their ``Frame``), if
    they have one: the emulated trackers then report poses in its frame, as a tracker on
    it would."""
    world = engine.world
    for _, hand in world.get_component(Hand):
        if hand.tracker in DESKTOP_TRACKERS and hand.frame is not None:
            return world.try_component(hand.frame, Transform)
    return None


class Outputs:
    """Values Python systems publish by name (``set``) and task markers (``marker``).
    ``sent`` names the values the scene's Output blocks send: a system with a value per
    object per frame (a hand's force) sets only those."""

    def __init__(self) -> None:
        self.values: dict[str, tuple[float, ...]] = {}
        self.markers: list[str] = []
        #: Each marker's LSL time when its sender gave one (None: when it is sent).
        self.stamps: list[float | None] = []
        self.sent: frozenset[str] = frozenset()

    def set(self, name: str, value: float | Sequence[float]) -> None:
        self.values[name] = (float(value),) if isinstance(value, (int, float)) else \
            tuple(float(v) for v in value)

    def marker(self, text: str, timestamp: float | None = None) -> None:
        """A marker; ``timestamp`` (LSL clock, s) stamps it on LSL streams, so it carries
        the moment its sender recorded (a trial's row) rather than the moment it is sent."""
        self.markers.append(str(text))
        self.stamps.append(timestamp)


class OutputSystem(System):
    """Sends each Output block's values every frame, and the frame's markers."""

    phase = Phase.POST_PHYSICS
    reads = (Transform, Controller, Name)

    def __init__(self) -> None:
        self.outputs = Outputs()
        self._publishers: list[tuple[Publisher, tuple[str, ...], bool]] = []
        self._readers: dict[str, Callable[[], tuple[float, ...] | None]] = {}

    def setup(self, engine: Engine) -> None:
        engine.insert_resource(self.outputs)
        for spec in _scene_input(engine).outputs:
            try:
                publisher = make_publisher(spec.kind, spec.address, spec.port, spec.name,
                                           spec.scope)
            except DeviceError as exc:
                log.error("%s; the run goes on without this output", exc)
                continue
            self._publishers.append((publisher, spec.values, spec.markers))
        self.outputs.sent = frozenset(name for _, names, _ in self._publishers
                                      for name in names)
        engine.events.subscribe(CustomEvent, self._on_custom)

    def _on_custom(self, event: CustomEvent) -> None:
        if event.name == "marker":
            self.outputs.marker(str(event.data))

    def run(self, engine: Engine, dt: float) -> None:
        markers, self.outputs.markers = self.outputs.markers, []
        stamps, self.outputs.stamps = self.outputs.stamps, []
        stamps += [None] * (len(markers) - len(stamps))  # markers appended directly
        for publisher, names, send_markers in self._publishers:
            values = {}
            for name in names:
                value = self._reader(engine, name)()
                if value is not None:
                    values[name] = value
            publisher.send(values)
            if send_markers:
                for text, stamp in zip(markers, stamps, strict=False):
                    publisher.marker(text, stamp)

    def _reader(self, engine: Engine, name: str) -> Callable[[], tuple[float, ...] | None]:
        reader = self._readers.get(name)
        if reader is None:
            reader = self._readers[name] = self._make_reader(engine, name)
        return reader

    def _make_reader(self, engine: Engine, name: str) -> Callable[[], tuple[float, ...] | None]:
        kind, _, arg = name.partition(":")
        world = engine.world
        if kind in ("position", "velocity", "angular_velocity", "controller"):
            entity = _named(engine, arg)
            if entity is None:
                log.error("output %r: no object %r; it is not sent", name, arg)
                return lambda: None
            if kind == "controller":
                return lambda: _controller_value(world.try_component(entity, Controller))
            field = "linear_velocity" if kind == "velocity" else kind
            return lambda: _transform_field(world.try_component(entity, Transform), field)
        state = engine.resource(InputState)
        if kind == "wheel":
            return lambda: None if state.wheel(arg) is None else (
                state.wheels[arg].angular_velocity,)
        if kind == "tracker":
            return lambda: None if state.tracker(arg) is None else tuple(
                float(v) for v in (*state.trackers[arg].position,
                                   *state.trackers[arg].orientation))
        return lambda: self.outputs.values.get(name)

    def shutdown(self, engine: Engine) -> None:
        for publisher, _, _ in self._publishers:
            publisher.close()
        self._publishers.clear()


def _transform_field(t: Transform | None, field: str) -> tuple[float, ...] | None:
    return None if t is None else tuple(float(v) for v in getattr(t, field))


def _controller_value(c: Controller | None) -> tuple[float, ...] | None:
    return None if c is None else (float(c.value),)


class InputPlugin:
    """Input devices in, engine values out (``requestPlugin("input")``)."""

    name = PluginName.INPUT

    def __init__(self, devices: Sequence[DeviceSpec | str] = ()) -> None:
        self.devices = devices

    def build(self, engine: Engine) -> None:
        engine.add_system(InputSystem(self.devices))
        engine.add_system(OutputSystem())
