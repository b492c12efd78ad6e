"""``colosseum experiment run|report|replay``: a participant's session, the sessions'
summaries and plots, one trial played back from its recording.

``run CONTENT --participant P [--resume]`` reads the content's ``Experiment`` block, opens
``sessions/<experiment>/<P>/`` (engine.experiments.session) and runs the participant's
trials in order: with ``Reset "trial"`` each in a world built afresh (the condition's
scene variables set as ``--param`` would), its input recorded to ``input/trial-NNN.input``;
with ``Reset "never"`` all in one world. Each trial's row is written, flushed and fsynced
when it ends. ``--resume`` continues a session from the first trial without a row.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
import traceback
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from app.runner import fail, prepare_run
from engine.config import EngineConfig
from engine.experiments.design import Design, TrialPlan, plan, staircase_trial
from engine.experiments.ordering import rng_for
from engine.experiments.session import SessionError, SessionFiles, read_rows
from engine.experiments.staircase import replayed

log = logging.getLogger("colosseum.experiment")

def command(args: argparse.Namespace) -> int:
    if args.experiment_command == "run":
        return run(args)
    if args.experiment_command == "report":
        from app.experiments.report import report

        return report(args.folder, args.out)
    return replay(args)


def _design(args: argparse.Namespace) -> tuple[Any, Design] | int:
    """The content and its design, or an exit code (the problem told)."""
    from app.scene_loading import SceneLoadError, load_content_scene
    from engine.content import ContentError, resolve

    try:
        content = resolve(args.path)
    except ContentError as exc:
        return fail(str(exc))
    try:
        scene = load_content_scene(content, seed=0, params=dict(args.param or ()),
                                   allow=getattr(args, "allow_path", ()))
    except SceneLoadError as exc:
        print(exc, file=sys.stderr)
        return 1
    design = scene.spec.experiment
    if design is None:
        return fail(f"{args.path}: the scene has no Experiment block "
                    "(docs/experiments.md)", 1)
    return scene.content, design


def trial_seed(seed: int, participant: int, index: int) -> int:
    """The engine seed of one trial (a replay uses it again)."""
    return int(rng_for(seed, participant, index).integers(2**31 - 1))


def variables(design: Design, trial: TrialPlan) -> dict[str, str]:
    """The scene variables a trial's condition sets."""
    out = {}
    for key, var in [(f.id, f.variable) for f in design.factors] + \
                    [(s.id, s.variable) for s in design.staircases]:
        if var is not None and key in trial.condition:
            out[var] = trial.condition[key]
    return out


def _truthy(value: Any) -> bool:
    if isinstance(value, str):
        return value.strip().lower() in ("1", "true", "yes", "y", "seen", "correct")
    return bool(value)


def trials(design: Design, participant: int, rows: list[dict[str, str]],
           answers: dict[str, list[bool]]) -> Iterator[TrialPlan]:
    """The participant's trials after the ``rows`` already run: factorial ones, then each
    staircase's, made as ``answers`` (filled in by the caller after each trial) come."""
    done = len(rows)
    fixed = plan(design, participant)
    yield from fixed[done:]
    index = len(fixed)
    for i, spec in enumerate(design.staircases):
        mine = [r for r in rows if r.get(spec.id)]
        answers[spec.id] = [_truthy(_response(r, spec.response)) for r in mine]
        index += len(mine)
        n = len(mine)
        while True:
            stair = replayed(spec, answers[spec.id])
            if stair.done:
                break
            index += 1
            n += 1
            yield staircase_trial(design, participant, index, i, n, stair.intensity)


def _response(row: dict[str, str], name: str) -> Any:
    import json

    try:
        return json.loads(row.get("responses") or "{}").get(name)
    except ValueError:
        return None


def _engine(args: argparse.Namespace, design: Design, trial: TrialPlan, seed: int,
            logs: Path) -> Any:
    """A fresh engine with the trial's scene variables, or an exit code."""
    from systems import create_engine

    run_args = argparse.Namespace(**vars(args))
    run_args.param = [*(args.param or ()), *variables(design, trial).items()]
    run_args.seed = seed
    for name in ("replay", "record", "stats", "save_state", "screenshot"):
        setattr(run_args, name, getattr(args, name, None))
    prepared = prepare_run(run_args)
    if isinstance(prepared, int):
        return prepared
    scene, config = prepared
    config.options["sessions"] = logs  # a Session block's logs stay with the session
    return scene, create_engine(config)


