"""The readback of every body's state into the ECS pose table, as the engine does it,
shared by the physics benchmarks of both backends.

:class:`EcsReadback` is the real path: the backend writes its rows into a snapshot table
(``read_state_into``, a buffer reused once no snapshot holds it,
:class:`engine.physics.driver._Tables`), which :class:`systems.dynamics.PoseCopy`
copies into the pose table in one block. :func:`time_readback` puts it beside the old
path (``read_state``: fresh arrays, then the same copy).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from engine.physics.backend import BodyState


class EcsReadback:
    """Every body's state into the ECS pose table, through a snapshot table, planned once
    per layout of bodies."""

    def __init__(self, backend: Any, poses: Any) -> None:
        from engine.physics.driver import _Tables
        from systems.dynamics import PoseCopy

        self._backend, self._tables = backend, _Tables()
        self._copy = PoseCopy(poses, backend.keys())

    def __call__(self) -> None:
        table = self._tables.take(self._backend.body_count())
        keys = self._backend.read_state_into(table)
        self._copy(BodyState(keys, table).freeze())


def pose_table(keys: np.ndarray) -> Any:
    """The ECS pose table with a Transform for every key, adopted in key order."""
    from components import Transform
    from engine.world import PoseTable

    poses = PoseTable()
    ordered = sorted(keys.tolist())
    poses.adopt_many(ordered, [Transform() for _ in ordered])
    return poses


def time_readback(backend: Any, calls: int = 2000) -> dict[str, float]:
    """µs per readback of every body's state into the ECS pose table, old path and new,
    alternating blocks of calls on the same backend; medians of the blocks."""
    from systems.dynamics import PoseCopy

    poses = pose_table(backend.keys())
    copy = PoseCopy(poses, backend.keys())
    readback = EcsReadback(backend, poses)

    def old() -> None:
        copy(backend.read_state())

    block = 50
    times: dict[str, list[float]] = {"read_state+copy": [], "read_state_into": []}
    for _ in range(max(1, calls // block)):
        for name, fn in (("read_state+copy", old), ("read_state_into", readback)):
            t0 = time.perf_counter()
            for _ in range(block):
                fn()
            times[name].append((time.perf_counter() - t0) / block * 1e6)
    old_us, new_us = (float(np.median(times[k])) for k in times)
    return {"N": backend.body_count(), "read_state+copy us": old_us,
            "read_state_into us": new_us, "new/old": new_us / old_us}
