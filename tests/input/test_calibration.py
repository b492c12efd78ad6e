"""Calibration and the OpenXR axis conversion, checked against rotation algebra."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from engine.rotation import euler_to_quat, quat_to_matrix
from engine.scene.inputs import axes_map
from services.input import Calibration, openxr_to_engine
from services.input.calibration import axes_matrix

AXES = ["x y z", "x -z y", "-y x z", "z x y", "-x -y z", "y x z", "x y -z"]
angles = st.floats(-180.0, 180.0, allow_nan=False)
unit = st.tuples(*[st.floats(-1, 1, allow_nan=False)] * 4).filter(
    lambda q: np.linalg.norm(q) > 0.1).map(lambda q: tuple(np.asarray(q) / np.linalg.norm(q)))


def test_offset_rotation_and_scale_apply_in_order():
    cal = Calibration(offset=(1.0, 2.0, 3.0), rotation=euler_to_quat((0.0, 0.0, 90.0)),
                      scale=0.01)
    # 100 cm along device x -> 1 m, turned 90 degrees about z onto +y, then offset
    np.testing.assert_allclose(cal.position(np.array([100.0, 0.0, 0.0])), [1.0, 3.0, 3.0],
                               atol=1e-12)
    np.testing.assert_allclose(cal.velocity(np.array([100.0, 0.0, 0.0])), [0.0, 1.0, 0.0],
                               atol=1e-12)
    turned = quat_to_matrix(cal.orientation(np.array([1.0, 0.0, 0.0, 0.0])))
    np.testing.assert_allclose(turned, quat_to_matrix(np.array(euler_to_quat((0, 0, 90)))),
                               atol=1e-12)


@pytest.mark.parametrize("axes", AXES)
@given(rotation=st.tuples(angles, angles, angles), pose=unit,
       vector=st.tuples(*[st.floats(-10, 10, allow_nan=False)] * 3))
def test_a_calibrated_pose_turns_calibrated_vectors_as_the_raw_pose_turned_raw_ones(
        axes, rotation, pose, vector):
    """Calibration changes the frame: for a body-local vector u (device convention, M u in
    the engine's), R' (M u) == L (R u), with L = C M the linear part."""
    cal = Calibration(rotation=euler_to_quat(rotation), axes=axes_map(axes))
    turned = quat_to_matrix(cal.orientation(np.array(pose)))
    np.testing.assert_allclose(turned @ turned.T, np.eye(3), atol=1e-9)
    assert np.linalg.det(turned) == pytest.approx(1.0)  # proper, even for mirroring maps
    v = np.array(vector)
    raw = quat_to_matrix(np.array(pose))
    local = axes_matrix(axes_map(axes)) @ v
    np.testing.assert_allclose(turned @ local, cal.velocity(raw @ v), atol=1e-9)


def test_axis_maps_are_signed_permutations():
    m = axes_matrix(axes_map("x -z y"))
    np.testing.assert_array_equal(m @ [1.0, 2.0, 3.0], [1.0, -3.0, 2.0])
    for bad in ("x y", "x x z", "x y w", "x y z z"):
        with pytest.raises(ValueError):
            axes_map(bad)


def test_openxr_poses_become_engine_poses():
    # a head 1.6 m up (OpenXR y) and 2 m forward (OpenXR -z)
    position, orientation = openxr_to_engine((0.5, 1.6, -2.0), (1.0, 0.0, 0.0, 0.0))
    assert position == pytest.approx((0.5, 2.0, 1.6))
    # identity looks along OpenXR -z, which is the engine's +y: the camera's look direction
    look = quat_to_matrix(np.array(orientation)) @ [0.0, 1.0, 0.0]
    np.testing.assert_allclose(look, [0.0, 1.0, 0.0], atol=1e-12)
    # a head turned 90 degrees left (about OpenXR +y, up) looks along OpenXR -x
    half = np.sqrt(0.5)
    _, turned = openxr_to_engine((0.0, 0.0, 0.0), (half, 0.0, half, 0.0))
    axes = quat_to_matrix(np.array(turned))
    np.testing.assert_allclose(axes @ [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(axes @ [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], atol=1e-12)  # up stays
