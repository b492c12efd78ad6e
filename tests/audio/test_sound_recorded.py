"""Pooling and streaming as heard: recorded by OpenAL Soft's wave writer in real time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import soundfile as sf
from sound_helpers import RATE, active, band_amplitude, pump, read, recording, tone


def test_contact_burst_with_16_sources_never_interrupts_a_loop(tmp_path: Path) -> None:
    """500 one-shots in one second through 16 sources: all accounted for, the loop steady."""
    hum = tone(tmp_path / "hum.wav", 200.0, 0.1, 0.5)  # 20 whole periods: a seamless loop
    knock = tone(tmp_path / "knock.wav", 1000.0, 0.12, 0.2)
    out = tmp_path / "out.wav"
    rng = np.random.default_rng(7)
    sent = [0]

    def burst(elapsed: float) -> None:
        due = min(500, int(elapsed * 500) + 10)
        while sent[0] < due:
            manager.play(knock, position=rng.uniform(-4, 4, 3), gain=0.3,
                         priority=int(rng.integers(-1, 2)))
            sent[0] += 1

    with recording(out, pool_size=16) as manager:
        loop = manager.play(hum, loop=True, position=(0.0, 1.0, 0.0), priority=-5)
        pump(manager, 1.0, every=0.02, each=burst)
        burst(1.0)
        pump(manager, 0.25)
        stats = manager.stats()
        assert loop.state == "playing"
    assert sent[0] == 500
    assert stats["requests"] == 501 and stats["waiting"] == 0
    assert (stats["played"] - 1) + stats["dropped"] == 500
    assert stats["played"] > 100 and stats["stolen"] > 0

    left = active(read(out))[:, 0]
    window = RATE // 20  # 50 ms: 10 periods of the hum
    levels = np.array([band_amplitude(left[i:i + window], 200.0)
                       for i in range(window, len(left) - 2 * window, window)])
    assert len(levels) >= 20
    assert levels.min() > 0.85 * np.median(levels)  # no dropout, never stolen
    assert levels.max() < 1.15 * np.median(levels)


def _gapless(signal: np.ndarray, reference: np.ndarray) -> None:
    """No silent run and no jump larger than the source itself ever makes."""
    quiet = np.abs(signal) < 1e-6
    runs = np.diff(np.flatnonzero(np.diff(np.r_[0, quiet.astype(np.int8), 0])))[::2]
    assert runs.max(initial=0) <= 2, "silence inside the stream"
    scale = np.abs(signal).max() / np.abs(reference).max()
    assert np.abs(np.diff(signal)).max() < 1.3 * scale * np.abs(np.diff(reference)).max()


def test_streaming_a_long_ogg_file_is_gapless(tmp_path: Path) -> None:
    seconds = 1.5
    path = tone(tmp_path / "ambience.ogg", 440.0, seconds, 0.5, subtype="VORBIS", fmt="OGG")
    out = tmp_path / "out.wav"
    # 93 ms blocks, 4 queued: refilled ~16 times from the loop, 0.37 s of slack for stalls.
    with recording(out, stream_threshold=1.0, stream_block=4096) as manager:
        voice = manager.play(path)
        assert voice._stream is not None
        pump(manager, seconds + 0.2, every=0.015)
        stats = manager.stats()
    assert voice.state == "done"
    assert stats["streamed"] == 1 and stats["underruns"] == 0
    heard = active(read(out))[:, 0]
    assert abs(len(heard) / RATE - seconds) < 0.02
    source, _ = sf.read(str(path))
    _gapless(heard, source)


def test_looping_stream_wraps_around_without_a_gap(tmp_path: Path) -> None:
    path = tone(tmp_path / "loop.flac", 500.0, 0.4, 0.5, subtype="PCM_16", fmt="FLAC")
    out = tmp_path / "out.wav"
    with recording(out, stream_threshold=0.2, stream_block=4096) as manager:
        voice = manager.play(path, loop=True)
        pump(manager, 1.0, every=0.015)
        assert voice.state == "playing"
    heard = active(read(out))[:, 0]
    assert len(heard) / RATE > 0.9  # played past the end twice
    source, _ = sf.read(str(path))
    _gapless(heard, source)
