"""The scene's ``Experiment`` block (and its ``Factor`` and ``Staircase``), declared on the
block registry, read into a checked :class:`Design`.

The schema checks the keys' types; this module checks what the design adds, each problem
at its line: levels (numbers or names, none twice), factor and staircase IDs (none
twice), what a factor sets (a scene variable the file defines, an anomaly the scene
declares or the vocabulary names, one of its parameters), a design that cannot be run
(no factor and no staircase; a Latin square of one cell; scene variables that vary while
the world is never reset), and a staircase's numbers (steps, bounds, rules). A scene
holds one ``Experiment`` (a second replaces the first); it is read by the block's finish
step, once every anomaly a factor may name is declared.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare
from engine.anomalies import ANOMALIES
from engine.experiments.design import END_ON, RESETS, Design, Factor
from engine.experiments.ordering import ORDERS
from engine.experiments.staircase import StaircaseSpec

#: An Experiment block's defaults are the design's (engine.experiments.design).
_DESIGN = Design("")
Values = Mapping[str, Any]


def _levels(value: Any, at: BuildContext) -> tuple[str, ...]:
    """A factor's ``Levels``: one number or name, or a vector of them (none twice)."""
    if isinstance(value, int | float | str):
        items: list[tuple[Any, int | None]] = [(value, None)]
    elif isinstance(value, tuple):
        items = [(item, i) for i, item in enumerate(value)]
    else:
        at.error("Levels", 'Levels are numbers [0 0.5 1] or names ["none" "left"]')
        return ()
    levels: list[str] = []
    for item, index in items:
        text = f"{item:g}" if isinstance(item, float) else str(item)
        if text in levels:
            at.error("Levels", f"level {text!r} given twice", item=index)
            continue
        levels.append(text)
    if not levels:
        at.error("Levels", "a factor needs at least one level")
    return tuple(levels)


def _line(at: BuildContext, key: str) -> int:
    """The line ``key`` is written at."""
    return int(at.where(key).rsplit(":", 1)[1])


