"""Skipping what a scene file got wrong, so that a run goes on.

``colosseum check`` reports every error and stops there; ``colosseum run`` reports the same
errors, then leaves out each broken part and runs the rest: the top-level entry an error
lies in (an ``Object``, a ``Joint``, a ``Light``, an unknown key, ...), or, inside a
settings block such as ``World``, just the broken key, whose default then holds. A part
that named a skipped one (a joint on a skipped object) fails in turn and is skipped the
next round. Parts are found by place (file, line, column), so the same text parsed again
with the same seed loses the same parts.

>>> from engine.scene.parser import parse_text
>>> db = parse_text('Object { ID "a" }\\nWorld { TimeStep 0 Gravity [0 0 -1] }\\n', "s")
>>> errors = [Diagnostic("s", 1, 1, "error", "x"), Diagnostic("s", 2, 18, "error", "y")]
>>> parts = broken_parts(db, errors)
>>> [(p.key, p.loc.line) for p in parts]
[('Object', 1), ('TimeStep', 2)]
>>> skip(db, {p.loc for p in parts})
>>> [e.key for e in db], db.root.blocks("World")[0].get("Gravity")
(['World'], (0, 0, -1))
"""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Collection, Iterable, Iterator

from engine.scene.db import STRUCTURE, VECTOR, Block, Entry, SceneDB, Value
from engine.scene.diagnostics import Diagnostic, Loc

#: Blocks of settings: a broken key in one is skipped alone (its default holds), not the
#: whole block.
SETTINGS = frozenset({"World"})


def _locs(value: Value) -> Iterator[Loc]:
    yield value.loc
    if value.kind == STRUCTURE:
        for entry in value.data:
            yield entry.loc
            yield from _locs(entry.value)
    elif value.kind == VECTOR or isinstance(value.data, list):
        for item in value.data:
            yield from _locs(item)


def _spans(entry: Entry) -> dict[str, tuple[tuple[int, int], tuple[int, int]]]:
    """Per file, the first and last place of ``entry``: its key and all inside its value."""
    spans: dict[str, tuple[tuple[int, int], tuple[int, int]]] = {}
    for loc in (entry.loc, *_locs(entry.value)):
        here = (loc.line, loc.col)
        low, high = spans.get(loc.path, (here, here))
        spans[loc.path] = (min(low, here), max(high, here))
    return spans


def _holds(span: tuple[tuple[int, int], ...] | None, where: tuple[int, int]) -> bool:
    return span is not None and span[0] <= where <= span[1]


def _top_entries(block: Block) -> Iterator[Entry]:
    """Top-level entries, included files' entries in place of their ``Include``."""
    for entry in block.entries:
        if entry.included is not None:
            yield from _top_entries(entry.included)
        else:
            yield entry


def broken_parts(db: SceneDB, errors: Iterable[Diagnostic | Loc]) -> list[Entry]:
    """The entries to skip for ``errors`` (diagnostics, or the places of a SceneError's
    every error), in file order; an error no entry holds (a file that could not be read,
    a problem of the whole scene) has none. Linear in the file and the errors: each
    top-level entry's span is found once, each error's entry by bisection."""
    tops = list(_top_entries(db.root))
    by_path: dict[str, list[tuple[tuple[int, int], tuple[int, int], int]]] = {}
    for i, top in enumerate(tops):
        for path, (low, high) in _spans(top).items():
            by_path.setdefault(path, []).append((low, high, i))
    starts = {}
    for path, spans in by_path.items():
        spans.sort()
        starts[path] = [low for low, _, _ in spans]
    found: dict[Loc, Entry] = {}
    for error in errors:
        where = (error.line, error.col)
        spans = by_path.get(error.path, [])
        k = bisect_right(starts.get(error.path, []), where) - 1
        if k < 0 or not _holds(spans[k][:2], where):  # not in the one starting last before
            k = next((j for j, span in enumerate(spans) if _holds(span[:2], where)), -1)
            if k < 0:
                continue
        top = part = tops[spans[k][2]]
        if top.key in SETTINGS and top.value.kind == STRUCTURE:
            part = next((e for e in top.value.data.entries
                         if _holds(_spans(e).get(error.path), where)), top)
        found[part.loc] = part
    return sorted(found.values(), key=lambda e: (e.loc.path, e.loc.line, e.loc.col))


def skip(db: SceneDB, places: Collection[Loc]) -> None:
    """Remove the entries whose keys stand at ``places`` (top level, in included files, or
    inside a settings block)."""
    def prune(block: Block, depth: int) -> None:
        kept = []
        for entry in block.entries:
            if entry.loc in places:
                continue
            if entry.included is not None:
                prune(entry.included, depth)
            elif depth == 0 and entry.key in SETTINGS and entry.value.kind == STRUCTURE:
                prune(entry.value.data, depth + 1)
            kept.append(entry)
        block.entries[:] = kept

    prune(db.root, 0)


def described(part: Entry) -> str:
    """``main.scene:3: Joint "hinge"`` for the list of what a run skipped."""
    name = ""
    if part.value.kind == STRUCTURE:
        named = part.value.data.value("ID")
        if named is not None and isinstance(named.data, str):
            name = f' "{named.data}"'
    return f"{part.loc.path}:{part.loc.line}: {part.key}{name}"
