"""``colosseum bench import``: a generated glTF of 10,000 nodes, each a KHR body with a box
collider and a mesh: imported to a scene file, and the time from that file to the first
frame; beside them, ``json.loads`` of the file's JSON (reading the data by itself, in C)
and the same first frame from a ``Model { Import 1 }`` block. Goal: each under 2 s.

Each stage runs ``repeats`` times and the fastest is shown, as timeit does, in wall and
CPU seconds; the goal is judged on CPU seconds, which other work on this shared machine
does not stretch (as ``bench scene`` does), with the median of the totals beside it.
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
    from app.bench.interchange_samples import many_bodies

    nodes = 1_000 if quick else 10_000
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        model = many_bodies(folder / "many.glb", nodes)
        (folder / "model.scene").write_text('Model { File "many.glb" }\n')
        runs = [_once(folder, model) for _ in range(1 if quick else repeats)]
    best = {stage: min(r[stage] for r in runs) for stage in runs[0]}
    rows = [{"nodes": nodes, "stage": "json.loads of the glTF's JSON (reference)",
             "wall s": best["json"], "cpu s": best["json cpu"], "MB": runs[0]["bytes"] / 1e6}]
    for total, parts, label in (
            ("import", ("read+import+check", "write scene file"), "import to scene file"),
            ("first", ("load scene file", "engine+instantiate", "first step"),
             "scene file to first frame"),
            ("model", (), "Model { Import 1 } to first frame")):
        for part in parts:
            rows.append({"nodes": nodes, "stage": f"  {part}", "wall s": best[part],
                         "cpu s": best[f"{part} cpu"]})
        cpu = best[f"{total} cpu"]
        rows.append({"nodes": nodes, "stage": label, "wall s": best[total], "cpu s": cpu,
                     f"cpu median of {len(runs)}": statistics.median(r[f"{total} cpu"]
                                                                    for r in runs),
                     "x json": cpu / best["json cpu"], "goal s": GOAL_S,
                     "ok": "yes" if cpu < GOAL_S or nodes != 10_000 else "NO"})
    return [{"kind": KIND, **row} for row in rows]


#: One table: the stages (indented) above their totals, so each total sits under its parts.
KIND = ("a generated glTF: each stage (indented) and its total, wall and CPU s, fastest of "
        "the runs; reference: json.loads of its JSON")


def _once(folder: Path, model: Path) -> dict[str, float]:
    """One pass of every stage, wall and CPU seconds each."""
    from engine.app import EngineConfig
    from engine.assets import Assets
    from engine.interchange import import_model
    from engine.scene import instantiate, load_spec, write
    from systems import create_engine

    out: dict[str, float] = {"bytes": float(model.stat().st_size)}
    data = model.read_bytes()
    size = struct.unpack_from("<I", data, 12)[0]
    _stage(out, "json", lambda: json.loads(data[20:20 + size]))
    scene = folder / "many.scene"
    imported = _stage(out, "read+import+check",
                      lambda: import_model(model.name, model.name, Assets(folder)))
    _stage(out, "write scene file", lambda: scene.write_text(write(imported.db)))
    _total(out, "import", "", ("read+import+check", "write scene file"))

    def _started(spec: Any) -> Any:
        engine = create_engine(EngineConfig(backend="ode", dt=spec.time_step, fast=True,
                                            world=spec.world))
        instantiate(engine, spec)
        return engine

    for path, prefix, total in ((scene, "", "first"), (folder / "model.scene", "model: ",
                                                       "model")):
        spec = _stage(out, f"{prefix}load scene file", lambda p=path: load_spec(p))
        engine = _stage(out, f"{prefix}engine+instantiate", lambda s=spec: _started(s))
        _stage(out, f"{prefix}first step", engine.step)
        engine.close()
        _total(out, total, prefix, ("load scene file", "engine+instantiate", "first step"))
    return out


def _stage(out: dict[str, float], name: str, work: Callable[[], Any]) -> Any:
    """Run ``work``; its wall seconds as ``name``, CPU seconds as ``name cpu``."""
    c0, t0 = time.process_time(), time.perf_counter()
    result = work()
    out[name] = time.perf_counter() - t0
    out[f"{name} cpu"] = time.process_time() - c0
    return result


def _total(out: dict[str, float], name: str, prefix: str, parts: tuple[str, ...]) -> None:
    for suffix in ("", " cpu"):
        out[f"{name}{suffix}"] = sum(out[f"{prefix}{p}{suffix}"] for p in parts)
