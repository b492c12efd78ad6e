"""A tracked hand's 26 joints, raw -> scene: the per-hand step of the input hub.

A hand source is calibrated by the ``Input { Tracker { ID ... } }`` of its name, as a
tracker is (no second block to learn): ``Offset``, ``Rotation``, ``Scale`` and ``Axes``
move every joint; ``Scale`` scales the radii too; ``Filter "oneeuro"`` smooths every
joint's position and orientation with its own one-euro filters (``MinCutoff``, ``Beta``).

Mirroring — an ``Axes`` map that reflects (``"-x y z"``, or a swap such as ``"y x z"``) — turns a
left hand into a right one (mirror therapy: the tracked left hand drives the virtual
right one). A mirrored joint frame would be left-handed; it is kept proper in the
convention of :mod:`services.input.hand_pose` (local +x along the bone and +z out of the
back of the hand mirror with the hand; +y, toward a right hand's thumb and away from a
left one's, turns round), so a mirrored hand reads as an ordinary hand of the other side.

``Predict`` applies to trackers only: a hand's joints are shown where they were sensed.
"""

from __future__ import annotations

import math

import numpy as np

from engine.rotation import matrix_to_quat, quat_to_matrix
from engine.scene.inputs import TrackerSpec
from services.input.calibration import Calibration, axes_matrix
from services.input.events import HAND_JOINTS, HandJoints, Quat
from services.input.filters import DERIVATIVE_CUTOFF, MIN_DT, smoothing

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
    # (as sets of lengths, counted in C: every sample of every hand passes here)
    if set(map(len, event.positions)) != {3} or set(map(len, event.orientations)) != {4}:
        return "a joint's position takes 3 numbers and its orientation 4"
    return None


def finite(hand: HandJoints) -> bool:
    """Whether every number of the hand is finite (a calibration or filter can overflow):
    a sum is NaN or infinite when any term is (or when finite terms overflow it, which
    is past anything a hand holds too)."""
    return math.isfinite(sum(map(sum, hand.positions)) + sum(map(sum, hand.orientations))
                         + sum(hand.radii))


class JointFilters:
    """The one-euro filter of every joint at once (positions as vectors, orientations by
    slerp), as :class:`~services.input.filters.OneEuro` and
    :class:`~services.input.filters.OneEuroRotation` filter one tracker: the joints share
    the hand's timestamps, each has its own speed and cutoff. In numpy: 52 filters a
    sample in Python were most of a hand's cost."""

    def __init__(self, min_cutoff: float, beta: float) -> None:
        self.min_cutoff, self.beta = min_cutoff, beta
        self.positions: np.ndarray | None = None
        self.orientations = np.zeros((0, 4))
        self.speed = np.zeros((0, 3))  # m/s, filtered, per joint
        self.angular_speed = np.zeros(0)  # rad/s, filtered, per joint
        self.time = 0.0

    def __call__(self, positions: np.ndarray, orientations: np.ndarray, t: float
                 ) -> tuple[np.ndarray, np.ndarray]:
        if self.positions is None:
            self.positions, self.orientations = positions, orientations
            self.speed = np.zeros_like(positions)
            self.angular_speed = np.zeros(len(positions))
            self.time = t
            return positions, orientations
        dt = max(t - self.time, MIN_DT)
        self.time = max(t, self.time)
        a = smoothing(DERIVATIVE_CUTOFF, dt)
        self.speed = self.speed + a * ((positions - self.positions) / dt - self.speed)
        b = _smoothing(self.min_cutoff + self.beta * np.linalg.norm(self.speed, axis=1), dt)
        self.positions = self.positions + b[:, None] * (positions - self.positions)
        turn = _turns(self.orientations, orientations)
        rate = np.linalg.norm(turn, axis=1) / dt
        self.angular_speed = self.angular_speed + a * (rate - self.angular_speed)
        b = _smoothing(self.min_cutoff + self.beta * self.angular_speed, dt)
        self.orientations = _qmul(_quats_from_rotation_vectors(turn * b[:, None]),
                                  self.orientations)
        return self.positions, self.orientations


