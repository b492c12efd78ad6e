"""The input hub: all devices, drained once per frame, calibrated, filtered, published.

Each frame :meth:`InputHub.step` does two things in a fixed order:

1. *collect* the frame's raw events — from the live devices (and the watchdog's
   DeviceLost/DeviceFound), or, when replaying, from the recording (live devices are
   then never opened). What is collected is what a recording holds.
2. *apply* them: calibration, one-euro filter and prediction per tracker, wheel rates
   from counts and timestamps, button inversion; the latest-state table
   (:class:`InputState`) is updated and the processed events are returned for the bus.

Step 2 depends only on what step 1 returned, so replaying a recording in serial mode
reproduces a live run bit for bit.
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from engine.scene.inputs import InputSpec, TrackerSpec
from services.input.calibration import Calibration
from services.input.device import MONOTONIC, BadMessages, Clock, DeviceError, InputDevice
from services.input.events import (
    TAGS,
    AnyInput,
    Axis,
    Button,
    DeviceFound,
    DeviceLost,
    HandJoints,
    KeyEvent,
    Pointer,
    TrackerPose,
    WheelCount,
)
from services.input.filters import OneEuro, OneEuroRotation, Velocity, predict
from services.input.hands import HandPipeline, finite, hand_problem
from services.input.record import FrameInput, Recording, RecordWriter
from services.input.state import InputState, TrackerState, WheelState
from services.input.wheel import WheelRate

log = logging.getLogger("colosseum.input")

S = TypeVar("S")

#: Event types that are never "lost": a keyboard or a mouse is silent when unused.
#: Events that come when something changes, not as a stream: their silence says nothing.
_UNWATCHED = (KeyEvent, Pointer, Button, Axis)
#: Distinct trackers, wheels, buttons and axes the devices may name in one run: a sender
#: inventing names (a counter in its addresses) would grow every table without end.
MAX_SOURCES = 1024


class TrackerPipeline:
    """Raw device poses of one tracker -> scene poses (calibrated, filtered, predicted)."""

    def __init__(self, spec: TrackerSpec | None) -> None:
        spec = spec or TrackerSpec("")
        self.calibration = Calibration.of(spec)
        self.filters = ((OneEuro(spec.min_cutoff, spec.beta),
                         OneEuroRotation(spec.min_cutoff, spec.beta))
                        if spec.filter == "oneeuro" else None)
        self.lead = spec.predict
        self.motion = Velocity()

    def __call__(self, raw: TrackerPose) -> TrackerPose:
        cal = self.calibration
        p, q, t = raw.position, raw.orientation, raw.timestamp
        if not cal.is_identity:
            p, q = cal.position(p), cal.orientation(q)
        if self.filters is not None:
            x, y, z = self.filters[0](p, t)
            p, q = (x, y, z), self.filters[1](q, t)
        self.motion.update(p, q, t)
        linear = self.motion.linear if raw.velocity is None else cal.velocity(raw.velocity)
        if self.lead > 0.0:
            p, q = predict(p, q, linear, self.motion.angular, self.lead)
        return TrackerPose(raw.device, p, q, linear, t)


#: The transport name of injected events (:meth:`InputHub.inject`).
INJECTED = "injected"


class InputHub:
    """Owns the devices, the watchdog, the pipelines and the latest-state table."""

    def __init__(self, spec: InputSpec, devices: Sequence[InputDevice],
                 clock: Clock = MONOTONIC, timeouts: dict[str, float] | None = None) -> None:
        self.spec = spec
        self.devices = list(devices)
        self.clock = clock
        self.state = InputState()
        self.state.button_ids = {b.id: (b.device, b.name) for b in spec.buttons}
        self._inverted = {(b.device, b.name) for b in spec.buttons if b.invert}
        self._tracker_specs = {t.id: t for t in spec.trackers}
        self._wheel_specs = {w.id: w for w in spec.wheels}
        self._pipelines: dict[str, TrackerPipeline] = {}
        self._hand_pipelines: dict[str, HandPipeline] = {}
        self._posed: dict[str, TrackerPose] = {}  # this frame's newest pose per tracker
        #: transport name -> seconds of silence before its sources are lost
        self._timeouts = {d.name: (timeouts or {}).get(d.name, spec.lost_after)
                          for d in self.devices}
        self._timeouts[INJECTED] = spec.lost_after
        self._watched = {d.name for d in self.devices if getattr(d, "watched", True)}
        self._last_heard: dict[str, tuple[float, float]] = {}  # source -> (time, timeout)
        self._lost: set[str] = set()
        self._complaints: dict[str, BadMessages] = {}
        #: the input names devices have sent so far (at most MAX_SOURCES of them)
        self._names: set[str | tuple[str, str]] = set()
        self._replay: Recording | None = None
        self._writer: RecordWriter | None = None
        self._started = False
        self._closed = False
        self._replay_clock = 0.0
        #: The recording's last frame, its clock and the mean frame interval (None: empty).
        self._replay_end: tuple[int, float, float] | None = None
        self._replay_ended = False
        self._injected: list[AnyInput] = []
        self.delivered: Counter[str] = Counter()
        #: Called with each frame's raw input as collected (a network node forwards it).
        self.listeners: list[Callable[[FrameInput], None]] = []

    # -- configuration ----------------------------------------------------------
    def replay(self, recording: Recording) -> None:
        """Deliver ``recording`` instead of the live devices (which are then never opened)."""
        if self._started:
            raise RuntimeError("replay must be chosen before the first frame")
        self._replay = recording
        frames = recording.frames
        if frames:
            first, last = min(frames), max(frames)
            span = frames[last].clock - frames[first].clock
            self._replay_end = (last, frames[last].clock,
                                span / (last - first) if last > first else 0.0)
        log.info("replaying %d input events over %d frames from %s", recording.event_count,
                 len(recording.frames), recording.path)

    @property
    def replaying(self) -> bool:
        return self._replay is not None

    def record(self, path: Path, header: dict[str, Any]) -> None:
        """Write every frame's raw input to ``path`` (see :mod:`services.input.record`)."""
        self._writer = RecordWriter(path, {**header, "devices": self.describe_devices()})

    def describe_devices(self) -> list[dict[str, Any]]:
        return [{"id": d.name, "kind": d.kind} for d in self.devices]

    def inject(self, event: AnyInput) -> None:
        """Feed a raw event as if a device had sent it (a network peer, a tool, a test):
        collected with the next frame's input (stamped with its clock when the event has
        no timestamp), watched for silence (DeviceLost after ``LostAfter``), recorded and
        applied like any other; a replay ignores it (the recording already holds the
        run's input)."""
        if not isinstance(event, tuple(TAGS)):
            raise TypeError(f"inject takes a typed input event, got {type(event).__name__}")
        self._injected.append(event)

    # -- running ------------------------------------------------------------------
    def start(self) -> None:
        """Open every device; one that cannot open is reported and left out."""
        if self._started:
            return
        self._started = True
        if self._replay is not None:
            return
        opened = []
        for device in self.devices:
            try:
                device.open()
            except DeviceError as exc:
                log.error("%s; the run goes on without it", exc)
                continue
            opened.append(device)
            if getattr(device, "watched", True):
                log.info("%s open", describe(device))
        self.devices = opened

    def step(self, frame: int) -> list[AnyInput]:
        """Collect, record and apply one frame's input; returns the events to publish."""
        self.start()
        batch = self.collect(frame)
        if self._writer is not None:
            self._writer.write(frame, batch)
        for listener in self.listeners:
            listener(batch)
        return self.apply(batch)

    def collect(self, frame: int) -> FrameInput:
        injected, self._injected = self._injected, []
        if self._replay is not None:
            recorded = self._replay.frames.get(frame)
            if recorded is not None:
                self._replay_clock = recorded.clock
                return recorded
            if self._replay_end is not None and frame > self._replay_end[0]:
                return self._after_replay(frame, self._replay_end)
            return FrameInput(self._replay_clock)
        now = self.clock()
        events: list[AnyInput] = []
        for event in injected:  # a peer's sources are watched like a device's
            event = event if event.timestamp else replace(event, timestamp=now)
            if not isinstance(event, (*_UNWATCHED, DeviceLost, DeviceFound)):
                self._heard(event.device, event.timestamp, INJECTED, events)
            events.append(event)
        for device in self.devices:
            for event in device.poll(now):
                if not self._wanted(event, device.name) or not self._admit(event, device.name):
                    continue
                if device.name in self._watched and not isinstance(event, _UNWATCHED):
                    self._heard(event.device, event.timestamp, device.name, events)
                events.append(event)
        for source, (last, timeout) in self._last_heard.items():
            if source not in self._lost and now - last > timeout:
                self._lost.add(source)
                events.append(DeviceLost(source, now))
        return FrameInput(now, events)

    def _after_replay(self, frame: int, end: tuple[int, float, float]) -> FrameInput:
        """A frame past the recording's end: its devices fell silent. The clock goes on
        at the recording's mean frame interval (so wheels come to rest as a silent
        encoder's do) and, at the first such frame, every source still tracked is lost."""
        last, last_clock, interval = end
        clock = last_clock + (frame - last) * interval
        if self._replay_ended:
            return FrameInput(clock)
        self._replay_ended = True
        log.info("the recorded input ended at frame %d: no input from here on", last)
        state = self.state
        sources = sorted((state.trackers.keys() | state.wheels.keys() | state.hands.keys())
                         - state.lost)
        return FrameInput(clock, [DeviceLost(source, clock) for source in sources])

    def _wanted(self, event: AnyInput, transport: str) -> bool:
        """Drop poses (and hands) of a tracker bound to another device (``Tracker { Device }``)."""
        if isinstance(event, (TrackerPose, HandJoints)):
            spec = self._tracker_specs.get(event.device)
            return spec is None or not spec.device or spec.device == transport
        return True

    def _admit(self, event: AnyInput, transport: str) -> bool:
        """False for an input name past the first MAX_SOURCES (told as a bad message)."""
        if isinstance(event, (TrackerPose, WheelCount, HandJoints)):
            name: str | tuple[str, str] = event.device
        elif isinstance(event, (Button, Axis)):
            name = (event.device, event.name)
        else:
            return True
        if name in self._names:
            return True
        if len(self._names) >= MAX_SOURCES:
            self._complain(transport, f"a new input name beyond the first {MAX_SOURCES} "
                                      "this run has heard; ignored", event)
            return False
        self._names.add(name)
        return True

    def _heard(self, source: str, timestamp: float, transport: str,
               events: list[AnyInput]) -> None:
        if source not in self._last_heard or source in self._lost:
            self._lost.discard(source)
            events.append(DeviceFound(source, timestamp))
        self._last_heard[source] = (timestamp, self._timeouts.get(transport, 0.5))

    def apply(self, batch: FrameInput) -> list[AnyInput]:
        state = self.state
        state.now = batch.clock
        out: list[AnyInput] = []
        self._posed.clear()
        for event in batch.events:
            processed = self._apply(event)
            if processed is None:
                continue
            out.append(processed)
            self.delivered[TAGS[type(processed)]] += 1
        for name, pose in self._posed.items():  # the table holds each tracker's newest pose
            tracker = state.trackers[name]
            tracker.position = np.array(pose.position)
            tracker.orientation = np.array(pose.orientation)
            tracker.velocity = np.array(pose.velocity)
            tracker.angular_velocity = np.array(self._pipelines[name].motion.angular)
            tracker.timestamp = pose.timestamp
        for wheel in state.wheels.values():
            wheel.angular_velocity = wheel.rate.angular_velocity(batch.clock)
        for complaints in self._complaints.values():
            complaints.report(batch.clock)
        _tell_changes(out)
        return out

    def _apply(self, event: AnyInput) -> AnyInput | None:
        """The processed event, after updating the state table; None when it is dropped."""
        state = self.state
        if isinstance(event, TrackerPose):
            return self._apply_pose(event)
        if isinstance(event, WheelCount):
            wheel = state.wheels.get(event.device)
            if wheel is None:
                spec = _scoped(self._wheel_specs, event.device)
                rate = WheelRate.of(spec) if spec is not None else WheelRate()
                wheel = state.wheels[event.device] = WheelState(rate)
            problem = wheel.rate.add(event.count, event.timestamp)
            if problem is not None:
                self._complain(event.device, problem, event)
            wheel.count, wheel.timestamp = event.count, event.timestamp
            return event
        if isinstance(event, Button):
            key = (event.device, event.name)
            if key in self._inverted or (event.device.rpartition("/")[2], event.name) \
                    in self._inverted:
                event = Button(event.device, event.name, not event.pressed, event.timestamp)
            state.buttons[key] = event.pressed
            return event
        if isinstance(event, Axis):
            state.axes[(event.device, event.name)] = event.value
            return event
        if isinstance(event, KeyEvent):
            if event.pressed:
                state.keys.add(event.key.lower())
            else:
                state.keys.discard(event.key.lower())
            return event
        if isinstance(event, Pointer):
            state.pointers[event.device] = (event.x, event.y)
            return event
        if isinstance(event, HandJoints):
            return self._apply_hand(event)
        tracked = isinstance(event, DeviceFound)
        if tracked:
            state.lost.discard(event.device)
        else:
            state.lost.add(event.device)
        tracker = state.trackers.get(event.device)
        if tracker is not None:
            tracker.tracked = tracked
        return event

    def _apply_hand(self, event: HandJoints) -> HandJoints | None:
        """A hand calibrated and filtered into the state table; None (told) when it is
        malformed or its calibration took it past float range."""
        problem = hand_problem(event)
        if problem is not None:
            self._complain(event.device, problem, event)
            return None
        pipeline = self._hand_pipelines.get(event.device)
        if pipeline is None:
            pipeline = self._hand_pipelines[event.device] = HandPipeline(
                _scoped(self._tracker_specs, event.device))
        hand = pipeline(event)
        if not finite(hand):
            self._complain(event.device, "a hand's calibrated or filtered joints are not "
                                         "finite (check the Tracker's Scale and Offset)", event)
            self._hand_pipelines.pop(event.device)  # its filters start afresh
            return None
        self.state.hands[event.device] = hand
        return hand

    def _apply_pose(self, event: TrackerPose) -> TrackerPose | None:
        """The pose calibrated, filtered and predicted by its tracker's pipeline."""
        pipeline = self._pipelines.get(event.device)
        if pipeline is None:
            pipeline = self._pipelines[event.device] = TrackerPipeline(
                _scoped(self._tracker_specs, event.device))
            self.state.trackers.setdefault(event.device, TrackerState())
        pose = pipeline(event)
        if not all(map(math.isfinite, (*pose.position, *pose.orientation,
                                       *(pose.velocity or ())))):
            # the scene's Scale, Offset or Predict took a sane sample past float range:
            # drop it, and start the filters afresh rather than keep an inf in them
            self._complain(event.device, "calibrated, filtered or predicted pose is not "
                                         "finite (check the Tracker's Scale, Offset and "
                                         "Predict)", event)
            self._pipelines[event.device] = TrackerPipeline(
                _scoped(self._tracker_specs, event.device))
            return None
        self._posed[event.device] = pose
        return pose

    def _complain(self, source: str, problem: str, event: AnyInput) -> None:
        complaints = self._complaints.get(source)
        if complaints is None:
            complaints = self._complaints[source] = BadMessages(f"input source {source!r}")
        complaints.note(problem, event)

    def close(self) -> str | None:
        """Close every device and the recording; returns the recording's summary, if any."""
        if self._closed:
            return None
        self._closed = True
        if self._started and self._replay is None:
            for device in self.devices:
                device.close()
        for complaints in self._complaints.values():
            complaints.report(0.0, final=True)
        return self._writer.close() if self._writer is not None else None

    def stats(self) -> dict[str, Any]:
        """The ``input`` section of ``--stats``."""
        return {"devices": [asdict(d.status()) for d in self.devices],
                "delivered": dict(self.delivered), "lost": sorted(self.state.lost),
                "replaying": self._replay is not None}


