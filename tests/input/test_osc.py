"""OSC devices on loopback: real python-osc clients move trackers, press buttons, turn
wheels; bad packets are counted and never applied; silent sources are lost and found."""

from __future__ import annotations

import logging
import socket
import time
from pathlib import Path

import numpy as np
import pytest
from input_helpers import input_engine, run_until
from pythonosc.udp_client import SimpleUDPClient

from components import Transform
from engine.input import (
    Button,
    DeviceError,
    DeviceFound,
    DeviceLost,
    InputHub,
    InputState,
    TrackerPose,
    WheelCount,
)
from engine.input.osc import OscDevice


def osc_scene(extra: str = "", lost_after: float = 0.5) -> str:
    return f"""
Input {{
  LostAfter {lost_after}
  Device {{ Kind "osc" Port 0 }}
  {extra}
}}
"""


def port_of(engine) -> int:
    engine.start()
    engine.resource(InputHub).start()
    device = osc_device(engine)
    return device.port


def osc_device(engine) -> OscDevice:
    return next(d for d in engine.resource(InputHub).devices if isinstance(d, OscDevice))


def f32(*values: float) -> list[float]:
    """What an OSC float (32 bits) carries of ``values``."""
    return np.float32(values).astype(np.float64).tolist()


def test_a_received_pose_is_in_the_state_table_at_the_next_frame(tmp_path: Path):
    with input_engine(osc_scene(), tmp_path) as engine:
        client = SimpleUDPClient("127.0.0.1", port_of(engine))
        state = engine.resource(InputState)
        poses: list[TrackerPose] = []
        engine.events.subscribe(TrackerPose, poses.append)
        engine.step()
        client.send_message("/colosseum/tracker/hand_r", [0.1, 0.2, 1.5, 1.0, 0.0, 0.0, 0.0])
        device = osc_device(engine)
        deadline = time.monotonic() + 5.0
        while device.status().received == 0 and time.monotonic() < deadline:
            time.sleep(0.001)
        assert state.tracker("hand_r") is None
        engine.step()  # the first frame after the packet arrived delivers it
        tracker = state.tracker("hand_r")
        assert tracker.position.tolist() == f32(0.1, 0.2, 1.5)
        assert tracker.orientation.tolist() == [1.0, 0.0, 0.0, 0.0]
        assert [p.device for p in poses] == ["hand_r"] and poses[0].timestamp > 0


def test_buttons_axes_and_wheel_counts_arrive_typed(tmp_path: Path):
    with input_engine(osc_scene(), tmp_path) as engine:
        client = SimpleUDPClient("127.0.0.1", port_of(engine))
        seen: list = []
        for kind in (Button, WheelCount):
            engine.events.subscribe(kind, seen.append)
        client.send_message("/colosseum/button/glove_r/index", 1)
        client.send_message("/colosseum/axis/joystick/x", -0.25)
        client.send_message("/colosseum/wheel/left", 4096)
        state = engine.resource(InputState)
        run_until(engine, lambda: state.wheel("left") is not None
                  and state.axis("joystick", "x") is not None and len(seen) >= 2)
        assert state.button("glove_r", "index") is True
        assert state.axis("joystick", "x") == -0.25
        assert state.wheel("left").count == 4096
        button = next(e for e in seen if isinstance(e, Button))
        assert (button.device, button.name, button.pressed) == ("glove_r", "index", True)
        wheel = next(e for e in seen if isinstance(e, WheelCount))
        assert isinstance(wheel.count, int) and wheel.count == 4096


def test_a_bound_object_follows_its_calibrated_tracker(tmp_path: Path):
    scene = osc_scene('Tracker { ID "head" Offset [0 0 1] Scale 0.01 Object "marker" }') + \
        'Object { ID "marker" VisualAttributes { Geometry { Primitive "sphere" } } }'
    with input_engine(scene, tmp_path) as engine:
        client = SimpleUDPClient("127.0.0.1", port_of(engine))
        client.send_message("/colosseum/tracker/head", [100.0, 0.0, 50.0, 1.0, 0.0, 0.0, 0.0])
        state = engine.resource(InputState)
        run_until(engine, lambda: state.tracker("head") is not None)
        marker = next(t for e, t in engine.world.get_component(Transform))
        # centimetres to metres, then lifted by the offset
        np.testing.assert_allclose(marker.position, [1.0, 0.0, 1.5], rtol=1e-7)


