"""The asset service: each file read once per run, by the loader its extension names,
checked, cached for render, physics shapes and sound alike, and every failure told the
same way: ``scene:line:col: error: cannot load model "rock.obj" (models/rock.obj): why``.
"""

from __future__ import annotations

import json
import os
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

import numpy as np

from engine.assets import generated, loaders
from engine.assets.registry import UnknownExtension, loader_for
from engine.assets.types import ImageAsset, ModelAsset

if TYPE_CHECKING:
    from engine.assets.skinned import SkinnedModel
    from engine.assets.sound import Clip, SoundInfo

T = TypeVar("T")


class Where(Protocol):
    """A place in a scene file (``engine.scene.Loc`` is one)."""

    @property
    def path(self) -> str: ...

    @property
    def line(self) -> int: ...

    @property
    def col(self) -> int: ...


class AssetError(ValueError):
    """An asset that cannot be used. ``message`` says what and why; ``str()`` puts the
    scene place that asked for it (when known) in front, compiler style."""

    def __init__(self, action: str, name: str, path: Path, reason: str,
                 where: Where | None = None) -> None:
        self.action, self.name, self.path, self.reason = action, name, path, reason
        self.where = where
        super().__init__(str(self))

    @property
    def message(self) -> str:
        return f'cannot {self.action} "{self.name}" ({self.path}): {self.reason}'

    def at(self, where: Where | None) -> AssetError:
        """The same failure, told at ``where`` (another scene line using the file)."""
        return self if where is None or where == self.where else AssetError(
            self.action, self.name, self.path, self.reason, where)

    def __str__(self) -> str:
        w = self.where
        head = f"{w.path}:{w.line}:{w.col}: " if w is not None else ""
        return f"{head}error: {self.message}"


@dataclass(slots=True)
class _Failed:
    """A cached failure: the file is not read again, and each use is told why."""

    error: AssetError