class _Check:
    """The Experiment block being read: its values, what its factors may set, and how
    many problems were found (a design with any is not returned)."""

    def __init__(self, values: Values, ctx: BuildContext) -> None:
        self.values, self.ctx = values, ctx
        self.variables = ctx.variables()
        self.declared = {a.id: a.kind for a in ctx.scene("anomalies")}
        self.problems = 0
        self.seen: dict[str, int] = {}

    def error(self, at: BuildContext, key: str | None, message: str) -> None:
        self.problems += 1
        at.error(key, message)

    def new_id(self, r: Values, at: BuildContext) -> str | None:
        """A factor's or staircase's ID, None when missing (the schema told) or taken."""
        ident = str(r["ID"] or "")
        if not ident:
            return None
        if ident in self.seen:
            self.error(at, "ID", f"a second factor or staircase {ident!r} (the first is "
                       f"at line {self.seen[ident]})")
            return None
        self.seen[ident] = _line(at, "ID")
        return ident

    def target(self, r: Values, at: BuildContext, what: str) -> None:
        """Check what a factor or staircase sets: Variable, Anomaly, Param."""
        var, anomaly, param = r.get("Variable"), r.get("Anomaly"), r.get("Param")
        if var is not None and var not in self.variables:
            self.error(at, "Variable", f"{what}: no scene variable {var!r} (a lower-case "
                       f"key at the top of the scene; defined: "
                       f"{', '.join(sorted(self.variables)) or 'none'})")
        if var is not None and self.values["Reset"] == "never":
            self.error(at, "Variable", f"{what}: a scene variable takes effect when the "
                       "world is built, and Reset \"never\" builds it once; use Reset "
                       "\"trial\" or set the value from Lua (experiment:condition)")
        if anomaly is not None:
            self.anomaly_target(anomaly, param, at, what)
        elif param is not None:
            self.error(at, "Param", f"{what}: Param names a parameter of the factor's "
                       "Anomaly; give Anomaly too")

    def anomaly_target(self, anomaly: str, param: str | None, at: BuildContext,
                       what: str) -> None:
        kind = self.declared.get(anomaly, anomaly if anomaly in ANOMALIES else None)
        if kind is None:
            self.error(at, "Anomaly", f"{what}: no anomaly {anomaly!r} (declared: "
                       f"{', '.join(self.declared) or 'none'}; anomalies: "
                       f"{', '.join(ANOMALIES)})")
        elif param is not None:
            keys = [p.key for p in ANOMALIES[kind].params]
            if param not in keys:
                self.error(at, "Param", f"{what}: anomaly {anomaly!r} ({kind}) has no "
                           f"parameter {param!r} (it has {', '.join(keys)})")

    def factors(self) -> list[Factor]:
        factors: list[Factor] = []
        for r, at in self.ctx.inner("Factor"):
            fid = self.new_id(r, at)
            if fid is None:
                continue
            levels = _levels(r["Levels"], at) if at.given("Levels") else ()
            if not levels:
                self.problems += 1
                continue
            self.target(r, at, f"factor {fid!r}")
            factors.append(Factor(fid, levels, bool(r["Within"]), r["Variable"],
                                  r["Anomaly"], r["Param"]))
        return factors

    def staircases(self) -> list[StaircaseSpec]:
        stairs: list[StaircaseSpec] = []
        for r, at in self.ctx.inner("Staircase"):
            sid = self.new_id(r, at)
            if sid is None:
                continue
            steps = tuple(float(x) for x in r["Step"])
            self.staircase_numbers(sid, r, at, steps)
            self.target(r, at, f"staircase {sid!r}")
            stairs.append(StaircaseSpec(
                sid, float(r["Start"]), steps or (0.1,), int(r["Up"]), int(r["Down"]),
                int(r["Trials"]), int(r["Reversals"]), float(r["Min"]), float(r["Max"]),
                int(r["Average"]), str(r["Method"]), str(r["Response"]), float(r["Slope"]),
                float(r["Guess"]), float(r["Lapse"]), r["Variable"], r["Anomaly"],
                r["Param"]))
        return stairs

    def staircase_numbers(self, sid: str, r: Values, at: BuildContext,
                          steps: tuple[float, ...]) -> None:
        if not steps or any(s <= 0 for s in steps):
            self.error(at, "Step", f"staircase {sid!r}: Step sizes must be positive, got "
                       f"{list(steps)}")
        if r["Min"] >= r["Max"]:
            self.error(at, "Max", f"staircase {sid!r}: Max {r['Max']:g} must be above Min "
                       f"{r['Min']:g}")
        elif not r["Min"] <= r["Start"] <= r["Max"]:
            self.error(at, "Start", f"staircase {sid!r}: Start {r['Start']:g} is outside "
                       f"Min..Max ({r['Min']:g}..{r['Max']:g})")
        for key in ("Up", "Down", "Trials", "Average"):
            if r[key] < 1:
                self.error(at, key, f"staircase {sid!r}: {key} must be at least 1, got "
                           f"{r[key]}")
        if r["Reversals"] < 0:
            self.error(at, "Reversals", f"staircase {sid!r}: Reversals must not be negative")
        if r["Method"] == "quest" and not (0 <= r["Guess"] < 1 and 0 <= r["Lapse"] < 1
                                           and r["Guess"] + r["Lapse"] < 1):
            self.error(at, "Guess", f"staircase {sid!r}: Guess and Lapse are rates from 0 "
                       "with Guess + Lapse below 1")

    def design_numbers(self, factors: list[Factor], stairs: list[StaircaseSpec]) -> None:
        values, ctx = self.values, self.ctx
        if not factors and not stairs and self.problems == 0:
            self.error(ctx, None, "an Experiment needs a Factor or a Staircase")
        for key in ("Blocks", "Repeats"):
            if values[key] < 1:
                self.error(ctx, key, f"{key} must be at least 1, got {values[key]}")
        if values["Practice"] < 0:
            self.error(ctx, "Practice", f"Practice must not be negative, got "
                       f"{values['Practice']}")
        if values["Timeout"] <= 0:
            self.error(ctx, "Timeout", f"Timeout must be positive, got "
                       f"{values['Timeout']:g}")
        if values["TrackRate"] < 0:
            self.error(ctx, "TrackRate", "TrackRate must not be negative (0: every frame)")
        if values["Order"] in ("latin", "balanced") and factors and not any(
                f.within for f in factors):
            self.error(ctx, "Order", f"Order {values['Order']!r} orders the within factors' "
                       "cells, and every factor here is between participants")


def read_design(values: Values, ctx: BuildContext) -> Design | None:
    """The checked design of an ``Experiment`` block; None where a problem was told."""
    check = _Check(values, ctx)
    factors, stairs = check.factors(), check.staircases()
    check.design_numbers(factors, stairs)
    if check.problems:
        return None
    name = str(values["ID"] or Path(ctx.folder()).name)
    if Path(name).name != name or name.strip(".") == "":
        ctx.error("ID", f"the experiment's ID {name!r} names its sessions' folder: a name, "
                  "not a path")
        return None
    return Design(name, tuple(factors), tuple(stairs), str(values["Order"]),
                  int(values["Blocks"]), int(values["Repeats"]), int(values["Practice"]),
                  float(values["Timeout"]), str(values["Reset"]), str(values["EndOn"]),
                  int(values["Seed"]), tuple(values["Track"] or ()),
                  bool(values["TrackCamera"]), float(values["TrackRate"]),
                  float(values["Break"]), ctx.where(None))


def build_experiment(values: Values, ctx: BuildContext) -> list[Any]:
    """The block's values and context, for the finish step: a factor may name any
    anomaly the scene declares, so the design is read once all are."""
    return [(values, ctx)]


def finish_experiment(parts: list[Any], ctx: BuildContext) -> None:
    """The scene's design (the ``Experiment`` written last; the others are warned of)."""
    if parts:
        ctx.settle("experiment", read_design(*parts[-1]))


def _values_only(values: Values, ctx: BuildContext) -> list[Any]:
    """A block the Experiment around it reads (it builds nothing itself)."""
    return []


