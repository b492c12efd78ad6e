"""Model, image and sound targets of the fuzzer (``python -m tools.fuzz --kind models``).

Small valid files of every format the asset layer reads (OBJ, STL, PLY, glTF and GLB,
skinned too, Collada; PNG, JPEG and the other Pillow formats in odd modes; WAV, FLAC
and Ogg in odd layouts) are made in code, then mutated: bytes (length fields,
truncation, bit flips), structure (a glTF's JSON fields, accessor counts; any number in
a text format made NaN, inf or huge) and headers (an image's size, a WAV's rate and
channels). Each goes through what a scene and ``colosseum import`` do with it: a scene
drawing it, giving it a triangle-mesh and a convex-hull body, importing it as a
``Model`` and animating it as an ``Avatar`` is checked (assets loaded, shapes made); a
glTF or Collada file is imported; a sound is decoded whole and streamed. Each must end
in success or a message naming the file.
"""

from __future__ import annotations

import base64
import copy
import functools
import io
import json
import random
import re
import struct
import tempfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from app.scene_loading import import_path
from engine.assets import AssetError, Assets
from engine.assets.sound import AudioFileError, StreamReader
from engine.interchange import FORMATS
from engine.scene import check
from tools.fuzz_core import Outcome, Target, mutate_bytes

#: Numbers a mutation puts in place of one in a file.
HOSTILE_NUMBERS = ["nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e999", "0", "-0", "-1",
                   "4294967295", "4294967296", "2147483647", "-2147483648",
                   "99999999999999999999", "1e-320", "0.5", "3"]
_NUMBER = re.compile(rb"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


@dataclass(slots=True)
class FileInput:
    """One asset file: its bytes and its extension (kept while shrinking)."""

    data: bytes
    ext: str = field(metadata={"keep": True})


def _files(inp: FileInput, stem: str) -> dict[str, bytes]:
    return {stem + inp.ext: inp.data}


def mutate_numbers(rng: random.Random, data: bytes, edits: int) -> bytes:
    """``data`` with ``edits`` of its decimal numbers replaced by hostile ones."""
    found = list(_NUMBER.finditer(data[:200_000]))
    for _ in range(min(edits, len(found))):
        m = rng.choice(found)
        data = data[:m.start()] + rng.choice(HOSTILE_NUMBERS).encode() + data[m.end():]
        found = list(_NUMBER.finditer(data[:200_000]))
    return data


# -- models ----------------------------------------------------------------------------

def _glb_parts(data: bytes) -> tuple[dict[str, Any], bytes]:
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + length])
    rest = data[20 + length:]
    return doc, rest[8:] if len(rest) >= 8 else b""


def _glb(doc: dict[str, Any], blob: bytes) -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text
    if blob:
        body += struct.pack("<I4s", len(blob), b"BIN\0") + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def _gltf_text(glb: bytes) -> bytes:
    """The GLB as one .gltf file, its buffer a data URI."""
    doc, blob = _glb_parts(glb)
    if doc.get("buffers"):
        doc["buffers"][0]["uri"] = ("data:application/octet-stream;base64,"
                                    + base64.b64encode(blob).decode())
    return json.dumps(doc, indent=1).encode()


@functools.cache
def model_seeds() -> tuple[tuple[str, bytes], ...]:
    """Small valid model files, each as (extension, bytes)."""
    import trimesh

    from app.bench import interchange_samples
    from tools import gltf_samples

    with tempfile.TemporaryDirectory(prefix="fuzz-models.") as tmp:
        folder = Path(tmp)
        made = [interchange_samples.shapes(folder / "shapes.glb"),
                interchange_samples.joints(folder / "joints.glb"),
                interchange_samples.extras(folder / "extras.glb"),
                gltf_samples.two_bone(folder / "bar.glb"),
                gltf_samples.two_bone(folder / "bar5.glb", influences=5, weight_scale=0.5),
                interchange_samples.collada(folder / "physics.dae"),
                interchange_samples.collada(folder / "y_up.dae", up="Y_UP", meter=0.01)]
        seeds = [(p.suffix, p.read_bytes()) for p in made]
    seeds += [(".gltf", _gltf_text(data)) for ext, data in seeds[:4]]
    box = trimesh.creation.box(extents=(1.0, 0.5, 0.25))
    for ext in ("stl", "ply", "obj", "glb", "dae"):
        seeds.append(("." + ext, box.export(file_type=ext)))
    seeds.append((".ply", box.export(file_type="ply", encoding="ascii")))
    seeds.append((".stl", box.export(file_type="stl_ascii").encode()))
    seeds.append((".obj", b"# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
                          b"f 1/1/1 2/1/1 3/1/1\nf -4 -2 -1\n"))
    return tuple((ext, data if isinstance(data, bytes) else data.encode()) for ext, data in seeds)


