"""Trial markers on LSL (a real pylsl inlet) carry the LSL times of the trials' rows."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from experiment_helpers import experiment, rows, write_content

from services.input import DeviceError
from services.input.lsl import load_pylsl
from services.input.output import LslOutput

try:  # discovery kept to this computer for the whole test process
    lsl = load_pylsl("machine")
except DeviceError as exc:
    pytest.skip(f"liblsl not available: {exc}", allow_module_level=True)

LUA = """
function onUpdate(dt)
  local trial = experiment:trial()
  if trial ~= nil and time() >= 0.03 then trial:respond("seen", trial.index % 2 == 0) end
end
"""


def test_markers_carry_the_rows_lsl_times(in_tmp: Path):
    """Goal: each trial's start and end marker within 1 ms of its row's LSL times."""
    LslOutput("exp-lsl", "machine")  # the session's stream, kept for the process
    found = lsl.resolve_byprop("name", "exp-lsl-markers", minimum=1, timeout=10.0)
    assert found
    inlet = lsl.StreamInlet(found[0])
    inlet.open_stream(timeout=5.0)
    time.sleep(0.3)  # connected before anything is sent
    content = write_content(in_tmp / "l", """
  ID "lsl"
  Factor { ID "cue" Levels ["a" "b" "c"] }
  Blocks 2
  EndOn "response"
""", LUA, top='Output { Kind "lsl" Scope "machine" Name "exp-lsl" }')
    wall = time.monotonic()
    assert experiment("run", str(content), "--participant", "1", "--headless") == 0
    wall = time.monotonic() - wall
    markers: dict[str, float] = {}
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline and len(markers) < 18:
        sample, stamp = inlet.pull_sample(timeout=0.2)
        if sample is not None:
            words = sample[0].split()
            markers[f"{words[0]} {words[1]}"] = stamp
    table = rows(in_tmp / "sessions" / "lsl" / "1" / "trials.csv")
    assert len(table) == 6
    for r in table:
        n = r["trial"]
        assert abs(markers[f"trial_start {n}"] - float(r["lsl_start"])) < 1e-3
        assert abs(markers[f"trial_end {n}"] - float(r["lsl_end"])) < 1e-3
        assert markers[f"trial_start {n}"] < markers[f"response {n}"] <= \
            markers[f"trial_end {n}"]
        # real time: the trial lasted its 0.03 s and a frame or so on LSL's clock too
        assert 0.02 < float(r["lsl_end"]) - float(r["lsl_start"]) < 0.5
    assert wall < 20
