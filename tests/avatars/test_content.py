"""content/avatars as an author runs it: it checks clean, runs headless, a key press
crossfades the leader to running, the porter carries its crate, and the walkers climb."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from avatar_helpers import ROOT, avatars, entity, position

from engine.app import Engine, EngineConfig
from engine.events import KeyEvent
from engine.scene import check, instantiate, load_spec
from systems import RegistryPlugin, load_plugin
from systems.avatars import AvatarsPlugin
from systems.scripting import ScriptingPlugin

FOLDER = ROOT / "content" / "avatars"


def test_the_avatars_content_checks_without_errors_or_warnings():
    assert list(check(FOLDER)) == []


def test_colosseum_runs_the_avatars_content_headless_with_a_screenshot(tmp_path: Path):
    shot = tmp_path / "avatars.png"
    done = subprocess.run([sys.executable, "-m", "app.cli", "run", str(FOLDER), "--headless",
                           "--fast", "--frames", "120", "--screenshot", str(shot)],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert "error" not in done.stderr.lower(), done.stderr
    assert "Traceback" not in done.stderr
    assert shot.stat().st_size > 10_000


@pytest.fixture
def engine() -> Engine:
    config = EngineConfig(backend="ode", fast=True, content_dir=FOLDER, dt=0.01)
    made = Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"), ScriptingPlugin(),
                                   AvatarsPlugin()])
    instantiate(made, load_spec(FOLDER / "main.scene", made.rng))
    yield made
    made.close()


def test_r_crossfades_the_leader_to_running_and_space_waves_then_walks_on(engine: Engine):
    engine.run(frames=50)
    system = avatars(engine)
    leader = entity(engine, "leader")
    assert {n: w for n, _, w in system.mixer.playing(leader)} == {"Walk": 1.0, "Run": 0.0}
    engine.events.emit(KeyEvent("r", True))
    engine.run(frames=20)  # half the 0.5 s fade
    weights = {n: w for n, _, w in system.mixer.playing(leader)}
    assert weights["Run"] == pytest.approx(0.4, abs=0.03)
    engine.run(frames=40)
    assert {n: w for n, _, w in system.mixer.playing(leader)} == {"Walk": 0.0, "Run": 1.0}
    engine.events.emit(KeyEvent("space", True))
    engine.run(frames=200)  # the 1.5 s wave, then the walk fades back in
    assert [n for n, _, w in system.mixer.playing(leader) if w == 1.0] == ["Walk"]


def test_the_porter_carries_its_crate_and_the_leader_climbs_the_ramp(engine: Engine):
    system = avatars(engine)
    porter = entity(engine, "porter")
    heights = []
    for _ in range(6):
        engine.run(frames=100)
        hand = system.bone_pose(porter, "hand.R")[0]
        assert np.linalg.norm(position(engine, "crate") - hand) < 0.3
        heights.append(position(engine, "leader")[2])
    assert max(heights) > 0.4  # up the ramp onto the plateau (0.6 m), feet on it