_JSON_VALUES: list[Any] = [float("nan"), float("inf"), -1, 0, 2**31, 2**32 + 1, 10**12, 1e308,
                           "x", "", None, True, [], {}, [0] * 3, {"a": 1}, -0.0, 5126, 34962]
_COUNT_KEYS = ["count", "byteOffset", "byteLength", "byteStride", "componentType", "bufferView",
               "buffer", "mesh", "skin", "accessor", "input", "output", "node", "scene",
               "material", "index", "indices", "POSITION", "JOINTS_0", "WEIGHTS_0",
               "inverseBindMatrices"]


def mutate_json(rng: random.Random, doc: Any, edits: int) -> Any:
    """``doc`` (a parsed glTF) with ``edits`` values replaced, deleted or copied: often
    an index or count field (the ones that say how much to read where)."""
    for _ in range(edits):
        parent: Any = None
        node, key = doc, None
        for _ in range(rng.randrange(1, 8)):
            if not isinstance(node, (dict, list)) or not node:
                break
            keys = list(node) if isinstance(node, dict) else list(range(len(node)))
            wanted = [k for k in keys if k in _COUNT_KEYS]
            key = rng.choice(wanted) if wanted and rng.random() < 0.6 else rng.choice(keys)
            parent, node = node, node[key]
            if rng.random() < 0.15:
                break
        if parent is None:
            continue
        op = rng.randrange(6)
        if op == 0 and isinstance(parent, dict):
            del parent[key]
        elif op == 1 and isinstance(parent, list):
            parent.append(copy.deepcopy(node))
        elif op == 2 and isinstance(node, int) and not isinstance(node, bool):
            parent[key] = node * rng.choice([2, 1000, 10**9]) + rng.choice([0, 1, -1])
        else:
            parent[key] = copy.deepcopy(rng.choice(_JSON_VALUES))
    return doc


def _obj_soup(rng: random.Random) -> bytes:
    """An OBJ of random vertex and face lines, indices in and out of range."""
    lines = []
    for _ in range(rng.randrange(1, 30)):
        kind = rng.randrange(5)
        if kind < 2:
            lines.append("v " + " ".join(rng.choice([repr(rng.uniform(-9, 9)),
                                                     *HOSTILE_NUMBERS[:6]])
                                         for _ in range(rng.choice([3, 3, 3, 2, 4, 6]))))
        elif kind < 4:
            lines.append("f " + " ".join(str(rng.randrange(-8, 12)) + rng.choice(
                ["", "/1", "//1", "/1/1", "/"]) for _ in range(rng.choice([3, 3, 4, 2, 9]))))
        else:
            lines.append(rng.choice(["vt 0 0", "vn 0 0 1", "o part", "g group", "usemtl red",
                                     "mtllib missing.mtl", "s 1", "l 1 2", "#"]))
    return "\n".join(lines).encode()


def make_model(rng: random.Random) -> FileInput:
    """A seed model, mutated in bytes, numbers or (glTF) structure; or an OBJ soup."""
    if rng.random() < 0.1:
        return FileInput(_obj_soup(rng), ".obj")
    ext, data = rng.choice(model_seeds())
    how = rng.randrange(10)
    edits = rng.randrange(1, 6)
    if how < 3 and ext in (".glb", ".gltf"):
        doc, blob = _glb_parts(data) if ext == ".glb" else (json.loads(data), b"")
        doc = mutate_json(rng, doc, edits)
        data = _glb(doc, blob) if ext == ".glb" else json.dumps(doc).encode()
    elif how < 6:
        data = mutate_numbers(rng, data, edits)
    elif how < 9:
        data = mutate_bytes(rng, data, edits)
    if rng.random() < 0.05:
        ext = rng.choice([".obj", ".stl", ".ply", ".glb", ".gltf", ".dae"])  # the wrong one
    return FileInput(data, ext)


