"""Lab Streaming Layer round trip on this machine: outlets in, markers and values out."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from input_helpers import input_engine

from engine.events import CustomEvent
from services.input import DeviceError, InputHub, InputState
from services.input import lsl as lsl_device
from services.input.lsl import LslDevice, load_pylsl

try:  # discovery kept to this computer (127.0.0.1) for the whole test process
    lsl = load_pylsl("machine")
except DeviceError as exc:
    pytest.skip(f"liblsl not available: {exc}", allow_module_level=True)

SCENE = """
Input { Device { Kind "lsl" Scope "machine" Streams ["test_hand" "type:Wheel" "test_glove"] } }
Output { Kind "lsl" Scope "machine" Name "colo" Value "tracker:test_hand" }
"""


def outlet(name: str, kind: str, channels: int, fmt: object, labels: tuple[str, ...] = ()):
    info = lsl.StreamInfo(name, kind, channels, lsl.IRREGULAR_RATE, fmt, f"{name}-test")
    if labels:
        chans = info.desc().append_child("channels")
        for label in labels:
            chans.append_child("channel").append_child_value("label", label)
    return lsl.StreamOutlet(info)


def test_lsl_streams_reach_the_state_table_and_markers_go_out(tmp_path: Path):
    hand = outlet("test_hand", "Mocap", 7, lsl.cf_double64)
    wheel = outlet("test_wheel", "Wheel", 1, lsl.cf_int32)
    glove = outlet("test_glove", "Buttons", 2, lsl.cf_int8, ("index", "middle"))
    with input_engine(SCENE, tmp_path) as engine:
        engine.start()
        state = engine.resource(InputState)
        deadline = time.monotonic() + 20.0
        count = 0
        while time.monotonic() < deadline and not (
                state.tracker("test_hand") and state.wheel("test_wheel")
                and state.button("test_glove", "middle")):
            count += 8
            hand.push_sample([0.25, -0.5, 1.25, 1.0, 0.0, 0.0, 0.0])
            wheel.push_sample([count])
            glove.push_sample([0, 1])
            engine.step()
            time.sleep(0.01)
        assert state.tracker("test_hand") is not None, "no pose arrived over LSL"
        np.testing.assert_array_equal(state.tracker("test_hand").position, [0.25, -0.5, 1.25])
        assert state.wheel("test_wheel").count > 0
        assert state.button("test_glove", "middle") and not state.button("test_glove", "index")
        # out: the engine's markers and the tracker as a 7-channel value stream
        markers = lsl.resolve_byprop("name", "colo-markers", minimum=1, timeout=10.0)
        values = lsl.resolve_byprop("name", "colo-tracker:test_hand", minimum=1, timeout=10.0)
        assert markers and values
        marker_in = lsl.StreamInlet(markers[0])
        value_in = lsl.StreamInlet(values[0])
        marker_in.open_stream(timeout=5.0)
        value_in.open_stream(timeout=5.0)
        time.sleep(0.5)  # let the inlets connect before anything is sent
        got, sample = None, None
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline and (got is None or sample is None):
            engine.events.emit(CustomEvent("marker", "grasp cup"))
            engine.step()
            got = got or marker_in.pull_sample(timeout=0.05)[0]
            sample = sample or value_in.pull_sample(timeout=0.05)[0]
        assert got == ["grasp cup"]
        np.testing.assert_allclose(sample, [0.25, -0.5, 1.25, 1.0, 0.0, 0.0, 0.0])


def test_samples_stamped_outside_now_are_counted_not_applied(tmp_path: Path):
    """An outlet stamps samples as it likes: NaN, or a time far from now, would stall the
    wheel's rate and the watchdog (and a recording of NaN could not be replayed)."""
    wheel = outlet("stamped_wheel", "Wheel", 1, lsl.cf_int32)
    scene = 'Input { Device { Kind "lsl" Scope "machine" Streams ["stamped_wheel"] } }'
    with input_engine(scene, tmp_path) as engine:
        engine.start()
        hub = engine.resource(InputHub)
        device = next(d for d in hub.devices if isinstance(d, LslDevice))
        state = engine.resource(InputState)
        deadline = time.monotonic() + 20.0
        while time.monotonic() < deadline and device.status().bad < 3:
            wheel.push_sample([5], float("nan"))
            wheel.push_sample([6], lsl.local_clock() + 60.0)
            wheel.push_sample([7], lsl.local_clock() - 1e6)
            engine.step()
            time.sleep(0.02)
        assert device.status().bad >= 3 and state.wheel("stamped_wheel") is None
        while time.monotonic() < deadline and state.wheel("stamped_wheel") is None:
            wheel.push_sample([8])
            engine.step()
            time.sleep(0.02)
        assert state.wheel("stamped_wheel").count == 8
        assert abs(state.wheel("stamped_wheel").timestamp - time.monotonic()) < 1.0


def test_a_stream_that_is_not_there_is_told_once_and_still_looked_for(monkeypatch, caplog):
    """A misspelt stream name (or an outlet not started) waited in silence for ever."""
    monkeypatch.setattr(lsl_device, "NOT_FOUND_AFTER", 0.2)
    monkeypatch.setattr(lsl_device, "RESOLVE_WAIT", 0.1)
    device = LslDevice("lab", ("no_such_stream",), scope="machine")
    device.open()
    try:
        deadline = time.monotonic() + 10.0
        while "no LSL stream" not in caplog.text and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.3)  # more searches: still one message
    finally:
        device.close()
    told = [r.getMessage() for r in caplog.records if "no LSL stream" in r.getMessage()]
    assert told == ["input device 'lab' (lsl, streams no_such_stream): no LSL stream with name "
                    "'no_such_stream' found in 0.2 s; still looking (is its outlet running, and "
                    "within the device's Scope 'machine'?)"]
