"""Parser: tokens -> SceneDB, evaluating expressions as it goes.

Grammar::

    file   := entry*
    entry  := KEY value
    value  := STRING | '{' entry* '}' | '[' item* ']' | expression
    item   := STRING | expression

Errors do not stop the pass: the parser reports, skips to the next line that
starts with a key, and carries on, so one run lists every mistake. Limits on
file size, token count and nesting depth turn hostile or broken input into a
clear message instead of a crash. ``Include "file"`` splices another file in
place (relative to the including file; cycles are errors).

Speed: most entries of a real file are plain (``KEY "text"``, ``KEY 1.5``,
``KEY [1 2 3]``, ``KEY {`` ... ``}`` on tidy lines). Those are read straight
from the text with a few compiled regular expressions (``FAST``), several
tokens per match and no Token objects; the token path (lexer + recursive
descent) reads everything else, and both give exactly the same SceneDB, places,
diagnostics and token count. That reads a 10,000-object file three times faster.
Built with Cython (``setup.py build_ext``), ``engine/scene/_scan.pyx`` replaces
that regex scanner (:func:`_scan_plain`) with one reading a character at a time,
about 2.5 times faster again; without the extension the regex scanner is used.
"""

from __future__ import annotations

import gc
import os
import re
from bisect import bisect_right
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from math import isfinite
from pathlib import Path

import numpy as np

from engine.scene import expr as ex
from engine.scene.db import (
    FLOAT,
    INCLUDE,
    INT,
    STRING,
    STRINGVECTOR,
    STRUCTURE,
    VECTOR,
    Block,
    Entry,
    SceneDB,
    Value,
)
from engine.scene.diagnostics import Loc, Reporter, sorted_diagnostics
from engine.scene.lexer import (
    EOF,
    IDENT,
    NAME_RE,
    NUMBER,
    NUMBER_RE,
    PUNCT,
    SPACE,
    Comment,
    Lexer,
    Token,
)
from engine.scene.lexer import STRING as T_STRING

_OPERATORS = frozenset("+-*/^")
_new = tuple.__new__  # Loc(...) without NamedTuple's Python-level __new__ (hot path)

#: A plain entry read straight from the text, without tokens: ``KEY "string"``,
#: ``KEY number`` (followed by a lexeme that is not an operator, a comment or a bad
#: character, which the lexer would skip), ``KEY [`` (items: ``_ITEM``) or
#: ``KEY {`` on one line; or a closing ``}``. Group :attr:`~re.Match.lastindex`
#: tells which. Anything else (comments, expressions, errors) takes the token path.
FAST = re.compile(
    rf"""[{SPACE}\n]*+(?:
    ({NAME_RE})[{SPACE}]*+(?:
        "([^"\\\n\u201c\u201d]*+)"
      | ({NUMBER_RE})(?=[{SPACE}\n]*+(?:[A-Za-z_0-9\[\](){{}},"\u201c\u201d]|\.[0-9]|\Z))
      | (\{{)
      | (\[))
    | (\}}))""", re.VERBOSE)
_STRING, _NUMBER, _OPEN, _VECTOR, _CLOSE = 2, 3, 4, 5, 6

#: A vector's items when all are numbers (optionally signed) one space apart, then ``]``.
_NUMBERS = re.compile(rf"((?:[+-]?{NUMBER_RE} )*+[+-]?{NUMBER_RE})?\]")

#: One vector item read from the text: a signed number, or an optionally signed number or
#: name with at most one operator and operand, written without spaces; or the closing ``]``.
_ITEM = re.compile(
    rf"""[{SPACE}]*+(?:
    (\])
  | ([+-]?)(?:({NUMBER_RE})|({NAME_RE}))
    (?:([*/+-])(?:({NUMBER_RE})|({NAME_RE})))?
    (?=[{SPACE}\]]))""", re.VERBOSE)


@dataclass(frozen=True, slots=True)
class Limits:
    """What a scene file may not exceed; past these the file is refused, not half-read."""

    max_bytes: int = 64 * 1024 * 1024
    max_tokens: int = 8_000_000
    max_nesting: int = 64
    max_files: int = 256


class _FileCursor(ex.Cursor):
    def __init__(self, lexer: Lexer, limits: Limits):
        super().__init__(lexer, limits.max_nesting)
        self.comments = lexer.comments
        self.ci = 0
        self.text = lexer.text

    def take_comments(self, before: int) -> list[Comment]:
        start = self.ci
        while self.ci < len(self.comments) and self.comments[self.ci].pos < before:
            self.ci += 1
        return self.comments[start:self.ci]


