"""The server's sockets: who is joined, what they ask, what goes out each frame.

:class:`NetServer` knows nothing of the engine. The server plugin (``systems/net.py``)
calls :meth:`NetServer.poll` once a frame — it answers hellos and state requests
itself (through :attr:`NetServer.full_state`, which the plugin provides), drops what
does not check out, and returns the joined nodes' input — and :meth:`publish` with the
frame's state.

Nothing a node does can stall the server: the state socket never blocks (a node that
reads too slowly loses frames at ZeroMQ's high-water mark, and counts them itself),
requests are drained at most :data:`MAX_REQUESTS` a frame, and a node not heard from for
``timeout`` seconds is let go (:attr:`NetServer.left`).
"""

from __future__ import annotations

import logging
import os
import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import zmq

from engine.realtime import CostLog
from services.net import protocol
from services.net.codec import PoseCoder
from services.net.keys import ServerKeys
from services.net.protocol import BARRIER_WAIT, MessageError

log = logging.getLogger("colosseum.net")

#: Requests handled per frame at most; the rest wait for the next frame.
MAX_REQUESTS = 2_000
#: State messages queued per node before ZeroMQ drops that node's newest (about 1 s).
STATE_QUEUE = 64
#: Seconds a node may take from its hello to its first message (building a large scene
#: and starting its renderer) before it counts as gone.
JOIN_GRACE = 30.0


class NetError(Exception):
    """A server or node that cannot start or go on; the message says why and what to do.
    ``reply`` is the server's refusal, when there was one."""

    def __init__(self, message: str, reply: dict[str, Any] | None = None) -> None:
        super().__init__(message)
        self.reply = reply or {}


@dataclass(slots=True)
class Peer:
    """A joined node."""

    identity: bytes
    user: str
    display: str | None
    heard: float
    #: Buttons it holds down now ((device, name), device unscoped) and sources it used.
    held: set[tuple[str, str]] = field(default_factory=set)
    sources: set[str] = field(default_factory=set)
    #: The oldest and newest frames it holds (a display at the swap barrier) and the
    #: barrier's round it waits in.
    ready: tuple[int, int, int] | None = None
    #: It sent something since its hello (until then JOIN_GRACE holds, not the timeout).
    settled: bool = False


@dataclass(slots=True)
class Outgoing:
    """A frame handed to the sender thread: the bodies' poses and the frame's events."""

    frame: int
    time: float
    sent: float
    ids: np.ndarray
    poses: np.ndarray
    events: dict[str, list[Any]]
    key: bool


