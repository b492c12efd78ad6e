"""Tracked hands that pinch things: 26-joint samples of a hand closing its thumb and index
round an object, from :func:`services.input.hand_pose.pose_hand`.

The fingered hand's bench, its tests and the recorded session of ``content/hands`` all
need a tracked hand that takes hold of an object of a known width the way a person
does: the pinch gesture opened or closed (its thumb–index distance ``width``), the hand
turned so that the line from thumb tip to index tip lies along a given direction
``across`` with the back of the hand up, and put where the tips' midpoint is the
object's centre. Closing past the object's width (the tracked fingers inside it) is
what presses it; opening past it lets go.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache

import numpy as np

from engine.rotation import from_to, matrices_to_quats
from services.input.events import HAND_JOINTS, HandJoints
from services.input.hand_pose import GESTURES, local_hand, pose_hand

THUMB, INDEX = HAND_JOINTS.index("thumb_tip"), HAND_JOINTS.index("index_tip")
#: The pinch gesture scaled by s in [0, MAX_SCALE]: its pads touch near 1.2.
MAX_SCALE = 1.2
_SCALES = np.linspace(0.0, MAX_SCALE, 121)


def curls(scale: float) -> dict[str, float]:
    """The pinch gesture's curls scaled by ``scale`` (0: open)."""
    return {k: float(np.clip(v * scale, 0.0, 1.0)) for k, v in GESTURES["pinch"].items()}


def _tips(scale: float, left: bool) -> tuple[np.ndarray, np.ndarray]:
    p = local_hand(curls(scale))[0]
    if left:
        p = p * np.array([1.0, -1.0, 1.0])
    return p[THUMB], p[INDEX]


@cache
def _gaps() -> np.ndarray:
    return np.array([float(np.linalg.norm(np.subtract(*_tips(s, False)))) for s in _SCALES])


def scale_for(width: float) -> float:
    """The pinch scale whose thumb and index tips (joint centres) are ``width`` apart."""
    return float(np.interp(-width, -_gaps(), _SCALES))  # the gaps fall as s grows


@cache
def _orientation(across: tuple[float, ...], width: float, left: bool) -> np.ndarray:
    return orientation(across, width, left)


def orientation(across: Sequence[float], width: float, left: bool = False) -> np.ndarray:
    """The wrist's rotation matrix putting the thumb→index line (at ``width``) along
    ``across`` (horizontal), the back of the hand as far up as it goes."""
    thumb, index = _tips(scale_for(width), left)
    a = np.asarray(across, dtype=float)
    a = a / np.linalg.norm(a)
    r1 = from_to((index - thumb)[None], a[None])[0]
    z1 = r1[:, 2]
    phi = np.arctan2(np.cross(a, z1)[2], z1[2])
    c, s = np.cos(phi), np.sin(phi)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    turn = np.eye(3) + s * k + (1.0 - c) * (k @ k)
    return turn @ r1


def pinch(device: str, centre: Sequence[float], across: Sequence[float], width: float,
          grip: float, *, left: bool = False, timestamp: float = 0.0,
          spread: float | None = None) -> HandJoints:
    """The tracked hand pinching an object of ``width`` centred at ``centre``: its tips
    ``grip`` apart (wider: open round it; narrower: pressing it), the hand placed and
    turned as for a pinch of ``spread`` (default ``width``) round the centre, so that
    opening and closing moves the fingers, not the hand."""
    fit = float(width if spread is None else spread)
    rot = _orientation(tuple(map(float, across)), fit, left)
    thumb, index = _tips(scale_for(fit), left)
    wrist = np.asarray(centre, dtype=float) - rot @ ((thumb + index) / 2)
    s = scale_for(grip)
    quat = matrices_to_quats(rot[None])[0]
    return pose_hand(device, wrist, quat, curls(s), left=left, timestamp=timestamp)


def grip_wrist(centre: Sequence[float], across: Sequence[float], width: float,
               left: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The wrist's position and orientation (w, x, y, z) of :func:`pinch` round an
    object of ``width`` at ``centre`` (the same for any grip of it)."""
    rot = _orientation(tuple(map(float, across)), float(width), left)
    thumb, index = _tips(scale_for(width), left)
    wrist = np.asarray(centre, dtype=float) - rot @ ((thumb + index) / 2)
    return wrist, matrices_to_quats(rot[None])[0]