class Assets:
    """One run's assets, each file read once however many objects, visuals, bodies and
    sounds use it. ``loads`` counts loader calls per resolved path (it stays at 1).

    Files are named as the scene wrote them, relative to ``root`` (the content folder);
    ``where`` is the scene place asking, used in the message if the file is bad (the
    first place that asked is remembered for later users that know none).
    """

    def __init__(self, root: str | Path = ".") -> None:
        self.root = Path(root)
        self.loads: Counter[Path] = Counter()
        self._cache: dict[Any, Any] = {}
        self._paths: dict[tuple[Path, str], Path] = {}
        self._shown: dict[Path, Path] = {}  # resolved path -> as joined, for messages
        self._places: dict[Path, Where] = {}
        self._told: set[Path] = set()
        #: models of nodes checked already, by id (held, so an id is never reused)
        self._checked: dict[int, ModelAsset] = {}

    @classmethod
    def of(cls, engine: Any) -> Assets:
        """The engine's Assets resource, made (rooted at its content folder) if missing."""
        found = engine.try_resource(cls)
        if found is None:
            found = cls(getattr(engine.config, "content_dir", None) or ".")
            engine.insert_resource(found)
        return found

    # -- typed entry points ----------------------------------------------------
    def model(self, name: str | Path, where: Where | None = None,
              root: Path | None = None) -> ModelAsset:
        """The model file ``name``: its parts, checked non-empty and finite. A name made by
        :func:`nodes_name` is some nodes of a file (its document, read once)."""
        file, nodes, mesh = split_nodes(str(name))
        if nodes is None:
            return self._load("model", name, where, root, _check_model)
        document = self.document(file, where, root)
        path = self.resolve(file, root)

        def build() -> ModelAsset:
            model = document.mesh_model(nodes[0]) if mesh else document.node_model(nodes)
            if self._checked.get(id(model)) is not model:  # nodes drawing alike share one
                _check_model(model)
                self._checked[id(model)] = model
            return model

        return self.derived(("nodes", path, nodes, mesh), "load model", _called(name), path,
                            build, where)

    def document(self, name: str | Path, where: Where | None = None,
                 root: Path | None = None) -> Any:
        """The model file ``name`` read as a document of named nodes (a glTF or Collada
        file: :class:`engine.assets.gltf.GltfDocument`), for importers and node models."""
        return self._load("document", name, where, root, _check_document)

    def image(self, name: str | Path, where: Where | None = None,
              root: Path | None = None) -> ImageAsset:
        """The image file ``name``: RGBA pixels, its size checked before decoding; a
        ``generated:`` name is made instead (:mod:`engine.assets.generated`)."""
        make = generated.IMAGES.get(str(name))
        if make is not None:
            key = ("generated", str(name))
            found = self._cache.get(key)
            if found is None:
                found = self._cache[key] = ImageAsset(Path(str(name)), make())
            return found
        return self._load("image", name, where, root, _check_image)

    def skinned(self, name: str | Path, where: Where | None = None,
                root: Path | None = None) -> SkinnedModel:
        """The glTF file ``name`` as a skinned, animated model (an avatar's), checked: its
        parts, palette and clips consistent. What was repaired is in its ``warnings``."""
        return self._load("skin", name, where, root, _check_skinned)

    def sound(self, name: str | Path, where: Where | None = None,
              root: Path | None = None) -> SoundInfo:
        """The sound file ``name``'s header (:class:`engine.assets.sound.SoundInfo`),
        checked: frames present, a plausible sample rate."""
        return self._load("sound", name, where, root, _check_sound)

    def clip(self, name: str | Path, mono: bool, where: Where | None = None,
             root: Path | None = None) -> Clip:
        """The sound ``name`` decoded whole to int16 (:class:`engine.assets.sound.Clip`),
        mixed to mono for a positional source; one decoding per file and ``mono``."""
        from engine.assets.sound import load_clip

        info = self.sound(name, where, root)
        path = self.resolve(name, root)
        return self.derived(("clip", path, mono), "decode sound", _called(name), path,
                            lambda: load_clip(info.path, mono), where)

    def derived(self, key: Any, action: str, name: str, path: Path,
                build: Callable[[], T], where: Where | None = None) -> T:
        """What ``build`` makes from the asset at ``path`` (as :meth:`resolve` gives it):
        a convex hull at a scale, a decoding. Cached under ``key`` like the file itself,
        a failure included; a failure is told as ``cannot {action} "{name}"``."""
        found = self._cache.get(key)
        if found is None:
            try:
                found = build()
            except Exception as exc:  # any library's error, told as this asset's
                found = _Failed(AssetError(action, name, self._shown.get(path, path),
                                           reason(exc), where or self._places.get(path)))
            self._cache[key] = found
        if isinstance(found, _Failed):
            raise found.error.at(where)
        return found

    def adopt(self, other: Assets) -> None:
        """Take over what ``other`` read (a scene built before the engine had this cache),
        so nothing it holds is read again."""
        for key, value in other._cache.items():
            self._cache.setdefault(key, value)
        for found, joined in other._shown.items():
            self._shown.setdefault(found, joined)
        for found, where in other._places.items():
            self._places.setdefault(found, where)
        self._told |= other._told
        self.loads.update(other.loads)

    def mark_told(self, error: AssetError) -> bool:
        """Note that ``error``'s file failure has been told; True if it had not been, so
        a later user (the renderer, the sound manager) does not tell it again."""
        if error.path in self._told:
            return False
        self._told.add(error.path)
        return True

    def resolve(self, name: str | Path, root: Path | None = None) -> Path:
        """The file ``name`` is, resolved (the cache's key): relative to ``root``
        (default: the content folder) unless absolute."""
        base = self.root if root is None else root
        key = (base, str(name))
        found = self._paths.get(key)
        if found is None:
            joined = base / name
            found = self._paths[key] = joined.resolve()
            self._shown.setdefault(found, joined)
        return found

    # -- internals -------------------------------------------------------------
    def _load(self, kind: str, name: str | Path, where: Where | None, root: Path | None,
              check: Callable[[Any], None]) -> Any:
        path = self.resolve(name, root)
        key = (kind, path)
        found = self._cache.get(key)
        if found is None:
            found = self._read(kind, name, path, where, check)
            self._cache[key] = found
        if isinstance(found, _Failed):
            raise found.error.at(where)
        return found

    def _read(self, kind: str, name: str | Path, path: Path, where: Where | None,
              check: Callable[[Any], None]) -> Any:
        if where is not None:
            self._places.setdefault(path, where)
        where = where or self._places.get(path)
        try:
            loader = loader_for(kind, path)
            if not path.is_file():
                raise ValueError("file not found")
            if path.stat().st_size == 0:
                raise ValueError("the file is empty")
            self.loads[path] += 1
            asset = loader.load(self._shown.get(path, path))
            check(asset)
            return asset
        except Exception as exc:  # any loader's error, told as this file's
            what = "model" if kind == "document" else kind  # a model read as its nodes
            return _Failed(AssetError(f"load {what}", _called(name), self._shown.get(path, path),
                                      reason(exc), where))


def nodes_name(file: str, nodes: Sequence[str], mesh: bool = False) -> str:
    """The model name of some nodes of a model file, ``room.glb#["Door", "Handle"]``: what a
    scene's ``Geometry { File "room.glb" Nodes ["Door" "Handle"] }`` draws; with ``mesh``,
    one mesh in its own space, ``room.glb#mesh["Cube"]`` (``Mesh "Cube"``)."""
    return f"{file}#{'mesh' if mesh else ''}{json.dumps(list(nodes), ensure_ascii=False)}"


