"""A tracked hand asked by name: one joint's pose, one finger's curl, in the world.

What Python systems and Lua (``hand:joint("index_tip")``, ``hand:curl("index")``) read of
a hand object's tracked joints. The joints are those of the input hand its ``Hand``
names (``Tracker``), carried by its ``Frame`` object when it has one (a wheelchair), as
the hand's drive carries its tracker — so a joint is where the person's finger is in the
world, whatever the physical hand was stopped by.

>>> joint_index("index_tip"), finger_named("thumb")
(10, 'thumb')
>>> joint_index("index_tp")
Traceback (most recent call last):
ValueError: no hand joint 'index_tp'; did you mean 'index_tip'?
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from components import Hand, Transform
from engine.rotation import quat_multiply, quat_to_matrix
from services.input.events import FINGERS, HAND_JOINTS, HandJoints
from services.input.hand_pose import curl
from services.input.state import InputState

if TYPE_CHECKING:
    from engine.world import World

_INDEX = {name: i for i, name in enumerate(HAND_JOINTS)}


@dataclass(frozen=True, slots=True)
class JointPose:
    """One tracked joint: position (m), orientation ``(w, x, y, z)`` of the bone starting
    at it, radius (m), and whether the tracker saw it this time."""

    position: np.ndarray
    orientation: np.ndarray
    radius: float
    valid: bool


def _unknown(what: str, name: object, known: tuple[str, ...]) -> ValueError:
    hint = difflib.get_close_matches(str(name), known, 1) if isinstance(name, str) else []
    extra = f"; did you mean {hint[0]!r}?" if hint else f" (known: {', '.join(known)})"
    return ValueError(f"no hand {what} {name!r}{extra}")


def joint_index(name: str) -> int:
    """The index of joint ``name`` in :data:`HAND_JOINTS` (ValueError names the nearest)."""
    index = _INDEX.get(name) if isinstance(name, str) else None
    if index is None:
        raise _unknown("joint", name, HAND_JOINTS)
    return index


def finger_named(name: str) -> str:
    """``name`` if it is a finger's (thumb to little), else ValueError naming the nearest."""
    if name not in FINGERS:
        raise _unknown("finger", name, FINGERS)
    return name


def joint(hand: HandJoints, name: str) -> JointPose:
    """Joint ``name`` of ``hand``."""
    i = joint_index(name)
    return JointPose(np.array(hand.positions[i]), np.array(hand.orientations[i]),
                     float(hand.radii[i]), bool(hand.valid[i]))


def finger_curl(hand: HandJoints, name: str) -> float:
    """How bent finger ``name`` is, 0 straight to 1 fully (:func:`hand_pose.curl`)."""
    return curl(hand, finger_named(name))


def in_frame(hand: HandJoints, position: np.ndarray, orientation: np.ndarray) -> HandJoints:
    """``hand``'s joints, given relative to a frame at ``position``/``orientation``, in
    the world."""
    rot = quat_to_matrix(np.asarray(orientation, dtype=float))
    p = np.asarray(hand.positions, dtype=float) @ rot.T + np.asarray(position, dtype=float)
    q = quat_multiply(np.asarray(orientation, dtype=float),
                      np.asarray(hand.orientations, dtype=float))
    return replace(hand, positions=tuple(map(tuple, p.tolist())),
                   orientations=tuple(map(tuple, q.tolist())))


def tracked_hand(world: World, entity: int, state: InputState) -> HandJoints | None:
    """The tracked joints of hand object ``entity`` in the world (through its ``Frame``);
    None when it has no Hand, its input hand was never seen or is lost, or its frame
    object is gone."""
    hand = world.try_component(entity, Hand)
    joints = None if hand is None else state.hand(hand.tracker)
    if joints is None or hand is None or hand.frame is None:
        return joints
    frame = world.try_component(hand.frame, Transform)
    return None if frame is None else in_frame(joints, frame.position, frame.orientation)
