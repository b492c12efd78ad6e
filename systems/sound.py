"""The sound system: Sound components and contacts → the SoundManager; camera → listener.

Every frame (POST_PHYSICS, after the poses and contacts of the step are in):

* a Sound with ``auto_play`` starts once (a looping one holds its source until
  its component or entity goes away); sounds on entities with a Transform are
  positional and follow it — position and velocity, so OpenAL applies Doppler —
  with one batched update for all of them; sounds on entities without one play
  at the listener;
* the listener takes the pose and velocity of the first active Camera's entity
  (its ``look_at`` wins over the orientation), looking along local +Y, Z up;
* the frame's Contacts batches go through a :class:`ContactSoundFilter` (bodies
  spawned in the last ``settle_time`` only settle); each contact that should
  sound plays its body's ``MaterialProps.contact_sound`` (body ``a``'s, else
  ``b``'s) at the contact point, gain from the impulse;
* the manager then reclaims sources, refills streams and serves its queue.

Scripts use :meth:`SoundSystem.play`, :meth:`SoundSystem.stop` and
:meth:`SoundSystem.set_gain` (``engine.resource(SoundSystem)``). Files are found
relative to the content folder, then its ``sounds/``. A file that cannot be
read logs one error naming it and its entity stays silent.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Camera, Name, Physical, Sound, Transform
from engine.assets import Assets
from engine.events import Contacts, Spawned
from engine.physics.backend import CONTACT_DTYPE
from engine.rotation import view_problem
from engine.services import SoundControl
from engine.system import Phase, PluginName, System
from services.audio import (
    ContactSoundFilter,
    ContactSoundSettings,
    SoundManager,
    Voice,
    create_audio_backend,
)

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.audio")

#: Priority of contact sounds: below authored sounds (0), so a burst never steals them.
CONTACT_PRIORITY = -1


class SoundSystem(System):
    phase = Phase.POST_PHYSICS
    reads = (Sound, Transform, Camera, Physical, Name)
    writes = ()

    def __init__(self, manager: SoundManager,
                 contact_settings: ContactSoundSettings | None = None) -> None:
        self.manager = manager
        self.contacts = ContactSoundFilter(contact_settings)
        self.contact_sounds = 0
        self._voices: dict[int, Voice] = {}
        self._new: list[int] = []  # entities whose Sound was just added
        self._started: set[int] = set()
        self._generation = -1  # the manager's generation the voice table matches
        self._content: Path | None = None
        self._paths: dict[str, str] = {}
        self._layout: int | None = None  # pose-table version the cached rows match
        self._rows = np.zeros(0, np.int64)
        self._placed: list[Voice] = []
        self._told_views: set[int] = set()  # cameras whose view direction was told wrong

    # -- life cycle -----------------------------------------------------------
    def setup(self, engine: Engine) -> None:
        self._content = engine.config.content_dir
        self.manager.assets = Assets.of(engine)  # the files the scene checked, decoded once
        for entity, _ in engine.world.get_component(Physical):
            self.contacts.settle(entity, engine.time)
        self._new = [entity for entity, _ in engine.world.get_component(Sound)]
        engine.world.on_add(Sound, lambda entity, _: self._new.append(entity))
        engine.world.on_remove(Sound, lambda entity, _: self._forget(entity))
        engine.world.on_remove(Transform, lambda entity, _: self.stop(entity))

    def run(self, engine: Engine, dt: float) -> None:
        if self._new:
            world, fresh, self._new = engine.world, self._new, []
            for entity in fresh:
                sound = world.try_component(entity, Sound)
                if sound is not None and sound.auto_play and entity not in self._started:
                    self.play(engine, entity)
        self._follow(engine)
        self._listen(engine)
        for spawned in engine.events.frame(Spawned):
            self.contacts.settle(spawned.entity, engine.time)
        batches = engine.events.frame(Contacts)
        if batches:
            batch = batches[0].batch if len(batches) == 1 else \
                np.concatenate([b.batch for b in batches])
        else:
            batch = _NO_CONTACTS
        self._contact_sounds(engine, batch)
        self.manager.update()

    def shutdown(self, engine: Engine) -> None:
        self.manager.close()
        self.manager.backend.close()

    # -- script API -------------------------------------------------------------
    def play(self, engine: Engine, entity: int) -> Voice | None:
        """(Re)start the entity's Sound; returns its Voice (None without a Sound)."""
        sound = engine.world.try_component(entity, Sound)
        if sound is None:
            return None
        self.stop(entity)
        self._started.add(entity)
        transform = engine.world.try_component(entity, Transform)
        voice = self.manager.play(
            self.resolve(sound.file), loop=sound.loop, gain=sound.gain, pitch=sound.pitch,
            ref_distance=sound.ref_distance, rolloff=sound.rolloff,
            max_distance=sound.max_distance, priority=sound.priority,
            position=None if transform is None else transform.position.copy(),
            velocity=None if transform is None else transform.linear_velocity.copy())
        if voice.active:
            self._voices[entity] = voice
            self._layout = None
        return voice

    def stop(self, entity: int) -> None:
        voice = self._voices.pop(entity, None)
        if voice is not None:
            self._layout = None
            self.manager.stop(voice)

    def set_gain(self, entity: int, gain: float) -> None:
        voice = self._voices.get(entity)
        if voice is not None:
            self.manager.set_gain(voice, gain)

    def resolve(self, file: str) -> str:
        """A sound file's path: absolute, or in the content folder, or in its sounds/."""
        found = self._paths.get(file)
        if found is not None:
            return found
        path = Path(file)
        if not path.is_absolute() and self._content is not None:
            for candidate in (self._content / path, self._content / "sounds" / path):
                if candidate.is_file():
                    path = candidate
                    break
            else:
                path = self._content / path
        self._paths[file] = str(path)
        return str(path)

    def stats(self) -> dict[str, Any]:
        """The manager's counters plus contact-sound ones, for ``--stats``."""
        return {**self.manager.stats(), "contact_sounds": self.contact_sounds}

    # -- per frame ---------------------------------------------------------------
    def _forget(self, entity: int) -> None:
        self.stop(entity)
        self._started.discard(entity)

    def _follow(self, engine: Engine) -> None:
        """Move every playing positional voice to its entity's pose, in one batch."""
        voices = self._voices
        finished = False
        if self._generation != self.manager.generation:  # some voice changed state
            self._generation = self.manager.generation
            ended = [e for e, v in voices.items() if not v.active]
            for entity in ended:
                del voices[entity]
            finished = bool(ended)
        if not voices:
            return
        poses = engine.world.poses
        if finished or self._layout != poses.version:
            rows = poses.rows(voices)
            keep = np.array([r >= 0 and v.positional
                             for v, r in zip(voices.values(), rows.tolist(), strict=True)])
            self._placed = [v for v, k in zip(voices.values(), keep, strict=True) if k]
            self._rows = rows[keep]
            self._layout = poses.version
        if len(self._rows):
            self.manager.move(self._placed, poses.position[self._rows],
                              poses.linear_velocity[self._rows])

    def _listen(self, engine: Engine) -> None:
        world = engine.world
        for entity, camera in world.get_component(Camera):
            if not camera.active:
                continue
            holder = entity if camera.follow is None else camera.follow
            t = world.try_component(holder, Transform)
            if t is None:
                return
            position = t.position + np.asarray(camera.offset) if camera.follow is not None \
                else t.position
            if camera.look_at is not None:
                forward = np.asarray(camera.look_at, np.float64) - position
                problem = view_problem(forward) if camera.follow is None else None
                if problem is not None and entity not in self._told_views:
                    self._told_views.add(entity)  # once per camera (a script may move it)
                    named = world.try_component(entity, Name)
                    log.warning("camera %r: %s; 3D sound is unpanned and the view meaningless "
                                "until it looks elsewhere", named.id if named else entity,
                                problem)
                self.manager.set_listener_axes(position, forward, (0.0, 0.0, 1.0),
                                               t.linear_velocity)
            else:
                self.manager.set_listener(position, t.orientation, t.linear_velocity)
            return

    def _contact_sounds(self, engine: Engine, batch: np.ndarray) -> None:
        hits = self.contacts.process(batch, engine.time)
        if not hits:
            return
        world = engine.world
        for hit in hits:
            file = None
            for body in (hit.a, hit.b):
                physical = world.try_component(body, Physical) if body >= 0 else None
                if physical is not None and physical.material.contact_sound:
                    file = physical.material.contact_sound
                    break
            if file is not None:
                self.play_contact(file, hit.gain, hit.position)

    def play_contact(self, file: str, gain: float, position: np.ndarray) -> None:
        """A contact's sound at its point (a network node plays the server's this way)."""
        self.contact_sounds += 1
        self.manager.play(self.resolve(file), gain=gain, position=position,
                          priority=CONTACT_PRIORITY)


