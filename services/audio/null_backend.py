"""The silent backend: no device, but sources play for as long as their sound lasts.

Keeping real durations (on the wall clock, like a device would) means the
SoundManager's pooling, queueing and counters behave exactly as with OpenAL, so
``--sound null`` runs report the same kind of statistics.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np


@dataclass(slots=True)
class _Source:
    buffers: list[int] = field(default_factory=list)
    started: float | None = None
    pitch: float = 1.0
    looping: bool = False
    consumed: int = 0  # queued buffers already played before ``started``


class NullBackend:
    """An AudioBackend that outputs nothing."""

    name = "null"

    def __init__(self, mono_sources: int = 255,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.mono_sources = mono_sources
        self._clock = clock
        self._sources: dict[int, _Source] = {}
        self._durations: dict[int, float] = {}
        self._next = 1

    def _ids(self, count: int) -> list[int]:
        ids = list(range(self._next, self._next + count))
        self._next += count
        return ids

    def gen_sources(self, count: int) -> list[int]:
        ids = self._ids(count)
        for i in ids:
            self._sources[i] = _Source()
        return ids

    def delete_sources(self, sources: list[int]) -> None:
        for i in sources:
            self._sources.pop(i, None)

    def gen_buffers(self, count: int) -> list[int]:
        ids = self._ids(count)
        for i in ids:
            self._durations[i] = 0.0
        return ids

    def delete_buffers(self, buffers: list[int]) -> None:
        for i in buffers:
            self._durations.pop(i, None)

    def buffer_data(self, buffer: int, pcm: np.ndarray, rate: int) -> None:
        self._durations[buffer] = len(pcm) / float(rate)

    def configure(self, source: int, *, gain: float, pitch: float, ref_distance: float,
                  rolloff: float, max_distance: float, looping: bool, relative: bool,
                  distance_model: str | None) -> None:
        src = self._sources[source]
        src.pitch = max(pitch, 1e-6)
        src.looping = looping

    def set_gain(self, source: int, gain: float) -> None:
        pass

    def set_pitch(self, source: int, pitch: float) -> None:
        self._sources[source].pitch = max(pitch, 1e-6)

    def attach(self, source: int, buffer: int) -> None:
        src = self._sources[source]
        src.buffers = [buffer] if buffer else []
        src.started = None
        src.consumed = 0

    def queue(self, source: int, buffers: list[int]) -> None:
        self._sources[source].buffers.extend(buffers)

    def _played(self, src: _Source) -> int:
        """How many of the queued buffers have finished playing by now."""
        if src.started is None:
            return src.consumed
        elapsed = (self._clock() - src.started) * src.pitch
        done = src.consumed
        for buf in src.buffers[src.consumed:]:
            length = self._durations.get(buf, 0.0)
            if elapsed < length:
                break
            elapsed -= length
            done += 1
        return done

    def unqueue_processed(self, source: int) -> list[int]:
        src = self._sources[source]
        if src.looping:
            return []
        done = self._played(src)
        if done == 0:
            return []
        if src.started is not None:
            src.started += sum(self._durations.get(b, 0.0) for b in src.buffers[:done]) \
                / src.pitch
        finished, src.buffers = src.buffers[:done], src.buffers[done:]
        src.consumed = 0
        return finished

    def play(self, source: int) -> None:
        src = self._sources[source]
        src.started = self._clock()

    def stop(self, source: int) -> None:
        src = self._sources[source]
        src.consumed = len(src.buffers)
        src.started = None

    def playing(self, source: int) -> bool:
        src = self._sources[source]
        if src.started is None or not src.buffers:
            return False
        return src.looping or self._played(src) < len(src.buffers)

    def set_poses(self, sources: list[int], positions: np.ndarray,
                  velocities: np.ndarray) -> None:
        pass

    def place(self, source: int, position: np.ndarray, velocity: np.ndarray) -> None:
        pass

    def set_listener(self, position: np.ndarray, velocity: np.ndarray, forward: np.ndarray,
                     up: np.ndarray, gain: float) -> None:
        pass

    def set_distance_model(self, model: str) -> None:
        pass

    def close(self) -> None:
        self._sources.clear()
        self._durations.clear()
