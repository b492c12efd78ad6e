"""Desktop emulation: the window's mouse and keys drive hands, pinches and wheel counters."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from input_helpers import input_engine

from engine.events import KeyEvent
from engine.rotation import euler_to_quat, quat_to_matrix
from services.input import Button, InputState, WheelCount
from services.input.desktop import DesktopDevice, DesktopView, WindowDevice

SCENE = """
Camera { Position [0 -5 1.5] LookAt [0 0 1.5] Fov 60 }
Input { Device { Kind "desktop" TurnsPerSecond 0.5 } Wheel { ID "left" } Wheel { ID "right" } }
"""


def test_the_mouse_moves_the_hand_in_the_camera_plane_and_scroll_sets_its_depth(
        tmp_path: Path):
    with input_engine(SCENE, tmp_path, options={"size": "800x600"}) as engine:
        engine.step()
        window = engine.resource(WindowDevice)
        state = engine.resource(InputState)
        window.pointer(0.5, 0.5)
        engine.step()
        # straight ahead of the camera at the default depth of 0.6 m
        np.testing.assert_allclose(state.tracker("hand_r").position, [0, -4.4, 1.5], atol=1e-9)
        window.scroll(4)  # 4 notches further: 0.8 m
        window.pointer(1.0, 0.0)  # the top right corner
        engine.step()
        half_height = 0.8 * math.tan(math.radians(30))
        np.testing.assert_allclose(state.tracker("hand_r").position,
                                   [half_height * 800 / 600, -4.2, 1.5 + half_height],
                                   atol=1e-9)


def test_left_button_pinches_and_tab_switches_hands(tmp_path: Path):
    with input_engine(SCENE, tmp_path) as engine:
        engine.start()
        window = engine.resource(WindowDevice)
        pinches: list[Button] = []
        engine.events.subscribe(Button, lambda b: b.device != "mouse" and pinches.append(b))
        window.mouse_button("left", True)
        window.mouse_button("left", False)
        window.key("tab", True)
        window.pointer(0.5, 0.5)
        window.mouse_button("left", True)
        engine.step()
        assert [(b.device, b.name, b.pressed) for b in pinches] == [
            ("glove_r", "pinch", True), ("glove_r", "pinch", False), ("glove_l", "pinch", True)]
        state = engine.resource(InputState)
        assert state.tracker("hand_l") is not None and state.tracker("hand_r") is None
        assert state.button("glove_l", "pinch") and state.key("tab")


@pytest.mark.parametrize(("keys", "left", "right"), [
    ("w", 1.0, 1.0), ("s", -1.0, -1.0), ("a", -1.0, 1.0), ("d", 1.0, -1.0), ("wd", 1.0, 0.0)])
def test_wasd_turn_the_wheel_counters(keys: str, left: float, right: float):
    window = WindowDevice()
    desktop = DesktopDevice("desktop", window, turns_per_second=0.5, counts_per_turn=1000)
    for key in keys:
        window.key(key, True)
    counts: dict[str, int] = {"left": 0, "right": 0}
    for frame in range(61):  # one second at 60 frames per second
        for event in desktop.poll(frame / 60):
            if isinstance(event, WheelCount):
                counts[event.device] = event.count
    assert counts == {"left": round(500 * left), "right": round(500 * right)}


def test_a_clock_set_back_turns_the_wheels_no_further_back():
    """Polled on one clock and then on another that reads less (a wall clock's hours, then
    a run's simulated seconds): the jump back is no motion, W held turns the counters at
    their rate from there, as if the clock had never read more."""
    window = WindowDevice()
    desktop = DesktopDevice("desktop", window, turns_per_second=0.5, counts_per_turn=1000)
    desktop.poll(10800.0)
    window.key("w", True)
    counts: dict[str, int] = {}
    for frame in range(61):
        for event in desktop.poll(frame / 60):
            if isinstance(event, WheelCount):
                counts[event.device] = event.count
    assert counts == {"left": 500, "right": 500}


def test_the_view_maps_window_corners_through_the_lens():
    view = DesktopView(np.zeros(3), np.array(euler_to_quat((0.0, 0.0, 90.0))), fov=90.0,
                       aspect=2.0)
    right, forward, up = quat_to_matrix(view.orientation).T
    np.testing.assert_allclose(view.point(0.5, 0.5, 2.0), forward * 2, atol=1e-12)
    np.testing.assert_allclose(view.point(0.0, 1.0, 1.0), forward - 2 * right - up, atol=1e-12)


def test_keys_from_the_window_reach_the_bus_typed(tmp_path: Path):
    with input_engine("", tmp_path) as engine:
        engine.start()
        keys: list[KeyEvent] = []
        engine.events.subscribe(KeyEvent, keys.append)
        engine.resource(WindowDevice).key("Space", True)
        engine.step()
        assert [(k.key, k.pressed, k.device) for k in keys] == [("space", True, "keyboard")]
        assert keys[0].timestamp > 0 and engine.resource(InputState).key("space")
