"""The network plugins: an engine that serves its simulation, and a node that follows one.

:class:`ServerPlugin` (``colosseum serve``) adds to a full engine:

* :class:`ServeInputSystem` (INPUT, before the input system): the nodes' requests;
  their input events are injected into the input hub with each source scoped by user
  (tracker ``hand_r`` of ``alice`` is ``alice/hand_r``, calibrated as the scene's
  ``hand_r``: see :mod:`engine.input.hub`), so a Controller or Hand bound to
  ``alice/hand_r`` follows alice's device, and the server's ``--record`` holds every
  user's input. A node that leaves (or goes silent) has every button it held released
  and every source it used lost, so its hands let go; scripts get the custom events
  ``userJoined`` and ``userLeft`` with the user's name; what stands for a user (an
  object or avatar with ``User "NAME"``) leaves the world ``--leave-after`` seconds after
  their node does, unless they come back.
* :class:`PublishSystem` (RENDER, the frame's last): every replicated entity (a named
  object with a Transform; cameras are each node's own) has a stable net id; the frame's
  poses go out encoded (:mod:`engine.net.codec`) with its events: objects scripts spawned
  (their scene text) and removed, sounds played, stopped and regained, contact sounds,
  uniforms set, custom events emitted.

:class:`NodePlugin` (``colosseum join``) runs without physics or scripts:
:class:`FollowSystem` (INPUT) takes the frames that came, applies their events,
and writes the poses it shows into the pose table — interpolated a little behind the
newest frame, or, on a display of a wall, exactly the frame all displays draw — and
forwards the node's raw input each frame.
"""

from __future__ import annotations

import logging
import math
import time
from collections import Counter, deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Camera, Name, Physical, Sound, Transform, UserOwned
from engine.audio import ContactSoundFilter
from engine.events import Contacts, CustomEvent, Despawned, Spawned
from engine.input import InputHub
from engine.input.events import Button, DeviceLost
from engine.input.record import FrameInput, event_from_record, event_record
from engine.messages import MessageLog
from engine.net import protocol
from engine.net.client import NetClient
from engine.net.codec import CodecError, Gap, PoseDecoder
from engine.net.follow import Follower
from engine.net.server import NetServer, Peer
from engine.realtime import CostLog
from engine.scene import SceneIds
from engine.scene.factory import SpawnRecord
from engine.services import ShaderControl, SoundControl, UniformValue
from engine.system import ANY_COMPONENT, Phase, System

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.net")

#: Frames between keyframes the server sends unasked (a node that missed one waits at
#: most this long, or asks).
KEY_EVERY = 120
#: Custom events a frame forwards at most; their data must be JSON.
MAX_CUSTOM = 64


# -- server --------------------------------------------------------------------------
@dataclass(slots=True)
class FrameEvents:
    """What happened in a frame besides poses, as the nodes are told it."""

    spawned: list[dict[str, Any]] = field(default_factory=list)
    removed: list[int] = field(default_factory=list)
    sounds: list[list[Any]] = field(default_factory=list)
    uniforms: list[list[Any]] = field(default_factory=list)
    custom: list[list[Any]] = field(default_factory=list)

    def take(self) -> dict[str, Any]:
        out = {k: v for k, v in (("spawned", self.spawned), ("removed", self.removed),
                                 ("sounds", self.sounds), ("uniforms", self.uniforms),
                                 ("custom", self.custom)) if v}
        self.spawned, self.removed, self.sounds, self.uniforms, self.custom = [], [], [], [], []
        return out


class SoundRelay:
    """The server's SoundControl: the sound plugin's (if loaded) plus telling the nodes."""

    plugin = "sound"

    def __init__(self, inner: SoundControl | None, publish: PublishSystem) -> None:
        self.inner = inner
        self.publish = publish

    def play(self, engine: Any, entity: int) -> Any:
        self.publish.sound("play", entity)
        return None if self.inner is None else self.inner.play(engine, entity)

    def stop(self, entity: int) -> None:
        self.publish.sound("stop", entity)
        if self.inner is not None:
            self.inner.stop(entity)

    def set_gain(self, entity: int, gain: float) -> None:
        self.publish.sound("gain", entity, gain)
        if self.inner is not None:
            self.inner.set_gain(entity, gain)


