"""Sound files: decoded with soundfile (libsndfile) into 16-bit PCM for OpenAL.

Part of the asset layer (any engine part may read a sound's header or samples);
the audio service plays what is decoded here.

Any format libsndfile reads works: WAV (8/16/24/32-bit PCM, 32/64-bit float),
Ogg Vorbis, FLAC, AIFF. Samples are decoded as float, clipped to [-1, 1] and
scaled to int16, because OpenAL 1.1 takes 8- or 16-bit buffers only.
Positional sources need mono (OpenAL plays multi-channel buffers unspatialised),
so they get a mixdown (the channel mean).

Short files are decoded whole (:func:`load_clip`); long ones are read block by
block (:class:`StreamReader`) so a ten-minute ambience never sits in memory.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: Sample rates a sound may have: outside these a header is broken, not unusual audio.
MIN_SAMPLE_RATE = 1_000
MAX_SAMPLE_RATE = 384_000


class AudioFileError(RuntimeError):
    """A sound file is missing, truncated or in a format libsndfile cannot read."""

    def __init__(self, path: str | Path, reason: str) -> None:
        super().__init__(f"{path}: error: {reason}")
        self.path = str(path)
        self.reason = reason


@dataclass(frozen=True, slots=True)
class SoundInfo:
    path: str
    rate: int
    channels: int
    frames: int

    @property
    def duration(self) -> float:
        return self.frames / float(self.rate)


@dataclass(frozen=True, slots=True)
class Clip:
    """A whole decoded sound: int16 frames ``(n, channels)`` at ``rate`` Hz."""

    path: str
    pcm: np.ndarray
    rate: int

    @property
    def duration(self) -> float:
        return len(self.pcm) / float(self.rate)


def to_pcm16(samples: np.ndarray, mono: bool) -> np.ndarray:
    """Float frames ``(n, channels)`` to int16, mixed down to one channel when ``mono``."""
    if mono and samples.shape[1] > 1:
        samples = samples.mean(axis=1, keepdims=True)
    elif samples.shape[1] > 2:  # OpenAL 1.1 plays mono or stereo: keep the front pair
        samples = samples[:, :2]
    return (np.clip(samples, -1.0, 1.0) * 32767.0).astype(np.int16)


def _check_riff(path: Path) -> None:
    """libsndfile silently shortens a truncated WAV; compare its data chunk to the file."""
    size = path.stat().st_size
    with path.open("rb") as f:
        head = f.read(12)
        if len(head) < 12 or head[:4] != b"RIFF" or head[8:12] != b"WAVE":
            return
        offset = 12
        while offset + 8 <= size:
            f.seek(offset)
            chunk, length = struct.unpack("<4sI", f.read(8))
            if chunk == b"data":
                available = size - offset - 8
                if length not in (0, 0xFFFFFFFF) and length > available:
                    raise AudioFileError(
                        path, f"truncated: the header declares {length} bytes of samples "
                        f"but the file holds {available}")
                return
            offset += 8 + length + (length & 1)


def probe(path: str | Path) -> SoundInfo:
    """Read a file's header, raising :class:`AudioFileError` that names the file."""
    import soundfile as sf  # libsndfile: loaded when a scene has a sound

    p = Path(path)
    if not p.is_file():
        raise AudioFileError(p, "file not found")
    try:
        _check_riff(p)
        info = sf.info(str(p))
    except AudioFileError:
        raise
    except (sf.LibsndfileError, RuntimeError, OSError, struct.error) as exc:
        raise AudioFileError(p, _reason(exc)) from exc
    found = SoundInfo(str(p), int(info.samplerate), int(info.channels), int(info.frames))
    check_header(found)
    return found


def check_header(info: SoundInfo) -> None:
    """Refuse a header no sound has (OpenAL would play it as noise, or not at all)."""
    if info.frames <= 0 or info.channels <= 0:
        raise AudioFileError(info.path, "no audio frames")
    if not MIN_SAMPLE_RATE <= info.rate <= MAX_SAMPLE_RATE:
        raise AudioFileError(info.path, f"its sample rate, {info.rate} Hz, is not one a sound "
                             f"can have ({MIN_SAMPLE_RATE} to {MAX_SAMPLE_RATE} Hz): a "
                             f"broken header")


def _reason(exc: BaseException) -> str:
    text = str(exc)
    if "Error opening" in text and ": " in text:
        text = text.rsplit(": ", 1)[-1]
    return f"cannot decode ({text.strip() or type(exc).__name__})"


def load_clip(path: str | Path, mono: bool) -> Clip:
    """Decode a whole file to int16 (mono when ``mono``)."""
    import soundfile as sf

    info = probe(path)
    try:
        data, rate = sf.read(info.path, dtype="float32", always_2d=True)
    except (sf.LibsndfileError, RuntimeError, OSError) as exc:
        raise AudioFileError(info.path, _reason(exc)) from exc
    if len(data) == 0:
        raise AudioFileError(info.path, "no audio frames")
    return Clip(info.path, to_pcm16(data, mono), int(rate))


class StreamReader:
    """Reads a long file in fixed-size int16 blocks, wrapping around when looping.

    Blocks are always full until the (non-looping) end, so consecutive buffers
    join without a gap, also across the loop point.
    """

    def __init__(self, info: SoundInfo, mono: bool, loop: bool) -> None:
        self.info = info
        self.mono = mono
        self.loop = loop
        import soundfile as sf

        self._errors = (sf.LibsndfileError, RuntimeError, OSError)
        try:
            self._file = sf.SoundFile(info.path)
        except self._errors as exc:
            raise AudioFileError(info.path, _reason(exc)) from exc
        self.finished = False

    @property
    def rate(self) -> int:
        return self.info.rate

    def read(self, frames: int) -> np.ndarray:
        """Up to ``frames`` int16 frames; fewer (or none) only at a non-looping end."""
        parts: list[np.ndarray] = []
        wanted = frames
        try:
            while wanted > 0 and not self.finished:
                block = self._file.read(wanted, dtype="float32", always_2d=True)
                if len(block):
                    parts.append(block)
                    wanted -= len(block)
                if wanted > 0:
                    if self.loop and (parts or self._file.tell() > 0):
                        self._file.seek(0)
                    else:
                        self.finished = True
        except self._errors as exc:
            self.finished = True
            raise AudioFileError(self.info.path, _reason(exc)) from exc
        if not parts:
            return np.zeros((0, 1 if self.mono else min(self.info.channels, 2)), np.int16)
        return to_pcm16(np.concatenate(parts), self.mono)

    def close(self) -> None:
        self._file.close()
