"""Parser: tokens -> SceneDB, evaluating expressions as it goes.

Grammar (the lexical classes are defined once, in :mod:`engine.scene.lexer`)::

    file   := entry*
    entry  := KEY value
    value  := STRING | '{' entry* '}' | '[' item* ']' | expression
    item   := STRING | expression

This recursive-descent parser over the lexer's tokens is the reference: it reads
every file. Errors do not stop the pass: the parser reports, skips to the next line
that starts with a key, and carries on, so one run lists every mistake. Limits on
file size, token count and nesting depth turn hostile or broken input into a clear
message instead of a crash. ``Include "file"`` splices another file in place
(relative to the including file; cycles are errors).

Speed: most entries of a real file are plain (``KEY "text"``, ``KEY 1.5``,
``KEY [1 2 3]``, ``KEY {`` ... ``}`` on tidy lines). The one fast path, the compiled
scanner ``engine/scene/_scan.pyx`` (built by ``tools/dev setup``), reads those
straight from the text, a character at a time and without tokens, and hands back
to the token path wherever the text is not plain; it makes exactly the SceneDB,
places, diagnostics and token count the token path would (a property test over
generated and mutated scenes checks it), and reads a 10,000-object file about
seven times faster. Without the extension every entry takes the token path.

Layout the writer keeps (``colosseum fmt``): a blank line between two entries or
comments is an empty string among the next one's ``comments`` (a run of blank lines
counts once; blank lines first or last in a block are dropped), and a block whose
``{`` and ``}`` are on one line is marked :attr:`~engine.scene.db.Block.inline`.
"""

from __future__ import annotations

import os
from bisect import bisect_right
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import engine.scene.expr as ex
from engine.confine import Confinement, resolved
from engine.memory import paused_gc
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
from engine.scene.diagnostics import Loc, Reporter, quoted
from engine.scene.lexer import EOF, IDENT, NUMBER, OPERATORS, PUNCT, Comment, Lexer, Token
from engine.scene.lexer import STRING as T_STRING
from engine.scene.paths import NOT_FOUND, file_problem, shown

#: A block opened by the scanner and not closed yet: (its entry, the parent's entries, the
#: parent's scope, the block, the line of its '{').
Open = tuple[Entry, list[Entry], dict[str, float], Block, int]
#: The fast path's signature: (parser, cursor, pos, token count, entries, scope, open blocks,
#: line the last item ended on or 0) -> (pos, token count, closing '}' or -1, last line).
ScanPlain = Callable[["Parser", "_FileCursor", int, int, list[Entry], dict[str, float],
                      list[Open], int], tuple[int, int, int, int]]
#: The plain-entry scanner in use; None reads everything with the token path (the reference).
scan_plain: ScanPlain | None
try:  # the compiled scanner, when built (tools/dev setup)
    from engine.scene._scan import scan_plain
except ImportError:  # not built: the token path reads every entry
    scan_plain = None
_BLANK = ""  # a blank line, among an entry's comments


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

    def forget(self) -> None:
        """Drop the tokens and comments read (all but the last token): between entries
        nothing looks further back, and a long file must not keep millions of them."""
        if self.i > 1:
            del self.tokens[:self.i - 1]
            self.i = 1
        del self.comments[:self.ci]
        self.ci = 0


_CLOSED = -1  # what Parser._plain returns after the block's closing '}'
_FORGET_AFTER = 4096  # tokens read before the cursor drops them (see _FileCursor.forget)


