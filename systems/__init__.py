"""Engine systems, one module each; every module exposes a plugin.

Plugins are registered by name so scenes and Lua's ``requestPlugin`` can load
them; :func:`default_plugins` is what ``colosseum run`` starts with.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from engine.app import Engine, EngineConfig

#: plugin name -> "module:Class"; aliases from the paper's plugin names.
PLUGINS: dict[str, str] = {
    "physics": "systems.dynamics:DynamicsPlugin",
}
ALIASES: dict[str, str] = {}


def load_plugin(name: str) -> Any:
    target = PLUGINS[ALIASES.get(name, name)]
    module_name, class_name = target.split(":")
    return getattr(importlib.import_module(module_name), class_name)()


def register_all(engine: Engine) -> None:
    """Make every known plugin loadable by name on ``engine``."""
    for name in PLUGINS:
        aliases = [alias for alias, target in ALIASES.items() if target == name]
        engine.register_plugin(name, lambda name=name: load_plugin(name), aliases)


class RegistryPlugin:
    """Registers the named plugins; the first plugin of every default engine."""

    name = "registry"

    def build(self, engine: Engine) -> None:
        register_all(engine)


def default_plugins(config: EngineConfig) -> list[Any]:
    return [RegistryPlugin(), load_plugin("physics")]