EXPERIMENT_BLOCK = declare(BlockDeclaration(
    "Experiment", inside=("Scene",), build=build_experiment, entity=False, once=True,
    finish=finish_experiment, doc="a study's design: factors and levels, blocks, "
    "counterbalancing, practice trials, staircases (colosseum experiment run; "
    "docs/experiments.md)", keys=(
        Key("ID", "string", "", "the experiment's name: sessions go to "
            "sessions/<ID>/<participant>/ (default: the content folder's name)",
            example='"reach"'),
        Key("Order", "enum", _DESIGN.order, "the order of the within cells: random (a seed "
            "per participant and block), latin (a Latin square's row by participant "
            "number), balanced (a balanced Latin square's), fixed (as declared)",
            allowed=ORDERS),
        Key("Blocks", "int", _DESIGN.blocks, "blocks; each holds every cell Repeats times"),
        Key("Repeats", "int", _DESIGN.repeats, "trials per cell in each block"),
        Key("Practice", "int", _DESIGN.practice, "practice trials before the first block "
            "(block 0, marked)"),
        Key("Timeout", "float", _DESIGN.timeout, "s of simulated time after which a trial "
            "ends with outcome \"timeout\""),
        Key("Reset", "enum", _DESIGN.reset, "trial: every trial starts from a freshly built "
            "world; never: one world runs through the session", allowed=RESETS),
        Key("EndOn", "enum", _DESIGN.end_on, "what ends a trial besides the timeout: finish "
            "(trial:finish(outcome)) or response (also the first trial:respond)",
            allowed=END_ON),
        Key("Seed", "int", _DESIGN.seed, "the design's seed: random orders come from it and "
            "the participant number"),
        Key("Track", "stringvector", None, "objects whose poses are logged each trial "
            "(tracking/trial-NNN.csv)", ref="Object", example='["wheelchair" "hand_r"]'),
        Key("TrackCamera", "bool", int(_DESIGN.track_camera), "1: log the active camera "
            "(the head) too"),
        Key("TrackRate", "float", _DESIGN.track_rate, "Hz of the tracking log (0: every "
            "frame)"),
        Key("Break", "float", _DESIGN.pause, "s of pause between blocks (none with --fast)"),
    )))
FACTOR_BLOCK = declare(BlockDeclaration(
    "ExperimentFactor", key="Factor", inside=("Experiment",), build=_values_only,
    repeat=True, doc="a factor and its levels", keys=(
        Key("ID", "string", None, "the factor's name (a trials.csv column; Lua "
            "experiment:condition(ID))", required=True, example='"blur"'),
        Key("Levels", "any", None, "its levels: numbers [0 0.5 1] or names "
            "[\"none\" \"left\"]", required=True, example="[0 0.3 0.6]"),
        Key("Within", "bool", 1, "1: every participant meets every level; 0: between "
            "participants, by participant number"),
        Key("Variable", "string", None, "a scene variable the level sets before the world "
            "is built (as --param)", example='"blur_level"'),
        Key("Anomaly", "string", None, "an anomaly the level switches: \"off\" or \"none\" "
            "off, any other level on", example='"blur"'),
        Key("Param", "string", None, "the Anomaly's parameter the level sets (Acuity, Side, "
            "Loss, ...)", example='"Acuity"'),
    )))
STAIRCASE_BLOCK = declare(BlockDeclaration(
    "Staircase", inside=("Experiment",), build=_values_only, repeat=True,
    doc="an adaptive procedure: one block of trials after the factorial ones", keys=(
        Key("ID", "string", None, "its name (a trials.csv column holding the intensity)",
            required=True, example='"contrast"'),
        Key("Method", "enum", "updown", "updown: a transformed up/down staircase; quest: a "
            "Bayesian (QUEST-style) one", allowed=("updown", "quest")),
        Key("Start", "float", 0.5, "the first trial's intensity"),
        Key("Step", "vector", (0.1,), "step sizes: the first, then one more after each "
            "reversal (the last kept)", example="[0.1 0.05 0.02]"),
        Key("Down", "int", 3, "correct answers in a row that lower the intensity"),
        Key("Up", "int", 1, "wrong answers in a row that raise it"),
        Key("Trials", "int", 40, "at most this many trials"),
        Key("Reversals", "int", 0, "stop after this many reversals (0: after Trials)"),
        Key("Average", "int", 6, "the threshold is the mean of the last this many "
            "reversals"),
        Key("Min", "float", 0.0, "the lowest intensity"),
        Key("Max", "float", 1.0, "the highest intensity"),
        Key("Response", "string", "seen", "the response (trial:respond(name, value)) whose "
            "true value is a correct answer"),
        Key("Slope", "float", 10.0, "quest: the logistic psychometric function's slope "
            "(per unit of intensity)"),
        Key("Guess", "float", 0.0, "quest: the guess rate"),
        Key("Lapse", "float", 0.01, "quest: the lapse rate"),
        Key("Variable", "string", None, "a scene variable the intensity sets",
            example='"loss"'),
        Key("Anomaly", "string", None, "an anomaly switched on at the intensity",
            example='"contrast_loss"'),
        Key("Param", "string", None, "the Anomaly's parameter the intensity sets",
            example='"Loss"'),
    )))
