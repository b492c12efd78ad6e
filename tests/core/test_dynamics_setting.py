"""The scene's Dynamics setting picks the backend; --backend overrides it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from app.scaffold import scaffold


def run(sim: Path, tmp_path: Path, *flags: str) -> str:
    stats = tmp_path / "stats.json"
    result = subprocess.run([sys.executable, "-m", "app.cli", "run", str(sim), "--frames", "5",
                             "--fast", "--stats", str(stats), *flags],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return json.loads(stats.read_text())["backend"]


def test_scene_dynamics_setting_and_flag(tmp_path: Path):
    sim = scaffold(tmp_path / "sim")
    assert run(sim, tmp_path) == "ode"
    scene = sim / "main.scene"
    scene.write_text(scene.read_text().replace("TimeStep 0.01", 'TimeStep 0.01 Dynamics "pymunk"'))
    assert run(sim, tmp_path) == "pymunk"
    assert run(sim, tmp_path, "--backend", "ode") == "ode"
