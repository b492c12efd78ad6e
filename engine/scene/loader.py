"""Entry points the CLI uses: load, check and format a scene file or content folder.

A PATH may be a ``.scene`` file or a content folder (its ``main.scene``). Asset
files are looked for relative to the scene file's folder.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Iterator, Mapping
from pathlib import Path

import numpy as np

from engine.memory import paused_gc
from engine.scene.db import SceneDB
from engine.scene.diagnostics import ERROR, Diagnostic, Report, Reporter, SceneError
from engine.scene.factory import Pose, SceneSpec, build_specs
from engine.scene.parser import Limits, parse_file, parse_text
from engine.scene.paths import FOLDER, NOT_FOUND, file_problem, shown
from engine.scene.validate import validate
from engine.scene.writer import write

MAIN_SCENE = "main.scene"


def scene_path(path: str | Path) -> Path:
    """The scene file a PATH names (a content folder means its main.scene)."""
    p = Path(path)
    return p / MAIN_SCENE if file_problem(p) == FOLDER else p


def _unreadable(path: Path) -> SceneError | None:
    """The error for a scene file that cannot be read, or None when it can."""
    problem = file_problem(path)
    if problem is None:
        return None
    if problem != NOT_FOUND:
        message = f"cannot read {shown(path)}: {problem}"
    elif path.name == MAIN_SCENE:
        message = f"content folder has no main.scene: {shown(path)}"
    else:
        message = f"no such file: {shown(path)}"
    return SceneError([Diagnostic(str(path), 1, 1, "error", message)])


def content_folder(db: SceneDB) -> Path:
    """The folder a scene's file names are relative to: the content folder a saved state
    names (``Content``), else the scene file's own. Raises SceneError when a saved
    state's folder is not there: the file was moved without it."""
    named = db.root.value("Content")
    if named is None or not isinstance(named.data, str):  # (the schema check reports one
        return Path(db.path).parent                        # that is not a string)
    folder = (Path(db.path).parent / named.data).resolve()
    if folder.is_dir() and not (folder / "main.scene").is_file():  # not one to trust
        raise SceneError([Diagnostic(
            named.loc.path, named.loc.line, named.loc.col, ERROR,
            f"this saved state continues {named.data!r}, which is not a content folder (it "
            "has no main.scene); a saved state's files are read from the content folder it "
            "continues, so it must name one")], db.sources)
    if folder.is_dir():
        return folder
    raise SceneError([Diagnostic(
        named.loc.path, named.loc.line, named.loc.col, ERROR,
        f"this saved state continues the content folder {named.data!r}, relative to the "
        f"file ({folder}), which does not exist: the file was moved (or its content folder "
        "was). Paths in a saved state are relative to the file; put it back, or change "
        "Content to the content folder's path from where the file is now")], db.sources)


def validated(db: SceneDB, content_dir: Path | None = None,
              known: Mapping[str, Collection[str]] | None = None,
              allow: Iterable[Path] = ()) -> SceneDB:
    """Check ``db`` against the schema; raises SceneError (with warnings kept) on errors.
    ``Model`` blocks are imported first (their blocks checked with the rest); what their
    files leave out is kept with the warnings. Files it names must lie in the content
    folder or one of ``allow``."""
    from engine.interchange.models import expand_models

    folder = content_dir if content_dir is not None else Path(db.path).parent
    _declare_blocks(folder)
    report = Reporter(list(db.warnings), dict(db.sources))
    with paused_gc():
        left_out = expand_models(db, folder, report, known, allow)
        validate(db, folder, report, known, allow)
    report.raise_if_errors()
    db.warnings = [*report.diagnostics, *left_out]
    return db


def load_scene(path: str | Path, rng: np.random.Generator | None = None,
               limits: Limits | None = None, allow: Iterable[Path] = ()) -> SceneDB:
    """Parse and validate a scene file or content folder. Raises SceneError."""
    return _with_folder(path, rng, limits, allow)[0]


def load_spec(path: str | Path, rng: np.random.Generator | None = None,
              allow: Iterable[Path] = ()) -> SceneSpec:
    """Parse, validate and build specs (models loaded), ready to instantiate. Raises SceneError."""
    return build_specs(*_with_folder(path, rng, allow=allow))


