"""The network plugins: an engine that serves its simulation, and a node that follows one.

:class:`ServerPlugin` (``colosseum serve``) adds to a full engine:

* :class:`ServeInputSystem` (INPUT, before the input system): the nodes' requests;
  their input events are injected into the input hub with each source scoped by user
  (tracker ``hand_r`` of ``alice`` is ``alice/hand_r``, calibrated as the scene's
  ``hand_r``: see :mod:`services.input.hub`), so a Controller or Hand bound to
  ``alice/hand_r`` follows alice's device, and the server's ``--record`` holds every
  user's input. A node that leaves (or goes silent) has every button it held released
  and every source it used lost, so its hands let go; scripts get the custom events
  ``userJoined`` and ``userLeft`` with the user's name; what stands for a user (an
  object or avatar with ``User "NAME"``) leaves the world ``--leave-after`` seconds after
  their node does, unless they come back.
* :class:`PublishSystem` (RENDER, the frame's last): every replicated entity (an object
  with a Transform and a Name or a Visual; cameras are each node's own) has a stable net
  id; the frame's poses go out encoded (:mod:`services.net.codec`), the avatars' joint
  matrices among them (:mod:`services.net.bones`), with its events: objects scripts spawned
  (their scene text) and Python code made (text written from their components,
  :mod:`engine.scene.objects_text`) and removed, sounds played, stopped and regained,
  contact sounds, uniforms set, custom events emitted.

:class:`NodePlugin` (``colosseum join``) runs without physics or scripts:
:class:`FollowSystem` (INPUT) takes the frames that came, applies their events,
and writes the poses it shows into the pose table — interpolated a little behind the
newest frame, or, on a display of a wall, exactly the frame all displays draw — and the
avatars' joint matrices into its :class:`~engine.animation.Palettes`, and forwards the
node's raw input each frame.
"""

from __future__ import annotations

import difflib
import logging
import math
import time
from collections import Counter, deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Camera, Name, Physical, Sound, Transform, UserOwned, Visual
from engine.animation import Palettes
from engine.anomalies import ANOMALIES, Anomalies
from engine.events import AnomalySwitched, Contacts, CustomEvent, Despawned, Spawned
from engine.messages import MessageLog
from engine.realtime import TIME_STEP, CostLog
from engine.scene import SceneIds
from engine.scene.factory import SceneSpec, SpawnRecord
from engine.services import ShaderControl, SoundControl, SwapGate, UniformValue
from engine.system import ANY_COMPONENT, Phase, PluginName, System
from services.audio import ContactSoundFilter
from services.input import InputHub
from services.input.events import Button, DeviceLost
from services.input.record import FrameInput, event_from_record, event_record
from services.net import protocol
from services.net.bones import (
    BONE_FLAG,
    MAX_AVATAR_NET,
    MAX_JOINTS,
    bone_ids,
    palette_matrices,
    palette_poses,
    split_bone_ids,
)
from services.net.client import NetClient
from services.net.codec import CodecError, Gap, PoseDecoder
from services.net.follow import Follower, Shown
from services.net.server import NetError, NetServer, Peer

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.net")

#: Frames between keyframes the server sends unasked (a node that missed one waits at
#: most this long, or asks).
KEY_EVERY = 120
#: Custom events a frame forwards at most (the rest are counted and told); their data
#: must be JSON.
MAX_CUSTOM = 64
#: Input events one message from a node may carry; the rest are dropped (and counted).
MAX_EVENTS = 1000
#: A joint whose matrix stretches an axis by more than this is told: nodes draw it rigid.
MAX_STRETCH = 1e-3


