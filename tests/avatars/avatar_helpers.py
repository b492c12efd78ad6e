"""Content folders with avatars, and engines that run them the way `colosseum run` does."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from components import Name, Transform
from engine.app import Engine, EngineConfig
from engine.scene import instantiate, load_spec
from engine.scripting.runtime import ScriptLimits
from systems import RegistryPlugin, load_plugin
from systems.avatars import AvatarsPlugin, AvatarSystem
from systems.scripting import ScriptingPlugin

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "content" / "avatars" / "models"
SAMPLES = Path(__file__).resolve().parent / "samples"
#: Every skinned model the project ships.
SHIPPED = (MODELS / "walker.glb", MODELS / "Fox.glb", SAMPLES / "walker_lost_texture.gltf")
LIMITS = ScriptLimits(instructions=2_000_000, memory=64 * 1024 * 1024)
GROUND = ('Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } }'
          ' VisualAttributes { Geometry { Primitive "plane" } Color [0.5 0.6 0.5] } }')


def content(root: Path, scene: str, scripts: dict[str, str] | None = None,
            models: tuple[Path, ...] = (MODELS / "walker.glb",)) -> Path:
    """A content folder: ``main.scene``, scripts, and copies of ``models`` in models/."""
    (root / "scripts").mkdir(parents=True, exist_ok=True)
    (root / "models").mkdir(exist_ok=True)
    for model in models:
        shutil.copy(model, root / "models" / model.name)
        if model.suffix == ".gltf" and model.with_suffix(".bin").exists():
            shutil.copy(model.with_suffix(".bin"), root / "models" / model.with_suffix(
                ".bin").name)
    (root / "main.scene").write_text(scene)
    for name, text in (scripts or {}).items():
        (root / "scripts" / name).write_text(text)
    return root


def avatar_engine(folder: Path, backend: str = "ode", dt: float = 1 / 64,
                  render: bool = False, mode: str = "serial") -> Engine:
    """Physics, scripts and avatars (and headless rendering when asked), the scene loaded."""
    config = EngineConfig(backend=backend, fast=True, content_dir=folder, dt=dt, mode=mode)
    plugins = [RegistryPlugin(), load_plugin("physics"), ScriptingPlugin(LIMITS, 0.0),
               AvatarsPlugin()]
    if render:
        from systems.render import RenderOptions, RenderPlugin

        plugins.append(RenderPlugin(RenderOptions(backend="headless", size=(160, 120))))
    engine = Engine(config, plugins=plugins)
    instantiate(engine, load_spec(folder / "main.scene", engine.rng))
    return engine


def entity(engine: Engine, name: str) -> int:
    (found,) = [e for e, n in engine.world.get_component(Name) if n.id == name]
    return found


def position(engine: Engine, name: str) -> np.ndarray:
    return engine.world.component_for_entity(entity(engine, name), Transform).position.copy()


def avatars(engine: Engine) -> AvatarSystem:
    engine.start()  # the plugin's system makes itself a resource when set up
    return engine.resource(AvatarSystem)
