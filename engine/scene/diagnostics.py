"""Diagnostics: every problem in a scene file, reported at once with its place.

A parse or check collects :class:`Diagnostic` records instead of stopping at the
first mistake; :class:`SceneError` carries all of them so an author fixes a file
in one round trip. Rendering follows the compiler convention
``path:line:col: error: message`` plus the source line and a caret.

Hostile input stays cheap: a :class:`Reporter` keeps the first ``MAX_PER_FILE``
diagnostics of each file (by place) and counts the rest into one :class:`Omitted`
line; rendering indexes each source once (linear in the report), shows at most
``LINE_WIDTH`` characters of a line around the column, and never reads a file:
a line is shown only from the text the parser kept.
"""

from __future__ import annotations

import difflib
import heapq
import json
import re
from collections.abc import Iterable, Iterator
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from engine.scene.db import SceneDB

ERROR = "error"
WARNING = "warning"
#: Diagnostics kept per file; past this many the rest are only counted.
MAX_PER_FILE = 100
#: Characters of a source line shown under a diagnostic (clipped around the column).
LINE_WIDTH = 100
#: Author text quoted in a message is clipped to this many characters.
QUOTE_WIDTH = 40
#: Names longer than this get no "did you mean" (no key or ID is a typo of one).
_SUGGEST_MAX_LEN = 64


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

    def head(self) -> str:
        """``path:line:col: severity: message`` on one line, whatever the message holds."""
        return f"{self.path}:{self.line}:{self.col}: {self.severity}: {printable(self.message)}"

    def render(self, source: str | None = None) -> str:
        """The head, then (given the file's text) the line and a caret under ``col``."""
        return render_all([self], {self.path: source} if source is not None else None)

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


@dataclass(frozen=True, slots=True)
class Omitted(Diagnostic):
    """Stands for the diagnostics of one file past :data:`MAX_PER_FILE`, at the first one's
    place; an error when any of them is."""

    errors: int = 0
    warnings: int = 0

    @staticmethod
    def of(path: str, line: int, col: int, errors: int, warnings: int) -> Omitted:
        parts = [f"{n} more {what}{'s' if n != 1 else ''}"
                 for n, what in ((errors, "error"), (warnings, "warning")) if n]
        message = (f"{' and '.join(parts)} in this file not shown (the first "
                   f"{MAX_PER_FILE} are)")
        return Omitted(path, line, col, ERROR if errors else WARNING, message, errors, warnings)


class SceneError(Exception):
    """The scene format's only error type: a list of diagnostics, at least one an error."""

    def __init__(self, diagnostics: Iterable[Diagnostic], sources: dict[str, str] | None = None):
        self.diagnostics: list[Diagnostic] = list(diagnostics)
        self.sources = sources or {}
        #: The scene as parsed, when the errors came after parsing (a run skips the
        #: parts they lie in: engine.scene.skipping).
        self.db: SceneDB | None = None
        #: Where every error lies, those past MAX_PER_FILE (not shown, only counted) too:
        #: a run leaves out the parts they lie in all at once.
        self.places: list[Loc] = [Loc(d.path, d.line, d.col) for d in self.diagnostics
                                  if d.is_error and not isinstance(d, Omitted)]
        super().__init__(self.diagnostics)

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.is_error]

    def render(self) -> str:
        return render_all(self.diagnostics, self.sources)

    def __str__(self) -> str:  # rendered when asked, not when raised
        return self.render()


@dataclass(slots=True)
class Report:
    """What a check found, with the texts it read, so rendering reads no file again."""

    diagnostics: list[Diagnostic]
    sources: dict[str, str] = field(default_factory=dict)

    def __iter__(self) -> Iterator[Diagnostic]:
        return iter(self.diagnostics)

    def __len__(self) -> int:
        return len(self.diagnostics)

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.is_error]

    def counts(self) -> tuple[int, int]:
        """Errors and warnings found, those not shown included."""
        errors = warnings = 0
        for d in self.diagnostics:
            if isinstance(d, Omitted):
                errors, warnings = errors + d.errors, warnings + d.warnings
            elif d.is_error:
                errors += 1
            else:
                warnings += 1
        return errors, warnings

    def render(self) -> str:
        return render_all(self.diagnostics, self.sources)

    def to_json(self) -> str:
        """The report for editors and CI: counts and every diagnostic shown, as objects."""
        errors, warnings = self.counts()
        return json.dumps({"errors": errors, "warnings": warnings,
                           "diagnostics": [d.as_dict() for d in self.diagnostics]}, indent=1)


def printable(text: str) -> str:
    """``text`` with control characters escaped (author text must not drive a terminal)."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def quoted(text: str, limit: int = QUOTE_WIDTH) -> str:
    """Author text for a message: clipped to ``limit`` characters."""
    return text if len(text) <= limit else text[:limit] + "..."


_NEWLINES = re.compile("\n")


class _Lines:
    """A source's line starts, found once, then any line in O(log n)."""

    __slots__ = ("starts", "text")

    def __init__(self, text: str):
        self.text = text
        self.starts = [0, *(m.end() for m in _NEWLINES.finditer(text))]

    def line(self, n: int) -> str | None:
        if not 1 <= n <= len(self.starts):
            return None
        end = self.starts[n] - 1 if n < len(self.starts) else len(self.text)
        return self.text[self.starts[n - 1]:end]


