"""Running others' physics files (../shared/gltf-physics) and reading what happened: the
helpers of the conformance tests (issue 31).

A file is run the way a scene imports it (``Model { File ... }`` in a scene of its own,
the file's folder allowed), headless and serial, and every body's pose is recorded each
frame: a :class:`Trace`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from components import Joint, Name, Physical, Shape, Transform
from engine.rotation import quat_to_matrix

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "gltf-physics"


@dataclass
class Trace:
    """Every body's pose, frame by frame (frame 0: as built), and what the world held."""

    names: list[str]
    kinds: list[str]
    bodies: list[Physical]
    times: np.ndarray  # (T,)
    position: np.ndarray  # (T, N, 3)
    orientation: np.ndarray  # (T, N, 4)
    joints: list[tuple[Joint, str, str | None]]
    errors: int
    dt: float

    def index(self, name: str) -> int:
        return self.names.index(name)

    def dynamic(self) -> list[int]:
        return [i for i, k in enumerate(self.kinds) if k == "dynamic"]

    def static(self) -> list[int]:
        return [i for i, k in enumerate(self.kinds) if k == "static"]

    def z_range(self, i: int, frame: int = -1) -> tuple[float, float]:
        """The lowest and highest world z of body ``i``'s shapes at ``frame``."""
        low, high = self.bounds(i, frame)
        return float(low[2]), float(high[2])

    def bounds(self, i: int, frame: int = -1) -> tuple[np.ndarray, np.ndarray]:
        """The world box around body ``i``'s shapes (planes aside) at ``frame``."""
        boxes = [shape_bounds(s, self.position[frame, i], self.orientation[frame, i])
                 for s in self.bodies[i].shapes if s.kind != "plane"]
        return (np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0))

    def velocity(self, i: int, frames: int = 5) -> np.ndarray:
        """Body ``i``'s mean velocity over the last ``frames`` frames (m/s)."""
        return (self.position[-1, i] - self.position[-1 - frames, i]) / (
            self.times[-1] - self.times[-1 - frames])

    def turned(self, i: int, frame: int = -1) -> float:
        """How far body ``i`` turned from its first orientation (degrees)."""
        q0, q1 = self.orientation[0, i], self.orientation[frame, i]
        return float(np.degrees(2 * np.arccos(min(1.0, abs(float(q0 @ q1))))))


def shape_bounds(shape: Shape, position: np.ndarray, orientation: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """A shape's world box, its body at ``position``/``orientation``."""
    body = quat_to_matrix(np.asarray(orientation, float))
    turn = body @ quat_to_matrix(np.asarray(shape.rotation, float))
    center = np.asarray(position, float) + body @ np.asarray(shape.offset, float)
    size = np.asarray(shape.size, float)
    if shape.kind == "sphere":
        reach = np.full(3, size[0])
    elif shape.kind == "box":
        reach = np.abs(turn) @ (size[:3] / 2)
    elif shape.kind in ("capsule", "cylinder"):
        r, length = size[0], size[1]
        axis = turn[:, 2]
        if shape.kind == "capsule":
            disc = np.full(3, r)
        else:
            disc = r * np.sqrt(np.clip(1 - axis * axis, 0.0, 1.0))
        reach = length / 2 * np.abs(axis) + disc
    else:
        world = (np.asarray(shape.vertices, float).reshape(-1, 3) @ turn.T) + center
        return world.min(axis=0), world.max(axis=0)
    return center - reach, center + reach


def world_of(model: Path, folder: Path, backend: str | None = None) -> tuple[Any, Any]:
    """An engine with ``model`` imported as a scene's Model block imports it; the scene."""
    from app.scene_loading import load_content_scene
    from engine.app import EngineConfig
    from engine.content import resolve
    from systems import create_engine

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "main.scene").write_text(f'Model {{ File "{model.resolve().as_posix()}" }}\n')
    scene = load_content_scene(resolve(folder), allow=[model.resolve().parent])
    config = EngineConfig(content_dir=scene.content.folder, fast=True, headless=True)
    scene.configure(config, backend=backend)
    engine = create_engine(config)
    scene.instantiate(engine)
    return engine, scene


def run(model: Path, folder: Path, seconds: float, backend: str | None = None) -> Trace:
    """Run ``model`` for ``seconds`` of simulated time, recording every body each frame."""
    engine, scene = world_of(model, folder, backend)
    try:
        rows = [(e, n.id, str(p.kind), p) for e, (n, p) in
                engine.world.get_components(Name, Physical)]
        ids = {e: name for e, name, _, _ in rows}
        joints = [(j, ids.get(j.body_a, "?"), None if j.body_b is None else
                   ids.get(j.body_b, "?")) for _, j in engine.world.get_component(Joint)]
        times, pos, quat = [], [], []

        def record() -> None:
            times.append(engine.time)
            pos.append([np.array(engine.world.component_for_entity(e, Transform).position,
                                 float) for e, *_ in rows])
            quat.append([np.array(engine.world.component_for_entity(e, Transform).orientation,
                                  float) for e, *_ in rows])

        record()
        frames = round(seconds / engine.config.dt)
        for _ in range(frames):
            engine.run(frames=1)
            record()
        return Trace([r[1] for r in rows], [r[2] for r in rows], [r[3] for r in rows],
                     np.array(times), np.array(pos), np.array(quat), joints, scene.errors,
                     engine.config.dt)
    finally:
        engine.close()