# -- server --------------------------------------------------------------------------
@dataclass(slots=True)
class FrameEvents:
    """What happened in a frame besides poses, as the nodes are told it."""

    spawned: list[dict[str, Any]] = field(default_factory=list)
    removed: list[int] = field(default_factory=list)
    sounds: list[list[Any]] = field(default_factory=list)
    #: ``[state, uniform, value]`` (setUniform)
    uniforms: list[list[Any]] = field(default_factory=list)
    #: ``["enable", pass, on]`` and ``["uniform", pass, uniform, value]`` (a PostPass)
    post: list[list[Any]] = field(default_factory=list)
    #: ``[id, kind, enabled, onset, eye, {key: value}]``: an anomaly as it stands now
    anomalies: list[list[Any]] = field(default_factory=list)
    custom: list[list[Any]] = field(default_factory=list)

    def take(self) -> dict[str, Any]:
        names = ("spawned", "removed", "sounds", "uniforms", "post", "anomalies", "custom")
        out = {name: getattr(self, name) for name in names if getattr(self, name)}
        for name in out:
            setattr(self, name, [])
        return out


class SoundRelay:
    """The server's SoundControl: the sound plugin's (if loaded) plus telling the nodes."""

    plugin = PluginName.SOUND

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
    """The server's ShaderControl: uniforms and post passes a script sets go to the nodes
    (a headless server draws nothing itself), each checked against the scene first as a
    renderer would; the latest of each is kept for the nodes that join later."""

    plugin = PluginName.RENDER

    def __init__(self, inner: ShaderControl | None, events: FrameEvents,
                 engine: Engine) -> None:
        self.inner = inner
        self.events = events
        self.engine = engine
        #: (what, name, uniform) -> its latest record, as :class:`FrameEvents` holds it
        self.latest: dict[tuple[str, ...], list[Any]] = {}

    def set_uniform(self, state_id: str, name: str, value: UniformValue) -> None:
        if self.inner is not None:
            self.inner.set_uniform(state_id, name, value)
        else:
            _known("shader state", state_id, self._spec().shader_states)
        record = [state_id, name, _plain(value)]
        self.events.uniforms.append(record)
        self.latest["uniform", state_id, name] = record

    def enable_post(self, name: str, enabled: bool = True) -> None:
        anomalies = self.engine.try_resource(Anomalies)
        if anomalies is not None and (name in anomalies.states or name in ANOMALIES):
            anomalies.switch(name, enabled, "python")  # as the renderer does: sent as one
            return
        if self.inner is not None:
            self.inner.enable_post(name, enabled)
        else:
            _known("PostPass", name, [p.id for p in self._spec().post_passes])
        record = ["enable", name, bool(enabled)]
        self.events.post.append(record)
        self.latest["post", name] = record

    def set_post_uniform(self, name: str, uniform: str, value: UniformValue) -> None:
        if self.inner is not None:
            self.inner.set_post_uniform(name, uniform, value)
        else:
            _known("PostPass", name, [p.id for p in self._spec().post_passes])
        record = ["uniform", name, uniform, _plain(value)]
        self.events.post.append(record)
        self.latest["post uniform", name, uniform] = record

    def _spec(self) -> Any:
        ids = self.engine.try_resource(SceneIds)
        return SceneSpec() if ids is None else ids.spec

    def state(self) -> dict[str, list[list[Any]]]:
        """What was set so far, for a node's full state."""
        return {"uniforms": [r for k, r in self.latest.items() if k[0] == "uniform"],
                "post": [r for k, r in self.latest.items() if k[0] != "uniform"]}


