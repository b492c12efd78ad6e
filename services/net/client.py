"""A node's sockets: joining a server, following its frames, sending input.

:meth:`NetClient.join` says hello and returns the server's welcome (with the full state
a node builds its world from), or raises :class:`NetError` with what went wrong — no
server there, a key it refuses, other content, a user name taken. Then, each frame,
:meth:`receive` drains the frames that arrived (never waiting) and :meth:`send` sends
the node's input and heartbeat.

The node notices a server that stopped (nothing for ``timeout`` seconds: :attr:`silent`)
and one that restarted (another epoch in a frame): the caller then asks :meth:`rejoin`,
which says hello again and returns the new full state.
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Callable
from typing import Any

import zmq
from zmq.utils.monitor import recv_monitor_message

from services.net import protocol
from services.net.keys import ClientKeys
from services.net.protocol import MessageError
from services.net.server import NetError

log = logging.getLogger("colosseum.net")

#: Frames a node queues before ZeroMQ drops new ones (it reads every frame, so only a
#: node that stalls for about a second loses any).
STATE_QUEUE = 64
#: Seconds between heartbeats.
BEAT = 0.25
#: Connections the server may close in the handshake before a node without keys gives up.
CUT_OFF = 3

_HANDSHAKE_FAILED = {
    getattr(zmq, "EVENT_HANDSHAKE_FAILED_NO_DETAIL", 0x0800): "the encryption handshake "
    "failed",
    getattr(zmq, "EVENT_HANDSHAKE_FAILED_PROTOCOL", 0x2000): "the server speaks another "
    "security mechanism (it was started with --key, or this node was and it was not)",
    getattr(zmq, "EVENT_HANDSHAKE_FAILED_AUTH", 0x4000): "the server refused this node's key "
    "(its public key is not among the server's users)",
}


class NetClient:
    """The SUB and DEALER sockets of ``colosseum join``."""

    def __init__(self, address: str, user: str, content: str, display: str | None = None,
                 keys: ClientKeys | None = None, timeout: float = 2.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.address = address
        self.user = user
        self.content = content
        self.display = display
        self.keys = keys
        self.timeout = timeout
        self.clock = clock
        self.epoch: str | None = None
        self.frames = 0
        self.bytes = 0
        self.malformed = 0
        self._heard = clock()
        self._beat = 0.0
        self._held: list[list[bytes]] = []
        #: The swap barrier's rounds this display has waited in.
        self._round = 0
        self._ctx = zmq.Context()
        self._sub: zmq.Socket | None = None
        self._dealer: zmq.Socket | None = None
        self._monitor: zmq.Socket | None = None

    def _connect(self) -> None:
        self._close_sockets()
        state_at, control_at = protocol.endpoints(self.address)
        self._sub = self._socket(zmq.SUB, state_at, queue=STATE_QUEUE)
        self._sub.setsockopt(zmq.SUBSCRIBE, b"")
        self._dealer = self._socket(zmq.DEALER, control_at, monitored=True)

    def _socket(self, kind: int, endpoint: str, monitored: bool = False,
                queue: int | None = None) -> zmq.Socket:
        """A socket connected to ``endpoint``; ``queue``: messages it queues (set before
        the connect, which takes the options as they are then)."""
        sock = self._ctx.socket(kind)
        sock.linger = 0
        if queue is not None:
            sock.rcvhwm = queue
        if self.keys is not None:
            sock.curve_secretkey = self.keys.secret
            sock.curve_publickey = self.keys.public
            sock.curve_serverkey = self.keys.server
        if monitored:  # before connecting: a refused handshake is told once, at once
            self._monitor = sock.get_monitor_socket()
        sock.connect(endpoint)
        return sock

    # -- joining ------------------------------------------------------------------
    def join(self, wait: float = 5.0) -> dict[str, Any]:
        """Say hello; the server's welcome (``epoch``, ``text``, ``names``, ``frame``,
        ``time``, ``dt``). Raises NetError when refused or when nothing answers."""
        if self._dealer is None:
            self._connect()
        assert self._dealer is not None
        self._dealer.send(protocol.encode({
            "type": "hello", "v": protocol.VERSION, "user": self.user,
            "content": self.content, "display": self.display}))
        reply = self._await("welcome", wait)
        self.epoch = reply["epoch"]
        self._heard = self.clock()
        return reply

    def rejoin(self, wait: float = 5.0) -> dict[str, Any]:
        """Join again (the server restarted or forgot this node)."""
        log.info("rejoining %s", self.address)
        return self.join(wait)

    def request_state(self, wait: float = 5.0) -> dict[str, Any]:
        """The server's full state now (to resynchronise)."""
        self.send({"type": "state"})
        return self._await("state", wait)

    def _await(self, kind: str, wait: float) -> dict[str, Any]:
        assert self._dealer is not None and self._monitor is not None
        poller = zmq.Poller()
        poller.register(self._dealer, zmq.POLLIN)
        poller.register(self._monitor, zmq.POLLIN)
        end = self.clock() + wait
        cut_off = 0
        while (left := end - self.clock()) > 0:
            ready = dict(poller.poll(int(left * 1000) + 1))
            if self._monitor in ready:
                event = recv_monitor_message(self._monitor)
                problem = _HANDSHAKE_FAILED.get(event["event"])
                if event["event"] == zmq.EVENT_HANDSHAKE_FAILED_NO_DETAIL and self.keys is None:
                    # a connection closed while it was made is retried; a server that
                    # closes every one is CURVE's (libzmq tells the mismatch only now and
                    # then) or not ZeroMQ at all
                    cut_off += 1
                    problem = None if cut_off < CUT_OFF else (
                        f"the server closed {cut_off} connections in ZeroMQ's handshake: it "
                        "speaks another security mechanism (it was started with --key: join "
                        "with --key DIR), or it is not a colosseum server")
                if problem is not None:
                    raise NetError(f"cannot join {self.address}: {problem}")
            if self._dealer in ready:
                try:
                    reply = protocol.decode_json(self._dealer.recv())
                except MessageError as exc:
                    raise NetError(f"{self.address} answered something that is not this "
                                   f"protocol ({exc}); is it a colosseum server?") from None
                if reply.get("type") == "refused":
                    if kind == "welcome" and reply.get("rejoin"):
                        continue  # answers a message sent before this hello
                    raise NetError(f"{self.address} refused this node: {reply.get('reason')}",
                                   reply)
                if reply.get("type") == kind:
                    return reply
        secured = " or its key differs" if self.keys is not None else ""
        raise NetError(f"no answer from {self.address} within {wait:g} s: is `colosseum serve` "
                       f"running there (it also uses the next port){secured}?")

    # -- each frame ---------------------------------------------------------------
    def receive(self, limit: int = 1000) -> list[tuple[bytes, dict[str, Any], bytes | None]]:
        """The messages that arrived: (kind, header, poses or None), oldest first; a
        header that does not decode is counted (:attr:`malformed`) and skipped."""
        held, self._held = self._held, []
        out: list[tuple[bytes, dict[str, Any], bytes | None]] = []
        for frames in held:
            self._take(frames, out)
        sub = self._sub
        assert sub is not None
        for _ in range(limit):
            try:
                frames = sub.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                break
            self._take(frames, out)
        if out:
            self._heard = self.clock()
        return out

    def _take(self, frames: list[bytes], out: list[tuple[bytes, dict[str, Any],
                                                          bytes | None]]) -> None:
        self.bytes += sum(map(len, frames))
        kind = frames[0]
        try:
            if kind == protocol.STATE and len(frames) == 3:
                self.frames += 1
                out.append((kind, protocol.decode_json(frames[1]), frames[2]))
            elif kind == protocol.BARRIER and len(frames) == 2:
                out.append((kind, protocol.decode_json(frames[1]), None))
            else:
                self.malformed += 1
        except MessageError:
            self.malformed += 1

    def wait(self, timeout: float) -> bool:
        """Block until a message is there to :meth:`receive` (at most ``timeout`` s)."""
        assert self._sub is not None
        return bool(self._held) or bool(self._sub.poll(int(timeout * 1000)))

    def wait_barrier(self, oldest: int, newest: int, wait: float) -> int | None:
        """Tell the server this display is ready, holding frames ``oldest`` to
        ``newest``, and wait (at most ``wait`` s) for the frame every display is to
        draw; None when the wait ran out. A
        release of a round this display was not in (one it came too late for) is passed
        over. State messages arriving meanwhile are kept for the next :meth:`receive`."""
        self._round += 1
        self.send({"type": "ready", "frame": newest, "oldest": oldest, "round": self._round})
        assert self._sub is not None
        end = self.clock() + wait
        while (left := end - self.clock()) > 0:
            if not self._sub.poll(int(left * 1000) + 1):
                break
            frames = self._sub.recv_multipart()
            if frames[0] != protocol.BARRIER or len(frames) != 2:
                self._held.append(frames)
                continue
            try:
                release = protocol.decode_json(frames[1])
            except MessageError:
                continue
            rounds, released = release.get("rounds"), release.get("frame")
            if isinstance(rounds, dict) and rounds.get(self.user) == self._round and \
                    isinstance(released, int):
                return released
        return None

    def send(self, message: dict[str, Any]) -> None:
        assert self._dealer is not None
        with contextlib.suppress(zmq.Again):  # a server gone or slow: `silent` tells
            self._dealer.send(protocol.encode(message), zmq.NOBLOCK)
        self._beat = self.clock()

    def beat(self) -> None:
        """A heartbeat when nothing else was sent for a while."""
        if self.clock() - self._beat >= BEAT:
            self.send({"type": "beat"})

    def replies(self) -> list[dict[str, Any]]:
        """Replies that came in outside a request (a server that forgot this node)."""
        out = []
        assert self._dealer is not None
        while True:
            try:
                raw = self._dealer.recv(zmq.NOBLOCK)
            except zmq.Again:
                return out
            try:
                out.append(protocol.decode_json(raw))
            except MessageError:
                continue

    @property
    def silent(self) -> bool:
        """Nothing came from the server for ``timeout`` seconds."""
        return self.clock() - self._heard > self.timeout

    def close(self) -> None:
        if self._dealer is not None and self.epoch is not None:
            self._dealer.linger = 200  # long enough for the bye to leave
            self.send({"type": "bye"})
        self._close_sockets()
        self._ctx.term()

    def _close_sockets(self) -> None:
        if self._dealer is not None and self._monitor is not None:
            self._dealer.disable_monitor()
        for sock in (self._monitor, self._sub, self._dealer):
            if sock is not None:
                sock.close()
        self._dealer = self._sub = self._monitor = None
