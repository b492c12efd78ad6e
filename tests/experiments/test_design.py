"""Designs: squares, plans, the block's check at its lines, and the counterbalancing goal
checked from the trials.csv files alone."""

from __future__ import annotations

import itertools
import json
from collections import Counter
from pathlib import Path

import pytest
from experiment_helpers import experiment, rows, write_content

from app.scene_loading import check_path
from engine.experiments.design import Design, Factor, plan
from engine.experiments.ordering import balanced_latin_square, latin_square


@pytest.mark.parametrize("n", range(2, 9))
def test_balanced_squares_balance_positions_and_neighbours(n: int):
    square = balanced_latin_square(n)
    assert len(square) == (n if n % 2 == 0 else 2 * n)
    reps = len(square) // n
    for position in range(n):
        assert Counter(row[position] for row in square) == {c: reps for c in range(n)}
    pairs = Counter((row[i], row[i + 1]) for row in square for i in range(n - 1))
    assert set(pairs.values()) == {reps} and len(pairs) == n * (n - 1)
    for row in latin_square(n):
        assert sorted(row) == list(range(n))


def test_plans_counterbalance_groups_and_repeat_for_a_participant():
    design = Design("d", (Factor("a", ("1", "2", "3")), Factor("g", ("x", "y"), within=False)),
                    order="latin", blocks=2, repeats=2, practice=2)
    one = plan(design, 1)
    assert one == plan(design, 1)  # a resumed session meets the same trials
    assert [t.block for t in one] == [0, 0] + [1] * 6 + [2] * 6
    assert all(t.practice for t in one[:2]) and not any(t.practice for t in one[2:])
    assert {t.condition["g"] for t in one} == {"x"}
    assert {t.condition["g"] for t in plan(design, 2)} == {"y"}
    # participants 1 and 2 are in different groups and take the square's first row; 3 and
    # 4 its second
    assert design.row(1) == design.row(2) == [0, 1, 2] and design.row(3) == [1, 2, 0]
    shuffled = Design("d", (Factor("a", tuple("abcdef")),), order="random", seed=7)
    orders = [[t.cell for t in plan(shuffled, p)] for p in (1, 2, 3)]
    assert orders[0] == [t.cell for t in plan(shuffled, 1)] and len({*map(tuple, orders)}) == 3


def test_the_block_is_checked_at_its_lines(tmp_path: Path, capsys):
    folder = write_content(tmp_path / "bad", """
  Factor { ID "blur" Levels [0 0.5 0.5] Variable "blurr" }
  Factor { ID "side" Levels ["none" "left"] Anomaly "hemianopia" Param "Sid" }
  Factor { ID "blur" Levels [1 2] }
  Factor { ID "grp" Levels ["a" "b"] Within 0 Anomaly "glare" }
  Staircase { ID "c" Min 1 Max 0.5 Step [0.1 -0.05] }
  Blocks 0
""", top="blur_level 0\nHemianopia { Enabled 0 }")
    assert check_path(folder, "json") == 1
    found = {(d["line"], d["message"]) for d in json.loads(capsys.readouterr().out)[
        "diagnostics"]}
    lines = {line for line, _ in found}
    # main.scene: lines 1-2 the top, 3-5 the ball, 6 Experiment {, 7 empty, then the keys
    at = {m: line for line, m in found}

    def line_of(part: str) -> int:
        return next(line for m, line in at.items() if part in m)

    assert line_of("level '0.5' given twice") == 8
    assert line_of("no scene variable 'blurr'") == 8
    assert line_of("anomaly 'hemianopia' (hemianopia) has no parameter 'Sid'") == 9
    assert line_of("a second factor or staircase 'blur'") == 10
    assert line_of("no anomaly 'glare'") == 11
    assert line_of("Step sizes must be positive") == 12
    assert line_of("Max 0.5 must be above Min 1") == 12
    assert line_of("Blocks must be at least 1") == 13 and lines <= set(range(8, 14))
    typo = write_content(tmp_path / "typo", '  Factor { ID "a" Levels [1 2] }\n  Order "sideways"')
    assert check_path(typo, "json") == 1
    told = json.loads(capsys.readouterr().out)["diagnostics"]
    assert [(d["line"], "sideways" in d["message"]) for d in told] == [(7, True)]


def test_keys_documents_the_blocks(capsys):
    from app.cli import main

    assert main(["keys", "Experiment"]) == 0
    out = capsys.readouterr().out
    for key in ("Factor", "Staircase", "Order", "Practice", "Reset", "Track", "TrackRate"):
        assert key in out
    assert main(["keys", "Staircase"]) == 0
    assert "Reversals" in capsys.readouterr().out


DESIGN_2x3 = """
  ID "latin"
  Factor { ID "hand" Levels ["left" "right"] }
  Factor { ID "blur" Levels [0 0.3 0.6] Anomaly "blur" Param "Acuity" }
  Order "balanced"
  Timeout 0.02
"""


def test_a_2x3_design_under_a_balanced_latin_square(in_tmp: Path):
    """Goal: 4 participants each take a row of the balanced square of the 6 cells, no
    position holds a condition twice; with the square's 6 rows done (participants 5 and 6)
    every condition stands in every position, and follows every other, exactly once.
    (With 6 conditions 4 participants cannot put each condition in each position equally
    often: each position holds 4 conditions.) Checked from the trials.csv files alone."""
    content = write_content(in_tmp / "latin", DESIGN_2x3, top="Blur { Enabled 0 }")
    cells = list(itertools.product(["left", "right"], ["0", "0.3", "0.6"]))
    square = balanced_latin_square(6)
    orders = {}
    for p in range(1, 7):
        assert experiment("run", str(content), "--participant", str(p), "--fast",
                          "--headless") == 0
        table = rows(in_tmp / "sessions" / "latin" / str(p) / "trials.csv")
        assert [int(r["trial"]) for r in table] == list(range(1, 7))
        assert {r["participant"] for r in table} == {str(p)}
        orders[p] = [cells.index((r["hand"], r["blur"])) for r in table]
        if p == 4:
            for p_ in range(1, 5):
                assert orders[p_] == square[p_ - 1]
            for position in range(6):
                assert len({orders[q][position] for q in range(1, 5)}) == 4
    for position in range(6):
        assert Counter(orders[q][position] for q in orders) == dict.fromkeys(range(6), 1)
    pairs = Counter((o[i], o[i + 1]) for o in orders.values() for i in range(5))
    assert len(pairs) == 30 and set(pairs.values()) == {1}
