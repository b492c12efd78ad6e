"""The latest-state table answers the controller input names, from typed events."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from engine.scene.inputs import ButtonSpec, InputSpec, TrackerSpec, WheelSpec
from services.input import (
    Axis,
    Button,
    DeviceFound,
    DeviceLost,
    InputHub,
    Key,
    TrackerPose,
    WheelCount,
    parse_binding,
)
from services.input.record import FrameInput


def test_every_input_name_reads_its_value():
    spec = InputSpec(trackers=(TrackerSpec("hand_r", offset=(0.0, 0.0, 1.0)),),
                     wheels=(WheelSpec("left", counts_per_turn=100),),
                     buttons=(ButtonSpec("grab", "glove_r", "index", invert=True),))
    hub = InputHub(spec, [])
    state = hub.state
    read = {name: parse_binding(name) for name in (
        "tracker:hand_r", "wheel:left", "axis:pad/x", "button:glove_r/index", "button:grab",
        "key:up/down", "key:space")}
    assert all(state.read(b) is None for n, b in read.items() if n[:2] in ("tr", "wh", "ax"))
    events = [TrackerPose("hand_r", (0.5, 0.0, 0.2), (1.0, 0.0, 0.0, 0.0), None, 10.0),
              Axis("pad", "x", -0.5, 10.0), Button("glove_r", "index", False, 10.0),
              Key("up", True, "keyboard", 10.0)]
    events += [WheelCount("left", 5 * i, 10.0 + 0.01 * i) for i in range(11)]
    hub.apply(FrameInput(10.1, events))
    np.testing.assert_array_equal(state.read(read["tracker:hand_r"]), [0.5, 0.0, 1.2])
    # 5 counts per 10 ms, 100 counts a turn: 5 turns per second
    assert state.read(read["wheel:left"]) == pytest.approx(2 * math.pi * 5)
    assert state.read(read["axis:pad/x"]) == -0.5
    assert state.read(read["button:glove_r/index"]) == 1.0  # a normally-closed switch read 0
    assert state.read(read["button:grab"]) == 1.0
    assert state.read(read["key:up/down"]) == 1.0 and state.read(read["key:space"]) == 0.0
    hub.apply(FrameInput(10.2, [DeviceLost("hand_r", 10.2)]))
    assert state.read(read["tracker:hand_r"]) is None  # untracked: nothing to follow
    assert not state.tracker("hand_r").tracked
    hub.apply(FrameInput(11.0, []))
    assert state.read(read["wheel:left"]) == 0.0  # no count for most of a second: standing


# (wheel:bob/left and button:alice/glove/index name a network user's sources: services.net)
@pytest.mark.parametrize("name", ["tracker:", "wheel:a/", "axis:x", "button:a//c", "mouse:x",
                                  "key:", "axis:/x", "tracker:/hand"])
def test_malformed_input_names_are_refused_with_the_forms_allowed(name: str):
    with pytest.raises(ValueError, match="use tracker:NAME, wheel:NAME"):
        parse_binding(name)


def test_sources_found_or_lost_together_are_told_in_one_line(caplog):
    """A sender with a counter in its addresses made a thousand sources in one frame, and
    a line each when they were found and again when they were lost."""
    hub = InputHub(InputSpec(), [])
    with caplog.at_level(logging.INFO, logger="colosseum.input"):
        hub.apply(FrameInput(1.0, [DeviceFound(f"t{i}", 1.0) for i in range(1000)]))
        hub.apply(FrameInput(2.0, [DeviceLost(f"t{i}", 2.0) for i in range(1000)]))
        hub.apply(FrameInput(3.0, [DeviceLost("hand_r", 3.0)]))
    lines = [r.getMessage() for r in caplog.records]
    assert lines == [
        "input sources 't0', 't1', 't2', 't3', 't4' and 995 more found",
        "input sources 't0', 't1', 't2', 't3', 't4' and 995 more lost: nothing received for "
        "their timeout; untracked until they send again",
        "input source 'hand_r' lost: nothing received for its timeout; untracked until it "
        "sends again"]
    assert len(hub.state.lost) == 1001
