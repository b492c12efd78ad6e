"""A tracked hand's 26 joints, raw -> scene: the per-hand step of the input hub.

A hand source is calibrated by the ``Input { Tracker { ID ... } }`` of its name, as a
tracker is (no second block to learn): ``Offset``, ``Rotation``, ``Scale`` and ``Axes``
move every joint; ``Scale`` scales the radii too; ``Filter "oneeuro"`` smooths every
joint's position and orientation with its own one-euro filters (``MinCutoff``, ``Beta``).

Mirroring — an ``Axes`` map with one (or three) negated axes, ``"-x y z"`` — turns a
left hand into a right one (mirror therapy: the tracked left hand drives the virtual
right one). A mirrored joint frame would be left-handed; it is kept proper in the
convention of :mod:`engine.input.hand_pose` (local +x along the bone and +z out of the
back of the hand mirror with the hand; +y, toward a right hand's thumb and away from a
left one's, turns round), so a mirrored hand reads as an ordinary hand of the other side.

``Predict`` applies to trackers only: a hand's joints are shown where they were sensed.
"""

from __future__ import annotations

import math

import numpy as np

from engine.input.calibration import Calibration, axes_matrix
from engine.input.events import HAND_JOINTS, HandJoints, Quat
from engine.input.filters import OneEuro, OneEuroRotation
from engine.rotation import matrix_to_quat, quat_product
from engine.scene.inputs import TrackerSpec

#: A joint frame's local mirror: +y turned round (see the module's docstring).
_LOCAL_MIRROR = np.diag([1.0, -1.0, 1.0])


def mirror_fix(spec: TrackerSpec) -> Quat | None:
    """What a mirroring calibration's joint orientations are multiplied by (on the right)
    to stay hand frames: the quaternion of ``M D`` (``M`` the axes map, ``D`` the local
    mirror); None when the axes map does not mirror. The calibration turns ``R`` into
    ``C M R Mᵀ``; times ``M D`` that is ``C M R D``: bone and back mirrored, +y turned."""
    m = axes_matrix(spec.axes)
    if np.linalg.det(m) > 0:
        return None
    q = matrix_to_quat(m @ _LOCAL_MIRROR)
    return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))


def hand_problem(event: HandJoints) -> str | None:
    """What is wrong with the shape of a hand event (from a peer or a tool, not checked
    by a device), or None: its joints are counted before anything indexes them."""
    joints = len(HAND_JOINTS)
    if not (len(event.positions) == len(event.orientations) == len(event.radii)
            == len(event.valid) == joints):
        return f"a hand needs {joints} positions, orientations, radii and validity flags"
    if any(len(p) != 3 for p in event.positions) or any(len(q) != 4
                                                         for q in event.orientations):
        return "a joint's position takes 3 numbers and its orientation 4"
    return None


def finite(hand: HandJoints) -> bool:
    """Whether every number of the hand is finite (a calibration or filter can overflow)."""
    return all(math.isfinite(v) for p in hand.positions for v in p) and \
        all(math.isfinite(v) for q in hand.orientations for v in q) and \
        all(math.isfinite(r) for r in hand.radii)


class HandPipeline:
    """Raw joints of one hand -> scene joints (calibrated, mirrored, filtered)."""

    def __init__(self, spec: TrackerSpec | None) -> None:
        spec = spec or TrackerSpec("")
        self.calibration = Calibration.of(spec)
        self.radius_scale = abs(spec.scale)
        self.mirror = mirror_fix(spec)
        self.filters = ([(OneEuro(spec.min_cutoff, spec.beta),
                          OneEuroRotation(spec.min_cutoff, spec.beta)) for _ in HAND_JOINTS]
                        if spec.filter == "oneeuro" else None)

    def __call__(self, raw: HandJoints) -> HandJoints:
        cal, t = self.calibration, raw.timestamp
        positions, orientations = raw.positions, raw.orientations
        radii = raw.radii
        if not cal.is_identity:
            positions = tuple(cal.position(p) for p in positions)
            orientations = tuple(cal.orientation(q) for q in orientations)
            if self.radius_scale != 1.0:
                radii = tuple(r * self.radius_scale for r in radii)
        if self.mirror is not None:
            fix = self.mirror
            orientations = tuple(quat_product(q, fix) for q in orientations)
        if self.filters is not None:
            filtered_p, filtered_q = [], []
            for (lowpass, turn), p, q in zip(self.filters, positions, orientations,
                                             strict=True):
                x, y, z = lowpass(p, t)
                filtered_p.append((x, y, z))
                filtered_q.append(turn(q, t))
            positions, orientations = tuple(filtered_p), tuple(filtered_q)
        return HandJoints(raw.device, positions, orientations, radii, raw.valid, t)
