"""Simulated participants on Dask: colosseum sweep --participants checks a design."""

from __future__ import annotations

import json
from pathlib import Path

from experiment_helpers import rows, write_content

from app.cli import main

POLICY = """
local start = 0
function onTrialStart(trial) start = time() end
function onUpdate(dt)
  local trial = experiment:trial()
  if trial and time() - start >= 0.05 * tonumber(experiment:condition("size")) then
    trial:finish("done")
  end
end
"""


def test_simulated_participants_check_the_design(in_tmp: Path):
    content = write_content(in_tmp / "sim", """
  ID "sim"
  Factor { ID "hand" Levels ["left" "right"] }
  Factor { ID "size" Levels [1 2] }
  Order "latin"
  Timeout 1
""", POLICY, top="ball_z 1")
    assert main(["--log-level", "warning", "sweep", str(content), "--participants", "1..4",
                 "--workers", "2", "--param", "ball_z=2", "--out", str(in_tmp / "out")]) == 0
    check = json.loads((in_tmp / "out" / "design_check.json").read_text())
    assert check["participants"] == 4 and check["balanced"] and not check["unreached"]
    assert check["failed"] == {}
    assert all(v == [1, 1, 1, 1] for v in check["counterbalance"].values())
    for label, c in check["conditions"].items():  # the policy's time: 0.05 s per size
        assert c["outcomes"] == {"done": 4}
        size = int(label.split("size=")[1])
        assert abs(c["duration_mean"] - 0.05 * size) < 0.025
    summary = rows(in_tmp / "out" / "report" / "summary.csv")
    assert len(summary) == 4 and {r["trials"] for r in summary} == {"4"}
