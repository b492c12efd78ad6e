"""The physics benchmark compares like with like: its C reference and our backend
simulate the same scene to the last bit, and with sleeping on put the same boxes to sleep
(both run the engine's sleep rule), so the ratio measures overhead only."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from app.bench.readback import EcsReadback, pose_table

pytest.importorskip("engine.physics.ode3d")
bench = pytest.importorskip("app.bench.physics")

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")


def test_reference_and_backend_simulate_the_same_boxes(tmp_path: Path) -> None:
    exe = bench.compile_reference(tmp_path)
    for n, steps, sleep in ((30, 90, False), (30, 90, True), (3, 300, True)):
        _, c_z, c_asleep = bench.run_reference(exe, n, steps, sleep, feedback=True)
        _, ours_z, ours_asleep = bench.time_ours(n, steps, sleep, sync=True)
        assert ours_z == pytest.approx(c_z, abs=1e-6)
        assert ours_asleep == c_asleep
    assert c_asleep == 3  # the short stack fell asleep, on both sides


def test_run_bench_reports_every_case(capsys: pytest.CaptureFixture[str]) -> None:
    rows = bench.run_bench(ns=(20,), steps=3, repeats=1)
    steps = [r for r in rows if "sleeping" in r]
    assert [(r["N"], r["sleeping"]) for r in steps] == [(20, "off"), (20, "on")]
    for r in steps:
        assert r["C ms"] > 0 and r["ours+sync ms"] > 0
        assert r["ratio+sync"] == pytest.approx(r["ours+sync ms"] / r["C ms"])
    (readback,) = [r for r in rows if "sleeping" not in r]
    assert readback["N"] == 20 and readback["read_state_into us"] > 0
    assert readback["new/old"] == pytest.approx(
        readback["read_state_into us"] / readback["read_state+copy us"])
    assert readback["sleep rule us"] > 0
    assert "N=20" in capsys.readouterr().out


def test_the_ecs_readback_leaves_the_pose_table_as_a_state_read_would() -> None:
    backend = bench.build_ours(30, False)
    for _ in range(20):
        backend.step(bench.DT)
    poses = pose_table(backend.keys())
    EcsReadback(backend, poses)()
    state = backend.read_state()
    np.testing.assert_array_equal(poses.table[poses.rows(state.keys)], state.table)