class ShaderRelay:
    """The server's ShaderControl: uniforms a script sets go to the nodes (a headless
    server draws nothing itself)."""

    plugin = "render"

    def __init__(self, inner: ShaderControl | None, events: FrameEvents) -> None:
        self.inner = inner
        self.events = events

    def set_uniform(self, state_id: str, name: str, value: UniformValue) -> None:
        self.events.uniforms.append([state_id, name, value])
        if self.inner is not None:
            self.inner.set_uniform(state_id, name, value)


class ServeInputSystem(System):
    """The nodes' requests, once a frame; their input into the hub, scoped by user."""

    phase = Phase.INPUT
    before = ("InputSystem",)
    reads = (ANY_COMPONENT,)  # a node's full state is the whole scene

    def __init__(self, server: NetServer, leave_after: float = 10.0) -> None:
        self.server = server
        self.leave_after = leave_after
        #: users whose node left -> the simulated time their objects leave the world
        self.leaving: dict[str, float] = {}
        self.hub: InputHub | None = None
        self.messages = MessageLog(log)

    def run(self, engine: Engine, dt: float) -> None:
        self.hub = engine.try_resource(InputHub)  # the input system's (set up after this)
        server = self.server
        for peer, records in server.poll():
            for record in records[:1000]:
                self._inject(peer, record)
        for peer in server.joined:
            self.leaving.pop(peer.user, None)
            engine.events.emit(CustomEvent("userJoined", peer.user))
        for peer in server.left:
            self._release(peer)
            self.leaving[peer.user] = engine.time + self.leave_after
            engine.events.emit(CustomEvent("userLeft", peer.user))
        for user in [u for u, t in self.leaving.items() if engine.time >= t]:
            del self.leaving[user]
            self._take_out(engine, user)

    def _take_out(self, engine: Engine, user: str) -> None:
        """What stands for a user who left and did not come back leaves the world."""
        gone = [e for e, owned in engine.world.get_component(UserOwned) if owned.user == user]
        for entity in gone:
            engine.despawn(entity)
        if gone:
            log.info("user %r left %g s ago and did not come back: %d object(s) standing "
                     "for them leave the world", user, self.leave_after, len(gone))

    def _inject(self, peer: Peer, record: Any) -> None:
        try:
            if not isinstance(record, dict):
                raise ValueError("an event must be a JSON object")
            record = {k: v for k, v in record.items() if k != "frame"}
            event = event_from_record(record)
        except (ValueError, KeyError, TypeError) as exc:
            self.server.counts["malformed"] += 1
            self.messages.warn(f"node {peer.user!r} sent an input event that is not one "
                               f"({exc}); dropped")
            return
        scoped = _scope(event, peer.user)
        if isinstance(scoped, Button):
            key = (event.device, scoped.name)
            (peer.held.add if scoped.pressed else peer.held.discard)(key)
        peer.sources.add(event.device)
        if self.hub is not None:
            self.hub.inject(scoped)

    def _release(self, peer: Peer) -> None:
        """A node that left lets go: buttons up, sources lost."""
        if self.hub is None:
            return
        for device, name in sorted(peer.held):
            self.hub.inject(Button(f"{peer.user}/{device}", name, False))
        for source in sorted(peer.sources):
            self.hub.inject(DeviceLost(f"{peer.user}/{source}"))


def _scope(event: Any, user: str) -> Any:
    """The event with its source named ``user/source``."""
    from dataclasses import replace

    return replace(event, device=f"{user}/{event.device}")


