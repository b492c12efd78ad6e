"""Tracked hands through the input layer: recorded and replayed bit for bit, checked like
every other event, calibrated (mirroring included), filtered per joint, lost and found."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pytest

from engine.rotation import (
    euler_to_quat,
    matrix_to_quat,
    quat_from_rotation_vector,
    quat_product,
    quat_to_matrix,
)
from engine.scene.inputs import InputSpec, TrackerSpec, axes_map
from services.input import DeviceFound, DeviceLost, InputHub, ReplayError, read_recording
from services.input.events import HAND_JOINTS, HandJoints
from services.input.filters import OneEuro, OneEuroRotation
from services.input.hand_pose import FINGERS, GESTURES, curl, pose_hand
from services.input.record import FrameInput, RecordWriter, event_from_record, event_record

WRIST = (0.3, -0.1, 1.1)
TURN = euler_to_quat((10.0, -20.0, 35.0))


def hand(name: str = "hand_r", t: float = 0.0, shape: str = "pinch",
         position: tuple = WRIST) -> HandJoints:
    return pose_hand(name, position, TURN, GESTURES[shape], timestamp=t)


class Clock:
    """The hub's clock, moved by the test."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


# -- recording -------------------------------------------------------------------------
def test_a_hand_line_reads_back_as_the_same_event_bit_for_bit():
    event = hand(t=12.345678901)
    assert event.timestamp == 12.345678901
    event = HandJoints(event.device, event.positions, event.orientations, event.radii,
                       tuple(i % 7 != 3 for i in range(26)), event.timestamp)
    record = json.loads(json.dumps(event_record(4, event)))
    assert record["type"] == "hand" and record.pop("frame") == 4
    assert event_from_record(record) == event


def bad_hand_line(change) -> str:
    record = event_record(1, hand())
    change(record)
    return json.dumps(record)


@pytest.mark.parametrize(("change", "why"), [
    (lambda r: r["positions"].pop(), "expected a list of 26"),
    (lambda r: r["positions"][5].__setitem__(1, float("nan")), "not finite"),
    (lambda r: r["orientations"][7].__setitem__(0, 2.0), "index_proximal quaternion length"),
    (lambda r: r["radii"].__setitem__(25, -0.01), "little_tip radius"),
    (lambda r: r["valid"].__setitem__(0, 1), "valid must be true or false"),
    (lambda r: r.pop("radii"), "radii"),
])
def test_a_bad_hand_line_names_the_file_line_and_joint(tmp_path: Path, change, why):
    path = tmp_path / "bad.jsonl"
    path.write_text('{"format": "colosseum-input", "version": 1}\n' + bad_hand_line(change)
                    + "\n")
    with pytest.raises(ReplayError, match=rf"bad.jsonl:2: not a recorded input line .*{why}"):
        read_recording(path)


def test_a_recorded_run_with_hands_replays_to_the_same_joints(tmp_path: Path):
    spec = InputSpec(trackers=(TrackerSpec("hand_l", filter="oneeuro", offset=(0, 0, 0.2),
                                           axes=axes_map("-x y z")),))
    clock = Clock()
    live = InputHub(spec, [], clock=clock)
    live.record(tmp_path / "run.input", {"scene": "", "seed": 0})
    rng = np.random.default_rng(3)
    seen = []
    for frame in range(20):
        clock.now += 1 / 90
        jitter = tuple(rng.normal(0.0, 0.002, 3))
        live.inject(hand("hand_l", 0.0, "open", tuple(np.add(WRIST, jitter))))
        live.step(frame)
        seen.append(live.state.hand("hand_l"))
    live.close()
    replay = InputHub(spec, [])
    replay.replay(read_recording(tmp_path / "run.input"))
    for frame in range(20):
        replay.step(frame)
        assert replay.state.hand("hand_l") == seen[frame]


# -- calibration -----------------------------------------------------------------------
def test_offset_rotation_and_scale_move_every_joint_and_scale_the_radii():
    turn = euler_to_quat((0.0, 0.0, 90.0))
    spec = TrackerSpec("hand_r", offset=(1.0, 2.0, 3.0), rotation=turn, scale=0.01)
    hub = InputHub(InputSpec(trackers=(spec,)), [])
    raw = pose_hand("hand_r", (30.0, 40.0, 110.0), TURN, GESTURES["point"], scale=100.0)
    hub.inject(raw)
    hub.step(0)
    out = hub.state.hand("hand_r")
    c = quat_to_matrix(np.asarray(turn))
    np.testing.assert_allclose(out.positions, np.asarray(raw.positions) @ c.T * 0.01
                               + [1.0, 2.0, 3.0], atol=1e-12)
    np.testing.assert_allclose(out.radii, np.asarray(raw.radii) * 0.01, atol=1e-15)
    frames = np.array([quat_to_matrix(np.asarray(q)) for q in out.orientations])
    raw_frames = np.array([quat_to_matrix(np.asarray(q)) for q in raw.orientations])
    np.testing.assert_allclose(frames, c @ raw_frames, atol=1e-12)
    # the same hand as the anatomy builds it at the calibrated wrist, 1/100 the size
    expected = pose_hand("hand_r", c @ (0.01 * np.asarray((30.0, 40.0, 110.0))) + (1, 2, 3),
                         matrix_to_quat(c @ quat_to_matrix(np.asarray(TURN))),
                         GESTURES["point"])
    np.testing.assert_allclose(out.positions, expected.positions, atol=1e-12)


