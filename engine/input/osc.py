"""OSC over UDP (python-osc): trackers, buttons, axes and wheel counters from any OSC sender.

Address space (one message each; bundles are unpacked)::

    /colosseum/tracker/<name>          x y z qw qx qy qz [vx vy vz]   m, unit quaternion, m/s
    /colosseum/button/<device>/<name>  0|1
    /colosseum/axis/<device>/<name>    value
    /colosseum/wheel/<name>            count                            cumulative encoder count

Phone apps, motion-capture bridges, Unity/Godot and Max/MSP can all send these. Packets
python-osc cannot parse, unknown addresses, wrong argument counts, NaN/inf and
quaternions far from unit length are counted and reported (:class:`BadMessages`), never
applied. See docs/input-format.md.
"""

from __future__ import annotations

import errno
import logging
import os
import socket
import struct

from pythonosc.osc_message import OscMessage
from pythonosc.osc_packet import OscPacket, ParseError

from engine.input.device import (
    MONOTONIC,
    BadMessage,
    Clock,
    DeviceError,
    QueuedDevice,
    button_state,
    make_pose,
    numbers,
    whole_count,
)
from engine.input.events import AnyInput, Axis, Button, WheelCount

PREFIX = "/colosseum/"
#: What python-osc raises for bytes that are no OSC packet (it does not wrap them all).
_GARBAGE = (ParseError, ValueError, IndexError, TypeError, OverflowError, struct.error)
#: Seconds a receive waits before checking whether the device is closing.
RECEIVE_TIMEOUT = 0.05


class _QuietOsc(logging.Filter):
    """python-osc logs each part of a packet it skips on the root logger (one line per
    packet, at 240 Hz); the device reports bad packets itself, a few seconds apart."""

    def filter(self, record: logging.LogRecord) -> bool:
        return f"{os.sep}pythonosc{os.sep}" not in record.pathname


_QUIET = _QuietOsc()


def osc_event(address: str, args: list[object], timestamp: float) -> AnyInput:
    """The typed event of one OSC message; BadMessage says what is wrong with it.

    >>> osc_event("/colosseum/wheel/left", [1024], 2.0)
    WheelCount(device='left', count=1024, timestamp=2.0)
    >>> osc_event("/colosseum/button/glove_r/index", [1], 2.0).pressed
    True
    """
    if not address.startswith(PREFIX):
        raise BadMessage(f"address {address!r} is not under {PREFIX}")
    parts = address[len(PREFIX):].split("/")
    kind, names = parts[0], parts[1:]
    if kind == "tracker" and len(names) == 1 and names[0]:
        if len(args) == 10:
            v = numbers(args, 10, address)
            return make_pose(names[0], v[:7], timestamp, v[7:])
        return make_pose(names[0], numbers(args, 7, address), timestamp)
    if kind == "wheel" and len(names) == 1 and names[0]:
        return WheelCount(names[0], whole_count(numbers(args, 1, address)[0], address),
                          timestamp)
    if kind in ("button", "axis") and len(names) == 2 and all(names):
        value = numbers(args, 1, address)[0]
        if kind == "button":
            return Button(names[0], names[1], button_state(value, address), timestamp)
        return Axis(names[0], names[1], value, timestamp)
    raise BadMessage(f"unknown address {address!r} (expected {PREFIX}tracker/NAME, "
                     f"wheel/NAME, button/DEVICE/NAME or axis/DEVICE/NAME)")


class OscDevice(QueuedDevice):
    """Listens on a UDP port for the /colosseum/... address space."""

    kind = "osc"

    def __init__(self, name: str = "osc", port: int = 9000, address: str = "127.0.0.1",
                 clock: Clock = MONOTONIC) -> None:
        self.port = port
        self.address = address
        self.clock = clock
        self._socket: socket.socket | None = None
        super().__init__(name)

    def describe_name(self) -> str:
        return f"input device {self.name!r} (osc, UDP {self.address}:{self.port})"

    def _open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.bind((self.address, self.port))
        except OSError as exc:
            sock.close()
            if exc.errno == errno.EADDRINUSE:
                raise DeviceError(
                    f"{self.describe_name()}: UDP port {self.port} is already in use (another "
                    f"program, or another Device with Port {self.port}); choose another Port "
                    f"or --input osc:PORT") from exc
            raise DeviceError(f"{self.describe_name()}: cannot listen: {exc}") from exc
        sock.settimeout(RECEIVE_TIMEOUT)
        logging.getLogger().addFilter(_QUIET)  # once: a filter is kept only once
        self.port = sock.getsockname()[1]  # the port the system chose for Port 0
        self.bad.device = self.describe_name()
        self._socket = sock

    def _receive(self) -> None:
        assert self._socket is not None
        try:
            data = self._socket.recv(65536)
        except TimeoutError:
            return
        now = self.clock()
        try:
            packet = OscPacket(data)
        except _GARBAGE as exc:
            self.bad.note(f"not an OSC packet ({exc})", data[:40])
            return
        if not packet.messages:
            self.bad.note("an OSC bundle without a message python-osc can read", data[:40])
        for timed in packet.messages:
            message: OscMessage = timed.message
            try:
                self.push(osc_event(message.address, list(message.params), now))
            except BadMessage as exc:
                self.bad.note(str(exc), (message.address, *message.params))

    def _close(self) -> None:
        if self._socket is not None:
            self._socket.close()
            self._socket = None
