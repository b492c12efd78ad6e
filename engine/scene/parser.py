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
"""

from __future__ import annotations

import gc
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
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
from engine.scene.lexer import EOF, IDENT, NUMBER, PUNCT, Comment, Token, lex
from engine.scene.lexer import STRING as T_STRING

_OPERATORS = frozenset("+-*/^")


@dataclass(frozen=True, slots=True)
class Limits:
    """What a scene file may not exceed; past these the file is refused, not half-read."""

    max_bytes: int = 64 * 1024 * 1024
    max_tokens: int = 8_000_000
    max_nesting: int = 64
    max_files: int = 256


class _FileCursor(ex.Cursor):
    def __init__(self, tokens: list[Token], comments: list[Comment], path: str, limits: Limits):
        super().__init__(tokens, path, limits.max_nesting)
        self.comments = comments
        self.ci = 0

    def take_comments(self, before: int) -> list[Comment]:
        start = self.ci
        while self.ci < len(self.comments) and self.comments[self.ci].pos < before:
            self.ci += 1
        return self.comments[start:self.ci]


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
        lexed = lex(text, path, self.report, self.limits.max_tokens)
        cur = _FileCursor(lexed.tokens, lexed.comments, path, self.limits)
        self.stack.append(os.path.abspath(path))
        try:
            self._block(cur, root, None)
        except ex.NestingError as exc:
            self.report.error(exc.loc, exc.message)
        finally:
            self.stack.pop()
        return root

    # -- blocks ------------------------------------------------------------
    def _block(self, cur: _FileCursor, block: Block, opener: Token | None) -> None:
        pending: list[str] = []
        prev: Entry | None = None
        prev_line = opener.line if opener else -1
        tokens, comments, path = cur.tokens, cur.comments, cur.path
        entries = block.entries
        scope = self.scopes[-1]
        while True:
            t = tokens[cur.i]
            if cur.ci < len(comments) and comments[cur.ci].pos < t.pos:
                for c in cur.take_comments(t.pos):
                    if c.trailing and c.line == prev_line:
                        (prev.trailing if prev else block.open_comment).append(c.text)
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
            entry = Entry(key, value, Loc(path, t.line, t.col), pending)
            if pending:
                pending = []
            if value.kind is INT or value.kind is FLOAT:
                scope[key] = value.data
            if key == INCLUDE:
                entry.included = self._include(value, cur)
            entries.append(entry)
            prev = entry
            prev_line = last.line
        block.tail_comments = pending

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
        t = cur.tokens[cur.i]
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
        t = cur.tokens[cur.i]
        if t.kind == NUMBER:  # fast path: a plain number not followed by an operator
            nxt = cur.tokens[cur.i + 1]
            if nxt.kind != PUNCT or nxt.text not in _OPERATORS or (
                    in_vector and nxt.text in "+-" and nxt.space_before
                    and not cur.tokens[cur.i + 2].space_before):
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
            t = tokens[cur.i]
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


@contextmanager
def paused_gc() -> Iterator[None]:
    """Pause the cyclic GC while building many small objects that all stay alive.

    Without this, collections re-scan the growing tree again and again and a
    10,000-object file takes about twice as long to read.
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


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