def test_a_mirroring_axes_map_turns_a_right_hand_into_the_left_hand_it_mirrors():
    """Mirror therapy: the tracked right hand, reflected across x = 0, is the left hand
    the anatomy builds at the reflected wrist, joint frames included, and bends alike."""
    hub = InputHub(InputSpec(trackers=(TrackerSpec("hand_r", axes=axes_map("-x y z")),)), [])
    raw = hand(shape="pinch")
    hub.inject(raw)
    hub.step(0)
    out = hub.state.hand("hand_r")
    m, d = np.diag([-1.0, 1.0, 1.0]), np.diag([1.0, -1.0, 1.0])
    wrist = m @ quat_to_matrix(np.asarray(TURN)) @ d  # a proper rotation
    left = pose_hand("mirror", m @ np.asarray(WRIST), matrix_to_quat(wrist),
                     GESTURES["pinch"], left=True)
    np.testing.assert_allclose(out.positions, left.positions, atol=1e-12)
    frames = np.array([quat_to_matrix(np.asarray(q)) for q in out.orientations])
    left_frames = np.array([quat_to_matrix(np.asarray(q)) for q in left.orientations])
    np.testing.assert_allclose(frames, left_frames, atol=1e-12)
    assert np.allclose(np.linalg.det(frames), 1.0)
    for finger in FINGERS:
        assert curl(out, finger) == pytest.approx(curl(raw, finger), abs=1e-9)


# -- filtering -------------------------------------------------------------------------
def test_every_joint_has_its_own_one_euro_filter():
    """A hand held still with 2 mm and 2 degrees of sensor noise: each joint's filtered
    track is what one-euro filters of that joint alone give, and steadier than the raw."""
    spec = TrackerSpec("hand_r", filter="oneeuro", min_cutoff=1.0, beta=0.5)
    clock = Clock()
    hub = InputHub(InputSpec(trackers=(spec,)), [], clock=clock)
    rng = np.random.default_rng(7)
    raws, outs, raw_qs, out_qs = [], [], [], []
    for frame in range(180):
        clock.now = 100.0 + frame / 90
        base = hand(t=clock.now)
        noisy = np.asarray(base.positions) + rng.normal(0.0, 0.002, (26, 3))
        shaken = [quat_product(quat_from_rotation_vector(rng.normal(0.0, 0.035, 3)), q)
                  for q in base.orientations]
        raw = HandJoints("hand_r", tuple(map(tuple, noisy)), tuple(shaken), base.radii,
                         base.valid, base.timestamp)
        hub.inject(raw)
        hub.step(frame)
        raws.append(noisy)
        raw_qs.append(shaken)
        outs.append(np.asarray(hub.state.hand("hand_r").positions))
        out_qs.append(hub.state.hand("hand_r").orientations)
    raws_a, outs_a = np.array(raws), np.array(outs)
    for joint in (0, HAND_JOINTS.index("index_tip"), 25):
        alone, turn = OneEuro(1.0, 0.5), OneEuroRotation(1.0, 0.5)
        track = [alone(tuple(raws_a[i, joint]), 100.0 + i / 90) for i in range(180)]
        np.testing.assert_allclose(outs_a[:, joint], track, atol=1e-12)
        turned = [turn(raw_qs[i][joint], 100.0 + i / 90) for i in range(180)]
        np.testing.assert_allclose([q[joint] for q in out_qs], turned, atol=1e-12)
    assert outs_a[90:].std(axis=0).mean() < 0.5 * raws_a[90:].std(axis=0).mean()


# -- lost, found, garbage --------------------------------------------------------------
def test_a_silent_hand_is_lost_and_found_when_it_sends_again():
    clock = Clock()
    hub = InputHub(InputSpec(lost_after=0.2), [], clock=clock)
    hub.inject(hand())
    events = hub.step(0)
    assert any(isinstance(e, DeviceFound) and e.device == "hand_r" for e in events)
    assert hub.state.hand("hand_r") is not None
    clock.now += 0.3
    events = hub.step(1)
    assert [e.device for e in events if isinstance(e, DeviceLost)] == ["hand_r"]
    assert hub.state.hand("hand_r") is None
    clock.now += 0.01
    hub.inject(hand(shape="fist"))
    events = hub.step(2)
    assert any(isinstance(e, DeviceFound) for e in events)
    assert curl(hub.state.hand("hand_r"), "index") == pytest.approx(1.0, abs=0.02)


def test_a_hand_past_float_range_or_of_the_wrong_shape_is_told_and_not_applied(caplog):
    spec = TrackerSpec("glove", scale=1e300)
    hub = InputHub(InputSpec(trackers=(spec,)), [])
    big = hand("glove", position=(1e10, 0.0, 0.0))
    short = HandJoints("peer_hand", big.positions[:25], big.orientations, big.radii, big.valid)
    with caplog.at_level(logging.WARNING, logger="colosseum.input"):
        hub.inject(big)
        hub.inject(short)
        assert not [e for e in hub.step(0) if isinstance(e, HandJoints)]
        hub.close()
    assert hub.state.hand("glove") is None and hub.state.hand("peer_hand") is None
    assert "input source 'glove': 1 bad message ignored, e.g. a hand's calibrated" \
        in caplog.text
    assert "input source 'peer_hand': 1 bad message ignored, e.g. a hand needs 26" in caplog.text


def test_a_recorded_event_stream_holds_the_raw_hand(tmp_path: Path):
    path = tmp_path / "raw.input"
    writer = RecordWriter(path, {"scene": "", "seed": 0, "devices": []})
    writer.write(0, FrameInput(1.0, [hand()]))
    writer.close()
    assert read_recording(path).frames[0].events == [hand()]