_CLOSED = -1  # what Parser._plain returns after the block's closing '}'
#: A block opened by the scanner and not closed yet: (entry, parent's entries, parent's scope).
Open = tuple[Entry, list[Entry], dict[str, float]]


class Parser:
    """One parse of a file and what it includes, sharing a reporter, an rng and scopes."""

    def __init__(self, rng: np.random.Generator | None, limits: Limits,
                 base_dir: Path | None = None):
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.base_dir = base_dir
        self.limits = limits
        self.report = Reporter()
        self.scopes: list[dict[str, float]] = [{}]
        self.stack: list[str] = []
        self.files = 0

    # -- files -------------------------------------------------------------
    def parse_file(self, path: Path, at: Loc | None = None) -> Block:
        text = self._read(path, at)
        return Block(loc=Loc(str(path), 1, 1)) if text is None else self.parse_source(text,
                                                                                     str(path))

    def _read(self, path: Path, at: Loc | None) -> str | None:
        where = at or Loc(str(path), 1, 1)
        try:
            size = path.stat().st_size
            if size > self.limits.max_bytes:
                self.report.error(where, f"file {path} is {size} bytes, larger than the "
                                         f"{self.limits.max_bytes}-byte limit")
                return None
            data = path.read_bytes()
        except OSError as exc:
            self.report.error(where, f"cannot read {path}: {exc.strerror or exc}")
            return None
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError as exc:
            text = data.decode("utf-8", errors="replace")
            before = data[:exc.start].decode("utf-8", errors="replace")
            line = before.count("\n") + 1
            col = len(before) - (before.rfind("\n") + 1) + 1
            self.report.error(Loc(str(path), line, col), "file is not valid UTF-8 text")
            return text

    def parse_source(self, text: str, path: str) -> Block:
        self.files += 1
        self.report.sources[path] = text
        root = Block(loc=Loc(path, 1, 1))
        if len(text) > self.limits.max_bytes:
            self.report.error(root.loc, f"scene text is {len(text)} characters, larger than "
                                        f"the {self.limits.max_bytes} limit")
            return root
        lexer = Lexer(text, path, self.report, self.limits.max_tokens)
        cur = _FileCursor(lexer, self.limits)
        self.stack.append(os.path.abspath(path))
        scopes = len(self.scopes)
        try:
            self._block(cur, root, None)
        except ex.NestingError as exc:
            self.report.error(exc.loc, exc.message)
        finally:
            self.stack.pop()
            del self.scopes[scopes:]  # blocks left open by the error
        lexer.finish()  # lexical errors after a refused nesting are still reported
        return root

    # -- blocks ------------------------------------------------------------
    def _block(self, cur: _FileCursor, block: Block, opener: Token | None,
               prev: Entry | None = None, prev_line: int | None = None) -> None:
        """Entries up to the block's ``}`` (or the file's end); ``prev`` and ``prev_line``
        carry on from entries the fast path already read into ``block``."""
        pending: list[str] = []
        if prev_line is None:
            prev_line = opener.line if opener else -1
        tokens, comments, path = cur.tokens, cur.comments, cur.path
        entries = block.entries
        scope = self.scopes[-1]
        while True:
            if cur.ci == len(comments) and (cur.i == len(tokens) or (
                    cur.i == len(tokens) - 1 and tokens[-1].kind is IDENT)):
                n = len(entries)
                last_line = self._plain(cur, block, opener is not None, scope)
                if len(entries) > n:
                    if pending:
                        entries[n].comments = pending
                        pending = []
                    prev = entries[-1]
                if last_line == _CLOSED:
                    break
                if last_line is not None:
                    prev_line = last_line
                    continue
            t = cur.at(cur.i)
            if cur.ci < len(comments) and comments[cur.ci].pos < t.pos:
                for c in cur.take_comments(t.pos):
                    if c.trailing and c.line == prev_line:
                        if prev:
                            prev.trailing = [*prev.trailing, c.text]
                        else:
                            block.open_comment = [*block.open_comment, c.text]
                    else:
                        pending.append(c.text)
            kind = t.kind
            if kind != IDENT:
                if kind == EOF:
                    if opener is not None:
                        self.report.error(cur.loc(opener), f"'{{' from line {opener.line} is "
                                                           "never closed with '}'")
                    break
                if kind == PUNCT and t.text == "}":
                    cur.advance()
                    if opener is not None:
                        break
                    self.report.error(cur.loc(t), "'}' without a matching '{'")
                    continue
                self.report.error(cur.loc(t), f"expected a key name but found {ex.describe(t)}")
                self._sync(cur, t.line, skip_first=True)
                continue
            cur.i += 1
            nesting = cur.nesting
            try:
                value = self._value(cur, t)
            except ex.NestingError:
                raise
            except ex.ExprError as exc:
                self.report.error(exc.loc, exc.message)
                cur.nesting = nesting
                self._sync(cur, t.line)
                continue
            key = t.text
            last = tokens[cur.i - 1]
            if cur.ci < len(comments) and comments[cur.ci].pos < last.pos:
                # Comments inside a vector or expression move above the key.
                pending.extend(c.text for c in cur.take_comments(last.pos))
            entry = Entry(key, value, Loc(path, t.line, t.col), pending or ())
            pending = []  # a new list: entries must not share one
            if value.kind is INT or value.kind is FLOAT:
                scope[key] = value.data
            if key == INCLUDE:
                entry.included = self._include(value, cur)
            entries.append(entry)
            prev = entry
            prev_line = last.line
        block.tail_comments = pending or ()

    def _plain(self, cur: _FileCursor, block: Block, nested: bool,
               scope: dict[str, float]) -> int | None:
        """Read plain entries (see ``FAST``) straight from the text, as many as follow.

        Returns None if there was none (nothing consumed), ``_CLOSED`` after the
        block's ``}`` (only if ``nested``), else the line of the last token read.
        Reads exactly what the token path would, with the same places and token
        count. Plain ``KEY {`` blocks are read here too, without recursion; where
        one stops being plain, :meth:`_block` reads the rest of it.
        """
        lexer, tokens = cur.lexer, cur.tokens
        lookahead = cur.i < len(tokens)  # a key already scanned: read it again from the text
        pos = tokens[-1].pos if lookahead else lexer.pos
        count = start = lexer.count - lookahead
        entries = block.entries
        stack: list[Open] = []  # blocks opened here and not closed yet
        while True:
            pos, count, close = scan_plain(self, cur, pos, count, entries, scope, stack)
            if lookahead and count != start:  # the key was read again from the text
                tokens.pop()
                lookahead = False
            if close >= 0 and nested:
                starts = lexer.line_starts
                line = bisect_right(starts, close)  # (never after a lookahead key)
                lexer.skip(close + 1, count + 1)
                tokens.append(Token(PUNCT, "}", None, line, close - starts[line - 1] + 1, close,
                                    close > pos))
                cur.i = len(tokens)
                return _CLOSED
            if count == start:
                return None
            lexer.skip(pos, count)
            starts = lexer.line_starts
            last_line = bisect_right(starts, pos - 1)  # of the last token read
            while stack:  # the token path reads the rest of each open block
                entry, entries, scope = stack.pop()
                inner: Block = entry.value.data
                loc = inner.loc
                opener = Token(PUNCT, "{", None, loc.line, loc.col,
                               starts[loc.line - 1] + loc.col - 1, True)
                self._block(cur, inner, opener, inner.entries[-1] if inner.entries else None,
                            last_line)
                self.scopes.pop()
                cur.nesting -= 1
                if entry.key == INCLUDE:
                    entry.included = self._include(entry.value, cur)
                last_line = tokens[cur.i - 1].line
                if cur.i == len(tokens) and cur.ci == len(cur.comments):
                    break  # plain again: read on in the enclosing block
            else:
                return last_line
            pos, count = lexer.pos, lexer.count

    def _sync(self, cur: _FileCursor, line: int, skip_first: bool = False) -> None:
        """Skip to the next key that starts a line, or the end of the current block."""
        if skip_first:
            cur.advance()
        depth = 0
        while cur.tok.kind != EOF:
            t = cur.tok
            if t.kind == PUNCT:
                if t.text in "{[(":
                    depth += 1
                elif t.text == "}":
                    if depth == 0:
                        return
                    depth -= 1
                elif t.text in "])":
                    depth = max(depth - 1, 0)
            elif (t.kind == IDENT and depth == 0 and t.line > line
                  and cur.tokens[cur.i - 1].line < t.line):
                return
            cur.advance()

    def _lookup(self, name: str) -> float | None:
        for scope in reversed(self.scopes):
            if name in scope:
                return scope[name]
        return None

    def _unknown(self, name: str) -> bool:
        """Not a variable, constant or function: most likely the next key."""
        return (self._lookup(name) is None and name not in ex.CONSTANTS
                and name not in ex.FUNCTIONS)

    def _names(self) -> list[str]:
        return [n for scope in self.scopes for n in scope]

    # -- values ------------------------------------------------------------
    def _value(self, cur: _FileCursor, key: Token) -> Value:
        t = cur.at(cur.i)
        kind = t.kind
        if kind == T_STRING:
            cur.i += 1
            return Value(STRING, t.value, Loc(cur.path, t.line, t.col))
        if kind == PUNCT:
            if t.text == "{":
                cur.i += 1
                cur.enter(t)
                loc = Loc(cur.path, t.line, t.col)
                block = Block(loc=loc)
                self.scopes.append({})
                try:
                    self._block(cur, block, t)
                finally:
                    self.scopes.pop()
                cur.nesting -= 1
                return Value(STRUCTURE, block, loc)
            if t.text == "[":
                return self._vector(cur, t)
        if kind == EOF or (kind == PUNCT and t.text == "}") or (
                kind == IDENT and t.line != key.line and self._unknown(t.text)):
            raise ex.ExprError(cur.loc(key), f"key '{key.text}' has no value")
        if kind in (NUMBER, IDENT) or (kind == PUNCT and t.text in "(+-"):
            return self._scalar(cur, in_vector=False)
        raise ex.ExprError(cur.loc(t), f"expected a value after '{key.text}' but found "
                                       f"{ex.describe(t)}")

    def _scalar(self, cur: _FileCursor, in_vector: bool) -> Value:
        t = cur.at(cur.i)
        if t.kind == NUMBER:  # a plain number not followed by an operator
            nxt = cur.at(cur.i + 1)
            if nxt.kind != PUNCT or nxt.text not in _OPERATORS or (
                    in_vector and nxt.text in "+-" and nxt.space_before
                    and not cur.at(cur.i + 2).space_before):
                cur.i += 1
                lit = ex.number(cur, t)
                return Value(INT if isinstance(lit, int) else FLOAT, lit,
                             Loc(cur.path, t.line, t.col))
        node = ex.parse_expression(cur, in_vector)
        loc = cur.loc(t)
        lit = ex.literal(node)
        if lit is not None:
            return Value(INT if isinstance(lit, int) else FLOAT, lit, loc)
        try:
            v = ex.evaluate(node, self._lookup, self._names, self.rng)
        except ex.ExprError as exc:
            self.report.error(exc.loc if exc.loc.line else loc, exc.message)
            v = 0.0
        return Value(FLOAT, v, loc, ex.unparse(node))

    def _vector(self, cur: _FileCursor, opener: Token) -> Value:
        cur.i += 1
        cur.enter(opener)
        items: list[Value] = []
        tokens, path = cur.tokens, cur.path
        strings = 0
        while True:
            t = cur.at(cur.i)
            kind = t.kind
            if kind == PUNCT and t.text == "]":
                cur.i += 1
                break
            if kind == EOF or (kind == PUNCT and t.text == "}"):
                raise ex.ExprError(cur.loc(opener), f"'[' from line {opener.line} is never "
                                                    "closed with ']'")
            if kind == T_STRING:
                cur.i += 1
                items.append(Value(STRING, t.value, Loc(path, t.line, t.col)))
                strings += 1
            elif kind == IDENT and tokens[cur.i - 1].line < t.line and self._unknown(t.text):
                # A key at the start of a line: the vector was left open.
                raise ex.ExprError(cur.loc(opener), f"'[' from line {opener.line} is never "
                                                    "closed with ']'")
            else:
                items.append(self._scalar(cur, in_vector=True))
        cur.nesting -= 1
        loc = Loc(path, opener.line, opener.col)
        if strings and strings != len(items):
            self.report.error(loc, "vector mixes strings and numbers; a VECTOR holds numbers, "
                                   "a STRINGVECTOR holds strings")
            items = [v for v in items if v.kind == STRING]
        return Value(STRINGVECTOR if strings else VECTOR, items, loc)

    def _include(self, value: Value, cur: _FileCursor) -> Block | None:
        if value.kind != STRING:
            self.report.error(value.loc, 'Include expects a file name: Include "other.scene"')
            return None
        base = Path(cur.path).parent if os.path.isfile(cur.path) else (
            self.base_dir or Path.cwd())
        target = (base / value.data).resolve()
        if str(target) in self.stack:
            chain = " -> ".join(Path(p).name for p in [*self.stack, str(target)])
            self.report.error(value.loc, f"Include cycle: {chain}")
            return None
        if len(self.stack) >= self.limits.max_nesting:
            self.report.error(value.loc, f"Includes nested deeper than "
                                         f"{self.limits.max_nesting} files (limit)")
            return None
        if self.files >= self.limits.max_files:
            self.report.error(value.loc, f"more than {self.limits.max_files} included files "
                                         "(limit)")
            return None
        if not target.is_file():
            self.report.error(value.loc, f"included file not found: {target}")
            return None
        return self.parse_file(target, value.loc)