class NetServer:
    """The state and control sockets of ``colosseum serve``.

    Frames are encoded and sent by a thread of their own (:meth:`submit` hands one over
    and returns), so the server's frame pays only for gathering its poses; encoding runs
    beside the next physics step. When the sender is still busy with a frame, the next
    one takes its place and their events are joined: poses are encoded against what the
    nodes hold, so a frame skipped so never breaks their chain.
    """

    def __init__(self, address: str, content: str, keys: ServerKeys | None = None,
                 timeout: float = 2.0, clock: Callable[[], float] = time.monotonic,
                 barrier_wait: float = BARRIER_WAIT) -> None:
        self.address = address
        self.content = content
        self.keys = keys
        self.timeout = timeout
        self.clock = clock
        self.barrier_wait = barrier_wait
        #: The content folder served, told to a node whose content differs (so a node on
        #: the same machine finds it).
        self.content_dir: str | None = None
        #: A fresh id per server run: a node seeing another one resynchronises.
        self.epoch = os.urandom(6).hex()
        self.peers: dict[bytes, Peer] = {}
        #: Nodes let go since the last poll (timed out, or said bye).
        self.left: list[Peer] = []
        #: Nodes that joined since the last poll.
        self.joined: list[Peer] = []
        #: Returns (state text, object ID -> net id, frame, time) for a node that asks.
        self.full_state: Callable[[], dict[str, Any]] = lambda: {}
        #: Set when a node asked for a keyframe (it missed a frame, or just came); the next
        #: frame submitted is one.
        self.key_wanted = False
        self.counts: Counter[str] = Counter()
        self.bytes_sent = 0
        self.frames_sent = 0
        self._barrier_since: float | None = None
        self.coder = PoseCoder()
        #: Wall seconds the sender thread spent encoding and sending each frame, and its
        #: CPU seconds (the wall time less waiting for the GIL or a core).
        self.send_costs = CostLog()
        self.send_cpu = CostLog()
        self._outgoing: Outgoing | None = None
        self._releases: list[dict[str, Any]] = []
        self._wake = threading.Condition()
        self._stopping = False
        self._sender: threading.Thread | None = None
        self._ctx: zmq.Context | None = None
        self._auth: Any = None
        self._pub: zmq.Socket | None = None
        self._router: zmq.Socket | None = None

    # -- sockets ----------------------------------------------------------------
    def bind(self) -> None:
        """Open both sockets; :class:`NetError` says why one cannot be."""
        state_at, control_at = protocol.endpoints(self.address)
        self._ctx = ctx = zmq.Context()
        if self.keys is not None:
            from zmq.auth.thread import ThreadAuthenticator

            self._auth = ThreadAuthenticator(ctx, log=logging.getLogger("colosseum.net.auth"))
            self._auth.start()
            self._auth.configure_curve(domain="*", location=str(self.keys.users))
        self._pub = self._socket(zmq.PUB, state_at, STATE_QUEUE)
        self._router = self._socket(zmq.ROUTER, control_at)
        self._router.setsockopt(zmq.ROUTER_MANDATORY, 0)
        self._sender = threading.Thread(target=self._send_loop, name="colosseum-net-send",
                                        daemon=True)
        self._sender.start()

    def _socket(self, kind: int, endpoint: str, queue: int | None = None) -> zmq.Socket:
        """A socket bound to ``endpoint``; ``queue``: messages it queues per peer (set
        before the bind: a listener's connections take the options it was bound with)."""
        assert self._ctx is not None
        sock = self._ctx.socket(kind)
        sock.linger = 0
        if queue is not None:
            sock.sndhwm = queue
        sock.setsockopt(zmq.MAXMSGSIZE, protocol.HARD_LIMIT)
        if self.keys is not None:
            sock.curve_secretkey = self.keys.secret
            sock.curve_publickey = self.keys.public
            sock.curve_server = True
        try:
            sock.bind(endpoint)
        except zmq.ZMQError as exc:
            sock.close(0)
            self.close()
            if exc.errno == zmq.EADDRINUSE:
                raise NetError(f"{endpoint} is in use (another server, or another program); "
                               "choose another port with --bind tcp://HOST:PORT (the server "
                               "takes PORT and PORT+1)") from None
            raise NetError(f"cannot bind {endpoint}: {exc}") from None
        return sock

    def close(self) -> None:
        if self._sender is not None:
            with self._wake:
                self._stopping = True
                self._wake.notify()
            self._sender.join(5.0)
            self._sender = None
        for sock in (self._pub, self._router):
            if sock is not None:
                sock.close(0)
        self._pub = self._router = None
        if self._auth is not None:
            self._auth.stop()
            self._auth = None
        if self._ctx is not None:
            self._ctx.term()
            self._ctx = None

    # -- each frame ---------------------------------------------------------------
    def poll(self) -> list[tuple[Peer, list[dict[str, Any]]]]:
        """Handle what the nodes sent since the last call; returns each input message's
        peer and its event records (unchecked: the caller checks each event)."""
        assert self._router is not None
        now = self.clock()
        self.left.clear()
        self.joined.clear()
        inputs: list[tuple[Peer, list[dict[str, Any]]]] = []
        router = self._router
        for _ in range(MAX_REQUESTS):
            try:
                frames = router.recv_multipart(zmq.NOBLOCK, copy=False)
            except zmq.Again:
                break
            identity, body = frames[0].bytes, [f.bytes for f in frames[1:]]
            try:
                request = protocol.decode_request(body)
            except MessageError as exc:
                self._bad("malformed", f"a malformed message ({exc})",
                          over=sum(map(len, body)) > protocol.MAX_MESSAGE)
                continue
            peer = self.peers.get(identity)
            kind = request["type"]
            if kind == "hello":
                self._hello(identity, request, now, self._key_owner(frames[-1]))
                continue
            if peer is None:  # a node the server forgot (it restarted, or timed out)
                self._reply(identity, {"type": "refused", "reason": "not joined: say hello",
                                       "rejoin": True})
                self.counts["unjoined"] += 1
                continue
            peer.heard = now
            peer.settled = True
            self.counts[kind] += 1
            if kind == "input":
                if isinstance(request["events"], list):
                    inputs.append((peer, request["events"]))
                else:
                    self._bad("malformed", "an input message whose events are not a list")
            elif kind == "state":
                self._reply(identity, {"type": "state", **self.full_state()})
                self.key_wanted = True
            elif kind == "key":
                self.key_wanted = True
            elif kind == "ready":
                held = (request["oldest"], request["frame"], request["round"])
                peer.ready = held if all(isinstance(n, int) for n in held) else None
            elif kind == "bye":
                self._let_go(peer, "left")
        for peer in list(self.peers.values()):
            limit = self.timeout if peer.settled else max(self.timeout, JOIN_GRACE)
            if now - peer.heard > limit:
                self._let_go(peer, f"not heard from for {limit:g} s")
        return inputs

    def _bad(self, what: str, message: str, over: bool = False) -> None:
        self.counts["oversized" if over else what] += 1
        total = self.counts["malformed"] + self.counts["oversized"]
        if total == 1 or total % 1000 == 0:
            log.warning("dropped %s (%d dropped so far; see --stats net)", message, total)

    def _key_owner(self, frame: zmq.Frame) -> str | None:
        """The user whose CURVE key sent ``frame`` (None without --key)."""
        if self.keys is None:
            return None
        try:
            user_id = frame.get("User-Id")
        except zmq.ZMQError:
            return ""
        return self.keys.names.get(str(user_id), "")

    def _hello(self, identity: bytes, request: dict[str, Any], now: float,
               owner: str | None = None) -> None:
        user, display = request.get("user"), request.get("display")
        reason = None
        if owner is not None and owner != user:
            reason = (f"its key is {owner!r}'s, not {user!r}'s: join with --user {owner}"
                      if owner else "its key is not among the server's users")
        elif request["v"] != protocol.VERSION:
            reason = f"protocol version {request['v']!r}; this server speaks {protocol.VERSION}"
        elif not isinstance(user, str) or not user or "/" in user or len(user) > 64:
            reason = "user must be a name of 1 to 64 characters without '/'"
        elif request["content"] != self.content:
            reason = ("its content folder differs from the server's (another version of "
                      "the files): copy the server's content folder, or join with the "
                      "same one")
        elif any(p.user == user and p.identity != identity for p in self.peers.values()):
            reason = f"user {user!r} is already joined from another node; choose another --user"
        if reason is not None:
            if request["content"] == "" and reason.startswith("its content"):
                # a node given no folder asks which one this server runs: not a refusal
                log.debug("told a node the content folder (%s)", self.content_dir)
            else:
                self.counts["refused"] += 1
                log.warning("refused a node: %s", reason)
            self._reply(identity, {"type": "refused", "reason": reason,
                                   "content_dir": self.content_dir})
            return
        peer = self.peers.get(identity)
        if peer is None:
            peer = self.peers[identity] = Peer(identity, user, display if isinstance(
                display, str) else None, now)
            self.joined.append(peer)
            log.info("%s joined%s", user, f" (display {peer.display})" if peer.display else "")
        peer.heard, peer.settled = now, False
        self.key_wanted = True
        self._reply(identity, {"type": "welcome", "epoch": self.epoch,
                               "barrier_wait": self.barrier_wait, **self.full_state()})

    def _let_go(self, peer: Peer, why: str) -> None:
        self.peers.pop(peer.identity, None)
        self.left.append(peer)
        log.info("%s %s", peer.user, why if why == "left" else f"let go: {why}")

    def _reply(self, identity: bytes, message: dict[str, Any]) -> None:
        assert self._router is not None
        try:
            self._router.send_multipart([identity, protocol.encode(message)], zmq.NOBLOCK)
        except zmq.Again:
            self.counts["replies dropped"] += 1

    def submit(self, frame: int, time_: float, ids: np.ndarray, poses: np.ndarray,
               events: dict[str, list[Any]], key: bool = False) -> None:
        """Hand a frame to the sender thread (``poses`` must not change afterwards);
        returns at once. ``key``: send every body (a keyframe)."""
        key = key or self.key_wanted
        self.key_wanted = False
        with self._wake:
            waiting = self._outgoing
            if waiting is not None:  # the sender is behind: this frame takes its place
                self.counts["frames merged"] += 1
                for name, items in waiting.events.items():
                    events[name] = [*items, *events.get(name, ())]
                key = key or waiting.key
            self._outgoing = Outgoing(frame, time_, time.time(), ids, poses, events, key)
            self._wake.notify()

    def _send_loop(self) -> None:
        while True:
            with self._wake:
                while self._outgoing is None and not self._releases and not self._stopping:
                    self._wake.wait()
                if self._stopping:
                    return
                out, self._outgoing = self._outgoing, None
                releases, self._releases = self._releases, []
            for release in releases:
                self._send([protocol.BARRIER, protocol.encode(release)])
            if out is not None:
                t0, cpu = time.perf_counter(), time.thread_time()
                if out.key:
                    self.coder.key_wanted = True
                poses = self.coder.encode(out.ids, out.poses)
                header = protocol.state_header(self.epoch, out.frame, out.time, out.sent,
                                               out.events)
                self._send([protocol.STATE, header, poses])
                self.frames_sent += 1
                self.bytes_sent += len(header) + len(poses) + 1
                self.send_costs.add(time.perf_counter() - t0)
                self.send_cpu.add(time.thread_time() - cpu)

    def _send(self, frames: list[bytes]) -> None:
        """Send on the state socket (the sender thread's alone). A PUB socket never blocks
        nor refuses: a node whose queue is full loses the frame, which only it can tell
        (it counts the frame numbers it missed)."""
        assert self._pub is not None
        self._pub.send_multipart(frames, copy=False)

    def barrier(self) -> int | None:
        """Release the displays waiting at the swap barrier: when each one is ready (or
        :attr:`barrier_wait` passed since the first), the newest frame they all hold
        goes out and is returned — or, when one joined after another's newest frame,
        the oldest frame the newcomer holds, which the others are about to receive. The
        release names each released display's round, so a display that was not in it
        (it came late) keeps waiting for its own."""
        displays = [p for p in self.peers.values() if p.display is not None]
        held = {p.user: p.ready for p in displays if p.ready is not None}
        if not held:
            return None
        now = self.clock()
        if self._barrier_since is None:
            self._barrier_since = now
        if len(held) < len(displays) and now - self._barrier_since < self.barrier_wait:
            return None
        if len(held) < len(displays):
            self.counts["barrier timeouts"] += 1
        frame = max(min(newest for _, newest, _ in held.values()),
                    max(oldest for oldest, _, _ in held.values()))
        for peer in displays:
            peer.ready = None
        self._barrier_since = None
        with self._wake:
            self._releases.append({"frame": frame, "rounds": {
                user: round_ for user, (_, _, round_) in held.items()}})
            self._wake.notify()
        return frame

    def stats(self) -> dict[str, Any]:
        return {"nodes": sorted(p.user for p in self.peers.values()),
                "frames_sent": self.frames_sent, "bytes_sent": self.bytes_sent,
                "malformed": self.counts["malformed"], "oversized": self.counts["oversized"],
                "refused": self.counts["refused"], "inputs": self.counts["input"],
                "barrier_timeouts": self.counts["barrier timeouts"],
                "send_ms_mean": self.send_costs.mean() * 1e3,
                "send_ms_p99": self.send_costs.percentile(99) * 1e3,
                "send_cpu_ms_mean": self.send_cpu.mean() * 1e3,
                "frames_merged": self.counts["frames merged"]}
