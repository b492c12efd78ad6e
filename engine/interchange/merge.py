"""Importing again: what came from the model is updated, what the author changed is kept.

``colosseum import room.glb -o room.scene`` writes the scene file and, beside it,
``room.scene.imported``: exactly what the import wrote, before anyone edited it. The next
import of the (changed) model is a three-way merge of that *base*, the author's file
(*ours*) and the new import (*theirs*), key by key:

* blocks are matched by kind and ID (a MaterialPair by its two materials), keys inside
  a block by name (a repeated key, such as ``Geometry``, as one list);
* a key the author left as the base has it takes the new import's value (or goes, if
  the model no longer declares it); a key the author changed, added or removed stays
  as the author left it, and a model change to it is told, not applied;
* a block the model adds is added; one it drops goes, unless the author edited it
  (then it stays, told); one the author deleted stays deleted; the author's own blocks,
  variables, includes and comments are kept where they are.

Without a base (a scene written by hand, or the ``.imported`` file lost) nothing tells
an edit from an import, so the file is not overwritten unless asked (``--force``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from engine.scene.db import STRUCTURE, Block, Entry, SceneDB
from engine.scene.writer import value_text

#: Suffix of the file keeping what the last import wrote.
BASE_SUFFIX = ".imported"


@dataclass(slots=True)
class MergeResult:
    """The merged scene and what the author's edits kept from the model (``kept``)."""

    db: SceneDB
    kept: list[str] = field(default_factory=list)
    added: int = 0
    updated: int = 0
    removed: int = 0


Identity = tuple[str, str]


def identity(entry: Entry) -> Identity | None:
    """What a top-level block is across imports: its kind and ID (None: not matched)."""
    if entry.value.kind != STRUCTURE:
        return None
    block: Block = entry.value.data
    if entry.key == "MaterialPair":
        return entry.key, f"{block.get('Material1')}|{block.get('Material2')}"
    found = block.get("ID")
    return None if found is None else (entry.key, str(found))


def merge(base: SceneDB, ours: SceneDB, theirs: SceneDB) -> MergeResult:
    """``ours`` (the author's file) with the model's changes from ``base`` to ``theirs``
    applied where the author did not edit; ``ours`` is changed in place and returned."""
    result = MergeResult(ours)
    base_items = _items(base.root)
    their_items = _items(theirs.root)
    our_items = _items(ours.root)
    for ident, theirs_entry in their_items.items():
        base_entry, our_entry = base_items.get(ident), our_items.get(ident)
        if base_entry is None and our_entry is None:
            ours.root.entries.append(theirs_entry)
            result.added += 1
        elif base_entry is None:
            result.kept.append(f"{_name(ident)}: the model now declares it too; yours is kept")
        elif our_entry is None:
            if not _same(base_entry, theirs_entry):
                result.kept.append(f"{_name(ident)}: you deleted it; the model changed it, it "
                                   f"stays deleted")
        elif _merge_block(base_entry.value.data, our_entry.value.data,
                          theirs_entry.value.data, _name(ident), result.kept):
            result.updated += 1
    for ident, base_entry in base_items.items():
        our_entry = our_items.get(ident)
        if ident in their_items or our_entry is None:
            continue
        if _same(base_entry, our_entry):
            ours.root.entries.remove(our_entry)
            result.removed += 1
        else:
            result.kept.append(f"{_name(ident)}: the model no longer declares it; you edited "
                               f"it, so it is kept")
    return result


def _items(block: Block) -> dict[Identity, Entry]:
    found: dict[Identity, Entry] = {}
    for e in block.entries:
        ident = identity(e)
        if ident is not None:
            found.setdefault(ident, e)
    return found


def _name(ident: Identity) -> str:
    return f"{ident[0]} '{ident[1]}'"


def _plain(entries: list[Entry]) -> tuple:
    return tuple((e.key, e.value.plain()) for e in entries)


def _same(a: Entry, b: Entry) -> bool:
    return a.value.plain() == b.value.plain()


def _merge_block(base: Block, ours: Block, theirs: Block, where: str,
                 kept: list[str]) -> bool:
    """Apply the model's changes (base -> theirs) to ``ours`` key by key where the author
    left the key as the base has it; True if anything changed."""
    changed = False
    keys = list(dict.fromkeys([e.key for e in theirs.entries] + [e.key for e in base.entries]))
    for key in keys:
        b, o, t = base.get_all(key), ours.get_all(key), theirs.get_all(key)
        if _plain(b) == _plain(t):
            continue  # the model did not change it: whatever the author has stays
        single = len(b) == len(o) == len(t) == 1 and all(
            x[0].value.kind == STRUCTURE for x in (b, o, t))
        if single:
            changed |= _merge_block(b[0].value.data, o[0].value.data, t[0].value.data,
                                    f"{where} {key}", kept)
        elif _plain(o) == _plain(b):
            _replace(ours, key, t)
            changed = True
        else:
            kept.append(f"{where}: your {key} is kept; the model now says "
                        f"{_text(t) or 'nothing'}")
    return changed


def _replace(block: Block, key: str, entries: list[Entry]) -> None:
    """Put ``entries`` where ``block``'s ``key`` entries were (or at its end)."""
    positions = [i for i, e in enumerate(block.entries) if e.key == key]
    at = positions[0] if positions else len(block.entries)
    block.entries[:] = [e for e in block.entries if e.key != key]
    block.entries[at:at] = entries


def _text(entries: list[Entry]) -> str:
    return " ".join(f"{e.key} {value_text(e.value)}" if e.value.kind != STRUCTURE
                    else f"{e.key} {{...}}" for e in entries)
