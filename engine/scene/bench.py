"""``colosseum bench scene``: parse and instantiate a generated file of many objects."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from engine.scene.factory import build_specs, instantiate
from engine.scene.loader import load_scene


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
    """Seconds to parse (+ validate), build specs and instantiate ``n`` objects.

    ``*_s`` are wall seconds; ``cpu_s`` is this process's CPU time for all three
    (steadier than wall time on a busy machine).
    """
    from engine.app import Engine, EngineConfig

    text = generate_scene(n)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "main.scene"
        path.write_text(text, encoding="utf-8")
        c0, t0 = time.process_time(), time.perf_counter()
        db = load_scene(path, np.random.default_rng(0))
        t1 = time.perf_counter()
        spec = build_specs(db, tmp)
        t2, c1 = time.perf_counter(), time.process_time()
        with Engine(EngineConfig(backend="ballistic", fast=True), plugins=()) as engine:
            c2, t3 = time.process_time(), time.perf_counter()
            ids = instantiate(engine, spec)
            t4, c3 = time.perf_counter(), time.process_time()
    return {"objects": n, "entities": len(ids), "file_bytes": len(text.encode("utf-8")),
            "parse_s": t1 - t0, "build_specs_s": t2 - t1, "instantiate_s": t4 - t3,
            "total_s": (t1 - t0) + (t2 - t1) + (t4 - t3), "cpu_s": (c1 - c0) + (c3 - c2)}
