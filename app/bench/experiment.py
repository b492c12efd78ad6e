"""``colosseum bench experiment``: what an experiment's per-frame tracking log costs.

2,000 bodies (boxes falling onto a floor in a grid, then resting) stepped at 90 Hz in
serial mode, unpaced, headless: the same frames once without a trial running, once with a
trial tracking all 2,000 objects every frame (``TrackRate 0``). Rows: the frame's wall
time in each run, the tracking system's own time per frame (timed about its call), and the
time it took to write the trial's tracking CSV after the trial (not part of any frame).
The goal: the log costs at most 5 % of the frame.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

OBJECTS = 2_000
RATE = 90.0


def _scene(n: int) -> str:
    side = int(n ** 0.5) + 1
    lines = ["World { TimeStep 1/90 }",
             'Object { ID "floor" Position [0 0 0] Dynamic 0 PhysicalAttributes { '
             'Geometry { Primitive "box" Size [200 200 1] } } }']
    for i in range(n):
        x, y = (i % side) * 0.6, (i // side) * 0.6
        lines.append(f'Object {{ ID "b{i}" Position [{x:.2f} {y:.2f} {1 + (i % 7) * 0.1:.2f}] '
                     'PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.3] } } }')
    return "\n".join(lines) + "\n"


def _run(folder: Path, frames: int, track: bool) -> dict[str, Any]:
    from app.scene_loading import load_content_scene
    from engine.app import EngineConfig
    from engine.content import resolve
    from engine.experiments.design import Design, Factor, TrialPlan
    from systems import create_engine
    from systems.experiments import ExperimentPlugin, TrialRunner

    scene = load_content_scene(resolve(str(folder)), seed=0)
    config = EngineConfig(content_dir=folder, fast=True, headless=True, backend="ode")
    scene.configure(config)
    engine = create_engine(config)
    spent = [0.0]
    runner = None
    if track:
        design = Design("bench", (Factor("x", ("1",)),), timeout=1e9,
                        track=tuple(f"b{i}" for i in range(OBJECTS)), track_rate=0.0)

        class Timed(TrialRunner):
            def run(self, engine: Any, dt: float) -> None:
                t0 = time.perf_counter()
                super().run(engine, dt)
                spent[0] += time.perf_counter() - t0

        runner = Timed(design, 1)
        engine.add_plugin(ExperimentPlugin(runner))
    scene.instantiate(engine)
    if runner is not None:
        runner.begin(TrialPlan(1, 1, 1, {"x": "1"}), folder / "trial-001.csv")
    engine.run(frames=10)  # the first frames build the bodies and open the log
    spent[0] = 0.0
    t0 = time.perf_counter()
    engine.run(frames=frames)
    wall = time.perf_counter() - t0
    row: dict[str, Any] = {"case": "tracking 2,000 objects" if track else "no trial",
                           "objects": OBJECTS, "frames": frames,
                           "frame ms": wall / frames * 1e3}
    if runner is not None:
        row["tracking ms/frame"] = spent[0] / frames * 1e3
        runner.finish("done")
        t0 = time.perf_counter()
        engine.step()  # the trial ends: the CSV is written
        row["csv s"] = time.perf_counter() - t0
        row["csv MB"] = (folder / "trial-001.csv").stat().st_size / 1e6
    engine.close()
    return row


def run_bench(quick: bool = False) -> list[dict[str, Any]]:
    frames = 180 if quick else 900
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "bench"
        folder.mkdir()
        (folder / "main.scene").write_text(_scene(OBJECTS), encoding="utf-8")
        rows = []
        for _ in range(2):  # alternated, so a busy moment of the machine falls on both
            rows.append(_run(folder, frames, track=False))
            rows.append(_run(folder, frames, track=True))
    without = min(r["frame ms"] for r in rows if r["case"] == "no trial")
    with_ = min(r["frame ms"] for r in rows if r["case"] != "no trial")
    tracking = min(r["tracking ms/frame"] for r in rows if "tracking ms/frame" in r)
    budget = 1e3 / RATE
    for r in rows:
        if "tracking ms/frame" in r:
            r["share of frame %"] = 100 * r["tracking ms/frame"] / without
            r["share of 90 Hz budget %"] = 100 * r["tracking ms/frame"] / budget
    rows.append({"case": "summary", "objects": OBJECTS, "frames": frames,
                 "frame ms": with_, "without ms": without, "tracking ms/frame": tracking,
                 "share of frame %": 100 * tracking / without,
                 "frame difference %": 100 * (with_ - without) / without,
                 "goal %": 5.0, "ok": "yes" if tracking / without <= 0.05 else "NO"})
    return rows
