"""Sound test helpers: tones written with soundfile, and recordings made by OpenAL Soft.

Recordings use the ``wave:FILE`` backend: OpenAL Soft mixes in real time and
writes what the listener hears, so a test plays for the real duration of its
sounds (kept to fractions of a second). OpenAL Soft reads its configuration
once per process; a process that opened a real device first cannot record,
which is why the "no device" test runs in a subprocess.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import soundfile as sf

from services.audio import SoundManager, create_audio_backend

RATE = 44100


def tone(path: Path, freq: float = 440.0, seconds: float = 0.3, amplitude: float = 0.5,
         channels: int = 1, subtype: str | None = None, fmt: str | None = None) -> Path:
    """Write a sine tone (every channel the same) and return its path."""
    t = np.arange(int(RATE * seconds)) / RATE
    wave = amplitude * np.sin(2 * np.pi * freq * t)
    data = np.repeat(wave[:, None], channels, axis=1) if channels > 1 else wave
    sf.write(str(path), data, RATE, subtype=subtype, format=fmt)
    return path


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x, dtype=np.float64)))) if len(x) else 0.0


def band_amplitude(x: np.ndarray, freq: float, rate: int = RATE) -> float:
    """Amplitude of the ``freq`` component of a mono signal.

    A Hann-windowed projection onto exactly ``freq`` (no FFT-bin scalloping).
    """
    window = np.hanning(len(x))
    phase = np.exp(-2j * np.pi * freq * np.arange(len(x)) / rate)
    return float(2 * abs(np.sum(x * window * phase)) / window.sum())


def active(data: np.ndarray, threshold: float = 1e-4) -> np.ndarray:
    """The frames between the first and last audible one."""
    loud = np.flatnonzero(np.abs(data).max(axis=1) > threshold)
    return data[loud[0]:loud[-1] + 1] if len(loud) else data[:0]


@contextmanager
def recording(path: Path, **manager_options: object) -> Iterator[SoundManager]:
    """A SoundManager on OpenAL Soft's wave writer; the file is complete after the block."""
    backend = create_audio_backend(f"wave:{path}", fallback=False)
    manager = SoundManager(backend, **manager_options)  # type: ignore[arg-type]
    try:
        yield manager
    finally:
        manager.close()
        backend.close()


def pump(manager: SoundManager, seconds: float, every: float = 0.01,
         each: Callable[[float], None] | None = None) -> None:
    """Run the manager's frame update for ``seconds`` of wall time."""
    start = time.monotonic()
    while (elapsed := time.monotonic() - start) < seconds:
        if each is not None:
            each(elapsed)
        manager.update()
        time.sleep(every)


class Clock:
    """A hand-driven clock, so pool tests need no sleeping."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now

    def advance(self, seconds: float) -> None:
        self.now += seconds


def read(path: Path) -> np.ndarray:
    data, rate = sf.read(str(path), dtype="float64", always_2d=True)
    assert rate == RATE and data.shape[1] == 2
    return data
