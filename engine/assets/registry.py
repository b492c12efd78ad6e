"""Loaders by file extension: which function reads a ``.obj``, a ``.png``, a ``.wav``.

A loader is a function ``load(path) -> asset`` registered for a *kind* (``"model"``,
``"image"``, ``"sound"`` or ``"skin"``: a skinned,
animated model for an avatar) and the extensions it reads; :class:`engine.assets.Assets`
picks it by the file's extension, calls it once per file and checks what it returned.
Registering an extension that already has a loader replaces that loader (a user's
loader may take over a built-in format).

The engine's own loaders (:data:`BUILT_IN`) register as their modules are imported, and
the registry imports them all before it is first read or written to by anyone else: a
scene's check that reads no glTF or Collada file and no avatar loads none of their readers.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

#: The kinds of asset there are loaders for, and what their loaders return. A
#: ``document`` is a model file read as named nodes: anything with
#: ``node_model(names)`` and ``mesh_model(name)``, each a ModelAsset (see
#: :mod:`engine.assets.gltf`).
KINDS = {"model": "ModelAsset", "image": "ImageAsset", "sound": "SoundInfo",
         "skin": "SkinnedModel", "document": "a document of nodes"}

F = TypeVar("F", bound=Callable[[Path], Any])


@dataclass(frozen=True, slots=True)
class Loader:
    kind: str
    extension: str
    load: Callable[[Path], Any]


class UnknownExtension(LookupError):
    """No loader of the wanted kind reads files with this extension."""


_LOADERS: dict[tuple[str, str], Loader] = {}
#: The modules of the engine's own loaders, imported in this order (the order their
#: extensions are listed in) before the registry's first use.
BUILT_IN = ("engine.assets.loaders", "engine.assets.gltf", "engine.assets.dae",
            "engine.assets.skinned")
_built_in: list[bool] = []  # [True] once BUILT_IN were imported


def _with_built_ins() -> None:
    """Import the engine's own loaders, once, so a lookup sees them and a user's
    registration comes after them (and may replace one)."""
    if not _built_in:
        _built_in.append(True)
        for module in BUILT_IN:
            importlib.import_module(module)


def _normal(extension: str) -> str:
    ext = extension.lower()
    return ext if ext.startswith(".") else f".{ext}"


def register_loader(kind: str, *extensions: str) -> Callable[[F], F]:
    """Decorator: the function reads files of ``kind`` ending in any of ``extensions``
    (see the example in :mod:`engine.assets`)."""
    _with_built_ins()
    return built_in_loader(kind, *extensions)


def built_in_loader(kind: str, *extensions: str) -> Callable[[F], F]:
    """:func:`register_loader` for the modules of :data:`BUILT_IN` themselves, which
    register as they are imported (by the registry or by whoever needs their readers)."""
    if kind not in KINDS:
        raise ValueError(f"unknown asset kind {kind!r}; kinds: {', '.join(KINDS)}")
    if not extensions:
        raise ValueError("register_loader needs at least one extension, such as '.obj'")

    def register(load: F) -> F:
        for ext in extensions:
            _LOADERS[(kind, _normal(ext))] = Loader(kind, _normal(ext), load)
        return load

    return register


def unregister_loader(kind: str, extension: str) -> None:
    """Forget the loader of ``kind`` for ``extension`` (tests, plugins that unload)."""
    _with_built_ins()
    _LOADERS.pop((kind, _normal(extension)), None)


def extensions(kind: str) -> tuple[str, ...]:
    """The extensions ``kind`` has loaders for, in the order they were registered."""
    _with_built_ins()
    return tuple(ext for k, ext in _LOADERS if k == kind)


def loader_for(kind: str, path: Path) -> Loader:
    """The loader of ``kind`` for ``path``'s extension; raises :class:`UnknownExtension`
    naming the extensions there are loaders for."""
    _with_built_ins()
    ext = path.suffix.lower()
    found = _LOADERS.get((kind, ext))
    if found is None:
        raise UnknownExtension(
            f"unsupported {kind} format {ext or '(no extension)'!r}; "
            f"supported: {', '.join(extensions(kind))} (more with "
            f"engine.assets.register_loader)")
    return found
