"""Lexer: scene text -> tokens and comments, each with line and column.

One compiled regular expression does the scanning, so a 10,000-object file
lexes in a fraction of a second. Bad characters and unterminated strings or
comments are reported and skipped, so one pass finds every lexical mistake.
Typographic quotes (as printed in the paper's listings) are accepted as string
delimiters with a warning.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from engine.scene.diagnostics import Loc, Reporter

# Token kinds.
NUMBER = "NUMBER"
STRING = "STRING"
IDENT = "IDENT"
PUNCT = "PUNCT"
EOF = "EOF"

QUOTES = "\"\u201c\u201d"
_ESCAPES = {"n": "\n", "t": "\t", "r": "\r"}

#: Whitespace, then one lexeme. ``findall`` gives (whitespace, lexeme) pairs in one C call;
#: the kind of a lexeme follows from its first characters.
_TOKEN_RE = re.compile(
    r"""
    ([ \t\r\f\v\ufeff\n]*)
    (
      (?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?
    | [A-Za-z_][A-Za-z0-9_]*
    | [\[\]{}(),+\-*^]
    | ["\u201c\u201d](?:[^"\u201c\u201d\\\n]|\\.)*["\u201c\u201d]
    | //[^\n]*
    | /\*.*?\*/
    | /\*.*
    | /
    | ["\u201c\u201d][^\n]*
    | .
    | \Z
    )
    """,
    re.VERBOSE | re.DOTALL,
)
_PUNCT_CHARS = frozenset("[]{}(),+-*^/")
_DIGITS = frozenset("0123456789")
_IDENT_START = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_")
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


@dataclass(slots=True)
class Lexed:
    tokens: list[Token]
    comments: list[Comment]


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


def lex(text: str, path: str, report: Reporter, max_tokens: int) -> Lexed:
    """Scan ``text``; problems go to ``report``. Stops with an error past ``max_tokens``."""
    tokens: list[Token] = []
    comments: list[Comment] = []
    line, line_start = 1, 0
    warned_quotes = False
    last_token_line = 0
    space = True
    append = tokens.append
    pos = 0
    for ws, lexeme in _TOKEN_RE.findall(text):
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
            append(Token(IDENT, lexeme, None, line, col, start, space))
        elif first in _DIGITS or (first == "." and len(lexeme) > 1):
            append(Token(NUMBER, lexeme, None, line, col, start, space))
        elif first in _PUNCT_CHARS and (first != "/" or lexeme == "/"):
            append(Token(PUNCT, lexeme, None, line, col, start, space))
        elif first in _QUOTE_CHARS:
            if len(lexeme) > 1 and lexeme[-1] in _QUOTE_CHARS and _closed(lexeme):
                if not warned_quotes and (first != '"' or lexeme[-1] != '"'):
                    warned_quotes = True
                    report.warning(Loc(path, line, col),
                                   "typographic quotes (\u201c \u201d) used as string "
                                   'delimiters; write plain " instead')
                append(Token(STRING, lexeme, decode_string(lexeme[1:-1]), line, col, start,
                             space))
            else:
                report.error(Loc(path, line, col),
                             "string is not closed before the end of the line")
                append(Token(STRING, lexeme, decode_string(lexeme[1:]), line, col, start,
                             space))
        elif first == "/":
            if lexeme.startswith("/*") and not (len(lexeme) >= 4 and lexeme.endswith("*/")):
                report.error(Loc(path, line, col), "comment '/*' is never closed with '*/'")
            nl = lexeme.count("\n")
            comments.append(Comment(lexeme, line, line + nl, start, last_token_line == line))
            if nl:
                line += nl
                line_start = start + lexeme.rindex("\n") + 1
            space = True
            continue
        elif not lexeme:
            break
        else:
            report.error(Loc(path, line, col), f"unexpected character {lexeme!r}")
            space = True
            continue
        space = False
        last_token_line = line
        if len(tokens) > max_tokens:
            report.error(Loc(path, line, col),
                         f"file has more than {max_tokens} tokens (limit); split it with Include")
            break
    tokens.append(Token(EOF, "", None, line, len(text) - line_start + 1, len(text), True))
    return Lexed(tokens, comments)


def _closed(lexeme: str) -> bool:
    """Whether a quoted lexeme ends with a quote that is not escaped."""
    backslashes = len(lexeme) - 1 - len(lexeme[:-1].rstrip("\\"))
    return backslashes % 2 == 0
