"""Files that must not crash the engine, made on the spot (no binary fixtures in the repo)."""

from __future__ import annotations

import shutil
import struct
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import soundfile as sf
import trimesh

CONTENT = Path(__file__).resolve().parents[2] / "content" / "demo"


def cube(path: Path, extents: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> Path:
    trimesh.creation.box(extents=extents).export(path)
    return path


def flat_obj(path: Path) -> Path:
    """A square: four points on one plane, no volume to wrap a hull around."""
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    return path


def non_finite_obj(value: str) -> Callable[[Path], Path]:
    def make(path: Path) -> Path:
        path.write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 {value}\n"
                        "f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
        return path
    return make


def garbage(path: Path) -> Path:
    path.write_bytes(np.random.default_rng(7).bytes(4096))
    return path


def empty(path: Path) -> Path:
    path.write_bytes(b"")
    return path


def png_bomb(path: Path, side: int = 100_000) -> Path:
    """A valid PNG header claiming ``side`` x ``side`` RGBA (40 GB decoded) over a few
    hundred bytes of data."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    header = struct.pack(">IIBBBBB", side, side, 8, 6, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + chunk(b"IDAT", zlib.compress(b"\0" * 100_000)) + chunk(b"IEND", b""))
    return path


def not_an_image(path: Path) -> Path:
    path.write_text("a text file given a picture's name\n")
    return path


def wav_with_rate(rate: int) -> Callable[[Path], Path]:
    """A PCM WAV whose header claims ``rate`` samples per second."""
    def make(path: Path) -> Path:
        data = np.zeros(800, np.int16).tobytes()
        fmt = struct.pack("<IHHIIHH", 16, 1, 1, rate, (2 * rate) & 0xFFFFFFFF, 2, 16)
        path.write_bytes(b"RIFF" + struct.pack("<I", 36 + len(data)) + b"WAVE" + b"fmt " + fmt
                         + b"data" + struct.pack("<I", len(data)) + data)
        return path
    return make


def truncated_wav(path: Path) -> Path:
    """A WAV whose header declares a second of samples but holds a tenth of it."""
    sf.write(str(path), np.zeros(44_100, np.float32), 44_100, subtype="PCM_16")
    whole = path.read_bytes()
    path.write_bytes(whole[:len(whole) // 10])
    return path


def knock(path: Path) -> Path:
    shutil.copy(CONTENT / "sounds" / "knock.wav", path)
    return path


@dataclass(frozen=True)
class Case:
    """One hostile file, how a scene uses it, and what the author must be told."""

    file: str
    make: Callable[[Path], Path]
    use: str  # scene text using the file; {file} is its name
    reason: str  # a piece of the message's reason
    action: str = "load model"
    left_out: bool = True  # the object is left out (not just its texture or sound)


_HULL = ('Object {{ ID "bad" Position [0 0 2] '
         'PhysicalAttributes {{ Geometry {{ File "{file}" ParseMethod "ConvexHull" }} }} }}')
_SEEN = 'Object {{ ID "bad" Position [0 0 2] VisualAttributes {{ Geometry {{ File "{file}" }} }} }}'
_TEXTURED = ('Object {{ ID "bad" Position [0 0 2] VisualAttributes {{ Texture "{file}" '
             'Geometry {{ Primitive "box" }} }} }}')
_SOUNDING = 'Object {{ ID "bad" Position [0 0 2] Sound {{ File "{file}" AutoPlay 1 }} }}'

CASES = [
    Case("flat.obj", flat_obj, _HULL, "enclose no volume",
         action="build a convex hull of model"),
    Case("nan.obj", non_finite_obj("nan"), _SEEN, "not finite"),
    Case("inf.obj", non_finite_obj("inf"), _HULL, "not finite"),
    Case("garbage.obj", garbage, _HULL, "holds no triangles"),
    Case("garbage.stl", garbage, _SEEN, "holds no triangles"),
    Case("garbage.ply", garbage, _HULL, "Not a ply file"),
    Case("garbage.glb", garbage, _SEEN, "incorrect header on GLB file"),
    Case("empty.obj", empty, _HULL, "the file is empty"),
    Case("bomb.png", png_bomb, _TEXTURED, "decompression bomb", action="load image",
         left_out=False),
    Case("words.png", not_an_image, _TEXTURED, "not an image", action="load image",
         left_out=False),
    Case("buzz.wav", wav_with_rate(3_000_000), _SOUNDING, "sample rate, 3000000 Hz",
         action="load sound", left_out=False),
    Case("cut.wav", truncated_wav, _SOUNDING, "truncated", action="load sound",
         left_out=False),
]


def case(file: str) -> Case:
    """The case of ``file``."""
    (found,) = [c for c in CASES if c.file == file]
    return found
