"""A pymunk space read in batches through pymunk's public ``pymunk.batch`` API.

One call copies every body's position, angle and velocities (with its id) into a
buffer, one call every arbiter's bodies, normal, points and impulse; a compiled pass
(``_rows``, on those plain arrays) turns them into our rows. pymunk lists bodies in
chipmunk's own
order, awake bodies first, then static ones, then sleeping ones, and that order
changes as bodies fall asleep and wake; a :class:`SpaceReader` keeps the
permutation to our rows and rebuilds it only when the ids come out in a new order,
which also tells which bodies are asleep.

A reader is planned for a fixed list of bodies, rows in key order (the backend plans
a new one when bodies come or go).
"""

from __future__ import annotations

import math

import numpy as np
import pymunk
import pymunk.batch

from engine.physics.backend import CONTACT_DTYPE
from engine.physics.pymunk2d import _rows

_ID = pymunk.batch.BodyFields.BODY_ID
_FORCE = pymunk.batch.BodyFields.FORCE
_ID_FORCE = _ID | _FORCE
_VELOCITY = pymunk.batch.BodyFields.VELOCITY | pymunk.batch.BodyFields.ANGULAR_VELOCITY
_BODY = (pymunk.batch.BodyFields.BODY_ID | pymunk.batch.BodyFields.POSITION
         | pymunk.batch.BodyFields.ANGLE | pymunk.batch.BodyFields.VELOCITY
         | pymunk.batch.BodyFields.ANGULAR_VELOCITY)
_ARB = pymunk.batch.ArbiterFields
_ARBITER = (_ARB.BODY_A_ID | _ARB.BODY_B_ID | _ARB.CONTACT_COUNT | _ARB.TOTAL_IMPULSE
            | _ARB.NORMAL | _ARB.POINT_A_1 | _ARB.POINT_B_1 | _ARB.DISTANCE_1
            | _ARB.POINT_A_2 | _ARB.POINT_B_2 | _ARB.DISTANCE_2)


class Buffers:
    """The batch buffers a space is read and written through, made once per backend and
    handed to every reader planned for it: pymunk never frees a ``pymunk.batch.Buffer``'s
    C arrays, so one made per plan leaked them each time bodies came or went (a script
    spawning and deleting every frame grew the process by ~700 bytes per object).

    ``forces`` reads ids and forces (and ids alone), so a body read stays valid through
    them; ``writes`` only ever writes: its floats are a numpy array of ours
    (``Buffer.set_float_buf``), which a read into it would reallocate under numpy."""

    def __init__(self) -> None:
        self.bodies = pymunk.batch.Buffer()
        self.arbiters = pymunk.batch.Buffer()
        self.forces = pymunk.batch.Buffer()
        self.writes = pymunk.batch.Buffer()
        self.velocities = pymunk.batch.Buffer()  # writes only, as ``writes``
        self.written: np.ndarray | None = None  # the array ``writes`` holds now


