"""colosseum sweep: runs on a 2-worker Dask LocalCluster give the numbers the same runs
give alone; a bad parameter is told before anything runs; a worker that dies is retried
once, then reported, and the other runs are kept."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.net.net_helpers import ROOT

SCENE = """drop 2.0
bounce 0.5
World { TimeStep 1/60 }
Material { ID "rubber" Bounce bounce Friction 0.4 }
Object { ID "ground" Dynamic 0
  PhysicalAttributes { Material "rubber" Geometry { Primitive "plane" } } }
Object { ID "ball" Position [randInterval(-0.5, 0.5) 0 drop] Velocity [randNormal(0, 1) 0 0]
  Size [0.2] PhysicalAttributes { Mass 1 Material "rubber" Geometry { Primitive "sphere" } } }
Measure { ID "height" Object "ball" Value "z" }
Measure { ID "speed" Object "ball" Value "speed" }
Measure { ID "x" Object "ball" Value "x" }
Script "scripts/count.lua"
"""
SCRIPT = """bounces = 0
function onCollisionBegin(a, b, impulse) bounces = bounces + 1 end
function onUpdate(dt) measure("bounces", bounces) end
"""


def content(tmp_path: Path, crash_seed: int | None = None) -> Path:
    folder = tmp_path / "balls"
    (folder / "scripts").mkdir(parents=True)
    (folder / "main.scene").write_text(SCENE)
    (folder / "scripts" / "count.lua").write_text(SCRIPT)
    if crash_seed is not None:  # a simulation that takes its process down
        (folder / "systems").mkdir()
        (folder / "systems" / "crash.py").write_text(
            "import os\nfrom pathlib import Path\n\n\ndef build(engine):\n"
            f"    if engine.config.seed == {crash_seed}:\n"
            "        with (Path(__file__).parents[1] / 'attempts').open('a') as f:\n"
            "            f.write('x')\n"
            "        os._exit(3)\n")
    return folder


def colosseum(*args: object, timeout: float = 180) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "app.cli", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


def table(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.slow
def test_a_sweep_equals_the_same_runs_alone(tmp_path: Path) -> None:
    folder = content(tmp_path)
    done = colosseum("sweep", folder, "--param", "bounce=0.2,0.8", "--seeds", "0..3",
                     "--frames", 90, "--out", tmp_path / "out", "--workers", 2)
    assert done.returncode == 0, done.stderr
    rows = table(tmp_path / "out" / "results.csv")
    assert len(rows) == 8 and not any(r["error"] for r in rows)
    assert (tmp_path / "out" / "results.png").stat().st_size > 1000
    for row in rows:
        stats = tmp_path / f"{row['bounce']}-{row['seed']}.json"
        alone = colosseum("run", folder, "--frames", 90, "--fast", "--headless", "--seed",
                          row["seed"], "--param", f"bounce={row['bounce']}", "--stats", stats)
        assert alone.returncode == 0, alone.stderr
        ran = json.loads(stats.read_text())
        for name in ("height", "speed", "x", "bounces"):
            assert float(row[name]) == ran["measures"][name], (row, name)  # bit for bit
        assert int(row["contacts"]) == ran["contacts"]
    assert len({r["x"] for r in rows}) == 8  # each seed starts elsewhere (randInterval...)


def test_a_parameter_the_scene_lacks_is_told_before_running(tmp_path: Path) -> None:
    done = colosseum("sweep", content(tmp_path), "--param", "bounse=0.2", "--frames", 10,
                     "--out", tmp_path / "out")
    assert done.returncode == 2
    assert "no scene variable 'bounse'" in done.stderr and "did you mean 'bounce'" in \
        done.stderr, done.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_a_dying_worker_is_retried_once_then_reported(tmp_path: Path) -> None:
    done = colosseum("sweep", content(tmp_path, crash_seed=2), "--seeds", "0..3", "--frames",
                     30, "--out", tmp_path / "out", "--workers", 2)
    assert done.returncode == 1, done.stderr
    rows = table(tmp_path / "out" / "results.csv")
    assert [bool(r["error"]) for r in rows] == [False, False, True, False]
    assert "worker died" in rows[2]["error"]
    assert (tmp_path / "balls" / "attempts").read_text() == "xx"  # tried once more
    assert all(r["height"] for r in rows if not r["error"])
    assert "Traceback" not in done.stderr and "rescheduling" not in done.stderr, done.stderr


def test_a_scheduler_that_is_not_there_is_told(tmp_path: Path) -> None:
    done = colosseum("sweep", content(tmp_path), "--frames", 10, "--out", tmp_path / "out",
                     "--scheduler", "nowhere")
    assert done.returncode == 1, done.stderr
    assert "--scheduler nowhere: no Dask scheduler answers there" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
