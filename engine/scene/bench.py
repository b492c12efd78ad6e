"""``colosseum bench scene``: parse and instantiate a generated file of many objects."""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np

from engine.scene.factory import build_specs, instantiate
from engine.scene.loader import validated
from engine.scene.parser import parse_file

T = TypeVar("T")


def generate_scene(n: int) -> str:
    """A scene of ``n`` physical, visible objects with a few expressions and a material."""
    parts = ['Material { ID "rubber" Friction 0.9 Bounce 0.5 }\n',
             "spacing 1.5\n",
             "World { Gravity [0 0 -9.81] TimeStep 0.01 }\n"]
    prims = ("sphere", "box", "capsule")
    sizes = ("[0.5]", "[0.4 0.4 0.4]", "[0.3 0.6]")
    for i in range(n):
        k = i % 3
        parts.append(
            f'Object {{\n  ID "body{i}"\n'
            f"  Position [{i % 100}*spacing {i // 100 % 100}*spacing {1 + i // 10000}]\n"
            f"  Orientation [0 0 {i % 360}]\n"
            f"  Size {sizes[k]}\n"
            f'  VisualAttributes {{ Geometry {{ Primitive "{prims[k]}" }} }}\n'
            f"  PhysicalAttributes {{\n    Mass 1.5\n    Material \"rubber\"\n"
            f'    Geometry {{ Primitive "{prims[k]}" }}\n  }}\n}}\n')
    return "".join(parts)


def bench_scene(n: int = 10000) -> dict[str, float]:
    """Seconds to parse, validate, build specs and instantiate ``n`` objects.

    ``*_s`` are wall seconds per stage; ``*_cpu_s`` this process's CPU seconds
    (steadier than wall time on a busy machine); ``parse_s`` includes reading the file.
    """
    from engine.app import Engine, EngineConfig

    text = generate_scene(n)
    times: dict[str, float] = {}

    def timed(stage: str, run: Callable[[], T]) -> T:
        c0, t0 = time.process_time(), time.perf_counter()
        result = run()
        times[f"{stage}_s"] = time.perf_counter() - t0
        times[f"{stage}_cpu_s"] = time.process_time() - c0
        return result

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "main.scene"
        path.write_text(text, encoding="utf-8")
        parsed = timed("parse", lambda: parse_file(path, np.random.default_rng(0)))
        db = timed("validate", lambda: validated(parsed))
        spec = timed("build_specs", lambda: build_specs(db, tmp))
        with Engine(EngineConfig(backend="ballistic", fast=True), plugins=()) as engine:
            ids = timed("instantiate", lambda: instantiate(engine, spec))
    stages = ("parse", "validate", "build_specs", "instantiate")
    return {"objects": n, "entities": len(ids), "file_bytes": len(text.encode("utf-8")),
            **times, "total_s": sum(times[f"{s}_s"] for s in stages),
            "cpu_s": sum(times[f"{s}_cpu_s"] for s in stages)}
