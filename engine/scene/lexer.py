"""Lexer: scene text -> tokens and comments, each with line and column.

The grammar's lexical classes are defined here once (``SPACE_CHARS`` ...
``NUMBER_RE``); one regular expression built from them scans a lexeme at a time, on
demand: the parser reads plain entries straight from the text with the compiled
scanner (``engine/scene/_scan.pyx``, whose character table comes from the same
definitions) and asks for tokens only where the text needs the general grammar.
Bad characters and unterminated strings or comments are reported and skipped, so
one pass finds every lexical mistake; a run of bad characters is one error.
Typographic quotes (as printed in the paper's listings) are accepted as string
delimiters with a warning.
"""

from __future__ import annotations

import re
import string
from bisect import bisect_right
from dataclasses import dataclass

from engine.scene.diagnostics import Loc, Reporter

# Token kinds.
NUMBER = "NUMBER"
STRING = "STRING"
IDENT = "IDENT"
PUNCT = "PUNCT"
EOF = "EOF"

# -- the grammar's lexical definitions, written once -------------------------------
# The lexer's regular expression below is built from these, and the compiled scanner
# (engine/scene/_scan.pyx) builds its character table from them at import.

#: Whitespace other than the newline (which also ends a line comment and a string).
SPACE_CHARS = " \t\r\f\v\ufeff"
NEWLINE = "\n"
DIGITS = "0123456789"
NAME_START = string.ascii_letters + "_"
NAME_CHARS = NAME_START + DIGITS
#: String delimiters: the plain quote and the typographic ones of the paper's listings
#: (accepted with a warning).
PLAIN_QUOTE = '"'
QUOTES = PLAIN_QUOTE + "\u201c\u201d"
#: Inside a string, a backslash makes the next character literal (see :func:`decode_string`).
ESCAPE = "\\"
OPERATORS = "+-*/^"
#: Punctuation that is neither an operator nor the start of a comment.
BRACKETS = "[]{}(),"


def char_class(chars: str) -> str:
    """``chars`` as the body of a regular-expression character class."""
    return "".join(re.escape(c) for c in chars)


_D = f"[{char_class(DIGITS)}]"
#: A NUMBER lexeme as an atomic regular expression (never shortened to let a longer pattern
#: match): digits with an optional fraction, or a fraction alone, then an optional exponent.
#: It is an INT without '.' or exponent (see ``expr.number_value``).
NUMBER_RE = rf"(?>(?:{_D}+\.?{_D}*|\.{_D}+)(?:[eE][+-]?{_D}+)?)"
SPACE = char_class(SPACE_CHARS)
NAME_RE = f"[{char_class(NAME_START)}][{char_class(NAME_CHARS)}]*+"
_Q = char_class(QUOTES)
#: Characters a lexeme may start with ('.' only before a digit); any other run of
#: characters is one "unexpected characters" error, however long.
_STARTS = char_class(SPACE_CHARS + NEWLINE + NAME_CHARS + QUOTES + OPERATORS + BRACKETS)

#: Whitespace, then one lexeme; the kind of a lexeme follows from its first characters.
#: Repeats of alternatives are possessive: nothing after them can need a shorter match,
#: and a backtracking repeat keeps a frame per character (190 MB for a 1 MB line).
_TOKEN_RE = re.compile(
    rf"""
    ([{SPACE}\n]*)
    (
      {NUMBER_RE}
    | {NAME_RE}
    | [{char_class(BRACKETS + OPERATORS.replace("/", ""))}]
    | [{_Q}](?:[^{_Q}\\\n]|\\[^\n])*+[{_Q}]
    | //[^\n]*
    | /\*.*?\*/
    | /\*.*
    | /
    | [{_Q}][^\n]*
    | (?:[^{_STARTS}.]|\.(?!{_D}))++
    | \Z
    )
    """,
    re.VERBOSE | re.DOTALL,
)
_ESCAPES = {"n": "\n", "t": "\t", "r": "\r"}
_NEWLINE = re.compile(NEWLINE)
_PUNCT_CHARS = frozenset(BRACKETS + OPERATORS)
_DIGITS = frozenset(DIGITS)
_IDENT_START = frozenset(NAME_START)
_QUOTE_CHARS = frozenset(QUOTES)


@dataclass(slots=True)
class Token:
    kind: str
    text: str
    value: object
    line: int
    col: int
    pos: int
    space_before: bool


@dataclass(slots=True)
class Comment:
    """A comment as written (``// ...`` or ``/* ... */``); ``trailing`` when code precedes it."""

    text: str
    line: int
    end_line: int
    pos: int
    trailing: bool


def decode_string(body: str) -> str:
    """Undo the writer's escapes: ``\\n \\t \\r`` and a backslash before any other char."""
    if "\\" not in body:
        return body
    out: list[str] = []
    i = 0
    while i < len(body):
        ch = body[i]
        if ch == "\\" and i + 1 < len(body):
            nxt = body[i + 1]
            out.append(_ESCAPES.get(nxt, nxt))
            i += 2
        else:
            out.append(ch)
            i += 1
    return "".join(out)


