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
- Tab (or 1 and 2) switches which hand the mouse drives.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from engine.rotation import quat_to_matrix
from engine.scene.inputs import DESKTOP_GLOVES, DESKTOP_TRACKERS
from services.input.device import MONOTONIC, Clock, DeviceStatus, QueuedDevice
from services.input.events import AnyInput, Button, KeyEvent, Pointer, TrackerPose, WheelCount

HANDS, GLOVES = DESKTOP_TRACKERS, DESKTOP_GLOVES
WHEELS = ("left", "right")
#: Metres the hand moves in depth per scroll notch, and the depth's bounds.
DEPTH_STEP = 0.05
DEPTH_RANGE = (0.1, 3.0)
#: Keys -> (left wheel, right wheel) direction while held.
WHEEL_KEYS = {"w": (1.0, 1.0), "s": (-1.0, -1.0), "a": (-1.0, 1.0), "d": (1.0, -1.0)}
HAND_KEYS = {"1": 0, "number_1": 0, "2": 1, "number_2": 1}


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


class DesktopDevice:
    """Emulates two tracked hands with pinch gloves and two wheel counters."""

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

    def open(self) -> None:
        self.window.open()

    def close(self) -> None:
        self.window.close()

    def status(self) -> DeviceStatus:
        inner = self.window.status()
        return DeviceStatus(self.name, self.kind, inner.state, "emulating hands and wheels",
                            inner.received + self.emulated, inner.bad)

    def poll(self, now: float) -> list[AnyInput]:
        out: list[AnyInput] = []
        for event in self.window.poll(now):
            out.append(event)
            made = self._emulate(event)
            if made is not None:
                out.append(made)
        out += self._turn_wheels(now)
        self.emulated += len(out)
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
            return None
        if isinstance(event, Pointer):
            lo, hi = DEPTH_RANGE
            self.depth = min(max(self.depth + event.scroll * DEPTH_STEP, lo), hi)
            p = self.view.point(event.x, event.y, self.depth)
            q = self.view.orientation
            return TrackerPose(HANDS[self.hand], (float(p[0]), float(p[1]), float(p[2])),
                               (float(q[0]), float(q[1]), float(q[2]), float(q[3])), None,
                               event.timestamp)
        if isinstance(event, Button) and event.device == "mouse" and event.name == "left":
            return Button(GLOVES[self.hand], "pinch", event.pressed, event.timestamp)
        return None

    def _turn_wheels(self, now: float) -> list[AnyInput]:
        # A clock set back (a replay's, a test's switched to simulated time) turns nothing:
        # a negative interval would wind the counters back by however far it jumped.
        dt = 0.0 if self._last_poll is None else max(now - self._last_poll, 0.0)
        self._last_poll = now
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
