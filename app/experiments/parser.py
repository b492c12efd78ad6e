"""The ``experiment`` command's arguments, apart from what runs it (:mod:`app.experiments.cli`):
building ``colosseum``'s parser, which every command does, loads no experiment code."""

from __future__ import annotations

from pathlib import Path
from typing import Any

#: ``run``'s flags that an experiment run takes (its trials set their own length).
RUN_FLAGS = ("headless", "backend", "mode", "fast", "seed", "dt", "substeps", "early", "late",
             "max_dt", "sound", "size", "render_scale", "stereo", "hud", "xr", "xr_mirror",
             "xr_fallback", "input", "allow_path", "progress")


def add_parser(sub: Any, add_run_flags: Any, add_param_flag: Any) -> None:
    """The ``experiment`` command and its subcommands."""
    exp = sub.add_parser("experiment", help="run a participant through the content's "
                         "Experiment, report on the sessions, replay a trial")
    subs = exp.add_subparsers(dest="experiment_command", required=True, metavar="ACTION")
    run = subs.add_parser("run", help="run a participant's session (trials.csv, tracking, "
                          "input recordings, session.json in sessions/<experiment>/<P>/)")
    run.add_argument("path", help="content folder or .scene file with an Experiment block")
    run.add_argument("--participant", type=int, required=True, metavar="P",
                     help="the participant's number (1, 2, ...): it picks the order")
    run.add_argument("--resume", action="store_true",
                     help="continue the participant's session at its first unfinished trial")
    run.add_argument("--sessions", type=Path, default=Path("sessions"), metavar="DIR",
                     help="where sessions go (default: sessions/ here)")
    run.add_argument("--stop-after", type=int, default=None, metavar="N",
                     help="run at most N trials now (--resume goes on later)")
    add_run_flags(run, RUN_FLAGS)
    add_param_flag(run)
    report = subs.add_parser("report", help="per-condition summaries and plots of an "
                             "experiment's sessions")
    report.add_argument("folder", type=Path, help="sessions/<experiment>")
    report.add_argument("--out", type=Path, metavar="DIR",
                        help="where summary.csv and the plots go (default: FOLDER/report)")
    replay = subs.add_parser("replay", help="play one trial back in the engine from its "
                             "input recording")
    replay.add_argument("path", help="the content folder the session ran")
    replay.add_argument("--participant", type=int, required=True, metavar="P")
    replay.add_argument("--trial", type=int, required=True, metavar="N")
    replay.add_argument("--sessions", type=Path, default=Path("sessions"), metavar="DIR")
    add_run_flags(replay, ("headless", "size", "render_scale", "hud", "fast", "sound"))
