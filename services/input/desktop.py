"""The window's keyboard and mouse as a device, and desktop emulation of the VR rig.

:class:`WindowDevice` turns the render window's callbacks into typed events (``Key``
from ``keyboard``; ``Pointer`` and mouse ``Button`` from ``mouse``). Without a window
(headless) it simply stays silent.

:class:`DesktopDevice` (``Device { Kind "desktop" }`` or ``--input desktop``) drives
everything the paper's rig has with them, so content runs without hardware:

- the mouse moves the active hand's tracker in the camera's image plane, at a depth
  the scroll wheel changes; the hand takes the camera's orientation;
- the left mouse button is that hand's pinch (``Button(glove_r, "pinch")``);
- W/S turn both wheel counters forward/back, A/D turn them against each other;
- Tab (or 1 and 2) switches which hand the mouse drives;
- Z, X, C, V shape that hand's fingers: open, pinch, point, fist (:data:`SHAPE_KEYS`; the
  hand keeps its shape until another key, and shows the pinch while the left button is
  down), blending into the new shape over :data:`BLEND` seconds.

Each emulated hand is also a tracked hand of 26 joints (``HandJoints`` of ``hand_l`` and
``hand_r``, :func:`~services.input.hand_pose.pose_hand`): the palm joint at the tracker's
position, the fingers pointing into the view, the back of the hand up. They are sent once
the hand has a pose and whenever it moves or changes shape (each frame of a blend); the
state table holds the latest, so a fingered hand has its joints every frame without
hardware, and a still hand costs no traffic (a recording, a node's link to its server).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from engine.rotation import quat_multiply, quat_to_matrix
from engine.scene.inputs import DESKTOP_GLOVES, DESKTOP_TRACKERS
from services.input.device import MONOTONIC, Clock, DeviceStatus, QueuedDevice
from services.input.events import (
    FINGERS,
    AnyInput,
    Button,
    HandJoints,
    KeyEvent,
    Pointer,
    TrackerPose,
    WheelCount,
)
from services.input.hand_pose import GESTURES, local_hand, pose_hand
from services.input.hand_query import in_frame

HANDS, GLOVES = DESKTOP_TRACKERS, DESKTOP_GLOVES
WHEELS = ("left", "right")
#: Metres the hand moves in depth per scroll notch, and the depth's bounds.
DEPTH_STEP = 0.05
DEPTH_RANGE = (0.1, 3.0)
#: Keys -> (left wheel, right wheel) direction while held.
WHEEL_KEYS = {"w": (1.0, 1.0), "s": (-1.0, -1.0), "a": (-1.0, 1.0), "d": (1.0, -1.0)}
HAND_KEYS = {"1": 0, "number_1": 0, "2": 1, "number_2": 1}
#: Keys -> the hand shape (a :data:`~services.input.hand_pose.GESTURES` name) they select: a
#: row under W/S/A/D, used by no content (the stroke simulator takes Y, R, N, M, digits).
SHAPE_KEYS = {"z": "open", "x": "pinch", "c": "point", "v": "fist"}
#: Seconds a hand takes to blend from one shape into the next.
BLEND = 0.15
#: The emulated hand's frame in the view's (columns right, forward, up): its fingers (+x)
#: point forward, the back of the hand (+z) up; a quarter turn about the view's up.
HAND_IN_VIEW = np.array([np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])
#: The palm joint in a right hand's own frame (the metacarpals do not bend with the
#: curls): the emulated hand is placed so that its palm is at the tracker.
_PALM = local_hand({})[0][0]


class WindowDevice(QueuedDevice):
    """Keys and mouse of the render window; the window calls these from the main thread."""

    kind = "window"
    watched = False  # a keyboard is silent when nobody types: never "lost"

    def __init__(self, name: str = "window", clock: Clock = MONOTONIC) -> None:
        self.clock = clock
        self._pointer = (0.5, 0.5)
        super().__init__(name)

    def key(self, name: str, pressed: bool) -> None:
        self.push(KeyEvent(name.lower(), pressed, "keyboard", self.clock()))

    def pointer(self, x: float, y: float) -> None:
        """The pointer is at ``(x, y)``, window coordinates 0..1 with y down."""
        self._pointer = (x, y)
        self.push(Pointer("mouse", x, y, 0.0, self.clock()))

    def scroll(self, notches: float) -> None:
        self.push(Pointer("mouse", *self._pointer, notches, self.clock()))

    def mouse_button(self, name: str, pressed: bool) -> None:
        self.push(Button("mouse", name, pressed, self.clock()))

    def _open(self) -> None:
        """Nothing to claim: the render window calls in when it exists."""

    def _receivers(self) -> list[Callable[[], None]]:
        return []


@dataclass(slots=True)
class DesktopView:
    """The camera the mouse works in: pose, vertical field of view (degrees), aspect."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    orientation: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))
    fov: float = 60.0
    aspect: float = 4.0 / 3.0

    def point(self, x: float, y: float, depth: float) -> np.ndarray:
        """The world point under window position ``(x, y)`` at ``depth`` m along the view."""
        axes = quat_to_matrix(self.orientation)  # columns: right, forward, up
        half_height = depth * math.tan(math.radians(self.fov) / 2.0)
        return (self.position + axes[:, 1] * depth
                + axes[:, 0] * (2.0 * x - 1.0) * half_height * self.aspect
                + axes[:, 2] * (1.0 - 2.0 * y) * half_height)


