"""A headset's controllers as the hands' third transport (after OSC trackers with pinch
gloves, and the desktop emulation): a squeeze grasps and lifts the cup, exactly as a
pinch does, and the grasp pulses the holding controller.

The events are made by the headset device's own conversion (:func:`input_events`) from
samples in OpenXR's axes, as the runtime reports them; no runtime is needed for this.
With a runtime, tests/xr/test_headset_runtime.py checks the samples it gives."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from components import Transform
from engine import Phase, system
from services.input.hub import InputHub
from services.xr.display import XrDisplay, input_events
from services.xr.projection import XrOrigin
from services.xr.session import InputSample
from systems.xr import HapticSystem
from tests.hands.hand_helpers import Rig, waypoints

G = 9.81
TABLE = ('Object { ID "table" Position [0 0 0.725] Dynamic 0\n'
         '  PhysicalAttributes { Geometry { Primitive "box" Size [1.2 1.2 0.05] } } }\n'
         'Object { ID "cup" Position [0 0 0.8]\n'
         '  PhysicalAttributes { Mass 0.3 Geometry { Primitive "cylinder" Size [0.08 0.1] } } }\n')
HAND = ('Object { ID "hand_r" Position [0 0 0.9]\n'
        '  Hand { Tracker "hand_r" Glove "hand_r" Button "squeeze" } }\n')
PATH = waypoints((0.0, (0, 0, 0.9)), (0.4, (0, 0, 0.852)), (0.6, (0, 0, 0.852)),
                 (1.4, (0, 0, 1.152)), (2.0, (0, 0, 1.152)))


def _xr_axes(p: np.ndarray) -> tuple[float, float, float]:
    """An engine point (z up, y ahead) in OpenXR's stage axes (y up, -z ahead)."""
    return (float(p[0]), float(p[2]), float(-p[1]))


def test_the_conversion_places_poses_and_tells_changes_only():
    origin = XrOrigin(np.array([1.0, 2.0, 0.0]), math.pi / 2)
    sample = InputSample(poses={"hand_r": ((0.0, 1.0, -0.5), (1.0, 0.0, 0.0, 0.0))},
                         buttons={("hand_r", "squeeze"): True},
                         axes={("hand_r", "trigger"): 0.25})
    pressed: dict = {}
    axes: dict = {}
    events = input_events(sample, origin, pressed, axes, 3.0)
    pose = events[0]
    # 0.5 m ahead of the origin, turned a quarter left: along world -x; 1 m up
    assert np.allclose(pose.position, (0.5, 2.0, 1.0))
    assert [type(e).__name__ for e in events] == ["TrackerPose", "Button", "Button", "Axis"]
    assert (events[2].device, events[2].name, events[2].pressed) == ("glove_r", "pinch", True)
    again = input_events(sample, origin, pressed, axes, 3.1)
    assert [type(e).__name__ for e in again] == ["TrackerPose"]  # nothing changed


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_controllers_squeeze_grasps_and_lifts_the_cup_and_pulses_it(tmp_path: Path,
                                                                      backend: str):
    with Rig(TABLE + HAND, tmp_path, backend) as rig:
        hub = rig.engine.resource(InputHub)
        haptics = HapticSystem(XrDisplay())
        rig.engine.add_system(haptics)
        pressed: dict = {}
        axes: dict = {}
        origin = XrOrigin()
        pulses: list = []

        @system(Phase.INPUT, before=("InputSystem",))
        def controller(e, dt):
            t = e.time
            squeeze = 0.5 <= t < 2.0
            sample = InputSample(poses={"hand_r": (_xr_axes(PATH(t)), (1.0, 0.0, 0.0, 0.0))},
                                 buttons={("hand_r", "squeeze"): squeeze},
                                 axes={("hand_r", "squeeze"): 1.0 if squeeze else 0.0})
            for event in input_events(sample, origin, pressed, axes, t):
                hub.inject(event)

        heights: dict[str, float] = {}

        @system(Phase.RENDER, reads=(Transform,))
        def note(e, dt):
            if haptics.last:
                pulses.append((e.time, dict(haptics.last)))
            if "hand" not in heights and e.time >= 0.45:  # touching, before the grasp
                heights["hand"], heights["cup"] = rig.position("hand_r")[2], \
                    rig.position("cup")[2]

        rig.engine.add_system(controller)
        rig.engine.add_system(note)
        rig.run(1.9)
        cup, hand = rig.position("cup"), rig.position("hand_r")
        assert hand[2] == pytest.approx(1.152, abs=2e-3)
        # lifted with the hand, as far as the hand rose from resting on it
        assert cup[2] - heights["cup"] == pytest.approx(hand[2] - heights["hand"], abs=2e-3)
        assert cup[2] > 1.05
        grasp = [t for t, p in pulses if p["hand_r"] == (0.6, 0.1)]  # HapticGrasp's pulse
        assert grasp and grasp[0] == pytest.approx(0.5, abs=0.03)  # pulsed at the grasp
        assert pulses[0][0] < 0.5  # touching the cup (its impulse) pulsed it before
        rig.run(0.6)  # let go at 2 s: it falls back onto the table
        assert rig.position("cup")[2] == pytest.approx(0.8, abs=0.01)