class Parser:
    """One parse of a file and what it includes, sharing a reporter, an rng and scopes."""

    def __init__(self, rng: np.random.Generator | None, limits: Limits,
                 base_dir: Path | None = None, confine: Confinement | None = None):
        self._rng = rng
        self.base_dir = base_dir
        #: Where included files may be (the content folder and the folders allowed).
        self.confine = confine or Confinement.of(base_dir or Path.cwd())
        self.limits = limits
        self.report = Reporter()
        self.scopes: list[dict[str, float]] = [{}]
        self.stack: list[str] = []
        self.files = 0

    @property
    def rng(self) -> np.random.Generator:
        """The caller's generator, else one seeded 0, made at the first draw: a scene that
        draws no random number loads no ``numpy.random``."""
        if self._rng is None:
            self._rng = np.random.default_rng(0)
        return self._rng

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
                self.report.error(where, f"file {shown(path)} is {size} bytes, larger than the "
                                         f"{self.limits.max_bytes}-byte limit")
                return None
            data = path.read_bytes()
        except OSError as exc:
            self.report.error(where, f"cannot read {shown(path)}: {exc.strerror or exc}")
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
    # Long: the token loop of a block: comments, blank lines, last entry shared
    def _block(self, cur: _FileCursor, block: Block, opener: Token | None,
               prev: Entry | None = None, prev_line: int | None = None) -> None:
        """Entries up to the block's ``}`` (or the file's end); ``prev`` and ``prev_line``
        carry on from entries the fast path already read into ``block``."""
        pending: list[str] = []
        if prev_line is None:
            prev_line = opener.line if opener else -1
        # The line the last entry or comment of this block ended on (0: none yet), for
        # blank lines between them.
        ended = prev_line if prev is not None else 0
        tokens, comments, path = cur.tokens, cur.comments, cur.path
        entries = block.entries
        scope = self.scopes[-1]
        while True:
            if scan_plain is not None and cur.ci == len(comments) and (
                    cur.i == len(tokens) or (cur.i == len(tokens) - 1
                                             and tokens[-1].kind is IDENT)):
                n = len(entries)
                last_line = self._plain(cur, block, opener is not None, scope, ended)
                if len(entries) > n:
                    if pending:
                        entries[n].comments = [*pending, *entries[n].comments]
                        pending = []
                    prev = entries[-1]
                if last_line == _CLOSED:
                    break
                if last_line is not None:
                    prev_line = ended = last_line
                    continue
            if cur.i > _FORGET_AFTER or cur.ci > _FORGET_AFTER:
                cur.forget()
            t = cur.at(cur.i)
            if cur.ci < len(comments) and comments[cur.ci].pos < t.pos:
                for c in cur.take_comments(t.pos):
                    if c.trailing and c.line == prev_line:
                        if prev:
                            prev.trailing = [*prev.trailing, c.text]
                            ended = c.end_line
                        else:
                            block.open_comment = [*block.open_comment, c.text]
                        continue
                    if ended and c.line > ended + 1:
                        pending.append(_BLANK)
                    pending.append(c.text)
                    ended = c.end_line
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
                        block.inline = t.line == opener.line
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
            if ended and t.line > ended + 1:
                pending.append(_BLANK)
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
            prev_line = ended = last.line
        block.tail_comments = pending or ()

    def _plain(self, cur: _FileCursor, block: Block, nested: bool,
               scope: dict[str, float], ended: int) -> int | None:
        """Read plain entries straight from the text with the compiled scanner.

        Returns None if there was none (nothing consumed), ``_CLOSED`` after the
        block's ``}`` (only if ``nested``), else the line of the last token read.
        Reads exactly what the token path would, with the same places and token
        count. Plain ``KEY {`` blocks are read here too, without recursion; where
        one stops being plain, :meth:`_block` reads the rest of it. ``ended``: the
        line the block's last entry or comment ended on (0: none yet).
        """
        assert scan_plain is not None
        lexer, tokens = cur.lexer, cur.tokens
        lookahead = cur.i < len(tokens)  # a key already scanned: read it again from the text
        pos = tokens[-1].pos if lookahead else lexer.pos
        count = start = lexer.count - lookahead
        entries = block.entries
        stack: list[Open] = []  # blocks opened here and not closed yet
        while True:
            pos, count, close, ended = scan_plain(self, cur, pos, count, entries, scope,
                                                  stack, ended)
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
                block.inline = line == block.loc.line
                return _CLOSED
            if count == start:
                return None
            lexer.skip(pos, count)
            starts = lexer.line_starts
            last_line = bisect_right(starts, pos - 1)  # of the last token read
            while stack:  # the token path reads the rest of each open block
                entry, entries, scope, inner, _ = stack.pop()
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
            pos, count, ended = lexer.pos, lexer.count, last_line

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
            if cur.i > _FORGET_AFTER:
                cur.forget()

    def _lookup(self, name: str) -> float | None:
        for scope in reversed(self.scopes):
            if name in scope:
                return scope[name]
        return None

    def _unknown(self, name: str) -> bool:
        """Not a variable, constant or function: most likely the next key."""
        return (self._lookup(name) is None and name not in ex.CONSTANTS
                and name not in ex.FUNCTIONS)

    def _names(self, at: Loc) -> list[str]:
        """Variables in scope, for a "did you mean" at ``at`` (none if it would not show)."""
        if not self.report.accepts(at):
            return []
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
            raise ex.ExprError(cur.loc(key), f"key '{quoted(key.text)}' has no value")
        if kind in (NUMBER, IDENT) or (kind == PUNCT and t.text in "(+-"):
            return self._scalar(cur, in_vector=False)
        raise ex.ExprError(cur.loc(t), f"expected a value after '{quoted(key.text)}' but found "
                                       f"{ex.describe(t)}")

    def _scalar(self, cur: _FileCursor, in_vector: bool) -> Value:
        t = cur.at(cur.i)
        if t.kind == NUMBER:  # a plain number not followed by an operator
            nxt = cur.at(cur.i + 1)
            if nxt.kind != PUNCT or nxt.text not in OPERATORS or (
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
        outside = self.confine.problem(base / value.data)
        if outside is not None:  # refused before it is looked at: nothing of it is told
            self.report.error(value.loc, f'cannot include "{quoted(value.data)}": {outside}')
            return None
        target = resolved(base / value.data)
        if str(target) in self.stack:
            chain = " -> ".join(Path(p).name for p in [*self.stack, str(target)])
            self.report.error(value.loc, f"Include cycle: {quoted(chain, 200)}")
            return None
        if len(self.stack) >= self.limits.max_nesting:
            self.report.error(value.loc, f"Includes nested deeper than "
                                         f"{self.limits.max_nesting} files (limit)")
            return None
        if self.files >= self.limits.max_files:
            self.report.error(value.loc, f"more than {self.limits.max_files} included files "
                                         "(limit)")
            return None
        problem = file_problem(target)
        if problem == NOT_FOUND:
            self.report.error(value.loc, f"included file not found: {shown(target)}")
            return None
        if problem is not None:
            self.report.error(value.loc, f'cannot include "{quoted(value.data)}": {problem}')
            return None
        return self.parse_file(target, value.loc)


@contextmanager
def token_path_only() -> Iterator[None]:
    """Read with the reference parser alone, as if the scanner were not built (the fast
    path's property test and ``colosseum bench scene`` compare the two). Not for use
    while another thread parses."""
    global scan_plain
    fast, scan_plain = scan_plain, None
    try:
        yield
    finally:
        scan_plain = fast


def parse_text(text: str, path: str = "<string>", rng: np.random.Generator | None = None,
               limits: Limits | None = None, base_dir: str | os.PathLike | None = None,
               allow: Iterable[str | os.PathLike] = ()) -> SceneDB:
    """Parse scene text. Raises :class:`SceneError` listing every error found.

    ``Include`` paths are relative to ``path``'s folder when it is a file, else to
    ``base_dir`` (default: the working directory), and must lie inside that folder or
    one of ``allow`` (:mod:`engine.confine`).
    """
    base = Path(base_dir) if base_dir is not None else None
    home = Path(path).parent if os.path.isfile(path) else base or Path.cwd()
    p = Parser(rng, limits or Limits(), base, Confinement.of(home, allow))
    with paused_gc():
        root = p.parse_source(text, path)
    return _finish(p, root, path)


def parse_file(path: str | os.PathLike, rng: np.random.Generator | None = None,
               limits: Limits | None = None, allow: Iterable[str | os.PathLike] = ()
               ) -> SceneDB:
    """Parse a scene file and what it includes (inside its folder or one of ``allow``).
    Raises :class:`SceneError`."""
    target = resolved(Path(path))
    p = Parser(rng, limits or Limits(), confine=Confinement.of(target.parent, allow))
    with paused_gc():
        root = p.parse_file(target)
    return _finish(p, root, str(target))


def _finish(p: Parser, root: Block, path: str) -> SceneDB:
    p.report.raise_if_errors()
    return SceneDB(root, path, p.report.sources, p.report.diagnostics)