_MODEL_SCENE = """\
Object {{ ID "drawn" VisualAttributes {{ Geometry {{ File "{f}" }} }} }}
Object {{ ID "hull" Position [0 0 2]
  VisualAttributes {{ Geometry {{ File "{f}" Scale [0.5 0.5 0.5] }} }}
  PhysicalAttributes {{ Mass 1 Geometry {{ ParseMethod "ConvexHull" }} }} }}
Object {{ ID "mesh" Dynamic 0 VisualAttributes {{ Geometry {{ File "{f}" }} }}
  PhysicalAttributes {{ Geometry {{ ParseMethod "TriangleMesh" }} }} }}
"""
_DOCUMENT_SCENE = """\
Model {{ File "{f}" Prefix "m_" }}
Object {{ ID "part" VisualAttributes {{ Geometry {{ File "{f}" Nodes ["Box" "root"] }} }} }}
"""
_SKIN_SCENE = 'Avatar {{ ID "walker" Model "{f}" Animation "Bend" }}\n'


def _checked(folder: Path, scene: str) -> Outcome:
    (folder / "main.scene").write_text(scene, encoding="utf-8")
    report = check(folder)
    report.render()
    report.to_json()
    return "message" if report.diagnostics else "ok"


def exercise_model(inp: FileInput, folder: Path) -> Outcome:
    """The model drawn, as two kinds of body, as a Model and an Avatar (glTF), checked as
    a scene; then imported as ``colosseum import`` does (glTF, Collada)."""
    name = "model" + inp.ext
    (folder / name).write_bytes(inp.data)
    scene = _MODEL_SCENE
    if inp.ext in FORMATS:
        scene += _DOCUMENT_SCENE
    if inp.ext in (".glb", ".gltf"):
        scene += _SKIN_SCENE
    outcome = _checked(folder, scene.format(f=name))
    if inp.ext in FORMATS:
        out = folder / "imported.scene"
        out.unlink(missing_ok=True)
        if import_path(folder / name, out, force=True) != 0:
            outcome = "message"
    return outcome


# -- images ----------------------------------------------------------------------------

_IMAGE_FORMATS = {"PNG": ".png", "JPEG": ".jpg", "BMP": ".bmp", "GIF": ".gif", "TIFF": ".tif",
                  "TGA": ".tga", "WEBP": ".webp"}
_MODES = ["1", "L", "LA", "P", "RGB", "RGBA", "I", "I;16", "F", "CMYK", "YCbCr"]


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def _png_resized(data: bytes, width: int, height: int) -> bytes:
    """A PNG whose header claims ``width`` x ``height`` (checksum right)."""
    if data[:8] != b"\x89PNG\r\n\x1a\n" or data[12:16] != b"IHDR":
        return data
    header = struct.pack(">II", width, height) + data[24:29]
    return data[:8] + _png_chunk(b"IHDR", header) + data[33:]


def make_image(rng: random.Random) -> FileInput:
    """A small image in a random mode and format, then mutated or given an absurd size."""
    from PIL import Image

    fmt = rng.choice(list(_IMAGE_FORMATS))
    mode = rng.choice(_MODES)
    size = (rng.choice([1, 2, 3, 17, 64]), rng.choice([1, 2, 5, 33]))
    pixels = np.random.default_rng(rng.randrange(2**32)).integers(0, 256, (size[1], size[0], 3),
                                                                   dtype=np.uint8)
    image = Image.fromarray(pixels, "RGB")
    out = io.BytesIO()
    try:
        image.convert(mode).save(out, fmt)
    except (OSError, ValueError, KeyError):  # a mode the format cannot hold
        out = io.BytesIO()
        image.save(out, fmt)
    data = out.getvalue()
    how = rng.randrange(10)
    if how < 2 and fmt == "PNG":
        data = _png_resized(data, rng.choice([0, 1, 2**16, 2**31 - 1, 2**32 - 1, 40_000]),
                            rng.choice([0, 1, 3, 2**16, 2**31 - 1, 50_000]))
    elif how < 5:
        data = mutate_bytes(rng, data, rng.randrange(1, 6))
    elif how < 7:
        data = data[:rng.randrange(len(data) + 1)]
    return FileInput(data, _IMAGE_FORMATS[fmt] if rng.random() > 0.05 else
                     rng.choice(list(_IMAGE_FORMATS.values())))


