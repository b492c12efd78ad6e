"""Running sessions: Lua and Python trials, the files, a kill -9 and --resume, replay."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from experiment_helpers import experiment, rows, write_content

LUA = """
local started = {}
function onTrialStart(trial)
  started[trial.index] = time()
  assert(experiment:condition("speed") == trial.condition.speed)
end
function onUpdate(dt)
  local trial = experiment:trial()
  if trial == nil then return end
  local speed = tonumber(experiment:condition("speed"))
  if speed > 0 and time() - started[trial.index] >= 0.1 / speed then
    measure("ball_z", select(3, find("ball"):getPosition()))
    trial:respond("key", "space")
    trial:finish("reached")
  end
end
function onTrialEnd(trial)
  emit("marker", "ended " .. trial.index .. " " .. trial.outcome)
end
"""

DESIGN = """
  ID "lua"
  Factor { ID "speed" Levels [0 1 2] }
  Order "fixed"
  Practice 1
  Timeout 0.25
  Track ["ball"]
  TrackRate 0
"""


def test_lua_sets_ends_and_records_trials(in_tmp: Path):
    content = write_content(in_tmp / "c", DESIGN, LUA)
    assert experiment("run", str(content), "--participant", "3", "--fast", "--headless") == 0
    folder = in_tmp / "sessions" / "lua" / "3"
    table = rows(folder / "trials.csv")
    assert [(r["block"], r["practice"], r["speed"]) for r in table] == [
        ("0", "1", "0"), ("1", "0", "0"), ("1", "0", "1"), ("1", "0", "2")]
    by_speed = {r["speed"]: r for r in table[1:]}
    assert by_speed["0"]["outcome"] == "timeout"
    assert abs(float(by_speed["0"]["end_s"]) - 0.25) < 0.011
    for speed in ("1", "2"):
        r = by_speed[speed]
        assert r["outcome"] == "reached"
        assert json.loads(r["responses"]) == {"key": "space"}
        assert json.loads(r["measures"])["ball_z"] < 1.0  # it fell
        assert abs(float(r["end_s"]) - float(r["start_s"]) - 0.1 / int(speed)) < 0.025
        assert float(r["lsl_end"]) > float(r["lsl_start"]) > 0
    # each trial's tracking: the ball every frame, falling
    track = (folder / "tracking" / "trial-003.csv").read_text().splitlines()
    assert track[0] == "t,frame,object,x,y,z,qw,qx,qy,qz"
    zs = [float(line.split(",")[5]) for line in track[1:]]
    assert len(zs) > 5 and zs == sorted(zs, reverse=True)
    meta = json.loads((folder / "session.json").read_text())
    assert meta["participant"] == 3 and meta["experiment"] == "lua"
    assert len(meta["content_hash"]) == 64 and meta["engine_version"]
    assert meta["design"]["factors"][0]["levels"] == ["0", "1", "2"]
    # the same participant again is refused: --resume continues, nothing is overwritten
    assert experiment("run", str(content), "--participant", "3", "--fast", "--headless") == 1
    # replay trial 3 from its recording: the same outcome at the same time
    assert experiment("replay", str(content), "--participant", "3", "--trial", "3",
                      "--headless") == 0
    assert (folder / "replay" / "trial-003.csv").read_bytes() == \
        (folder / "tracking" / "trial-003.csv").read_bytes()  # the same poses, frame for frame
    # the report: a summary per condition (practice left out) and the plots
    assert experiment("report", str(in_tmp / "sessions" / "lua")) == 0
    summary = rows(in_tmp / "sessions" / "lua" / "report" / "summary.csv")
    assert [(r["speed"], r["trials"]) for r in summary] == [("0", "1"), ("1", "1"), ("2", "1")]
    assert summary[0]["outcome_timeout"] == "1" and summary[2]["outcome_reached"] == "1"
    assert abs(float(summary[2]["time_mean"]) - 0.05) < 0.025
    assert float(summary[1]["measure_ball_z_mean"]) < 1.0
    for plot in ("times.png", "trajectories.png", "heatmap.png"):
        assert (in_tmp / "sessions" / "lua" / "report" / plot).stat().st_size > 1000


POLICY = '''
from engine import Phase, system
from engine.events import CustomEvent
from engine.services import ExperimentControl

seen = []


def build(engine):
    engine.events.subscribe(CustomEvent, lambda ev: seen.append(ev.name)
                            if ev.name in ("trialStart", "trialEnd") else None)

    @system(Phase.SCRIPT)
    def policy(engine, dt):
        control = engine.try_resource(ExperimentControl)
        trial = control.trial_data()
        if trial is not None and "trialStart" in seen and engine.time >= 0.05:
            control.respond("level", control.condition("level"))
            control.respond("events", len(seen))

    engine.add_system(policy)
'''


def test_python_systems_respond_and_a_response_ends_the_trial(in_tmp: Path):
    content = write_content(in_tmp / "py", """
  ID "py"
  Factor { ID "level" Levels ["low" "high"] }
  Factor { ID "group" Levels ["a" "b"] Within 0 }
  EndOn "response"
  Timeout 1
