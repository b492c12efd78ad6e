"""What plugins offer scripts and tools, as protocols the core can name.

A plugin that provides one registers itself as the resource of that protocol
(``engine.insert_resource(system, as_type=SoundControl)``); a caller asks for it with
``engine.try_resource(SoundControl)`` and gets None when the plugin is not loaded. The
core and the services below the plugin layer never import a plugin to find it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from components.script import SavedScript

#: A uniform's value: one number or a vector of numbers.
UniformValue = float | tuple[float, ...]


class SoundControl(Protocol):
    """Playing an entity's Sound component (the sound plugin)."""

    #: The plugin to request (``requestPlugin``) when this service is missing.
    plugin = "sound"

    def play(self, engine: Any, entity: int) -> Any: ...
    def stop(self, entity: int) -> None: ...
    def set_gain(self, entity: int, gain: float) -> None: ...


class ShaderControl(Protocol):
    """Changing shader uniforms at run time (the render plugin)."""

    plugin = "render"

    def set_uniform(self, state_id: str, name: str, value: UniformValue) -> None: ...


class ScriptStates(Protocol):
    """The running scripts' states, for a saved run (the scripting plugin)."""

    plugin = "scripting"

    def saved_scripts(self, object_name: Callable[[int], str | None]
                      ) -> dict[int, SavedScript]:
        """Entity -> the state of the script it runs; ``object_name`` gives the scene ID
        an entity is written under (None: it is not written)."""
        ...