def _known(what: str, name: str, names: Any) -> None:
    """KeyError naming the closest of ``names`` when ``name`` is not one of them."""
    if name not in names:
        close = difflib.get_close_matches(name, list(names), 1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise KeyError(f"unknown {what} {name!r}{hint}")


def _plain(value: Any) -> Any:
    """A uniform's or parameter's value as JSON holds it (vectors as lists)."""
    return [float(v) for v in value] if isinstance(value, tuple | list) else value


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
            for record in records[:MAX_EVENTS]:
                self._inject(peer, record)
            if len(records) > MAX_EVENTS:
                server.counts["oversized"] += 1
                self.messages.warn(f"node {peer.user!r} sent {len(records)} input events in "
                                   f"one message; the first {MAX_EVENTS} were taken, the "
                                   "rest dropped", key=f"too many events from {peer.user}")
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
            self.messages.warn(f"node {peer.user!r} sends input events that are not ones, "
                               f"dropped (counted as malformed); the first: {exc}",
                               key=f"malformed input from {peer.user}")
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


def _object_name(engine: Engine, entity: int, fallback: str | None = None) -> str:
    named = engine.world.try_component(entity, Name)
    return named.id if named is not None else fallback or f"entity {entity}"


def _scope(event: Any, user: str) -> Any:
    """The event with its source named ``user/source``."""
    from dataclasses import replace

    return replace(event, device=f"{user}/{event.device}")


class PublishSystem(System):
    """Every frame's state to the nodes: poses of what moved, and the frame's events."""

    phase = Phase.RENDER
    reads = (Name, Transform, Camera, Physical, Sound, Visual, UserOwned)

    def __init__(self, server: NetServer) -> None:
        self.server = server
        #: Gather and send frames while no node is joined too (a server nobody follows
        #: skips both); ``colosseum bench net`` sets it, so that its no-node baseline does
        #: the same work as a server with nodes.
        self.publish_alone = False
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
        self._fresh: list[int] = []  # entities replicated since the last frame went out
        self.shaders: ShaderRelay  # made in setup, with the engine
        self.publish_costs = CostLog()
        #: Custom events a frame held beyond MAX_CUSTOM, which the nodes were not told.
        self.custom_dropped = 0
        self.messages = MessageLog(log)
        self._full: tuple[int, dict[str, Any]] | None = None
        #: (layout key, bone ids, palette rows, each bone's avatar entity) of the avatars
        #: whose skeletons go out
        self._bones: tuple[Any, np.ndarray, np.ndarray, np.ndarray] | None = None

    def setup(self, engine: Engine) -> None:
        sound = engine.try_resource(SoundControl)  # type: ignore[type-abstract]
        engine.insert_resource(SoundRelay(sound, self), as_type=SoundControl)
        shader = engine.try_resource(ShaderControl)  # type: ignore[type-abstract]
        self.shaders = ShaderRelay(shader, self.events, engine)
        engine.insert_resource(self.shaders, as_type=ShaderControl)
        for entity in sorted(engine.world.entities()):
            self._track(engine, entity)
        self._announced.update(self.net_of)  # in the full state (made in Python or not)
        self._fresh.clear()
        self.server.full_state = lambda: self.full_state(engine)
        engine.stat_sources["net"] = self.stats

    def _track(self, engine: Engine, entity: int) -> None:
        """Replicate ``entity`` if it is an object: a Transform and a Name or a Visual (an
        unnamed one made in Python), cameras excepted (each node has its own)."""
        world = engine.world
        if entity in self.net_of or not world.entity_exists(entity):
            return
        if world.try_component(entity, Transform) is None or world.try_component(
                entity, Camera) is not None or (world.try_component(entity, Name) is None
                                                and world.try_component(entity, Visual) is None):
            return
        self.net_of[entity] = self._next
        self._next += 1
        self._layout += 1
        self._fresh.append(entity)

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
        self._python_objects(engine)
        self._contact_sounds(engine)
        self._anomalies(engine)
        self._custom(engine)
        server = self.server
        events = self.events.take()
        if server.peers or self.publish_alone:
            ids, poses = self._poses(engine)
            bones, joints = self._skeletons(engine)
            if len(bones):
                ids, poses = np.concatenate([ids, bones]), np.concatenate([poses, joints])
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

    def _skeletons(self, engine: Engine) -> tuple[np.ndarray, np.ndarray]:
        """Every replicated avatar's joint matrices as poses, with their bone ids
        (:mod:`services.net.bones`): what the avatars plugin published for this frame."""
        palettes = engine.try_resource(Palettes)
        if palettes is None or not palettes.offsets:
            return np.zeros(0, np.uint32), np.zeros((0, 7))
        key = (self._layout, tuple(palettes.offsets.items()), len(palettes.matrices))
        if self._bones is None or self._bones[0] != key:
            self._bones = (key, *self._bone_layout(engine, palettes))
        _, ids, rows, owners = self._bones
        poses, stretch = palette_poses(palettes.matrices[rows])
        for entity in np.unique(owners[stretch > MAX_STRETCH]).tolist():
            self.messages.warn(f"avatar {_object_name(engine, entity)!r} scales its bones; "
                               "nodes draw its skeleton without the scale")
        return ids, poses

    def _bone_layout(self, engine: Engine, palettes: Palettes
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        ends = sorted(palettes.offsets.values()) + [len(palettes.matrices)]
        joints = {start: stop - start for start, stop in zip(ends, ends[1:], strict=False)}
        chosen = []
        for entity, start in palettes.offsets.items():
            net = self.net_of.get(entity)
            if net is None:
                continue
            if net >= MAX_AVATAR_NET or joints[start] > MAX_JOINTS:
                self.messages.error(f"avatar {_object_name(engine, entity)!r} has "
                                    f"{joints[start]} joints (at most {MAX_JOINTS} go to "
                                    "nodes) or too many objects came before it; nodes draw "
                                    "it in its rest pose")
                continue
            chosen.append((net, start, joints[start], entity))
        chosen.sort()
        nets = np.array([c[0] for c in chosen], np.int64)
        counts = np.array([c[2] for c in chosen], np.int64)
        rows = np.concatenate([np.arange(c[1], c[1] + c[2]) for c in chosen]) if chosen \
            else np.zeros(0, np.int64)
        return bone_ids(nets, counts), rows, np.repeat(
            np.array([c[3] for c in chosen], np.int64), counts)

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

    def _python_objects(self, engine: Engine) -> None:
        """Objects made this frame by Python code (no scene text of their own) go out as
        text written from their components."""
        fresh, self._fresh = self._fresh, []
        for entity in fresh:
            if entity in self._announced or entity not in self.net_of:
                continue
            self._announced.add(entity)
            text = self._object_text(engine, entity)
            if text is not None:
                self.events.spawned.append({"text": text, "objects": [self.net_of[entity]]})

    def _object_name(self, engine: Engine, entity: int) -> str:
        """Its Name, else one made from its net id (an object made in Python unnamed)."""
        return _object_name(engine, entity, f"unnamed~{self.net_of[entity]}")

    def _object_text(self, engine: Engine, entity: int) -> str | None:
        """Scene text of an object made in Python; None (told, once per object) when its
        components cannot be written: the nodes do not show it."""
        from engine.scene.db import STRUCTURE, Block, Entry, Value
        from engine.scene.objects_text import Unwritable, object_block
        from engine.scene.writer import write

        world = engine.world
        name = self._object_name(engine, entity)
        try:
            block = object_block(name, world.component_for_entity(entity, Transform),
                                 world.try_component(entity, Visual),
                                 world.try_component(entity, Sound),
                                 world.try_component(entity, UserOwned))
        except Unwritable as exc:
            self.messages.error(f"object {name!r}, made in Python, is not shown on the "
                                f"nodes: its {exc} has no scene text")
            return None
        entry = Entry("Object", Value(STRUCTURE, block, block.loc), block.loc)
        return write(Block([entry]), literal=True)

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

    def _anomalies(self, engine: Engine) -> None:
        """Each anomaly switched or set this frame, as it stands now (the nodes ramp it)."""
        switched = {e.anomaly for e in engine.events.frame(AnomalySwitched)}
        anomalies = engine.try_resource(Anomalies)
        if not switched or anomalies is None:
            return
        for state in anomalies.states.values():
            if state.id in switched:
                self.events.anomalies.append([
                    state.id, state.kind.name, state.enabled, state.onset, state.eye,
                    {key: _plain(value) for key, value in state.values.items()}])

    def _custom(self, engine: Engine) -> None:
        events = engine.events.frame(CustomEvent)
        over = events[MAX_CUSTOM:]
        if over:
            self.custom_dropped += len(over)
            names = ", ".join(repr(n) for n in dict.fromkeys(e.name for e in over))
            self.messages.warn(f"{len(events)} custom events in one frame: the nodes are told "
                               f"the first {MAX_CUSTOM}, not the other {len(over)} ({names}); "
                               "see --stats net.custom_dropped")
        for event in events[:MAX_CUSTOM]:
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
        for entity in self.net_of:  # objects made in Python: their text from components
            if entity not in written:
                made = self._object_text(engine, entity)
                if made is not None:
                    text += made
                    written[entity] = self._object_name(engine, entity)
        names = {name: self.net_of[e] for e, name in written.items() if e in self.net_of}
        folder = engine.config.content_dir
        state = {"text": text, "names": names, "frame": engine.frame, "time": engine.time,
                 "dt": engine.config.dt, "content_dir": None if folder is None else str(folder),
                 **self.shaders.state()}
        self._full = (engine.frame, state)
        return state

    def stats(self) -> dict[str, Any]:
        return {**self.server.stats(), "replicated": len(self.net_of),
                "custom_dropped": self.custom_dropped,
                "publish_ms_mean": self.publish_costs.mean() * 1e3,
                "publish_ms_p99": self.publish_costs.percentile(99) * 1e3}


class ServerPlugin:
    """Serves the engine's simulation to nodes (``colosseum serve``)."""

    name = PluginName.NET_SERVER

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
        #: How long a display waits at the barrier: the server's own wait, and a frame
        #: or two for its release to arrive.
        self.barrier_wait = float(welcome.get("barrier_wait", protocol.BARRIER_WAIT)) + 0.25
        self.decoder = PoseDecoder()
        self.follower = Follower(delay=1.5 * float(welcome.get("dt") or TIME_STEP))
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
        #: The frame the swap barrier's last round released (every display released in it
        #: draws it next), that frame if it was held then, and whether this frame waited
        #: at the barrier already.
        self._agreed: int | None = None
        self._pinned: Shown | None = None
        self._waited = False
        self.messages = MessageLog(log)
        #: The full state joined from; its uniforms and post passes are set at the first
        #: frame (the renderer is running then).
        self._welcome: dict[str, Any] | None = welcome

    def setup(self, engine: Engine) -> None:
        assert self._welcome is not None
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
        self._waited = False
        if self._welcome is not None:
            self._visuals(engine, self._welcome)
            self._welcome = None
        if self._outbox:
            events, self._outbox = self._outbox[:1000], self._outbox[1000:]
            client.send({"type": "input", "events": events})
        client.beat()
        # a server that forgot this node (it restarted) answers each message the node
        # queued while it was away: one rejoin answers them all
        if any(reply.get("rejoin") for reply in client.replies()) and \
                not self._rejoin(engine, 1.0):
            return
        wall = time.monotonic()
        newest = None
        for kind, header, blob in client.receive():
            if kind == protocol.BARRIER:
                continue
            if header.get("epoch") != client.epoch:
                self._rejoin(engine, 2.0)
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
            self._visuals(engine, events)
            for name, data in events.get("custom", ()):
                engine.events.emit(CustomEvent(name, data))
        except (KeyError, TypeError, ValueError) as exc:
            self.counts["malformed"] += 1
            self.messages.warn(f"a frame's events from the server are not understood "
                               f"({exc!r}); the rest of them are skipped")

    def _visuals(self, engine: Engine, events: dict[str, Any]) -> None:
        """Uniforms, post passes and anomalies the server's scripts set, drawn here; one
        this node cannot draw (its renderer refused it) is told and the rest go on."""
        control = engine.try_resource(ShaderControl)  # type: ignore[type-abstract]
        anomalies = engine.try_resource(Anomalies)
        for kind in ("uniforms", "post", "anomalies"):
            for record in events.get(kind, ()):
                try:
                    if kind == "anomalies" and anomalies is not None:
                        anomaly, what, enabled, onset, eye, values = record
                        if anomaly not in anomalies.states:
                            anomalies.declare(anomaly, kind=what)
                        anomalies.set(anomaly, "server", enabled=bool(enabled), onset=onset,
                                      eye=eye, values={k: _vector(v) for k, v in
                                                       values.items()})
                    elif kind == "uniforms" and control is not None:
                        state, name, value = record
                        control.set_uniform(state, name, _vector(value))
                    elif kind == "post" and control is not None and record[0] == "enable":
                        control.enable_post(record[1], bool(record[2]))
                    elif kind == "post" and control is not None:
                        _, name, uniform, value = record
                        control.set_post_uniform(name, uniform, _vector(value))
                except (KeyError, TypeError, ValueError, RuntimeError) as exc:
                    self.messages.warn(f"the server's {kind} {record!r} cannot be drawn "
                                       f"here ({exc}); skipped")

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
                if self._agreed is None:  # nothing agreed yet (the first frame, or the last
                    # wait ran out): agree before drawing; a wait that ran out is not waited
                    # again before the swap
                    self._agreed = self._barrier_round()
                    self._waited = self._agreed is None
                if self._agreed is not None:
                    found = self._pinned if self._pinned is not None else self._frame_at(
                        engine, self._agreed, time.monotonic() + self.barrier_wait)
                    self._agreed, self._pinned = None, None
                    if not follower.frames:
                        return  # the server restarted meanwhile: rejoined, nothing to draw yet
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

    def _barrier_round(self) -> int | None:
        """Wait at the swap barrier holding the frames held; the frame the round released
        (None, counted, when the wait ran out)."""
        frames = self.follower.frames
        agreed = self.client.wait_barrier(frames[0].frame, frames[-1].frame, self.barrier_wait)
        if agreed is None:
            self.counts["barrier misses"] += 1
        return agreed

    def before_swap(self) -> None:
        """The swap barrier between a frame drawn and its swap (this display's
        :class:`~engine.services.SwapGate`), once a frame: every display released in a
        round swaps then, and draws the frame the round released next."""
        if self._waited or not self.follower.frames:
            return
        self._waited = True
        self._agreed = self._barrier_round()
        # held on to now: frames arriving before it is drawn must not push it out
        self._pinned = None if self._agreed is None else self.follower.frame(self._agreed)

    def _frame_at(self, engine: Engine, number: int, end: float) -> Shown | None:
        """Frame ``number`` of those held, or of those arriving before ``end`` (the
        barrier agreed on a frame newer than this display's newest)."""
        follower, client = self.follower, self.client
        while (found := follower.frame(number)) is None and \
                number > follower.frames[-1].frame and \
                client.wait(max(end - time.monotonic(), 0.0)):
            wall = time.monotonic()
            for kind, header, blob in client.receive():
                if kind == protocol.BARRIER:
                    continue
                if header.get("epoch") != client.epoch:
                    self._rejoin(engine, 2.0)
                    return None
                self._take(engine, header, blob, wall)
        return found

    def _write(self, engine: Engine, ids: np.ndarray, rows: np.ndarray) -> None:
        cut = int(np.searchsorted(ids, BONE_FLAG))  # bodies first, then the avatars' bones
        if cut < len(ids):
            self._skeletons(engine, ids[cut:], rows[cut:, :7])
            ids, rows = ids[:cut], rows[:cut]
        table = engine.world.poses
        cached = self._rows
        if cached is None or cached[:2] != (self._layout, table.version) or \
                len(cached[3]) != len(ids) or (cached[3] != ids).any():
            found = table.rows([self.entity_of.get(int(n), -1) for n in ids.tolist()])
            cached = self._rows = (self._layout, table.version, found, ids)
        where = cached[2]
        have = where >= 0
        table.table[where[have]] = rows[have]

    def _skeletons(self, engine: Engine, ids: np.ndarray, poses: np.ndarray) -> None:
        """The avatars' joint matrices as the server drew them, for the renderer."""
        palettes = engine.resource(Palettes)
        owners, _ = split_bone_ids(ids)
        nets, starts = np.unique(owners, return_index=True)
        palettes.matrices = palette_matrices(poses)
        palettes.offsets = {self.entity_of[net]: int(start) for net, start in
                            zip(nets.tolist(), starts.tolist(), strict=True)
                            if net in self.entity_of}
        palettes.version += 1

    def _rejoin(self, engine: Engine, wait: float) -> bool:
        """Join the server again and rebuild from its state; a refusal or silence is told
        and tried again next frame (False)."""
        try:
            welcome = self.client.rejoin(wait)
        except NetError as exc:
            log.warning("%s; trying again", exc)
            return False
        self._resync(engine, welcome)
        return True

    def _resync(self, engine: Engine, welcome: dict[str, Any]) -> None:
        """Another server (a restart) or a lost place: build the world from its state."""
        self.counts["resyncs"] += 1
        log.info("resynchronising with %s at its frame %s", self.client.address,
                 welcome.get("frame"))
        self.decoder = PoseDecoder()
        self.follower.reset()
        self._frame = -1
        self._agreed, self._pinned = None, None  # the other server's frame numbers
        spec = node_scene(welcome, engine.config.content_dir or Path("."))
        for entity in list(engine.world.entities()):
            engine.despawn(entity)

        def rebuild() -> None:
            from engine.scene import instantiate

            instantiate(engine, spec)
            self._map_names(engine, welcome["names"])
            anomalies = engine.try_resource(Anomalies)
            for declared in spec.anomalies if anomalies is not None else ():
                if declared.id not in anomalies.states:
                    anomalies.declare(declared.id, kind=declared.kind)
                anomalies.set(declared.id, "server", enabled=declared.enabled,
                              values=declared.values, onset=declared.onset, eye=declared.eye)
            self._welcome = welcome  # its uniforms and post passes, at the next frame

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


def _vector(value: Any) -> Any:
    """A value from JSON as the engine holds it (vectors as tuples)."""
    return tuple(float(v) for v in value) if isinstance(value, list) else value


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


class SwapBarrierSystem(System):
    """A display's swap barrier on a frame it did not draw (a headless display draws only
    the frames it saves; a drawn one waited before its swap): waited at the frame's end,
    so the displays keep in step whether they draw or not."""

    phase = Phase.RENDER
    after = ("RenderSystem",)

    def __init__(self, follow: FollowSystem) -> None:
        self.follow = follow

    def run(self, engine: Engine, dt: float) -> None:
        self.follow.before_swap()


class NodePlugin:
    """Follows a server (``colosseum join``): no physics, no scripts of its own."""

    name = PluginName.NET_NODE

    def __init__(self, client: NetClient, welcome: dict[str, Any], display: bool = False,
                 barrier: bool = False) -> None:
        self.system = FollowSystem(client, welcome, display, barrier)

    def build(self, engine: Engine) -> None:
        engine.insert_resource(self.system)
        engine.insert_resource(Palettes())  # the server's skeletons, drawn here
        engine.add_system(self.system)
        if self.system.display and self.system.barrier:
            engine.insert_resource(self.system, as_type=SwapGate)
            engine.add_system(SwapBarrierSystem(self.system))