class PublishSystem(System):
    """Every frame's state to the nodes: poses of what moved, and the frame's events."""

    phase = Phase.RENDER
    reads = (Name, Transform, Camera, Physical, Sound)

    def __init__(self, server: NetServer) -> None:
        self.server = server
        self.events = FrameEvents()
        self.contacts = ContactSoundFilter()
        #: entity -> net id, for every replicated entity; and the ids sorted with their
        #: entities in the same order.
        self.net_of: dict[int, int] = {}
        self._next = 1
        self._ids = np.zeros(0, np.uint32)
        self._entities = np.zeros(0, np.int64)
        self._rows: tuple[int, int, np.ndarray] | None = None
        self._layout = 0
        self._announced: set[int] = set()  # spawned entities whose record went out
        self.publish_costs = CostLog()
        self.messages = MessageLog(log)
        self._full: tuple[int, dict[str, Any]] | None = None

    def setup(self, engine: Engine) -> None:
        sound = engine.try_resource(SoundControl)  # type: ignore[type-abstract]
        engine.insert_resource(SoundRelay(sound, self), as_type=SoundControl)
        shader = engine.try_resource(ShaderControl)  # type: ignore[type-abstract]
        engine.insert_resource(ShaderRelay(shader, self.events), as_type=ShaderControl)
        for entity in sorted(engine.world.entities()):
            self._track(engine, entity)
        self._announced.update(self.net_of)
        self.server.full_state = lambda: self.full_state(engine)
        engine.stat_sources["net"] = self.stats

    def _track(self, engine: Engine, entity: int) -> None:
        world = engine.world
        if entity in self.net_of or not world.entity_exists(entity):
            return
        if world.try_component(entity, Name) is None or world.try_component(
                entity, Transform) is None or world.try_component(entity, Camera) is not None:
            return
        self.net_of[entity] = self._next
        self._next += 1
        self._layout += 1

    def sound(self, what: str, entity: int, *args: float) -> None:
        net = self.net_of.get(entity)
        if net is not None:
            self.events.sounds.append([what, net, *args])

    def run(self, engine: Engine, dt: float) -> None:
        t0 = time.perf_counter()
        for spawned in engine.events.frame(Spawned):
            self._track(engine, spawned.entity)
            self.contacts.settle(spawned.entity, engine.time)
        for gone in engine.events.frame(Despawned):
            net = self.net_of.pop(gone.entity, None)
            if net is not None:
                self.events.removed.append(net)
                self._layout += 1
        self._spawn_records(engine)
        self._contact_sounds(engine)
        self._custom(engine)
        server = self.server
        events = self.events.take()
        if server.peers:
            ids, poses = self._poses(engine)
            server.submit(engine.frame, engine.physics.snapshot.time, ids, poses, events,
                          key=engine.frame % KEY_EVERY == 0)
            server.barrier()
        self.publish_costs.add(time.perf_counter() - t0)

    def _poses(self, engine: Engine) -> tuple[np.ndarray, np.ndarray]:
        poses = engine.world.poses
        if self._rows is None or self._rows[:2] != (self._layout, poses.version):
            if self._rows is None or self._rows[0] != self._layout:
                pairs = sorted((net, entity) for entity, net in self.net_of.items())
                self._ids = np.array([p[0] for p in pairs], np.uint32)
                self._entities = np.array([p[1] for p in pairs], np.int64)
            rows = poses.rows(self._entities)
            keep = rows >= 0
            if not keep.all():  # a Transform was taken away: no longer replicated
                for entity in self._entities[~keep].tolist():
                    self.events.removed.append(self.net_of.pop(entity))
                self._layout += 1
                return self._poses(engine)
            self._rows = (self._layout, poses.version, rows)
        return self._ids, poses.table[self._rows[2], :7]  # a copy: the sender's own

    def _spawn_records(self, engine: Engine) -> None:
        """Objects a script spawned since the last frame go out as their scene text."""
        ids = engine.try_resource(SceneIds)
        if ids is None:
            return
        fresh = []
        for record in reversed(ids.spawned):
            if record.db is None:  # a joint: nodes have no physics
                continue
            alive = [e for e in record.objects if e >= 0 and e in self.net_of]
            if alive and all(e in self._announced for e in alive):
                break
            if alive:
                fresh.append(record)
        from engine.scene.writer import write

        for record in reversed(fresh):
            assert record.db is not None
            self._announced.update(record.objects)
            self.events.spawned.append({
                "text": write(record.db, literal=True, flatten=True),
                "objects": [self.net_of.get(e, -1) for e in record.objects]})

    def _contact_sounds(self, engine: Engine) -> None:
        batches = engine.events.frame(Contacts)
        if not batches:
            return
        world = engine.world
        for batch in batches:
            for hit in self.contacts.process(batch.batch, engine.time):
                for body in (hit.a, hit.b):
                    physical = world.try_component(body, Physical) if body >= 0 else None
                    if physical is not None and physical.material.contact_sound:
                        self.events.sounds.append(["hit", physical.material.contact_sound,
                                                   float(hit.gain),
                                                   [float(x) for x in hit.position]])
                        break

    def _custom(self, engine: Engine) -> None:
        for event in engine.events.frame(CustomEvent)[:MAX_CUSTOM]:
            try:
                protocol.encode({"d": event.data})
            except (TypeError, ValueError):
                self.messages.warn(f"custom event {event.name!r}: its data is not plain data "
                                   "(numbers, strings, lists, tables); the nodes are not told")
                continue
            self.events.custom.append([event.name, event.data])

    def full_state(self, engine: Engine) -> dict[str, Any]:
        """What a node builds its world from: the saved-state text and which object ID is
        which net id (made once a frame however many nodes ask)."""
        from engine.scene.snapshot import write_state

        if self._full is not None and self._full[0] == engine.frame:
            return self._full[1]
        written: dict[int, str] = {}
        text = write_state(engine, None, written)
        names = {name: self.net_of[e] for e, name in written.items() if e in self.net_of}
        folder = engine.config.content_dir
        state = {"text": text, "names": names, "frame": engine.frame, "time": engine.time,
                 "dt": engine.config.dt, "content_dir": None if folder is None else str(folder)}
        self._full = (engine.frame, state)
        return state

    def stats(self) -> dict[str, Any]:
        return {**self.server.stats(), "replicated": len(self.net_of),
                "publish_ms_mean": self.publish_costs.mean() * 1e3,
                "publish_ms_p99": self.publish_costs.percentile(99) * 1e3}


