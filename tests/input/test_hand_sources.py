"""Hands from real transports on this machine: OSC datagrams on 127.0.0.1 and an LSL
outlet of 26 x 8 channels reach ``services.input.hand``; bad messages are counted, told
with the device's name and never applied."""

from __future__ import annotations

import logging
import re
import time
from pathlib import Path

import numpy as np
import pytest
from input_helpers import input_engine, run_until
from pythonosc.udp_client import SimpleUDPClient

from engine.rotation import euler_to_quat
from services.input import DeviceError, InputHub, InputState
from services.input.events import HandJoints
from services.input.hand_pose import GESTURES, curl, pose_hand
from services.input.osc import OscDevice


def flat(hand: HandJoints) -> list[float]:
    """The 208 numbers of a hand message: per joint x y z qw qx qy qz radius."""
    return [v for p, q, r in zip(hand.positions, hand.orientations, hand.radii, strict=True)
            for v in (*p, *q, r)]


def a_hand(shape: str = "point") -> HandJoints:
    return pose_hand("glove_r", (0.2, 0.4, 1.0), euler_to_quat((0.0, 30.0, 90.0)),
                     GESTURES[shape])


def osc_devices(engine) -> dict[str, OscDevice]:
    engine.start()
    hub = engine.resource(InputHub)
    hub.start()
    return {d.name: d for d in hub.devices if isinstance(d, OscDevice)}


def test_an_osc_hand_reaches_the_state_table(tmp_path: Path):
    scene = 'Input { Device { Kind "osc" Port 0 } }'
    with input_engine(scene, tmp_path) as engine:
        port = osc_devices(engine)["osc"].port
        hand = a_hand()
        SimpleUDPClient("127.0.0.1", port).send_message("/colosseum/hand/glove_r", flat(hand))
        state = engine.resource(InputState)
        run_until(engine, lambda: state.hand("glove_r") is not None)
        got = state.hand("glove_r")
        # OSC floats are 32 bits: positions and radii to float32, quaternions normalised
        f32 = np.float32
        np.testing.assert_array_equal(got.positions, np.asarray(hand.positions, f32))
        np.testing.assert_array_equal(got.radii, np.asarray(hand.radii, f32))
        np.testing.assert_allclose(got.orientations, hand.orientations, atol=1e-6)
        assert got.valid == (True,) * 26
        assert abs(curl(got, "index") - curl(hand, "index")) < 1e-5


def test_bad_osc_hands_are_counted_told_and_not_applied(tmp_path: Path, caplog):
    scene = 'Input { Device { ID "gloves" Kind "osc" Port 0 } }'
    with input_engine(scene, tmp_path) as engine:
        device = osc_devices(engine)["gloves"]
        client = SimpleUDPClient("127.0.0.1", device.port)
        good = flat(a_hand())
        nan = list(good)
        nan[8 * 9 + 1] = float("nan")  # joint 9's y
        tilted = list(good)
        tilted[8 * 3 + 3] = 3.0  # joint 3's qw: no unit quaternion
        with caplog.at_level(logging.WARNING, logger="colosseum.input"):
            client.send_message("/colosseum/hand/glove_r", good[:-1])
            client.send_message("/colosseum/hand/glove_r", nan)
            client.send_message("/colosseum/hand/glove_r", tilted)
            client.send_message("/colosseum/hand/", good)
            client.send_message("/colosseum/wheel/sentinel", [1])  # after the bad ones
            state = engine.resource(InputState)
            run_until(engine, lambda: state.wheel("sentinel") is not None)
            engine.close()
        assert device.status().bad == 4
        assert state.hand("glove_r") is None
        told = " ".join(r.getMessage() for r in caplog.records)
        # told in one warning, or in two where the datagrams came in over two frames
        counts = re.findall(rf"input device 'gloves' \(osc, UDP 127\.0\.0\.1:{device.port}\): "
                            r"(\d+) bad messages", told)
        assert sum(map(int, counts)) == 4
        assert "/colosseum/hand/glove_r (26 joints x x y z qw qx qy qz radius) takes 208 " \
               "numbers, got 207" in told