def exercise_image(inp: FileInput, folder: Path) -> Outcome:
    """The image as a texture of a scene's object, checked."""
    name = "texture" + inp.ext
    (folder / name).write_bytes(inp.data)
    return _checked(folder, f'Object {{ ID "t" VisualAttributes {{ Geometry {{ Primitive '
                            f'"box" }} Texture "{name}" }} }}\n')


# -- sounds ----------------------------------------------------------------------------

_SOUND_LAYOUTS = [("WAV", "PCM_16", ".wav"), ("WAV", "PCM_U8", ".wav"), ("WAV", "PCM_24", ".wav"),
                  ("WAV", "FLOAT", ".wav"), ("WAV", "ULAW", ".wav"), ("FLAC", "PCM_16", ".flac"),
                  ("OGG", "VORBIS", ".ogg"), ("AIFF", "PCM_16", ".aiff")]
#: Offsets of a plain 44-byte WAV header's fields: channels, rate, byte rate, block
#: align, bits per sample, data size (struct formats).
_WAV_FIELDS = [(22, "<H"), (24, "<I"), (28, "<I"), (32, "<H"), (34, "<H"), (40, "<I"), (4, "<I"),
               (16, "<I"), (20, "<H")]


def make_sound(rng: random.Random) -> FileInput:
    """A short sound in a random format, rate and channel count, then given absurd header
    fields, truncated or mutated."""
    import soundfile as sf

    container, subtype, ext = rng.choice(_SOUND_LAYOUTS)
    channels = rng.choice([1, 1, 2, 3, 6, 8])
    rate = rng.choice([8000, 22050, 44100, 48000, 96000, 1000])
    frames = rng.choice([1, 10, 400, 3000])
    samples = np.random.default_rng(rng.randrange(2**32)).uniform(-1, 1, (frames, channels))
    out = io.BytesIO()
    try:
        sf.write(out, samples, rate, subtype=subtype, format=container)
    except (sf.LibsndfileError, RuntimeError, ValueError):  # a layout the format refuses
        out = io.BytesIO()
        sf.write(out, samples[:, :1], 44100, subtype="PCM_16", format="WAV")
        ext = ".wav"
    data = out.getvalue()
    how = rng.randrange(10)
    if how < 4 and data[:4] == b"RIFF":
        for _ in range(rng.randrange(1, 3)):
            offset, fmt = rng.choice(_WAV_FIELDS)
            top = 0xFFFF if fmt == "<H" else 0xFFFFFFFF
            value = rng.choice([0, 1, 2, 3, 7, 255, 1000, 65535, top, top // 2 + 1])
            data = data[:offset] + struct.pack(fmt, min(value, top)) + \
                data[offset + struct.calcsize(fmt):]
    elif how < 6:
        data = data[:rng.randrange(len(data) + 1)]
    elif how < 9:
        data = mutate_bytes(rng, data, rng.randrange(1, 6))
    return FileInput(data, ext)


def exercise_sound(inp: FileInput, folder: Path) -> Outcome:
    """The sound on a scene's object, checked; then decoded whole (mono and stereo) and
    streamed, as the sound manager does."""
    name = "sound" + inp.ext
    (folder / name).write_bytes(inp.data)
    outcome = _checked(folder, f'Object {{ ID "s" Sound {{ File "{name}" }} }}\n')
    assets = Assets(folder)
    try:
        for mono in (True, False):
            assets.clip(name, mono)
        stream = StreamReader(assets.sound(name), mono=True, loop=True)
        try:
            stream.read(4096)
            stream.read(4096)
        finally:
            stream.close()
    except (AssetError, AudioFileError):
        return "message"
    return outcome


MODELS = Target("models", make_model, exercise_model, _files, lambda folder: model_seeds())
IMAGES = Target("images", make_image, exercise_image, _files)
SOUNDS = Target("sounds", make_sound, exercise_sound, _files)