def _excerpt(line: str, col: int) -> tuple[str, int]:
    """At most :data:`LINE_WIDTH` characters of ``line`` around ``col`` and the caret's
    offset in them; ``...`` marks a cut."""
    line = line.rstrip("\r")
    at = max(col - 1, 0)
    if len(line) <= LINE_WIDTH:
        start, end = 0, len(line)
    else:
        start = min(max(at - LINE_WIDTH // 2, 0), len(line) - LINE_WIDTH)
        end = start + LINE_WIDTH
    shown = printable(line[start:end].replace("\t", " "))
    caret = len(printable(line[start:min(at, end)].replace("\t", " ")))
    if start > 0:
        shown, caret = "..." + shown, caret + 3
    if end < len(line):
        shown += "..."
    return shown, caret


def render_all(diagnostics: Iterable[Diagnostic], sources: dict[str, str] | None = None) -> str:
    """Every diagnostic with its line and caret where its file's text is in ``sources``."""
    sources = sources or {}
    indexed: dict[str, _Lines | None] = {}
    out: list[str] = []
    for d in diagnostics:
        out.append(d.head())
        if isinstance(d, Omitted):
            continue
        lines = indexed.get(d.path, ...)
        if lines is ...:
            text = sources.get(d.path)
            lines = indexed[d.path] = _Lines(text) if text is not None else None
        line = lines.line(d.line) if lines is not None else None
        if line is not None:
            shown, caret = _excerpt(line, d.col)
            out.append(f"    {shown}\n    {' ' * caret}^")
    return "\n".join(out)


class Reporter:
    """Collects diagnostics during one pass; ``raise_if_errors`` ends the pass.

    Keeps the first :data:`MAX_PER_FILE` of each file by place (a heap of the kept
    ones, latest on top) and counts the rest; :attr:`diagnostics` gives them sorted,
    with one :class:`Omitted` per file that had more.
    """

    def __init__(self, diagnostics: Iterable[Diagnostic] = (),
                 sources: dict[str, str] | None = None):
        self.sources: dict[str, str] = sources if sources is not None else {}
        self._kept: dict[str, list[tuple[int, int, int, Diagnostic]]] = {}
        #: path -> [line, col, errors, warnings] of what is only counted (made an Omitted
        #: when asked for: 200,000 errors must not format 200,000 messages)
        self._omitted: dict[str, list[int]] = {}
        self._seq = 0
        self._errors = 0
        self._places: list[Loc] = []  # of every error added, shown or not
        for d in diagnostics:
            self.add(d)

    def error(self, loc: Loc, message: str) -> None:
        if not self.accepts(loc):  # only counted: no record made (200,000 errors are cheap)
            self._errors += 1
            self._places.append(Loc(*loc))
            self._omit(loc.path, loc.line, loc.col, 1, 0)
            return
        self.add(Diagnostic(loc.path, loc.line, loc.col, ERROR, message))

    def warning(self, loc: Loc, message: str) -> None:
        if not self.accepts(loc):
            self._omit(loc.path, loc.line, loc.col, 0, 1)
            return
        self.add(Diagnostic(loc.path, loc.line, loc.col, WARNING, message))

    def accepts(self, loc: Loc) -> bool:
        """Whether a diagnostic at ``loc`` would be shown (skip costly hints otherwise)."""
        kept = self._kept.get(loc.path)
        return kept is None or len(kept) < MAX_PER_FILE or (loc.line, loc.col) < (
            -kept[0][0], -kept[0][1])

    def add(self, d: Diagnostic) -> None:
        if d.is_error:
            self._errors += 1
            if not isinstance(d, Omitted):
                self._places.append(Loc(d.path, d.line, d.col))
        if isinstance(d, Omitted):
            self._omit(d.path, d.line, d.col, d.errors, d.warnings)
            return
        kept = self._kept.setdefault(d.path, [])
        self._seq += 1
        item = (-d.line, -d.col, -self._seq, d)
        if len(kept) < MAX_PER_FILE:
            heapq.heappush(kept, item)
            return
        if item[:3] > kept[0][:3]:  # before the latest kept one: it takes that one's place
            item = heapq.heapreplace(kept, item)
        dropped = item[3]
        self._omit(dropped.path, dropped.line, dropped.col, int(dropped.is_error),
                   int(not dropped.is_error))

    def _omit(self, path: str, line: int, col: int, errors: int, warnings: int) -> None:
        o = self._omitted.get(path)
        if o is None:
            self._omitted[path] = [line, col, errors, warnings]
            return
        o[2] += errors
        o[3] += warnings
        if (line, col) < (o[0], o[1]):
            o[0], o[1] = line, col

    @property
    def diagnostics(self) -> list[Diagnostic]:
        """Kept diagnostics by file and place (ties in report order), each file's
        :class:`Omitted` after its own."""
        items = [(path, -i[0], -i[1], -i[2], i[3]) for path, kept in self._kept.items()
                 for i in kept]
        items += [(path, o[0], o[1], self._seq + 1, Omitted.of(path, *o))
                  for path, o in self._omitted.items()]
        items.sort(key=lambda i: i[:4])
        return [i[4] for i in items]

    @property
    def has_errors(self) -> bool:
        return self._errors > 0

    def raise_if_errors(self) -> None:
        if self.has_errors:
            error = SceneError(self.diagnostics, self.sources)
            error.places = self._places
            raise error


def suggest(name: str, candidates: Iterable[str]) -> str:
    """`` (did you mean 'X'?)`` for the closest candidate, case first; empty if none is close."""
    if len(name) > _SUGGEST_MAX_LEN:
        return ""
    pool = sorted(set(candidates))
    for c in pool:
        if c.lower() == name.lower() and c != name:
            return f" (did you mean '{c}'?)"
    lowered = {c.lower(): c for c in pool}
    close = difflib.get_close_matches(name.lower(), list(lowered), n=1, cutoff=0.6)
    return f" (did you mean '{lowered[close[0]]}'?)" if close else ""
