"""The tutorial (docs/getting-started/tutorial.md) runs as written: every ``sh`` block,
in order, in one shell in an empty folder, with .venv/bin on PATH; then what the page says
happened is checked (issue 34)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import soundfile

from tools.docs import TUTORIAL, run_tutorial, shell_blocks


def test_the_tutorial_runs_as_written_and_ends_with_the_cup_in_the_hand(tmp_path: Path):
    blocks = shell_blocks(TUTORIAL.read_text(encoding="utf-8"))
    assert len(blocks) >= 6 and blocks[0].startswith("colosseum new kitchen")
    result = run_tutorial(tmp_path)  # as in CI: no display, so every run is headless
    log = result.stdout + result.stderr
    assert result.returncode == 0, log[-4000:]

    kitchen = tmp_path / "kitchen"
    assert (kitchen / "main.scene").is_file() and (kitchen / "scripts" / "cup.lua").is_file()
    assert (kitchen / "sounds" / "clink.wav").is_file()  # step 1: what colosseum new wrote
    assert "bounce 1 off ground" in log and "ball z=" in log  # its script and its system ran
    assert "clink: the cup hit table" in log  # step 3: the script heard the landing
    landing, _ = soundfile.read(tmp_path / "landing.wav")
    assert np.abs(landing).max() > 0.01  # ... and the clink is in the mix
    assert "the cup is in hand" in log  # step 5: onGrasp
    measures = json.loads((tmp_path / "stats.json").read_text())["measures"]
    assert 0.95 < measures["cup height"] < 1.15  # lifted off the table (top at 0.75)
    assert (tmp_path / "grasp.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for saved in ("held.scene", "later.scene"):  # step 6: held, and still held after
        assert 'Holding ["cup"]' in (tmp_path / saved).read_text(), saved