class Lexer:
    """Scans ``text`` one token at a time into ``tokens`` and ``comments``.

    Problems go to ``report``. Past ``max_tokens`` tokens (counting those the
    parser read without asking, see :meth:`skip`) it reports a limit error and
    ends with EOF.
    """

    def __init__(self, text: str, path: str, report: Reporter, max_tokens: int):
        self.text = text
        self.path = path
        self.report = report
        self.max_tokens = max_tokens
        self.tokens: list[Token] = []
        self.comments: list[Comment] = []
        self.pos = 0
        self.line = 1
        self.line_start = 0
        self.count = 0  # tokens scanned so far, not counting EOF
        self.done = False  # EOF is the last token
        self._space = True
        self._last_token_line = 0
        self._warned_quotes = False
        self._line_starts: list[int] | None = None
        self._skipped = False  # text was read by the parser since the last token

    @property
    def line_starts(self) -> list[int]:
        """Offset of each line's first character (made on first use)."""
        if self._line_starts is None:
            self._line_starts = [0, *(m.end() for m in _NEWLINE.finditer(self.text))]
        return self._line_starts

    def skip(self, pos: int, count: int) -> None:
        """The parser read plain text up to ``pos`` itself; ``count`` tokens so far.

        The line there is worked out when the next token is scanned, if one is.
        """
        self.pos = pos
        self.count = count
        self._skipped = True

    def _resume(self) -> None:
        line = bisect_right(self.line_starts, self.pos)
        self.line = self._last_token_line = line
        self.line_start = self.line_starts[line - 1]
        self._space = False
        self._skipped = False

    def finish(self) -> None:
        """Scan to the end, reporting every remaining lexical problem (the parse is over:
        the tokens and comments are not kept)."""
        tokens, comments = self.tokens, self.comments
        while not self.done:
            self.next_token()
            del tokens[:-1]
            comments.clear()

    # Long: dispatch on the next character, once a token: no call per branch
    def next_token(self) -> Token:
        """Scan the next token (EOF at the end or past the limit) and append it."""
        tokens = self.tokens
        if self.done:
            return tokens[-1]
        if self._skipped:
            self._resume()
        text, path, report = self.text, self.path, self.report
        pos, line, line_start = self.pos, self.line, self.line_start
        space = self._space
        match = _TOKEN_RE.match
        token: Token | None = None
        while token is None:
            ws, lexeme = match(text, pos).group(1, 2)  # type: ignore[union-attr]
            if ws:
                nl = ws.count("\n")
                if nl:
                    line += nl
                    line_start = pos + ws.rindex("\n") + 1
                pos += len(ws)
                space = True
            start = pos
            pos += len(lexeme)
            col = start - line_start + 1
            first = lexeme[:1]
            if first in _IDENT_START:
                token = Token(IDENT, lexeme, None, line, col, start, space)
            elif first in _DIGITS or (first == "." and lexeme[1:2] in _DIGITS):
                token = Token(NUMBER, lexeme, None, line, col, start, space)
            elif first in _PUNCT_CHARS and (first != "/" or lexeme == "/"):
                token = Token(PUNCT, lexeme, None, line, col, start, space)
            elif first in _QUOTE_CHARS:
                if len(lexeme) > 1 and lexeme[-1] in _QUOTE_CHARS and _closed(lexeme):
                    if not self._warned_quotes and first + lexeme[-1] != PLAIN_QUOTE * 2:
                        self._warned_quotes = True
                        report.warning(Loc(path, line, col),
                                       "typographic quotes (\u201c \u201d) used as string "
                                       'delimiters; write plain " instead')
                    token = Token(STRING, lexeme, decode_string(lexeme[1:-1]), line, col,
                                  start, space)
                else:
                    report.error(Loc(path, line, col),
                                 "string is not closed before the end of the line")
                    token = Token(STRING, lexeme, decode_string(lexeme[1:]), line, col, start,
                                  space)
            elif first == "/":
                if lexeme.startswith("/*") and not (len(lexeme) >= 4 and lexeme.endswith("*/")):
                    report.error(Loc(path, line, col), "comment '/*' is never closed with '*/'")
                nl = lexeme.count("\n")
                self.comments.append(Comment(lexeme, line, line + nl, start,
                                             self._last_token_line == line))
                if nl:
                    line += nl
                    line_start = start + lexeme.rindex("\n") + 1
                space = True
            elif not lexeme:
                token = Token(EOF, "", None, line, len(text) - line_start + 1, len(text), True)
            else:
                report.error(Loc(path, line, col), _unexpected(lexeme))
                space = True
        self.pos, self.line, self.line_start = pos, line, line_start
        self._space = False
        self._last_token_line = line
        if token.kind is EOF:
            self.done = True
        else:
            self.count += 1
            if self.count > self.max_tokens:
                report.error(Loc(path, line, token.col), f"file has more than "
                             f"{self.max_tokens} tokens (limit); split it with Include")
                tokens.append(token)
                token = Token(EOF, "", None, line, len(text) - line_start + 1, len(text), True)
                self.done = True
        tokens.append(token)
        return token


def _unexpected(run: str) -> str:
    """One message for a run of characters no lexeme starts with (one error, not one each)."""
    if len(run) == 1:
        return f"unexpected character {run!r}"
    shown = repr(run) if len(run) <= 20 else repr(run[:20] + "...")
    return f"unexpected characters {shown} ({len(run)} in a row)"


def _closed(lexeme: str) -> bool:
    """Whether a quoted lexeme ends with a quote that is not escaped."""
    backslashes = len(lexeme) - 1 - len(lexeme[:-1].rstrip("\\"))
    return backslashes % 2 == 0
