"""Functions longer than 60 lines (``python -m tools.long_functions``), outside the tests.

A function over a screen is read in pieces and changed in the wrong one; the limit is 60
lines, definition to last line, docstring and comments included. The few that stay
longer are listed in :data:`ALLOWED`, each with its reason, which also stands in a
comment above the function; a new long function, or one that grew long, is reported as
``file:line``, and so is an allowed one that is no longer long, so the list only shrinks.

Python is read with :mod:`ast`. Cython (``.pyx``/``.pxi``) is read by indentation: a
``def``/``cdef``/``cpdef`` function runs until the next line that is not blank, not a
comment and not indented deeper than its definition.
"""

from __future__ import annotations

import ast
import re
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FOLDERS = ("components", "engine", "services", "systems", "app", "tools")
LIMIT = 60


#: ``path::qualified name`` -> why it stays long (the same reason is a comment above it,
#: except in files another engineer is rewriting).
ALLOWED: dict[str, str] = {
    "engine/scene/_scan.pyx::scan_plain":
        "the scanner's pass over plain entries: its cursor stays in C locals",
    "engine/scene/_scan.pyx::_vector":
        "a vector literal in one C loop, its cursor in C locals as scan_plain's",
    "engine/scene/parser.py::Parser._block":
        "the token loop of a block: comments, blank lines, last entry shared",
    "engine/scene/lexer.py::Lexer.next_token":
        "dispatch on the next character, once a token: no call per branch",
    "engine/physics/ode3d/_world.pxi::World.step":
        "the step as one sequence, the GIL released once around it",
    "engine/physics/pymunk2d/_rows.pyx::carried_down":
        "one typed pass over the contact rows (C locals; a helper per part would be a "
        "Python call per row)",
    "engine/physics/pymunk2d/_rows.pyx::Rows.contacts":
        "one typed pass over the arbiter rows (C locals, as carried_down)",
    "engine/physics/pymunk2d/_rows.pyx::planar_poses":
        "one typed pass over the pose table into the plane (C locals, as carried_down)",
}


@dataclass(frozen=True, slots=True)
class Function:
    path: Path
    name: str
    line: int
    length: int

    def key(self, root: Path = ROOT) -> str:
        return f"{self.path.relative_to(root).as_posix()}::{self.name}"


def python_functions(path: Path) -> list[Function]:
    """Every function and method of a Python file, by qualified name (``Class.method``,
    ``outer.<locals>.inner``)."""
    found: list[Function] = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef):
                name = prefix + child.name
                start = min([child.lineno, *(d.lineno for d in child.decorator_list)])
                found.append(Function(path, name, start, child.end_lineno - start + 1))
                visit(child, name + ".<locals>.")
            elif isinstance(child, ast.ClassDef):
                visit(child, prefix + child.name + ".")
            else:
                visit(child, prefix)

    visit(ast.parse(path.read_text(encoding="utf-8"), str(path)), "")
    return found


_CYTHON_DEF = re.compile(r"^(\s*)(?:cdef|cpdef|def)\s+(?:(?:inline|public|api)\s+)*"
                         r"(?:[\w.\[\], *]+?\s+)??\**(\w+)\s*\(")
_CYTHON_CLASS = re.compile(r"^(\s*)(?:cdef\s+)?class\s+(\w+)")


def cython_functions(path: Path) -> list[Function]:
    """Every function of a Cython file (``cdef``, ``cpdef`` and ``def``), methods as
    ``Class.method``; ``cdef`` declarations without a body (``extern``, fields) are not
    functions."""
    lines = path.read_text(encoding="utf-8").splitlines()
    found: list[Function] = []
    classes: list[tuple[int, str]] = []
    for i, text in enumerate(lines):
        klass = _CYTHON_CLASS.match(text)
        if klass and text.rstrip().endswith(":"):
            depth = len(klass.group(1))
            classes = [c for c in classes if c[0] < depth] + [(depth, klass.group(2))]
            continue
        match = _CYTHON_DEF.match(text)
        if not match or "extern" in text:
            continue
        depth = len(match.group(1))
        end = _signature_end(lines, i)
        if end is None:
            continue  # a declaration: no body
        last = end
        for j in range(end + 1, len(lines)):
            stripped = lines[j].strip()
            if not stripped or stripped.startswith("#"):
                continue
            if len(lines[j]) - len(lines[j].lstrip()) <= depth:
                break
            last = j
        classes = [c for c in classes if c[0] < depth]
        owner = "".join(f"{c[1]}." for c in classes)
        found.append(Function(path, owner + match.group(2), i + 1, last - i + 1))
    return found


def _signature_end(lines: list[str], start: int) -> int | None:
    """The line where a definition's signature ends with ``:``, or None when it ends
    without one (a forward declaration)."""
    depth = 0
    for j in range(start, min(start + 40, len(lines))):
        code = lines[j].split("#")[0]
        depth += code.count("(") - code.count(")")
        if depth <= 0:
            return j if code.rstrip().endswith(":") else None
    return None


def functions(root: Path = ROOT) -> list[Function]:
    """Every function of the project's source (the tests are not counted)."""
    found: list[Function] = []
    for folder in FOLDERS:
        for path in sorted((root / folder).rglob("*")):
            if path.suffix == ".py":
                found.extend(python_functions(path))
            elif path.suffix in (".pyx", ".pxi"):
                found.extend(cython_functions(path))
    return found


def long_functions(root: Path = ROOT) -> list[Function]:
    return [f for f in functions(root) if f.length > LIMIT]


def check(root: Path = ROOT, allowed: dict[str, str] | None = None) -> list[str]:
    """A message per long function not allowed and per allowed one no longer long."""
    allowed = ALLOWED if allowed is None else allowed
    problems = []
    long = long_functions(root)
    for f in long:
        if f.key(root) not in allowed:
            problems.append(f"{f.path.relative_to(root)}:{f.line}: {f.name} is {f.length} "
                            f"lines (at most {LIMIT}): split it, or say in ALLOWED why not")
    for f in long:
        reason = allowed.get(f.key(root))
        if reason is not None and not _commented(f):
            problems.append(f"{f.path.relative_to(root)}:{f.line}: {f.name} is allowed to be "
                            f"long; say why in a '# Long: ...' line above it")
    keys = {f.key(root) for f in long}
    problems += [f"{key}: allowed as long but no longer is (or is gone); take it off ALLOWED"
                 for key in sorted(set(allowed) - keys)]
    return problems


def _commented(f: Function) -> bool:
    """Whether the line above the function (above its decorators) is its ``# Long:``."""
    lines = f.path.read_text(encoding="utf-8").splitlines()
    return f.line >= 2 and lines[f.line - 2].strip().startswith("# Long:")


def main() -> int:
    long = long_functions()
    for f in sorted(long, key=lambda f: -f.length):
        print(f"{f.length:4d}  {f.path.relative_to(ROOT)}:{f.line}  {f.name}")
    problems = check()
    for problem in problems:
        print(problem, file=sys.stderr)
    print(f"{len(long)} function(s) over {LIMIT} lines, {len(problems)} problem(s)",
          file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
