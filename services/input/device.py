"""The InputDevice protocol, and the parts every device shares.

A device is opened once, polled once per frame on the main thread, and closed at the
end. Devices on a transport (a UDP port, a serial line, an LSL inlet) receive on an I/O
thread of their own and hand typed events to :meth:`QueuedDevice.poll` through a deque,
so a frame never waits for a packet and a packet never waits for a frame.

Bad input never raises out of a device: a message that cannot be read (malformed, the
wrong number of arguments, NaN or inf, a quaternion far from unit length) raises
:class:`BadMessage` inside the device, is counted, and is reported once per device
every few seconds with one example (:class:`BadMessages`).
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from services.input.events import HAND_JOINTS, AnyInput, HandJoints, TrackerPose

log = logging.getLogger("colosseum.input")

#: Where devices read the time (injectable for tests); monotonic seconds.
Clock = Callable[[], float]
MONOTONIC: Clock = time.monotonic
#: Seconds between two reports of a device's bad messages.
REPORT_EVERY = 3.0
#: Seconds an open device may stay silent before it is told (once): a sender pointed at
#: the wrong port or address, a serial line at the wrong baud rate.
SILENT_AFTER = 10.0
#: How far from 1 a quaternion's length may be and still be normalised (else it is bad).
QUAT_TOLERANCE = 0.01
#: Largest position or velocity component a device may send, in its own units: the
#: world's edge (1e6 m) in millimetres. Finite but larger values (an OSC double of 1e308)
#: overflowed the one-euro filter to inf and then NaN, for good.
MAX_COORDINATE = 1e9


class DeviceError(Exception):
    """A device cannot open; the message names the device and what to do about it."""


class BadMessage(ValueError):
    """One message a device could not use; the text says why."""


@dataclass(slots=True)
class DeviceStatus:
    """What a device is doing, for ``--stats`` and the log."""

    name: str
    kind: str
    state: str  # "closed" | "open" | "failed"
    detail: str = ""
    received: int = 0
    bad: int = 0


@runtime_checkable
class InputDevice(Protocol):
    """An input device: a transport that produces typed events."""

    name: str
    kind: str

    def open(self) -> None:
        """Start receiving; raises DeviceError with a clear message when it cannot."""

    def poll(self, now: float) -> list[AnyInput]:
        """Everything received since the last poll (main thread, once per frame)."""

    def close(self) -> None:
        """Stop receiving and release the transport; safe to call twice."""

    def status(self) -> DeviceStatus: ...


class BadMessages:
    """Counts a device's bad messages and reports them at most every ``every`` seconds."""

    def __init__(self, device: str, every: float = REPORT_EVERY) -> None:
        self.device = device
        self.every = every
        self.total = 0
        self._pending = 0
        self._example = ""
        self._last_report = -math.inf
        self._lock = threading.Lock()

    def note(self, reason: str, message: object) -> None:
        """Count one bad message (any thread); the first since the last report is the example."""
        with self._lock:
            self.total += 1
            self._pending += 1
            if self._pending == 1:
                text = repr(message)
                self._example = f"{reason}: {text[:120]}{'...' if len(text) > 120 else ''}"

    def report(self, now: float, final: bool = False) -> str | None:
        """Log (and return) the summary when there is news and the last one is old enough
        (or this is the ``final`` one, when the device closes)."""
        with self._lock:
            if not self._pending or (now - self._last_report < self.every and not final):
                return None
            count, example = self._pending, self._example
            self._pending = 0
            self._last_report = now
        text = (f"{self.device}: {count} bad message{'s' if count != 1 else ''} ignored, "
                f"e.g. {example}")
        log.warning("%s", text)
        return text


class PluginDevices(list):
    """Devices another plugin brings (the headset display's controllers), as a resource:
    the input system opens them beside the scene's."""


