"""Lab Streaming Layer (pylsl): the streams rehabilitation and neuroscience labs already use.

``Device { Kind "lsl" Streams ["hand_r" "type:Wheel"] }`` opens an inlet for every
stream of that name (or, with ``type:``, that type), resolving in the background, so a
stream that starts later (or restarts) is picked up. What a sample means follows
the stream's type:

- ``Mocap`` or ``Pose`` with 7 channels ``x y z qw qx qy qz``: a TrackerPose named
  after the stream;
- ``Wheel`` or ``Counter`` with 1 channel: a WheelCount named after the stream;
- ``Hand`` with 208 channels, 26 joints × ``x y z qw qx qy qz radius`` in the engine's
  frame (:data:`~services.input.events.HAND_JOINTS` order): a HandJoints named after the
  stream;
- ``Buttons``: one channel per button (0/1, labelled in the stream's
  ``channels/channel/label`` description, else numbered); a Button on each change;
- anything else: an Axis per channel.

Sample times are LSL's, clock-synchronised and moved onto the engine's monotonic clock.
``Scope`` sets how far discovery reaches (``machine`` keeps it on this computer); the
first LSL device or output of a process decides it for the whole process.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from types import ModuleType
from typing import Any

from services.input.device import (
    MONOTONIC,
    BadMessage,
    Clock,
    DeviceError,
    QueuedDevice,
    button_state,
    hand_from_values,
    make_pose,
    numbers,
    whole_count,
)
from services.input.events import Axis, Button, WheelCount

log = logging.getLogger("colosseum.input")

INSTALL_HINT = ("install pylsl with its bundled liblsl (pip install pylsl), or the liblsl "
                "library of your system and set PYLSL_LIB to its path")
#: Seconds one background resolve of a stream waits before trying again.
RESOLVE_WAIT = 0.5
#: Seconds without finding a stream before saying so (once; the search goes on).
NOT_FOUND_AFTER = 5.0
#: Seconds a pull waits for a sample before checking whether the device is closing.
PULL_WAIT = 0.05
#: How far (s) a sample's time may lie ahead of the engine's clock (clock correction is
#: good to milliseconds), and behind it (an inlet buffers 360 s by default); an outlet
#: may stamp anything, NaN included, and the stamp is what wheel rates, filters and
#: the watchdog measure by.
MAX_AHEAD = 1.0
MAX_AGE = 360.0
POSE_TYPES = ("mocap", "pose")
WHEEL_TYPES = ("wheel", "counter")
HAND_TYPES = ("hand", "handjoints")

_config_lock = threading.Lock()
_configured_scope: list[str] = []


def load_pylsl(scope: str = "site") -> ModuleType:
    """pylsl with liblsl loaded; DeviceError with what to install when it cannot be.

    The first call sets the process's discovery scope (``machine``: this computer only).
    """
    try:
        import pylsl  # finds and loads liblsl as it is imported (RuntimeError without)

        pylsl.library_version()
    except ImportError as exc:
        raise DeviceError(f"lsl: pylsl is not installed; {INSTALL_HINT}") from exc
    except (RuntimeError, OSError, AttributeError) as exc:
        raise DeviceError(f"lsl: liblsl cannot be loaded ({exc}); {INSTALL_HINT}") from exc
    with _config_lock:
        if not _configured_scope:
            pylsl.set_config_content(lsl_config(scope))
            _configured_scope.append(scope)
        elif _configured_scope[0] != scope:
            log.warning("lsl: discovery scope %r asked, but this process already uses %r "
                        "(liblsl reads its configuration once)", scope, _configured_scope[0])
    return pylsl


def lsl_config(scope: str) -> str:
    """liblsl's configuration for a discovery scope (``machine`` keeps to 127.0.0.1)."""
    text = f"[multicast]\nResolveScope = {scope}\n[log]\nlevel = -2\n"
    if scope == "machine":
        text += "[ports]\nIPv6 = disable\n"
    return text


class LslDevice(QueuedDevice):
    """One inlet per named stream, each pulled on its own thread."""

    kind = "lsl"

    def __init__(self, name: str, streams: tuple[str, ...], scope: str = "site",
                 clock: Clock = MONOTONIC) -> None:
        self.streams = streams
        self.scope = scope
        self.clock = clock
        self._lsl: Any = None
        self._offset = 0.0
        super().__init__(name)

    def describe_name(self) -> str:
        return f"input device {self.name!r} (lsl, streams {', '.join(self.streams)})"

    def _open(self) -> None:
        if not self.streams:
            raise DeviceError(f"{self.describe_name()}: no Streams named (give stream names, "
                              "or \"type:TYPE\")")
        try:
            self._lsl = load_pylsl(self.scope)
        except DeviceError as exc:
            raise DeviceError(f"{self.describe_name()}: {exc}") from exc
        self._offset = self.clock() - self._lsl.local_clock()

    def _receivers(self) -> list[Callable[[], None]]:
        return [_StreamReader(self, stream).step for stream in self.streams]


