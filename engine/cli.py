"""colosseum: run, check, format, scaffold and benchmark content folders.

Exit codes: 0 success, 1 errors in the content (or a system that raised),
2 usage errors (unknown flags, missing paths).
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
import traceback
from pathlib import Path
from typing import Any

from engine.input.config import input_option
from engine.physics.backend import BackendName

log = logging.getLogger("colosseum")

USAGE_ERROR = 2


def _positive(kind: type) -> Any:
    def parse(text: str) -> Any:
        value = kind(text)
        if value <= 0:
            raise argparse.ArgumentTypeError(f"must be positive, got {text}")
        return value

    return parse


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="colosseum", description=__doc__.splitlines()[0])
    parser.add_argument("--log-level", default="info",
                        choices=["debug", "info", "warning", "error"],
                        help="how much to log (default: info)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    run = sub.add_parser("run", help="run a content folder (default: the bundled demo)")
    run.add_argument("path", nargs="?", help="content folder or .scene file")
    limit = run.add_mutually_exclusive_group()
    limit.add_argument("--seconds", type=_positive(float), help="simulated seconds to run")
    limit.add_argument("--frames", type=_positive(int), help="frames to run")
    run.add_argument("--headless", action="store_true",
                     help="no window (automatic without a display)")
    run.add_argument("--backend", choices=list(BackendName), default=None,
                     help="dynamics backend (default: the scene's, else ode)")
    run.add_argument("--mode", choices=["serial", "threaded"], default="serial",
                     help="serial: everything on the main thread; threaded: physics on its own")
    run.add_argument("--fast", action="store_true",
                     help="run as fast as possible, not in real time")
    run.add_argument("--seed", type=int, default=0, help="seed for the scene's random functions")
    run.add_argument("--dt", type=_positive(float), default=None, help="physics time step (s)")
    run.add_argument("--substeps", type=_positive(int), default=1, help="physics steps per frame")
    run.add_argument("--early", choices=["sleep", "substep"], default="sleep",
                     help="when a step finishes early: sleep, or take smaller substeps")
    run.add_argument("--late", choices=["slowmo", "grow"], default="slowmo",
                     help="when steps run late: slow motion, or grow the step (bounded)")
    run.add_argument("--max-dt", type=_positive(float), default=1.0 / 20.0,
                     help="upper bound for --late grow (s)")
    run.add_argument("--sound", default="null", help="audio backend: openal, wave:FILE or null")
    run.add_argument("--screenshot", type=Path, help="write the last frame to FILE.png")
    run.add_argument("--record-frames", type=Path, help="write every Nth frame into DIR")
    run.add_argument("--record-every", type=_positive(int), default=1, help="N for --record-frames")
    run.add_argument("--interpolate", action="store_true",
                     help="threaded mode: interpolate poses between physics states when drawing")
    run.add_argument("--hud", action="store_true", help="show the HUD line (fps, physics ms, rtf)")
    run.add_argument("--size", default="640x480", help="window/render size WxH")
    run.add_argument("--save-state", type=Path, help="write the final state as a scene file")
    run.add_argument("--stats", type=Path, help="write run statistics as JSON")
    run.add_argument("--record", type=Path, help="record input events to FILE (JSON lines)")
    run.add_argument("--replay", type=Path, help="replay input events recorded with --record")
    run.add_argument("--input", action="append", default=[], type=input_option,
                     metavar="KIND[:ARG]", help="open an input device: osc:PORT, "
                     "serial:PATH[@BAUD], lsl:STREAM[,...], desktop or openxr (repeatable)")
    run.add_argument("--progress", action="store_true",
                     help="print a status line every second, also into a log or pipe (on a "
                          "terminal: a progress bar when the run has --frames or --seconds)")
    run.add_argument("--watch", action="store_true",
                     help="start again from the files when the scene or a model, image or "
                          "sound it uses changes on disk")

    check = sub.add_parser("check", help="validate a content folder or scene file",
                           epilog="exit codes: 0 no errors (warnings allowed), 1 errors, "
                                  "2 no such file or folder or a usage error")
    check.add_argument("path")
    check.add_argument("--format", choices=["text", "json"], default="text",
                       help="text: path:line:col lines on stderr (default); json: one "
                            "object on stdout for editors and CI")
    fmt = sub.add_parser("fmt", help="print a scene file in canonical form")
    fmt.add_argument("path")
    fmt.add_argument("--write", action="store_true",
                     help="rewrite the file in place (keeps a .bak)")

    imp = sub.add_parser("import", help="a scene file from a glTF or Collada model's bodies, "
                                        "joints, materials and extras")
    imp.add_argument("model", type=Path, help=".gltf, .glb or .dae file")
    imp.add_argument("-o", "--output", type=Path,
                     help="scene file to write (merged with your edits if it exists; "
                          "default: print)")
    imp.add_argument("--force", action="store_true",
                     help="replace an existing scene file no import wrote (keeps a .bak)")

    export = sub.add_parser("export", help="a scene (or saved state) as glTF with physics "
                                           "extensions, for Blender or Godot")
    export.add_argument("scene", type=Path, help="content folder or .scene file")
    export.add_argument("-o", "--output", type=Path, required=True, help="OUT.glb or .gltf")

    keys = sub.add_parser("keys", help="the scene keys: every block, or one block's keys with "
                          "type, default, meaning and an example")
    keys.add_argument("block", nargs="?", help="a block (Object, Camera, World, ...)")

    new = sub.add_parser("new", help="scaffold a content folder that runs")
    new.add_argument("name")

    bench = sub.add_parser("bench", help="benchmarks, printed as tables")
    bench.add_argument("what", nargs="?", default="scheduler",
                       help="scheduler, physics, scene, scripting, sound, render, input, "
                            "contacts, avatars, import")
    bench.add_argument("--backend", default=None, help="physics benchmark backend (ode, pymunk)")
    bench.add_argument("--quick", action="store_true", help="fewer sizes and steps")
    bench.add_argument("--json", nargs="?", const="-", metavar="FILE",
                       help="the rows and figures as JSON: to FILE, or alone on stdout")
    bench.add_argument("--plot", type=Path, metavar="FILE.png",
                       help="our figures beside their references as a bar chart")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=getattr(logging, args.log_level.upper()),
                        format="%(levelname)s %(name)s: %(message)s")
    handler = COMMANDS[args.command]
    try:
        return handler(args)
    except KeyboardInterrupt:
        print("colosseum: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `colosseum keys | head`: the reader left, nothing to tell
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


def _fail(message: str, code: int = USAGE_ERROR) -> int:
    print(f"colosseum: error: {message}", file=sys.stderr)
    return code


def cmd_run(args: argparse.Namespace) -> int:
    from engine.app import EngineConfig
    from engine.content import ContentError, load_systems, resolve
    from engine.input import InputRecorder, InputReplayer, ReplayError
    from engine.physics import BackendUnavailable
    from engine.scene_loading import SceneLoadError, load_content_scene
    from engine.stats import collect, sections, status_line, write_json
    from engine.system import SystemFailure
    from systems import create_engine

    try:
        content = resolve(args.path)
    except ContentError as exc:
        return _fail(str(exc))
    if args.replay is not None and not args.replay.is_file():
        return _fail(f"{args.replay}: no such recording")
    for out in (args.stats, args.save_state, args.screenshot, args.record):
        if out is not None and not out.parent.exists():
            return _fail(f"{out}: folder {out.parent} does not exist")
    headless = args.headless or not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    try:
        scene = load_content_scene(content, seed=args.seed)
    except SceneLoadError as exc:
        print(exc, file=sys.stderr)
        return 1
    content = scene.content  # a saved state runs in the content folder it names
    config = EngineConfig(
        content_dir=content.folder, mode=args.mode, seed=args.seed, fast=args.fast,
        substeps=args.substeps, early=args.early, late=args.late, max_dt=args.max_dt,
        headless=headless, sound=args.sound,
        options={"screenshot": args.screenshot, "record_frames": args.record_frames,
                 "record_every": args.record_every, "interpolate": args.interpolate,
                 "hud": args.hud, "size": args.size, "input": args.input},
    )
    scene.configure(config, backend=args.backend, dt=args.dt)
    if args.watch:
        return _run_watching(args, content, config, scene)
    try:
        engine = create_engine(config)
    except BackendUnavailable as exc:
        return _fail(str(exc), 1)
    try:
        if args.replay is not None:
            engine.add_system(InputReplayer(args.replay))
        if args.record is not None:
            engine.add_system(InputRecorder(args.record))
        load_systems(engine, content.folder)
        scene.instantiate(engine)
        progress = args.progress or sys.stderr.isatty()
        _run_limited(engine, args, progress, status_line)
        if args.save_state is not None:
            from engine.scene_loading import save_state

            save_state(engine, args.save_state)
        stats = collect(engine)  # before close(), which empties the world
    except (ContentError, ReplayError) as exc:
        engine.close()
        return _fail(str(exc), 1)
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


def _run_watching(args: argparse.Namespace, content: Any, config: Any, scene: Any) -> int:
    """``run --watch``: run the scene; when a file it came from changes, load it again and
    start over from the new files (a scene with errors is told and the old one runs on).
    Frames and seconds count across the restarts."""
    from engine.content import ContentError, load_systems
    from engine.scene_loading import SceneLoadError, SceneWatcher, load_content_scene
    from engine.system import SystemFailure
    from systems import create_engine

    frames, seconds = args.frames, args.seconds
    while True:
        watcher = SceneWatcher(scene.spec)
        engine = create_engine(config)
        try:
            load_systems(engine, content.folder)
            scene.instantiate(engine)
            engine.run(frames=frames, seconds=seconds, until=watcher.poll)
        except (ContentError, SystemFailure) as exc:
            engine.close()
            return _fail(str(exc), 1)
        engine.close()
        if frames is not None:
            frames -= engine.frame
        if seconds is not None:
            seconds -= engine.time
        if not watcher.changed() or (frames is not None and frames <= 0) or (
                seconds is not None and seconds <= 1e-9):
            return 0
        names = ", ".join(sorted(p.name for p in watcher.changed()))
        try:
            scene = load_content_scene(content, seed=args.seed)
        except SceneLoadError as exc:
            print(f"{exc}\ncolosseum: {names} changed but has errors; running the last "
                  f"good scene", file=sys.stderr)
            continue
        print(f"colosseum: {names} changed; starting again", file=sys.stderr)
        scene.configure(config, backend=args.backend, dt=args.dt)


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


def cmd_check(args: argparse.Namespace) -> int:
    from engine.scene_loading import check_path

    return check_path(Path(args.path), args.format)


def cmd_fmt(args: argparse.Namespace) -> int:
    from engine.scene_loading import format_path

    return format_path(Path(args.path), write=args.write)


def cmd_import(args: argparse.Namespace) -> int:
    from engine.scene_loading import import_path

    return import_path(args.model, args.output, force=args.force)


def cmd_export(args: argparse.Namespace) -> int:
    from engine.scene_loading import export_path

    return export_path(args.scene, args.output)


def cmd_keys(args: argparse.Namespace) -> int:
    from engine.scene import keys

    if args.block is None:
        for block in keys.blocks():
            print(f"{block:<15} {keys.about(block)}")
        print("\ncolosseum keys BLOCK lists a block's keys; docs/KEYS.md has them all")
        return 0
    block = keys.find_block(args.block)
    if block is None:
        return _fail(f"no block {args.block!r}{keys.suggest(args.block)} "
                     f"(blocks: {', '.join(keys.blocks())})")
    print(keys.block_text(block))
    return 0


def cmd_new(args: argparse.Namespace) -> int:
    from engine.scaffold import ScaffoldError, scaffold

    try:
        folder = scaffold(Path(args.name))
    except ScaffoldError as exc:
        return _fail(str(exc))
    print(f"created {folder}; run it with: colosseum run {folder}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from tools.bench import BENCHMARKS, run_benchmark

    if args.what not in BENCHMARKS:
        return _fail(f"unknown benchmark {args.what!r}; choose from {', '.join(BENCHMARKS)}")
    for out in (None if args.json in (None, "-") else Path(args.json), args.plot):
        if out is not None and not out.parent.exists():
            return _fail(f"{out}: folder {out.parent} does not exist")
    return run_benchmark(args.what, backend=args.backend, quick=args.quick,
                         json_out=args.json, plot_out=args.plot)


COMMANDS = {
    "run": cmd_run,
    "check": cmd_check,
    "fmt": cmd_fmt,
    "import": cmd_import,
    "export": cmd_export,
    "keys": cmd_keys,
    "new": cmd_new,
    "bench": cmd_bench,
}


if __name__ == "__main__":
    sys.exit(main())