def _scan_plain(p: Parser, cur: _FileCursor, pos: int, count: int, entries: list[Entry],
                scope: dict[str, float], stack: list[Open]) -> tuple[int, int, int]:
    """Plain entries (see ``FAST``) from ``pos`` into ``entries``, until one is not plain.

    ``count`` is the token count so far; blocks opened go on ``stack`` (and their
    scopes on ``p.scopes``) and are closed at their ``}``. Returns the position and
    token count after the last entry read, and where a ``}`` closing the block being
    read stands (-1 if reading stopped elsewhere). ``engine.scene._scan`` is the same
    scanner compiled, used when built.
    """
    lexer = cur.lexer
    text, path, starts = cur.text, cur.path, lexer.line_starts
    match = FAST.match
    max_tokens = lexer.max_tokens
    scopes = p.scopes
    while True:
        m = match(text, pos)
        if m is None:
            break
        kind = m.lastindex
        if kind == _CLOSE:
            if count >= max_tokens:
                break
            if not stack:
                return pos, count, m.start(_CLOSE)
            pos = m.end()
            count += 1
            entry, entries, scope = stack.pop()
            scopes.pop()
            cur.nesting -= 1
            if entry.key == INCLUDE:
                entry.included = p._include(entry.value, cur)
            continue
        at = m.start(1)
        line = bisect_right(starts, at)
        line_start = starts[line - 1]
        vpos = m.start(kind)
        end = m.end()
        used = 2
        if kind == _STRING:  # the group is inside the quotes
            value = Value(STRING, m.group(_STRING), _new(Loc, (path, line, vpos - line_start)))
        elif kind == _NUMBER:
            digits = m.group(_NUMBER)
            lit = (int(digits) if len(digits) < 16 and digits.isdigit()
                   else ex.number_value(digits))
            if lit is None:
                break
            value = Value(INT if type(lit) is int else FLOAT, lit,
                          _new(Loc, (path, line, vpos - line_start + 1)))
        elif cur.nesting >= cur.max_nesting:
            break  # the token path reports the limit
        else:
            vloc = _new(Loc, (path, line, vpos - line_start + 1))
            if kind == _VECTOR:
                found = _fast_vector(scopes, text, end, vloc, line_start,
                                     cur.nesting + 2 <= cur.max_nesting)
                if found is None:
                    break
                value, end, used = found
            else:
                value = Value(STRUCTURE, Block([], vloc), vloc)
        if count + used > max_tokens:
            break
        count += used
        pos = end
        key = m.group(1)
        entry = Entry(key, value, _new(Loc, (path, line, at - line_start + 1)))
        entries.append(entry)
        if kind == _NUMBER:
            scope[key] = lit
        if kind == _OPEN:
            stack.append((entry, entries, scope))
            entries = value.data.entries
            scope = {}
            scopes.append(scope)
            cur.nesting += 1
        elif key == INCLUDE:
            entry.included = p._include(value, cur)
    return pos, count, -1