class _StreamReader:
    """Resolves one stream, then pulls its samples; resolves again if it is closed."""

    def __init__(self, device: LslDevice, stream: str) -> None:
        self.device = device
        by_type = stream.startswith("type:")
        self.prop = "type" if by_type else "name"
        self.value = stream[len("type:"):] if by_type else stream
        self.source = stream
        self.correction = 0.0
        self.inlet: Any = None
        self.kind = ""
        self.labels: list[str] = []
        self.pressed: list[bool] = []
        self.searching_since: float | None = None
        self.told_missing = False

    def step(self) -> None:
        if self.inlet is None:
            self._resolve()
            return
        sample, stamp = self.inlet.pull_sample(timeout=PULL_WAIT)
        if sample is None:
            return
        device = self.device
        try:
            self._deliver(list(sample), self._time(stamp))
        except BadMessage as exc:
            device.bad.note(str(exc), (self.source, *sample))

    def _time(self, stamp: float) -> float:
        """A sample's LSL time on the engine's clock; BadMessage if it cannot be one."""
        device = self.device
        timestamp = stamp + self.correction + device._offset
        now = device.clock()
        if not (now - MAX_AGE <= timestamp <= now + MAX_AHEAD):  # NaN fails too
            raise BadMessage(f"stream {self.source!r}: sample time {stamp!r} is "
                             f"{'not finite' if not math.isfinite(timestamp) else 'not now'} "
                             f"(from {MAX_AGE:g} s ago to {MAX_AHEAD:g} s ahead)")
        return timestamp

    def _resolve(self) -> None:
        lsl = self.device._lsl
        if self.searching_since is None:
            self.searching_since = time.monotonic()
        found = lsl.resolve_byprop(self.prop, self.value, minimum=1, timeout=RESOLVE_WAIT)
        if not found:
            if not self.told_missing and \
                    time.monotonic() - self.searching_since >= NOT_FOUND_AFTER:
                self.told_missing = True
                log.warning("%s: no LSL stream with %s %r found in %g s; still looking (is "
                            "its outlet running, and within the device's Scope %r?)",
                            self.device.describe_name(), self.prop, self.value,
                            NOT_FOUND_AFTER, self.device.scope)
            return
        inlet = lsl.StreamInlet(found[0], recover=True)
        info = inlet.info(timeout=2.0)
        self.source = info.name()
        self.kind = info.type().lower()
        count = info.channel_count()
        self.labels = _labels(info, count)
        self.pressed = [False] * count
        self.correction = inlet.time_correction(timeout=2.0)
        self.inlet = inlet
        log.info("lsl: stream %r (%s, %d channels) connected", self.source, info.type(), count)

    def _deliver(self, sample: list[Any], timestamp: float) -> None:
        device, source = self.device, self.source
        values = numbers(sample, len(self.labels), f"stream {source!r}")
        if self.kind in POSE_TYPES:
            if len(values) != 7:
                raise BadMessage(f"pose stream {source!r} needs 7 channels x y z qw qx qy qz")
            device.push(make_pose(source, values, timestamp))
        elif self.kind in HAND_TYPES:
            device.push(hand_from_values(source, values, timestamp))
        elif self.kind in WHEEL_TYPES:
            device.push(WheelCount(source, whole_count(values[0], source), timestamp))
        elif self.kind == "buttons":
            for i, value in enumerate(values):
                pressed = button_state(value, f"{source}/{self.labels[i]}")
                if pressed != self.pressed[i]:
                    self.pressed[i] = pressed
                    device.push(Button(source, self.labels[i], pressed, timestamp))
        else:
            for label, value in zip(self.labels, values, strict=True):
                device.push(Axis(source, label, value, timestamp))


def _labels(info: Any, count: int) -> list[str]:
    """Channel labels from the stream's description, numbered where it gives none."""
    labels = []
    channel = info.desc().child("channels").child("channel")
    for i in range(count):
        label = channel.child_value("label") if not channel.empty() else ""
        labels.append(label or str(i))
        channel = channel.next_sibling() if not channel.empty() else channel
    return labels