@dataclass(slots=True)
class ShapeBlend:
    """One emulated hand's finger curls on their way from one shape to another: smoothstep
    over :data:`BLEND` seconds, advanced by the intervals the device is polled at (so a
    clock set back or jumping ahead moves no finger by more than the blend)."""

    start: dict[str, float] = field(default_factory=lambda: dict(GESTURES["open"]))
    target: dict[str, float] = field(default_factory=lambda: dict(GESTURES["open"]))
    progress: float = 1.0

    def curls(self) -> dict[str, float]:
        """The curls now: ``start`` to ``target``, eased in and out."""
        s = min(max(self.progress, 0.0), 1.0)
        w = s * s * (3.0 - 2.0 * s)
        return {f: self.start[f] + (self.target[f] - self.start[f]) * w for f in FINGERS}

    def toward(self, shape: str) -> None:
        """Blend from the curls now into ``shape`` (nothing changes if it is the target)."""
        if GESTURES[shape] == self.target:
            return
        self.start, self.target, self.progress = self.curls(), dict(GESTURES[shape]), 0.0

    def advance(self, dt: float) -> None:
        self.progress = min(self.progress + dt / BLEND, 1.0)


class DesktopDevice:
    """Emulates two tracked hands (poses, pinch gloves, 26 joints shaped from keys) and
    two wheel counters."""

    kind = "desktop"
    watched = False

    def __init__(self, name: str, window: WindowDevice, turns_per_second: float = 0.5,
                 counts_per_turn: int = 1024) -> None:
        self.name = name
        self.window = window
        self.turns_per_second = turns_per_second
        self.counts_per_turn = counts_per_turn
        self.view = DesktopView()
        self.hand = 1  # the right hand
        self.depth = 0.6
        self.held: set[str] = set()
        self.wheel_counts = [0.0, 0.0]
        self._sent = [0, 0]
        self._last_poll: float | None = None
        self.emulated = 0
        #: Per hand (left, right): the shape its key chose, whether its pinch is down,
        #: its blend, its latest device pose, and the (pose, curls) its joints last showed.
        self.shape = ["open", "open"]
        self.pinching = [False, False]
        self.blends = [ShapeBlend(), ShapeBlend()]
        self.poses: list[tuple[tuple[float, ...], tuple[float, ...]] | None] = [None, None]
        self._shown: list[tuple[Any, ...] | None] = [None, None]
        self._shaped: list[HandJoints | None] = [None, None]  # the shape shown, unplaced

    def open(self) -> None:
        self.window.open()

    def close(self) -> None:
        self.window.close()

    def status(self) -> DeviceStatus:
        inner = self.window.status()
        return DeviceStatus(self.name, self.kind, inner.state, "emulating hands and wheels",
                            inner.received + self.emulated, inner.bad)

    def poll(self, now: float) -> list[AnyInput]:
        # A clock set back (a replay's, a test's switched to simulated time) turns nothing:
        # a negative interval would wind the counters back by however far it jumped.
        dt = 0.0 if self._last_poll is None else max(now - self._last_poll, 0.0)
        self._last_poll = now
        for blend in self.blends:  # the interval before this poll's keys
            blend.advance(dt)
        out: list[AnyInput] = []
        for event in self.window.poll(now):
            out.append(event)
            made = self._emulate(event)
            if made is not None:
                out.append(made)
        out += self._turn_wheels(dt, now)
        out += self._hands(now)
        self.emulated += len(out)
        return out

    def _hands(self, now: float) -> list[HandJoints]:
        """Each posed hand's 26 joints, where its pose or its shape changed since sent."""
        out = []
        for i, pose in enumerate(self.poses):
            if pose is None:
                continue
            self.blends[i].toward("pinch" if self.pinching[i] else self.shape[i])
            curls = self.blends[i].curls()
            shape = tuple(curls.values())
            if (pose, shape) == self._shown[i]:
                continue
            if self._shown[i] is None or self._shown[i][1] != shape:  # type: ignore[index]
                self._shaped[i] = shaped_hand(HANDS[i], curls, left=i == 0)
            self._shown[i] = (pose, shape)
            out.append(emulated_hand(HANDS[i], pose[0], pose[1], curls, left=i == 0,
                                     timestamp=now, shaped=self._shaped[i]))
        return out

    def _emulate(self, event: AnyInput) -> AnyInput | None:
        if isinstance(event, KeyEvent):
            key = event.key
            if event.pressed and key == "tab":
                self.hand = 1 - self.hand
            elif event.pressed and key in HAND_KEYS:
                self.hand = HAND_KEYS[key]
            elif key in WHEEL_KEYS:
                (self.held.add if event.pressed else self.held.discard)(key)
            elif event.pressed and key in SHAPE_KEYS:
                self.shape[self.hand] = SHAPE_KEYS[key]
            return None
        if isinstance(event, Pointer):
            lo, hi = DEPTH_RANGE
            self.depth = min(max(self.depth + event.scroll * DEPTH_STEP, lo), hi)
            p = self.view.point(event.x, event.y, self.depth)
            q = self.view.orientation
            position = (float(p[0]), float(p[1]), float(p[2]))
            orientation = (float(q[0]), float(q[1]), float(q[2]), float(q[3]))
            self.poses[self.hand] = (position, orientation)
            return TrackerPose(HANDS[self.hand], position, orientation, None, event.timestamp)
        if isinstance(event, Button) and event.device == "mouse" and event.name == "left":
            self.pinching[self.hand] = event.pressed
            return Button(GLOVES[self.hand], "pinch", event.pressed, event.timestamp)
        return None

    def _turn_wheels(self, dt: float, now: float) -> list[AnyInput]:
        out: list[AnyInput] = []
        if not self.held:
            return out
        speed = self.turns_per_second * self.counts_per_turn * dt
        for i, name in enumerate(WHEELS):
            direction = sum(WHEEL_KEYS[k][i] for k in self.held)
            self.wheel_counts[i] += max(-1.0, min(1.0, direction)) * speed
            count = round(self.wheel_counts[i])
            if count != self._sent[i]:
                self._sent[i] = count
                out.append(WheelCount(name, count, now))
        return out



def emulated_hand(device: str, position: Sequence[float], view: Sequence[float],
                  curls: dict[str, float], *, left: bool, timestamp: float,
                  shaped: HandJoints | None = None) -> HandJoints:
    """The 26 joints of an emulated hand whose tracker is at ``position`` turned as the
    view ``view`` (w, x, y, z): palm joint at the tracker, fingers forward, back up.
    ``shaped``: :func:`shaped_hand` of these curls, made once for any number of poses."""
    local = shaped_hand(device, curls, left=left) if shaped is None else shaped
    orientation = quat_multiply(np.asarray(view, dtype=float), HAND_IN_VIEW)
    return replace(in_frame(local, np.asarray(position, dtype=float), orientation),
                   device=device, timestamp=timestamp)


def shaped_hand(device: str, curls: dict[str, float], *, left: bool) -> HandJoints:
    """A hand of these curls in its own frame, moved so that its palm joint is at the
    origin (what :func:`emulated_hand` turns and places)."""
    palm = _PALM * (1.0, -1.0, 1.0) if left else _PALM
    return pose_hand(device, -palm, (1.0, 0.0, 0.0, 0.0), curls, left=left)
