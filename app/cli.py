"""colosseum: run, check, format, scaffold and benchmark content folders.

Exit codes: 0 success, 1 errors in the content (or a system that raised),
2 usage errors (unknown flags, missing paths).
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path
from typing import Any

from app.runner import execute_run, fail, prepare_run
from engine.config import EngineConfig
from engine.memory import keep_freed_memory
from engine.physics.backend import BackendName
from services.net.protocol import BARRIER_WAIT

log = logging.getLogger("colosseum")
#: The engine's own defaults: a flag not given leaves the setting where EngineConfig has it.
_ENGINE = EngineConfig()


def _positive(kind: type) -> Any:
    def parse(text: str) -> Any:
        value = kind(text)
        if value <= 0:
            raise argparse.ArgumentTypeError(f"must be positive, got {text}")
        return value

    return parse


def input_option(text: str) -> Any:
    """``--input KIND[:ARG]`` as a device spec (the input package loaded when it is given)."""
    from services.input.config import input_option as parse

    return parse(text)


def render_scale_option(text: str) -> float:
    """``--render-scale``: a share of the window's resolution, 0.25 to 1."""
    from services.render.renderer import MIN_RENDER_SCALE

    value = float(text)
    if not MIN_RENDER_SCALE <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be {MIN_RENDER_SCALE:g} to 1, got {text}")
    return value