class QueuedDevice:
    """Base of devices with an I/O thread: the thread pushes events, the frame polls them.

    Subclasses implement :meth:`_open` (claim the transport, raise DeviceError) and
    :meth:`_receive` (one blocking read of at most ~0.1 s, pushing what it got), or
    :meth:`_receivers` for one thread per stream.
    """

    kind = "device"
    #: False for devices whose silence says nothing (a keyboard nobody types on).
    watched = True

    def __init__(self, name: str) -> None:
        self.name = name
        self.bad = BadMessages(self.describe_name())
        self.received = 0
        self._queue: deque[AnyInput] = deque()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._state = "closed"
        self._detail = ""
        #: Whether a silence since opening is still to be told; from the first poll's time.
        self._silence_watch = False
        self._silent_since: float | None = None

    def describe_name(self) -> str:
        return f"input device {self.name!r} ({self.kind})"

    # -- the I/O thread's side ---------------------------------------------------
    def push(self, event: AnyInput) -> None:
        self.received += 1
        self._queue.append(event)

    def _loop(self, receive: Callable[[], None]) -> None:
        while not self._stop.is_set():
            try:
                receive()
            except Exception as exc:  # a transport error ends this device, not the run
                if self._stop.is_set():
                    return
                self._state, self._detail = "failed", f"{type(exc).__name__}: {exc}"
                log.error("%s stopped receiving: %s", self.describe_name(), self._detail)
                return

    # -- the main thread's side ----------------------------------------------------
    def open(self) -> None:
        self._open()
        self._state = "open"
        self._silence_watch, self._silent_since = True, None
        self._threads = [threading.Thread(target=self._loop, args=(receive,), daemon=True,
                                          name=f"input-{self.name}")
                         for receive in self._receivers()]
        for thread in self._threads:
            thread.start()

    def poll(self, now: float) -> list[AnyInput]:
        queue = self._queue
        out = [queue.popleft() for _ in range(len(queue))]
        self.bad.report(now)
        if self._silence_watch:
            self._check_silence(now)
        return out

    def _check_silence(self, now: float) -> None:
        if self.received or self.bad.total or not self.watched:
            self._silence_watch = False
        elif self._silent_since is None:
            self._silent_since = now
        elif now - self._silent_since >= SILENT_AFTER:
            self._silence_watch = False
            log.warning("%s: nothing received in %g s since it opened%s", self.describe_name(),
                        SILENT_AFTER, self.silence_hint())

    def silence_hint(self) -> str:
        """What to check when nothing arrives (``; ...``), per transport."""
        return ""

    def close(self) -> None:
        self._stop.set()
        for thread in self._threads:
            thread.join(timeout=2.0)
        self._threads = []
        self._close()
        self.bad.report(0.0, final=True)  # what came since the last report is told too
        if self._state == "open":
            self._state = "closed"

    def status(self) -> DeviceStatus:
        return DeviceStatus(self.name, self.kind, self._state, self._detail, self.received,
                            self.bad.total)

    @property
    def threads(self) -> list[threading.Thread]:
        """The I/O threads (a benchmark reads their CPU clocks)."""
        return list(self._threads)

    def _open(self) -> None:
        raise NotImplementedError

    def _receive(self) -> None:
        raise NotImplementedError

    def _receivers(self) -> list[Callable[[], None]]:
        return [self._receive]

    def _close(self) -> None:
        """Release the transport (after the thread stopped)."""


def numbers(args: Sequence[object], count: int, what: str) -> list[float]:
    """``count`` finite floats from a message's arguments, or BadMessage saying what is off."""
    if len(args) != count:
        raise BadMessage(f"{what} takes {count} number{'s' if count != 1 else ''}, "
                         f"got {len(args)}")
    out = []
    for a in args:
        if isinstance(a, bool) or not isinstance(a, (int, float)):
            raise BadMessage(f"{what}: {a!r} is not a number")
        f = float(a)
        if not math.isfinite(f):
            raise BadMessage(f"{what}: {f} is not finite")
        out.append(f)
    return out


def make_pose(device: str, values: Sequence[float], timestamp: float,
              velocity: Sequence[float] | None = None) -> TrackerPose:
    """A TrackerPose from ``x y z qw qx qy qz`` (finite floats); the quaternion is
    normalised when within QUAT_TOLERANCE of unit length, else BadMessage, as is a
    position or velocity component beyond ±MAX_COORDINATE."""
    x, y, z, qw, qx, qy, qz = values
    for what, vector in (("position", (x, y, z)), ("velocity", velocity or ())):
        if any(abs(v) > MAX_COORDINATE for v in vector):
            raise BadMessage(f"tracker {device!r}: {what} {tuple(vector)} is beyond "
                             f"±{MAX_COORDINATE:g}")
    norm = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    if abs(norm - 1.0) > QUAT_TOLERANCE:
        raise BadMessage(f"tracker {device!r}: quaternion length {norm:.4g} is not 1")
    if abs(norm - 1.0) > 1e-12:  # so normalising twice (a replay) changes no bit
        qw, qx, qy, qz = qw / norm, qx / norm, qy / norm, qz / norm
    vel = None if velocity is None else (float(velocity[0]), float(velocity[1]),
                                         float(velocity[2]))
    return TrackerPose(device, (x, y, z), (qw, qx, qy, qz), vel, timestamp)


