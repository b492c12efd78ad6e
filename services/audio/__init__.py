"""3D sound: audio backends picked by name, decoding, streaming and the SoundManager.

Backends (``--sound`` on ``colosseum run``):

* ``openal`` — the default sound device through OpenAL Soft;
* ``wave:FILE`` — OpenAL Soft's wave writer: a headless run records what the
  listener hears, in real time, to ``FILE`` (32-bit float stereo, 44.1 kHz);
* ``null`` — silent, but sources keep their real durations so pooling and the
  statistics behave as with a device.

Axes: engine Z-up vectors become OpenAL's Y-up ones in :func:`services.audio.backend.to_al`
only; the listener looks along its camera's local +Y with +Z up (as the renderer).

>>> backend = create_audio_backend("null")
>>> manager = SoundManager(backend, pool_size=4)
>>> manager.stats()["pool_size"]
4
"""

from __future__ import annotations

import logging
from pathlib import Path

from engine.assets.sound import AudioFileError, Clip, StreamReader, load_clip, probe
from services.audio.backend import (
    DISTANCE_MODELS,
    ENGINE_TO_AL,
    AudioBackend,
    AudioDeviceError,
    AudioError,
    inverse_clamped_gain,
    listener_axes,
    to_al,
)
from services.audio.contacts import ContactSoundFilter, ContactSoundSettings
from services.audio.manager import SoundManager, Voice
from services.audio.null_backend import NullBackend

log = logging.getLogger("colosseum.audio")

BACKEND_NAMES = ("openal", "wave:FILE", "null")
_fell_back: list[str] = []  # device failures already reported in this process


def create_audio_backend(spec: str, *, hrtf: bool = False,
                         fallback: bool = True) -> AudioBackend:
    """The backend named by ``spec``: ``openal``, ``wave:FILE`` or ``null``.

    When the device cannot be opened (no sound card, no libopenal) the run goes
    on silently with ``null`` after one warning (per process), unless ``fallback``
    is False.
    An unknown name is always an error.
    """
    name, _, arg = spec.partition(":")
    if name == "null" and not arg:
        return NullBackend()
    if name not in ("openal", "wave") or (name == "openal" and arg) \
            or (name == "wave" and not arg):
        raise ValueError(f"unknown sound backend {spec!r}; choose one of "
                         f"{', '.join(BACKEND_NAMES)}")
    from services.audio.openal_backend import OpenALBackend

    try:
        return OpenALBackend(wave_file=Path(arg) if name == "wave" else None, hrtf=hrtf)
    except AudioDeviceError as exc:
        if not fallback:
            raise
        report = log.debug if _fell_back else log.warning
        _fell_back.append(str(exc))
        report("%s; sound disabled (using the null backend)", exc)
        return NullBackend()


__all__ = [
    "BACKEND_NAMES",
    "DISTANCE_MODELS",
    "ENGINE_TO_AL",
    "AudioBackend",
    "AudioDeviceError",
    "AudioError",
    "AudioFileError",
    "Clip",
    "ContactSoundFilter",
    "ContactSoundSettings",
    "NullBackend",
    "SoundManager",
    "StreamReader",
    "Voice",
    "create_audio_backend",
    "inverse_clamped_gain",
    "listener_axes",
    "load_clip",
    "probe",
    "to_al",
]