class SpaceReader:
    """Reads one space's bodies (row ``i`` is ``bodies[i]``, rows in key order) and its
    contacts; the per-row work is done by :class:`_rows.Rows`.

    ``y`` holds each row's Y (kept as authored; the backend writes it in place),
    ``rest`` (n, 4) each body's fixed tilt, applied after the turn about Y, ``cog``
    (n, 2) its centre of mass in the body frame, ``static`` whether each row is a
    static body.
    """

    def __init__(self, space: pymunk.Space, bodies: list[pymunk.Body], keys: np.ndarray,
                 y: np.ndarray, rest: np.ndarray, cog: np.ndarray, static: np.ndarray,
                 buffers: Buffers) -> None:
        self._space = space
        self._buffers = buffers
        self._buffer, self._arbiters = buffers.bodies, buffers.arbiters
        #: the step's arbiters as read (ints, floats) and the body order then; dropped by
        #: :meth:`new_step`, and read again if a body has fallen asleep or woken since
        self._arbiter_read: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._sleepers = 0
        ids = np.fromiter((b.id for b in bodies), np.int64, len(bodies))
        self._rows = _rows.Rows(ids, keys, static, y, rest, cog, CONTACT_DTYPE)
        # the static bodies pymunk lists between the awake and the sleeping ones: ours
        # and the space's own
        self._static_ids = np.sort(np.append(ids[static], space.static_body.id))
        self._order = np.zeros(0, np.int64)
        self._order_bytes = b"-"  # never a read: the first read plans the order
        self.gather = np.zeros(len(bodies), np.intp)  # row -> place in pymunk's list
        self._awake = np.zeros(len(bodies), bool)
        self._zeros = np.zeros((0, 2))  # no force on any body, in pymunk's list

    def _plan_order(self, ids: np.ndarray) -> None:
        """pymunk listed the bodies in a new order: where each row is, and who sleeps."""
        gather = np.full(len(self.gather), -1, np.intp)
        others = self._rows.order(ids, gather)
        if others != 1 or (gather < 0).any():
            raise RuntimeError("pymunk lists other bodies than the backend planned for")
        static = np.isin(ids, self._static_ids)
        first = int(np.argmax(static))
        if not static[first:first + len(self._static_ids)].all() or \
                static[first + len(self._static_ids):].any():
            raise RuntimeError("pymunk no longer lists static bodies in one run between the "
                               "awake and the sleeping ones; the backend cannot tell who sleeps")
        self.gather = gather
        self._awake = gather < first
        self._sleepers = len(ids) - first - len(self._static_ids)
        self._order = ids.copy()
        self._order_bytes = ids.tobytes()

    def _check_order(self, ids: bytes) -> None:
        """``ids``: pymunk's list of body ids as read (bytes, compared in one memcmp)."""
        if ids != self._order_bytes:
            self._plan_order(np.frombuffer(ids, np.int64))

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """Every body's (x, z, θ, vx, vz, ω) as pymunk has them (velocity of the centre of
        mass), in pymunk's order (row ``i`` is at ``gather[i]``); and which rows are
        awake. Valid until the next read."""
        buffer = self._buffer
        buffer.clear()
        pymunk.batch.get_space_bodies(self._space, _BODY, buffer)
        self._check_order(buffer.int_buf()[:])
        return np.frombuffer(buffer.float_buf(), np.float64).reshape(-1, 6), self._awake

    def forces(self) -> tuple[np.ndarray, np.ndarray, bool]:
        """Every body's force (x, z) as it stands now, in pymunk's order (row ``i`` at
        ``gather[i]``; valid until the next call); which rows are awake, and whether any
        body sleeps."""
        buffer = self._buffers.forces
        buffer.clear()
        pymunk.batch.get_space_bodies(self._space, _ID_FORCE, buffer)
        self._check_order(buffer.int_buf()[:])
        return (np.frombuffer(buffer.float_buf(), np.float64).reshape(-1, 2), self._awake,
                self._sleepers > 0)

    def known_forces(self) -> tuple[np.ndarray, np.ndarray, bool]:
        """As :meth:`forces`, without a read, for a space whose bodies are listed as at
        the last read and have no force (pymunk zeroes each dynamic body's force as it
        steps it, and a static or kinematic body's force moves nothing)."""
        zeros = self._zeros
        if len(zeros) != len(self._order):
            zeros = self._zeros = np.zeros((len(self._order), 2))
        return zeros, self._awake, self._sleepers > 0

    def force_rows(self) -> np.ndarray:
        """An array (pymunk's list: a row per body, x and z) for :meth:`set_forces`."""
        out = self._buffers.written
        if out is None or len(out) != len(self._order):
            out = np.zeros((len(self._order), 2))
        return out

    def set_forces(self, forces: np.ndarray) -> None:
        """Every body's force from ``forces`` (from :meth:`force_rows`), in one batch.
        Setting a force wakes a body: only for a space where none sleeps."""
        if self._sleepers:
            raise RuntimeError("set_forces would wake the sleeping bodies")
        buffers = self._buffers
        if buffers.written is not forces:
            buffers.writes.set_float_buf(forces.reshape(-1))
            buffers.written = forces
        pymunk.batch.set_space_bodies(self._space, _FORCE, buffers.writes)

    def set_velocities(self, raw: np.ndarray) -> None:
        """Every body's velocity and spin from a read (:meth:`read`'s array, (n, 6)), in
        one batch. Setting a velocity wakes a body: only for a space where none sleeps."""
        if self._sleepers:
            raise RuntimeError("set_velocities would wake the sleeping bodies")
        velocities = np.ascontiguousarray(raw[:, 3:6])
        buffer = self._buffers.velocities
        buffer.set_float_buf(velocities.reshape(-1))
        pymunk.batch.set_space_bodies(self._space, _VELOCITY, buffer)

    @property
    def sleepers(self) -> int:
        """How many bodies slept at the last read."""
        return self._sleepers

    def new_step(self) -> None:
        """The space was stepped: its arbiters are new."""
        self._arbiter_read = None

    def table(self, raw: np.ndarray, out: np.ndarray, keep: np.ndarray,
              extent: float = math.inf, max_speed: float = math.inf) -> bool:
        """A read as state rows (BodyState's layout) in ``out[:n]``, and in row order as
        it is in ``keep`` (n, 6); whether all finite, inside ``extent`` and under
        ``max_speed``."""
        return self._rows.table(raw, self.gather, out, keep, extent, max_speed)

    def motion(self, raw: np.ndarray, velocity: np.ndarray) -> None:
        """A read's centre-of-mass velocities as the sleep rule keeps them, (6, n)."""
        self._rows.motion(raw, self.gather, velocity)

    @property
    def rows(self) -> _rows.Rows:
        """The compiled rows (ids to rows) this reader was planned with."""
        return self._rows

    def arbiters(self, ordered: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The space's arbiters (ints, floats; ``_rows.ARBITER_INTS``/``ARBITER_FLOATS``
        per arbiter), read once per step: chipmunk changes them between steps only as
        bodies fall asleep (their arbiters leave its cache) or wake, which the order
        pymunk lists the bodies in tells (a read of the ids alone; ``ordered``: the caller
        has just read the bodies, which checked it)."""
        if not ordered:
            ids = self._buffers.forces
            ids.clear()
            pymunk.batch.get_space_bodies(self._space, _ID, ids)
            self._check_order(ids.int_buf()[:])
        read = self._arbiter_read
        if read is not None and read[2] is self._order:
            return read[0], read[1]
        buffer = self._arbiters
        buffer.clear()
        pymunk.batch.get_space_arbiters(self._space, _ARBITER, buffer)
        ints = np.frombuffer(buffer.int_buf(), np.int64).reshape(-1, _rows.ARBITER_INTS)
        floats = np.frombuffer(buffer.float_buf(), np.float64).reshape(-1,
                                                                        _rows.ARBITER_FLOATS)
        self._arbiter_read = (ints, floats, self._order)
        return ints, floats

    def contacts(self) -> tuple[np.ndarray, np.ndarray]:
        """One CONTACT_DTYPE row per touching shape pair, sorted by keys then place, and
        each one's rows (a, b; -1: the keyless world), (m, 2) (see
        :meth:`_rows.Rows.contacts`)."""
        return self._rows.contacts(*self.arbiters())

    def islands(self, movable: np.ndarray, joints: np.ndarray) -> np.ndarray:
        """Each row's island label: rows tied by the step's contacts between ``movable``
        rows, or by ``joints`` ((m, 2) rows; -1: the world) (see
        :meth:`_rows.Rows.islands`)."""
        labels = np.empty(len(self.gather), np.intp)
        self._rows.islands(self.arbiters()[0], movable.view(np.uint8), labels,
                           np.ascontiguousarray(joints, np.int64))
        return labels
