"""A package's names loaded on first use (PEP 562), so importing one of its modules does
not load all of them: ``colosseum check`` reads a scene without the engine's runtime, and
a system needing one helper of the renderer does not load the renderer.

A package lists where each of its names lives; the layers check (``tools.layers``) reads
the same modules under ``if TYPE_CHECKING:`` in the package, for type checkers and readers.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from typing import Any


def lazy_exports(package: str, homes: dict[str, tuple[str, ...]]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``: ``homes`` maps a module to the names
    the package takes from it. A name found once is kept in the package, as an import
    would have put it there. A name not listed raises AttributeError, so ``from package
    import submodule`` imports the submodule as usual."""
    home_of = {name: module for module, names in homes.items() for name in names}

    def __getattr__(name: str) -> Any:
        home = home_of.get(name)
        if home is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(home), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(sys.modules[package]), *home_of})

    return __getattr__, __dir__
