"""SceneDB: the ordered, typed tree a scene file parses into.

Every :class:`Entry` (a key with its value) and every :class:`Value` keeps the
file, line and column it came from, so later stages (schema, factory) can point
at the author's text. Keys may repeat and keep their order. An ``Include``
entry keeps the included file's entries under it: the writer writes the
``Include`` line back, while queries see the included entries in place.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from engine.scene.diagnostics import Diagnostic, Loc

INT = "INT"
FLOAT = "FLOAT"
STRING = "STRING"
VECTOR = "VECTOR"
STRINGVECTOR = "STRINGVECTOR"
STRUCTURE = "STRUCTURE"
INCLUDE = "Include"


@dataclass(slots=True, eq=False)
class Value:
    """One typed value. ``expr`` is the canonical expression text a FLOAT came from."""

    kind: str
    data: Any  # int | float | str | list[Value] | Block
    loc: Loc
    expr: str | None = None

    def py(self) -> Any:
        """Plain Python: numbers, str, tuple of numbers/str, or the Block itself."""
        if self.kind in (VECTOR, STRINGVECTOR):
            return tuple(v.data for v in self.data)
        return self.data

    def plain(self) -> Any:
        """Comparable form: kind and data with expression texts, without places/comments."""
        if self.kind == STRUCTURE:
            return (STRUCTURE, self.data.plain())
        if self.kind in (VECTOR, STRINGVECTOR):
            return (self.kind, tuple(v.plain() for v in self.data))
        return (self.kind, self.data, self.expr)


@dataclass(slots=True, eq=False)
class Entry:
    """``key value`` with its place, the comments above it and a trailing comment.

    An empty string among ``comments`` is a blank line the author left there. Comments
    default to a shared empty tuple: a large file has few, and a list per
    entry would be most of what reading it allocates. Give a new sequence to change them.
    """

    key: str
    value: Value
    loc: Loc
    comments: Sequence[str] = ()
    trailing: Sequence[str] = ()
    included: Block | None = None


@dataclass(slots=True, eq=False)
class Block:
    """A STRUCTURE (or a whole file): ordered entries, repeated keys allowed.

    ``inline``: its ``{`` and ``}`` were on one line (the writer keeps a short one so).
    """

    entries: list[Entry] = field(default_factory=list)
    loc: Loc = field(default_factory=lambda: Loc("", 1, 1))
    open_comment: Sequence[str] = ()
    tail_comments: Sequence[str] = ()
    inline: bool = False

    def __iter__(self) -> Iterator[Entry]:
        """Entries in order, with included files' entries spliced in place."""
        for e in self.entries:
            if e.included is not None:
                yield from e.included
            else:
                yield e

    def entry(self, key: str) -> Entry | None:
        """The last entry named ``key`` (a later key overrides an earlier one)."""
        found = None
        for e in self:
            if e.key == key:
                found = e
        return found

    def value(self, key: str) -> Value | None:
        e = self.entry(key)
        return e.value if e is not None else None

    def get(self, key: str, default: Any = None) -> Any:
        """The plain value of ``key`` (see :meth:`Value.py`), or ``default``."""
        v = self.value(key)
        return default if v is None else v.py()

    def get_all(self, key: str) -> list[Entry]:
        return [e for e in self if e.key == key]

    def blocks(self, key: str) -> list[Block]:
        """Every STRUCTURE value named ``key``, in order."""
        return [e.value.data for e in self if e.key == key and e.value.kind == STRUCTURE]

    def keys(self) -> list[str]:
        return [e.key for e in self]

    def find(self, path: str) -> Value | None:
        """Path lookup: ``"Object[cow]/VisualAttributes/Geometry/File"``.

        A segment ``Key[n]`` picks the n-th (0-based) ``Key``; ``Key[name]`` picks
        the ``Key`` block whose ``ID`` is ``name``; a bare ``Key`` the last one.
        """
        node: Value | None = None
        block: Block | None = self
        for seg in [s for s in path.split("/") if s]:
            if block is None:
                return None
            key, _, sel = seg.partition("[")
            sel = sel.rstrip("]")
            matches = block.get_all(key)
            if sel:
                if sel.lstrip("-").isdigit() and not any(_id_of(e) == sel for e in matches):
                    idx = int(sel)
                    matches = matches[idx:idx + 1] if -len(matches) <= idx < len(matches) else []
                else:
                    matches = [e for e in matches if _id_of(e) == sel]
            if not matches:
                return None
            node = matches[-1].value
            block = node.data if node.kind == STRUCTURE else None
        return node

    def plain(self) -> tuple:
        out = []
        for e in self.entries:
            inc = e.included.plain() if e.included is not None else None
            out.append((e.key, e.value.plain(), inc))
        return tuple(out)


def _id_of(e: Entry) -> str | None:
    if e.value.kind != STRUCTURE:
        return None
    v = e.value.data.value("ID")
    return None if v is None else str(v.data)


@dataclass(slots=True, eq=False)
class SceneDB:
    """A parsed scene: the root block, the file it came from and the texts read."""

    root: Block
    path: str
    sources: dict[str, str] = field(default_factory=dict)
    warnings: list[Diagnostic] = field(default_factory=list)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, SceneDB) and self.root.plain() == other.root.plain()

    def __iter__(self) -> Iterator[Entry]:
        return iter(self.root)

    def get(self, key: str, default: Any = None) -> Any:
        return self.root.get(key, default)

    def get_all(self, key: str) -> list[Entry]:
        return self.root.get_all(key)

    def blocks(self, key: str) -> list[Block]:
        return self.root.blocks(key)

    def find(self, path: str) -> Value | None:
        return self.root.find(path)
