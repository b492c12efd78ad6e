"""``colosseum bench pareto`` (app/bench/pareto.py): its plain-libode reference is libode
without the engine's step, its rows say what each engine costs beside how accurate it is,
and the frontier keeps only the settings nothing beats on both."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from engine.physics.backend import WorldSettings
from engine.physics.sleep import SLEEP_ANGULAR, SLEEP_LINEAR, SLEEP_TIME, SMOOTHING, STEADY_SHARE

pytest.importorskip("engine.physics.ode3d")
pareto = pytest.importorskip("app.bench.pareto")

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")


def test_the_frontier_keeps_what_nothing_beats_on_cost_and_error() -> None:
    points = [(3.0, 0.5), (1.0, 2.0), (2.0, 2.5), (4.0, 0.1), (2.5, 0.5), (5.0, 0.1)]
    assert pareto.frontier(points) == [(1.0, 2.0), (2.5, 0.5), (4.0, 0.1)]


def test_plain_libode_is_stepped_without_the_engine_s_policy(tmp_path: Path) -> None:
    """The same short column, sleeping asked for: with the engine's step (stepper.h) the
    sleep rule puts it to sleep; plain QuickStep has no sleep rule, nor any other policy."""
    exe = pareto.compile_reference(tmp_path)
    w = WorldSettings()
    asleep = []
    for policy in (1, 0):
        out = subprocess.run([str(exe), "3", "300", "1", "1", *map(repr, (
            SLEEP_TIME, SLEEP_LINEAR, SLEEP_ANGULAR, STEADY_SHARE, SMOOTHING)),
            str(w.iterations), repr(w.erp), repr(w.cfm), repr(w.warm_start),
            repr(w.contact_softness), str(w.exact_rows), str(policy), repr(1 / 60)],
            check=True, capture_output=True, text=True).stdout
        fields = dict(item.split("=") for item in out.split())
        assert float(fields["mean_z"]) == pytest.approx(1.5, abs=0.02)  # standing
        assert int(fields["contacts"]) >= (0 if policy else 8)  # asleep: none made
        asleep.append(int(fields["asleep"]))
    assert asleep == [3, 0]
    assert pareto.time_libode(exe, 30, 1 / 60, 60, 5, policy=False)["ms"] > 0


def test_at_the_default_settings_every_goal_holds_on_ode() -> None:
    got = pareto.accuracy("ode", 20, 0.01)
    assert got["worst/goal"] <= 1.0, got
    assert got["stack drift mm"] <= 10.0


def test_a_quick_run_has_every_table_and_a_plot(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(pareto, "installed", lambda module: False)  # ours and libode only
    monkeypatch.setattr(pareto, "ITERATIONS", (5,))
    rows = [*pareto.grid(pareto.compile_reference(tmp_path), (20,), (5,), (0.02,), 0.2),
            *pareto.price_of_policy(pareto.compile_reference(tmp_path), (20,), 0.2, 1)]
    engines = {r["engine"] for r in rows if r["table"] == "frontier"}
    assert engines == {"ode", "pymunk", "libode plain", "libode+stepper.h"}
    ode = next(r for r in rows if r.get("engine") == "ode")
    assert ode["ms/sim s 20"] == pytest.approx(ode["ms/step 20"] / 0.02)
    assert ode["worst/goal"] == max(v for k, v in ode.items() if k.endswith("/goal"))
    policy = [r for r in rows if r["table"] == "price of the policy"]
    assert {r["variant"] for r in policy} >= {"policies on, sleeping off", "libode+stepper.h"}
    data = {"rows": rows, "machine": {"platform": "test"}, "date": "2026-01-01"}
    path = pareto.plot(json.loads(json.dumps(data)), tmp_path / "pareto.png")
    assert path.stat().st_size > 1000


def test_mujoco_is_compared_sleeping_beside_ours_sleeping() -> None:
    """Ours with its sleeping on is set beside MuJoCo with its own sleeping on, not beside
    MuJoCo awake: where MuJoCo can sleep, its settled boxes do fall asleep."""
    pytest.importorskip("mujoco")
    if not pareto.mujoco_sleeps():
        pytest.skip("this MuJoCo has no sleeping")
    assert pareto.time_mujoco(20, 1 / 60, 180, sleep=True)["asleep"] == 20
    assert pareto.time_mujoco(20, 1 / 60, 180)["asleep"] == 0
    rows = pareto.versus_mujoco((20,), 0.5, 1)
    assert [(r["ours"], r["mujoco"]) for r in rows] == [
        ("ours", "mujoco"), ("ours sleeping", "mujoco sleeping")]
    assert all(r["faster by"] > 0 for r in rows)


@pytest.mark.parametrize("engine", ["ours", "mujoco"])
def test_a_settled_scene_asleep_costs_less_than_awake_on_either_engine(engine: str) -> None:
    if engine == "mujoco":
        pytest.importorskip("mujoco")
        if not pareto.mujoco_sleeps():
            pytest.skip("this MuJoCo has no sleeping")
    (row,) = pareto.asleep_vs_awake(30, 1, settle=4.0, engine=engine)
    assert row["engine"] == engine and 0 < row["all asleep at s"] < 4.0
    assert row["asleep ms/step"] < 0.5 * row["awake ms/step"]
