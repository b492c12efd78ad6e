"""What plugins offer scripts and tools, as protocols the core can name.

A plugin that provides one registers itself as the resource of that protocol
(``engine.insert_resource(system, as_type=SoundControl)``); a caller asks for it with
``engine.try_resource(SoundControl)`` and gets None when the plugin is not loaded. The
core and the services below the plugin layer never import a plugin to find it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from components.script import SavedScript
from engine.system import PluginName

if TYPE_CHECKING:
    from components.avatar_saved import SavedAvatar

#: A uniform's value: one number or a vector of numbers.
UniformValue = float | tuple[float, ...]


class SoundControl(Protocol):
    """Playing an entity's Sound component (the sound plugin)."""

    #: The plugin to request (``requestPlugin``) when this service is missing.
    plugin = PluginName.SOUND

    def play(self, engine: Any, entity: int) -> Any: ...
    def stop(self, entity: int) -> None: ...
    def set_gain(self, entity: int, gain: float) -> None: ...


class ShaderControl(Protocol):
    """Changing shader uniforms and post-processing passes at run time (the render plugin)."""

    plugin = PluginName.RENDER

    def set_uniform(self, state_id: str, name: str, value: UniformValue) -> None: ...
    def enable_post(self, name: str, enabled: bool = True) -> None: ...
    def set_post_uniform(self, name: str, uniform: str, value: UniformValue) -> None: ...


class SwapGate(Protocol):
    """What a drawn frame waits for before it is shown (the net node plugin's swap
    barrier, so the walls of a cluster swap together): the render system calls
    :meth:`before_swap` once a frame is drawn and the GPU has finished it, then swaps."""

    plugin = PluginName.NET_NODE

    def before_swap(self) -> None: ...


class ScriptStates(Protocol):
    """The running scripts' states, for a saved run (the scripting plugin)."""

    plugin = PluginName.SCRIPTING

    def saved_scripts(self, object_name: Callable[[int], str | None]
                      ) -> dict[int, SavedScript]:
        """Entity -> the state of the script it runs; ``object_name`` gives the scene ID
        an entity is written under (None: it is not written)."""
        ...


#: The methods an avatar's handle has in Lua (``avatar:play("Run", {fade=0.3})``); each is
#: :meth:`AvatarControl.script_call` with its name and arguments.
AVATAR_METHODS = ("play", "queue", "blend", "stopAnimation", "animation", "clips", "setPath",
                  "hold", "release", "driveBone", "releaseBone", "bonePose")


class AvatarControl(Protocol):
    """Animating avatars from scripts (the avatars plugin)."""

    plugin = PluginName.AVATARS

    def script_call(self, entity: int, method: str, args: list[Any]) -> Any:
        """Run one of :data:`AVATAR_METHODS` on avatar ``entity``; plain data in and out;
        raises ValueError (KeyError for an object that is not an avatar) with a message
        naming what exists."""


class AvatarStates(Protocol):
    """The avatars' states, for a saved run (the avatars plugin)."""

    plugin = PluginName.AVATARS

    def saved_avatars(self, object_name: Callable[[int], str | None]
                      ) -> dict[int, SavedAvatar]:
        """Avatar entity -> where it stands (see :class:`components.avatar_saved.SavedAvatar`);
        ``object_name`` gives the scene ID an object is written under (None: it is not
        written, so an avatar holding it lets go in the saved state, with a message)."""
        ...


class HandControl(Protocol):
    """Virtual hands asked from scripts (the hands plugin)."""

    plugin = PluginName.HANDS

    def state(self, hand: int) -> str: ...
    def held(self, hand: int) -> tuple[int, ...]: ...
    def grasp(self, hand: int, obj: int) -> None: ...
    def release(self, hand: int) -> None: ...


class HeadsetControl(Protocol):
    """The headset display (the xr plugin): controller pulses and recentering."""

    plugin = PluginName.XR

    def haptic(self, source: str, amplitude: float, seconds: float) -> bool:
        """Pulse the controller of ``source`` (``hand_l``/``hand_r``); False when none."""
        ...

    def recenter(self) -> None:
        """Move the player over the active camera, facing its way."""
        ...


class ExperimentControl(Protocol):
    """The trial running now (the experiment plugin, ``colosseum experiment run``)."""

    plugin = PluginName.EXPERIMENT

    def condition(self, factor: str) -> str | None: ...
    def trial_data(self) -> dict[str, Any] | None: ...
    def respond(self, name: str, value: Any) -> None: ...
    def finish(self, outcome: str) -> None: ...
