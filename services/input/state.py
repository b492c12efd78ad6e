"""The latest-state table: what every input reads now, queryable by any system.

``engine.resource(InputState).tracker("hand_r")`` is the hand's calibrated pose (or
None before it was ever seen); ``.wheel("left").angular_velocity`` the wheel's rad/s
from counts and device timestamps; ``.button("glove_r", "index")``, ``.axis(...)``,
``.key("space")``. Controllers name inputs as strings — ``tracker:NAME``,
``wheel:NAME``, ``axis:DEVICE/NAME``, ``button:DEVICE/NAME`` (or ``button:ID`` of an
``Input { Button }``), ``key:A`` or ``key:UP/DOWN`` — which :func:`parse_binding`
checks once and :meth:`InputState.read` answers every frame.

>>> state = InputState()
>>> state.keys.add("up")
>>> state.read(parse_binding("key:Up/Down"))
1.0
>>> parse_binding("foo:bar")  # doctest: +ELLIPSIS
Traceback (most recent call last):
ValueError: unknown input 'foo:bar': use tracker:NAME, wheel:NAME, ...
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from services.input.events import HandJoints
from services.input.wheel import WheelRate

_KINDS = ("tracker:NAME, wheel:NAME, axis:DEVICE/NAME, button:DEVICE/NAME, button:ID, key:A "
          "or key:A/B")


@dataclass(slots=True)
class TrackerState:
    """A tracker's latest calibrated (and filtered, predicted) pose, in the scene frame."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    orientation: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    timestamp: float = 0.0
    #: False once its source is lost (DeviceLost), until it sends again.
    tracked: bool = True


@dataclass(slots=True)
class WheelState:
    """A wheel counter's latest count and its angular velocity at this frame."""

    rate: WheelRate
    count: int = 0
    angular_velocity: float = 0.0  # rad/s
    timestamp: float = 0.0

    @property
    def turns(self) -> float:
        return self.rate.turns


@dataclass(frozen=True, slots=True)
class Binding:
    """A parsed input name: ``kind`` and its parts (``key`` holds one or two key names)."""

    kind: str
    parts: tuple[str, ...]
    text: str


def parse_binding(text: str) -> Binding:
    """Check an input name once (ValueError says what is wrong and what is allowed)."""
    kind, _, rest = text.partition(":")
    parts = tuple(rest.split("/")) if rest else ()
    if kind in ("tracker", "wheel", "axis", "button") and len(parts) > 1 and all(parts):
        # a network user's source (services.net): tracker:alice/hand_r, axis:alice/pad/x
        keep = 1 if kind in ("tracker", "wheel") else 2
        parts = ("/".join(parts[:len(parts) - keep + 1]), *parts[len(parts) - keep + 1:])
    ok = {"tracker": (1,), "wheel": (1,), "axis": (2,), "button": (1, 2), "key": (1, 2)}
    if kind not in ok or len(parts) not in ok[kind] or not all(parts):
        raise ValueError(f"unknown input {text!r}: use {_KINDS}")
    if kind == "key":
        parts = tuple(p.lower() for p in parts)
    return Binding(kind, parts, text)


class InputState:
    """Latest value of every input, updated in the INPUT phase, read by everyone after it."""

    def __init__(self) -> None:
        self.trackers: dict[str, TrackerState] = {}
        self.wheels: dict[str, WheelState] = {}
        self.buttons: dict[tuple[str, str], bool] = {}
        self.axes: dict[tuple[str, str], float] = {}
        self.keys: set[str] = set()
        #: Each tracked hand's latest 26 joints (calibrated and filtered), by source name.
        self.hands: dict[str, HandJoints] = {}
        #: Pointer position (0..1, y down) per pointing device.
        self.pointers: dict[str, tuple[float, float]] = {}
        #: ``Input { Button { ID } }`` names -> (device, name).
        self.button_ids: dict[str, tuple[str, str]] = {}
        #: Sources lost and not yet found again.
        self.lost: set[str] = set()
        #: The input clock of this frame (monotonic seconds; recorded, so replays agree).
        self.now = 0.0

    def tracker(self, name: str) -> TrackerState | None:
        return self.trackers.get(name)

    def hand(self, name: str) -> HandJoints | None:
        """A hand's latest joints, or None before it was seen or while it is lost."""
        return None if name in self.lost else self.hands.get(name)

    def wheel(self, name: str) -> WheelState | None:
        return self.wheels.get(name)

    def button(self, device: str, name: str | None = None) -> bool:
        """``button("glove_r", "index")``, or ``button(ID)`` of a declared Button."""
        key = self.button_ids.get(device) if name is None else (device, name)
        return key is not None and self.buttons.get(key, False)

    def axis(self, device: str, name: str) -> float | None:
        return self.axes.get((device, name))

    def key(self, name: str) -> bool:
        return name.lower() in self.keys

    def read(self, binding: Binding) -> float | np.ndarray | None:
        """The value a controller reads: a number, a tracker's position, or None (not yet)."""
        kind, parts = binding.kind, binding.parts
        if kind == "key":
            if len(parts) == 1:
                return float(parts[0] in self.keys)
            return float(parts[0] in self.keys) - float(parts[1] in self.keys)
        if kind == "button":
            return float(self.button(*parts))
        if kind == "axis":
            return self.axes.get((parts[0], parts[1]))
        if kind == "wheel":
            wheel = self.wheels.get(parts[0])
            return None if wheel is None else wheel.angular_velocity
        tracker = self.trackers.get(parts[0])
        return None if tracker is None or not tracker.tracked else tracker.position