def test_a_hand_bound_to_one_device_ignores_another(tmp_path: Path):
    scene = ('Input { Device { ID "a" Kind "osc" Port 0 } Device { ID "b" Kind "osc" Port 0 }\n'
             '  Tracker { ID "glove_r" Device "b" Offset [0 0 1] } }')
    with input_engine(scene, tmp_path) as engine:
        devices = osc_devices(engine)
        hand = a_hand("fist")
        SimpleUDPClient("127.0.0.1", devices["a"].port).send_message(
            "/colosseum/hand/glove_r", flat(hand))
        run_until(engine, lambda: devices["a"].status().received == 1)
        engine.step()
        state = engine.resource(InputState)
        assert state.hand("glove_r") is None
        SimpleUDPClient("127.0.0.1", devices["b"].port).send_message(
            "/colosseum/hand/glove_r", flat(hand))
        run_until(engine, lambda: state.hand("glove_r") is not None)
        lifted = np.asarray(hand.positions, np.float32).astype(float) + [0.0, 0.0, 1.0]
        np.testing.assert_allclose(state.hand("glove_r").positions, lifted, atol=1e-12)


def test_an_lsl_hand_stream_reaches_the_state_table(tmp_path: Path):
    from services.input.lsl import LslDevice, load_pylsl

    try:
        lsl = load_pylsl("machine")
    except DeviceError as exc:
        pytest.skip(f"liblsl not available: {exc}")
    info = lsl.StreamInfo("lsl_hand", "Hand", 208, lsl.IRREGULAR_RATE, lsl.cf_double64,
                          "lsl_hand-test")
    outlet = lsl.StreamOutlet(info)
    scene = 'Input { Device { Kind "lsl" Scope "machine" Streams ["lsl_hand"] } }'
    hand = a_hand("pinch")
    bad = flat(hand)
    bad[0] = float("inf")
    with input_engine(scene, tmp_path) as engine:
        engine.start()
        device = next(d for d in engine.resource(InputHub).devices
                      if isinstance(d, LslDevice))
        state = engine.resource(InputState)
        deadline = time.monotonic() + 20.0
        while time.monotonic() < deadline and (state.hand("lsl_hand") is None
                                               or device.status().bad == 0):
            outlet.push_sample(bad)
            outlet.push_sample(flat(hand))
            engine.step()
            time.sleep(0.01)
        got = state.hand("lsl_hand")
        assert got is not None, "no hand arrived over LSL"
        assert device.status().bad >= 1
        np.testing.assert_array_equal(got.positions, hand.positions)  # doubles: exact
        np.testing.assert_array_equal(got.radii, hand.radii)
        np.testing.assert_allclose(got.orientations, hand.orientations, atol=1e-15)


def test_osc_hands_recorded_live_replay_to_the_same_joints(tmp_path: Path):
    """InputRecorder and InputReplayer carry hands: a live OSC session (filtered, offset)
    replayed with the port taken (the device never opens) gives the same joints."""
    import socket

    from services.input import InputRecorder, InputReplayer

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    scene = (f'Input {{ Device {{ Kind "osc" Port {port} }}\n'
             '  Tracker { ID "glove_r" Filter "oneeuro" Offset [0 0 0.3] } }')
    path = tmp_path / "hands.input"

    def run(live: bool, system: object) -> list:
        seen = []
        with input_engine(scene, tmp_path) as engine:
            engine.add_system(system)
            engine.start()
            client = SimpleUDPClient("127.0.0.1", port)
            for frame in range(40):
                if live and frame < 30:
                    curls = {f: frame / 30 for f in GESTURES["fist"]}
                    hand = pose_hand("glove_r", (0.1, 0.3 + 0.01 * frame, 1.0),
                                     (1.0, 0.0, 0.0, 0.0), curls)
                    client.send_message("/colosseum/hand/glove_r", flat(hand))
                    time.sleep(0.005)
                engine.step()
                seen.append(engine.resource(InputState).hand("glove_r"))
        return seen

    live = run(True, InputRecorder(path))
    assert sum(h is not None for h in live) > 10
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as blocker:
        blocker.bind(("127.0.0.1", port))
        replayed = run(False, InputReplayer(path))
    assert replayed == live
