"""The built-in loaders: models through trimesh, images through Pillow, sounds through
libsndfile (:mod:`engine.assets.sound`).

Each raises with a short reason on a bad file; :class:`engine.assets.Assets` adds the
file and the scene line that asked for it.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from engine.assets.registry import built_in_loader
from engine.assets.types import WHITE, ImageAsset, MeshPart, ModelAsset

if TYPE_CHECKING:
    from engine.assets.sound import SoundInfo

#: Model formats trimesh reads for us (.dae through pycollada).
MODEL_EXTENSIONS = (".obj", ".stl", ".ply", ".glb", ".gltf", ".dae")
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".tif", ".tiff", ".gif", ".webp")
SOUND_EXTENSIONS = (".wav", ".ogg", ".oga", ".flac", ".aiff", ".aif")

#: Largest image side and pixel count we decode: a texture GL can hold (16k) and at most
#: 256 MiB of RGBA, so a decompression bomb is refused from its header, before decoding.
MAX_IMAGE_SIDE = 16384
MAX_IMAGE_PIXELS = 8192 * 8192

#: glTF is +Y up; the engine is +Z up.
_Y_UP_TO_Z_UP = np.array([[1.0, 0, 0, 0], [0, 0, -1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])


@built_in_loader("model", *MODEL_EXTENSIONS)
def load_trimesh_model(path: Path) -> ModelAsset:
    """Every triangle geometry of the file's scene, placed by its node, one part per
    geometry (trimesh splits by material), glTF turned Z up."""
    import trimesh

    if path.suffix.lower() == ".gltf":  # trimesh reads non-JSON as a lookup of another file
        try:
            json.loads(path.read_bytes())
        except ValueError as exc:
            raise ValueError(f"not a glTF file: it is not JSON ({exc})") from None
    scene = trimesh.load(str(path), force="scene", process=False)
    parts = []
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        _require_finite(np.asarray(geom.vertices), str(geom_name))
        geom = geom.copy()
        geom.process()  # merge duplicate vertices, so normals are smooth as the file meant
        geom.apply_transform(transform)
        if path.suffix.lower() in (".gltf", ".glb"):
            geom.apply_transform(_Y_UP_TO_Z_UP)
        parts.append(_part(geom, str(geom_name)))
    return ModelAsset(path, tuple(parts))


def _require_finite(vertices: np.ndarray, part: str) -> None:
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"{int(bad.sum())} vertices are not finite numbers (the first, "
                         f"vertex {i + 1} of {part!r}, is {vertices[i].tolist()})")


def _part(tm: Any, name: str) -> MeshPart:
    """A trimesh mesh as a part: its positions, smooth normals, uv and material."""
    positions = np.asarray(tm.vertices, dtype=np.float64)
    uv = colors = texture = None
    color = WHITE
    visual = tm.visual
    if visual is not None and visual.kind == "texture":
        found = getattr(visual, "uv", None)
        if found is not None and len(found) == len(positions):
            uv = np.asarray(found, dtype=np.float64)
        material = getattr(visual, "material", None)
        if material is not None:
            image = getattr(material, "baseColorTexture", None) or getattr(material, "image",
                                                                           None)
            # glTF multiplies its texture by baseColorFactor; for OBJ/MTL the texture map
            # replaces Kd, as in common viewers
            factor = getattr(material, "baseColorFactor", None)
            if factor is None and image is None:
                factor = getattr(material, "diffuse", None)
            if factor is not None:
                color = _rgba(factor)
            if image is not None and uv is not None:
                texture = rgba_pixels(image)
    elif visual is not None and visual.kind in ("vertex", "face"):
        colors = np.asarray(visual.vertex_colors, dtype=np.float64)[:, :4] / 255.0
    return MeshPart(positions, np.asarray(tm.faces, dtype=np.int64),
                    np.asarray(tm.vertex_normals, dtype=np.float64), uv, colors, color,
                    texture, name)


def _rgba(factor: Any) -> tuple[float, float, float, float]:
    f = np.asarray(factor, dtype=np.float64).reshape(-1)
    c = tuple(float(x) for x in (f / 255.0 if f.max() > 1.0 else f))
    return (c[0], c[1], c[2], c[3] if len(c) > 3 else 1.0)


def rgba_pixels(image: Any) -> np.ndarray:
    """RGBA uint8 ``(H, W, 4)`` of a PIL image or an array (float 0..1 or uint8)."""
    from PIL import Image

    if isinstance(image, Image.Image):
        check_image_size(*image.size)
        return np.asarray(image.convert("RGBA"), dtype=np.uint8)
    arr = np.asarray(image)
    if arr.dtype != np.uint8:
        arr = np.clip(arr * 255.0, 0, 255).astype(np.uint8)
    if arr.ndim == 2:
        arr = np.repeat(arr[:, :, None], 3, axis=2)
    if arr.shape[2] == 3:
        arr = np.concatenate([arr, np.full(arr.shape[:2] + (1,), 255, np.uint8)], axis=2)
    return arr


def check_image_size(width: int, height: int) -> None:
    """Refuse, from the header alone, an image too large to be a texture."""
    if width <= 0 or height <= 0:
        raise ValueError(f"the image is {width}x{height} pixels: empty")
    if max(width, height) > MAX_IMAGE_SIDE or width * height > MAX_IMAGE_PIXELS:
        raise ValueError(f"the image claims {width}x{height} pixels, more than a texture may "
                         f"have ({MAX_IMAGE_SIDE} a side, {MAX_IMAGE_PIXELS} in all); not "
                         f"decoded (a decompression bomb, or far too large)")


@built_in_loader("image", *IMAGE_EXTENSIONS)
def load_pillow_image(path: Path) -> ImageAsset:
    """Pixels through Pillow; the size is checked from the header before decoding."""
    from PIL import Image, UnidentifiedImageError

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(path) as img:
                check_image_size(*img.size)
                return ImageAsset(path, rgba_pixels(img))
    except UnidentifiedImageError:
        raise ValueError("not an image Pillow can read") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        raise ValueError(f"not decoded: {str(exc).rstrip('.')}") from None


@built_in_loader("sound", *SOUND_EXTENSIONS)
def load_sound_info(path: Path) -> SoundInfo:
    """The sound's header (rate, channels, frames), checked; decoding is per use
    (:meth:`engine.assets.Assets.clip`), since positional sources need a mono mixdown
    and long files are streamed."""
    from engine.assets.sound import probe

    return probe(path)