def run(args: argparse.Namespace) -> int:
    from engine.content import ContentError
    from engine.system import SystemFailure
    from services.input import ReplayError

    found = _design(args)
    if isinstance(found, int):
        return found
    content, design = found
    if args.participant < 1:
        return fail(f"--participant {args.participant}: participant numbers start at 1")
    try:
        files = SessionFiles(args.sessions, design, args.participant, content.folder,
                             resume=args.resume, seed=args.seed)
    except SessionError as exc:
        return fail(str(exc), 1)
    if files.changed_content:
        log.warning("the content folder changed since this session began (session.json "
                    "keeps both hashes)")
    if args.resume:
        print(f"colosseum: resuming participant {args.participant} at trial "
              f"{len(files.rows) + 1}", file=sys.stderr)
    try:
        return _run_trials(args, content, design, files)
    except (ContentError, ReplayError, SystemFailure) as exc:
        if isinstance(exc, SystemFailure):
            trace = "".join(traceback.format_exception(exc.original))
            return fail(f"system {exc.system_name!r} raised; the session stopped before its "
                        f"trial ended (--resume runs it again).\n{trace}", 1)
        return fail(f"{exc}; the session stopped (--resume runs the trial again)", 1)


def _run_trials(args: argparse.Namespace, content: Any, design: Design,
                files: SessionFiles) -> int:
    from systems.experiments import TrialRunner

    answers: dict[str, list[bool]] = {}
    runner = TrialRunner(design, args.participant)
    engine = None
    last_block = int(files.rows[-1]["block"]) if files.rows else None
    count = 0
    try:
        for trial in trials(design, args.participant, files.rows, answers):
            if args.stop_after is not None and count >= args.stop_after:
                break
            if last_block is not None and trial.block != last_block and design.pause > 0 \
                    and not args.fast:
                print(f"colosseum: a break of {design.pause:g} s before block {trial.block}",
                      file=sys.stderr)
                time.sleep(design.pause)
            last_block = trial.block
            stale = files.trial_file("tracking", trial.index)
            for suffix in (".bin", ".times.bin"):
                stale.with_suffix(suffix).unlink(missing_ok=True)
            if engine is None or design.reset == "trial":
                engine = _trial_engine(args, content, design, trial, files, runner)
                if isinstance(engine, int):
                    return engine
            runner.begin(trial, files.trial_file("tracking", trial.index))
            engine.run(until=lambda e: runner.ended)
            if not runner.ended:
                runner.abandon()
                engine.close()
                print(f"colosseum: stopped in trial {trial.index}; it has no row. "
                      f"--resume runs it again", file=sys.stderr)
                return 1
            _keep_result(runner, design, trial, files, answers)
            count += 1
            if design.reset == "trial":
                engine.close()
                engine = None
    finally:
        if engine is not None and not isinstance(engine, int):
            engine.close()
    summary = _summary(design, files.rows)
    files.finish(summary)
    print(f"colosseum: participant {args.participant}: {count} trial(s) run, "
          f"{len(files.rows)} in {files.trials_path}", file=sys.stderr)
    for sid, value in summary.get("thresholds", {}).items():
        print(f"colosseum: staircase {sid}: threshold {value:.4g}", file=sys.stderr)
    return 0


def _trial_engine(args: argparse.Namespace, content: Any, design: Design, trial: TrialPlan,
                  files: SessionFiles, runner: Any) -> Any:
    """The engine a trial runs in (or, Reset "never", every trial from this one), its
    input recorded; an exit code when the scene cannot be built."""
    from engine.content import load_systems
    from services.input import InputRecorder
    from systems.experiments import ExperimentPlugin

    seed = trial_seed(args.seed, args.participant, trial.index)
    built = _engine(args, design, trial, seed, files.folder / "logs")
    if isinstance(built, int):
        return built
    scene, engine = built
    engine.add_plugin(ExperimentPlugin(runner))
    record = files.trial_file("input", trial.index) if design.reset == "trial" \
        else files.folder / "input" / f"from-trial-{trial.index:03d}.input"
    engine.add_system(InputRecorder(record))
    load_systems(engine, content.folder)
    scene.instantiate(engine)
    return engine


