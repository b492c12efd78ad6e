"""``colosseum bench stroke``: the stroke simulator's apartment drawn in a window at
1280x720, in real time, serial beside threaded, and where each millisecond of a frame goes.

The content is ``--content DIR`` if given, else content/stroke when it exists, else a
stand-in of comparable size (:mod:`app.bench.stroke_standin`: about 2,000 objects in view, 300
small dynamic bodies, written to a temporary folder). The window is on a virtual X display
(Xvfb, started for the run) when one can be started, else the frames are drawn headless with
EGL (a GPU machine without X); the ``target`` column says which.

Rows, each the median of rounds that alternate between the cases so that load from other
processes touches them alike:

* ``serial`` and ``threaded``: ``colosseum run --mode ...`` paced in real time: frames/s,
  the real-time factor (simulated seconds per wall second), and the breakdown of a frame
  (ms): scene update (the render system syncing the renderer with the world), instance
  upload (world matrices, culling, levels of detail, buffer writes), shadows, draw calls,
  post-processing, present (HUD and buffer swap), physics (serial: its step inside the
  frame; threaded: a step on its own thread) and the rest of the frame (input, scripts,
  controllers, contacts); ``paced_sleep_ms`` is what the real-time controller slept at
  the end of the frame, the time to spare (the goal, real time at 60 frames/s, is met
  when a run keeps its 60 Hz ticks in real time). The breakdown comes from a stretch of
  frames where the renderer waits for the GPU at the end of each stage, so the GPU's work
  lands in its stage; the frames/s are measured without those waits.
* ``serial, everything drawn``: serial with culling, levels of detail and the shadow cache
  off, as the renderer drew before them: the reference for what they buy.
* ``serial, --render-scale 0.75``: serial with the view drawn at three quarters of the
  window's resolution and scaled up (``colosseum run --render-scale``): what trading
  sharpness for frame rate buys on a renderer whose cost is per pixel.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
STROKE = ROOT / "content" / "stroke"
SIZE = (1280, 720)
GOAL_FPS = 60.0
#: Frame stages of the breakdown, as FrameStats fields.
STAGES = ("scene_ms", "upload_ms", "shadow_ms", "draw_ms", "post_ms", "present_ms")
#: case -> (mode, culling/levels of detail/shadow cache on, render scale)
CASES = {"serial": ("serial", True, 1.0), "threaded": ("threaded", True, 1.0),
         "serial, everything drawn": ("serial", False, 1.0),
         "serial, --render-scale 0.75": ("serial", True, 0.75)}


@contextmanager
def virtual_display() -> Iterator[str | None]:
    """An Xvfb display for the run (its name, e.g. ``:7``), or None without Xvfb."""
    if shutil.which("Xvfb") is None:
        yield None
        return
    read, write = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write), "-screen", "0", f"{SIZE[0]}x{SIZE[1]}x24",
         "-nolisten", "tcp"], pass_fds=(write,), stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL)
    os.close(write)
    try:
        with os.fdopen(read) as pipe:
            number = pipe.readline().strip()
        if not number:
            raise RuntimeError("Xvfb did not start")
        yield f":{number}"
    finally:
        server.terminate()
        server.wait(timeout=10)


def content_folder(content: str | Path | None, scratch: Path) -> tuple[Path, str]:
    """The folder benchmarked and what it is."""
    from app.bench.stroke_standin import write_standin

    if content is not None:
        return Path(content), str(content)
    if (STROKE / "main.scene").is_file():
        return STROKE, "content/stroke"
    return write_standin(scratch / "standin"), "stand-in (app/bench/stroke_standin.py)"


def _case(folder: Path, mode: str, fast_paths: bool, scale: float, display: str | None,
          warmup: float, seconds: float, profiled: int) -> dict[str, float]:
    """One run of the content: frames/s and real-time factor over ``seconds`` of wall
    time after ``warmup``, then the breakdown over ``profiled`` frames."""
    from app.scene_loading import load_content_scene
    from engine.app import EngineConfig
    from engine.content import load_systems, resolve
    from systems import create_engine
    from systems.render import RenderSystem

    content = resolve(str(folder))
    scene = load_content_scene(content)
    config = EngineConfig(content_dir=content.folder, mode=mode, headless=display is None,
                          render=True, debug=False,
                          options={"size": f"{SIZE[0]}x{SIZE[1]}"})
    scene.configure(config)
    with create_engine(config) as engine:
        load_systems(engine, content.folder)
        scene.instantiate(engine)
        engine.start()
        renderer = engine.resource(RenderSystem).renderer
        assert renderer is not None
        renderer.culling = renderer.lod = renderer.shadow_cache = fast_paths
        renderer.render_scale = scale
        _run_for(engine, warmup)
        frames, sim, t0 = engine.frame, engine.physics.time, time.perf_counter()
        _run_for(engine, seconds)
        wall = time.perf_counter() - t0
        out = {"fps": (engine.frame - frames) / wall,
               "real_time_factor": (engine.physics.time - sim) / wall}
        renderer.profile = True
        totals = dict.fromkeys(("frame_ms", *STAGES, "physics_ms"), 0.0)
        counts = {"instances": 0.0, "culled": 0.0, "draw_calls": 0.0}
        steps = engine.physics.controller.step_costs
        slept = engine.controller.slept
        for _ in range(profiled):
            t = time.perf_counter()
            engine.step()
            totals["frame_ms"] += (time.perf_counter() - t) * 1e3
            stats = renderer.stats
            for stage in STAGES:
                totals[stage] += getattr(stats, stage)
            totals["physics_ms"] += (engine.physics_seconds * 1e3 if mode == "serial"
                                     else steps.mean() * 1e3)
            for key in counts:
                counts[key] += getattr(stats, key)
        out.update({k: v / profiled for k, v in totals.items()})
        out["paced_sleep_ms"] = (engine.controller.slept - slept) / profiled * 1e3
        out["other_ms"] = out["frame_ms"] - sum(out[s] for s in STAGES) - (
            out["physics_ms"] if mode == "serial" else 0.0) - out["paced_sleep_ms"]
        out.update({k: v / profiled for k, v in counts.items()})
        out["target"] = "window (Xvfb)" if display is not None else "headless EGL"
        out["gl_renderer"] = renderer.target.renderer_name
    return out


def holds_real_time(row: dict[str, Any]) -> bool:
    """The goal: real time at 60 frames/s. A paced run draws a frame a tick (content/stroke's
    TimeStep is 1/60 s) and sleeps what is left of it, so it shows at most 60 frames/s: the
    goal is met when it keeps that rate in real time (both within 1 %)."""
    return row["fps"] >= 0.99 * GOAL_FPS and row["real_time_factor"] >= 0.99


def _run_for(engine: Any, seconds: float) -> None:
    end = time.perf_counter() + seconds
    engine.run(until=lambda e: time.perf_counter() >= end)


def _case_in_process(folder: Path, case: str, display: str | None, timing: tuple[float, ...]
                     ) -> dict[str, Any]:
    """:func:`_case` in a process of its own (as ``colosseum run`` is: a window's GL and
    a headless EGL context do not mix in one process)."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY",
                                                             "PYOPENGL_PLATFORM")}
    if display is not None:
        env["DISPLAY"] = display
    done = subprocess.run([sys.executable, "-m", "app.bench.stroke", str(folder), case,
                           *map(str, timing)], capture_output=True, text=True, env=env,
                          cwd=ROOT, timeout=600)
    if done.returncode != 0:
        raise RuntimeError(f"bench stroke, case {case!r} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def run_bench(quick: bool = False, content: str | Path | None = None) -> list[dict[str, Any]]:
    """Frames/s, real-time factor and a frame's breakdown, per case (see the module doc)."""
    rounds, timing = (1, (0.5, 1.0, 10)) if quick else (3, (2.0, 5.0, 30))
    with tempfile.TemporaryDirectory() as scratch, virtual_display() as display:
        folder, what = content_folder(content, Path(scratch))
        results: dict[str, list[dict[str, Any]]] = {case: [] for case in CASES}
        for _ in range(rounds):
            for case in CASES:
                results[case].append(_case_in_process(folder, case, display, timing))
    rows = []
    for case, runs in results.items():
        row: dict[str, Any] = {"case": case}
        for key, value in runs[0].items():
            row[key] = statistics.median(r[key] for r in runs) if isinstance(
                value, float) else value
        rows.append({**row, "content": what, "size": f"{SIZE[0]}x{SIZE[1]}",
                     "rounds": len(runs)})
    serial, threaded = rows[0], rows[1]
    threaded["threaded/serial fps"] = threaded["fps"] / serial["fps"]
    for row in (serial, threaded, rows[3]):
        row["goal 60 fps met"] = holds_real_time(row)
    threaded["goal 1.5x met"] = threaded["threaded/serial fps"] >= 1.5
    return rows


if __name__ == "__main__":  # one case, in its own process: folder case warmup seconds frames
    mode_of, fast_of, scale_of = CASES[sys.argv[2]]
    print(json.dumps(_case(Path(sys.argv[1]), mode_of, fast_of, scale_of,
                           os.environ.get("DISPLAY"), float(sys.argv[3]), float(sys.argv[4]),
                           int(sys.argv[5]))))