def _fast_vector(scopes: list[dict[str, float]], text: str, pos: int, loc: Loc,
                 line_start: int, signs: bool) -> tuple[Value, int, int] | None:
    """``KEY [`` ... ``]`` from ``pos`` (just after ``[``) as (VECTOR, end, tokens used).

    None if an item is not plain, or has a sign where ``signs`` is false (a sign is
    one more nesting level for the token path, which reports the limit).
    """
    items: list[Value] = []
    path, line = loc.path, loc.line
    m = _NUMBERS.match(text, pos)
    if m is not None:  # only numbers: split them instead of matching each one
        numbers = m.group(1)
        parts = numbers.split(" ") if numbers else []
        col = pos - line_start + 1
        signs_used = 0
        for part in parts:
            at = col
            col += len(part) + 1
            if len(part) < 16 and part.isdigit():
                items.append(Value(INT, int(part), _new(Loc, (path, line, at))))
                continue
            sign = part[0] in "+-"
            v = ex.number_value(part[1:] if sign else part)
            if v is None or (sign and not signs):
                return None
            if sign:
                signs_used += 1
                if part[0] == "-":
                    v = -v
            items.append(Value(INT if type(v) is int else FLOAT, v,
                               _new(Loc, (path, line, at))))
        return Value(VECTOR, items, loc), m.end(), 3 + len(parts) + signs_used
    used = 3
    match = _ITEM.match
    scopes = scopes[::-1]  # innermost first, as Parser._lookup reads them
    while True:
        m = match(text, pos)
        if m is None:
            return None
        pos = m.end()
        if m.lastindex == 1:  # ']'
            break
        sign, num, name, op, num2, name2 = m.group(2, 3, 4, 5, 6, 7)
        if sign and not signs:
            return None
        at = _new(Loc, (path, line, m.start(2) - line_start + 1))
        if num is not None:
            a = int(num) if len(num) < 16 and num.isdigit() else ex.number_value(num)
            if a is None:
                return None
            if op is None:
                used += 2 if sign else 1
                items.append(Value(INT if type(a) is int else FLOAT,
                                   -a if sign == "-" else a, at))
                continue
            text_a = sign + ex.number_text(a)
        else:
            a = _find(scopes, name)
            if a is None:
                return None
            text_a = sign + name
        x = -float(a) if sign == "-" else float(a)
        if op is None:
            used += 2 if sign else 1
            items.append(Value(FLOAT, x, at, text_a))
            continue
        if num2 is not None:
            b = int(num2) if len(num2) < 16 and num2.isdigit() else ex.number_value(num2)
            if b is None:
                return None
            text_b = ex.number_text(b)
        else:
            b = _find(scopes, name2)
            if b is None:
                return None
            text_b = name2
        y = float(b)
        if op == "*":
            x *= y
        elif op == "/":
            if y == 0:
                return None
            x /= y
        elif op == "+":
            x += y
        else:
            x -= y
        if not isfinite(x):
            return None
        used += 4 if sign else 3
        sep = f" {op} " if op in "+-" else op
        items.append(Value(FLOAT, x, at, f"{text_a}{sep}{text_b}"))
    return Value(VECTOR, items, loc), pos, used