def _with_folder(path: str | Path, rng: np.random.Generator | None,
                 limits: Limits | None = None, allow: Iterable[Path] = ()
                 ) -> tuple[SceneDB, Path]:
    """The checked scene and the folder its file names are relative to (a saved state's
    content folder, else the file's own); files it names lie there or in ``allow``.
    Raises SceneError."""
    target = scene_path(path)
    unreadable = _unreadable(target)
    if unreadable is not None:
        raise unreadable
    db = parse_file(target, rng, limits, allow)
    folder = content_folder(db)
    return validated(db, folder, allow=allow), folder


def _declare_blocks(folder: Path) -> None:
    """Import the content folder's systems/*.py before its scene is checked, wherever the
    scene comes from (its file, a saved state, a server's state on a node): the blocks
    they declare (engine.scene.blocks) are part of the scene's language. A module that
    fails is a SceneError at its file."""
    from engine.content import ContentError, import_systems

    try:
        import_systems(folder)
    except ContentError as exc:
        path = str(exc).split(":", 1)[0]
        raise SceneError([Diagnostic(path, 1, 1, ERROR, str(exc).split(": ", 1)[-1])]
                         ) from exc


class Besides(Collection[str]):
    """The names in ``names`` but not in ``own`` (a snippet's own IDs shadow the running
    world's), asked in place: a world of any size is never copied."""

    def __init__(self, names: Collection[str], own: Collection[str]) -> None:
        self.names, self.own = names, own

    def __contains__(self, name: object) -> bool:
        return name not in self.own and name in self.names

    def __iter__(self) -> Iterator[str]:
        return (n for n in self.names if n not in self.own)

    def __len__(self) -> int:
        return sum(1 for _ in self)


def spec_from_text(text: str, content_dir: str | Path, rng: np.random.Generator | None = None,
                   path: str = "<string>", scene: SceneSpec | None = None,
                   bodies: Mapping[str, Pose] | None = None,
                   allow: Iterable[Path] = ()) -> SceneSpec:
    """Specs from a scene-format snippet (what Lua uses to spawn objects at run time).

    With ``scene`` (the running scene's spec) the snippet may use its materials and
    shader states by ID; ``bodies`` (ID -> current pose) are what its joints may
    attach to besides its own objects. An object or material ID the snippet declares
    itself names its own, not a duplicate of the scene's (spawning "ball" again, with
    its "wood"); the snippet's objects use the snippet's material. Files it names (its
    ``Include``s too) lie in ``content_dir`` or one of ``allow``.
    """
    db = parse_text(text, path, rng, base_dir=content_dir, allow=allow)
    own = {str(b.get("ID")) for b in db.blocks("Object")}
    if bodies is None:  # looked up by ID, never copied or counted: a live view of a world
        bodies = {}
    known: dict[str, Collection[str]] = {"Object": Besides(bodies.keys(), own)}
    if scene is not None:
        own_materials = {str(b.get("ID")) for b in db.blocks("Material")}
        known |= {"Material": [m for m in scene.materials if m not in own_materials],
                  "ShaderState": scene.shader_states, "ShaderProgram": scene.shader_programs}
    db = validated(db, Path(content_dir), known, allow)
    return build_specs(db, content_dir, scene.materials if scene is not None else None, bodies,
                       scene.assets if scene is not None else None,
                       scene.world.extent if scene is not None else None)


def check(path: str | Path, rng: np.random.Generator | None = None,
          allow: Iterable[Path] = ()) -> Report:
    """Every error and warning of a scene (parse, schema, references, assets, models),
    with the texts read, so the report renders without reading a file again."""
    try:
        db, folder = _with_folder(path, rng, allow=allow)
        spec = build_specs(db, folder)
    except SceneError as exc:
        return Report(exc.diagnostics, exc.sources)
    except RecursionError:  # the limits should make this unreachable; never crash a check
        return Report([Diagnostic(str(path), 1, 1, "error",
                                  "scene is nested too deeply to read")])
    return Report(Reporter([*db.warnings, *spec.problems]).diagnostics, db.sources)


def format_scene(path: str | Path) -> str:
    """Canonical text of a scene file (comments kept, includes not inlined). Raises SceneError."""
    target = scene_path(path)
    unreadable = _unreadable(target)
    if unreadable is not None:
        raise unreadable
    return write(parse_file(target))


__all__ = ["check", "format_scene", "load_scene", "load_spec", "scene_path",
           "spec_from_text", "validated"]
