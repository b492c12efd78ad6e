"""Running imported models: sample files made by app/bench/interchange_samples.py, imported as
``colosseum import`` does, built and stepped on a real backend."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from app.scene_loading import import_path
from components import Transform
from engine.app import Engine, EngineConfig
from engine.scene import SceneSpec, instantiate, load_spec
from systems import create_engine


def import_scene(model: Path, out: Path | None = None) -> Path:
    """``colosseum import MODEL -o OUT`` (beside the model by default); the scene's path."""
    out = out or model.with_suffix(".scene")
    assert import_path(model, out, force=True) in (0, 1)
    return out


@dataclass
class Run:
    """A scene built and stepped: positions and velocities by object ID."""

    spec: SceneSpec
    engine: Engine
    ids: dict[str, int]

    @classmethod
    def start(cls, scene: Path, backend: str = "ode", dt: float | None = None) -> Run:
        spec = load_spec(scene, np.random.default_rng(0))
        engine = create_engine(EngineConfig(backend=backend, dt=dt or spec.time_step,
                                            content_dir=spec.content_dir,
                                            fast=True, world=spec.world))
        return cls(spec, engine, instantiate(engine, spec))

    def __enter__(self) -> Run:
        return self

    def __exit__(self, *exc: object) -> None:
        self.engine.close()

    def step(self, seconds: float) -> None:
        self.engine.run(seconds=seconds)

    def transform(self, oid: str) -> Transform:
        return self.engine.world.component_for_entity(self.ids[oid], Transform)

    def position(self, oid: str) -> np.ndarray:
        return self.transform(oid).position.copy()

    def velocity(self, oid: str) -> np.ndarray:
        return self.transform(oid).linear_velocity.copy()

    def spin(self, oid: str) -> np.ndarray:
        return self.transform(oid).angular_velocity.copy()
