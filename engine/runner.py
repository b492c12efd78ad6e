"""Running a scene to the limits a command line sets: what ``run``, ``serve`` and ``join``
share (their flags, loading, the run loop with its progress, saving, statistics)."""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
import traceback
from typing import Any

log = logging.getLogger("colosseum")

USAGE_ERROR = 2


def fail(message: str, code: int = USAGE_ERROR) -> int:
    print(f"colosseum: error: {message}", file=sys.stderr)
    return code


def prepare_run(args: argparse.Namespace) -> Any:
    """The scene and engine configuration a run's flags ask for, or an exit code (the
    problem told). ``run`` and ``serve`` share it."""
    from engine.app import EngineConfig
    from engine.content import ContentError, resolve
    from engine.scene_loading import SceneLoadError, load_content_scene

    try:
        content = resolve(args.path)
    except ContentError as exc:
        return fail(str(exc))
    if getattr(args, "replay", None) is not None and not args.replay.is_file():
        return fail(f"{args.replay}: no such recording")
    problem = outputs_problem(args)
    if problem is not None:
        return fail(problem)
    headless = getattr(args, "headless", True) or not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    try:
        scene = load_content_scene(content, seed=args.seed,
                                   params=dict(getattr(args, "param", None) or ()))
    except SceneLoadError as exc:
        print(exc, file=sys.stderr)
        return 1
    content = scene.content  # a saved state runs in the content folder it names
    config = EngineConfig(
        content_dir=content.folder, mode=args.mode, seed=args.seed, fast=args.fast,
        substeps=args.substeps, early=args.early, late=args.late, max_dt=args.max_dt,
        headless=headless, sound=args.sound,
        options={"screenshot": getattr(args, "screenshot", None),
                 "record_frames": getattr(args, "record_frames", None),
                 "record_every": getattr(args, "record_every", 1),
                 "interpolate": getattr(args, "interpolate", False),
                 "hud": getattr(args, "hud", False), "size": getattr(args, "size", "640x480"),
                 "input": args.input},
    )
    scene.configure(config, backend=args.backend, dt=args.dt)
    return scene, config


def outputs_problem(args: argparse.Namespace) -> str | None:
    """What is wrong with the files a run is asked to write (a folder that is not there)."""
    for name in ("stats", "save_state", "screenshot", "record"):
        out = getattr(args, name, None)
        if out is not None and not out.parent.exists():
            return f"{out}: folder {out.parent} does not exist"
    return None


def execute_run(engine: Any, args: argparse.Namespace, scene: Any,
                custom_systems: bool = True, before_save: Any = None) -> int:
    """Load the scene into ``engine``, run it to the flags' limit, save and report; the
    exit code. ``custom_systems``: build the content's systems/*.py; ``before_save(engine)``
    runs before the state is written (a node stamps the server's time)."""
    from engine.content import ContentError
    from engine.input import InputRecorder, InputReplayer, ReplayError
    from engine.stats import collect, sections, status_line, write_json
    from engine.system import SystemFailure

    try:
        if getattr(args, "replay", None) is not None:
            engine.add_system(InputReplayer(args.replay))
        if getattr(args, "record", None) is not None:
            engine.add_system(InputRecorder(args.record))
        if custom_systems:
            from engine.content import load_systems

            load_systems(engine, scene.content.folder)
        scene.instantiate(engine)
        progress = args.progress or sys.stderr.isatty()
        _run_limited(engine, args, progress, status_line)
        if args.save_state is not None:
            from engine.scene_loading import save_state

            if before_save is not None:
                before_save(engine)
            save_state(engine, args.save_state)
        stats = collect(engine)  # before close(), which empties the world
    except (ContentError, ReplayError) as exc:
        engine.close()
        return fail(str(exc), 1)
    except SystemFailure as exc:
        engine.close()
        trace = "".join(traceback.format_exception(exc.original))
        print(f"colosseum: error: system {exc.system_name!r} raised; the run stopped.\n{trace}",
              file=sys.stderr)
        return 1
    except BaseException:
        engine.close()
        raise
    engine.close()
    stats.update(sections(engine))  # what shutting down did (the --screenshot frame)
    if args.stats is not None:
        write_json(args.stats, stats)
    log.info("ran %d frames, %.2f simulated s in %.2f wall s (real-time factor %.2f)",
             stats["frames"], stats["sim_seconds"], stats["wall_seconds"],
             stats["real_time_factor"])
    return 0


def _short_status(engine: Any) -> str:
    """What fits beside a progress bar: simulated time and real-time factor."""
    return f"t={engine.time:.2f} s  rtf {engine.real_time_factor:.2f}"


def _run_limited(engine: Any, args: argparse.Namespace, progress: bool, status_line: Any) -> None:
    """Run to the requested limit. On a terminal, a run with a limit shows a progress bar;
    otherwise ``progress`` prints the status line every second
    (``--progress``: also into a log or a pipe)."""
    from engine.progress import on_terminal
    from engine.progress import progress as progress_bar

    limited = args.frames is not None or args.seconds is not None
    if on_terminal() and limited:
        total = args.frames if args.frames is not None else args.seconds
        start_frame, start_time = engine.frame, engine.time
        last = [0.0]
        with progress_bar("running", total) as report:
            def tick(eng: Any) -> bool:
                now = time.monotonic()
                if now - last[0] >= 0.1:
                    last[0] = now
                    done = eng.frame - start_frame if args.frames is not None \
                        else eng.time - start_time
                    report(done, _short_status(eng))
                return False

            engine.run(frames=args.frames, seconds=args.seconds, until=tick)
            report(total, _short_status(engine))
        return
    last = [time.monotonic()]

    def line(eng: Any) -> bool:
        now = time.monotonic()
        if progress and now - last[0] >= 1.0:
            last[0] = now
            print("\r" + status_line(eng), end="", file=sys.stderr, flush=True)
        return False

    engine.run(frames=args.frames, seconds=args.seconds, until=line)
    if progress:
        print(file=sys.stderr)


