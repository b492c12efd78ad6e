"""The dynamics system's copy of a state read into the pose table, on every path."""

from __future__ import annotations

import numpy as np

from components import Transform
from engine.physics.backend import BodyState
from engine.world import PoseTable
from systems.dynamics import PoseCopy


def _state(keys: list[int], seed: int) -> BodyState:
    rng = np.random.default_rng(seed)
    n = len(keys)
    return BodyState.from_arrays(np.array(keys, np.int64), rng.random((n, 3)),
                                 rng.random((n, 4)), rng.random((n, 3)), rng.random((n, 3)))


def _table(entities: list[int]) -> tuple[PoseTable, dict[int, Transform]]:
    poses = PoseTable(capacity=4)
    transforms = {e: Transform() for e in entities}
    poses.adopt_many(list(transforms), list(transforms.values()))
    return poses, transforms


def _check(state: BodyState, transforms: dict[int, Transform]) -> None:
    for i, key in enumerate(state.keys.tolist()):
        if key in transforms:
            t = transforms[key]
            np.testing.assert_array_equal(t.position, state.position[i])
            np.testing.assert_array_equal(t.orientation, state.orientation[i])
            np.testing.assert_array_equal(t.linear_velocity, state.linear_velocity[i])
            np.testing.assert_array_equal(t.angular_velocity, state.angular_velocity[i])


def test_rows_in_one_run_are_copied_through_views() -> None:
    poses, transforms = _table([10, 11, 12, 13, 14, 15])  # grows past its capacity of 4
    state = _state([10, 11, 12, 13, 14, 15], 1)
    copy = PoseCopy(poses, state.keys)
    copy(state)
    _check(state, transforms)
    later = _state([10, 11, 12, 13, 14, 15], 2)
    later = BodyState(state.keys, later.table)
    assert copy.fits(poses, later.keys)  # the same key array: no comparison needed
    copy(later)
    _check(later, transforms)


def test_scattered_rows_and_bodies_without_a_transform() -> None:
    poses, transforms = _table([1, 2, 3, 4, 5])
    poses.release(3)
    del transforms[3]
    state = _state([5, 3, 1, 99, 4], 3)  # 3 and 99 have no Transform; rows out of order
    copy = PoseCopy(poses, state.keys)
    copy(state)
    _check(state, transforms)
    np.testing.assert_array_equal(transforms[2].position, [0.0, 0.0, 0.0])  # untouched


def test_a_plan_stops_fitting_when_the_table_changes() -> None:
    poses, transforms = _table([1, 2])
    state = _state([1, 2], 4)
    copy = PoseCopy(poses, state.keys)
    assert copy.fits(poses, np.array([1, 2]))
    assert not copy.fits(poses, np.array([2, 1]))
    extra = Transform()
    poses.adopt(7, extra)  # rows assigned: views planned before may be stale
    assert not copy.fits(poses, state.keys)
