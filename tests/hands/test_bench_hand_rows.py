"""``colosseum bench hands`` prints every fingered-hand figure at two steps (0.005 and
0.01 s) and on both backends, with the palm-only hand's beside it (issue 29): the plan
covers every (case, step, backend), the rows come out keyed by them, one table a kind."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest

from app.bench import fingers2d, hand_rows
from app.bench.hand_rows import BACKENDS, GROUPS, STEPS, plan, run_rows


def _keys(jobs: list[hand_rows.Job]) -> set[tuple[str, float, str]]:
    return {(case, job.step, job.backend) for job in jobs for case in job.cases}


def test_the_full_bench_plans_every_row_at_both_steps_on_both_backends():
    cases = [case for names, _ in GROUPS.values() for case in names]
    assert STEPS == (0.005, 0.01) and set(BACKENDS) == {"ode", "pymunk"}
    assert {"fingertips, 0.5 m/s", "palm, 1 m/s", "pinched ball, lifted",
            "index pushing a box", "pinched ball held still", "cup shaken 3 Hz +-10 cm",
            "right to left", "open hand, 3 m/s, 5 mm plate"} == set(cases)
    full = plan()
    assert _keys(full) == set(itertools.product(cases, STEPS, BACKENDS))
    assert len(full) == len(set((j.group, j.step, j.backend) for j in full))  # none twice
    quick = plan(quick=True)  # every case on both backends, at one step
    assert _keys(quick) == set(itertools.product(cases, (0.01,), BACKENDS))
    assert _keys(plan(backends=("pymunk",), only=("swipe",))) == {
        ("open hand, 3 m/s, 5 mm plate", step, "pymunk") for step in STEPS}


def test_rows_come_out_keyed_by_case_step_and_backend_beside_the_palm_only_hand(
        tmp_path: Path):
    rows = run_rows(tmp_path, only=("swipe",))
    assert {(r["case"], r["step s"], r["backend"]) for r in rows} == \
        _keys(plan(only=("swipe",)))
    for row in rows:
        assert row["kind"] == hand_rows.SWIPE
        # hands step at 1/120 s or finer: 0.01 s is two substeps of 0.005
        assert row["physics step s"] == pytest.approx(0.005)
        assert row["ok"] == "yes", row  # neither hand's centre reached the plate
        assert row["farthest mm"] < -2.5 and row["palm-only farthest mm"] < -2.5


def test_the_2d_hand_holds_a_pinched_ball_still_without_sinking_into_it(tmp_path: Path):
    """The pymunk rows' grip, at the 0.01 s step: lifted, held still, shallow contacts."""
    got = fingers2d.held_ball_2d(tmp_path, 100.0)
    assert got["held"] and got["jitter_rms_mm"] <= 0.1  # goal 0.5 mm (0.006 measured)
    assert len(got["depths"]) > 100 and max(got["depths"]) <= 0.0018  # goal 2 mm (1.55)
