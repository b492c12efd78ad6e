"""Engine systems, one module each; every module exposes a plugin. This package is where
an application is assembled: :func:`default_plugins` is what ``colosseum run`` starts with,
:func:`create_engine` an engine built with them.

Plugins are registered by name (:data:`PLUGINS`, the one list of plugin names and the
paper's aliases for them) so scenes and Lua's ``requestPlugin`` can load them.

A plugin that serves only entities with its feature's components (:data:`FEATURES`:
avatars, hands) is loaded when its scene has one: an engine told which components its
scene makes (``options["components"]``, set by ``LoadedScene.configure``) builds the others
only when the first such component is added (a script's spawn, a server's world), so a
plain scene's run loads no animation or finger code.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from engine.app import Engine, EngineConfig
from engine.system import PluginName

if TYPE_CHECKING:
    from engine.system import Plugin

#: plugin name -> "module:Class", in the order a default engine builds them (systems of
#: one phase run in the order added unless they declare before/after); render last, and
#: only when something is drawn.
PLUGINS: dict[PluginName, str] = {
    PluginName.INPUT: "systems.input:InputPlugin",
    PluginName.PHYSICS: "systems.dynamics:DynamicsPlugin",
    PluginName.SCRIPTING: "systems.scripting:ScriptingPlugin",
    PluginName.CONTROLLERS: "systems.controllers:ControllersPlugin",
    PluginName.SOUND: "systems.sound:SoundPlugin",
    PluginName.AVATARS: "systems.avatars:AvatarsPlugin",
    PluginName.TRIGGERS: "systems.triggers:TriggersPlugin",
    PluginName.HANDS: "systems.hands:HandsPlugin",
    PluginName.MEASURES: "systems.measures:MeasuresPlugin",
    PluginName.WHEELCHAIR: "systems.wheelchair:WheelchairPlugin",
    PluginName.SESSION: "systems.session:SessionPlugin",
    PluginName.ANOMALIES: "systems.anomalies:AnomaliesPlugin",
    PluginName.RENDER: "systems.render:RenderPlugin",
    PluginName.XR: "systems.xr:XrPlugin",
}
#: plugin name -> the components (names in :mod:`components`) whose entities it serves.
FEATURES: dict[PluginName, tuple[str, ...]] = {
    PluginName.AVATARS: ("Avatar",),
    PluginName.HANDS: ("Hand",),
}
#: The paper's plugin names.
ALIASES: dict[str, PluginName] = {
    "osg": PluginName.RENDER, "osgsim": PluginName.RENDER, "openalpp": PluginName.SOUND,
    "openal": PluginName.SOUND, "ode": PluginName.PHYSICS, "dynamics": PluginName.PHYSICS,
    "interaction": PluginName.HANDS}


def load_plugin(name: str) -> Any:
    target = PLUGINS[ALIASES.get(name, name)]
    module_name, class_name = target.split(":")
    return getattr(importlib.import_module(module_name), class_name)()


def register_all(engine: Engine) -> None:
    """Make every known plugin loadable by name on ``engine``."""
    for name in PLUGINS:
        aliases = [alias for alias, target in ALIASES.items() if target == name]
        engine.register_plugin(name, lambda name=name: load_plugin(name), aliases)


class WaitingPlugin:
    """Stands for a feature's plugin (:data:`FEATURES`) in an engine whose scene has none
    of its components: the first one added builds it, at the next phase boundary (its
    systems then run after those of the default plugins of their phase)."""

    def __init__(self, plugin: PluginName) -> None:
        self.plugin = plugin
        self.name = f"{plugin} (until its first {' or '.join(FEATURES[plugin])})"
        self._woken = False

    def build(self, engine: Engine) -> None:
        import components

        def wake(entity: int, component: Any) -> None:
            if not self._woken:
                self._woken = True
                engine.defer(lambda: self._load(engine))

        for kind in FEATURES[self.plugin]:
            engine.world.on_add(getattr(components, kind), wake)

    def _load(self, engine: Engine) -> None:
        if str(self.plugin) not in engine.plugins:  # (a script may have asked for it)
            engine.add_plugin(load_plugin(self.plugin))


def _feature(name: PluginName, config: EngineConfig) -> Plugin:
    """Plugin ``name``, or one waiting for its feature where the scene has none of it."""
    present = config.options.get("components")
    wakes = FEATURES.get(name)
    if present is not None and wakes and present.isdisjoint(wakes):
        return WaitingPlugin(name)
    return load_plugin(name)


class RegistryPlugin:
    """Registers the named plugins; the first plugin of every default engine."""

    name = PluginName.REGISTRY

    def build(self, engine: Engine) -> None:
        register_all(engine)


def wants_render(config: EngineConfig) -> bool:
    """Draw when someone looks: a window, or a screenshot, recorded frames or a HUD asked for."""
    opts = config.options
    return (config.render or not config.headless or bool(opts.get("screenshot"))
            or bool(opts.get("record_frames")) or bool(opts.get("xr")))


def default_plugins(config: EngineConfig) -> list[Plugin]:
    """The registry, then every plugin but the displays (a feature's only where the scene
    has it: :data:`FEATURES`); the headset display (before the input it brings devices to)
    where ``options["xr"]`` asks for it; the renderer last, when something is drawn."""
    plugins: list[Plugin] = [RegistryPlugin()]
    if config.options.get("xr"):
        plugins.append(load_plugin(PluginName.XR))
    plugins.extend(_feature(name, config) for name in PLUGINS
                   if name not in (PluginName.RENDER, PluginName.XR))
    if wants_render(config):
        plugins.append(load_plugin(PluginName.RENDER))
    return plugins


def create_engine(config: EngineConfig | None = None, **kwargs: Any) -> Engine:
    """An engine with the default plugins (``kwargs`` go to :class:`Engine`)."""
    config = config or EngineConfig()
    return Engine(config, plugins=default_plugins(config), **kwargs)
