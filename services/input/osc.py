"""OSC over UDP (python-osc): trackers, buttons, axes and wheel counters from any OSC sender.

Address space (one message each; bundles are unpacked)::

    /colosseum/tracker/<name>          x y z qw qx qy qz [vx vy vz]   m, unit quaternion, m/s
    /colosseum/button/<device>/<name>  0|1
    /colosseum/axis/<device>/<name>    value
    /colosseum/wheel/<name>            count                            cumulative encoder count
    /colosseum/hand/<name>             26 x (x y z qw qx qy qz radius)  a hand's joints, m

Phone apps, motion-capture bridges, Unity/Godot and Max/MSP can all send these. Packets
python-osc cannot parse, unknown addresses, wrong argument counts, NaN/inf and
quaternions far from unit length are counted and reported (:class:`BadMessages`), never
applied. See docs/input-format.md.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import math
import os
import socket
import struct

from pythonosc.osc_message import OscMessage
from pythonosc.osc_packet import OscPacket

from services.input.device import (
    HAND_VALUES,
    MONOTONIC,
    REPORT_EVERY,
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
from services.input.events import AnyInput, Axis, Button, WheelCount

log = logging.getLogger("colosseum.input")

PREFIX = "/colosseum/"
#: Seconds a receive waits before checking whether the device is closing.
RECEIVE_TIMEOUT = 0.05
#: Receive buffer asked of the system (bytes; Linux grants up to net.core.rmem_max, and
#: doubles it). The default 208 kB holds about 256 datagrams: 0.2 s of 240 Hz x 5
#: streams, less than one slow frame holding the interpreter.
RECEIVE_BUFFER = 4 << 20
#: Bundles nested deeper than this are refused unread: python-osc unpacks them
#: recursively (600 levels, one 12 kB datagram, raised RecursionError on the device's
#: thread, or not, as the process's recursion limit happened to be set).
MAX_BUNDLE_DEPTH = 16
#: Linux's socket option that stamps each datagram with the socket's count of datagrams
#: dropped so far (a full buffer); the socket module does not name it.
SO_RXQ_OVFL = 40


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
    if kind == "hand" and len(names) == 1 and names[0]:
        return hand_from_values(names[0], numbers(args, HAND_VALUES, f"{address} (26 joints x "
                                                   "x y z qw qx qy qz radius)"), timestamp)
    if kind == "wheel" and len(names) == 1 and names[0]:
        return WheelCount(names[0], whole_count(numbers(args, 1, address)[0], address),
                          timestamp)
    if kind in ("button", "axis") and len(names) == 2 and all(names):
        value = numbers(args, 1, address)[0]
        if kind == "button":
            return Button(names[0], names[1], button_state(value, address), timestamp)
        return Axis(names[0], names[1], value, timestamp)
    raise BadMessage(f"unknown address {address!r} (expected {PREFIX}tracker/NAME, "
                     f"wheel/NAME, hand/NAME, button/DEVICE/NAME or axis/DEVICE/NAME)")


class OscDevice(QueuedDevice):
    """Listens on a UDP port for the /colosseum/... address space."""

    kind = "osc"

    def __init__(self, name: str = "osc", port: int = 9000, address: str = "127.0.0.1",
                 clock: Clock = MONOTONIC) -> None:
        self.port = port
        self.address = address
        self.clock = clock
        self._socket: socket.socket | None = None
        #: Datagrams the system dropped before they were read, and how many were told.
        self.dropped = 0
        self._dropped_told = 0
        self._dropped_at = -math.inf
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
        with contextlib.suppress(OSError):  # best effort: a smaller buffer still works
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER)
        with contextlib.suppress(OSError):  # Linux only: elsewhere drops go uncounted
            sock.setsockopt(socket.SOL_SOCKET, SO_RXQ_OVFL, 1)
        logging.getLogger().addFilter(_QUIET)  # once: a filter is kept only once
        self.port = sock.getsockname()[1]  # the port the system chose for Port 0
        self.bad.device = self.describe_name()
        self._socket = sock

    def silence_hint(self) -> str:
        if self.address.startswith("127."):
            return (f" (it listens on {self.address} only: a sender on another machine needs "
                    f"Address \"0.0.0.0\", or --input osc:0.0.0.0:{self.port})")
        return f" (is the sender sending to UDP port {self.port} of this machine?)"

    def _receive(self) -> None:
        assert self._socket is not None
        try:
            data, ancillary, _, _ = self._socket.recvmsg(65536, socket.CMSG_SPACE(4))
        except TimeoutError:
            return
        for level, kind, payload in ancillary:
            if level == socket.SOL_SOCKET and kind == SO_RXQ_OVFL and len(payload) >= 4:
                self.dropped = struct.unpack("=I", payload[:4])[0]
        self.take(data, self.clock())

    def poll(self, now: float) -> list[AnyInput]:
        self._tell_dropped(now)
        return super().poll(now)

    def _tell_dropped(self, now: float, final: bool = False) -> None:
        """Datagrams lost in the system, told as bad messages are: every few seconds."""
        dropped = self.dropped
        if dropped == self._dropped_told or (now - self._dropped_at < REPORT_EVERY
                                             and not final):
            return
        log.warning("%s: %d datagram%s dropped by the system before they were read (the "
                    "receive buffer was full: the engine fell behind the sender)",
                    self.describe_name(), dropped - self._dropped_told,
                    "s" * (dropped - self._dropped_told != 1))
        self._dropped_told, self._dropped_at = dropped, now
        self._detail = f"{dropped} datagrams dropped by the system"

    def take(self, data: bytes, now: float) -> None:
        """One datagram: its messages pushed as events, anything wrong counted as bad."""
        if _bundles_deeper_than(data, MAX_BUNDLE_DEPTH):
            self.bad.note(f"OSC bundles nested deeper than {MAX_BUNDLE_DEPTH} levels",
                          data[:40])
            return
        try:
            packet = OscPacket(data)
        except Exception as exc:  # hostile bytes in a third-party parser:
            # python-osc raises ParseError, struct.error, IndexError...; none may end the
            # device's thread
            self.bad.note(f"not an OSC packet ({type(exc).__name__}: {exc})", data[:40])
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
        self._tell_dropped(0.0, final=True)


def _bundles_deeper_than(data: bytes, limit: int) -> bool:
    """Whether the datagram's bundles nest deeper than ``limit``: one pass over the
    element sizes, without parsing anything."""
    pending = [(0, len(data), 1)]  # (start, end, depth) of each bundle still to read
    while pending:
        start, end, depth = pending.pop()
        if not data.startswith(b"#bundle\x00", start):
            continue
        if depth > limit:
            return True
        at = start + 16  # "#bundle\0" and the time tag
        while at + 4 <= end:
            size = int.from_bytes(data[at:at + 4], "big", signed=True)
            if size <= 0 or at + 4 + size > end:
                break
            pending.append((at + 4, at + 4 + size, depth + 1))
            at += 4 + size
    return False