def param_option(text: str) -> tuple[str, str]:
    """``KEY=VALUE`` of ``--param``."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    return key.strip(), value.strip()


#: ``run``'s flags by name (serve and join take those that make sense for them): data,
#: read by add_run_flags (argparse copies an ``append`` default before adding to it).
RUN_FLAG_TABLE: dict[str, tuple[tuple[str, ...], dict[str, Any]]] = {
    "seconds": (("--seconds",), {"type": _positive(float),
                                 "help": "simulated seconds to run"}),
    "frames": (("--frames",), {"type": _positive(int), "help": "frames to run"}),
    "headless": (("--headless",), {"action": "store_true",
                                   "help": "no window (automatic without a display)"}),
    "backend": (("--backend",), {"choices": list(BackendName), "default": None,
                                 "help": "dynamics backend (default: the scene's, else "
                                         "ode)"}),
    "mode": (("--mode",), {"choices": ["serial", "threaded"], "default": _ENGINE.mode,
                           "help": "serial: everything on the main thread; threaded: "
                                   "physics on its own"}),
    "fast": (("--fast",), {"action": "store_true",
                           "help": "run as fast as possible, not in real time"}),
    "seed": (("--seed",), {"type": int, "default": _ENGINE.seed,
                           "help": "seed for the scene's random functions"}),
    "dt": (("--dt",), {"type": _positive(float), "default": None,
                       "help": "physics time step (s)"}),
    "substeps": (("--substeps",), {"type": _positive(int), "default": _ENGINE.substeps,
                                   "help": "physics steps per frame"}),
    "early": (("--early",), {"choices": ["sleep", "substep"], "default": _ENGINE.early,
                             "help": "when a step finishes early: sleep, or take smaller "
                                     "substeps"}),
    "late": (("--late",), {"choices": ["slowmo", "grow"], "default": _ENGINE.late,
                           "help": "when steps run late: slow motion, or grow the step "
                                   "(bounded)"}),
    "max_dt": (("--max-dt",), {"type": _positive(float), "default": _ENGINE.max_dt,
                               "help": "upper bound for --late grow (s)"}),
    "sound": (("--sound",), {"default": _ENGINE.sound,
                             "help": "audio backend: openal, wave:FILE or null"}),
    "screenshot": (("--screenshot",), {"type": Path,
                                       "help": "write the last frame to FILE.png"}),
    "record_frames": (("--record-frames",), {"type": Path,
                                             "help": "write every Nth frame into DIR"}),
    "record_every": (("--record-every",), {"type": _positive(int), "default": 1,
                                           "help": "N for --record-frames"}),
    "interpolate": (("--interpolate",), {"action": "store_true",
                                         "help": "threaded mode: interpolate poses between "
                                                 "physics states when drawing"}),
    "hud": (("--hud",), {"action": "store_true",
                         "help": "show the HUD line (fps, physics ms, rtf)"}),
    "size": (("--size",), {"default": "640x480", "help": "window/render size WxH"}),
    "render_scale": (("--render-scale",), {
        "type": render_scale_option, "default": 1.0, "metavar": "S",
        "help": "draw the 3D view at S times the window's resolution (0.25 to 1) and "
                "scale it up: frame rate for sharpness on a software rasteriser "
                "(default 1: full resolution)"}),
    "stereo": (("--stereo",), {"choices": ["mono", "sbs"], "default": None,
                               "help": "sbs: two eyes side by side (HMDs, 3D displays), "
                                       "with the camera's EyeSeparation or 0.064 m; "
                                       "mono: one view even for a stereo camera "
                                       "(default: as the camera says)"}),
    "xr": (("--xr",), {"action": argparse.BooleanOptionalAction, "default": None,
                       "help": "draw into a headset through the active OpenXR runtime "
                               "(--no-xr: not even when the scene's Display asks for it; "
                               "see docs/headset.md)"}),
    "xr_mirror": (("--xr-mirror",), {"choices": ["none", "left", "both"], "default": None,
                                     "help": "with --xr: a window showing the left eye "
                                             "or both (default: as the scene says; none)"}),
    "xr_fallback": (("--xr-fallback",), {"action": "store_true",
                                         "help": "with --xr: when no headset can be used, "
                                                 "run in the window instead of ending"}),
    "save_state": (("--save-state",), {"type": Path,
                                       "help": "write the final state as a scene file"}),
    "stats": (("--stats",), {"type": Path, "help": "write run statistics as JSON"}),
    "record": (("--record",), {"type": Path,
                               "help": "record input events to FILE (JSON lines)"}),
    "replay": (("--replay",), {"type": Path,
                               "help": "replay input events recorded with --record"}),
    "input": (("--input",), {"action": "append", "default": [], "type": input_option,
                             "metavar": "KIND[:ARG]",
                             "help": "open an input device: osc:PORT, serial:PATH[@BAUD], "
                                     "lsl:STREAM[,...], desktop or openxr (repeatable)"}),
    "allow_path": (("--allow-path",), {"action": "append", "default": [], "type": Path,
                                       "metavar": "DIR",
                                       "help": "let the scene and its scripts name files "
                                               "in DIR too (by default only the content "
                                               "folder; repeatable)"}),
    "sessions": (("--sessions",), {"type": Path, "metavar": "DIR",
                                   "help": "where a scene's session log goes (a Session "
                                           "block; default: sessions/ here)"}),
    "progress": (("--progress",), {"action": "store_true",
                                   "help": "print a status line every second, also into "
                                           "a log or pipe (on a terminal: a progress bar "
                                           "when the run has --frames or --seconds)"}),
}


RUN_FLAGS = tuple(RUN_FLAG_TABLE)
#: What makes sense on a server (it draws nothing) and on a node (it steps no physics).
SERVE_FLAGS = tuple(f for f in RUN_FLAGS if f not in (
    "screenshot", "record_frames", "record_every", "interpolate", "hud", "size",
    "render_scale", "stereo", "xr", "xr_mirror", "xr_fallback"))
JOIN_FLAGS = ("seconds", "frames", "headless", "sound", "screenshot", "record_frames",
              "record_every", "hud", "size", "render_scale", "stereo", "save_state", "stats",
              "record", "input", "progress")


def add_run_flags(parser: argparse.ArgumentParser, names: tuple[str, ...]) -> None:
    """``names``' flags; ``--seconds`` and ``--frames`` exclude each other. The group is
    made only where one of them is taken (argparse fails on an empty group when it
    prints the usage: ``colosseum experiment run`` without its arguments did)."""
    limit = parser.add_mutually_exclusive_group() if {"seconds", "frames"} & set(names) \
        else parser
    for name in names:
        flags, options = RUN_FLAG_TABLE[name]
        (limit if name in ("seconds", "frames") else parser).add_argument(*flags, **options)


def add_param_flag(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--param", action="append", default=[], type=param_option,
                        metavar="KEY=VALUE", help="set a scene variable before the scene is "
                        "built (repeatable; what colosseum sweep varies)")


class _OnlyCommand:
    """The sub-commands' action, passing on only ``name``'s parser: ``colosseum check``
    builds check's arguments alone, not the other commands' (a few milliseconds of its
    start). The others' parsers are never made, so they take no arguments either."""

    def __init__(self, sub: Any, name: str) -> None:
        self.sub, self.name = sub, name

    def add_parser(self, name: str, **kwargs: Any) -> Any:
        return self.sub.add_parser(name, **kwargs) if name == self.name else _Unused()


