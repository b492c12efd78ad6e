"""What a listener hears, recorded by OpenAL Soft's wave writer: panning, distance, motion.

The listener stands at the origin looking along engine +Y with Z up (the camera
convention), so engine +X is to its right.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from sound_helpers import RATE, active, band_amplitude, pump, read, recording, rms, tone

from services.audio import SoundManager, create_audio_backend, inverse_clamped_gain


def _channels(path: Path) -> tuple[float, float]:
    data = active(read(path))
    return rms(data[:, 0]), rms(data[:, 1])


@pytest.mark.parametrize(("x", "loud", "quiet"), [(2.0, 1, 0), (-2.0, 0, 1)])
def test_source_to_the_side_is_heard_on_that_side_only(tmp_path: Path, x: float, loud: int,
                                                       quiet: int) -> None:
    sound = tone(tmp_path / "beep.wav", 440.0, 0.25)
    out = tmp_path / "out.wav"
    with recording(out) as manager:
        manager.set_listener((0.0, 0.0, 0.0))
        manager.play(sound, position=(x, 0.0, 0.0))
        pump(manager, 0.35)
    levels = _channels(out)
    assert levels[loud] > 0.05
    assert levels[quiet] < 0.01 * levels[loud]


def test_listener_orientation_turns_the_scene(tmp_path: Path) -> None:
    """Turned to face +X (yaw -90° about Z), a source at +X is ahead, one at +Y on the left."""
    front = tone(tmp_path / "front.wav", 500.0, 0.25)
    left = tone(tmp_path / "left.wav", 900.0, 0.25)
    out = tmp_path / "out.wav"
    yaw = -math.pi / 2
    with recording(out) as manager:
        manager.set_listener((0.0, 0.0, 0.0), (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)))
        manager.play(front, position=(3.0, 0.0, 0.0))
        manager.play(left, position=(0.0, 3.0, 0.0))
        pump(manager, 0.35)
    data = active(read(out))
    ahead = [band_amplitude(data[:, c], 500.0) for c in (0, 1)]
    aside = [band_amplitude(data[:, c], 900.0) for c in (0, 1)]
    assert ahead[0] == pytest.approx(ahead[1], rel=0.05)
    assert aside[1] < 0.01 * aside[0]


def test_gain_falls_with_distance_by_the_inverse_clamped_model(tmp_path: Path) -> None:
    """Tones at once, ahead at several distances: their levels follow OpenAL's formula."""
    cases = [  # (frequency, distance, ref_distance, rolloff, max_distance)
        (300.0, 1.0, 1.0, 1.0, 1000.0),
        (500.0, 2.0, 1.0, 1.0, 1000.0),
        (700.0, 4.0, 1.0, 1.0, 1000.0),
        (1100.0, 8.0, 1.0, 1.0, 1000.0),
        (1300.0, 6.0, 2.0, 0.5, 1000.0),
        (1500.0, 30.0, 1.0, 1.0, 10.0),  # beyond max_distance: clamped
        (1700.0, 0.5, 1.0, 1.0, 1000.0),  # inside ref_distance: clamped
    ]
    out = tmp_path / "out.wav"
    with recording(out) as manager:
        manager.set_listener((0.0, 0.0, 0.0))
        for freq, d, ref, rolloff, far in cases:
            manager.play(tone(tmp_path / f"{int(freq)}.wav", freq, 0.4, 0.1),
                         position=(0.0, d, 0.0), ref_distance=ref, rolloff=rolloff,
                         max_distance=far)
        pump(manager, 0.45)
    data = active(read(out))
    mid = data[len(data) // 8: -len(data) // 8, 0]  # steady part, left channel
    reference = band_amplitude(mid, 300.0)
    for freq, d, ref, rolloff, far in cases[1:]:
        measured = band_amplitude(mid, freq) / reference
        expected = inverse_clamped_gain(d, ref, rolloff, far)
        assert measured == pytest.approx(expected, rel=0.01), (freq, d)


def test_source_moving_past_the_listener_pans_left_to_right(tmp_path: Path) -> None:
    sound = tone(tmp_path / "hum.wav", 300.0, 1.0)
    out = tmp_path / "out.wav"
    seconds = 0.6
    with recording(out) as manager:
        manager.set_listener((0.0, 0.0, 0.0))
        voice = manager.play(sound, position=(-4.0, 1.0, 0.0), loop=True)

        def fly(elapsed: float) -> None:
            x = -4.0 + 8.0 * elapsed / seconds
            manager.move([voice], np.array([[x, 1.0, 0.0]]), np.array([[8.0 / seconds, 0, 0]]))

        pump(manager, seconds, each=fly)
    data = active(read(out))
    n = len(data)
    first, last = data[: n // 4], data[-n // 4:]
    assert rms(first[:, 0]) > 3 * rms(first[:, 1])  # starts on the left
    assert rms(last[:, 1]) > 3 * rms(last[:, 0])  # ends on the right


def test_velocity_gives_doppler_shift(tmp_path: Path) -> None:
    """A source approaching at a tenth of the speed of sound is heard 10/9 higher."""
    sound = tone(tmp_path / "siren.wav", 450.0, 0.4)
    out = tmp_path / "out.wav"
    with recording(out) as manager:
        manager.set_listener((0.0, 0.0, 0.0))
        manager.play(sound, position=(0.0, 10.0, 0.0), velocity=(0.0, -34.33, 0.0))
        pump(manager, 0.45)
    data = active(read(out))[:, 0]
    spectrum = np.abs(np.fft.rfft(data * np.hanning(len(data)), n=1 << 18))
    peak = np.argmax(spectrum) * RATE / (1 << 18)
    assert peak == pytest.approx(450.0 * 343.3 / (343.3 - 34.33), abs=2.0)


def test_hrtf_option_renders_for_headphones(tmp_path: Path) -> None:
    """With HRTF the far ear hears a filtered, quieter copy instead of nothing."""
    sound = tone(tmp_path / "beep.wav", 440.0, 0.25)
    out = tmp_path / "out.wav"
    backend = create_audio_backend(f"wave:{out}", hrtf=True, fallback=False)
    manager = SoundManager(backend)
    manager.set_listener((0.0, 0.0, 0.0))
    manager.play(sound, position=(2.0, 0.0, 0.0))
    pump(manager, 0.35)
    manager.close()
    backend.close()
    left, right = _channels(out)
    assert 0.05 * right < left < 0.7 * right
