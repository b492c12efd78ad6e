"""engine.scene has no module-level import cycle, its package __init__ included.

A module of the package imports its siblings by their own names
(``from engine.scene.db import ...``), never through the package
(``from engine.scene import ...``), which would run ``__init__`` in the middle of
their own import. ``__init__`` itself imports none of them: its names load on first
use (engine.lazy), so ``colosseum keys`` reads the schema without the factory.
Imports inside functions and under ``TYPE_CHECKING`` are not module-level and do not
count.
"""

from __future__ import annotations

import re
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import engine.scene

PACKAGE = Path(engine.scene.__file__).parent
#: A module-level import statement (not indented) naming an engine.scene module.
IMPORT = re.compile(r"^(?:from\s+(engine\.scene[\w.]*)\s+c?import|import\s+(engine\.scene[\w.]*))",
                    re.MULTILINE)


def module_name(path: Path) -> str:
    return "engine.scene" if path.stem == "__init__" else f"engine.scene.{path.stem}"


def import_graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {}
    for path in sorted([*PACKAGE.glob("*.py"), *PACKAGE.glob("*.pyx")]):
        found = IMPORT.findall(path.read_text(encoding="utf-8"))
        graph[module_name(path)] = {a or b for a, b in found}
    return graph


def test_the_graph_is_read():
    graph = import_graph()
    assert "engine.scene.db" in graph["engine.scene.parser"]
    assert "engine.scene.expr" in graph["engine.scene._scan"]
    assert "engine.scene.parser" in graph["engine.scene.loader"]
    assert graph["engine.scene"] == set()  # under TYPE_CHECKING only: loaded on first use


def test_no_module_level_import_cycle_in_engine_scene():
    graph = import_graph()
    try:
        list(TopologicalSorter(graph).static_order())
    except CycleError as exc:
        raise AssertionError(f"import cycle: {' -> '.join(exc.args[1])}") from None
    through_package = sorted(m for m, deps in graph.items() if "engine.scene" in deps)
    assert not through_package, f"import siblings by their own names: {through_package}"
