"""``colosseum sweep CONTENT --participants 1..24 --out DIR``: an experiment run by
simulated participants on Dask, to check a design before a real person sits down.

Each participant is one ``colosseum experiment run CONTENT --participant P --fast
--headless`` on a Dask worker, into ``DIR/sessions``; the participant is whatever the
content scripts (a Lua or Python policy); ``--param KEY=VALUE`` sets a scene variable in
every participant's run. Then ``DIR/design_check.json`` says
what the sessions show:

- ``counterbalance``: for each condition, how often it stood in each position of the
  first block, and whether every position holds every condition equally often;
- ``unreached``: conditions no trial met;
- ``conditions``: per condition the trials, their outcomes and durations (s);
- ``failed``: participants whose run failed, with the error;

and ``DIR/report`` holds ``colosseum experiment report``'s summary and plots.
"""

from __future__ import annotations

import argparse
import itertools
import json
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

from app.runner import fail


def participant_run(path: str, participant: int, sessions: str, seed: int,
                    params: list[tuple[str, str]]) -> int:
    """One simulated participant's session (a Dask task); the exit code."""
    from app.experiments.cli import run
    from app.experiments.parser import RUN_FLAGS

    args = argparse.Namespace(
        path=path, participant=participant, resume=False, sessions=Path(sessions),
        stop_after=None, param=list(params), headless=True, fast=True, seed=seed,
        backend=None, mode="serial", dt=None, substeps=1, early="sleep", late="slowmo",
        max_dt=1.0 / 20.0, sound="null", size="640x480", render_scale=1.0, stereo=None,
        hud=False, xr=False, xr_mirror=None, xr_fallback=False, input=[], allow_path=[],
        progress=False)
    assert all(hasattr(args, flag) for flag in RUN_FLAGS)
    code = run(args)
    if code != 0:
        raise RuntimeError(f"participant {participant}: the run ended with exit code {code}")
    return code


def check_design(folder: Path) -> dict[str, Any]:
    """What an experiment's sessions show about its design (the module doc)."""
    from app.experiments.report import _sessions

    positions: dict[str, Counter[int]] = defaultdict(Counter)
    conditions: dict[str, dict[str, Any]] = {}
    factors: list[str] = []
    levels: list[list[str]] = []
    for session in _sessions(folder):
        meta = json.loads((session / "session.json").read_text(encoding="utf-8"))
        design = meta["design"]
        factors = [f["id"] for f in design["factors"] if f["within"]]
        levels = [f["levels"] for f in design["factors"] if f["within"]]
        from engine.experiments.session import read_rows

        for row in read_rows(session / "trials.csv"):
            if row["practice"] == "1" or not factors or not row.get(factors[0]):
                continue
            label = " ".join(f"{k}={row[k]}" for k in factors)
            if row["block"] == "1":
                positions[label][int(row["block_trial"])] += 1
            entry = conditions.setdefault(label, {"trials": 0, "outcomes": Counter(),
                                                  "durations": []})
            entry["trials"] += 1
            entry["outcomes"][row["outcome"]] += 1
            entry["durations"].append(float(row["end_s"]) - float(row["start_s"]))
    every = [" ".join(f"{k}={v}" for k, v in zip(factors, combo, strict=True))
             for combo in itertools.product(*levels)] if factors else []
    places = sorted({p for c in positions.values() for p in c})
    table = {label: [positions[label][p] for p in places] for label in every}
    counts = {n for row in table.values() for n in row}
    summary = {label: {"trials": c["trials"], "outcomes": dict(c["outcomes"]),
                       "duration_mean": sum(c["durations"]) / len(c["durations"]),
                       "duration_max": max(c["durations"])}
               for label, c in conditions.items()}
    return {"participants": len(_sessions(folder)), "positions": places,
            "counterbalance": table, "balanced": len(counts) == 1 and bool(table),
            "unreached": [label for label in every if label not in conditions],
            "conditions": summary}


def simulate(args: argparse.Namespace) -> int:
    """``colosseum sweep --participants``."""
    from app.experiments.cli import _design
    from app.experiments.report import report
    from app.sweep import SweepError, map_on_dask, parse_seeds

    try:
        participants = parse_seeds(args.participants)
    except SweepError as exc:
        return fail(str(exc).replace("--seeds", "--participants"))
    if min(participants) < 1:
        return fail("--participants: participant numbers start at 1")
    params = []
    for option in args.param:
        key, sep, value = option.partition("=")
        if not sep or "," in value:
            return fail(f"--param {option}: with --participants each KEY=VALUE is one value "
                        "every participant's run gets")
        params.append((key.strip(), value.strip()))
    design_args = argparse.Namespace(path=args.path, param=params, allow_path=[])
    found = _design(design_args)
    if isinstance(found, int):
        return found
    content, design = found
    out = Path(args.out).resolve()
    sessions = out / "sessions"
    sessions.mkdir(parents=True, exist_ok=True)
    calls = [(str(content.folder), p, str(sessions), 0, params) for p in participants]
    try:
        results = map_on_dask(participant_run, calls, args, "participants")
    except SweepError as exc:
        return fail(str(exc), 1)
    failed = {p: str(r) for p, r in zip(participants, results, strict=True)
              if isinstance(r, BaseException)}
    check = check_design(sessions / design.id) if (sessions / design.id).is_dir() else {}
    check["failed"] = failed
    (out / "design_check.json").write_text(json.dumps(check, indent=2) + "\n",
                                           encoding="utf-8")
    if (sessions / design.id).is_dir():
        report(sessions / design.id, out / "report")
    print(f"{len(participants) - len(failed)} of {len(participants)} participant(s) ran; "
          f"counterbalanced: {'yes' if check.get('balanced') else 'no'}; conditions never "
          f"met: {', '.join(check.get('unreached', [])) or 'none'}; {out / 'design_check.json'}")
    return 1 if failed else 0
