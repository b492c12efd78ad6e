"""Colosseum: an entity-component-system engine for physics-driven virtual environments."""

from engine.app import Engine, EngineConfig
from engine.system import Phase, Plugin, System, system

__all__ = ["Engine", "EngineConfig", "Phase", "Plugin", "System", "system"]
