"""Record and replay: a live run with devices replays bit-identically in serial mode."""

from __future__ import annotations

import json
import logging
import math
import socket
import threading
import time
from pathlib import Path

import pytest
from input_helpers import input_engine
from pythonosc.udp_client import SimpleUDPClient

from app.cli import main
from components import Physical, Transform
from engine import Phase, system
from engine.physics.commands import ApplyImpulse
from engine.scene.inputs import InputSpec, WheelSpec
from services.input import (
    DeviceLost,
    InputHub,
    InputRecorder,
    InputReplayer,
    InputState,
    ReplayError,
    TrackerPose,
    WheelCount,
    read_recording,
)
from services.input.osc import OscDevice
from services.input.record import FrameInput, RecordWriter
from systems import load_plugin

SCENE = """
Input {{
  Device {{ Kind "osc" Port {port} }}
  Tracker {{ ID "hand_r" Filter "oneeuro" Predict 20 Offset [0 0 0.5] }}
  Wheel {{ ID "left" CountsPerTurn 256 }}
}}
Object {{ ID "ball" Position [0 0 10] PhysicalAttributes {{ Mass 1 }} }}
"""


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@system(Phase.SCRIPT, reads=(Physical, Transform))
def steer_ball(engine, dt):
    """Input drives physics: the hand pulls the ball, the wheel spins it up."""
    state = engine.resource(InputState)
    ball = next(e for e, _ in engine.world.get_components(Physical, Transform))
    hand, wheel = state.tracker("hand_r"), state.wheel("left")
    if hand is not None:
        pull = (hand.position - engine.world.component_for_entity(ball, Transform).position)
        engine.physics.push(ApplyImpulse(ball, tuple(pull * 0.01)))
    if wheel is not None and wheel.angular_velocity:
        engine.physics.push(ApplyImpulse(ball, (0.0, wheel.angular_velocity * 1e-3, 0.0)))
    if state.button("glove_r", "index"):
        engine.physics.push(ApplyImpulse(ball, (0.0, 0.0, 0.2)))


def run(tmp_path: Path, port: int, frames: int, live: bool = False, **extra):
    """Final ball position and the hand's pose per frame; ``live`` sends OSC meanwhile."""
    with input_engine(SCENE.format(port=port), tmp_path,
                      extra_plugins=(load_plugin("physics"),),
                      backend=extra.get("backend", "ballistic")) as engine:
        engine.add_system(steer_ball)
        for s in extra.get("systems", ()):
            engine.add_system(s)
        hands = []
        sender = None
        if live:
            engine.start()
            sender = threading.Thread(target=send_motion, args=(port,))
            sender.start()
        for _ in range(frames):
            engine.step()
            hand = engine.resource(InputState).tracker("hand_r")
            hands.append(None if hand is None else (*hand.position, *hand.orientation))
            if live:
                time.sleep(0.004)
        if sender is not None:
            sender.join()
        return engine.physics.snapshot.bodies.position.copy(), hands


def send_motion(port: int) -> None:
    client = SimpleUDPClient("127.0.0.1", port)
    for i in range(120):
        t = i / 240.0
        half = 0.5 * math.sin(t)
        client.send_message("/colosseum/tracker/hand_r",
                            [0.2 * math.sin(6 * t), 0.1, 1.0 + 0.1 * t, math.cos(half), 0.0,
                             0.0, math.sin(half)])
        client.send_message("/colosseum/wheel/left", [int(300 * t)])
        if i % 40 == 20:
            client.send_message("/colosseum/button/glove_r/index", [int(i % 80 == 20)])
        time.sleep(1 / 240)


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_replay_in_serial_mode_is_bit_identical_to_the_live_run(tmp_path: Path, backend):
    port = free_port()
    path = tmp_path / "session.jsonl"
    live_end, live_hands = run(tmp_path, port, 150, live=True, systems=[InputRecorder(path)],
                               backend=backend)
    recording = read_recording(path)
    kinds = {type(e).__name__ for f in recording.frames.values() for e in f.events}
    assert {"TrackerPose", "WheelCount", "Button", "DeviceFound"} <= kinds
    assert recording.header["devices"] == [{"id": "osc", "kind": "osc"},
                                           {"id": "window", "kind": "window"}]
    assert recording.header["seed"] == 0 and recording.header["scene_sha256"]
    # the port is taken during the replay: the replay must not open the live device
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as blocker:
        blocker.bind(("127.0.0.1", port))
        replay_end, replay_hands = run(tmp_path, port, 150, systems=[InputReplayer(path)],
                                       backend=backend)
    assert replay_hands == live_hands
    assert replay_end.tobytes() == live_end.tobytes()
    quiet_end, _ = run(tmp_path, free_port(), 150, backend=backend)
    assert quiet_end.tobytes() != live_end.tobytes()  # the input mattered


def test_replaying_never_opens_the_live_devices(tmp_path: Path):
    path = tmp_path / "empty.jsonl"
    run(tmp_path, free_port(), 3, systems=[InputRecorder(path)])
    with input_engine(SCENE.format(port=free_port()), tmp_path) as engine:
        engine.add_system(InputReplayer(path))
        engine.run(frames=3)
        device = next(d for d in engine.resource(InputHub).devices if isinstance(d, OscDevice))
        assert device.status().state == "closed"


