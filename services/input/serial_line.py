"""Serial lines (pyserial): wheel encoders, gloves or trackers that print one line per reading.

The line protocol is a template (``Device { Kind "serial" Line "{name} {count}" }``):
``{field}`` placeholders between literal text, whitespace matching any run of spaces
or tabs. A line must hold the fields of one event: ``{count}`` (a wheel), ``{button}
{pressed}``, ``{axis} {value}``, or ``{x} {y} {z} {qw} {qx} {qy} {qz}`` (a tracker);
``{name}`` names the source (default: the device's ID). A port that goes away (a USB
adapter unplugged) is reported and reopened every second until it is back.

>>> fmt = LineFormat("{name} {count}")
>>> fmt.event("left 1024", "wheels", 3.0)
WheelCount(device='left', count=1024, timestamp=3.0)
>>> LineFormat("glove {button} {pressed}").event("glove index 1", "glove_r", 3.0).name
'index'
"""

from __future__ import annotations

import logging
import math
import re

from engine.scene.inputs import LINE_EVENTS, line_fields
from services.input.device import (
    MONOTONIC,
    BadMessage,
    Clock,
    DeviceError,
    QueuedDevice,
    make_pose,
)
from services.input.events import AnyInput, Axis, Button, WheelCount

log = logging.getLogger("colosseum.input")

#: Longest line kept waiting for its newline (bytes); longer is garbage on the line.
MAX_LINE = 1024
#: Seconds between attempts to reopen a port that went away (a USB adapter unplugged).
REOPEN_EVERY = 1.0
_PATTERNS = {"name": r"\S+", "button": r"\S+", "axis": r"\S+", "count": r"[-+]?\d+",
             "pressed": r"[01]"}
_NUMBER = r"\S+"  # checked by float(), so "nan" and "1e999" are named in the report
_POSE = ("x", "y", "z", "qw", "qx", "qy", "qz")


class LineFormat:
    """A compiled line template."""

    def __init__(self, template: str) -> None:
        self.template = template
        self.fields = line_fields(template)  # ValueError names what is wrong
        #: The one event the fields make whole (others may be there, unused: a {value}
        #: beside a tracker's seven is read and ignored).
        self.kind = next(k for k, need in LINE_EVENTS.items() if set(need) <= set(self.fields))
        pattern = ""
        for i, part in enumerate(re.split(r"\{(\w+)\}", template)):
            if i % 2:  # a field's name
                pattern += f"(?P<{part}>{_PATTERNS.get(part, _NUMBER)})"
            else:  # literal text; any run of whitespace matches any other
                pattern += "".join(r"\s+" if w.isspace() else re.escape(w)
                                   for w in re.split(r"(\s+)", part) if w)
        self.regex = re.compile(pattern)

    def event(self, line: str, device: str, timestamp: float) -> AnyInput:
        """The event of one line (without its newline); BadMessage if it does not fit."""
        found = self.regex.fullmatch(line.strip())
        if found is None:
            raise BadMessage(f"line does not match {self.template!r}")
        values = found.groupdict()
        source = values.get("name") or device
        if self.kind == "wheel":
            return WheelCount(source, int(values["count"]), timestamp)
        if self.kind == "button":
            return Button(source, values["button"], values["pressed"] == "1", timestamp)
        if self.kind == "axis":
            return Axis(source, values["axis"], _finite(values["value"]), timestamp)
        return make_pose(source, [_finite(values[k]) for k in _POSE], timestamp)


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise BadMessage(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise BadMessage(f"{text} is not finite")
    return value


class SerialDevice(QueuedDevice):
    """Reads lines from a serial port on its own thread."""

    kind = "serial"

    def __init__(self, name: str, path: str, baud: int = 115200,
                 line: str = "{name} {count}", clock: Clock = MONOTONIC) -> None:
        self.path = path
        self.baud = baud
        self.format = LineFormat(line)
        self.clock = clock
        self._port = None
        self._buffer = b""
        self._overlong = False
        super().__init__(name)

    def describe_name(self) -> str:
        return f"input device {self.name!r} (serial, {self.path})"

    def silence_hint(self) -> str:
        return f" (is the device on, and sending at Baud {self.baud}?)"

    def _open(self) -> None:
        import serial

        try:
            self._port = serial.Serial(self.path, self.baud, timeout=0.05, exclusive=True)
        except (serial.SerialException, ValueError, OSError) as exc:
            busy = "lock" in str(exc).lower() or "busy" in str(exc).lower()
            reason = ("the port is already in use by another program or Device" if busy
                      else str(exc))
            raise DeviceError(f"{self.describe_name()}: cannot open serial port {self.path}: "
                              f"{reason}") from exc

    def _receive(self) -> None:
        import serial

        port = self._port
        if port is None:  # unplugged: try again, as a USB adapter comes back
            self._reopen()
            return
        try:
            data = port.read(max(1, port.in_waiting))
        except (serial.SerialException, OSError) as exc:
            port.close()
            self._port = None
            self._detail = f"port lost ({exc}); reopening it every {REOPEN_EVERY:g} s"
            log.error("%s: %s", self.describe_name(), self._detail)
            return
        if data:
            self.take(data, self.clock())

    def _reopen(self) -> None:
        if self._stop.wait(REOPEN_EVERY):
            return
        try:
            self._open()
        except DeviceError:
            return
        self._buffer, self._overlong, self._detail = b"", False, ""
        log.info("%s: port reopened", self.describe_name())

    def take(self, data: bytes, now: float) -> None:
        """Bytes read from the port: each whole line pushed as an event (or counted as
        bad), the rest kept for the next read."""
        *lines, self._buffer = (self._buffer + data).split(b"\n")
        if self._overlong and lines:  # the rest of a line already reported as too long
            self._overlong = False
            lines.pop(0)
        if len(self._buffer) > MAX_LINE:  # one bad line however many reads it spans
            if not self._overlong:
                self.bad.note(f"no newline in {MAX_LINE} bytes", self._buffer[:40])
            self._buffer, self._overlong = b"", True
        for raw in lines:
            if not raw.strip():
                continue
            try:
                text = raw.decode("ascii")
            except UnicodeDecodeError:
                self.bad.note("not a text line", raw[:40])
                continue
            try:
                self.push(self.format.event(text, self.name, now))
            except BadMessage as exc:
                self.bad.note(str(exc), text)

    def _close(self) -> None:
        if self._port is not None:
            self._port.close()
            self._port = None