def _product_table() -> np.ndarray:
    """``T`` with ``p ⊗ q = (p qᵀ).ravel() @ T`` (Hamilton, w x y z): one small matmul
    for a batch of products, where the four-line formula costs sixteen numpy calls."""
    table = np.zeros((4, 4, 4))
    for i, j, k, sign in ((0, 0, 0, 1), (1, 1, 0, -1), (2, 2, 0, -1), (3, 3, 0, -1),
                          (0, 1, 1, 1), (1, 0, 1, 1), (2, 3, 1, 1), (3, 2, 1, -1),
                          (0, 2, 2, 1), (1, 3, 2, -1), (2, 0, 2, 1), (3, 1, 2, 1),
                          (0, 3, 3, 1), (1, 2, 3, 1), (2, 1, 3, -1), (3, 0, 3, 1)):
        table[i, j, k] = sign
    return table.reshape(16, 4)


_PRODUCT = _product_table()
_CONJUGATE = np.array([1.0, -1.0, -1.0, -1.0])


def _qmul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``p ⊗ q`` row by row, (n, 4) each."""
    return (p[:, :, None] * q[:, None, :]).reshape(len(p), 16) @ _PRODUCT


def _turns(q_from: np.ndarray, q_to: np.ndarray) -> np.ndarray:
    """:func:`~engine.rotation.rotation_vector_between` of rows (the short way)."""
    d = _qmul(q_to, q_from * _CONJUGATE)
    d = np.where(d[:, :1] < 0, -d, d)
    s = np.linalg.norm(d[:, 1:], axis=1, keepdims=True)
    small = s < 1e-12
    angle = 2.0 * np.arctan2(s, d[:, :1])
    return np.where(small, 2.0 * d[:, 1:], d[:, 1:] / np.where(small, 1.0, s) * angle)


def _smoothing(cutoff: np.ndarray, dt: float) -> np.ndarray:
    """:func:`~services.input.filters.smoothing` of many cutoffs."""
    return 1.0 / (1.0 + 1.0 / (2.0 * np.pi * cutoff * dt))


def _quats_from_rotation_vectors(v: np.ndarray) -> np.ndarray:
    """:func:`~engine.rotation.quat_from_rotation_vector` of rows."""
    angle = np.linalg.norm(v, axis=1, keepdims=True)
    small = angle < 1e-12
    s = np.where(small, 0.5, np.sin(0.5 * angle) / np.where(small, 1.0, angle))
    return np.concatenate([np.where(small, 1.0, np.cos(0.5 * angle)), v * s], axis=1)


class HandPipeline:
    """Raw joints of one hand -> scene joints (calibrated, mirrored, filtered)."""

    def __init__(self, spec: TrackerSpec | None) -> None:
        spec = spec or TrackerSpec("")
        self.is_identity = Calibration.of(spec).is_identity
        m = axes_matrix(spec.axes)
        rotation = quat_to_matrix(np.asarray(spec.rotation, np.float64))
        self.linear = rotation @ (spec.scale * m)
        self.offset = np.asarray(spec.offset, np.float64)
        self.radius_scale = abs(spec.scale)
        # orientations: R -> C T R Tᵀ (T = ±M, proper), then the mirror's fix on the right:
        # q -> b ⊗ q ⊗ a, one 4x4 matrix (left and right products are linear in q)
        turn = m if np.linalg.det(m) > 0 else -m
        fix = mirror_fix(spec)
        before = matrix_to_quat(rotation @ turn)
        after = matrix_to_quat(turn.T if fix is None else turn.T @ quat_to_matrix(
            np.asarray(fix)))
        eye = np.eye(4)
        self.turn = np.stack([_qmul(before[None], _qmul(e[None], after[None]))[0]
                              for e in eye])  # row i: the image of basis quaternion i
        self.filters = (JointFilters(spec.min_cutoff, spec.beta)
                        if spec.filter == "oneeuro" else None)

    def __call__(self, raw: HandJoints) -> HandJoints:
        if self.is_identity and self.filters is None:
            return raw
        p = np.asarray(raw.positions, np.float64)
        q = np.asarray(raw.orientations, np.float64)
        radii = raw.radii
        with np.errstate(all="ignore"):  # past float range: told by the hub (finite())
            if not self.is_identity:
                p = p @ self.linear.T + self.offset
                q = q @ self.turn
                if self.radius_scale != 1.0:
                    radii = tuple(r * self.radius_scale for r in radii)
            if self.filters is not None:
                p, q = self.filters(p, q, raw.timestamp)
        return HandJoints(raw.device, tuple(map(tuple, p.tolist())),
                          tuple(map(tuple, q.tolist())), radii, raw.valid, raw.timestamp)
