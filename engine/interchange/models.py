"""A scene's ``Model`` blocks: model files whose bodies, joints and materials join the scene.

::

    Model {
      File "models/room.glb"
      Import 1          // 0: draw the file whole, as scenery
      Prefix "room/"    // before every ID it declares (to import a model twice)
    }

:func:`expand_models` runs when a scene is checked, before the schema check: each
``Model`` entry gets the imported blocks as its ``included`` block, like an ``Include``,
so the check, the factory and a saved state (which writes them out, with their poses
then) see them in its place. Their places point at the ``Model`` block's ``File``, so a
clash with the scene's own IDs is told there. What the model file leaves out is told
as warnings (and errors that skip the broken part); a model that cannot be read at all
leaves its objects out, and the run goes on.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

from engine.assets import AssetError, Assets
from engine.scene.db import STRING, STRUCTURE, Block, Entry, SceneDB, Value
from engine.scene.diagnostics import ERROR, Diagnostic, Reporter
from engine.scene.validate import validate

MODEL = "Model"


def expand_models(db: SceneDB, folder: Path, report: Reporter,
                  known: Mapping[str, Iterable[str]] | None = None,
                  allow: Iterable[Path] = ()) -> list[Diagnostic]:
    """Import every ``Model`` block of ``db`` in place; mistakes in the blocks themselves
    go to ``report``; returns what the model files leave out (to tell, not to stop). Model
    files lie in ``folder`` or one of ``allow`` (engine.confine)."""
    entries = [e for e in db.root if e.key == MODEL and e.value.kind == STRUCTURE]
    if not entries:
        return []
    from engine.interchange.importer import FORMATS, import_model  # only with a Model block

    materials = [str(b.get("ID")) for b in db.root.blocks("Material")]
    has_world = bool(db.root.blocks("World"))
    materials += list((known or {}).get("Material", ()))
    assets = Assets(folder)
    left_out: list[Diagnostic] = []
    for entry in entries:
        if entry.included is not None:
            continue
        own = Reporter(sources=report.sources)  # told by the scene's check, which sees it
        validate(SceneDB(Block([entry], entry.loc), db.path), folder, own, allow=allow)
        if own.has_errors:
            continue
        block: Block = entry.value.data
        file_value = block.value("File")
        file = str(file_value.data)
        if Path(file).suffix.lower() not in FORMATS:
            report.error(file_value.loc, f"Model File \"{file}\" is not a model with bodies to "
                                         f"import: expected {', '.join(FORMATS)}")
            continue
        if not block.get("Import", 1):
            entry.included = _scenery(block, file)
            continue
        try:
            imported = import_model(file, file, assets, file_value.loc, folder,
                                    str(block.get("Prefix", "")), {"Material": materials},
                                    loc=file_value.loc, check=False)
        except AssetError as exc:
            left_out.append(Diagnostic(file_value.loc.path, file_value.loc.line,
                                       file_value.loc.col, ERROR,
                                       f"{exc.message}; the model's objects are left out"))
            entry.included = Block([], entry.loc)
            continue
        report.sources.update(imported.db.sources)
        db.sources.update(imported.db.sources)
        left_out.extend(imported.problems)
        root = imported.db.root
        if has_world and root.blocks("World"):  # one World: the scene's
            root.entries = [e for e in root.entries if e.key != "World"]
            report.warning(file_value.loc, f"the scene's World wins over {file}'s gravity "
                                           f"and time step")
        has_world |= bool(root.blocks("World"))
        entry.included = root
    return left_out


def _scenery(block: Block, file: str) -> Block:
    """``Import 0``: one object drawing the whole file where it stands, without a body."""
    loc = block.value("File").loc
    prefix = str(block.get("Prefix", ""))

    def entry(key: str, value: Value) -> Entry:
        return Entry(key, value, loc)

    def struct(*entries: Entry) -> Value:
        return Value(STRUCTURE, Block(list(entries), loc), loc)

    obj = struct(entry("ID", Value(STRING, prefix + Path(file).stem, loc)),
                 entry("VisualAttributes", struct(entry("Geometry", struct(
                     entry("File", Value(STRING, file, loc)))))))
    return Block([entry("Object", obj)], loc)
