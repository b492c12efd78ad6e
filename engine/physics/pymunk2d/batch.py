"""A pymunk space read and written in batches: one compiled pass over chipmunk each.

One call reads every body's position, angle and velocities, row by row (and who sleeps),
one every cached arbiter's bodies, normal, points and impulse, straight from chipmunk
through pymunk's cffi library (``_rows``' ``_chipmunk.pxi``: the functions
``pymunk.batch`` calls and the arbiter fields pymunk declares, the same numbers to the
bit, without its Python); a compiled pass (``_rows``) turns them into our rows. The
arbiters are read once per step (chipmunk changes its cache of them between steps only as
bodies fall asleep or wake, which the rows' awake flags tell).

A reader is planned for a fixed list of bodies, rows in key order (the backend plans a new
one when bodies come or go): it holds them, so the cpBody pointers the passes follow stay
valid while it stands.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from engine.physics.backend import CONTACT_DTYPE
from engine.physics.pymunk2d import _rows


class SpaceReader:
    """Reads one space's bodies (row ``i`` is ``bodies[i]``, rows in key order) and its
    contacts; the per-row work is done by :class:`_rows.Rows`.

    ``y`` holds each row's Y (kept as authored; the backend writes it in place),
    ``rest`` (n, 4) each body's fixed tilt, applied after the turn about Y, ``cog``
    (n, 2) its centre of mass in the body frame, ``static`` whether each row is a
    static body.
    """

    def __init__(self, space: pymunk.Space, bodies: list[pymunk.Body], keys: np.ndarray,
                 y: np.ndarray, rest: np.ndarray, cog: np.ndarray,
                 static: np.ndarray) -> None:
        n = len(bodies)
        ids = np.fromiter((b.id for b in bodies), np.int64, n)
        pointers = np.fromiter((_rows.chipmunk_pointer(b._body) for b in bodies), np.uintp, n)
        self._rows = _rows.Rows(ids, keys, static, y, rest, cog, CONTACT_DTYPE, pointers,
                                list(bodies), _rows.chipmunk_pointer(space._space))

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """Every body's (x, z, θ, vx, vz, ω) as pymunk has them (velocity of the centre of
        mass), row by row; and which rows are awake. The same two arrays each time: valid
        until the next read."""
        return self._rows.read()

    @property
    def sleepers(self) -> int:
        """How many bodies slept at the last read."""
        return self._rows.sleepers

    def new_step(self) -> None:
        """The space was stepped: its arbiters are new."""
        self._rows.new_step()

    def table(self, raw: np.ndarray, out: np.ndarray, keep: np.ndarray,
              extent: float = math.inf, max_speed: float = math.inf) -> bool:
        """A read as state rows (BodyState's layout) in ``out[:n]``, and as it is in
        ``keep`` (n, 6); whether all finite, inside ``extent`` and under ``max_speed``."""
        return self._rows.table(raw, out, keep, extent, max_speed)

    def motion(self, raw: np.ndarray, velocity: np.ndarray) -> None:
        """A read's centre-of-mass velocities as the sleep rule keeps them, (6, n)."""
        self._rows.motion(raw, velocity)

    @property
    def rows(self) -> _rows.Rows:
        """The compiled rows (ids to rows, reads and writes) this reader was planned
        with."""
        return self._rows

    def arbiters(self, ordered: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The space's arbiters (ints, floats; ``_rows.ARBITER_INTS``/``ARBITER_FLOATS``
        per arbiter), read once per step: chipmunk changes them between steps only as
        bodies fall asleep (their arbiters leave its cache) or wake, which the rows' awake
        flags tell (``ordered``: the caller has just read the bodies, which looked)."""
        return self._rows.arbiters(ordered)

    def islands(self, movable: np.ndarray, joints: np.ndarray) -> np.ndarray:
        """Each row's island label: rows tied by the step's contacts between ``movable``
        rows, or by ``joints`` ((m, 2) rows; -1: the world) (see
        :meth:`_rows.Rows.islands`)."""
        labels = np.empty(len(movable), np.intp)
        self._rows.islands(movable.view(np.uint8), labels,
                           np.ascontiguousarray(joints, np.int64))
        return labels
