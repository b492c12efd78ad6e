"""``colosseum bench import``: a generated glTF of 10,000 nodes, each a KHR body with a box
collider and a mesh: imported to a scene file, and the time from that file to the first
frame; beside them, ``json.loads`` of the file's JSON (reading the data by itself, in C)
and the same first frame from a ``Model { Import 1 }`` block. Goal: each under 2 s.

Each stage runs ``repeats`` times and the fastest is shown, as timeit does (this shared
machine's speed swings); the median of the totals beside it.
"""

from __future__ import annotations

import json
import statistics
import struct
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

GOAL_S = 2.0


def run_bench(quick: bool = False, repeats: int = 3) -> list[dict[str, Any]]:
    from tools.interchange_samples import many_bodies

    nodes = 1_000 if quick else 10_000
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        model = many_bodies(folder / "many.glb", nodes)
        (folder / "model.scene").write_text('Model { File "many.glb" }\n')
        runs = [_once(folder, model) for _ in range(1 if quick else repeats)]
    best = {stage: min(r[stage] for r in runs) for stage in runs[0]}
    rows = [{"nodes": nodes, "stage": "json.loads of the glTF's JSON (reference)",
             "s": best["json"], "MB": runs[0]["bytes"] / 1e6}]
    for total, parts, label in (
            ("import", ("read+import+check", "write scene file"), "import to scene file"),
            ("first", ("load scene file", "engine+instantiate", "first step"),
             "scene file to first frame"),
            ("model", (), "Model { Import 1 } to first frame")):
        for part in parts:
            rows.append({"nodes": nodes, "stage": f"  {part}", "s": best[part]})
        rows.append({"nodes": nodes, "stage": label, "s": best[total],
                     f"median of {len(runs)}": statistics.median(r[total] for r in runs),
                     "x json": best[total] / best["json"], "goal s": GOAL_S,
                     "ok": "yes" if best[total] < GOAL_S or nodes != 10_000 else "NO"})
    return rows


def _once(folder: Path, model: Path) -> dict[str, float]:
    """One pass of every stage, wall seconds each."""
    from engine.app import EngineConfig
    from engine.assets import Assets
    from engine.interchange import import_model
    from engine.scene import instantiate, load_spec, write
    from systems import create_engine

    out: dict[str, float] = {"bytes": float(model.stat().st_size)}
    data = model.read_bytes()
    size = struct.unpack_from("<I", data, 12)[0]
    out["json"] = _timed(lambda: json.loads(data[20:20 + size]))
    scene = folder / "many.scene"
    imported = _stage(out, "read+import+check",
                      lambda: import_model(model.name, model.name, Assets(folder)))
    _stage(out, "write scene file", lambda: scene.write_text(write(imported.db)))
    out["import"] = out["read+import+check"] + out["write scene file"]

    def first_frame(path: Path, prefix: str) -> float:
        spec = _stage(out, f"{prefix}load scene file", lambda: load_spec(path))
        engine = _stage(out, f"{prefix}engine+instantiate", lambda: _started(spec))
        _stage(out, f"{prefix}first step", engine.step)
        engine.close()
        return sum(out[f"{prefix}{k}"] for k in ("load scene file", "engine+instantiate",
                                                 "first step"))

    def _started(spec: Any) -> Any:
        engine = create_engine(EngineConfig(backend="ode", dt=spec.time_step, fast=True,
                                            world=spec.world))
        instantiate(engine, spec)
        return engine

    out["first"] = first_frame(scene, "")
    out["model"] = first_frame(folder / "model.scene", "model: ")
    return out


def _timed(work: Callable[[], Any]) -> float:
    t0 = time.perf_counter()
    work()
    return time.perf_counter() - t0


def _stage(out: dict[str, float], name: str, work: Callable[[], Any]) -> Any:
    t0 = time.perf_counter()
    result = work()
    out[name] = time.perf_counter() - t0
    return result
