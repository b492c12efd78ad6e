"""The shared hand anatomy: curls to 26 joints and back, both hands, any wrist pose."""

from __future__ import annotations

import numpy as np
import pytest

from engine.rotation import quat_to_matrix
from services.input.events import FINGERS, HAND_JOINTS
from services.input.hand_pose import GESTURES, MAX_FLEXION, curl, flexion, pose_hand

TURNED = (0.8535534, 0.1464466, 0.3535534, 0.3535534)  # an arbitrary wrist orientation


def joint(hand, name: str) -> np.ndarray:
    return np.asarray(hand.positions[HAND_JOINTS.index(name)])


@pytest.mark.parametrize("left", [False, True])
@pytest.mark.parametrize("amount", [0.0, 0.25, 0.6, 1.0])
def test_flexion_reads_back_the_curl_it_was_made_with(left: bool, amount: float) -> None:
    curls = {f: amount * (0.5 + 0.1 * i) for i, f in enumerate(FINGERS)}
    hand = pose_hand("hand_r", (0.3, -0.2, 1.1), TURNED, curls, left=left)
    angles = flexion(hand)
    for finger in FINGERS:
        expected = [curls[finger] * m for m in MAX_FLEXION[finger]]
        assert angles[finger] == pytest.approx(expected, abs=1e-9)
        assert curl(hand, finger) == pytest.approx(curls[finger], abs=1e-9)


def test_each_joint_faces_along_its_bone() -> None:
    hand = pose_hand("h", (0, 0, 1), TURNED, GESTURES["pinch"])
    for finger in FINGERS:
        names = [n for n in HAND_JOINTS if n.startswith(finger)]
        for a, b in zip(names, names[1:], strict=False):
            bone = joint(hand, b) - joint(hand, a)
            axis = quat_to_matrix(np.asarray(hand.orientations[HAND_JOINTS.index(a)]))[:, 0]
            assert axis @ bone / np.linalg.norm(bone) == pytest.approx(1.0, abs=1e-9)


def test_left_hand_is_the_mirror_of_the_right() -> None:
    right = pose_hand("r", (0, 0, 0), (1, 0, 0, 0), GESTURES["point"])
    left = pose_hand("l", (0, 0, 0), (1, 0, 0, 0), GESTURES["point"], left=True)
    mirrored = np.asarray(right.positions) * (1, -1, 1)
    assert np.asarray(left.positions) == pytest.approx(mirrored)
    assert joint(right, "thumb_proximal")[1] > 0 > joint(left, "thumb_proximal")[1]


def test_gestures_look_like_their_names() -> None:
    pinch = pose_hand("h", (0, 0, 0), (1, 0, 0, 0), GESTURES["pinch"])
    gap = np.linalg.norm(joint(pinch, "thumb_tip") - joint(pinch, "index_tip"))
    radii = sum(pinch.radii[HAND_JOINTS.index(n)] for n in ("thumb_tip", "index_tip"))
    assert gap == pytest.approx(radii, abs=0.003)  # the pads touch
    opened = pose_hand("h", (0, 0, 0), (1, 0, 0, 0), GESTURES["open"])
    fist = pose_hand("h", (0, 0, 0), (1, 0, 0, 0), GESTURES["fist"])
    assert joint(opened, "middle_tip")[0] > 0.17  # an adult's hand, wrist to fingertip
    assert joint(fist, "middle_tip")[0] < joint(fist, "middle_proximal")[0]  # folded back
    assert joint(fist, "middle_tip")[2] < -0.02  # under the palm
    point = pose_hand("h", (0, 0, 0), (1, 0, 0, 0), GESTURES["point"])
    assert joint(point, "index_tip")[0] > joint(point, "middle_tip")[0] + 0.08


def test_unknown_finger_is_named() -> None:
    hand = pose_hand("h", (0, 0, 0), (1, 0, 0, 0), GESTURES["open"])
    with pytest.raises(ValueError, match="unknown finger 'pinky'.*little"):
        curl(hand, "pinky")
