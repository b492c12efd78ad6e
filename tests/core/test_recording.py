"""Recorded input replays to the same state in serial mode."""

from __future__ import annotations

import numpy as np
import pytest

from components import Physical, Transform
from engine import EngineConfig, Phase, system
from engine.events import KeyEvent
from engine.physics.commands import ApplyImpulse
from engine.recording import InputRecorder, InputReplayer, ReplayError
from systems import create_engine


def run(recorder=None, replayer=None, live_keys=True) -> np.ndarray:
    with create_engine(EngineConfig(backend="ballistic", fast=True)) as eng:
        ball = eng.spawn(Transform(position=(0, 0, 100)), Physical())
        if live_keys:  # stands in for a device that produces key presses
            eng.add_system(system(Phase.INPUT)(
                lambda e, dt: e.frame in (3, 40, 41) and e.events.emit(KeyEvent("space", True))))
        for extra in (recorder, replayer):
            if extra is not None:
                eng.add_system(extra)
        eng.events.subscribe(KeyEvent, lambda ev: eng.physics.push(
            ApplyImpulse(ball, (1.0, 0.0, 5.0))))
        eng.run(frames=120)
        return eng.physics.snapshot.bodies.position.copy()


def test_replay_reproduces_a_recorded_run(tmp_path):
    path = tmp_path / "input.jsonl"
    live = run(recorder=InputRecorder(path))
    assert len(path.read_text().splitlines()) == 3
    replayed = run(replayer=InputReplayer(path), live_keys=False)
    assert replayed.tobytes() == live.tobytes()
    assert run(live_keys=False).tobytes() != live.tobytes()  # the input mattered


def test_a_corrupt_recording_names_the_line(tmp_path):
    path = tmp_path / "bad.jsonl"
    path.write_text('{"frame": 1, "type": "key", "key": "a", "pressed": true}\n{"frame": oops}\n')
    with pytest.raises(ReplayError, match=r"bad.jsonl:2:"):
        InputReplayer(path)
