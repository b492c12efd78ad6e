"""Decoding: every format an author may drop in sounds/ becomes the same 16-bit PCM."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sound_helpers import RATE, tone

from engine.assets.sound import StreamReader
from services.audio import AudioFileError, load_clip, probe

FORMATS = [
    ("PCM_U8", "wav", "WAV"),
    ("PCM_16", "wav", "WAV"),
    ("PCM_24", "wav", "WAV"),
    ("PCM_32", "wav", "WAV"),
    ("FLOAT", "wav", "WAV"),
    ("VORBIS", "ogg", "OGG"),
    ("PCM_16", "flac", "FLAC"),
]


@pytest.mark.parametrize(("subtype", "ext", "fmt"), FORMATS)
def test_formats_decode_to_the_same_int16_tone(tmp_path: Path, subtype: str, ext: str,
                                               fmt: str) -> None:
    path = tone(tmp_path / f"t.{ext}", 440.0, 0.25, 0.5, subtype=subtype, fmt=fmt)
    clip = load_clip(path, mono=True)
    assert clip.pcm.dtype == np.int16 and clip.pcm.shape[1] == 1
    assert clip.rate == RATE and clip.duration == pytest.approx(0.25, abs=0.01)
    peak = np.abs(clip.pcm[:, 0]).max() / 32767
    assert peak == pytest.approx(0.5, abs=0.03)  # 8-bit and Vorbis are lossy


def test_stereo_kept_for_the_listener_and_mixed_down_for_positions(tmp_path: Path) -> None:
    path = tmp_path / "st.wav"
    import soundfile as sf

    left_only = np.zeros((1000, 2))
    left_only[:, 0] = 0.8
    sf.write(str(path), left_only, RATE)
    assert load_clip(path, mono=False).pcm.shape == (1000, 2)
    mono = load_clip(path, mono=True).pcm
    assert mono.shape == (1000, 1) and abs(mono[0, 0] / 32767 - 0.4) < 1e-3


def test_float_overs_are_clipped_not_wrapped(tmp_path: Path) -> None:
    import soundfile as sf

    path = tmp_path / "hot.wav"
    sf.write(str(path), np.full(100, 1.7, np.float32), RATE, subtype="FLOAT")
    assert load_clip(path, mono=True).pcm.min() == 32767


def test_missing_file_names_it(tmp_path: Path) -> None:
    with pytest.raises(AudioFileError, match=r"nope\.wav: error: file not found"):
        probe(tmp_path / "nope.wav")


def test_truncated_wav_is_an_error_naming_the_file(tmp_path: Path) -> None:
    path = tone(tmp_path / "cut.wav", seconds=0.5)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(AudioFileError, match=r"cut\.wav: error: truncated"):
        load_clip(path, mono=True)


def test_truncated_ogg_and_unsupported_files_name_the_file(tmp_path: Path) -> None:
    ogg = tone(tmp_path / "cut.ogg", seconds=1.0, subtype="VORBIS", fmt="OGG")
    ogg.write_bytes(ogg.read_bytes()[:2000])
    text = tmp_path / "notes.mp4"
    text.write_text("not audio at all")
    for path in (ogg, text):
        with pytest.raises(AudioFileError, match=rf"{path.name}: error: cannot decode"):
            load_clip(path, mono=True)


def test_stream_reader_wraps_around_without_a_gap(tmp_path: Path) -> None:
    """Looping blocks stay full across the loop point: the wave continues seamlessly."""
    path = tone(tmp_path / "loop.wav", freq=441.0, seconds=4400 / RATE)  # 44 whole periods
    reader = StreamReader(probe(path), mono=True, loop=True)
    blocks = [reader.read(3000) for _ in range(5)]
    assert all(len(b) == 3000 for b in blocks)
    joined = np.concatenate(blocks)[:, 0] / 32767
    expected = 0.5 * np.sin(2 * np.pi * 441.0 * np.arange(15000) / RATE)
    assert np.abs(joined - expected).max() < 1e-3
    reader.close()


def test_stream_reader_ends_once_without_loop(tmp_path: Path) -> None:
    path = tone(tmp_path / "once.wav", seconds=0.1)
    reader = StreamReader(probe(path), mono=True, loop=False)
    sizes = [len(reader.read(3000)) for _ in range(3)]
    assert sizes == [3000, 1410, 0] and reader.finished
    reader.close()