""", files={"systems/policy.py": POLICY})
    assert experiment("run", str(content), "--participant", "2", "--fast", "--headless") == 0
    table = rows(in_tmp / "sessions" / "py" / "2" / "trials.csv")
    assert {r["group"] for r in table} == {"b"}
    for r in table:
        assert r["outcome"] == "response"
        assert json.loads(r["responses"])["level"] == r["level"]
        assert float(r["end_s"]) < 0.1


KILL_DESIGN = """
  ID "kill"
  Factor { ID "size" Levels [1 2 3 4] }
  Blocks 2
  Order "random"
  Seed 11
  Timeout 0.3
  Track ["ball"]
"""


def test_a_session_killed_in_trial_5_resumes_there(in_tmp: Path):
    """Goal: SIGKILL in trial 5, --resume: trials 1-4 byte for byte, trial 5 again, none
    twice."""
    content = write_content(in_tmp / "k", KILL_DESIGN)
    folder = in_tmp / "sessions" / "kill" / "1"
    env = {**os.environ, "COLOSSEUM_DEBUG": "0"}
    proc = subprocess.Popen([sys.executable, "-m", "app.cli", "--log-level", "warning",
                             "experiment", "run", str(content), "--participant", "1",
                             "--headless"], cwd=in_tmp, env=env,
                            stderr=subprocess.PIPE, stdout=subprocess.DEVNULL)
    in_five = folder / "tracking" / "trial-005.bin"
    deadline = time.monotonic() + 60
    while not in_five.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.005)
    assert in_five.exists(), proc.stderr.read().decode() if proc.poll() is not None else ""
    time.sleep(0.05)  # into the trial's frames (it lasts 0.3 s in real time)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    before = (folder / "trials.csv").read_bytes()
    assert len(rows(folder / "trials.csv")) == 4
    tracks = {n: (folder / "tracking" / f"trial-{n:03d}.csv").read_bytes() for n in range(1, 5)}
    inputs = {n: (folder / "input" / f"trial-{n:03d}.input").read_bytes() for n in range(1, 5)}
    assert not (folder / "tracking" / "trial-005.csv").exists()

    assert experiment("run", str(content), "--participant", "1", "--fast", "--headless",
                      "--resume") == 0
    after = (folder / "trials.csv").read_bytes()
    assert after.startswith(before)
    table = rows(folder / "trials.csv")
    assert [int(r["trial"]) for r in table] == list(range(1, 9))
    assert all(r["outcome"] == "timeout" for r in table)
    for n in range(1, 5):
        assert (folder / "tracking" / f"trial-{n:03d}.csv").read_bytes() == tracks[n]
        assert (folder / "input" / f"trial-{n:03d}.input").read_bytes() == inputs[n]
    assert not in_five.exists() and (folder / "tracking" / "trial-005.csv").exists()
    # the resumed trials are the ones the plan had: each block holds every size once
    for block in ("1", "2"):
        assert sorted(r["size"] for r in table if r["block"] == block) == ["1", "2", "3", "4"]
    meta = json.loads((folder / "session.json").read_text())
    assert [run["resumed_at"] for run in meta["runs"]] == [None, 5]


def test_one_world_through_the_session(in_tmp: Path):
    """Reset "never": the trials follow each other in one world (its clock runs on) and
    each trial's anomaly is switched in it."""
    content = write_content(in_tmp / "n", """
  ID "never"
  Factor { ID "blur" Levels ["off" "0.5"] Anomaly "blur" Param "Acuity" }
  Blocks 2
  Order "fixed"
  Reset "never"
""", """
local start = 0
function onTrialStart(trial) start = time() end
function onUpdate(dt)
  local trial = experiment:trial()
  if trial and time() - start >= 0.05 then
    local blur = getAnomaly("blur")
    trial:respond("on", blur.enabled)
    trial:respond("acuity", blur.acuity)
    trial:finish()
  end
end
""", top="Blur { Enabled 0 Onset 0 }")
    assert experiment("run", str(content), "--participant", "1", "--fast", "--headless") == 0
    folder = in_tmp / "sessions" / "never" / "1"
    table = rows(folder / "trials.csv")
    starts = [float(r["start_s"]) for r in table]
    assert starts == sorted(starts) and starts[-1] > 0.15  # one clock through the session
    assert [json.loads(r["responses"])["on"] for r in table] == [False, True, False, True]
    assert json.loads(table[1]["responses"])["acuity"] == 0.5
    assert all(r["outcome"] == "done" for r in table)
    assert [p.name for p in (folder / "input").iterdir()] == ["from-trial-001.input"]


