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


class _Check:
    """One Experiment block being read: its values, what its factors may set, and how
    many problems were found (a design with any is not returned)."""

    def __init__(self, root: Block, block: Block, report: Reporter,
                 anomalies: list[AnomalySpec]) -> None:
        self.block, self.report = block, report
        self.values, written = _values(block, "Experiment")
        self.where = {key: v.loc for key, v in written.items()}
        self.variables = {e.key for e in root if e.key[:1].islower()}
        self.declared = {a.id: a.kind for a in anomalies}
        self.problems = 0
        self.seen: dict[str, Loc] = {}

    def error(self, loc: Loc, message: str) -> None:
        self.problems += 1
        self.report.error(loc, message)

    def new_id(self, r: dict[str, Any], w: dict[str, Value]) -> str | None:
        """A factor's or staircase's ID, None when missing (the schema told) or taken."""
        ident = str(r["ID"] or "")
        if not ident:
            return None
        if ident in self.seen:
            self.error(w["ID"].loc, f"a second factor or staircase {ident!r} (the first is "
                       f"at line {self.seen[ident].line})")
            return None
        self.seen[ident] = w["ID"].loc
        return ident

    def target(self, r: dict[str, Any], w: dict[str, Value], what: str) -> None:
        """Check what a factor or staircase sets: Variable, Anomaly, Param."""
        var, anomaly, param = r.get("Variable"), r.get("Anomaly"), r.get("Param")
        if var is not None and var not in self.variables:
            self.error(w["Variable"].loc, f"{what}: no scene variable {var!r} (a lower-case "
                       f"key at the top of the scene; defined: "
                       f"{', '.join(sorted(self.variables)) or 'none'})")
        if var is not None and self.values["Reset"] == "never":
            self.error(w["Variable"].loc, f"{what}: a scene variable takes effect when the "
                       "world is built, and Reset \"never\" builds it once; use Reset "
                       "\"trial\" or set the value from Lua (experiment:condition)")
        if anomaly is not None:
            self.anomaly_target(anomaly, param, w, what)
        elif param is not None:
            self.error(w["Param"].loc, f"{what}: Param names a parameter of the factor's "
                       "Anomaly; give Anomaly too")

    def anomaly_target(self, anomaly: str, param: str | None, w: dict[str, Value],
                       what: str) -> None:
        kind = self.declared.get(anomaly, anomaly if anomaly in ANOMALIES else None)
        if kind is None:
            self.error(w["Anomaly"].loc, f"{what}: no anomaly {anomaly!r} (declared: "
                       f"{', '.join(self.declared) or 'none'}; anomalies: "
                       f"{', '.join(ANOMALIES)})")
        elif param is not None:
            keys = [p.key for p in ANOMALIES[kind].params]
            if param not in keys:
                self.error(w["Param"].loc, f"{what}: anomaly {anomaly!r} ({kind}) has no "
                           f"parameter {param!r} (it has {', '.join(keys)})")

    def factors(self) -> list[Factor]:
        factors: list[Factor] = []
        for fb in self.block.blocks("Factor"):
            r, w = _values(fb, "ExperimentFactor")
            fid = self.new_id(r, w)
            if fid is None:
                continue
            levels = _levels(w["Levels"], self.report) if "Levels" in w else ()
            if not levels:
                self.problems += 1
                continue
            self.target(r, w, f"factor {fid!r}")
            factors.append(Factor(fid, levels, bool(r["Within"]), r["Variable"],
                                  r["Anomaly"], r["Param"]))
        return factors

    def staircases(self) -> list[StaircaseSpec]:
        stairs: list[StaircaseSpec] = []
        for sb in self.block.blocks("Staircase"):
            r, w = _values(sb, "Staircase")
            sid = self.new_id(r, w)
            if sid is None:
                continue
            steps = tuple(float(x) for x in r["Step"])
            self.staircase_numbers(sid, r, {key: v.loc for key, v in w.items()}, sb.loc,
                                   steps)
            self.target(r, w, f"staircase {sid!r}")
            stairs.append(StaircaseSpec(
                sid, float(r["Start"]), steps or (0.1,), int(r["Up"]), int(r["Down"]),
                int(r["Trials"]), int(r["Reversals"]), float(r["Min"]), float(r["Max"]),
                int(r["Average"]), str(r["Method"]), str(r["Response"]), float(r["Slope"]),
                float(r["Guess"]), float(r["Lapse"]), r["Variable"], r["Anomaly"],
                r["Param"]))
        return stairs

    def staircase_numbers(self, sid: str, r: dict[str, Any], at: dict[str, Loc],
                          loc: Loc, steps: tuple[float, ...]) -> None:
        if not steps or any(s <= 0 for s in steps):
            self.error(at.get("Step", loc), f"staircase {sid!r}: Step sizes must be "
                       f"positive, got {list(steps)}")
        if r["Min"] >= r["Max"]:
            self.error(at.get("Max", loc), f"staircase {sid!r}: Max {r['Max']:g} must be "
                       f"above Min {r['Min']:g}")
        elif not r["Min"] <= r["Start"] <= r["Max"]:
            self.error(at.get("Start", loc), f"staircase {sid!r}: Start {r['Start']:g} is "
                       f"outside Min..Max ({r['Min']:g}..{r['Max']:g})")
        for key in ("Up", "Down", "Trials", "Average"):
            if r[key] < 1:
                self.error(at.get(key, loc), f"staircase {sid!r}: {key} must be at least "
                           f"1, got {r[key]}")
        if r["Reversals"] < 0:
            self.error(at["Reversals"], f"staircase {sid!r}: Reversals must not be negative")
        if r["Method"] == "quest" and not (0 <= r["Guess"] < 1 and 0 <= r["Lapse"] < 1
                                           and r["Guess"] + r["Lapse"] < 1):
            self.error(at.get("Guess", loc), f"staircase {sid!r}: Guess and Lapse are rates "
                       "from 0 with Guess + Lapse below 1")

    def design_numbers(self, factors: list[Factor], stairs: list[StaircaseSpec]) -> None:
        values, where = self.values, self.where
        if not factors and not stairs and self.problems == 0:
            self.error(self.block.loc, "an Experiment needs a Factor or a Staircase")
        for key in ("Blocks", "Repeats"):
            if values[key] < 1:
                self.error(where[key], f"{key} must be at least 1, got {values[key]}")
        if values["Practice"] < 0:
            self.error(where["Practice"], f"Practice must not be negative, got "
                       f"{values['Practice']}")
        if values["Timeout"] <= 0:
            self.error(where["Timeout"], f"Timeout must be positive, got "
                       f"{values['Timeout']:g}")
        if values["TrackRate"] < 0:
            self.error(where["TrackRate"], "TrackRate must not be negative (0: every frame)")
        if values["Order"] in ("latin", "balanced") and factors and not any(
                f.within for f in factors):
            self.error(where.get("Order", self.block.loc), f"Order {values['Order']!r} "
                       "orders the within factors' cells, and every factor here is between "
                       "participants")


def read_experiment(root: Block, report: Reporter, anomalies: list[AnomalySpec],
                    folder: Path | None) -> Design | None:
    """The scene's ``Experiment`` block (the last one), or None without one; problems go
    to ``report``."""
    blocks = root.blocks("Experiment")
    if not blocks:
        return None
    block = blocks[-1]
    check = _Check(root, block, report, anomalies)
    factors, stairs = check.factors(), check.staircases()
    check.design_numbers(factors, stairs)
    if check.problems:
        return None
    values, where = check.values, check.where
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
