"""``colosseum bench WHAT``: benchmarks printed as tables, each beside a reference.

Every benchmark measures our path and a reference in the same run and reports
the ratio, so the numbers mean something on any machine.
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable
from typing import Any

from systems import create_engine

#: name -> "module:function"; each function takes (quick, backend) and returns table rows.
BENCHMARKS: dict[str, str] = {
    "scheduler": "tools.bench:bench_scheduler",
    "physics": "tools.bench_physics:run_bench",
    "scene": "tools.bench:bench_scene",
    "scripting": "tools.bench_scripting:run_bench",
    "sound": "tools.bench_sound:run_bench",
    "render": "tools.bench_render:run_bench",
    "import": "tools.bench_import:run_bench",
}


def print_table(rows: list[dict[str, Any]]) -> None:
    if not rows:
        return
    columns = list(rows[0])
    for row in rows[1:]:
        columns += [c for c in row if c not in columns]
    cells = [[_fmt(row.get(c, "")) for c in columns] for row in rows]
    widths = [max(len(c), *(len(r[i]) for r in cells)) for i, c in enumerate(columns)]
    print("  ".join(c.rjust(w) for c, w in zip(columns, widths, strict=True)))
    print("  ".join("-" * w for w in widths))
    for r in cells:
        print("  ".join(v.rjust(w) for v, w in zip(r, widths, strict=True)))


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def run_benchmark(what: str, backend: str | None = None, quick: bool = False) -> int:
    module_name, func_name = BENCHMARKS[what].split(":")
    func: Callable[..., list[dict[str, Any]]] = getattr(importlib.import_module(module_name),
                                                        func_name)
    kwargs: dict[str, Any] = {}
    if backend is not None:
        kwargs["backend"] = backend
    if quick:
        kwargs["quick"] = True
    rows = func(**kwargs)
    print(f"\ncolosseum bench {what}")
    print_table(rows)
    return 0


def bench_scheduler(quick: bool = False) -> list[dict[str, Any]]:
    """Engine overhead per frame: no bodies, ten trivial systems; reference: a bare loop."""
    from engine import EngineConfig, Phase, system

    frames = 2_000 if quick else 20_000
    phases = list(Phase)
    counter = [0]

    def trivial(engine: Any, dt: float) -> None:
        counter[0] += 1

    functions = [trivial] * 10
    t0 = time.perf_counter()
    for _ in range(frames):
        for fn in functions:
            fn(None, 0.016)
    bare_ms = (time.perf_counter() - t0) / frames * 1e3

    rows = []
    for mode in ("serial", "threaded"):
        with create_engine(EngineConfig(backend="ballistic", mode=mode, fast=True)) as eng:
            for i in range(10):
                eng.add_system(system(phases[i % len(phases)])(trivial))
            eng.run(frames=100)
            t0 = time.perf_counter()
            eng.run(frames=frames)
            ms = (time.perf_counter() - t0) / frames * 1e3
        rows.append({"mode": mode, "systems": 10, "frames": frames, "ms/frame": ms,
                     "bare loop ms": bare_ms, "overhead ms": ms - bare_ms,
                     "target ms": 0.2, "ok": "yes" if ms < 0.2 else "NO"})
    return rows


def bench_scene(quick: bool = False, repeats: int = 3) -> list[dict[str, Any]]:
    """Parse, validate, build and instantiate a generated file of 10,000 objects; reference:
    json.loads (a C parser) of the same objects as JSON (a list of dicts with the same keys
    and values), timed in the same run, to show what reading the data costs by itself.

    Both are run ``repeats`` times and the fastest run is shown, as timeit does (this
    machine's speed swings from minute to minute); the total's median is shown beside it.
    """
    import json
    import statistics

    import numpy as np

    from engine.scene import bench_scene as run
    from engine.scene import generate_scene, parse_text

    n = 1_000 if quick else 10_000
    runs = [run(n) for _ in range(1 if quick else repeats)]
    r = min(runs, key=lambda x: x["cpu_s"])
    median = statistics.median(x["cpu_s"] for x in runs)
    db = parse_text(generate_scene(n), rng=np.random.default_rng(0))
    as_json = json.dumps([_plain_dict(b) for b in db.blocks("Object")])
    json_s = json_cpu_s = float("inf")
    for _ in range(len(runs)):
        c0, t0 = time.process_time(), time.perf_counter()
        json.loads(as_json)
        json_s = min(json_s, time.perf_counter() - t0)
        json_cpu_s = min(json_cpu_s, time.process_time() - c0)
    target = 1.0 if n == 10_000 else 0.1
    return [{"objects": n, "file MB": r["file_bytes"] / 1e6, "stage": stage,
             "wall s": r[f"{key}_s"], "cpu s": r[f"{key}_cpu_s"]}
            for stage, key in (("parse (read+lex+parse)", "parse"), ("validate", "validate"),
                               ("build specs", "build_specs"), ("instantiate", "instantiate"))
            ] + [{"objects": n, "file MB": r["file_bytes"] / 1e6, "stage": "total",
                  "wall s": r["total_s"], "cpu s": r["cpu_s"], "target s": target,
                  "ok": "yes" if r["cpu_s"] < target else "NO",
                  f"median of {len(runs)}": median},
                 {"objects": n, "file MB": len(as_json) / 1e6, "stage": "json.loads (reference)",
                  "wall s": json_s, "cpu s": json_cpu_s,
                  "total/json": r["cpu_s"] / json_cpu_s if json_cpu_s else float("inf")}]


def _plain_dict(block: Any) -> dict[str, Any]:
    """A scene block as plain JSON-able data: STRUCTUREs as dicts, vectors as lists."""
    return {e.key: _plain_dict(e.value.data) if e.value.kind == "STRUCTURE" else e.value.py()
            for e in block}
