"""OpenXR's tracked hands as the engine's: the joints a runtime writes (pyopenxr's own
XrHandJointLocationEXT array, filled as a runtime fills it) become HandJoints in the
engine's frame and joint convention. The OpenXR side of each test is written from the
specification's words (y up, -z forward; a joint's +y out of the back of the hand, its
-z along the bone toward the tip), not from the conversion's matrices."""

from __future__ import annotations

import numpy as np
import pytest

from engine.rotation import euler_to_quat, matrices_to_quats, quat_to_matrix
from services.input.events import HAND_JOINTS
from services.input.hand_pose import FINGERS, GESTURES, curl, pose_hand
from services.input.openxr_hands import JOINT_VALID, RawHand, hand_event, raw_hand
from services.xr.projection import XrOrigin

xr = pytest.importorskip("xr", reason="pyopenxr (the openxr extra) is not installed")


def xr_vector(v: np.ndarray) -> np.ndarray:
    """An engine vector (x right, y forward, z up) in OpenXR's axes (x right, y up, z back)."""
    return np.stack([v[..., 0], v[..., 2], -v[..., 1]], axis=-1)


def as_runtime_writes(hand, flags: list[int] | None = None) -> bytes:
    """An engine hand as a runtime reports it: each joint's position in OpenXR's axes, its
    orientation the frame whose -z runs along the bone and +y out of the back of the hand
    (x completing it, right-handed), float32, in an XrHandJointLocationEXT array."""
    frames = np.array([quat_to_matrix(np.asarray(q)) for q in hand.orientations])
    along, back = xr_vector(frames[:, :, 0]), xr_vector(frames[:, :, 2])
    z, y = -along, back
    x = np.cross(y, z)
    q = matrices_to_quats(np.stack([x, y, z], axis=-1))
    p = xr_vector(np.asarray(hand.positions))
    joints = (xr.HandJointLocationEXT * 26)()
    for i in range(26):
        joints[i] = xr.HandJointLocationEXT(
            location_flags=JOINT_VALID if flags is None else flags[i],
            pose=xr.Posef(orientation=xr.Quaternionf(q[i, 1], q[i, 2], q[i, 3], q[i, 0]),
                          position=xr.Vector3f(*p[i])), radius=hand.radii[i])
    return bytes(joints)


@pytest.mark.parametrize("left", [False, True])
@pytest.mark.parametrize("shape", ["open", "pinch", "fist"])
def test_a_runtimes_hand_is_the_same_hand_in_the_engine(left: bool, shape: str):
    hand = pose_hand("truth", (0.2, 0.35, 1.1), euler_to_quat((15.0, -30.0, 80.0)),
                     GESTURES[shape], left=left)
    got = hand_event("hand_l" if left else "hand_r", raw_hand(as_runtime_writes(hand)), 4.5)
    assert (got.device, got.timestamp, got.valid) == ("hand_l" if left else "hand_r", 4.5,
                                                      (True,) * 26)
    np.testing.assert_allclose(got.positions, hand.positions, atol=1e-6)  # float32
    np.testing.assert_allclose(got.radii, hand.radii, atol=1e-8)
    frames = np.array([quat_to_matrix(np.asarray(q)) for q in got.orientations])
    truth = np.array([quat_to_matrix(np.asarray(q)) for q in hand.orientations])
    np.testing.assert_allclose(frames, truth, atol=1e-6)
    for finger in FINGERS:
        assert curl(got, finger) == pytest.approx(curl(hand, finger), abs=1e-4)


def test_a_flat_right_hand_ahead_points_along_the_engines_y():
    """Palm down, fingers ahead: every OpenXR joint orientation is the identity (+y up is
    the back of the hand, -z ahead the bones). In the engine the bones run along +y, the
    back faces +z and the index tip is ahead of the wrist, at the wrist's height."""
    joints = (xr.HandJointLocationEXT * 26)()
    for i in range(26):
        ahead = 0.01 * i
        joints[i] = xr.HandJointLocationEXT(location_flags=JOINT_VALID, pose=xr.Posef(
            position=xr.Vector3f(0.2, 1.0, -0.3 - ahead)), radius=0.01)
    got = hand_event("hand_r", raw_hand(bytes(joints)), 0.0)
    frames = np.array([quat_to_matrix(np.asarray(q)) for q in got.orientations])
    np.testing.assert_allclose(frames[:, :, 0], np.tile([0.0, 1.0, 0.0], (26, 1)), atol=1e-7)
    np.testing.assert_allclose(frames[:, :, 2], np.tile([0.0, 0.0, 1.0], (26, 1)), atol=1e-7)
    wrist, tip = got.positions[1], got.positions[HAND_JOINTS.index("index_tip")]
    np.testing.assert_allclose(wrist, [0.2, 0.31, 1.0], atol=1e-6)
    assert tip[1] > wrist[1] and tip[2] == pytest.approx(wrist[2], abs=1e-6)


def test_joints_the_runtime_did_not_locate_keep_their_last_values():
    hand = pose_hand("truth", (0.0, 0.3, 1.0), euler_to_quat((0.0, 0.0, 90.0)),
                     GESTURES["open"])
    first = hand_event("hand_r", raw_hand(as_runtime_writes(hand)), 1.0)
    fist = pose_hand("truth", (0.0, 0.3, 1.0), euler_to_quat((0.0, 0.0, 90.0)),
                     GESTURES["fist"])
    flags = [JOINT_VALID] * 26
    hidden = HAND_JOINTS.index("ring_tip")
    flags[hidden] = 0x1  # orientation only: not a pose
    raw = raw_hand(as_runtime_writes(fist, flags))
    raw.positions[hidden] = np.nan  # undefined, as OpenXR allows
    got = hand_event("hand_r", raw, 2.0, first)
    assert got.valid[hidden] is False and sum(got.valid) == 25
    assert got.positions[hidden] == first.positions[hidden]
    assert got.radii[hidden] == first.radii[hidden]
    assert np.isfinite(got.positions).all() and np.isfinite(got.orientations).all()
    index_tip = HAND_JOINTS.index("index_tip")
    np.testing.assert_allclose(got.positions[index_tip], fist.positions[index_tip], atol=1e-6)
    # before any hand was seen: the first located joint's pose, radius 0
    got = hand_event("hand_r", raw, 2.0)
    assert got.positions[hidden] == got.positions[0] and got.radii[hidden] == 0.0


def test_a_hand_with_no_joint_located_is_no_event():
    raw = RawHand(np.zeros((26, 3)), np.zeros((26, 4)), np.zeros(26), np.zeros(26, np.uint64))
    assert hand_event("hand_l", raw, 1.0) is None


def test_the_headsets_origin_places_every_joint_as_it_places_a_controller():
    origin = XrOrigin(np.array([1.0, -2.0, 0.0]), yaw=0.7)
    hand = pose_hand("truth", (0.1, 0.4, 1.2), euler_to_quat((5.0, 10.0, -20.0)),
                     GESTURES["point"])
    raw = raw_hand(as_runtime_writes(hand))
    placed = hand_event("hand_r", raw, 0.0, place=origin.place_joints)
    unplaced = hand_event("hand_r", raw, 0.0)
    c, s = np.cos(0.7), np.sin(0.7)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    for i in range(26):
        p, q = origin.place_xr(tuple(raw.positions[i]), tuple(raw.orientations[i]))
        np.testing.assert_allclose(placed.positions[i], p, atol=1e-9)  # as a controller
        np.testing.assert_allclose(
            quat_to_matrix(np.asarray(placed.orientations[i])),
            turn @ quat_to_matrix(np.asarray(unplaced.orientations[i])), atol=1e-9)
