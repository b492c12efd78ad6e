"""A model file as checked scene blocks: read by its format's importer, turned into blocks,
checked against the schema (an author's extras that do not check are told and left
out, node by node), materials the extras name declared."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from engine.assets import AssetError, Assets, Where
from engine.assets.service import reason
from engine.interchange.model import ImportedScene, MaterialDecl, Problems, to_db
from engine.memory import paused_gc
from engine.scene.db import STRING, SceneDB
from engine.scene.diagnostics import WARNING, Diagnostic, Loc, Reporter, SceneError
from engine.scene.validate import validate

#: Model formats the importer reads, by extension.
FORMATS = {".gltf": "glTF", ".glb": "glTF", ".dae": "Collada"}


@dataclass(slots=True)
class Imported:
    """One import: the scene blocks, what the file declared, and every problem told."""

    db: SceneDB
    scene: ImportedScene
    problems: list[Diagnostic]


def read_model(name: str | Path, assets: Assets, where: Where | None = None,
               root: Path | None = None) -> ImportedScene:
    """What the model file ``name`` declares. A file that cannot be read at all raises
    ``AssetError`` (at ``where``); anything less is a problem in the result."""
    path = assets.resolve(name, root)
    document = assets.document(name, where, root)
    problems = Problems(str(Path(name)) if not Path(name).is_absolute() else str(path))
    from engine.interchange.collada import import_collada
    from engine.interchange.gltf_physics import import_gltf

    read = import_collada if path.suffix.lower() == ".dae" else import_gltf
    return read(document, problems)


def import_model(name: str | Path, file_ref: str, assets: Assets | None = None,
                 where: Where | None = None, root: Path | None = None, prefix: str = "",
                 known: Mapping[str, Iterable[str]] | None = None,
                 header: bool = False, loc: Loc | None = None, check: bool = True) -> Imported:
    """The model file ``name`` as checked scene blocks naming it ``file_ref`` (relative
    to the scene's folder). ``known`` are IDs the scene declares besides (a scene that
    imports the model may define the materials its extras name); ``header`` puts a
    comment on top saying where the blocks came from; ``loc`` is the place the blocks
    say they come from (default: the model file). Raises ``AssetError`` when the file
    cannot be read at all. ``check`` False leaves the schema check of what the importer
    made to the caller (a scene checks its Model blocks' with the rest); the author's
    extras are checked either way."""
    assets = assets or Assets(root or Path(name).parent)
    try:
        with paused_gc():  # many small objects that all stay alive
            return _imported(name, file_ref, assets, where, root, prefix, known, header, loc,
                             check)
    except (AssetError, SceneError):  # told already, at their own places
        raise
    except (ValueError, TypeError, AttributeError, KeyError, IndexError, OverflowError) as exc:
        # a part the importer needs whole (the scene's node list, a body's position) lies
        # or has the wrong JSON or XML shape: the file cannot be imported
        raise AssetError("import model", str(name), assets.resolve(name, root),
                         f"it is malformed ({reason(exc)})", where) from None


def _imported(name: str | Path, file_ref: str, assets: Assets, where: Where | None,
              root: Path | None, prefix: str, known: Mapping[str, Iterable[str]] | None,
              header: bool, loc: Loc | None, check: bool) -> Imported:
    scene = read_model(name, assets, where, root)
    problems = scene.problems or Problems(str(name))
    _declare_materials(scene, prefix, known or {}, problems)
    lines = _header(scene, file_ref) if header else ()
    for _ in range(len(scene.objects) + 1):  # each round leaves out one more node's extras
        db = to_db(scene, file_ref, prefix, lines, loc)
        db.sources.update(scene.sources)
        report = Reporter(sources=dict(db.sources))
        if not check and not scene.sources:
            break
        validate(db, None, report, known)
        bad = {d.path for d in report.diagnostics if d.is_error and d.path in scene.sources}
        if not bad:
            break
        problems.items.extend(d for d in report.diagnostics if d.path in bad)
        for obj in scene.objects:
            if any(e.loc.path in bad for entries in obj.extras.values() for e in entries):
                obj.extras.clear()
                problems.error(obj.node, "its extras are left out (see the errors above)")
        scene.scene_extras = [e for e in scene.scene_extras if e.loc.path not in bad]
    if report.has_errors:  # not the author's extras: the importer made a bad block
        raise SceneError(report.diagnostics, db.sources)
    problems.items.extend(d for d in report.diagnostics if d.severity == WARNING)
    return Imported(db, scene, problems.items)


def _declare_materials(scene: ImportedScene, prefix: str,
                       known: Mapping[str, Iterable[str]], problems: Problems) -> None:
    """Materials the nodes' extras name that neither the file nor the scene declares get
    a default declaration (told), so the imported scene runs and the author can tune it."""
    declared = {m.id for m in scene.materials} | {"default"}
    declared |= {str(x)[len(prefix):] for x in known.get("Material", ())}
    declared |= {str(e.value.data.get("ID")) for e in scene.scene_extras
                 if e.key == "Material" and e.value.kind == "STRUCTURE"}
    for obj in scene.objects:
        for e in obj.extras.get("Physical", []):
            name = str(e.value.data)
            if e.key == "Material" and e.value.kind == STRING and name not in declared:
                declared.add(name)
                scene.materials.append(MaterialDecl(name, 0.5, 0.0))
                problems.warn(obj.node, f"its extras name Material '{name}', which is not "
                                        f"declared: declared here with the default friction "
                                        f"and bounce (edit them in the scene)")


def _header(scene: ImportedScene, file_ref: str) -> tuple[str, ...]:
    read = ", ".join(scene.read) if scene.read else "no physics extension"
    return (f"Imported from {file_ref} ({scene.format}; read: {read}) by colosseum import.",
            "Edit freely: importing again keeps what you change here and updates the rest",
            "(the file beside this one ending in .imported is what the last import wrote).")