def _find(scopes: list[dict[str, float]], name: str) -> float | None:
    """A variable from ``scopes`` (innermost first), else a constant; None if unknown."""
    for scope in scopes:
        if name in scope:
            return scope[name]
    return ex.CONSTANTS.get(name)


@contextmanager
def paused_gc() -> Iterator[None]:
    """Pause the cyclic GC while building many small objects that all stay alive.

    Without this, collections re-scan the growing tree again and again. A big
    load (a scene file, its specs, its entities) is then frozen (``gc.freeze``):
    it lives as long as the scene, so scanning it in later collections would only
    cost time (about a third of a second per collection for 10,000 objects).
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if gc.get_count()[0] > _FREEZE_AFTER:
            gc.freeze()
        if was_enabled:
            gc.enable()


#: New GC-tracked objects above which a load is frozen instead of scanned later.
_FREEZE_AFTER = 100_000


def parse_text(text: str, path: str = "<string>", rng: np.random.Generator | None = None,
               limits: Limits | None = None, base_dir: str | os.PathLike | None = None
               ) -> SceneDB:
    """Parse scene text. Raises :class:`SceneError` listing every error found.

    ``Include`` paths are relative to ``path``'s folder when it is a file, else to
    ``base_dir`` (default: the working directory).
    """
    p = Parser(rng, limits or Limits(), Path(base_dir) if base_dir is not None else None)
    with paused_gc():
        root = p.parse_source(text, path)
    return _finish(p, root, path)


def parse_file(path: str | os.PathLike, rng: np.random.Generator | None = None,
               limits: Limits | None = None) -> SceneDB:
    """Parse a scene file and what it includes. Raises :class:`SceneError`."""
    p = Parser(rng, limits or Limits())
    target = Path(path).resolve()
    with paused_gc():
        root = p.parse_file(target)
    return _finish(p, root, str(target))


def _finish(p: Parser, root: Block, path: str) -> SceneDB:
    p.report.raise_if_errors()
    return SceneDB(root, path, p.report.sources, sorted_diagnostics(p.report.diagnostics))


try:  # the compiled scanner (engine/scene/_scan.pyx), when built
    from engine.scene._scan import scan_plain
except ImportError:  # not built: the regex scanner above reads the same
    scan_plain = _scan_plain
