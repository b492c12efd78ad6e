"""OSC devices on loopback: real python-osc clients move trackers, press buttons, turn
wheels; bad packets are counted and never applied; silent sources are lost and found."""

from __future__ import annotations

import logging
import socket
import struct
import time
from pathlib import Path

import numpy as np
import pytest
from input_helpers import input_engine, run_until
from pythonosc.osc_message import OscMessage
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.udp_client import SimpleUDPClient

from components import Transform
from engine import EngineConfig
from services.input import (
    Button,
    DeviceError,
    DeviceFound,
    DeviceLost,
    InputHub,
    InputState,
    TrackerPose,
    WheelCount,
    osc,
)
from services.input import device as device_module
from services.input.osc import OscDevice


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
        state = engine.resource(InputState)  # the one latest-state table
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


def test_an_engine_without_the_input_plugin_says_which_resource_is_missing():
    from engine import Engine
    from engine.app import MissingResource

    with Engine(EngineConfig(backend="ballistic", fast=True)) as engine:
        engine.run(frames=1)
        with pytest.raises(MissingResource, match=r"no InputState resource: the plugin that "
                                                  r"provides it is not loaded"):
            engine.resource(InputState)
        assert not hasattr(engine, "input")  # one table, the resource


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


def huge_double_pose() -> OscMessage:
    """A pose whose x is 1e308, as an OSC double: finite, and past anything a tracker sees."""
    builder = OscMessageBuilder("/colosseum/tracker/hand_r")
    builder.add_arg(1e308, OscMessageBuilder.ARG_TYPE_DOUBLE)
    for value in (0.0, 0.0, 1.0, 0.0, 0.0, 0.0):
        builder.add_arg(value)
    return builder.build()


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
               lambda: client.send(huge_double_pose()),
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


def nested_bundle(depth: int) -> bytes:
    """A wheel count wrapped in ``depth`` bundles: 20 bytes a level, valid OSC throughout."""
    inner = b"/colosseum/wheel/left\x00\x00\x00,i\x00\x00" + struct.pack(">i", 1)
    for _ in range(depth):
        inner = b"#bundle\x00" + struct.pack(">Qi", 1, len(inner)) + inner
    return inner


def test_a_deeply_nested_bundle_is_one_bad_message_and_the_device_keeps_listening(
        tmp_path: Path):
    """python-osc unpacks bundles recursively: 600 levels (12 kB, one datagram) raised
    RecursionError on the device's thread, which ended it for the rest of the run."""
    with input_engine(osc_scene(), tmp_path) as engine:
        port = port_of(engine)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as raw:
            raw.sendto(nested_bundle(600), ("127.0.0.1", port))
            raw.sendto(nested_bundle(3), ("127.0.0.1", port))  # a shallow one is read
        state = engine.resource(InputState)
        run_until(engine, lambda: state.wheel("left") is not None)
        status = osc_device(engine).status()
        assert (status.state, status.bad, status.received) == ("open", 1, 1)


def test_bad_messages_since_the_last_report_are_told_when_the_device_closes(caplog):
    device = OscDevice("mocap", 0)
    device.open()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as raw, \
            caplog.at_level(logging.WARNING, logger="colosseum.input"):
        for count, packet in enumerate((b"first garbage", b"second garbage",
                                        b"third garbage"), 1):
            raw.sendto(packet, ("127.0.0.1", device.port))
            deadline = time.monotonic() + 5.0
            while device.status().bad < count and time.monotonic() < deadline:
                time.sleep(0.001)
            device.poll(time.monotonic())  # reports the first; the others are too soon
        device.close()
    reports = [r.getMessage() for r in caplog.records if "bad message" in r.getMessage()]
    assert len(reports) == 2
    assert "1 bad message ignored" in reports[0] and "first garbage" in reports[0]
    assert "2 bad messages ignored" in reports[1] and "second garbage" in reports[1]


