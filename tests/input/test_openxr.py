"""OpenXR: without a runtime the device says so clearly; with none, nothing else breaks.
What the device makes of each frame's controller and headset state (pyopenxr's own
structs, filled as a runtime fills them) is checked without one."""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
import pytest
from input_helpers import input_engine

from engine.rotation import quat_to_matrix
from services.input import DeviceError
from services.input.openxr import POSE_VALID, OpenXRDevice, located_pose, select_change

xr = pytest.importorskip("xr", reason="pyopenxr (the openxr extra) is not installed")


def test_no_runtime_is_one_clear_message(monkeypatch, tmp_path: Path):
    monkeypatch.setenv("XR_RUNTIME_JSON", str(tmp_path / "no-runtime.json"))
    with pytest.raises(DeviceError, match=r"'openxr' \(openxr\): no OpenXR runtime found: "
                                          r"install one .*XR_RUNTIME_JSON"):
        OpenXRDevice().open()


def test_a_run_without_a_runtime_goes_on(monkeypatch, tmp_path: Path, caplog):
    monkeypatch.setenv("XR_RUNTIME_JSON", str(tmp_path / "no-runtime.json"))
    with caplog.at_level(logging.ERROR), input_engine('Input { Device { Kind "openxr" } }',
                                                      tmp_path) as engine:
        engine.run(frames=3)
    errors = [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR]
    assert len(errors) == 1 and "no OpenXR runtime found" in errors[0]


#: OpenXR's stage axes in the engine's frame, written out from the two conventions (x
#: right in both; OpenXR's y up is the engine's z; OpenXR's -z forward the engine's y).
XR_TO_ENGINE = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def location(flags: int, position: tuple[float, ...], orientation: tuple[float, ...]):
    """An XrSpaceLocation as the runtime fills it (orientation given w, x, y, z)."""
    w, x, y, z = orientation
    return xr.SpaceLocation(location_flags=flags, pose=xr.Posef(
        orientation=xr.Quaternionf(x, y, z, w), position=xr.Vector3f(*position)))


def test_a_controller_pose_becomes_its_tracker_in_the_engines_frame():
    """A right controller 0.1 m right, 1.2 m up and 0.3 m ahead (OpenXR: x, y, -z), turned
    by a rotation about an oblique axis: the engine's pose is at (0.1, 0.3, 1.2), and
    turning a direction by it is turning the same direction by the OpenXR rotation."""
    valid = xr.SpaceLocationFlags.POSITION_VALID_BIT | xr.SpaceLocationFlags.ORIENTATION_VALID_BIT
    assert int(valid) == POSE_VALID
    axis = np.array([0.3, 0.8, -0.52]) / np.linalg.norm([0.3, 0.8, -0.52])
    half = math.radians(70.0) / 2
    q_xr = (math.cos(half), *(math.sin(half) * axis))
    pose = located_pose("hand_r", location(POSE_VALID, (0.1, 1.2, -0.3), q_xr), 12.5)
    assert (pose.device, pose.timestamp, pose.velocity) == ("hand_r", 12.5, None)
    # float32 on the runtime's side: what the struct holds is what is converted
    np.testing.assert_allclose(pose.position, (0.1, 0.3, 1.2), atol=1e-7)
    r_engine = quat_to_matrix(np.array(pose.orientation))
    r_xr = quat_to_matrix(np.array(q_xr))
    for v in np.eye(3):
        np.testing.assert_allclose(r_engine @ (XR_TO_ENGINE @ v), XR_TO_ENGINE @ (r_xr @ v),
                                   atol=1e-6)
    # a headset looking straight ahead (identity in OpenXR) looks along the engine's +y
    ahead = located_pose("hmd", location(POSE_VALID, (0, 1.7, 0), (1, 0, 0, 0)), 0.0)
    np.testing.assert_allclose(quat_to_matrix(np.array(ahead.orientation)) @ (0, 1, 0),
                               (0, 1, 0), atol=1e-12)


@pytest.mark.parametrize("flags", [0, 0x1, 0x2], ids=["none", "orientation only",
                                                      "position only"])
def test_a_space_not_located_in_full_is_no_pose(flags):
    assert located_pose("hand_l", location(flags, (0, 1, 0), (1, 0, 0, 0)), 1.0) is None


def test_the_select_button_is_told_when_it_changes_while_bound():
    def state(pressed: bool, active: bool = True):
        return xr.ActionStateBoolean(current_state=int(pressed), is_active=int(active))

    down = select_change("hand_r", state(True), False, 3.0)
    assert (down.device, down.name, down.pressed, down.timestamp) == ("hand_r", "select",
                                                                      True, 3.0)
    assert select_change("hand_r", state(True), True, 3.1) is None  # held: no new event
    up = select_change("hand_r", state(False), True, 3.2)
    assert (up.name, up.pressed) == ("select", False)
    # a controller switched off (inactive) tells nothing, not a release
    assert select_change("hand_r", state(False, active=False), True, 3.3) is None