_NO_CONTACTS = np.zeros(0, dtype=CONTACT_DTYPE)


class SoundPlugin:
    """Opens the audio backend named by ``--sound`` and adds the sound system."""

    name = PluginName.SOUND

    def __init__(self, spec: str | None = None, *, pool_size: int | None = None,
                 hrtf: bool = False, distance_model: str = "inverse_clamped",
                 queue_deadline: float = 0.1,
                 contact_settings: ContactSoundSettings | None = None) -> None:
        self.spec = spec
        self.pool_size = pool_size
        self.hrtf = hrtf
        self.distance_model = distance_model
        self.queue_deadline = queue_deadline
        self.contact_settings = contact_settings
        self.system: SoundSystem | None = None

    def build(self, engine: Engine) -> None:
        spec = self.spec or engine.config.sound
        backend = create_audio_backend(spec, hrtf=self.hrtf)
        manager = SoundManager(backend, pool_size=self.pool_size,
                               distance_model=self.distance_model,
                               queue_deadline=self.queue_deadline)
        self.system = SoundSystem(manager, self.contact_settings)
        engine.insert_resource(manager)
        engine.insert_resource(self.system)
        engine.insert_resource(self.system, as_type=SoundControl)
        engine.add_system(self.system)
        engine.stat_sources["sound"] = self.system.stats
