"""Writer: SceneDB -> canonical scene text, the parser's inverse.

Canonical form: one key per line, two-space indent, ``Key {`` ... ``}`` for
structures, numbers as Python writes them (floats round-trip exactly),
expressions as their canonical text, comments kept where they were attached
(above a key, trailing on its line, after an opening brace, or at a block's
end). ``Include`` lines are written back as they were, not inlined. The author's
layout is kept where it reads well: a blank line between entries stays (one for a
run of them), and a block written on one line stays on one line while it has no
comments and fits in :data:`LINE_LIMIT` columns.
"""

from __future__ import annotations

from collections.abc import Sequence

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


#: Widest line a one-line block is kept on (wider ones are written a key per line).
LINE_LIMIT = 100


def _comments(texts: Sequence[str], pad: str, lines: list[str]) -> None:
    lines.extend(pad + t if t else "" for t in texts)  # "" is a blank line


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
            one_line = _one_line(inner, literal, flatten)
            if one_line is not None and len(pad) + len(e.key) + len(one_line) + len(
                    trailing) < LINE_LIMIT:
                lines.append(f"{pad}{e.key} {one_line}{trailing}")
                continue
            lines.append(f"{pad}{e.key} {{{opener}")
            _block(inner, depth + 1, lines, literal, flatten)
            lines.append(f"{pad}}}{trailing}")
        else:
            lines.append(f"{pad}{e.key} {value_text(v, literal)}{trailing}")
    _comments(block.tail_comments, pad, lines)


def _one_line(block: Block, literal: bool, flatten: bool) -> str | None:
    """``{ a 1 b { c 2 } }`` for a block written on one line without comments, else None."""
    if not block.inline or block.open_comment or block.tail_comments:
        return None
    parts: list[str] = []
    for e in block.entries:
        if e.comments or e.trailing or (flatten and e.included is not None):
            return None
        if e.value.kind == STRUCTURE:
            inner = _one_line(e.value.data, literal, flatten)
            if inner is None:
                return None
            parts.append(f"{e.key} {inner}")
        else:
            parts.append(f"{e.key} {value_text(e.value, literal)}")
    return "{ " + " ".join(parts) + " }" if parts else "{}"


def value_text(v: Value, literal: bool = False) -> str:
    if v.kind in (VECTOR, STRINGVECTOR):
        return "[" + " ".join(scalar(i, literal) for i in v.data) + "]"
    return scalar(v, literal)
