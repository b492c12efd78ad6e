"""Typed input events: what devices say, frozen, each with a monotonic timestamp.

``device`` is the *source* a value belongs to: a tracker's name (``hand_r``), a glove
(``glove_r``), a wheel counter (``left``), ``keyboard`` or ``mouse`` — not the transport
that carried it (one OSC port carries them all). ``timestamp`` is ``time.monotonic()``
seconds when the engine received it (replays keep the recorded ones). Vectors are
tuples, so an event can be logged, recorded and sent over a network as it is.

The same classes travel the event bus (subscribe to ``TrackerPose`` etc.) and the
recording format (:mod:`services.input.record`, ``TAGS``).
"""

from __future__ import annotations

from dataclasses import dataclass

from engine.events import KeyEvent

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]

#: A key on a keyboard (the window's, or any device's); ``KeyEvent`` keeps its old name.
Key = KeyEvent


@dataclass(frozen=True, slots=True)
class TrackerPose:
    """A 6-DOF pose: position (m), orientation ``(w, x, y, z)``, velocity (m/s) if known."""

    device: str
    position: Vec3
    orientation: Quat
    velocity: Vec3 | None = None
    timestamp: float = 0.0


@dataclass(frozen=True, slots=True)
class Button:
    """A button, switch or pinch contact went down or up."""

    device: str
    name: str
    pressed: bool
    timestamp: float = 0.0


@dataclass(frozen=True, slots=True)
class Axis:
    """A continuous value (a joystick axis, a slider, a trigger)."""

    device: str
    name: str
    value: float
    timestamp: float = 0.0


@dataclass(frozen=True, slots=True)
class WheelCount:
    """A wheel encoder's cumulative count (it may wrap; see ``Wheel { Wrap }``)."""

    device: str
    count: int
    timestamp: float = 0.0


@dataclass(frozen=True, slots=True)
class Pointer:
    """A pointer at ``(x, y)`` in window coordinates 0..1 (y down), ``scroll`` notches
    turned since the last Pointer."""

    device: str
    x: float
    y: float
    scroll: float = 0.0
    timestamp: float = 0.0


#: The 26 joints of a tracked hand, in OpenXR's order (``XR_EXT_hand_tracking``): palm,
#: wrist, four of the thumb, then five of each finger from metacarpal to tip.
HAND_JOINTS: tuple[str, ...] = (
    "palm", "wrist",
    "thumb_metacarpal", "thumb_proximal", "thumb_distal", "thumb_tip",
    *(f"{finger}_{bone}" for finger in ("index", "middle", "ring", "little")
      for bone in ("metacarpal", "proximal", "intermediate", "distal", "tip")),
)
#: The fingers, thumb first (a joint's name starts with its finger's).
FINGERS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "little")


@dataclass(frozen=True, slots=True)
class HandJoints:
    """A tracked hand's 26 joints (:data:`HAND_JOINTS` order), in engine coordinates:
    each a position (m), an orientation ``(w, x, y, z)`` and a radius (m); ``valid`` says
    which joints the tracker saw this time (an invalid joint's values are the last known)."""

    device: str
    positions: tuple[Vec3, ...]
    orientations: tuple[Quat, ...]
    radii: tuple[float, ...]
    valid: tuple[bool, ...]
    timestamp: float = 0.0


@dataclass(frozen=True, slots=True)
class DeviceLost:
    """A source sent nothing for its timeout: its trackers are untracked until it is found."""

    device: str
    timestamp: float = 0.0


@dataclass(frozen=True, slots=True)
class DeviceFound:
    """A source that was lost (or never heard from) sends again."""

    device: str
    timestamp: float = 0.0


#: Any typed input event.
AnyInput = TrackerPose | Button | Axis | WheelCount | KeyEvent | Pointer | DeviceLost | \
    DeviceFound | HandJoints

#: The recording format's ``type`` of each event class.
TAGS: dict[type, str] = {TrackerPose: "tracker", Button: "button", Axis: "axis",
                         WheelCount: "wheel", KeyEvent: "key", Pointer: "pointer",
                         DeviceLost: "lost", DeviceFound: "found",
                         HandJoints: "hand"}
