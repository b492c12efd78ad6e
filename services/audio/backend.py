"""The AudioBackend protocol and the one place engine space becomes OpenAL space.

Axes. The engine is right-handed with Z up; a camera (and so the listener) looks
along its local +Y with local +Z up and +X to its right (the renderer's
convention, see ``services.render.math3d``). OpenAL is right-handed with Y up and
a listener that looks down -Z. :func:`to_al` maps engine ``(x, y, z)`` to OpenAL
``(x, z, -y)``: engine +X (right) stays +X, engine +Y (forward) becomes -Z,
engine +Z (up) becomes +Y. Every position, velocity and listener axis passes
through it (or through :data:`ENGINE_TO_AL`) and nowhere else.

Backends address sources and buffers by plain integer ids and move poses in
batches, so the SoundManager above them costs a few calls per source per frame.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from engine.rotation import quat_to_matrix

#: Rotation taking engine axes (Z up, camera forward +Y) to OpenAL axes (Y up, forward -Z).
ENGINE_TO_AL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

#: Distance models by the names a scene or the CLI use.
DISTANCE_MODELS = (
    "none",
    "inverse",
    "inverse_clamped",
    "linear",
    "linear_clamped",
    "exponent",
    "exponent_clamped",
)


def to_al(vectors: np.ndarray) -> np.ndarray:
    """Engine-frame vectors ``(..., 3)`` in OpenAL's frame (x, z, -y)."""
    v = np.asarray(vectors, dtype=np.float64)
    out = np.empty(v.shape)
    out[..., 0] = v[..., 0]
    out[..., 1] = v[..., 2]
    out[..., 2] = -v[..., 1]
    return out


def listener_axes(orientation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Engine-frame (forward, up) of a camera with quaternion ``(w, x, y, z)``."""
    rot = quat_to_matrix(orientation)
    return rot[:, 1], rot[:, 2]


def inverse_clamped_gain(distance: float, ref_distance: float = 1.0, rolloff: float = 1.0,
                         max_distance: float = 1000.0) -> float:
    """OpenAL's AL_INVERSE_DISTANCE_CLAMPED attenuation (the engine default)."""
    d = min(max(distance, ref_distance), max_distance)
    return ref_distance / (ref_distance + rolloff * (d - ref_distance))


class AudioError(RuntimeError):
    """Base of audio failures."""


class AudioDeviceError(AudioError):
    """The audio device could not be opened or used."""


@runtime_checkable
class AudioBackend(Protocol):
    """What the SoundManager needs from an audio library. Vectors are engine-frame."""

    name: str
    #: How many mono (positional) sources the device can play at once.
    mono_sources: int

    def gen_sources(self, count: int) -> list[int]: ...
    def delete_sources(self, sources: list[int]) -> None: ...
    def gen_buffers(self, count: int) -> list[int]: ...
    def delete_buffers(self, buffers: list[int]) -> None: ...

    def buffer_data(self, buffer: int, pcm: np.ndarray, rate: int) -> None:
        """Fill ``buffer`` with int16 frames ``(n, channels)``, channels 1 or 2."""

    def configure(self, source: int, *, gain: float, pitch: float, ref_distance: float,
                  rolloff: float, max_distance: float, looping: bool, relative: bool,
                  distance_model: str | None) -> None:
        """Set a source's static properties before it plays (rewinds nothing)."""

    def set_gain(self, source: int, gain: float) -> None: ...
    def set_pitch(self, source: int, pitch: float) -> None: ...
    def attach(self, source: int, buffer: int) -> None:
        """Make ``buffer`` the source's only buffer (0 detaches every buffer)."""

    def queue(self, source: int, buffers: list[int]) -> None: ...
    def unqueue_processed(self, source: int) -> list[int]: ...
    def play(self, source: int) -> None: ...
    def stop(self, source: int) -> None: ...
    def playing(self, source: int) -> bool: ...

    def set_poses(self, sources: list[int], positions: np.ndarray,
                  velocities: np.ndarray) -> None:
        """Move many sources at once; positions and velocities are ``(n, 3)``."""

    def place(self, source: int, position: np.ndarray, velocity: np.ndarray) -> None:
        """Move one source (as it starts)."""

    def set_listener(self, position: np.ndarray, velocity: np.ndarray, forward: np.ndarray,
                     up: np.ndarray, gain: float) -> None: ...
    def set_distance_model(self, model: str) -> None: ...
    def close(self) -> None: ...