def split_nodes(name: str) -> tuple[str, tuple[str, ...] | None, bool]:
    """``(file, nodes, mesh)`` of a :func:`nodes_name`; ``(name, None, False)`` for a plain
    file name."""
    for mark, mesh in (('#["', False), ('#mesh["', True)):
        file, found, rest = name.partition(mark)
        if found and rest.endswith("]"):
            try:
                items = json.loads('["' + rest)
            except ValueError:
                continue
            return file, tuple(str(n) for n in items), mesh
    return name, None, False


def _called(name: str | Path) -> str:
    """The name a message quotes: as the scene wrote it, or a full path's file name (the
    full path follows it in parentheses)."""
    text = os.fspath(name)  # os.path, not pathlib: asked for every model a scene draws
    return os.path.basename(text) if os.path.isabs(text) else text


def reason(exc: BaseException) -> str:
    """A library's exception as a short reason an author can act on."""
    if isinstance(exc, ModuleNotFoundError):
        return (f"reading it needs the Python package {exc.name!r}, which is not installed "
                f"(tools/dev setup installs the engine's dependencies)")
    if isinstance(exc, UnknownExtension):
        return str(exc.args[0])
    if isinstance(exc, FileNotFoundError):  # raised inside a loader: a file the file names
        return f"a file it refers to is not there: {exc.filename or exc.args[0]}"
    if isinstance(exc, MemoryError):
        return "not enough memory to read it"
    text = str(exc).strip().splitlines()
    first = text[0] if text else ""
    from engine.assets.sound import AudioFileError

    if isinstance(exc, AudioFileError) and ": error: " in first:  # names the file already
        first = first.split(": error: ", 1)[1]
    if isinstance(exc, (ValueError, AudioFileError)) and first:
        return first
    kind = type(exc).__name__
    return first if first.startswith(kind) else f"{kind}: {first}" if first else kind


def _check_model(model: ModelAsset) -> None:
    if not isinstance(model, ModelAsset):
        raise TypeError(f"a model loader returned {type(model).__name__}, not a ModelAsset")
    if not model.parts:
        raise ValueError("the file holds no triangles")
    for part in model.parts:
        v, f = part.vertices, part.faces
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
            raise ValueError(f"part {part.name!r}: vertices must be (N, 3) and faces (M, 3)")
        if not np.isfinite(v).all():
            raise ValueError(f"part {part.name!r} has vertices that are not finite numbers")
        if len(f) and (f.min() < 0 or f.max() >= len(v)):
            raise ValueError(f"part {part.name!r} has faces naming vertices it does not have")


def _check_skinned(model: SkinnedModel) -> None:
    from engine.assets.skinned import MAX_INFLUENCES, SkinnedModel

    if not isinstance(model, SkinnedModel):
        raise TypeError(f"a skin loader returned {type(model).__name__}, not a SkinnedModel")
    nodes, palette = len(model.parents), len(model.palette_nodes)
    if len(model.inverse_bind) != palette or (palette and model.palette_nodes.max() >= nodes):
        raise ValueError("the palette and its inverse bind matrices do not match the nodes")
    if (model.parents >= np.arange(nodes)).any():
        raise ValueError("nodes must come after their parents")
    for part in model.parts:
        n = len(part.vertices)
        if part.joints.shape != (n, MAX_INFLUENCES) or part.weights.shape != (n, MAX_INFLUENCES):
            raise ValueError(f"part {part.name!r}: joints and weights must be (N, "
                             f"{MAX_INFLUENCES})")
        if n and (part.joints.min() < 0 or part.joints.max() >= palette):
            raise ValueError(f"part {part.name!r} names joints outside the palette")
    for clip in model.clips:
        if any(c.node >= nodes for c in clip.channels):
            raise ValueError(f"clip {clip.name!r} animates a node the model does not have")


def _check_document(document: Any) -> None:
    if not callable(getattr(document, "node_model", None)):
        raise TypeError(f"a document loader returned {type(document).__name__}, which has no "
                        f"node_model(names) and mesh_model(name)")


def _check_image(image: ImageAsset) -> None:
    if not isinstance(image, ImageAsset):
        raise TypeError(f"an image loader returned {type(image).__name__}, not an ImageAsset")
    rgba = image.rgba
    if rgba.dtype != np.uint8 or rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError("an image must be RGBA uint8 pixels (height, width, 4)")
    loaders.check_image_size(rgba.shape[1], rgba.shape[0])


def _check_sound(info: SoundInfo) -> None:
    from engine.assets.sound import SoundInfo, check_header

    if not isinstance(info, SoundInfo):
        raise TypeError(f"a sound loader returned {type(info).__name__}, not a SoundInfo")
    check_header(info)
