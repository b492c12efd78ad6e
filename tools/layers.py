"""Dependencies run one way: a check over the project's imports (``python -m tools.layers``).

Layers, lowest first (docs/ARCHITECTURE.md draws them), one top-level folder each::

    components  <-  engine  <-  services  <-  systems  <-  app  <-  tools

``engine`` is the core (world, phases, scene format, physics, assets, importers);
``services`` what drives a device or a library for the plugins (render, audio, scripting,
input, net, xr, and the glTF exporter, which draws primitives with the renderer's meshes);
``systems`` the plugins; ``app`` what a user runs (the CLI, runner, sweep, benchmarks);
``tools`` developer scripts (docs, fuzzing, this check). A module's layer is its folder:
there is no exception to look up, so a new module is placed by where it is written.

A module may import its own layer and the ones below; an import of a higher layer
is an error, and so is any import cycle among the project's modules. Imports under
``if TYPE_CHECKING:`` are type hints, not dependencies, and are not counted; imports
inside functions are (deferring an import does not remove the dependency).

>>> layer_of("services.render.camera").name, layer_of("engine.scene.parser").name
('services', 'engine core')
"""

from __future__ import annotations

import ast
import re
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


@dataclass(frozen=True, slots=True)
class Layer:
    rank: int
    name: str
    folder: str


#: The layers, lowest first: one top-level folder each.
LAYERS = tuple(Layer(rank, name, folder) for rank, (folder, name) in enumerate((
    ("components", "components"),
    ("engine", "engine core"),
    ("services", "services"),
    ("systems", "systems"),
    ("app", "application"),
    ("tools", "developer tools"),
)))
PACKAGES = tuple(layer.folder for layer in LAYERS)
_BY_FOLDER = {layer.folder: layer for layer in LAYERS}


def layer_of(module: str) -> Layer:
    """The layer of a dotted module name: that of its top-level folder."""
    layer = _BY_FOLDER.get(module.split(".")[0])
    if layer is None:
        raise ValueError(f"{module} belongs to no layer (folders: {', '.join(PACKAGES)})")
    return layer


@dataclass(frozen=True, slots=True)
class Import:
    source: str
    target: str
    path: Path
    line: int


def module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def project_modules(root: Path) -> dict[str, Path]:
    """Python and Cython modules of the project by dotted name."""
    found = {}
    for package in PACKAGES:
        for pattern in ("*.py", "*.pyx"):
            for path in (root / package).rglob(pattern):
                found[module_name(path, root)] = path
    return found


_IMPORT_START = re.compile(r"^(from\s+[\w.]+\s+import\s|import\s+[\w.]+)")


def _cython_imports(path: Path) -> ast.Module:
    """The Python-level imports of a Cython module (its ``cimport``s are C, not modules):
    the top-level ``import``/``from ... import`` statements, parenthesised ones joined."""
    statements: list[str] = []
    pending: list[str] = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if pending:
            pending.append(line)
            if ")" in line:
                statements.append(" ".join(pending))
                pending = []
        elif _IMPORT_START.match(line):
            if "(" in line and ")" not in line:
                pending = [line]
            else:
                statements.append(line)
    body: list[ast.stmt] = []
    for statement in statements:
        try:
            body.extend(ast.parse(statement, str(path)).body)
        except SyntaxError:  # prose in a docstring that happens to start like an import
            continue
    return ast.Module(body=body, type_ignores=[])


def _type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports_of(path: Path, name: str, modules: dict[str, Path]) -> list[Import]:
    """The project modules ``path`` imports (``from pkg import sub`` names ``pkg.sub``)."""
    tree = _cython_imports(path) if path.suffix == ".pyx" else ast.parse(
        path.read_text(encoding="utf-8"), str(path))
    is_package = path.name == "__init__.py"
    found: list[Import] = []

    def add(target: str, line: int) -> None:
        if target.split(".")[0] in PACKAGES and target != name:
            found.append(Import(name, target, path, line))

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _type_checking(child):
                for sub in child.orelse:
                    visit(sub)
                continue
            if isinstance(child, ast.Import):
                for alias in child.names:
                    add(alias.name, child.lineno)
            elif isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    package = name if is_package else name.rpartition(".")[0]
                    for _ in range(child.level - 1):
                        package = package.rpartition(".")[0]
                    base = f"{package}.{base}" if base else package
                for alias in child.names:
                    sub = f"{base}.{alias.name}"
                    add(sub if sub in modules else base, child.lineno)
            visit(child)

    visit(tree)
    return found


def upward_imports(graph: list[Import]) -> list[Import]:
    return [i for i in graph if layer_of(i.target).rank > layer_of(i.source).rank]


def cycles(graph: list[Import]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan), sorted."""
    edges: dict[str, set[str]] = {}
    for i in graph:
        edges.setdefault(i.source, set()).add(i.target)
        edges.setdefault(i.target, set())
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10 * len(edges) + 100))

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(edges):
        if v not in index:
            connect(v)
    return sorted(groups)


def check(root: Path = ROOT) -> list[str]:
    """Every upward import (``file:line``) and every cycle, as messages; empty when clean."""
    modules = project_modules(root)
    graph = [i for name, path in sorted(modules.items())
             for i in imports_of(path, name, modules)]
    problems = [f"{i.path.relative_to(root)}:{i.line}: {i.source} ({layer_of(i.source).name}) "
                f"imports {i.target} ({layer_of(i.target).name}), a higher layer"
                for i in upward_imports(graph)]
    for group in cycles(graph):
        problems.append("import cycle: " + " -> ".join(group))
    return problems


def main() -> int:
    problems = check()
    for problem in problems:
        print(problem)
    print(f"{len(problems)} layering problem(s)", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