def button_state(value: float, what: str) -> bool:
    """A 0/1 argument as pressed; anything else is BadMessage."""
    if value not in (0.0, 1.0):
        raise BadMessage(f"{what}: {value:g} is not 0 or 1")
    return value == 1.0


def whole_count(value: float, what: str) -> int:
    if not float(value).is_integer():
        raise BadMessage(f"{what}: count {value:g} is not a whole number")
    return int(value)



#: Numbers per joint in a flat hand message (OSC, LSL): x y z qw qx qy qz radius.
JOINT_VALUES = 8
#: Numbers in a flat hand message: 26 joints of JOINT_VALUES.
HAND_VALUES = len(HAND_JOINTS) * JOINT_VALUES


def _unit(device: str, what: str, q: Sequence[float]) -> tuple[float, float, float, float]:
    """``q`` normalised as :func:`make_pose` does (BadMessage when far from unit length)."""
    qw, qx, qy, qz = (float(v) for v in q)
    norm = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    if not abs(norm - 1.0) <= QUAT_TOLERANCE:  # NaN fails too
        raise BadMessage(f"hand {device!r}: {what} quaternion length {norm:.4g} is not 1")
    if abs(norm - 1.0) > 1e-12:  # so normalising twice (a replay) changes no bit
        qw, qx, qy, qz = qw / norm, qx / norm, qy / norm, qz / norm
    return (qw, qx, qy, qz)


def make_hand(device: str, positions: Sequence[Sequence[float]],
              orientations: Sequence[Sequence[float]], radii: Sequence[float],
              valid: Sequence[bool], timestamp: float) -> HandJoints:
    """A HandJoints of 26 joints, each checked as a tracker's pose is (finite, within
    ±MAX_COORDINATE, a quaternion of unit length, normalised) and a radius from 0 to
    MAX_COORDINATE; BadMessage names the hand and the first joint that is wrong."""
    for what, items, size in (("positions", positions, 3), ("orientations", orientations, 4)):
        if len(items) != len(HAND_JOINTS) or any(len(v) != size for v in items):
            raise BadMessage(f"hand {device!r}: {len(HAND_JOINTS)} {what} of {size} numbers "
                             "each needed")
    if len(radii) != len(HAND_JOINTS) or len(valid) != len(HAND_JOINTS):
        raise BadMessage(f"hand {device!r}: {len(HAND_JOINTS)} radii and validity flags needed")
    out_p, out_q = [], []
    for joint, p, q, r in zip(HAND_JOINTS, positions, orientations, radii, strict=True):
        x, y, z = (float(v) for v in p)
        if not all(abs(v) <= MAX_COORDINATE for v in (x, y, z)):  # NaN fails too
            raise BadMessage(f"hand {device!r}: {joint} position {(x, y, z)} is not finite "
                             f"or beyond ±{MAX_COORDINATE:g}")
        if not 0.0 <= float(r) <= MAX_COORDINATE:
            raise BadMessage(f"hand {device!r}: {joint} radius {float(r)!r} is not from 0 "
                             f"to {MAX_COORDINATE:g}")
        out_p.append((x, y, z))
        out_q.append(_unit(device, joint, q))
    return HandJoints(device, tuple(out_p), tuple(out_q), tuple(float(r) for r in radii),
                      tuple(bool(v) for v in valid), timestamp)


def hand_from_values(device: str, values: Sequence[float], timestamp: float) -> HandJoints:
    """The hand of a flat message, 26 × (x y z qw qx qy qz radius) finite numbers (every
    joint valid); BadMessage says what is wrong."""
    count = HAND_VALUES
    if len(values) != count:
        raise BadMessage(f"hand {device!r} takes {count} numbers (26 joints x "
                         f"x y z qw qx qy qz radius), got {len(values)}")
    joints = [values[i:i + JOINT_VALUES] for i in range(0, count, JOINT_VALUES)]
    return make_hand(device, [j[0:3] for j in joints], [j[3:7] for j in joints],
                     [j[7] for j in joints], (True,) * len(HAND_JOINTS), timestamp)
