"""OpenXR hand tracking (``XR_EXT_hand_tracking``): 26 joints per hand as HandJoints.

Both OpenXR paths use it: the headless input device (:mod:`services.input.openxr`) and the
headset's session (:mod:`services.xr.session`). Where the runtime offers the extension
and its system tracks hands, a hand tracker is made per hand and its joints are located
at the frame's predicted display time; the hands are named ``hand_l`` and ``hand_r``,
as the controllers are. A runtime without the extension, or whose system tracks no
hands (Monado's simulated headset offers the extension and reports
``supportsHandTracking`` false), is told in one line and gives no hand events.

The joints arrive in OpenXR's frame (y up, -z forward) and in OpenXR's joint
convention (+y out of the back of the hand, -z along the bone toward the fingertip);
:func:`joints_to_engine` turns them into the engine's frame (z up, +y forward, as the
controllers' poses are converted) and the joint convention of
:mod:`services.input.hand_pose` (+x along the bone, +z out of the back of the hand).
"""

from __future__ import annotations

import ctypes
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from engine.rotation import matrices_to_quats, quat_to_matrix
from engine.scene.inputs import axes_map
from services.input.calibration import axes_matrix
from services.input.events import HAND_JOINTS, HandJoints

log = logging.getLogger("colosseum.input")

HAND_TRACKING = "XR_EXT_hand_tracking"
#: The hands in the order trackers are made (XR_HAND_LEFT_EXT, XR_HAND_RIGHT_EXT).
HAND_NAMES = ("hand_l", "hand_r")
#: XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT.
JOINT_VALID = 0x1 | 0x2
#: Engine axes from OpenXR's (x right, y up, -z forward -> x right, y forward, z up).
ENGINE_FROM_XR = axes_matrix(axes_map("x -z y"))
#: A joint's engine axes (columns: along the bone, toward a right hand's thumb, out of the
#: back) in OpenXR's joint axes: -z, -x and +y. A proper rotation.
JOINT_FROM_XR = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
#: One XrHandJointLocationEXT: flags, XrPosef (orientation x y z w, position), radius.
JOINT_DTYPE = np.dtype([("flags", "<u8"), ("q", "<f4", 4), ("p", "<f4", 3), ("radius", "<f4")])

#: Places arrays of engine-axis positions (n, 3) and frames (n, 3, 3) in the world.
Placement = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass(slots=True)
class RawHand:
    """One located hand as the runtime gave it: OpenXR's frame and joint convention."""

    positions: np.ndarray  # (26, 3) m
    orientations: np.ndarray  # (26, 4) w x y z
    radii: np.ndarray  # (26,) m
    flags: np.ndarray  # (26,) XrSpaceLocationFlags


