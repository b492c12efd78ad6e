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
    from app.scene_loading import SceneLoadError, load_content_scene
    from engine.app import EngineConfig
    from engine.content import ContentError, resolve

    try:
        content = resolve(args.path)
    except ContentError as exc:
        return fail(str(exc))
    if getattr(args, "replay", None) is not None and not args.replay.is_file():
        return fail(f"{args.replay}: no such recording")
    if getattr(args, "replay", None) is not None:
        problem = replay_flags(args)
        if problem is not None:
            return fail(problem)
    problem = outputs_problem(args) or allowed_problem(args) or step_problem(args)
    if problem is not None:
        return fail(problem)
    headless = getattr(args, "headless", True) or not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    try:
        scene = load_content_scene(content, seed=args.seed,
                                   params=dict(getattr(args, "param", None) or ()),
                                   allow=getattr(args, "allow_path", ()), skip_broken=True)
    except SceneLoadError as exc:
        print(exc, file=sys.stderr)
        return 1
    content = scene.content  # a saved state runs in the content folder it names
    config = EngineConfig(
        content_dir=content.folder, mode=args.mode, seed=args.seed, fast=args.fast,
        substeps=args.substeps, early=args.early, late=args.late, max_dt=args.max_dt,
        headless=headless, sound=args.sound,
        allow_paths=tuple(getattr(args, "allow_path", ())),
        options={"screenshot": getattr(args, "screenshot", None),
                 "record_frames": getattr(args, "record_frames", None),
                 "record_every": getattr(args, "record_every", 1),
                 "interpolate": getattr(args, "interpolate", False),
                 "hud": getattr(args, "hud", False), "size": getattr(args, "size", "640x480"),
                 "stereo": getattr(args, "stereo", None),
                 "render_scale": getattr(args, "render_scale", 1.0),
                 "input": args.input, "session_log": True,
                 "sessions": getattr(args, "sessions", None),
                 "record": getattr(args, "record", None), "replay": getattr(args, "replay", None),
                 "run_flags": {"params": dict(getattr(args, "param", None) or ()),
                               "dt": args.dt, "substeps": args.substeps,
                               "backend": args.backend}},
    )
    scene.configure(config, backend=args.backend, dt=args.dt)
    headset(args, scene, config)
    _tell_shaders(scene, config)
    return scene, config


def headset(args: argparse.Namespace, scene: Any, config: Any) -> None:
    """Whether the run draws into a headset (``--xr``, or the scene's ``Display { Kind
    "openxr" }`` unless ``--no-xr``), and the headset flags, into ``config``."""
    from components import Headset

    declared = any(isinstance(c, Headset) for e in scene.spec.entities for c in e.components)
    flag = getattr(args, "xr", None)
    wanted = flag if flag is not None else declared
    config.options.update({"xr": bool(wanted), "xr_mirror": getattr(args, "xr_mirror", None),
                           "xr_fallback": bool(getattr(args, "xr_fallback", False))})
    if wanted:
        config.render = True


def _tell_shaders(scene: Any, config: Any) -> None:
    """A run that draws nothing compiles no shader, so the renderer's warning about a
    uniform nothing sets never comes: it is told here from the GLSL source, as
    ``colosseum check`` tells it (a run that draws tells it from the compiled program)."""
    from app.scene_loading import shader_diagnostics
    from systems import wants_render

    if wants_render(config) or not scene.spec.shader_programs:
        return
    for said in shader_diagnostics(scene.spec, scene.content.folder):
        print(said.render(), file=sys.stderr)


def replay_flags(args: argparse.Namespace) -> str | None:
    """A replay runs with the flags that changed what its recording simulated (``--param``,
    ``--dt``, ``--substeps``, ``--backend``: its header keeps them). Those this run leaves
    at their defaults are taken from the recording and told; one set otherwise is warned
    about, as the run will not repeat the recorded one. Returns what is wrong with the
    file's header."""
    from engine.physics.backend import BackendName
    from services.input.record import ReplayError, read_header

    try:
        header = read_header(args.replay)
    except ReplayError as exc:
        return str(exc)
    params = header.get("params") or {}
    if not isinstance(params, dict) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in params.items()):
        return f"{args.replay}: the header's params must map names to text, got {params!r}"
    valid = {"dt": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0,
             "substeps": lambda v: isinstance(v, int) and not isinstance(v, bool) and v > 0,
             "backend": lambda v: v in tuple(BackendName)}
    for key, ok in valid.items():
        if header.get(key) is not None and not ok(header[key]):
            return f"{args.replay}: the header's {key} {header[key]!r} is not a valid --{key}"
    recorded: dict[str, Any] = {key: header.get(key) for key in valid}
    recorded["dt"] = recorded["dt"] and float(recorded["dt"])
    recorded["substeps"] = recorded["substeps"] or 1
    if hasattr(args, "param"):
        recorded["param"] = list(params.items())
    defaults = {"dt": None, "substeps": 1, "backend": None, "param": []}
    for key, value in recorded.items():
        mine = getattr(args, key, defaults[key])
        if mine == value:
            continue
        flag = (" ".join(f"--param {k}={v}" for k, v in value) if key == "param"
                else f"--{key} {value}")
        if mine == defaults[key]:
            setattr(args, key, value)
            log.info("replaying with the recording's %s", flag)
        else:
            log.warning("%s was recorded with %s; this run's %s differs, so it will not "
                        "repeat the recorded one", args.replay, flag or "no --param",
                        "--" + key)
    return None


