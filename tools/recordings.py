"""Recorded input sessions of content folders: what the demo generators share
(tools/hands_demo.py, tools/stroke_demo.py)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from engine.content import REPO_ROOT


def record_session(folder: Path, out: Path, feeder: Callable[[Any, Any], Any],
                   seconds: float, digits: int | None = None,
                   scene_file: str = "main.scene") -> Path:
    """Run ``folder``'s scene unpaced with the input layer recording to ``out`` while the
    system ``feeder(engine, hub)`` returns injects input each frame (a scripted user).
    The devices' clock is the simulated time (to ``digits`` decimals: shorter numbers, a
    smaller file); the header names the scene relative to the repository, not by this
    machine's path. The run ends at ``seconds`` or when the feeder asks it to quit.
    ``scene_file``: which of the folder's scenes (a folder may hold several)."""
    from engine import EngineConfig
    from engine.scene import instantiate, load_spec
    from services.input import InputHub
    from services.input.replay import InputRecorder
    from systems import create_engine

    scene = folder / scene_file
    spec = load_spec(scene)
    config = EngineConfig(content_dir=folder, fast=True, dt=spec.time_step, debug=False,
                          world=spec.world)
    with create_engine(config) as engine:
        engine.add_system(InputRecorder(out))
        instantiate(engine, spec)
        engine.start()
        hub = engine.resource(InputHub)
        hub.clock = (lambda: engine.time) if digits is None else \
            (lambda: round(engine.time, digits))
        engine.add_system(feeder(engine, hub))
        engine.run(seconds=seconds)
    lines = out.read_text().splitlines()
    header = json.loads(lines[0])
    header["scene"] = scene.resolve().relative_to(REPO_ROOT).as_posix()
    out.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    return out
