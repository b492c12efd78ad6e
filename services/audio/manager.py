"""The SoundManager: brokers a fixed pool of sources among many sound requests.

Contact sounds come in bursts of hundreds while a device mixes a few dozen
sources, so every request goes through this pool (Colosseum3D, section 3.3).

Policy, in order:

* **Loops and streams are exclusive.** A looping sound, or any file longer than
  ``stream_threshold`` seconds (streamed through a queue of buffers), holds its
  source until stopped and is never stolen. When no source is free it takes the
  source of the oldest playing one-shot of the lowest priority (counted as
  *stolen*); when every source is exclusive it waits (state ``pending``) and
  starts as soon as one frees, before any waiting one-shot.
* **One-shots are first-in, first-out.** A one-shot plays on a free source. With
  none free it takes the source of the oldest playing one-shot of *strictly
  lower* priority, if any (*stolen*); otherwise it waits in the queue (*queued*)
  for at most ``queue_deadline`` seconds, then is *dropped*: a late contact sound
  is wrong, not merely late. Waiting requests are served highest priority first,
  first-come first-served within a priority, and before newer requests. When
  more than ``queue_limit`` wait, the oldest request of the lowest waiting
  priority is dropped.
* Every request ends as exactly one of played, dropped, failed (unreadable file)
  or cancelled (stopped while waiting); :meth:`SoundManager.stats` reports them.
  Stolen one-shots were played, and are counted as such too.

Time is wall-clock (``time.monotonic``): sources play in real time whatever pace
the simulation runs at. Call :meth:`SoundManager.update` once per frame: it
reclaims finished sources, refills streams and serves the queue.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from engine.assets import AssetError, Assets
from engine.assets.sound import AudioFileError, StreamReader
from services.audio.backend import DISTANCE_MODELS, AudioBackend, listener_axes

log = logging.getLogger("colosseum.audio")

_ZERO = np.zeros(3)


@dataclass(slots=True, eq=False)
class Voice:
    """One request to play a sound, and the handle its owner keeps.

    ``state``: queued, pending (exclusive, waiting), playing, done, dropped,
    stolen, failed or stopped. ``position is None`` means non-positional (played
    at the listener, stereo kept).
    """

    file: str
    loop: bool = False
    gain: float = 1.0
    pitch: float = 1.0
    ref_distance: float = 1.0
    rolloff: float = 1.0
    max_distance: float = 1000.0
    priority: int = 0
    distance_model: str | None = None
    position: np.ndarray | None = None
    velocity: np.ndarray = field(default_factory=lambda: _ZERO.copy())
    state: str = "new"
    source: int | None = None
    requested: float = 0.0
    started: float = 0.0
    ends_at: float = float("inf")
    error: str | None = None
    _buffer: int = 0
    _duration: float = 0.0
    _stream: _Stream | None = None
    _seq: int = 0

    @property
    def positional(self) -> bool:
        return self.position is not None

    @property
    def exclusive(self) -> bool:
        return self.loop or self._stream is not None

    @property
    def active(self) -> bool:
        return self.state in ("queued", "pending", "playing")


@dataclass(slots=True)
class _Stream:
    reader: StreamReader
    buffers: list[int]
    in_flight: int = 0


@dataclass(slots=True)
class SoundStats:
    requests: int = 0
    played: int = 0
    queued: int = 0
    dropped: int = 0
    stolen: int = 0
    failed: int = 0
    cancelled: int = 0
    underruns: int = 0
    streamed: int = 0


class SoundManager:
    """A pool of backend sources shared by one-shots, loops and streams."""

    def __init__(self, backend: AudioBackend, pool_size: int | None = None,
                 queue_deadline: float = 0.1, queue_limit: int | None = None,
                 stream_threshold: float = 2.0, stream_block: int = 8192,
                 stream_buffers: int = 4, distance_model: str = "inverse_clamped",
                 clock: Callable[[], float] = time.monotonic,
                 assets: Assets | None = None) -> None:
        size = min(backend.mono_sources, 32) if pool_size is None else pool_size
        if size < 1:
            raise ValueError(f"pool_size must be at least 1, not {size}")
        self.backend = backend
        self.pool_size = size
        self.queue_deadline = queue_deadline
        self.queue_limit = 4 * size if queue_limit is None else queue_limit
        self.stream_threshold = stream_threshold
        self.stream_block = stream_block
        self.stream_buffers = stream_buffers
        self.clock = clock
        #: Where sound files are read and decoded (the run's shared cache).
        self.assets = assets if assets is not None else Assets()
        self.counters = SoundStats()
        #: Bumped whenever a voice starts or ends, so callers can skip rescanning theirs.
        self.generation = 0
        self._free: list[int] = backend.gen_sources(size)[::-1]
        self._active: dict[int, Voice] = {}
        self._queue: dict[int, deque[Voice]] = {}  # priority -> waiting one-shots, FIFO
        self._waiting = 0
        self._shots: dict[int, deque[Voice]] = {}  # priority -> playing one-shots, oldest first
        self._shot_entries = 0
        self._pending: deque[Voice] = deque()
        self._cache: dict[tuple[str, bool], tuple[int, float]] = {}
        self._reported: set[str] = set()
        self._warned_stereo: set[str] = set()
        self._seq = 0
        self.set_distance_model(distance_model)

    # -- requests -------------------------------------------------------------
    def play(self, file: str | Path, *, loop: bool = False, gain: float = 1.0,
             pitch: float = 1.0, ref_distance: float = 1.0, rolloff: float = 1.0,
             max_distance: float = 1000.0, priority: int = 0,
             position: Sequence[float] | np.ndarray | None = None,
             velocity: Sequence[float] | np.ndarray | None = None,
             distance_model: str | None = None) -> Voice:
        """Request a sound; returns its Voice at once, whether it plays, waits or fails.

        ``position`` (engine frame) makes it positional (mono); None plays it at the
        listener. An unreadable file logs one error naming it and yields a silent,
        ``failed`` Voice: the caller keeps running.
        """
        now = self.clock()
        self._seq += 1
        voice = Voice(str(file), loop, gain, pitch, ref_distance, rolloff, max_distance,
                      priority, distance_model,
                      None if position is None else np.array(position, dtype=np.float64),
                      _ZERO.copy() if velocity is None else np.array(velocity, np.float64),
                      requested=now, _seq=self._seq)
        self.counters.requests += 1
        try:
            self._prepare(voice)
        except (AssetError, AudioFileError) as exc:
            self.counters.failed += 1
            voice.state, voice.error = "failed", str(exc)
            told = self.assets.mark_told(exc) if isinstance(exc, AssetError) else \
                voice.file not in self._reported
            self._reported.add(voice.file)
            if told:
                log.error("%s (the sound stays silent)", exc)
            return voice
        if voice.exclusive:
            source = self._take_source(voice, steal_any=True)
            if source is None:
                voice.state = "pending"
                self._pending.append(voice)
            else:
                self._start(voice, source, now)
            return voice
        if self._waiting and self._free:  # a source freed since the last update
            self._serve(now)  # goes to those who waited first
        source = self._take_source(voice, steal_any=False)
        if source is not None:
            self._start(voice, source, now)
            return voice
        self.counters.queued += 1
        voice.state = "queued"
        line = self._queue.get(voice.priority)
        if line is None:
            line = self._queue[voice.priority] = deque()
        line.append(voice)
        self._waiting += 1
        if self._waiting > self.queue_limit:
            lowest = min(self._queue)
            self._drop(self._dequeue(lowest))
        return voice

    def stop(self, voice: Voice) -> None:
        """Stop a voice wherever it is (playing, queued or pending)."""
        self.generation += 1
        if voice.state == "queued":
            self._queue[voice.priority].remove(voice)
            self._waiting -= 1
            if not self._queue[voice.priority]:
                del self._queue[voice.priority]
            self.counters.cancelled += 1
        elif voice.state == "pending":
            self._pending.remove(voice)
            self.counters.cancelled += 1
        elif voice.state == "playing":
            self._release(voice)
        else:
            return
        voice.state = "stopped"

    def set_gain(self, voice: Voice, gain: float) -> None:
        voice.gain = gain
        if voice.source is not None:
            self.backend.set_gain(voice.source, gain)

    def set_pitch(self, voice: Voice, pitch: float) -> None:
        voice.pitch = pitch
        if voice.source is not None:
            self.backend.set_pitch(voice.source, pitch)

    def move(self, voices: Sequence[Voice], positions: np.ndarray,
             velocities: np.ndarray | None = None) -> None:
        """Move positional voices (engine frame, ``(n, 3)``); one backend batch."""
        if velocities is None:
            velocities = np.zeros_like(positions)
        sources = [v.source for v in voices]
        if None not in sources and all(v.position is not None for v in voices):
            self.backend.set_poses(sources, positions, velocities)  # type: ignore[arg-type]
            return
        rows = []
        for i, voice in enumerate(voices):
            if voice.position is None:
                continue
            if voice.source is None:  # waiting: remember where it will start
                voice.position = positions[i].copy()
                voice.velocity = velocities[i].copy()
            else:
                rows.append(i)
        if rows:
            self.backend.set_poses([sources[i] for i in rows],  # type: ignore[misc]
                                   positions[rows], velocities[rows])

    def set_listener(self, position: Sequence[float] | np.ndarray,
                     orientation: Sequence[float] | np.ndarray = (1.0, 0.0, 0.0, 0.0),
                     velocity: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
                     gain: float = 1.0) -> None:
        """Place the listener: a camera pose (it looks along local +Y, Z up)."""
        forward, up = listener_axes(np.asarray(orientation, dtype=np.float64))
        self.backend.set_listener(np.asarray(position, np.float64),
                                  np.asarray(velocity, np.float64), forward, up, gain)

    def set_listener_axes(self, position: Sequence[float] | np.ndarray,
                          forward: Sequence[float] | np.ndarray,
                          up: Sequence[float] | np.ndarray = (0.0, 0.0, 1.0),
                          velocity: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
                          gain: float = 1.0) -> None:
        """Place the listener by explicit engine-frame axes (a camera's look-at)."""
        f = np.asarray(forward, np.float64)
        u = np.asarray(up, np.float64)
        u = u - f * (f @ u) / max(f @ f, 1e-12)  # OpenAL wants them orthogonal
        if u @ u < 1e-12:  # looking straight along "up": any perpendicular will do
            u = np.array([0.0, 1.0, 0.0]) if abs(f[1]) < abs(f[0]) + abs(f[2]) else \
                np.array([1.0, 0.0, 0.0])
        self.backend.set_listener(np.asarray(position, np.float64),
                                  np.asarray(velocity, np.float64), f, u, gain)

    def set_distance_model(self, model: str) -> None:
        if model not in DISTANCE_MODELS:
            raise ValueError(f"unknown distance model {model!r}; "
                             f"choose one of {', '.join(DISTANCE_MODELS)}")
        self.distance_model = model
        self.backend.set_distance_model(model)

    # -- per frame --------------------------------------------------------------
    def update(self) -> None:
        """Reclaim finished sources, refill streams, serve waiting requests."""
        now = self.clock()
        for voice in list(self._active.values()):
            if voice._stream is not None:
                self._refill(voice)
            elif not voice.loop and now >= voice.ends_at \
                    and not self.backend.playing(voice.source):  # type: ignore[arg-type]
                self._release(voice)
                voice.state = "done"
        while self._pending:
            source = self._take_source(self._pending[0], steal_any=True)
            if source is None:
                break
            self._start(self._pending.popleft(), source, now)
        if self._queue:
            self._serve(now)

    def stats(self) -> dict[str, int | float | str]:
        """Counters for ``--stats``: every request is played, dropped, failed or cancelled."""
        c = self.counters
        return {
            "backend": self.backend.name,
            "pool_size": self.pool_size,
            "requests": c.requests,
            "played": c.played,
            "queued": c.queued,
            "dropped": c.dropped,
            "stolen": c.stolen,
            "failed": c.failed,
            "cancelled": c.cancelled,
            "waiting": self._waiting + len(self._pending),
            "active": len(self._active),
            "streamed": c.streamed,
            "underruns": c.underruns,
        }

    @property
    def voices(self) -> list[Voice]:
        """Voices holding a source now."""
        return list(self._active.values())

    def close(self) -> None:
        """Stop everything and free every source and buffer this manager made."""
        for voice in list(self._active.values()):
            self._release(voice)
            voice.state = "stopped"
        for line in (*self._queue.values(), self._pending):
            for voice in line:
                voice.state = "stopped"
        self._queue.clear()
        self._waiting = 0
        self._pending.clear()
        self.backend.delete_sources(self._free)
        self._free = []
        self.backend.delete_buffers([buf for buf, _ in self._cache.values()])
        self._cache.clear()

    # -- internals -------------------------------------------------------------
    def _prepare(self, voice: Voice) -> None:
        """Find the file's buffer (decoding it once) or open a stream for a long file."""
        mono = voice.positional
        cached = self._cache.get((voice.file, mono))
        if cached is not None:
            voice._buffer, voice._duration = cached
            return
        info = self.assets.sound(voice.file)
        if mono and info.channels > 1 and voice.file not in self._warned_stereo:
            self._warned_stereo.add(voice.file)
            log.warning("%s: warning: %d-channel sound used by a positional source; mixed "
                        "down to mono (OpenAL spatialises mono sounds only)",
                        voice.file, info.channels)
        if info.duration > self.stream_threshold:
            voice._stream = _Stream(StreamReader(info, mono, voice.loop), [])
            return
        clip = self.assets.clip(voice.file, mono)
        (buffer,) = self.backend.gen_buffers(1)
        self.backend.buffer_data(buffer, clip.pcm, clip.rate)
        self._cache[(voice.file, mono)] = (buffer, clip.duration)
        voice._buffer, voice._duration = buffer, clip.duration

    def _take_source(self, voice: Voice, steal_any: bool) -> int | None:
        """A free source, or the one of the oldest playing one-shot of the lowest
        priority (below ``voice``'s unless ``steal_any``); None if there is neither."""
        if self._free:
            return self._free.pop()
        for priority in sorted(self._shots):
            if not steal_any and priority >= voice.priority:
                break
            line = self._shots[priority]
            while line:
                victim = line.popleft()
                self._shot_entries -= 1
                if victim.state == "playing" and not victim.exclusive:
                    source = victim.source
                    self._release(victim, free=False)
                    victim.state = "stolen"
                    self.counters.stolen += 1
                    if not line:
                        del self._shots[priority]
                    return source
            del self._shots[priority]
        return None

    def _track_shot(self, voice: Voice) -> None:
        """Remember a playing one-shot for stealing; finished ones are pruned lazily."""
        line = self._shots.get(voice.priority)
        if line is None:
            line = self._shots[voice.priority] = deque()
        line.append(voice)
        self._shot_entries += 1
        if self._shot_entries > 4 * self.pool_size:
            for key in list(self._shots):
                kept = deque(v for v in self._shots[key] if v.state == "playing")
                if kept:
                    self._shots[key] = kept
                else:
                    del self._shots[key]
            self._shot_entries = sum(len(line) for line in self._shots.values())

    def _start(self, voice: Voice, source: int, now: float) -> None:
        self.generation += 1
        b = self.backend
        voice.source = source
        voice.state = "playing"
        voice.started = now
        self._active[source] = voice
        b.configure(source, gain=voice.gain, pitch=voice.pitch,
                    ref_distance=voice.ref_distance, rolloff=voice.rolloff,
                    max_distance=voice.max_distance,
                    looping=voice.loop and voice._stream is None,
                    relative=voice.position is None, distance_model=voice.distance_model)
        if voice.position is not None:
            b.place(source, voice.position, voice.velocity)
        self.counters.played += 1
        stream = voice._stream
        if stream is None:
            if not voice.loop:
                self._track_shot(voice)
            b.attach(source, voice._buffer)
            voice.ends_at = now + voice._duration / max(voice.pitch, 1e-6)
            b.play(source)
            return
        self.counters.streamed += 1
        b.attach(source, 0)
        stream.buffers = b.gen_buffers(self.stream_buffers)
        self._feed(voice, stream.buffers)
        b.play(source)

    def _feed(self, voice: Voice, buffers: list[int]) -> None:
        stream = voice._stream
        assert stream is not None and voice.source is not None
        filled: list[int] = []
        for buf in buffers:
            try:
                pcm = stream.reader.read(self.stream_block)
            except AudioFileError as exc:
                if voice.file not in self._reported:
                    self._reported.add(voice.file)
                    log.error("%s (the stream stops)", exc)
                break
            if len(pcm) == 0:
                break
            self.backend.buffer_data(buf, pcm, stream.reader.rate)
            filled.append(buf)
        if filled:
            self.backend.queue(voice.source, filled)
            stream.in_flight += len(filled)

    def _refill(self, voice: Voice) -> None:
        stream = voice._stream
        assert stream is not None and voice.source is not None
        done = self.backend.unqueue_processed(voice.source)
        stream.in_flight -= len(done)
        if done and not stream.reader.finished:
            self._feed(voice, done)
        if not self.backend.playing(voice.source):
            if stream.in_flight > 0:
                self.counters.underruns += 1  # the engine loop stalled longer than the queue
                self.backend.play(voice.source)
            else:
                self._release(voice)
                voice.state = "done"

    def _release(self, voice: Voice, free: bool = True) -> None:
        source = voice.source
        if source is None:
            return
        self.generation += 1
        b = self.backend
        b.stop(source)
        stream = voice._stream
        if stream is not None:
            b.attach(source, 0)
            b.delete_buffers(stream.buffers)
            stream.reader.close()
            voice._stream = None
        del self._active[source]
        voice.source = None
        if free:
            self._free.append(source)

    def _serve(self, now: float) -> None:
        """Drop waiting one-shots past their deadline, start the rest on free sources."""
        oldest_allowed = now - self.queue_deadline
        for priority in list(self._queue):  # each line is in request order
            line = self._queue[priority]
            while line and line[0].requested < oldest_allowed:
                self._drop(self._dequeue(priority))
        while self._queue and self._free:
            self._start(self._dequeue(max(self._queue)), self._free.pop(), now)

    def _dequeue(self, priority: int) -> Voice:
        """The oldest waiting one-shot of ``priority``."""
        line = self._queue[priority]
        voice = line.popleft()
        if not line:
            del self._queue[priority]
        self._waiting -= 1
        return voice

    def _drop(self, voice: Voice) -> None:
        self.generation += 1
        voice.state = "dropped"
        self.counters.dropped += 1
