"""The SoundManager's pool policy, on the null backend with a hand-driven clock.

The null backend keeps real sound durations, so these are the same decisions
the manager makes over OpenAL (test_sound_pool_recorded.py checks that part).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
from sound_helpers import Clock, tone

from services.audio import NullBackend, SoundManager


def _manager(clock: Clock, **options: object) -> SoundManager:
    return SoundManager(NullBackend(clock=clock), clock=clock, **options)  # type: ignore[arg-type]


def test_default_pool_is_the_device_mono_sources_capped_at_32(clock: Clock) -> None:
    assert SoundManager(NullBackend(mono_sources=255)).pool_size == 32
    assert SoundManager(NullBackend(mono_sources=12)).pool_size == 12


def test_one_shots_are_first_in_first_out(tmp_path: Path, clock: Clock) -> None:
    beep = tone(tmp_path / "beep.wav", seconds=0.1)
    manager = _manager(clock, pool_size=2, queue_deadline=1.0)
    voices = [manager.play(beep, position=(0, 0, 0)) for _ in range(5)]
    assert [v.state for v in voices] == ["playing"] * 2 + ["queued"] * 3
    order = []
    for _ in range(4):
        clock.advance(0.1)
        manager.update()
        order.append([i for i, v in enumerate(voices) if v.state == "playing"])
    assert order == [[2, 3], [4], [], []]
    assert manager.stats()["played"] == 5 and manager.stats()["dropped"] == 0


def test_waiting_past_the_deadline_drops(tmp_path: Path, clock: Clock) -> None:
    beep = tone(tmp_path / "beep.wav", seconds=0.5)
    manager = _manager(clock, pool_size=1, queue_deadline=0.1)
    manager.play(beep)
    late = manager.play(beep)
    clock.advance(0.2)
    manager.update()
    assert late.state == "dropped"
    s = manager.stats()
    assert (s["requests"], s["played"], s["queued"], s["dropped"]) == (2, 1, 1, 1)


def test_higher_priority_steals_the_oldest_lowest_priority_one_shot(tmp_path: Path,
                                                                    clock: Clock) -> None:
    beep = tone(tmp_path / "beep.wav", seconds=1.0)
    manager = _manager(clock, pool_size=3)
    low_old = manager.play(beep, priority=-1)
    clock.advance(0.01)
    low_new = manager.play(beep, priority=-1)
    normal = manager.play(beep, priority=0)
    urgent = manager.play(beep, priority=5)
    assert urgent.state == "playing"
    assert low_old.state == "stolen"
    assert low_new.state == "playing" and normal.state == "playing"
    same = manager.play(beep, priority=-1)  # equal priority never steals: it waits
    assert same.state == "queued"
    assert manager.stats()["stolen"] == 1


def test_loops_are_exclusive_and_never_stolen(tmp_path: Path, clock: Clock) -> None:
    hum = tone(tmp_path / "hum.wav", seconds=0.2)
    beep = tone(tmp_path / "beep.wav", seconds=0.2)
    manager = _manager(clock, pool_size=2)
    loop = manager.play(hum, loop=True, priority=-10)
    for _ in range(50):
        manager.play(beep, priority=10)
        clock.advance(0.05)
        manager.update()
        assert loop.state == "playing" and loop.source is not None
    assert manager.stats()["stolen"] == 0


def test_a_loop_takes_a_one_shots_source_or_waits_for_one(tmp_path: Path,
                                                          clock: Clock) -> None:
    hum = tone(tmp_path / "hum.wav", seconds=0.2)
    beep = tone(tmp_path / "beep.wav", seconds=0.2)
    manager = _manager(clock, pool_size=2)
    shot = manager.play(beep)
    loops = [manager.play(hum, loop=True), manager.play(hum, loop=True)]
    assert shot.state == "stolen" and [v.state for v in loops] == ["playing", "playing"]
    third = manager.play(hum, loop=True)
    assert third.state == "pending"
    manager.stop(loops[0])
    manager.update()
    assert third.state == "playing"


def test_500_contact_sounds_in_one_second_are_all_accounted_for(tmp_path: Path,
                                                                clock: Clock) -> None:
    knock = tone(tmp_path / "knock.wav", 900.0, 0.15)
    hum = tone(tmp_path / "hum.wav", 200.0, 0.1)
    manager = _manager(clock, pool_size=16)
    loops = [manager.play(hum, loop=True, position=(i, 0, 0)) for i in range(3)]
    rng = np.random.default_rng(1)
    for frame in range(60):
        for _ in range(500 // 60 + (frame < 500 % 60)):
            manager.play(knock, position=rng.uniform(-5, 5, 3), priority=int(rng.integers(-1, 2)),
                         gain=0.5)
        clock.advance(1 / 60)
        manager.update()
        assert all(v.state == "playing" for v in loops)
    for _ in range(30):
        clock.advance(1 / 60)
        manager.update()
    s = manager.stats()
    contact_played = s["played"] - len(loops)
    assert s["requests"] - len(loops) == 500
    assert contact_played + s["dropped"] == 500
    assert s["waiting"] == 0 and s["failed"] == 0
    assert contact_played >= 13 * 6  # the 13 free sources were kept busy
    assert s["active"] == len(loops)


def test_queue_overflow_drops_the_oldest_lowest_priority_request(tmp_path: Path,
                                                                 clock: Clock) -> None:
    beep = tone(tmp_path / "beep.wav", seconds=1.0)
    manager = _manager(clock, pool_size=1, queue_limit=2, queue_deadline=5.0)
    manager.play(beep)
    low = manager.play(beep, priority=-1)
    mid = manager.play(beep, priority=0)
    newer = manager.play(beep, priority=0)
    assert low.state == "dropped" and mid.state == "queued" and newer.state == "queued"


def test_bad_files_fail_once_loudly_and_stay_silent(tmp_path: Path, clock: Clock,
                                                    caplog: pytest.LogCaptureFixture) -> None:
    manager = _manager(clock, pool_size=2)
    bad = tmp_path / "broken.ogg"
    bad.write_bytes(b"OggS" + b"\0" * 100)
    with caplog.at_level(logging.ERROR, "colosseum.audio"):
        voices = [manager.play(tmp_path / "missing.wav"), manager.play(tmp_path / "missing.wav"),
                  manager.play(bad)]
    assert [v.state for v in voices] == ["failed"] * 3
    errors = [r.getMessage() for r in caplog.records]
    assert len(errors) == 2
    assert errors[0] == (f'error: cannot load sound "missing.wav" ({tmp_path / "missing.wav"}): '
                         f"file not found (the sound stays silent)")
    assert 'cannot load sound "broken.ogg"' in errors[1] and "cannot decode" in errors[1]
    manager.update()
    assert manager.stats()["failed"] == 3 and manager.stats()["active"] == 0


def test_stereo_file_used_positionally_warns_once(tmp_path: Path, clock: Clock,
                                                  caplog: pytest.LogCaptureFixture) -> None:
    music = tone(tmp_path / "music.wav", channels=2, seconds=0.1)
    manager = _manager(clock, pool_size=4)
    with caplog.at_level(logging.WARNING, "colosseum.audio"):
        manager.play(music)  # at the listener: stereo is fine
        manager.play(music, position=(1, 0, 0))
        manager.play(music, position=(2, 0, 0))
    warnings = [r.getMessage() for r in caplog.records]
    assert len(warnings) == 1
    assert "music.wav: warning: 2-channel sound used by a positional source" in warnings[0]


def test_short_files_are_decoded_once(tmp_path: Path, clock: Clock) -> None:
    beep = tone(tmp_path / "beep.wav", seconds=0.1)
    backend = NullBackend(clock=clock)
    manager = SoundManager(backend, pool_size=4, clock=clock)
    voices = [manager.play(beep, position=(0, 0, 0)) for _ in range(4)]
    assert len({v._buffer for v in voices}) == 1


def test_close_frees_every_source_and_buffer(tmp_path: Path, clock: Clock) -> None:
    beep = tone(tmp_path / "beep.wav", seconds=0.1)
    backend = NullBackend(clock=clock)
    manager = SoundManager(backend, pool_size=4, clock=clock)
    manager.play(beep, loop=True)
    manager.play(beep, position=(1, 0, 0))
    manager.close()
    assert backend._sources == {} and backend._durations == {}


def test_a_source_freed_between_frames_goes_to_the_oldest_waiting_request(
        tmp_path: Path, clock: Clock) -> None:
    beep = tone(tmp_path / "beep.wav", seconds=1.0)
    manager = _manager(clock, pool_size=1, queue_deadline=1.0)
    first = manager.play(beep)
    waiting = manager.play(beep)
    manager.stop(first)
    newcomer = manager.play(beep)
    assert waiting.state == "playing" and newcomer.state == "queued"


def test_long_files_stream_and_free_their_buffers_when_done(tmp_path: Path,
                                                            clock: Clock) -> None:
    ambience = tone(tmp_path / "ambience.ogg", seconds=2.5, subtype="VORBIS", fmt="OGG")
    backend = NullBackend(clock=clock)
    manager = SoundManager(backend, pool_size=2, clock=clock, stream_block=4096)
    voice = manager.play(ambience)
    assert voice.state == "playing" and voice._stream is not None
    assert len(backend._durations) == manager.stream_buffers
    for _ in range(int(2.4 / 0.05)):
        clock.advance(0.05)
        manager.update()
        assert voice.state == "playing"
    for _ in range(10):
        clock.advance(0.05)
        manager.update()
    assert voice.state == "done" and manager.stats()["streamed"] == 1
    assert backend._durations == {}  # the stream's buffers are freed
    assert manager.stats()["active"] == 0
