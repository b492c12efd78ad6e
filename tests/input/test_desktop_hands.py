"""Desktop emulation of tracked hands: keys shape the fingers of either hand, blended."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from input_helpers import input_engine

from engine.rotation import euler_to_quat, quat_to_matrix
from services.input import InputHub, InputState
from services.input.desktop import BLEND, SHAPE_KEYS, DesktopDevice, WindowDevice
from services.input.events import FINGERS, HAND_JOINTS, HandJoints
from services.input.hand_pose import GESTURES, curl

FPS = 120


def _device() -> tuple[WindowDevice, DesktopDevice]:
    window = WindowDevice()
    desktop = DesktopDevice("desktop", window)
    desktop.view.orientation = np.array(euler_to_quat((0.0, 0.0, 30.0)))  # turned 30° left
    desktop.view.position = np.array([0.5, -2.0, 1.4])
    return window, desktop


def _poll(desktop: DesktopDevice, start: float, seconds: float) -> dict[str, HandJoints]:
    """Poll at FPS for ``seconds`` from ``start``; the latest joints of each hand sent."""
    latest: dict[str, HandJoints] = {}
    for frame in range(round(seconds * FPS) + 1):
        for event in desktop.poll(start + frame / FPS):
            if isinstance(event, HandJoints):
                latest[event.device] = event
    return latest


def _curls(hand: HandJoints) -> dict[str, float]:
    return {f: curl(hand, f) for f in FINGERS}


@pytest.mark.parametrize("hand", ["hand_l", "hand_r"])
@pytest.mark.parametrize(("key", "shape"), sorted(SHAPE_KEYS.items()))
def test_each_key_gives_its_hand_the_named_shape(hand: str, key: str, shape: str):
    """The joints the device sends, read back as curls (hand_pose.curl, from positions),
    are the gesture's once the blend is over; the other hand stays open."""
    window, desktop = _device()
    window.pointer(0.3, 0.6)  # the right hand
    window.key("tab", True)
    window.pointer(0.6, 0.4)  # the left hand: both are posed now
    if hand == "hand_r":
        window.key("tab", True)
    window.key(key, True)
    window.key(key, False)
    latest = _poll(desktop, 0.0, BLEND + 0.05)
    other = "hand_l" if hand == "hand_r" else "hand_r"
    want = GESTURES[shape]
    assert _curls(latest[hand]) == pytest.approx(want, abs=2e-3)
    assert _curls(latest[other]) == pytest.approx(GESTURES["open"], abs=2e-3)


def test_a_new_shape_blends_in_smoothly_over_the_blend_time():
    """From open to fist: every finger's curl rises monotonically, is half way at half
    the blend time (smoothstep), and reaches the fist at BLEND s; no frame jumps more
    than the steepest smoothstep slope allows (1.5 per BLEND)."""
    window, desktop = _device()
    window.pointer(0.5, 0.5)
    _poll(desktop, 0.0, 0.1)
    window.key("v", True)
    index = []
    for frame in range(round(2 * BLEND * FPS)):
        t = 0.1 + (frame + 1) / FPS
        for event in desktop.poll(t):
            if isinstance(event, HandJoints):
                index.append((t, curl(event, "index")))
    times, values = (np.array(v) for v in zip(*index, strict=True))
    assert np.all(np.diff(values) >= -1e-9)
    pressed = 0.1 + 1 / FPS  # the frame the key arrived still shows the open hand
    assert times[0] == pytest.approx(pressed + 1 / FPS)
    s = 1 / (BLEND * FPS)
    assert values[0] == pytest.approx(s * s * (3 - 2 * s), abs=1e-3)
    half = np.interp(pressed + BLEND / 2, times, values)
    assert half == pytest.approx(0.5, abs=0.03)
    assert values[times >= pressed + BLEND] == pytest.approx(1.0, abs=2e-3)
    assert np.max(np.diff(values)) <= 1.5 / (BLEND * FPS) + 1e-3
    # once there, a still hand sends nothing more
    assert times[-1] <= pressed + BLEND + 1e-9
    assert not [e for e in desktop.poll(1.0) if isinstance(e, HandJoints)]


def test_the_pinch_button_shows_the_pinch_while_it_is_down():
    window, desktop = _device()
    window.pointer(0.5, 0.5)
    window.key("c", True)  # point
    assert _curls(_poll(desktop, 0.0, 0.3)["hand_r"]) == pytest.approx(GESTURES["point"],
                                                                        abs=2e-3)
    window.mouse_button("left", True)
    assert _curls(_poll(desktop, 1.0, 0.3)["hand_r"]) == pytest.approx(GESTURES["pinch"],
                                                                        abs=2e-3)
    window.mouse_button("left", False)
    assert _curls(_poll(desktop, 2.0, 0.3)["hand_r"]) == pytest.approx(GESTURES["point"],
                                                                        abs=2e-3)


@pytest.mark.parametrize("left", [False, True])
def test_the_emulated_hand_lies_palm_down_at_the_tracker_fingers_into_the_view(left: bool):
    """Its palm joint is the tracker's position; the fingers point along the view, the
    back of the hand up; the thumb is on the hand's inner side (a right hand's to the
    left of the view, a left hand's to the right)."""
    window, desktop = _device()
    if left:
        window.key("tab", True)
    window.pointer(0.7, 0.2)
    latest = _poll(desktop, 0.0, 0.0)
    name = "hand_l" if left else "hand_r"
    joints = latest[name]
    p = np.array(joints.positions)
    tracker = desktop.poses[0 if left else 1]
    assert tracker is not None
    np.testing.assert_allclose(p[0], tracker[0], atol=1e-12)
    right, forward, up = quat_to_matrix(desktop.view.orientation).T
    middle = p[HAND_JOINTS.index("middle_tip")] - p[HAND_JOINTS.index("wrist")]
    assert middle @ forward > 0.95 * np.linalg.norm(middle)
    wrist_axes = quat_to_matrix(np.array(joints.orientations[1]))
    np.testing.assert_allclose(wrist_axes[:, 2], up, atol=1e-9)  # the back of the hand
    thumb = p[HAND_JOINTS.index("thumb_tip")] - p[0]
    assert (thumb @ right > 0.02) if left else (thumb @ right < -0.02)


def test_the_input_state_holds_each_hands_joints_every_frame(tmp_path: Path):
    """Through the input plugin: after the mouse placed the hand and a key made a fist,
    the state table has its joints on every later frame, the fist's curls, though a still
    hand sends nothing."""
    scene = 'Camera { Position [0 -5 1.5] LookAt [0 0 1.5] }\nInput { Device { Kind "desktop" } }\n'
    with input_engine(scene, tmp_path) as engine:
        engine.step()
        engine.resource(InputHub).clock = lambda: engine.time  # blends in simulated time
        window = engine.resource(WindowDevice)
        state = engine.resource(InputState)
        assert state.hand("hand_r") is None
        window.pointer(0.5, 0.5)
        window.key("v", True)
        engine.run(seconds=0.4)
        hand = state.hand("hand_r")
        assert hand is not None and state.hand("hand_l") is None
        assert _curls(hand) == pytest.approx(GESTURES["fist"], abs=2e-3)
        np.testing.assert_allclose(hand.positions[0], state.tracker("hand_r").position,
                                   atol=1e-9)
        sent: list[HandJoints] = []
        engine.events.subscribe(HandJoints, sent.append)
        engine.run(frames=3)
        assert sent == [] and state.hand("hand_r") is hand
