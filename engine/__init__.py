"""Colosseum: an entity-component-system engine for physics-driven virtual environments.

:class:`Engine` and :class:`EngineConfig` load on first use (:mod:`engine.lazy`), so a
command that only reads scene files (``colosseum check``, ``keys``) does not import the
engine's runtime. ``engine.system`` is the decorator, as it always was (it shadows the
module of that name, which stays importable as ``engine.system``'s names).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.lazy import lazy_exports
from engine.system import Phase, Plugin, System, system

if TYPE_CHECKING:
    from engine.app import Engine
    from engine.config import EngineConfig

__all__ = ["Engine", "EngineConfig", "Phase", "Plugin", "System", "system"]

__getattr__, __dir__ = lazy_exports(__name__, {"engine.app": ("Engine",),
                                               "engine.config": ("EngineConfig",)})