class ServerPlugin:
    """Serves the engine's simulation to nodes (``colosseum serve``)."""

    name = "net-server"

    def __init__(self, server: NetServer, leave_after: float = 10.0) -> None:
        self.server = server
        self.leave_after = leave_after

    def build(self, engine: Engine) -> None:
        engine.add_system(ServeInputSystem(self.server, self.leave_after))
        engine.add_system(PublishSystem(self.server))


# -- node ------------------------------------------------------------------------------
class FollowSystem(System):
    """A node's frame: the server's frames in, the poses it shows out, its input back."""

    phase = Phase.INPUT
    after = ("InputSystem",)
    reads = (ANY_COMPONENT,)
    writes = (ANY_COMPONENT,)

    def __init__(self, client: NetClient, welcome: dict[str, Any], display: bool = False,
                 barrier: bool = False) -> None:
        self.client = client
        self.display = display
        self.barrier = barrier
        self.decoder = PoseDecoder()
        self.follower = Follower(delay=1.5 * float(welcome.get("dt") or 1 / 60))
        self.entity_of: dict[int, int] = {}
        self.shown_frame = -1
        #: The server frames a display drew, newest last (the frame lock's record).
        self.shown_frames: deque[int] = deque(maxlen=3600)
        self.shown_time = float(welcome.get("time", 0.0))
        self.counts: Counter[str] = Counter()
        self.latency = CostLog()
        self._frame = -1
        self._key_asked = -math.inf
        self._silent_told = False
        self._outbox: list[dict[str, Any]] = []
        self._rows: tuple[int, int, np.ndarray, np.ndarray] | None = None
        self._layout = 0
        self.messages = MessageLog(log)
        self._welcome = welcome

    def setup(self, engine: Engine) -> None:
        self._map_names(engine, self._welcome["names"])
        hub = engine.try_resource(InputHub)
        if hub is not None:
            hub.listeners.append(self._forward)
        engine.stat_sources["net"] = self.stats

    def _map_names(self, engine: Engine, names: dict[str, int]) -> None:
        ids = engine.resource(SceneIds)
        self.entity_of = {int(net): ids.entities[name] for name, net in names.items()
                          if name in ids.entities}
        self._layout += 1

    def _forward(self, batch: FrameInput) -> None:
        self._outbox += [event_record(0, event) for event in batch.events]

    # -- per frame ---------------------------------------------------------------
    def run(self, engine: Engine, dt: float) -> None:
        client = self.client
        if self._outbox:
            events, self._outbox = self._outbox[:1000], self._outbox[1000:]
            client.send({"type": "input", "events": events})
        client.beat()
        for reply in client.replies():
            if reply.get("rejoin"):
                self._resync(engine, client.rejoin(1.0))
        wall = time.monotonic()
        newest = None
        for kind, header, blob in client.receive():
            if kind == protocol.BARRIER:
                continue
            if header.get("epoch") != client.epoch:
                self._resync(engine, client.rejoin(2.0))
                return
            newest = self._take(engine, header, blob, wall) or newest
        if newest is None and client.silent:
            if not self._silent_told:
                self._silent_told = True
                log.warning("nothing from %s for %.1f s: the server stopped or the network "
                            "is down; waiting for it", client.address, client.timeout)
            return
        self._silent_told = False
        if not self.follower.frames:
            return
        self._show(engine, wall)

    def _take(self, engine: Engine, header: dict[str, Any], blob: bytes | None,
              wall: float) -> int | None:
        frame = header.get("frame")
        if not isinstance(frame, int) or blob is None:
            self.counts["malformed"] += 1
            return None
        if self._frame >= 0 and frame > self._frame + 1:
            self.counts["dropped"] += frame - self._frame - 1
        self._frame = frame
        sent = header.get("sent")
        if isinstance(sent, float):
            self.latency.add(max(time.time() - sent, 0.0))
        events = header.get("events")
        if isinstance(events, dict):
            self._apply_events(engine, events)
        try:
            self.decoder.decode(blob)
        except Gap:
            if self.decoder.seq < 0:
                return None  # joined between keyframes: the hello asked for the next one
            self.counts["gaps"] += 1
            if self._frame - self._key_asked > 10:
                self._key_asked = self._frame
                self.client.send({"type": "key"})
            return None
        except CodecError as exc:
            self.counts["malformed"] += 1
            self.messages.warn(f"a frame from the server does not decode ({exc}); skipped")
            return None
        time_ = header.get("time")
        self.follower.push(frame, float(time_) if isinstance(time_, int | float) else 0.0,
                           self.decoder.ids, self.decoder.poses, wall)
        return frame

    def _apply_events(self, engine: Engine, events: dict[str, Any]) -> None:
        try:
            for spawn in events.get("spawned", ()):
                self._spawn(engine, spawn["text"], spawn["objects"])
            for net in events.get("removed", ()):
                entity = self.entity_of.pop(int(net), None)
                if entity is not None:
                    engine.despawn(entity)
                    self._layout += 1
            for sound in events.get("sounds", ()):
                self._sound(engine, sound)
            control = engine.try_resource(ShaderControl)  # type: ignore[type-abstract]
            for state, name, value in events.get("uniforms", ()):
                if control is not None:
                    control.set_uniform(state, name, tuple(value) if isinstance(value, list)
                                        else value)
            for name, data in events.get("custom", ()):
                engine.events.emit(CustomEvent(name, data))
        except (KeyError, TypeError, ValueError) as exc:
            self.counts["malformed"] += 1
            self.messages.warn(f"a frame's events from the server are not understood "
                               f"({exc!r}); the rest of them are skipped")

    def _spawn(self, engine: Engine, text: str, objects: list[int]) -> None:
        from engine.scene import SceneError, spec_from_text

        ids = engine.resource(SceneIds)
        folder = engine.config.content_dir or Path(".")
        try:
            spec = spec_from_text(text, folder, engine.rng, path="<server spawn>",
                                  scene=ids.spec)
        except SceneError as exc:
            self.messages.error(f"an object the server spawned cannot be made here: {exc}")
            return
        made = []
        for net, es in zip(objects, spec.entities, strict=False):
            entity = -1
            if net >= 0 and not es.skipped:
                entity = self.entity_of[int(net)] = engine.spawn(*es.components)
            made.append(entity)
        # recorded as the server's scripts record it, so a saved state writes it too
        ids.record(SpawnRecord(spec.db, spec.content_dir, made, []),
                   engine.world.entity_exists)
        self._layout += 1

    def _sound(self, engine: Engine, sound: list[Any]) -> None:
        what = sound[0]
        if what == "hit":
            from systems.sound import SoundSystem

            system = engine.try_resource(SoundSystem)
            if system is not None:
                system.play_contact(str(sound[1]), float(sound[2]), np.array(sound[3], float))
            return
        control = engine.try_resource(SoundControl)  # type: ignore[type-abstract]
        entity = self.entity_of.get(int(sound[1]))
        if control is None or entity is None:
            return
        if what == "play":
            control.play(engine, entity)
        elif what == "stop":
            control.stop(entity)
        elif what == "gain":
            control.set_gain(entity, float(sound[2]))

    def _show(self, engine: Engine, wall: float) -> None:
        follower = self.follower
        if self.display:
            newest = follower.frames[-1]
            shown = newest
            if self.barrier:
                agreed = self.client.wait_barrier(newest.frame, 0.25)
                found = None if agreed is None else follower.frame(agreed)
                if found is None:
                    self.counts["barrier misses"] += 1
                else:
                    shown = found
            ids, when = shown.ids, shown.time
            rows = np.zeros((len(ids), 13))
            rows[:, :7] = shown.poses
            self.counts["stale"] += max(newest.frame - shown.frame, 0)
            self.shown_frame = shown.frame
            self.shown_frames.append(shown.frame)
        else:
            server_time = follower.server_time(wall)
            assert server_time is not None
            ids, rows, when = follower.at(server_time)
            self.shown_frame = follower.frames[-1].frame
        self.shown_time = when
        self._write(engine, ids, rows)

    def _write(self, engine: Engine, ids: np.ndarray, rows: np.ndarray) -> None:
        table = engine.world.poses
        cached = self._rows
        if cached is None or cached[:2] != (self._layout, table.version) or \
                len(cached[3]) != len(ids) or (cached[3] != ids).any():
            found = table.rows([self.entity_of.get(int(n), -1) for n in ids.tolist()])
            cached = self._rows = (self._layout, table.version, found, ids)
        where = cached[2]
        have = where >= 0
        table.table[where[have]] = rows[have]

    def _resync(self, engine: Engine, welcome: dict[str, Any]) -> None:
        """Another server (a restart) or a lost place: build the world from its state."""
        self.counts["resyncs"] += 1
        log.info("resynchronising with %s at its frame %s", self.client.address,
                 welcome.get("frame"))
        self.decoder = PoseDecoder()
        self.follower.reset()
        self._frame = -1
        spec = node_scene(welcome, engine.config.content_dir or Path("."))
        for entity in list(engine.world.entities()):
            engine.despawn(entity)

        def rebuild() -> None:
            from engine.scene import instantiate

            instantiate(engine, spec)
            self._map_names(engine, welcome["names"])

        engine.defer(rebuild)

    def stats(self) -> dict[str, Any]:
        return {"frames_received": self.client.frames, "bytes_received": self.client.bytes,
                "dropped": self.counts["dropped"], "gaps": self.counts["gaps"],
                "stale": self.counts["stale"], "malformed": self.counts["malformed"] +
                self.client.malformed, "resyncs": self.counts["resyncs"],
                "barrier_misses": self.counts["barrier misses"],
                "shown_frame": self.shown_frame, "shown_time": self.shown_time,
                "shown_frames": list(self.shown_frames),
                "latency_ms_p50": self.latency.percentile(50) * 1e3,
                "latency_ms_p99": self.latency.percentile(99) * 1e3}


def node_scene(welcome: dict[str, Any], folder: Path) -> Any:
    """The spec of the server's full state, run in the node's content ``folder`` (without
    the scripts' saved states: scripts run on the server). Raises SceneError when this
    folder cannot build it."""
    from engine.scene import build_specs, parse_text, validated

    text = welcome["text"]
    if not isinstance(text, str):
        raise TypeError("the server's state is not text")
    lines = text.splitlines(keepends=True)
    while lines and lines[0].startswith("//"):  # the server's header: where it saved from
        lines.pop(0)
    db = parse_text("".join(lines), "<server state>", base_dir=folder)
    # scripts run on the server alone; a node's saved state starts them afresh
    db.root.entries = [e for e in db.root.entries if e.key != "ScriptState"]
    return build_specs(validated(db, folder), folder)


class NodePlugin:
    """Follows a server (``colosseum join``): no physics, no scripts of its own."""

    name = "net-node"

    def __init__(self, client: NetClient, welcome: dict[str, Any], display: bool = False,
                 barrier: bool = False) -> None:
        self.system = FollowSystem(client, welcome, display, barrier)

    def build(self, engine: Engine) -> None:
        engine.insert_resource(self.system)
        engine.add_system(self.system)