def test_malformed_and_non_finite_packets_are_counted_not_applied(tmp_path: Path, caplog):
    with input_engine(osc_scene(), tmp_path) as engine:
        port = port_of(engine)
        client = SimpleUDPClient("127.0.0.1", port)
        raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        bad = [lambda: raw.sendto(b"\x00garbage that is no OSC", ("127.0.0.1", port)),
               lambda: raw.sendto(b"/colosseum/tracker/x\x00\x00\x00\x00,ff", ("127.0.0.1",
                                                                                 port)),
               lambda: client.send_message("/colosseum/tracker/hand_r", [float("nan"), 0.0,
                                                                         0.0, 1.0, 0.0, 0.0,
                                                                         0.0]),
               lambda: client.send_message("/colosseum/tracker/hand_r", [0.0, 0.0, 0.0, 2.0,
                                                                         0.0, 0.0, 0.0]),
               lambda: client.send_message("/colosseum/tracker/hand_r", [1.0, 2.0]),
               lambda: client.send_message("/colosseum/wheel/left", [float("inf")]),
               lambda: client.send_message("/colosseum/wheel/left", [1.5]),
               lambda: client.send_message("/colosseum/button/glove/index", [7]),
               lambda: client.send_message("/colosseum/nothing/here", [1]),
               lambda: client.send_message("/elsewhere", [1])]
        with caplog.at_level(logging.WARNING, logger="colosseum.input"):
            for send in bad:
                send()
            client.send_message("/colosseum/wheel/sentinel", [1])  # arrives after the bad ones
            state = engine.resource(InputState)
            run_until(engine, lambda: state.wheel("sentinel") is not None)
        raw.close()
        device = osc_device(engine)
        assert device.status().bad == len(bad)
        assert state.tracker("hand_r") is None and state.wheel("left") is None
        assert not state.buttons
        reports = [r.getMessage() for r in caplog.records if "bad message" in r.getMessage()]
        assert len(reports) == 1  # once per device per few seconds, with one example
        assert f"UDP 127.0.0.1:{port}" in reports[0] and "e.g." in reports[0]


def test_random_bytes_never_reach_the_engine(tmp_path: Path):
    rng = np.random.default_rng(7)
    with input_engine(osc_scene(), tmp_path) as engine:
        port = port_of(engine)
        raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for _ in range(300):
            head = b"/colosseum/tracker/h\x00\x00\x00\x00," if rng.random() < 0.5 else b""
            raw.sendto(head + rng.bytes(int(rng.integers(0, 64))), ("127.0.0.1", port))
            time.sleep(0.0005)  # within what the socket buffers: loss here would be the kernel's
        raw.close()
        device = osc_device(engine)
        run_until(engine, lambda: device.status().received + device.status().bad >= 300)
        assert device.status().state == "open"  # still listening


def test_a_port_in_use_names_the_port_and_the_device(tmp_path: Path, caplog):
    taken = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    taken.bind(("127.0.0.1", 0))
    port = taken.getsockname()[1]
    with pytest.raises(DeviceError, match=rf"'glove'.*UDP port {port} is already in use"):
        OscDevice("glove", port).open()
    scene = f'Input {{ Device {{ ID "glove" Kind "osc" Port {port} }} }}'
    with caplog.at_level(logging.ERROR), input_engine(scene, tmp_path) as engine:
        engine.run(frames=3)  # the run goes on without it
    taken.close()
    assert any(f"UDP port {port} is already in use" in r.getMessage() for r in caplog.records)


def test_a_silent_source_is_lost_and_found_again(tmp_path: Path):
    scene = osc_scene('Tracker { ID "hand_r" }', lost_after=0.2)
    with input_engine(scene, tmp_path) as engine:
        client = SimpleUDPClient("127.0.0.1", port_of(engine))
        lost: list = []
        found: list = []
        engine.events.subscribe(DeviceLost, lost.append)
        engine.events.subscribe(DeviceFound, found.append)
        pose = [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0]
        state = engine.resource(InputState)
        client.send_message("/colosseum/tracker/hand_r", pose)
        run_until(engine, lambda: state.tracker("hand_r") is not None)
        assert [e.device for e in found] == ["hand_r"] and state.tracker("hand_r").tracked
        silent_since = time.monotonic()
        run_until(engine, lambda: bool(lost))
        assert time.monotonic() - silent_since >= 0.2 - 0.05
        assert lost[0].device == "hand_r" and not state.tracker("hand_r").tracked
        assert "hand_r" in state.lost
        client.send_message("/colosseum/tracker/hand_r", pose)
        run_until(engine, lambda: len(found) == 2)
        assert state.tracker("hand_r").tracked and not state.lost
