"""A windowed run end to end on a virtual X display (Xvfb), where one is installed."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from app.scaffold import scaffold

pytestmark = pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")


def test_run_opens_a_window_when_a_display_exists(tmp_path: Path):
    sim = scaffold(tmp_path / "sim")
    shot = tmp_path / "shot.png"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    result = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 800x600x24", sys.executable, "-m", "app.cli",
         "run", str(sim), "--frames", "30", "--fast", "--size", "320x240",
         "--screenshot", str(shot)],
        capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 0, result.stderr
    assert "rendering with window" in result.stderr
    image = np.asarray(Image.open(shot).convert("RGB"))
    assert image.shape == (240, 320, 3)
    assert image.std() > 5  # a real picture, not a blank buffer