def test_recording_with_no_events_writes_a_valid_file_and_says_so(tmp_path: Path, caplog):
    content = tmp_path / "content"
    content.mkdir()
    (content / "main.scene").write_text('Object { ID "a" Position [0 0 1] }\n')
    out = tmp_path / "quiet.jsonl"
    with caplog.at_level(logging.INFO, logger="colosseum.input"):
        code = main(["run", str(content), "--headless", "--frames", "5", "--fast", "--record",
                     str(out)])
    assert code == 0
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    assert lines[0]["format"] == "colosseum-input" and lines[0]["version"] == 1
    assert [line["frame"] for line in lines[1:]] == [0, 1, 2, 3, 4]
    assert any("no device produced an event" in r.getMessage() for r in caplog.records)
    recording = read_recording(out)
    assert recording.event_count == 0 and len(recording.frames) == 5


def test_a_replay_against_another_scene_warns(tmp_path: Path, caplog):
    path = tmp_path / "session.jsonl"
    run(tmp_path, free_port(), 2, systems=[InputRecorder(path)])
    with caplog.at_level(logging.WARNING), input_engine('Object { ID "other" }', tmp_path) as e:
        e.add_system(InputReplayer(path))
        e.run(frames=2)
    assert any("was recorded with scene" in r.getMessage() for r in caplog.records)


HEADER = '{"format": "colosseum-input", "version": 1, "scene": "", "seed": 0, "devices": []}\n'


@pytest.mark.parametrize(("body", "line", "why"), [
    ('{"frame": oops}\n', 2, "not a recorded input line"),
    ('{"frame": 1, "type": "tracker", "device": "h", "position": [NaN, 0, 0], '
     '"orientation": [1, 0, 0, 0]}\n', 2, "not finite"),
    ('{"frame": 1, "type": "tracker", "device": "h", "position": [0, 0, 0], '
     '"orientation": [2, 0, 0, 0]}\n', 2, "quaternion length"),
    ('{"frame": 0, "clock": 1.0}\n{"frame": 1, "type": "wheel", "device": "l", "count": 1.5}\n',
     3, "not a whole number"),
    ('{"frame": 1, "type": "laser", "device": "l"}\n', 2, "unknown or missing type"),
    ('{"frame": 1, "type": "key", "key": "a", "pressed": true, "extra": 1}\n', 2,
     "unexpected field"),
])
def test_a_bad_recording_names_the_file_and_line(tmp_path: Path, body: str, line: int, why):
    path = tmp_path / "bad.jsonl"
    path.write_text(HEADER + body)
    with pytest.raises(ReplayError, match=rf"bad.jsonl:{line}: .*{why}"):
        InputReplayer(path)


def test_a_file_without_the_header_is_refused(tmp_path: Path):
    path = tmp_path / "old.jsonl"
    path.write_text('{"frame": 1, "type": "key", "key": "a", "pressed": true}\n')
    with pytest.raises(ReplayError, match=r"old.jsonl:1: .*header"):
        read_recording(path)


def test_an_infinite_frame_number_is_a_replay_error_naming_the_line(tmp_path):
    """Found by the fuzzer: ``"frame": 1e999`` (infinity) raised OverflowError."""
    path = tmp_path / "run.input"
    path.write_text('{"format": "colosseum-input", "version": 1}\n{"frame": 1e999, "clock": 1}\n')
    with pytest.raises(ReplayError, match=r"run.input:2: not a recorded input line"):
        read_recording(path)


def test_past_the_end_of_a_replay_wheels_come_to_rest_and_sources_are_lost(tmp_path, caplog):
    """The recording's devices fall silent where it ends: the clock went on standing
    still there, so a wheel turned at its last rate for ever and a hand stayed tracked."""
    path = tmp_path / "short.jsonl"
    writer = RecordWriter(path, {"scene": "", "seed": 0, "devices": []})
    for frame in range(30):  # 2 turns a second at 60 frames a second
        t = 100.0 + frame / 60
        writer.write(frame, FrameInput(t, [
            WheelCount("left", round(2 * 1024 * (t - 100.0)), t),
            TrackerPose("hand_r", (0.0, 0.0, 1.0), (1.0, 0.0, 0.0, 0.0), None, t)]))
    writer.close()
    hub = InputHub(InputSpec(wheels=(WheelSpec("left", counts_per_turn=1024),)), [])
    hub.replay(read_recording(path))
    lost: list[DeviceLost] = []
    with caplog.at_level(logging.INFO, logger="colosseum.input"):
        for frame in range(30):
            hub.step(frame)
        assert hub.state.wheel("left").angular_velocity == pytest.approx(4 * math.pi, rel=0.01)
        for frame in range(30, 60):
            lost += [e for e in hub.step(frame) if isinstance(e, DeviceLost)]
    assert hub.state.now == pytest.approx(100.0 + 59 / 60)
    assert hub.state.wheel("left").angular_velocity == 0.0
    assert sorted(e.device for e in lost) == ["hand_r", "left"]
    assert not hub.state.tracker("hand_r").tracked
    assert "the recorded input ended at frame 29" in caplog.text


def test_a_scenes_fingerprint_ignores_comments_but_not_what_it_says() -> None:
    from services.input.record import scene_fingerprint

    scene = 'Object { ID "a" Position [0 0 1] }\nFile "x//y"\n'
    same = scene_fingerprint({"main.scene": scene})
    noted = '// how to run it\nObject { ID "a" Position [0 0 1] }  // the ball\n\nFile "x//y"\n'
    assert scene_fingerprint({"main.scene": noted}) == same
    changed = scene.replace("[0 0 1]", "[0 0 2]")
    assert scene_fingerprint({"main.scene": changed}) != same
    assert scene_fingerprint({"main.scene": scene.replace("x//y", "x")}) != same
