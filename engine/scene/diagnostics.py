"""Diagnostics: every problem in a scene file, reported at once with its place.

A parse or check collects :class:`Diagnostic` records instead of stopping at the
first mistake; :class:`SceneError` carries all of them so an author fixes a file
in one round trip. Rendering follows the compiler convention
``path:line:col: error: message`` plus the source line and a caret.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

ERROR = "error"
WARNING = "warning"


class Loc(NamedTuple):
    """A place in a scene file: 1-based line and column (a tuple: cheap to make)."""

    path: str
    line: int
    col: int


@dataclass(frozen=True, slots=True)
class Diagnostic:
    path: str
    line: int
    col: int
    severity: str
    message: str

    @property
    def is_error(self) -> bool:
        return self.severity == ERROR

    def render(self, source: str | None = None) -> str:
        """``path:line:col: severity: message`` then the line and a caret under ``col``."""
        head = f"{self.path}:{self.line}:{self.col}: {self.severity}: {self.message}"
        if source is None:
            source = _read_source(self.path)
        lines = source.split("\n") if source else []  # the lexer counts "\n" only
        if not 1 <= self.line <= len(lines):
            return head
        text = lines[self.line - 1].rstrip("\r").replace("\t", " ")
        caret = " " * max(self.col - 1, 0) + "^"
        return f"{head}\n    {text}\n    {caret}"


def _read_source(path: str) -> str | None:
    try:
        return Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None


class SceneError(Exception):
    """The scene format's only error type: a list of diagnostics, at least one an error."""

    def __init__(self, diagnostics: Iterable[Diagnostic], sources: dict[str, str] | None = None):
        self.diagnostics: list[Diagnostic] = list(diagnostics)
        self.sources = sources or {}
        super().__init__(self.render())

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.is_error]

    def render(self) -> str:
        return render_all(self.diagnostics, self.sources)


def render_all(diagnostics: Iterable[Diagnostic], sources: dict[str, str] | None = None) -> str:
    sources = sources or {}
    return "\n".join(d.render(sources.get(d.path)) for d in diagnostics)


@dataclass
class Reporter:
    """Collects diagnostics during one pass; ``raise_if_errors`` ends the pass."""

    diagnostics: list[Diagnostic] = field(default_factory=list)
    sources: dict[str, str] = field(default_factory=dict)

    def error(self, loc: Loc, message: str) -> None:
        self.diagnostics.append(Diagnostic(loc.path, loc.line, loc.col, ERROR, message))

    def warning(self, loc: Loc, message: str) -> None:
        self.diagnostics.append(Diagnostic(loc.path, loc.line, loc.col, WARNING, message))

    @property
    def has_errors(self) -> bool:
        return any(d.is_error for d in self.diagnostics)

    def raise_if_errors(self) -> None:
        if self.has_errors:
            raise SceneError(sorted_diagnostics(self.diagnostics), self.sources)


def sorted_diagnostics(diagnostics: Iterable[Diagnostic]) -> list[Diagnostic]:
    """Stable order by file then position, so reports read top to bottom."""
    return sorted(diagnostics, key=lambda d: (d.path, d.line, d.col))


def suggest(name: str, candidates: Iterable[str]) -> str:
    """`` (did you mean 'X'?)`` for the closest candidate, case first; empty if none is close."""
    pool = sorted(set(candidates))
    for c in pool:
        if c.lower() == name.lower() and c != name:
            return f" (did you mean '{c}'?)"
    lowered = {c.lower(): c for c in pool}
    close = difflib.get_close_matches(name.lower(), list(lowered), n=1, cutoff=0.6)
    return f" (did you mean '{lowered[close[0]]}'?)" if close else ""
