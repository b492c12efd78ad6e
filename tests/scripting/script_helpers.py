"""Engines with scripting on real backends, built from scene files the way `colosseum run` does."""

from __future__ import annotations

import importlib
from pathlib import Path

from engine.app import Engine, EngineConfig
from engine.scene import instantiate, load_spec
from services.scripting.runtime import ScriptLimits, ScriptRuntime
from systems import RegistryPlugin, load_plugin
from systems.controllers import ControllersPlugin
from systems.scripting import ScriptingPlugin

LIMITS = ScriptLimits(instructions=2_000_000, memory=64 * 1024 * 1024)


def backends() -> list[str]:
    names = ["pymunk"]
    try:
        importlib.import_module("engine.physics.ode3d")
        names.append("ode")
    except ImportError:
        pass
    return names


def write_content(root: Path, scene: str, scripts: dict[str, str]) -> Path:
    (root / "scripts").mkdir(exist_ok=True)
    (root / "main.scene").write_text(scene)
    for name, text in scripts.items():
        (root / "scripts" / name).write_text(text)
    return root


def scripted_engine(content: Path, backend: str = "pymunk", mode: str = "serial",
                    extra_plugins: tuple = ()) -> Engine:
    config = EngineConfig(backend=backend, fast=True, content_dir=content, mode=mode,
                          dt=1 / 60)
    engine = Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                     ScriptingPlugin(LIMITS, reload_interval=0.0),
                                     ControllersPlugin(), *extra_plugins])
    instantiate(engine, load_spec(content / "main.scene", engine.rng))
    return engine


def runtime_of(engine: Engine) -> ScriptRuntime:
    return engine.resource(ScriptRuntime)


def script_named(engine: Engine, name: str):
    return next(s for s in runtime_of(engine).scripts if s.name == name)
