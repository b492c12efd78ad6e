"""Headless runs draw only what is saved: a screenshot costs one frame, not every frame."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

from app.scaffold import scaffold


def test_headless_screenshot_draws_only_the_final_frame(tmp_path: Path):
    sim = scaffold(tmp_path / "sim")
    shot, stats, frames = tmp_path / "shot.png", tmp_path / "stats.json", tmp_path / "frames"
    frames.mkdir()
    result = subprocess.run(
        [sys.executable, "-m", "app.cli", "run", str(sim), "--headless", "--frames", "60",
         "--fast", "--size", "160x120", "--screenshot", str(shot), "--stats", str(stats),
         "--record-frames", str(frames), "--record-every", "20"],
        capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    render = json.loads(stats.read_text())["render"]
    # frames 0, 20 and 40 written; the last one drawn again for the screenshot, counted too
    assert render["frames_written"] == 3 and render["frames_drawn"] == 4
    assert sorted(p.name for p in frames.iterdir()) == [
        "frame_000000.png", "frame_000020.png", "frame_000040.png"]
    image = np.asarray(Image.open(shot).convert("RGB"))
    assert image.shape == (120, 160, 3) and image.std() > 5
