"""Content folders: find the scene, load the author's Python systems.

A content folder holds ``main.scene`` and optionally ``systems/*.py``; each
such module defines ``build(engine)`` (a plugin function) or a ``plugin``
object with ``build``. The modules are imported before the scene is built, so
one may register asset loaders (:func:`engine.assets.register_loader`) for the
files the scene names; ``build`` runs once the engine exists. A module that
fails to import or build is reported with its path and traceback.
"""

from __future__ import annotations

import importlib.util
import sys
import traceback
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from engine.app import Engine

REPO_ROOT = Path(__file__).resolve().parent.parent
#: The module names a content folder's systems/*.py are imported under start so.
CONTENT_MODULES = "colosseum_content_"
DEMO = REPO_ROOT / "content" / "demo"
SCENE_NAME = "main.scene"


class ContentError(Exception):
    """A content folder or one of its files cannot be used; the message names it."""


@dataclass(frozen=True, slots=True)
class Content:
    folder: Path
    scene: Path


def resolve(path: str | Path | None) -> Content:
    """Map a CLI PATH (folder, scene file or nothing) to a content folder and its scene."""
    target = DEMO if path is None else Path(path)
    if not target.exists():
        raise ContentError(f"{target}: no such file or folder")
    if target.is_dir():
        scene = target / SCENE_NAME
        if not scene.is_file():
            raise ContentError(
                f"{target}: not a content folder: it has no {SCENE_NAME} "
                f"(create one with `colosseum new NAME`)"
            )
        return Content(target.resolve(), scene.resolve())
    return Content(target.resolve().parent, target.resolve())


def import_systems(folder: Path) -> list[tuple[Path, ModuleType]]:
    """Import ``folder/systems/*.py``, each once per process (its module code runs then:
    the place to register asset loaders); returns (path, module) in name order."""
    imported = []
    for path in sorted((folder / "systems").glob("*.py")):
        module_name = f"{CONTENT_MODULES}{abs(hash(str(folder)))}_{path.stem}"
        module = sys.modules.get(module_name)
        if module is None:
            try:
                spec = importlib.util.spec_from_file_location(module_name, path)
                assert spec is not None and spec.loader is not None
                module = importlib.util.module_from_spec(spec)
                sys.modules[module_name] = module
                spec.loader.exec_module(module)
            except Exception as exc:
                sys.modules.pop(module_name, None)
                trace = "".join(traceback.format_exception(exc))
                raise ContentError(f"{path}: custom system failed to load:\n{trace}") from exc
        imported.append((path, module))
    return imported


def load_systems(engine: Engine, folder: Path) -> list[str]:
    """Import ``folder/systems/*.py`` (if not yet) and build each as a plugin; return
    their names."""
    loaded = []
    for path, module in import_systems(folder):
        try:
            build = getattr(module, "build", None)
            plugin = getattr(module, "plugin", None)
            if build is not None:
                build(engine)
            elif plugin is not None:
                engine.add_plugin(plugin)
            else:
                raise ContentError(f"{path}: defines neither build(engine) nor plugin")
        except ContentError:
            raise
        except Exception as exc:
            trace = "".join(traceback.format_exception(exc))
            raise ContentError(f"{path}: custom system failed to load:\n{trace}") from exc
        loaded.append(path.stem)
    return loaded
