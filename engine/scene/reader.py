"""A scene block's values as plain Python, the schema's defaults filled in: what the
scene builder (engine.scene.factory) and an Object's parts (engine.scene.objects) read."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import engine.scene.blocks as blocks
import engine.scene.schema as sc
from engine.scene.db import (
    INCLUDE,
    STRINGVECTOR,
    STRUCTURE,
    VECTOR,
    Block,
    Entry,
    Value,
)

_DEFAULTS = {name: {k: f.default for k, f in fields.items()}
             for name, fields in sc.SCHEMAS.items()}
blocks.on_register(lambda name: _DEFAULTS.__setitem__(
    name, {k: f.default for k, f in sc.SCHEMAS[name].items()}))


class Reader(dict):
    """A block's values as plain Python with the schema's defaults filled in.

    ``r("Key")`` is the value (or default); ``r.has("Key")`` whether the author wrote it.
    """

    __slots__ = ("entries", "block", "has", "value", "block_name")
    __call__ = dict.__getitem__

    def __init__(self, block: Block | None, schema: str):
        dict.__init__(self, _DEFAULTS[schema])
        self.block_name = schema
        entries = [] if block is None else block.entries
        last = self._read(entries)
        if INCLUDE in last:  # read again with the included files' entries spliced in
            entries = list(block)  # type: ignore[arg-type]
            self.clear()
            self.update(_DEFAULTS[schema])
            last = self._read(entries)
        self.entries = entries
        self.block = block
        #: Whether the author wrote ``key``; the Value written (or None).
        self.has: Callable[[str], bool] = last.__contains__
        self.value: Callable[[str], Value | None] = last.get

    def _read(self, entries: list[Entry]) -> dict[str, Value]:
        """Set each key's plain value (the last one written wins); returns the Values."""
        last: dict[str, Value] = {}
        for e in entries:
            v = last[e.key] = e.value
            self[e.key] = tuple([x.data for x in v.data]) if v.kind in _VECTORS else v.data
        return last

    def blocks(self, key: str) -> list[Block]:
        return [e.value.data for e in self.entries
                if e.key == key and e.value.kind == STRUCTURE]


_VECTORS = (VECTOR, STRINGVECTOR)


class Index:
    """The root block's entries grouped by key in one pass (10,000 objects, a dozen keys)."""

    def __init__(self, root: Block):
        self.loc = root.loc
        self.groups: dict[str, list[Entry]] = {}
        for e in root:
            self.groups.setdefault(e.key, []).append(e)

    def get_all(self, key: str) -> list[Entry]:
        return self.groups.get(key, [])

    def blocks(self, key: str) -> list[Block]:
        return [e.value.data for e in self.get_all(key) if e.value.kind == STRUCTURE]

    def value(self, key: str) -> Value | None:
        found = self.get_all(key)
        return found[-1].value if found else None


def floats(t: Any) -> tuple[float, ...]:
    return tuple(map(float, t))