def step_problem(args: argparse.Namespace) -> str | None:
    """What is wrong with ``--dt`` (the same range as a scene's TimeStep); a long one is
    warned about, as in a scene."""
    from engine.realtime import STEP_RANGE, STEP_WARNING

    dt = getattr(args, "dt", None)
    if dt is not None and dt > STEP_RANGE[1]:
        return f"--dt {dt:g}: the time step is at most {STEP_RANGE[1]:g} s"
    if dt is not None and dt > STEP_WARNING:
        log.warning("--dt %g s is long: contacts and joints lose accuracy past %g s", dt,
                    STEP_WARNING)
    return None


def allowed_problem(args: argparse.Namespace) -> str | None:
    """What is wrong with the folders ``--allow-path`` names (one that is not there)."""
    for folder in getattr(args, "allow_path", ()):
        if not folder.is_dir():
            return f"--allow-path {folder}: no such folder"
    return None


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
    from engine.stats import collect, sections, status_line, write_json
    from engine.system import SystemFailure
    from services.input import InputRecorder, InputReplayer, ReplayError

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
            from app.scene_loading import save_state

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
    if _headset_failed(engine):
        return 1
    errors = getattr(scene, "errors", 0)
    if errors:  # the run went on without the broken parts; a script or CI must still know
        print(f"colosseum: the content had {errors} error(s) (told above; colosseum check "
              f"lists them): exit code 1", file=sys.stderr)
        return 1
    return 0


def _headset_failed(engine: Any) -> bool:
    """Whether the run was to draw into a headset and could not (told already), or lost it."""
    display = getattr(engine.plugins.get("xr"), "display", None)
    return bool(display is not None and display.failed and not display.unavailable)


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




def score(args: argparse.Namespace) -> int:
    """``colosseum score RECORDING``: replay a recorded session headless and unpaced to its
    last frame, writing its session log again, and print what the log says (tasks done
    and when, grasps, collisions, distance) as a table or ``--json``."""
    import json

    from services.input import ReplayError, read_recording
    from systems import create_engine
    from systems.session import SessionLog, summarize

    try:
        recording = read_recording(args.recording)
    except (OSError, ReplayError) as exc:
        return fail(f"{args.recording}: {exc}")
    path = args.path or recording.header.get("scene") or None
    if path is None:
        return fail(f"{args.recording} names no scene; give the content folder too")
    run_args = argparse.Namespace(
        path=str(path), replay=args.recording, record=None, headless=True, fast=True,
        mode="serial", seed=recording.header.get("seed", 0), substeps=1, early="sleep",
        late="slowmo", max_dt=1.0 / 20.0, sound="null", backend=None, dt=None, input=[],
        param=[], sessions=args.sessions, frames=max(recording.frames, default=0) + 1,
        seconds=None, progress=False, save_state=None, stats=None)
    prepared = prepare_run(run_args)
    if isinstance(prepared, int):
        return prepared
    scene, config = prepared
    engine = create_engine(config)
    code = execute_run(engine, run_args, scene)
    logged = engine.try_resource(SessionLog)
    if code != 0:
        return code
    if logged is None or logged.path is None:
        return fail(f"{path}: the scene keeps no session log (it has no Session block)", 1)
    summary = {"log": str(logged.path), **summarize(logged.path)}
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"session log: {summary['log']}")
    for name, task in summary["tasks"].items():
        done = "not done" if task["done"] is None else f"done at {task['done']:.2f} s"
        print(f"  task {name:<12} {done} ({task['events']} events)")
    print(f"  grasps {summary['grasp']}, collisions {summary['collision']}, anomaly "
          f"switches {summary['anomaly']}, chair moved {summary['distance']:.2f} m")
    end = summary["end"]
    if end is not None:
        print(f"  ended: {end['reason']} at {end['t']:.2f} s")
    return 0