def test_datagrams_the_system_dropped_are_counted_and_told(monkeypatch, caplog):
    """A receive buffer too small for a burst (the system's default holds 256 datagrams)
    lost packets without a word; the count of drops Linux keeps is told like bad messages."""
    monkeypatch.setattr(osc, "RECEIVE_BUFFER", 2048)  # a few datagrams
    device = OscDevice("mocap", 0)
    device.open()
    sent, late = 2000, 0
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as raw, \
            caplog.at_level(logging.WARNING, logger="colosseum.input"):
        packet = OscMessageBuilder("/colosseum/wheel/left")
        packet.add_arg(1)
        data = packet.build().dgram
        for _ in range(sent):
            raw.sendto(data, ("127.0.0.1", device.port))
        deadline = time.monotonic() + 5.0
        while device.received + device.dropped < sent + late and time.monotonic() < deadline:
            raw.sendto(data, ("127.0.0.1", device.port))  # a datagram read brings the count
            late += 1
            time.sleep(0.05)
        events = device.poll(time.monotonic())
        device.close()
    assert device.dropped > 0 and len(events) + device.dropped == sent + late
    told = [r.getMessage() for r in caplog.records if "dropped by the system" in r.getMessage()]
    assert told and f"{device.dropped} datagrams dropped" in told[0]
    assert f"UDP 127.0.0.1:{device.port}" in told[0]
    assert device.status().detail == f"{device.dropped} datagrams dropped by the system"


def test_a_device_that_never_hears_anything_says_so_once(monkeypatch, caplog):
    """A phone app sending to this machine's LAN address while the device listens on
    127.0.0.1 (the default) delivered nothing, and nothing said why."""
    monkeypatch.setattr(device_module, "SILENT_AFTER", 0.1)
    quiet, heard = OscDevice("mocap", 0), OscDevice("gloves", 0)
    quiet.open()
    heard.open()
    try:
        SimpleUDPClient("127.0.0.1", heard.port).send_message("/colosseum/wheel/left", 1)
        deadline = time.monotonic() + 5.0
        while heard.received == 0 and time.monotonic() < deadline:
            time.sleep(0.001)
        with caplog.at_level(logging.WARNING, logger="colosseum.input"):
            for now in (100.0, 100.05, 100.2, 100.3, 200.0):
                quiet.poll(now)
                heard.poll(now)
    finally:
        quiet.close()
        heard.close()
    assert [r.getMessage() for r in caplog.records] == [
        f"input device 'mocap' (osc, UDP 127.0.0.1:{quiet.port}): nothing received in 0.1 s "
        f"since it opened (it listens on 127.0.0.1 only: a sender on another machine needs "
        f'Address "0.0.0.0", or --input osc:0.0.0.0:{quiet.port})']


def test_a_sender_inventing_names_is_held_to_a_bounded_table(tmp_path: Path, caplog):
    """A counter in the addresses would add a table entry per packet for ever: names past
    the first MAX_SOURCES are bad messages, the ones already heard keep working."""
    from services.input.hub import MAX_SOURCES

    with input_engine(osc_scene(), tmp_path) as engine:
        client = SimpleUDPClient("127.0.0.1", port_of(engine))
        state = engine.resource(InputState)
        device = osc_device(engine)
        sent = MAX_SOURCES + 100
        for i in range(sent):
            client.send_message(f"/colosseum/button/glove/b{i}", 1)
            if i % 200 == 199:  # let the device's thread keep up with the burst
                run_until(engine, lambda n=i: device.status().received > n - 50)
        run_until(engine, lambda: device.status().received >= sent)
        engine.step()
        assert len(state.buttons) == MAX_SOURCES
        client.send_message("/colosseum/button/glove/b0", 0)
        run_until(engine, lambda: not state.button("glove", "b0"))
    assert f"a new input name beyond the first {MAX_SOURCES}" in caplog.text
