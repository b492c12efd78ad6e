"""Content folders with avatars, and engines that run them the way `colosseum run` does."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from components import Name, Transform
from engine.app import Engine, EngineConfig
from engine.scene import instantiate, load_spec
from services.scripting.runtime import ScriptLimits
from systems import RegistryPlugin, load_plugin
from systems.avatars import AvatarsPlugin, AvatarSystem
from systems.scripting import ScriptingPlugin

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "content" / "avatars" / "models"
SAMPLES = Path(__file__).resolve().parent / "samples"
#: Every skinned model the project ships (all written by tools/gltf_samples.py).
SHIPPED = (MODELS / "walker.glb", MODELS / "hound.glb", SAMPLES / "walker_lost_texture.gltf",
           SAMPLES / "strip.gltf")
#: Skinned glTF files others made, to load, animate and draw when a folder of them is at
#: hand (the Khronos samples RiggedSimple, RiggedFigure, CesiumMan, BrainStem...; none is
#: shipped): shared/gltf-samples beside the checkout, or the folder COLOSSEUM_GLTF_SAMPLES
#: names. Parameters for the tests that read them: one skipped, saying why, when absent.
_AT_HAND = Path(os.environ.get("COLOSSEUM_GLTF_SAMPLES", ROOT.parent / "shared" / "gltf-samples"))
_FOUND = sorted(p for p in _AT_HAND.glob("*") if p.suffix in (".glb", ".gltf"))
AT_HAND = tuple(pytest.param(p, id=p.name) for p in _FOUND) or (pytest.param(
    None, marks=pytest.mark.skip(reason=f"no folder of others' skinned glTF files at hand "
                                        f"({_AT_HAND}, or the one COLOSSEUM_GLTF_SAMPLES names)")),)
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