class _Unused:
    """A parser not built: whatever is asked of it, it takes and does nothing."""

    def __getattr__(self, name: str) -> Any:
        return lambda *args, **kwargs: self


#: ``--log-level``'s choices.
LOG_LEVELS = ("debug", "info", "warning", "error")


def _command_named(argv: list[str]) -> str | None:
    """The sub-command ``argv`` names, where it names a known one before anything else
    (``--log-level LEVEL`` may come first); None otherwise (``--help``, a mistake)."""
    rest = list(argv)
    if rest and rest[0] == "--log-level" and len(rest) > 1 and rest[1] in LOG_LEVELS:
        rest = rest[2:]
    elif rest and rest[0].startswith("--log-level=") and rest[0][12:] in LOG_LEVELS:
        rest = rest[1:]
    return rest[0] if rest and rest[0] in COMMANDS else None


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The ``colosseum`` command: one helper per group of sub-commands; with ``only``,
    that sub-command's arguments alone (what parsing a command line naming it needs)."""
    parser = argparse.ArgumentParser(prog="colosseum", description=__doc__.splitlines()[0])
    parser.add_argument("--log-level", default="info", choices=list(LOG_LEVELS),
                        help="how much to log (default: info)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    if only is not None:
        sub = _OnlyCommand(sub, only)
    _add_run(sub)
    _add_serve_and_join(sub)
    _add_sweep_and_score(sub)
    from app.experiments.parser import add_parser as add_experiment_parser

    add_experiment_parser(sub, add_run_flags, add_param_flag)
    _add_files(sub)
    _add_bench(sub)
    return parser


def _add_run(sub: Any) -> None:
    """``run``."""
    run = sub.add_parser("run", help="run a content folder (default: the bundled demo)")
    run.add_argument("path", nargs="?", help="content folder or .scene file")
    add_run_flags(run, RUN_FLAGS)
    run.add_argument("--watch", action="store_true",
                     help="start again from the files when the scene or a model, image or "
                          "sound it uses changes on disk")
    add_param_flag(run)


def _add_serve_and_join(sub: Any) -> None:
    """``serve`` and ``join``: a server and the nodes that follow it."""
    serve = sub.add_parser("serve", help="run the authoritative simulation headless and "
                           "publish it to nodes that join (colosseum join)")
    serve.add_argument("path", nargs="?", help="content folder or .scene file")
    serve.add_argument("--bind", default="tcp://127.0.0.1:5555", metavar="tcp://HOST:PORT",
                       help="where nodes join (PORT: state, PORT+1: control); loopback unless "
                            "told otherwise (default: tcp://127.0.0.1:5555)")
    serve.add_argument("--key", type=Path, metavar="DIR",
                       help="CURVE encryption and authentication with the keys in DIR "
                            "(colosseum keygen)")
    serve.add_argument("--timeout", type=_positive(float), default=2.0,
                       help="seconds of silence before a node is let go (default: 2)")
    serve.add_argument("--leave-after", type=_positive(float), default=10.0,
                       help="seconds after a user's node leaves that what stands for them "
                            "(User \"NAME\" objects and avatars) leaves the world, unless "
                            "they come back (default: 10)")
    serve.add_argument("--barrier-wait", type=_positive(float), default=BARRIER_WAIT,
                       metavar="S", help="seconds the swap barrier waits for every display "
                       "before it lets the ready ones go (default: %(default)g)")
    add_run_flags(serve, SERVE_FLAGS)
    add_param_flag(serve)

    join = sub.add_parser("join", help="follow a server: draw, play sounds, send this "
                          "node's input (no local physics)")
    join.add_argument("address", metavar="tcp://HOST:PORT", help="the server's --bind")
    join.add_argument("path", nargs="?", help="the content folder or a .scene file in it, as "
                      "serve takes (default: the server's folder, when it is at the same "
                      "place here)")
    join.add_argument("--user", default=None, help="this node's user name: its input drives "
                      "the trackers, buttons and wheels named USER/... on the server "
                      "(default: the login name and process id)")
    join.add_argument("--display", metavar="NAME", help="draw the scene's Display block NAME "
                      "(a wall of a cluster): off-axis from its head tracker, frame-locked")
    join.add_argument("--swap-barrier", action="store_true",
                      help="with --display: wait until every display holds the frame")
    join.add_argument("--key", type=Path, metavar="DIR",
                      help="the server's public key and this user's key (colosseum keygen)")
    join.add_argument("--timeout", type=_positive(float), default=2.0,
                      help="seconds without frames before the server counts as gone")
    add_run_flags(join, JOIN_FLAGS)


def _add_sweep_and_score(sub: Any) -> None:
    """``sweep`` (many runs on Dask) and ``score`` (a recorded session scored again)."""
    sweep = sub.add_parser("sweep", help="run a content folder many times over parameters "
                           "and seeds on Dask; one results table and a plot")
    sweep.add_argument("path", help="content folder or .scene file")
    sweep.add_argument("--param", action="append", default=[], metavar="KEY=v1,v2,...",
                       help="a scene variable and the values it takes (repeatable: every "
                            "combination runs)")
    sweep.add_argument("--seeds", default="0", metavar="A..B",
                       help="seeds of each combination: A..B, N or N,M (default: 0)")
    sweep.add_argument("--participants", metavar="A..B",
                       help="run the content's Experiment for these participant numbers "
                            "(a scripted participant; --param KEY=VALUE sets a scene "
                            "variable in every run) and check the design: "
                            "docs/experiments.md")
    sweep_limit = sweep.add_mutually_exclusive_group()
    sweep_limit.add_argument("--frames", type=_positive(int), help="frames each run takes")
    sweep_limit.add_argument("--seconds", type=_positive(float),
                             help="simulated seconds each run takes")
    sweep.add_argument("--out", type=Path, required=True, metavar="DIR",
                       help="where results.csv and results.png go (--participants: "
                            "sessions/, design_check.json and report/)")
    sweep.add_argument("--scheduler", metavar="ADDRESS",
                       help="a running Dask scheduler (tcp://HOST:8786); default: a "
                            "LocalCluster on this machine")
    sweep.add_argument("--workers", type=_positive(int), default=2,
                       help="worker processes of the LocalCluster (default: 2)")
    sweep.add_argument("--backend", choices=list(BackendName), default=None,
                       help="dynamics backend (default: the scene's)")
    sweep.add_argument("--dt", type=_positive(float), default=None,
                       help="physics time step (s)")

    score = sub.add_parser("score", help="replay a recorded session (--record) to its end and "
                           "score it from the session log it writes again")
    score.add_argument("recording", type=Path, help="the input recording")
    score.add_argument("path", nargs="?", help="content folder or .scene file (default: the "
                       "scene the recording names)")
    score.add_argument("--sessions", type=Path, metavar="DIR",
                       help="where the session log goes (default: sessions/ here)")
    score.add_argument("--json", action="store_true", help="the summary as JSON")


def _add_files(sub: Any) -> None:
    """The commands over files: ``keygen``, ``check``, ``fmt``, ``import``, ``export``,
    ``keys``, ``new``."""
    keygen = sub.add_parser("keygen", help="make CURVE keys for serve --key and join --key")
    keygen.add_argument("folder", type=Path)
    keygen.add_argument("--user", action="append", default=[], help="a user (repeatable)")

    check = sub.add_parser("check", help="validate a content folder or scene file",
                           epilog="exit codes: 0 no errors (warnings allowed), 1 errors, "
                                  "2 no such file or folder or a usage error")
    check.add_argument("path")
    check.add_argument("--allow-path", action="append", default=[], type=Path, metavar="DIR",
                       help="files the scene names may lie in DIR too, as for run")
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
    keys.add_argument("--content", type=Path, metavar="DIR",
                      help="also the blocks DIR's systems/*.py declare")

    new = sub.add_parser("new", help="scaffold a content folder that runs")
    new.add_argument("name")


def _add_bench(sub: Any) -> None:
    """``bench``."""
    bench = sub.add_parser("bench", help="benchmarks, printed as tables")
    bench.add_argument("what", nargs="?", default="scheduler",
                       help="scheduler, physics, scene, scripting, sound, render, input, "
                            "contacts, avatars, import, hands, net, sweep, accuracy, stroke, "
                            "experiment, startup, pareto")
    bench.add_argument("--backend", default=None, help="physics benchmark backend (ode, pymunk)")
    bench.add_argument("--quick", action="store_true", help="fewer sizes and steps")
    bench.add_argument("--stereo", action="store_true",
                       help="render: a headset's stereo frame (both eyes in one pass, and one "
                            "pass an eye) beside a mono frame at one eye's size (bench stereo)")
    bench.add_argument("--content", type=Path, metavar="DIR",
                       help="the content folder a benchmark runs (stroke; default: "
                            "content/stroke, else a stand-in of its size)")
    bench.add_argument("--json", nargs="?", const="-", metavar="FILE",
                       help="the rows and figures as JSON: to FILE, or alone on stdout")
    bench.add_argument("--plot", type=Path, metavar="FILE.png",
                       help="our figures beside their references as a bar chart")


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line as parsed, where a command's trailing path may also come after its
    options (``join tcp://HOST:PORT --user alice my_sim``: argparse alone stops taking
    positionals once an option follows the first)."""
    argv = sys.argv[1:] if argv is None else argv
    parser = build_parser(only=_command_named(argv))
    args, extra = parser.parse_known_args(argv)
    if (len(extra) == 1 and not extra[0].startswith("-") and hasattr(args, "path")
            and args.path is None):
        args.path = extra[0]
    elif extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    logging.basicConfig(level=getattr(logging, args.log_level.upper()),
                        format="%(levelname)s %(name)s: %(message)s")
    handler = COMMANDS[args.command]
    keep_freed_memory()
    try:
        return handler(args)
    except KeyboardInterrupt:
        print("colosseum: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `colosseum keys | head`: the reader left, nothing to tell
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


def cmd_run(args: argparse.Namespace) -> int:
    from engine.physics import BackendUnavailable
    from systems import create_engine

    prepared = prepare_run(args)
    if isinstance(prepared, int):
        return prepared
    scene, config = prepared
    if args.watch:
        return _run_watching(args, scene.content, config, scene)
    try:
        engine = create_engine(config)
    except BackendUnavailable as exc:
        return fail(str(exc), 1)
    return execute_run(engine, args, scene)


def _run_watching(args: argparse.Namespace, content: Any, config: Any, scene: Any) -> int:
    """``run --watch``: run the scene; when a file it came from changes, load it again and
    start over from the new files (a scene with errors is told and the old one runs on);
    a scene ``colosseum import`` wrote is imported again from its changed model first,
    the author's edits kept. Frames and seconds count across the restarts."""
    from app.scene_loading import SceneLoadError, SceneWatcher, load_content_scene
    from engine.content import ContentError, load_systems
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
            return fail(str(exc), 1)
        engine.close()
        if frames is not None:
            frames -= engine.frame
        if seconds is not None:
            seconds -= engine.time
        if not watcher.changed() or (frames is not None and frames <= 0) or (
                seconds is not None and seconds <= 1e-9):
            if scene.errors:  # as a run without --watch: went on without them, exit 1
                return fail(f"the content had {scene.errors} error(s) (told above)", 1)
            return 0
        names = ", ".join(sorted(p.name for p in watcher.changed()))
        for again in watcher.reimport():  # a scene colosseum import wrote: imported again
            print(f"colosseum: {again.name} imported again from its changed model",
                  file=sys.stderr)
        try:
            scene = load_content_scene(content, seed=args.seed, params=dict(args.param),
                                       allow=args.allow_path)
        except SceneLoadError as exc:
            print(f"{exc}\ncolosseum: {names} changed but has errors; running the last "
                  f"good scene", file=sys.stderr)
            continue
        print(f"colosseum: {names} changed; starting again", file=sys.stderr)
        scene.configure(config, backend=args.backend, dt=args.dt)


def cmd_check(args: argparse.Namespace) -> int:
    from app.runner import allowed_problem
    from app.scene_loading import check_path

    problem = allowed_problem(args)
    if problem is not None:
        return fail(problem)
    return check_path(Path(args.path), args.format, args.allow_path)


def cmd_fmt(args: argparse.Namespace) -> int:
    from app.scene_loading import format_path

    return format_path(Path(args.path), write=args.write)


def cmd_import(args: argparse.Namespace) -> int:
    from app.scene_loading import import_path

    return import_path(args.model, args.output, force=args.force)


def cmd_export(args: argparse.Namespace) -> int:
    from app.scene_loading import export_path

    return export_path(args.scene, args.output)


def cmd_keys(args: argparse.Namespace) -> int:
    from engine.content import ContentError, import_systems
    from engine.scene import keys

    if args.content is not None:
        try:
            import_systems(args.content)
        except ContentError as exc:
            return fail(str(exc), 1)
    if args.block is None:
        for block in keys.blocks(content=args.content is not None):
            print(f"{block:<15} {keys.about(block)}")
        print("\ncolosseum keys BLOCK lists a block's keys; docs/KEYS.md has them all")
        return 0
    block = keys.find_block(args.block)
    if block is None:
        return fail(f"no block {args.block!r}{keys.suggest(args.block)} "
                     f"(blocks: {', '.join(keys.blocks())})")
    print(keys.block_text(block))
    return 0


def cmd_new(args: argparse.Namespace) -> int:
    from app.scaffold import ScaffoldError, scaffold

    try:
        folder = scaffold(Path(args.name))
    except ScaffoldError as exc:
        return fail(str(exc))
    print(f"created {folder}; run it with: colosseum run {folder}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from app.bench import BENCHMARKS, run_benchmark

    if args.stereo:
        if args.what not in ("render", "stereo"):
            return fail("--stereo goes with bench render")
        args.what = "stereo"
    if args.what not in BENCHMARKS:
        return fail(f"unknown benchmark {args.what!r}; choose from {', '.join(BENCHMARKS)}")
    for out in (None if args.json in (None, "-") else Path(args.json), args.plot):
        if out is not None and not out.parent.exists():
            return fail(f"{out}: folder {out.parent} does not exist")
    if args.content is not None and not (args.content / "main.scene").is_file():
        return fail(f"{args.content}: not a content folder (no main.scene)")
    return run_benchmark(args.what, backend=args.backend, quick=args.quick,
                         json_out=args.json, plot_out=args.plot, content=args.content)


def cmd_serve(args: argparse.Namespace) -> int:
    from app.cli_net import serve

    return serve(args)


def cmd_join(args: argparse.Namespace) -> int:
    from app.cli_net import join

    return join(args)


def cmd_sweep(args: argparse.Namespace) -> int:
    from app.sweep import sweep

    if args.participants:  # an experiment's simulated participants
        from app.experiments.simulate import simulate

        return simulate(args)

    return sweep(args)


def cmd_score(args: argparse.Namespace) -> int:
    from app.runner import score

    return score(args)


def cmd_experiment(args: argparse.Namespace) -> int:
    from app.experiments.cli import command

    return command(args)


def cmd_keygen(args: argparse.Namespace) -> int:
    from app.cli_net import keygen

    return keygen(args)


COMMANDS = {
    "run": cmd_run,
    "serve": cmd_serve,
    "join": cmd_join,
    "sweep": cmd_sweep,
    "score": cmd_score,
    "experiment": cmd_experiment,
    "keygen": cmd_keygen,
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
