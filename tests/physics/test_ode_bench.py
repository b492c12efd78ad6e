"""The physics benchmark compares like with like: its C reference and our backend
simulate the same scene to the last bit (so the ratio measures overhead only)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

pytest.importorskip("engine.physics.ode3d")
bench = pytest.importorskip("tools.bench_physics")

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")


def test_reference_and_backend_simulate_the_same_boxes(tmp_path: Path) -> None:
    exe = bench.compile_reference(tmp_path)
    for sleep in (False, True):
        _, c_z = bench.run_reference(exe, 30, 90, sleep, feedback=True)
        _, ours_z = bench.time_ours(30, 90, sleep, sync=True)
        assert ours_z == pytest.approx(c_z, abs=1e-6)


def test_run_bench_reports_every_case(capsys: pytest.CaptureFixture[str]) -> None:
    rows = bench.run_bench(ns=(20,), steps=3, repeats=1)
    assert [(r["N"], r["sleeping"]) for r in rows] == [(20, "off"), (20, "on")]
    for r in rows:
        assert r["C ms"] > 0 and r["ours+sync ms"] > 0
        assert r["ratio+sync"] == pytest.approx(r["ours+sync ms"] / r["C ms"])
    assert "N=20" in capsys.readouterr().out