def _tell_changes(events: list[AnyInput]) -> None:
    """One line for the sources found in a frame and one for those lost (a sender with a
    counter in its addresses finds a thousand in one frame)."""
    found = [e.device for e in events if isinstance(e, DeviceFound)]
    lost = [e.device for e in events if isinstance(e, DeviceLost)]
    if found:
        log.info("input source%s %s found", "s" * (len(found) > 1), _listed(found))
    if lost:
        log.warning("input source%s %s lost: nothing received for %s timeout; untracked "
                    "until %s again", "s" * (len(lost) > 1), _listed(lost),
                    "their" if len(lost) > 1 else "its",
                    "they send" if len(lost) > 1 else "it sends")


def _listed(names: list[str], shown: int = 5) -> str:
    """``'a', 'b' and 3 more``."""
    text = ", ".join(repr(n) for n in names[:shown])
    return text + (f" and {len(names) - shown} more" if len(names) > shown else "")


def _scoped(specs: dict[str, S], source: str) -> S | None:
    """The spec of ``source``; for a user's source ``alice/hand_r`` (a network node's,
    see services.net) with none of its own, the spec of ``hand_r``: every user's devices are
    calibrated as the scene calibrates that device."""
    found = specs.get(source)
    if found is None and "/" in source:
        found = specs.get(source.rpartition("/")[2])
    return found


def describe(device: InputDevice) -> str:
    describe_name = getattr(device, "describe_name", None)
    return describe_name() if describe_name else f"input device {device.name!r} ({device.kind})"

