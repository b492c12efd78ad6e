"""Interpolation between the two latest physics states (threaded mode, --interpolate)."""

from __future__ import annotations

import math

import numpy as np

from engine.physics.backend import BodyState
from engine.physics.driver import Snapshot
from services.render.interpolate import PoseInterpolator, interpolate_states


def _state(keys, xs, angles) -> BodyState:
    n = len(keys)
    quat = np.array([[math.cos(a / 2), 0.0, 0.0, math.sin(a / 2)] for a in angles])
    pos = np.zeros((n, 3))
    pos[:, 0] = xs
    return BodyState.from_arrays(np.array(keys, np.int64), pos, quat, np.zeros((n, 3)),
                                 np.zeros((n, 3)))


def test_halfway_is_halfway_in_position_and_angle():
    a = _state([1, 2], [0.0, 10.0], [0.0, 0.0])
    b = _state([1, 2], [1.0, 12.0], [math.pi / 2, 0.0])
    keys, pos, quat = interpolate_states(a, b, 0.5)
    assert np.allclose(pos[:, 0], [0.5, 11.0])
    assert np.isclose(2 * math.atan2(quat[0, 3], quat[0, 0]), math.pi / 4)
    assert np.allclose(np.linalg.norm(quat, axis=1), 1.0)


def test_bodies_new_in_the_latest_state_keep_their_pose():
    a = _state([2], [0.0], [0.0])
    b = _state([1, 2], [5.0, 2.0], [0.0, 0.0])
    keys, pos, _ = interpolate_states(a, b, 0.25)
    assert list(keys) == [1, 2] and np.allclose(pos[:, 0], [5.0, 0.5])


def test_interpolator_follows_wall_time_between_arrivals():
    now = [0.0]
    interp = PoseInterpolator(clock=lambda: now[0])
    assert interp.poses() is None
    interp.push(Snapshot(1, 0.01, _state([1], [0.0], [0.0])))
    now[0] = 0.02
    interp.push(Snapshot(2, 0.02, _state([1], [1.0], [0.0])))
    interp.push(Snapshot(2, 0.02, _state([1], [9.0], [0.0])))  # same step again: ignored
    now[0] = 0.025  # a quarter of the 20 ms arrival interval after the newer one
    assert np.isclose(interp.poses()[1][0, 0], 0.25)
    now[0] = 0.5
    assert np.isclose(interp.poses()[1][0, 0], 1.0)  # never extrapolates