def joints_to_engine(positions: np.ndarray, orientations: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """OpenXR joint poses -> engine positions (n, 3) and joint frames (n, 3, 3):
    ``p' = M p`` and ``R' = M R J`` (``M`` the axis change, ``J`` the joint convention's)."""
    p = np.asarray(positions, np.float64) @ ENGINE_FROM_XR.T
    frames = ENGINE_FROM_XR @ quat_to_matrix(np.asarray(orientations, np.float64)) \
        @ JOINT_FROM_XR
    return p, frames


def hand_event(name: str, raw: RawHand, now: float, last: HandJoints | None = None,
               place: Placement | None = None) -> HandJoints | None:
    """The HandJoints of a located hand (None when no joint is valid). A joint the runtime
    did not locate keeps ``last``'s values (its pose is undefined in OpenXR), or, before
    any, the first located joint's pose with radius 0; ``place`` puts the joints in the
    world (the headset's origin), else they stay in the reference space."""
    valid = (raw.flags & JOINT_VALID) == JOINT_VALID
    if not valid.any():
        return None
    first = int(np.argmax(valid))
    positions = np.where(valid[:, None], raw.positions, raw.positions[first])
    orientations = np.where(valid[:, None], raw.orientations, raw.orientations[first])
    p, frames = joints_to_engine(positions, orientations)
    if place is not None:
        p, frames = place(p, frames)
    q = matrices_to_quats(frames)
    radii = np.where(valid, raw.radii, 0.0).astype(np.float64)
    if last is not None and not valid.all():
        p = np.where(valid[:, None], p, np.asarray(last.positions))
        q = np.where(valid[:, None], q, np.asarray(last.orientations))
        radii = np.where(valid, radii, np.asarray(last.radii))
    return HandJoints(name, tuple(map(tuple, p.tolist())), tuple(map(tuple, q.tolist())),
                      tuple(radii.tolist()), tuple(valid.tolist()), now)


def system_tracks_hands(xr: Any, instance: Any, system: Any) -> bool:
    """Whether the system says it tracks hands (XrSystemHandTrackingPropertiesEXT)."""
    hands = xr.SystemHandTrackingPropertiesEXT()
    properties = xr.SystemProperties(next=hands)
    result = xr.check_result(xr.raw_functions.xrGetSystemProperties(
        instance, system, ctypes.byref(properties)))
    if result.is_exception():
        raise result
    return bool(hands.supports_hand_tracking)


class OpenXRHands:
    """The two hand trackers of a session, located together each frame."""

    def __init__(self, xr: Any, instance: Any, session: Any) -> None:
        self._xr = xr
        self.trackers = [xr.create_hand_tracker_ext(session, xr.HandTrackerCreateInfoEXT(
            hand=hand, hand_joint_set=xr.HandJointSetEXT.DEFAULT))
            for hand in (xr.HandEXT.LEFT, xr.HandEXT.RIGHT)]
        # pyopenxr's xrLocateHandJointsEXT wrapper passes no joint array: called directly
        self._locate = ctypes.cast(xr.get_instance_proc_addr(instance, "xrLocateHandJointsEXT"),
                                   xr.PFN_xrLocateHandJointsEXT)
        self._joints = [(xr.HandJointLocationEXT * len(HAND_JOINTS))() for _ in HAND_NAMES]

    @staticmethod
    def create(xr: Any, instance: Any, system: Any, session: Any, enabled: set[str],
               who: str) -> OpenXRHands | None:
        """The hand trackers, or None told in one line (``who`` names the device) when
        the extension is not enabled or the system tracks no hands."""
        if HAND_TRACKING not in enabled:
            log.info("%s: the OpenXR runtime does not offer %s: no tracked hands",
                     who, HAND_TRACKING)
            return None
        if not system_tracks_hands(xr, instance, system):
            log.info("%s: the OpenXR runtime offers %s but its system tracks no hands: no "
                     "tracked hands", who, HAND_TRACKING)
            return None
        try:
            return OpenXRHands(xr, instance, session)
        except xr.exception.XrException as exc:
            log.warning("%s: the OpenXR runtime refused a hand tracker (%s): no tracked hands",
                        who, exc)
            return None

    def locate(self, space: Any, when: int) -> dict[str, RawHand]:
        """Each hand the runtime tracks now, at display time ``when`` in ``space``."""
        xr, out = self._xr, {}
        info = xr.HandJointsLocateInfoEXT(base_space=space, time=when)
        for name, tracker, joints in zip(HAND_NAMES, self.trackers, self._joints,
                                         strict=True):
            located = xr.HandJointLocationsEXT(joint_count=len(joints), joint_locations=joints)
            result = xr.check_result(self._locate(tracker, info, ctypes.byref(located)))
            if result.is_exception():
                raise result
            if not located.is_active:
                continue
            out[name] = raw_hand(bytes(joints))
        return out

    def destroy(self) -> None:
        for tracker in self.trackers:
            self._xr.destroy_hand_tracker_ext(tracker)
        self.trackers = []


def raw_hand(data: bytes) -> RawHand:
    """A RawHand from the bytes of 26 XrHandJointLocationEXT."""
    joints = np.frombuffer(data, JOINT_DTYPE, count=len(HAND_JOINTS))
    q = joints["q"].astype(np.float64)
    return RawHand(joints["p"].astype(np.float64), q[:, [3, 0, 1, 2]],
                   joints["radius"].astype(np.float64), joints["flags"].copy())
