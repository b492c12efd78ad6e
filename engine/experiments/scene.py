"""The scene's ``Experiment`` block as a checked :class:`Design`.

The schema checks the keys' types; this module checks what the design adds, each problem
at its line: levels (numbers or names, none twice), factor and staircase IDs (none
twice), what a factor sets (a scene variable the file defines, an anomaly the scene
declares or the vocabulary names, one of its parameters), a design that cannot be run
(no factor and no staircase; a Latin square of one cell; scene variables that vary while
the world is never reset), and a staircase's numbers (steps, bounds, rules).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import engine.scene.schema as sc
from engine.anomalies import ANOMALIES, AnomalySpec
from engine.experiments.design import Design, Factor
from engine.experiments.staircase import StaircaseSpec
from engine.scene.db import FLOAT, INT, STRING, STRINGVECTOR, VECTOR, Block, Value
from engine.scene.diagnostics import Loc, Reporter


def _values(block: Block, schema: str) -> tuple[dict[str, Any], dict[str, Value]]:
    """The block's keys as plain values over the schema's defaults, and what was written."""
    written = {e.key: e.value for e in block}
    values = {key: f.default for key, f in sc.SCHEMAS[schema].items()}
    values.update({key: v.py() for key, v in written.items()})
    return values, written


def _levels(value: Value, report: Reporter) -> tuple[str, ...]:
    if value.kind in (INT, FLOAT) or value.kind == STRING:
        items = [value]
    elif value.kind in (VECTOR, STRINGVECTOR):
        items = list(value.data)
    else:
        report.error(value.loc, 'Levels are numbers [0 0.5 1] or names ["none" "left"]')
        return ()
    levels = []
    for item in items:
        text = f"{item.data:g}" if isinstance(item.data, float) else str(item.data)
        if text in levels:
            report.error(item.loc, f"level {text!r} given twice")
            continue
        levels.append(text)
    if not levels:
        report.error(value.loc, "a factor needs at least one level")
    return tuple(levels)


def read_experiment(root: Block, report: Reporter, anomalies: list[AnomalySpec],
                    folder: Path | None) -> Design | None:
    """The scene's ``Experiment`` block (the last one), or None without one; problems go
    to ``report``."""
    blocks = root.blocks("Experiment")
    if not blocks:
        return None
    block = blocks[-1]
    values, written = _values(block, "Experiment")
    where = {key: v.loc for key, v in written.items()}
    variables = {e.key for e in root if e.key[:1].islower()}
    declared = {a.id: a.kind for a in anomalies}
    problems = [0]

    def error(loc: Loc, message: str) -> None:
        problems[0] += 1
        report.error(loc, message)

    def target(r: dict[str, Any], w: dict[str, Value], loc: Loc, what: str) -> None:
        """Check what a factor or staircase sets: Variable, Anomaly, Param."""
        var, anomaly, param = r.get("Variable"), r.get("Anomaly"), r.get("Param")
        if var is not None and var not in variables:
            close = sorted(variables)
            error(w["Variable"].loc, f"{what}: no scene variable {var!r} (a lower-case key "
                  f"at the top of the scene; defined: {', '.join(close) or 'none'})")
        if var is not None and values["Reset"] == "never":
            error(w["Variable"].loc, f"{what}: a scene variable takes effect when the world "
                  "is built, and Reset \"never\" builds it once; use Reset \"trial\" or set "
                  "the value from Lua (experiment:condition)")
        if anomaly is not None:
            kind = declared.get(anomaly, anomaly if anomaly in ANOMALIES else None)
            if kind is None:
                error(w["Anomaly"].loc, f"{what}: no anomaly {anomaly!r} (declared: "
                      f"{', '.join(declared) or 'none'}; anomalies: {', '.join(ANOMALIES)})")
            elif param is not None:
                keys = [p.key for p in ANOMALIES[kind].params]
                if param not in keys:
                    error(w["Param"].loc, f"{what}: anomaly {anomaly!r} ({kind}) has no "
                          f"parameter {param!r} (it has {', '.join(keys)})")
        elif param is not None:
            error(w["Param"].loc, f"{what}: Param names a parameter of the factor's Anomaly; "
                  "give Anomaly too")

    factors: list[Factor] = []
    seen: dict[str, Loc] = {}
    for fb in block.blocks("Factor"):
        r, w = _values(fb, "ExperimentFactor")
        fid = str(r["ID"] or "")
        if not fid:
            continue  # the schema told the missing ID
        if fid in seen:
            error(w["ID"].loc, f"a second factor or staircase {fid!r} (the first is at line "
                  f"{seen[fid].line})")
            continue
        seen[fid] = w["ID"].loc
        levels = _levels(w["Levels"], report) if "Levels" in w else ()
        if not levels:
            problems[0] += 1
            continue
        target(r, w, fb.loc, f"factor {fid!r}")
        factors.append(Factor(fid, levels, bool(r["Within"]), r["Variable"], r["Anomaly"],
                              r["Param"]))

    stairs: list[StaircaseSpec] = []
    for sb in block.blocks("Staircase"):
        r, w = _values(sb, "Staircase")
        sid = str(r["ID"] or "")
        if not sid:
            continue
        if sid in seen:
            error(w["ID"].loc, f"a second factor or staircase {sid!r} (the first is at line "
                  f"{seen[sid].line})")
            continue
        seen[sid] = w["ID"].loc
        at = {key: v.loc for key, v in w.items()}
        steps = tuple(float(x) for x in r["Step"])
        if not steps or any(s <= 0 for s in steps):
            error(at.get("Step", sb.loc), f"staircase {sid!r}: Step sizes must be positive, "
                  f"got {list(steps)}")
        if r["Min"] >= r["Max"]:
            error(at.get("Max", sb.loc), f"staircase {sid!r}: Max {r['Max']:g} must be above "
                  f"Min {r['Min']:g}")
        elif not r["Min"] <= r["Start"] <= r["Max"]:
            error(at.get("Start", sb.loc), f"staircase {sid!r}: Start {r['Start']:g} is "
                  f"outside Min..Max ({r['Min']:g}..{r['Max']:g})")
        for key in ("Up", "Down", "Trials", "Average"):
            if r[key] < 1:
                error(at.get(key, sb.loc), f"staircase {sid!r}: {key} must be at least 1, "
                      f"got {r[key]}")
        if r["Reversals"] < 0:
            error(at["Reversals"], f"staircase {sid!r}: Reversals must not be negative")
        if r["Method"] == "quest" and not (0 <= r["Guess"] < 1 and 0 <= r["Lapse"] < 1
                                           and r["Guess"] + r["Lapse"] < 1):
            error(at.get("Guess", sb.loc), f"staircase {sid!r}: Guess and Lapse are rates "
                  "from 0 with Guess + Lapse below 1")
        target(r, w, sb.loc, f"staircase {sid!r}")
        stairs.append(StaircaseSpec(
            sid, float(r["Start"]), steps or (0.1,), int(r["Up"]), int(r["Down"]),
            int(r["Trials"]), int(r["Reversals"]), float(r["Min"]), float(r["Max"]),
            int(r["Average"]), str(r["Method"]), str(r["Response"]), float(r["Slope"]),
            float(r["Guess"]), float(r["Lapse"]), r["Variable"], r["Anomaly"], r["Param"]))

    if not factors and not stairs and problems[0] == 0:
        error(block.loc, "an Experiment needs a Factor or a Staircase")
    for key in ("Blocks", "Repeats"):
        if values[key] < 1:
            error(where[key], f"{key} must be at least 1, got {values[key]}")
    if values["Practice"] < 0:
        error(where["Practice"], f"Practice must not be negative, got {values['Practice']}")
    if values["Timeout"] <= 0:
        error(where["Timeout"], f"Timeout must be positive, got {values['Timeout']:g}")
    if values["TrackRate"] < 0:
        error(where["TrackRate"], "TrackRate must not be negative (0: every frame)")
    within = [f for f in factors if f.within]
    if values["Order"] in ("latin", "balanced") and factors and not within:
        error(where.get("Order", block.loc), f"Order {values['Order']!r} orders the within "
              "factors' cells, and every factor here is between participants")
    if problems[0]:
        return None
    name = str(values["ID"] or (folder.name if folder is not None else "experiment"))
    if Path(name).name != name or name.strip(".") == "":
        report.error(where.get("ID", block.loc), f"the experiment's ID {name!r} names its "
                     "sessions' folder: a name, not a path")
        return None
    return Design(name, tuple(factors), tuple(stairs), str(values["Order"]),
                  int(values["Blocks"]), int(values["Repeats"]), int(values["Practice"]),
                  float(values["Timeout"]), str(values["Reset"]), str(values["EndOn"]),
                  int(values["Seed"]), tuple(values["Track"] or ()),
                  bool(values["TrackCamera"]), float(values["TrackRate"]),
                  float(values["Break"]), f"{block.loc.path}:{block.loc.line}")