def _keep_result(runner: Any, design: Design, trial: TrialPlan, files: SessionFiles,
                 answers: dict[str, list[bool]]) -> None:
    """The finished trial's row, and its answer to the staircase it served."""
    result = runner.result
    assert result is not None
    files.write_row(trial, result.start, result.end, result.wall, result.lsl_start,
                    result.lsl_end, result.outcome, result.responses, result.measures)
    if trial.staircase is not None:
        spec = next(s for s in design.staircases if s.id == trial.staircase)
        answers[spec.id].append(_truthy(result.responses.get(spec.response)))


def _summary(design: Design, rows: list[dict[str, str]]) -> dict[str, Any]:
    """The session's staircase thresholds from its rows."""
    thresholds = {}
    for spec in design.staircases:
        answers = [_truthy(_response(r, spec.response)) for r in rows if r.get(spec.id)]
        if answers:
            thresholds[spec.id] = replayed(spec, answers).estimate
    return {"thresholds": thresholds, "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z")}


def replay(args: argparse.Namespace) -> int:
    """Play trial N back from its recording: the same condition, seed and input; prints
    the outcome and end time beside the row's."""
    from engine.content import load_systems
    from services.input import InputReplayer
    from systems.experiments import ExperimentPlugin, TrialRunner

    args.param = []
    found = _design(args)
    if isinstance(found, int):
        return found
    content, design = found
    folder = args.sessions / design.id / str(args.participant)
    recorded = _recorded_trial(args, design, folder)
    if isinstance(recorded, int):
        return recorded
    row, trial, recording, seed = recorded
    args.replay = recording
    out = folder / "replay"
    out.mkdir(exist_ok=True)
    built = _engine(args, design, trial, seed, out / "logs")
    if isinstance(built, int):
        return built
    scene, engine = built
    runner = TrialRunner(design, args.participant)
    engine.add_plugin(ExperimentPlugin(runner))
    engine.add_system(InputReplayer(recording))
    try:
        load_systems(engine, content.folder)
        scene.instantiate(engine)
        runner.begin(trial, out / f"trial-{trial.index:03d}.csv")
        engine.run(until=lambda e: runner.ended)
    finally:
        engine.close()
    result = runner.result
    if result is None:
        return fail(f"trial {trial.index}: the replay stopped before the trial ended", 1)
    same = result.outcome == row["outcome"] and f"{result.end:.6f}" == row["end_s"]
    print(f"trial {trial.index}: outcome {result.outcome} at {result.end:.6f} s "
          f"(recorded: {row['outcome']} at {row['end_s']} s){'' if same else ' - differs'}")
    print(f"tracking: {out / f'trial-{trial.index:03d}.csv'}")
    return 0 if same else 1


def _recorded_trial(args: argparse.Namespace, design: Design,
                    folder: Path) -> tuple[dict[str, str], TrialPlan, Path, int] | int:
    """Trial N's row, its plan, its input recording and its seed, as the session ran it
    (``args`` given the run flags replay does not take, at the engine's defaults); an
    exit code when the session, the row or the recording is missing."""
    import json

    path = folder / "trials.csv"
    if not path.is_file():
        return fail(f"{path}: no such session", 1)
    rows = [r for r in read_rows(path) if r["trial"] == str(args.trial)]
    if not rows:
        return fail(f"{path}: no trial {args.trial} (it has not finished)", 1)
    row = rows[0]
    recording = folder / "input" / f"trial-{args.trial:03d}.input"
    if not recording.is_file():
        return fail(f"{recording}: no recording of trial {args.trial} (a Reset \"never\" "
                    "session records its run as a whole)", 1)
    meta = json.loads((folder / "session.json").read_text(encoding="utf-8"))
    known = [f.id for f in design.factors] + [s.id for s in design.staircases]
    condition = {k: row[k] for k in known if row.get(k)}
    stair = next((s.id for s in design.staircases if row.get(s.id)), None)
    trial = TrialPlan(int(row["trial"]), int(row["block"]), int(row["block_trial"]),
                      condition, row["practice"] == "1", None, stair)
    config = EngineConfig()
    for name, default in (("mode", config.mode), ("backend", None), ("dt", None),
                          ("substeps", config.substeps), ("early", config.early),
                          ("late", config.late), ("max_dt", config.max_dt), ("input", []),
                          ("allow_path", []), ("progress", False)):
        setattr(args, name, getattr(args, name, default))
    seed = trial_seed(int(meta.get("run_seed", 0)), args.participant, trial.index)
    return row, trial, recording, seed
