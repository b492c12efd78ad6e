"""Writer: SceneDB -> canonical scene text, the parser's inverse.

Canonical form: one key per line, two-space indent, ``Key {`` ... ``}`` for
structures, numbers as Python writes them (floats round-trip exactly),
expressions as their canonical text, comments kept where they were attached
(above a key, trailing on its line, after an opening brace, or at a block's
end). ``Include`` lines are written back as they were, not inlined.
"""

from __future__ import annotations

from engine.scene.db import STRINGVECTOR, STRUCTURE, VECTOR, Block, SceneDB, Value

INDENT = "  "
_ESCAPE = {"\\": "\\\\", '"': '\\"', "\u201c": "\\\u201c", "\u201d": "\\\u201d",
           "\n": "\\n", "\t": "\\t", "\r": "\\r"}


def quote(s: str) -> str:
    return '"' + "".join(_ESCAPE.get(ch, ch) for ch in s) + '"'


def scalar(v: Value, literal: bool = False) -> str:
    """A scalar's text; ``literal`` drops expressions and writes the evaluated number."""
    if v.expr is not None and not literal:
        return v.expr
    if isinstance(v.data, str):
        return quote(v.data)
    if isinstance(v.data, int):
        return str(v.data)
    return repr(float(v.data))


def write(db: SceneDB | Block, literal: bool = False, flatten: bool = False) -> str:
    """The whole scene in canonical form.

    ``literal`` freezes every expression's value; ``flatten`` writes included
    files' entries in place of their ``Include`` lines (a self-contained file).
    """
    block = db.root if isinstance(db, SceneDB) else db
    lines: list[str] = []
    _block(block, 0, lines, literal, flatten)
    return "\n".join(lines) + "\n" if lines else ""


def _comments(texts: list[str], pad: str, lines: list[str]) -> None:
    lines.extend(pad + t for t in texts)


def _block(block: Block, depth: int, lines: list[str], literal: bool, flatten: bool) -> None:
    pad = INDENT * depth
    for e in block.entries:
        _comments(e.comments, pad, lines)
        if flatten and e.included is not None:
            _block(e.included, depth, lines, literal, flatten)
            continue
        trailing = (" " + " ".join(e.trailing)) if e.trailing else ""
        v = e.value
        if v.kind == STRUCTURE:
            inner: Block = v.data
            opener = (" " + " ".join(inner.open_comment)) if inner.open_comment else ""
            if not inner.entries and not inner.tail_comments and not opener:
                lines.append(f"{pad}{e.key} {{}}{trailing}")
                continue
            lines.append(f"{pad}{e.key} {{{opener}")
            _block(inner, depth + 1, lines, literal, flatten)
            lines.append(f"{pad}}}{trailing}")
        else:
            lines.append(f"{pad}{e.key} {value_text(v, literal)}{trailing}")
    _comments(block.tail_comments, pad, lines)


def value_text(v: Value, literal: bool = False) -> str:
    if v.kind in (VECTOR, STRINGVECTOR):
        return "[" + " ".join(scalar(i, literal) for i in v.data) + "]"
    return scalar(v, literal)