CRASH = """
from engine import Phase, system
from engine.services import ExperimentControl


def build(engine):
    @system(Phase.SCRIPT)
    def crash(engine, dt):
        trial = engine.resource(ExperimentControl).trial_data()
        if trial is not None and trial["index"] == 2:
            raise RuntimeError("the policy broke")

    engine.add_system(crash)
"""


def test_a_system_that_raises_stops_the_session_with_its_rows_kept(in_tmp: Path, capsys):
    content = write_content(in_tmp / "x", """
  ID "crash"
  Factor { ID "a" Levels [1 2 3] }
  Order "fixed"
  Timeout 0.05
""", files={"systems/crash.py": CRASH})
    assert experiment("run", str(content), "--participant", "1", "--fast", "--headless") == 1
    err = capsys.readouterr().err
    assert "crash' raised" in err and "the policy broke" in err
    table = rows(in_tmp / "sessions" / "crash" / "1" / "trials.csv")
    assert [r["trial"] for r in table] == ["1"]


def test_a_torn_last_line_is_cut_and_a_changed_design_refused(tmp_path: Path):
    from engine.experiments.design import Design, Factor, plan
    from engine.experiments.session import SessionError, SessionFiles

    content = write_content(tmp_path / "c", '  Factor { ID "a" Levels [1 2 3] }')
    design = Design("torn", (Factor("a", ("1", "2", "3")),))
    files = SessionFiles(tmp_path / "s", design, 1, content)
    for trial in plan(design, 1)[:2]:
        files.write_row(trial, 0.0, 1.0, 0.0, None, None, "done", {"k": "v, w"}, {})
    whole = files.trials_path.read_bytes()
    with files.trials_path.open("ab") as f:
        f.write(b"1,1,3,3,0,3,0.000000,0.5")  # a kill in the middle of a write
    resumed = SessionFiles(tmp_path / "s", design, 1, content, resume=True)
    assert files.trials_path.read_bytes() == whole and len(resumed.rows) == 2
    assert resumed.rows[1]["responses"] == '{"k": "v, w"}'
    with pytest.raises(SessionError, match="already"):
        SessionFiles(tmp_path / "s", design, 1, content)
    with pytest.raises(SessionError, match="changed"):
        SessionFiles(tmp_path / "s", Design("torn", (Factor("a", ("1", "2")),)), 1, content,
                     resume=True)


WHEELS_PY = '''
from engine import Phase, system
from services.input import InputHub
from services.input.events import WheelCount


def build(engine):
    @system(Phase.INPUT, before=("InputSystem",))
    def turn(e, dt):  # the left wheel turns at one turn a second: 100 counts per turn
        e.resource(InputHub).inject(WheelCount("left", int(e.time * 100), e.time))
    engine.add_system(turn)
'''


def test_the_wheel_counters_are_logged_beside_the_tracked_poses(in_tmp: Path):
    """Issue 33: the per-frame tracking holds the wheel counts too (the wheelchair's)."""
    design = 'ID "wheels"\n  Factor { ID "speed" Levels [1] }\n  Timeout 0.5\n' \
             '  Track ["ball"]\n  TrackRate 20'
    content = write_content(in_tmp / "w", design,
                            top='Input { Wheel { ID "left" CountsPerTurn 100 } }',
                            files={"systems/wheels.py": WHEELS_PY})
    assert experiment("run", str(content), "--participant", "1", "--fast", "--headless") == 0
    tracking = in_tmp / "sessions" / "wheels" / "1" / "tracking"
    logged = rows(tracking / "trial-001.wheels.csv")
    assert len(logged) >= 8 and {r["wheel"] for r in logged} == {"left"}
    counts = [int(r["count"]) for r in logged]
    assert counts == sorted(counts) and counts[-1] >= 40  # half a second at 100 counts/s
    assert float(logged[-1]["turns"]) == pytest.approx(counts[-1] / 100)  # CountsPerTurn
    assert "rad_s" in logged[-1]  # the input layer's rate (its own clock decides it)
