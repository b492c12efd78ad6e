"""content/stroke's study: its design as planned, and its first trial run in the engine."""

from __future__ import annotations

import json
from pathlib import Path

from experiment_helpers import experiment, rows

from app.scene_loading import load_content_scene
from engine.experiments.design import plan
from engine.experiments.ordering import balanced_latin_square

STROKE = Path(__file__).resolve().parents[2] / "content" / "stroke"


def test_the_stroke_design_counterbalances_six_conditions_after_practice():
    from engine.content import resolve

    design = load_content_scene(resolve(str(STROKE)), seed=0).spec.experiment
    assert design is not None and design.id == "stroke"
    cells = [(c["anomaly"], c["severity"]) for c in design.cells()]
    assert len(cells) == 6 and design.order == "balanced"
    for p, row in enumerate(balanced_latin_square(6), start=1):
        trials = plan(design, p)
        assert [t.practice for t in trials] == [True, True] + [False] * 6
        assert [t.cell for t in trials[2:]] == row
    (stair,) = design.staircases
    assert (stair.anomaly, stair.param, stair.down, stair.up) == ("contrast_loss", "Loss", 3, 1)


def test_a_stroke_trial_runs_under_its_condition(in_tmp: Path):
    assert experiment("run", str(STROKE), "--participant", "1", "--fast", "--headless",
                      "--param", "trial_seconds=0.2", "--stop-after", "1") == 0
    folder = in_tmp / "sessions" / "stroke" / "1"
    (row,) = rows(folder / "trials.csv")
    assert (row["practice"], row["anomaly"], row["severity"], row["outcome"]) == \
        ("1", "hemianopia", "mild", "timeout")
    track = (folder / "tracking" / "trial-001.csv").read_text().splitlines()
    assert {line.split(",")[2] for line in track[1:]} == {"wheelchair", "right hand",
                                                         "left hand", "head"}
    (log,) = (folder / "logs").glob("stroke-*.jsonl")
    switched = [r for r in map(json.loads, log.read_text().splitlines())
                if r["kind"] == "anomaly" and r["name"] == "hemianopia" and r["on"]]
    assert switched and switched[-1]["Sparing"] == 10 and switched[-1]["Depth"] == 0.7
    # the run stopped after one trial; --resume goes on with the second
    assert experiment("run", str(STROKE), "--participant", "1", "--fast", "--headless",
                      "--param", "trial_seconds=0.2", "--stop-after", "1", "--resume") == 0
    assert [r["severity"] for r in rows(folder / "trials.csv")] == ["mild", "severe"]
