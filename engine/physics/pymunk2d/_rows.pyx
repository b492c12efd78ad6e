# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""A pymunk space's bodies and arbiters into engine rows, as C loops over chipmunk.

The passes read chipmunk directly, through the functions pymunk's cffi library exports
and the arbiter fields it declares (``_chipmunk.pxi``): every body's pose and velocities,
who sleeps, every cached arbiter's bodies, normal, points and impulse, and they write the
forces and velocities the resting warm start sets, each one call with no Python per body
(``pymunk.batch``, the public batch API, reads the same numbers to the bit through
chipmunk's getters, but its Python per call and its growable buffers were a fixed cost of
each of the several reads a step takes). Turning the reads into our rows (the state
table; sorted contact records) is one pass each too.

A :class:`Rows` is planned for a fixed list of bodies, identified by their pymunk
``Body.id`` (chipmunk's user data of the body, which is how an arbiter names its
bodies) and reached through their cpBody pointers (the backend plans a new one when
bodies come or go).
"""

cimport numpy as cnp
from libc.math cimport INFINITY, atan2, cos, exp, fabs, hypot, isfinite, sin, sqrt
from libc.stdint cimport int8_t, int64_t, uint64_t, uintptr_t
from libc.stdlib cimport free, malloc, realloc
from libc.string cimport memcpy


cdef extern from "math.h" nogil:
    void sincos(double x, double *sin, double *cos)  # GNU; setup.py defines _GNU_SOURCE

import numpy as np

cnp.import_array()

#: Numbers per body in the body buffer: x, y, angle, vx, vy, ω.
BODY_FLOATS = 6
#: Numbers per arbiter: ids (a, b) and contact count; impulse (2), normal (2), then per
#: contact point a (2), point b (2), distance (1), for two contacts.
ARBITER_INTS = 3
ARBITER_FLOATS = 14
#: :func:`planar_poses` flags: the orientation tilts otherwise than the body's rest tilt;
#: a velocity leaves the X–Z plane.
RETILT = 1
OFF_PLANE = 2
#: How far (any component) a row's tilt may be from its body's rest tilt.
TILT_TOLERANCE = 1e-6

cdef enum:  # the same counts, for code without the GIL
    _BF = 6
    _AI = 3
    _AF = 14


cdef struct _Table:
    # body id (or cpBody pointer) -> row: open addressing with linear probing (slot_row
    # -1: empty)
    const uint64_t *slot_id
    const Py_ssize_t *slot_row
    uint64_t mask
    Py_ssize_t n


cdef inline uint64_t _mix(uint64_t h) noexcept nogil:
    """splitmix64's finaliser: ids share their low bits, so spread every bit."""
    h = (h ^ (h >> 30)) * <uint64_t>0xBF58476D1CE4E5B9
    h = (h ^ (h >> 27)) * <uint64_t>0x94D049BB133111EB
    return h ^ (h >> 31)


cdef void _fill(uint64_t *slot_id, Py_ssize_t *slot_row, uint64_t mask, const uint64_t *ids,
                Py_ssize_t n) noexcept nogil:
    """A table of ``mask + 1`` slots (at most a quarter full) from row ``i`` to ``ids[i]``."""
    cdef uint64_t s
    cdef Py_ssize_t i
    for s in range(mask + 1):
        slot_row[s] = -1
    for i in range(n):
        s = _mix(ids[i]) & mask
        while slot_row[s] != -1:
            s = (s + 1) & mask
        slot_id[s] = ids[i]
        slot_row[s] = i


cdef inline Py_ssize_t _row_of(const _Table *t, uint64_t body_id) noexcept nogil:
    """A body's row; ``n`` (the keyless world) when it is not one of ours."""
    cdef uint64_t s = _mix(body_id) & t.mask
    while t.slot_row[s] != -1:
        if t.slot_id[s] == body_id:
            return t.slot_row[s]
        s = (s + 1) & t.mask
    return t.n


include "_chipmunk.pxi"


cdef struct Contact:
    # laid out as CONTACT_DTYPE: a, b, position (3), normal (3), depth, impulse
    int64_t a
    int64_t b
    double point[3]
    double normal[3]
    double depth
    double impulse


cdef inline bint _before(const Contact *a, const Contact *b) noexcept nogil:
    """Within one side-a body: by key b, then x, z and impulse (a pair may touch twice)."""
    if a.b != b.b:
        return a.b < b.b
    if a.point[0] != b.point[0]:
        return a.point[0] < b.point[0]
    if a.point[2] != b.point[2]:
        return a.point[2] < b.point[2]
    return a.impulse < b.impulse


cdef inline Py_ssize_t _root(Py_ssize_t *parent, Py_ssize_t r) noexcept nogil:
    """Union-find: ``r``'s root, halving the path on the way."""
    while parent[r] != r:
        parent[r] = parent[parent[r]]
        r = parent[r]
    return r


cdef class Rows:
    """Rows of one list of bodies (row ``i`` is the body with ``ids[i]``, whose cpBody is
    at ``bodies[i]``), keys in increasing order.

    ``owners`` is what keeps those cpBody alive (the pymunk bodies, held as long as the
    rows); ``y`` holds each row's Y (kept as authored; the backend writes it in place),
    ``rest`` (n, 4) each body's fixed tilt, applied after the turn about Y, ``cog``
    (n, 2) its centre of mass in the body frame (pymunk keeps that point's velocity;
    ours is the origin's), ``static`` whether each row is a static body.
    """

    cdef Py_ssize_t n
    cdef uint64_t mask
    cdef uint64_t *slot_id
    cdef Py_ssize_t *slot_row
    cdef _Table lookup  # the same, for the passes
    cdef uint64_t *slot_body  # cpBody pointer -> row, likewise
    cdef Py_ssize_t *slot_body_row
    cdef _Table by_body
    cdef cnp.ndarray _ids  # each row's body id (chipmunk's user data of its body)
    cdef Py_ssize_t *run_end
    # contacts' scratch, kept between calls (grown as needed): records, side-a row, side-b
    cdef Contact *scratch
    cdef Py_ssize_t *scratch_a
    cdef Py_ssize_t *scratch_b
    cdef Py_ssize_t scratch_size
    cdef bint any_rest, any_cog
    cdef object contact_dtype
    # the arrays behind the raw pointers below, kept alive
    cdef cnp.ndarray _keys, _static, _y, _rest, _cog
    cdef const int64_t *keys
    cdef const unsigned char *static
    cdef const double *y
    cdef const double *rest
    cdef const double *cog
    cdef object _owners, _bodies
    cdef void *space  # the cpSpace
    cdef void **bodies  # each row's cpBody
    # the last read (n, 6) and who is awake (n), and the arrays behind them
    cdef double *raw
    cdef unsigned char *awake
    #: the last body read, (n, 6), and who is awake then (n): :meth:`read`'s two arrays
    cdef readonly cnp.ndarray bodies_read, bodies_awake
    # per row, whether that read's position is its centre of gravity (chipmunk's body p:
    # the centre of gravity is the body's origin and the position finite)
    cdef cnp.ndarray _centred
    #: how many rows slept at the last look; counts the changes of who is awake
    cdef readonly Py_ssize_t sleepers, epoch
    # the step's arbiter read (ARBITER_INTS, ARBITER_FLOATS per arbiter, and its rows a,
    # b), grown as needed: m arbiters, read when ``epoch`` was read_epoch (-1: none)
    cdef cnp.ndarray _arbiter_ptrs, _arbiter_ints, _arbiter_floats, _pairs
    # (ints, floats) buffers handed over by :meth:`keep_arbiters`, and those free again
    cdef list _kept, _spare
    cdef Py_ssize_t m, read_epoch

    def __cinit__(self) -> None:
        self.slot_id = NULL
        self.slot_row = NULL
        self.slot_body = NULL
        self.slot_body_row = NULL
        self.run_end = NULL
        self.scratch = NULL
        self.scratch_a = NULL
        self.scratch_b = NULL
        self.scratch_size = 0

    def __init__(self, ids, keys, static, y, rest, cog, contact_dtype, bodies=None,
                 owners=None, space=0) -> None:
        cdef Py_ssize_t n = len(ids)
        if np.dtype(contact_dtype).itemsize != sizeof(Contact):
            raise ValueError("contact dtype does not match the Contact record")
        if bodies is None:  # no space behind the rows: the passes over given arrays only
            bodies = np.zeros(n, np.uintp)
        if not (len(keys) == len(static) == len(y) == len(rest) == len(cog) == len(bodies)
                == n):
            raise ValueError("Rows: arrays do not match the bodies")
        self._chipmunk(bodies, owners, space)
        if n > 1 and not np.all(np.diff(keys) > 0):
            raise ValueError("Rows: rows must be in increasing key order")
        self._y = y
        if not (isinstance(y, np.ndarray) and y.dtype == np.float64 and y.flags.c_contiguous):
            raise ValueError("y must be a contiguous float64 array (it is written in place)")
        self._keys = np.ascontiguousarray(keys, np.int64)
        self._static = np.ascontiguousarray(static, np.uint8)
        self._rest = np.ascontiguousarray(rest, np.float64).reshape(n, 4)
        self._cog = np.ascontiguousarray(cog, np.float64).reshape(n, 2)
        self.keys = <const int64_t *>cnp.PyArray_DATA(self._keys)
        self.static = <const unsigned char *>cnp.PyArray_DATA(self._static)
        self.y = <const double *>cnp.PyArray_DATA(self._y)
        self.rest = <const double *>cnp.PyArray_DATA(self._rest)
        self.cog = <const double *>cnp.PyArray_DATA(self._cog)
        self.any_rest = bool(n) and not np.all(self._rest[:, 0] == 1.0)
        self.any_cog = bool(np.any(self._cog))
        self.contact_dtype = contact_dtype
        self.n = n
        self._tables(ids)

    cdef void _tables(self, ids) except *:
        """Body id -> row and cpBody pointer -> row (open addressing with linear probing,
        at most a quarter full), and the scratch of the contacts' sort."""
        cdef Py_ssize_t n = self.n
        cdef uint64_t size = 16
        while size < 4 * <uint64_t>n:
            size <<= 1
        self.mask = size - 1
        self._ids = np.ascontiguousarray(ids, np.int64).reshape(n)
        self.slot_id = <uint64_t *>malloc(size * sizeof(uint64_t))
        self.slot_row = <Py_ssize_t *>malloc(size * sizeof(Py_ssize_t))
        self.slot_body = <uint64_t *>malloc(size * sizeof(uint64_t))
        self.slot_body_row = <Py_ssize_t *>malloc(size * sizeof(Py_ssize_t))
        self.run_end = <Py_ssize_t *>malloc((n + 1) * sizeof(Py_ssize_t))
        if (self.slot_id == NULL or self.slot_row == NULL or self.slot_body == NULL
                or self.slot_body_row == NULL or self.run_end == NULL):
            raise MemoryError
        _fill(self.slot_id, self.slot_row, self.mask,
              <const uint64_t *>cnp.PyArray_DATA(self._ids), n)
        _fill(self.slot_body, self.slot_body_row, self.mask, <const uint64_t *>self.bodies, n)
        self.lookup.slot_id = self.slot_id
        self.lookup.slot_row = self.slot_row
        self.lookup.mask = self.mask
        self.lookup.n = n
        self.by_body.slot_id = self.slot_body
        self.by_body.slot_row = self.slot_body_row
        self.by_body.mask = self.mask
        self.by_body.n = n

    cdef void _chipmunk(self, bodies, owners, space) except *:
        """The rows' cpBody and cpSpace (held alive by ``owners``), and the buffers the
        passes over them read into."""
        n = len(bodies)
        self._owners = owners
        self._bodies = np.ascontiguousarray(bodies, np.uintp)
        self.bodies = <void **>cnp.PyArray_DATA(self._bodies)
        self.space = <void *><uintptr_t>space
        self._arbiter_ints = np.zeros((0, _AI), np.int64)
        self._arbiter_floats = np.zeros((0, _AF), np.float64)
        self._pairs = np.zeros((0, 2), np.intp)
        self._arbiter_ptrs = np.zeros(0, np.uintp)
        self._kept = []
        self._spare = []
        self.m = 0
        self.read_epoch = -1
        self.epoch = 0
        self.sleepers = 0
        self.bodies_read = np.zeros((n, _BF))
        self.bodies_awake = np.zeros(n, bool)
        self.raw = <double *>cnp.PyArray_DATA(self.bodies_read)
        self.awake = <unsigned char *>cnp.PyArray_DATA(self.bodies_awake)
        self._centred = np.zeros(n, np.uint8)

    def __dealloc__(self) -> None:
        free(self.slot_id)
        free(self.slot_row)
        free(self.slot_body)
        free(self.slot_body_row)
        free(self.run_end)
        free(self.scratch)
        free(self.scratch_a)
        free(self.scratch_b)

    cdef int _reserve(self, Py_ssize_t m) except -1:
        """Scratch for ``m`` contacts (a fresh allocation per call of that size came
        from mmap, page faults and all, at a few thousand contacts)."""
        cdef void *grown
        if m <= self.scratch_size:
            return 0
        m = max(m, 2 * self.scratch_size)
        grown = realloc(self.scratch, m * sizeof(Contact))
        if grown == NULL:
            raise MemoryError("out of memory collecting contacts")
        self.scratch = <Contact *>grown
        grown = realloc(self.scratch_a, m * sizeof(Py_ssize_t))
        if grown == NULL:
            raise MemoryError("out of memory collecting contacts")
        self.scratch_a = <Py_ssize_t *>grown
        grown = realloc(self.scratch_b, m * sizeof(Py_ssize_t))
        if grown == NULL:
            raise MemoryError("out of memory collecting contacts")
        self.scratch_b = <Py_ssize_t *>grown
        self.scratch_size = m
        return 0

    cdef inline Py_ssize_t row(self, uint64_t body_id) noexcept nogil:
        """A body's row; ``n`` (the keyless world) when it is not one of ours."""
        return _row_of(&self.lookup, body_id)

    cdef int _bound(self) except -1:
        """Refuse a pass over chipmunk for rows planned without their bodies."""
        if self.n and self.bodies[0] == NULL:
            raise ValueError("Rows: planned without their cpBody pointers")
        return 0

    cdef Py_ssize_t _look(self, bint pose) noexcept nogil:
        """Whether each row is awake (neither static nor asleep) into ``awake``, and with
        ``pose`` its (x, z, θ, vx, vz, ω) into ``raw``; a new ``epoch`` where who is awake
        changed. How many rows sleep."""
        cdef Py_ssize_t r, sleepers = 0
        cdef void *b
        cdef double *p
        cdef cpVect v
        cdef unsigned char now
        cdef unsigned char *centred = <unsigned char *>cnp.PyArray_DATA(self._centred)
        cdef bint changed = False
        for r in range(self.n):
            b = self.bodies[r]
            if r + 8 < self.n:
                _ahead(self.bodies[r + 8])
            if pose:
                p = &self.raw[_BF * r]
                v = cp.position(b)
                p[0] = v.x
                p[1] = v.y
                p[2] = cp.angle(b)
                v = cp.velocity(b)
                p[3] = v.x
                p[4] = v.y
                p[5] = cp.spin(b)
                v = cp.cog(b)
                # cpBodyGetPosition is the origin, body p the centre of gravity: the same
                # where the centre of gravity is the origin (the transform's c·0 terms)
                centred[r] = (v.x == 0.0 and v.y == 0.0 and isfinite(p[0])
                              and isfinite(p[1]))
            now = not self.static[r] and not cp.sleeping(b)
            changed |= now != self.awake[r]
            self.awake[r] = now
            sleepers += not self.static[r] and not now
        if changed:
            self.epoch += 1
        self.sleepers = sleepers
        return sleepers

    def read(self):
        """Every row's (x, z, θ, vx, vz, ω) as chipmunk has them (velocity of the centre
        of mass), row by row, and whether it is awake (neither static nor asleep): the
        arrays :attr:`bodies_read` (n, 6) and :attr:`bodies_awake` (n,), the same two each
        time."""
        self._bound()
        with nogil:
            self._look(True)
        return self.bodies_read, self.bodies_awake

    cdef int _arbiters(self, bint read=False) except -1:
        """The step's arbiters read into ``arbiter_ints``/``arbiter_floats`` (and each
        one's rows into ``pairs``) unless they were read this step, with who is awake as
        it is now: chipmunk changes its cache of arbiters between steps only as bodies
        fall asleep (their arbiters leave it) or wake. ``read``: the bodies were read
        right before, nothing moved since (their positions give the points)."""
        cdef _Collect found
        cdef _Known known
        cdef Py_ssize_t size
        if self.read_epoch == self.epoch:
            return 0
        if self.space == NULL:
            raise ValueError("Rows: planned without their space")
        while True:
            found.arbiters = <void **>cnp.PyArray_DATA(self._arbiter_ptrs)
            found.size = cnp.PyArray_DIM(self._arbiter_ptrs, 0)
            found.used = 0
            with nogil:
                cp.each_cached_arbiter(self.space, _collect, &found)
            if found.used <= found.size:
                break
            size = max(found.used + found.used // 2, 64)
            self._arbiter_ptrs = np.zeros(size, np.uintp)
            self._arbiter_ints = np.zeros((size, _AI), np.int64)
            self._arbiter_floats = np.zeros((size, _AF), np.float64)
            self._pairs = np.zeros((size, 2), np.intp)
        known.table = &self.lookup
        known.by_body = &self.by_body
        known.ids = <const int64_t *>cnp.PyArray_DATA(self._ids)
        known.raw = self.raw if read else NULL
        known.centred = <const unsigned char *>cnp.PyArray_DATA(self._centred)
        with nogil:
            _read_arbiters(found.arbiters, found.used,
                           <int64_t *>cnp.PyArray_DATA(self._arbiter_ints),
                           <double *>cnp.PyArray_DATA(self._arbiter_floats),
                           <Py_ssize_t *>cnp.PyArray_DATA(self._pairs), &known)
        self.m = found.used
        self.read_epoch = self.epoch
        return 0

    def new_step(self) -> None:
        """The space was stepped: its arbiters are new."""
        self.read_epoch = -1

    def arbiters(self, bint looked=False):
        """The step's arbiters, read once: ints (m, ARBITER_INTS: body ids a and b,
        contact count) and floats (m, ARBITER_FLOATS: total impulse, normal, then per
        contact point a, point b and distance, for two), every arbiter chipmunk has cached,
        in its order, as pymunk.batch reads them. ``looked``: who is awake was read since
        anything could change it (else it is looked at first). Valid until the next
        read."""
        self._bound()
        if not looked:
            with nogil:
                self._look(False)
        self._arbiters()
        return self._arbiter_ints[:self.m], self._arbiter_floats[:self.m]

    def keep_arbiters(self, bint looked=False):
        """:meth:`arbiters`' read handed over: valid until :meth:`reuse` (the next reads
        go into other buffers), where a copy of it cost a substep two new arrays."""
        cdef tuple read = self.arbiters(looked)
        cdef Py_ssize_t size = cnp.PyArray_DIM(self._arbiter_ptrs, 0)
        self._kept.append((self._arbiter_ints, self._arbiter_floats))
        while self._spare:
            ints, floats = self._spare.pop()
            if cnp.PyArray_DIM(ints, 0) == size:
                break
        else:
            ints, floats = np.zeros((size, _AI), np.int64), np.zeros((size, _AF), np.float64)
        self._arbiter_ints, self._arbiter_floats = ints, floats
        self.read_epoch = -1  # the read is no longer in the rows' buffers
        return read

    def reuse(self) -> None:
        """The reads :meth:`keep_arbiters` handed over are no longer held: their buffers
        take the next ones."""
        self._spare.extend(self._kept)
        self._kept.clear()

    cdef void _set_velocities(self, const unsigned char *rows) noexcept nogil:
        """The velocity and spin of each row flagged in ``rows`` from :attr:`raw`, into
        chipmunk as its setters set them (:func:`_awake_velocity`)."""
        cdef Py_ssize_t r
        cdef cpVect v
        cdef bint direct = self.space != NULL and _idle_unread(self.space)
        for r in range(self.n):
            if rows[r]:
                v.x = self.raw[_BF * r + 3]
                v.y = self.raw[_BF * r + 4]
                _awake_velocity(self.bodies[r], v, self.raw[_BF * r + 5], direct)

    def table(self, cnp.ndarray raw, cnp.ndarray out, cnp.ndarray keep,
              double extent=INFINITY, double max_speed=INFINITY) -> bool:
        """Rows of ``raw`` (a read, row by row: x, z, θ, vx, vz, ω) into state rows in
        ``out`` (BodyState's layout), and as they are into ``keep`` (n, 6); whether
        all of them were finite, inside ``extent`` (|x|, |z|) and under ``max_speed``
        (|vx|, |vz|, |ω|).

        The turn θ about pymunk's axis is a quaternion about −Y (pymunk turns X toward Z;
        a right-handed turn about +Y turns Z toward X), the rest tilt after it; the
        velocity is the origin's; the angular velocity is (0, −ω, 0).
        """
        cdef Py_ssize_t i
        cdef const double *p
        cdef const double *r
        cdef const double *g
        cdef double *row
        cdef double c, s, ox, oz, total = 0.0, far = 0.0, fast = 0.0
        cdef const double *read = <const double *>_numbers(raw, cnp.NPY_DOUBLE, _BF * self.n, "raw")
        cdef double *kept = <double *>_numbers(keep, cnp.NPY_DOUBLE, _BF * self.n, "keep")
        cdef double *rows = _state_rows(out, self.n)
        with nogil:
            for i in range(self.n):
                p = &read[_BF * i]
                row = &rows[13 * i]
                memcpy(&kept[_BF * i], p, 6 * sizeof(double))
                total += p[0] + p[1] + p[2] + p[3] + p[4] + p[5]
                far = max(far, max(fabs(p[0]), fabs(p[1])))
                fast = max(fast, max(fabs(p[3]), max(fabs(p[4]), fabs(p[5]))))
                row[0] = p[0]
                row[1] = self.y[i]
                row[2] = p[1]
                sincos(-0.5 * p[2], &s, &c)
                if self.any_rest:  # (c, 0, s, 0) ⊗ rest
                    r = &self.rest[4 * i]
                    row[3] = c * r[0] - s * r[2]
                    row[4] = c * r[1] + s * r[3]
                    row[5] = c * r[2] + s * r[0]
                    row[6] = c * r[3] - s * r[1]
                else:
                    row[3] = c
                    row[4] = 0.0
                    row[5] = s
                    row[6] = 0.0
                if self.any_cog:  # v_origin = v_cog + ω × (origin − cog)
                    g = &self.cog[2 * i]
                    sincos(p[2], &s, &c)
                    ox = c * g[0] - s * g[1]
                    oz = s * g[0] + c * g[1]
                    row[7] = p[3] + p[5] * oz
                    row[9] = p[4] - p[5] * ox
                else:
                    row[7] = p[3]
                    row[9] = p[4]
                row[8] = 0.0
                row[10] = 0.0
                row[11] = -p[5]
                row[12] = 0.0
        return bool(isfinite(total)) and not (far > extent or fast > max_speed)

    def motion(self, cnp.ndarray raw, cnp.ndarray velocity, cnp.ndarray awake=None,
               cnp.ndarray awake_out=None) -> None:
        """Centre-of-mass velocities as the sleep rule keeps them: columns of (6, n),
        (vx, 0, vz) then (0, −ω, 0); and ``awake`` (n bools) copied into ``awake_out``
        where given."""
        cdef Py_ssize_t i, n = self.n
        cdef const double *p
        cdef const double *r = <const double *>_numbers(raw, cnp.NPY_DOUBLE, _BF * n, "raw")
        cdef double *v = <double *>_numbers(velocity, cnp.NPY_DOUBLE, 6 * n, "velocity")
        if awake is not None:
            memcpy(_numbers(awake_out, cnp.NPY_BOOL, n, "awake_out"),
                   _numbers(awake, cnp.NPY_BOOL, n, "awake"), n)
        with nogil:
            for i in range(n):
                p = &r[_BF * i]
                v[i] = p[3]
                v[n + i] = 0.0
                v[2 * n + i] = p[4]
                v[3 * n + i] = 0.0
                v[4 * n + i] = -p[5]
                v[5 * n + i] = 0.0

    # Long: one typed pass over the arbiter rows (C locals)
    def contacts(self, const int64_t[:, ::1] ints, const double[:, ::1] floats):
        """One CONTACT_DTYPE row per touching arbiter, sorted by keys then place; and
        each one's rows (side a, side b; -1: the keyless world), (m, 2) int64.

        Side "a" is the moving body or the lower key, "b" the static one (−1: the
        keyless world); the normal points from b toward a; the point is the mean of
        the contact points on both surfaces (Y: side a's); depth is the deepest
        overlap; impulse the magnitude of the pair's total impulse this step.
        """
        cdef Py_ssize_t m = ints.shape[0], i, k, used = 0
        cdef Py_ssize_t ra, rb, t
        cdef int64_t ka, kb
        cdef bint sa, sb, swap
        cdef int points
        cdef double sign, d, deepest, x, z
        cdef const double *f
        cdef Contact *c
        cdef cnp.ndarray out, pairs
        cdef Contact *rows
        self._reserve(max(m, 1))
        rows = self.scratch
        with nogil:
            for i in range(m):
                points = <int>ints[i, 2]
                if points <= 0:  # separated, kept a few steps in pymunk's cache
                    continue
                ra = self.row(<uint64_t>ints[i, 0])
                rb = self.row(<uint64_t>ints[i, 1])
                ka = self.keys[ra] if ra < self.n else -1
                kb = self.keys[rb] if rb < self.n else -1
                sa = self.static[ra] if ra < self.n else True
                sb = self.static[rb] if rb < self.n else True
                swap = (sa and not sb) or (sa == sb and ka > kb)
                if swap:
                    ka, kb = kb, ka
                    t = ra
                    ra = rb
                    rb = t
                f = &floats[i, 0]
                c = &rows[used]
                self.scratch_a[used] = ra
                self.scratch_b[used] = rb
                used += 1
                c.a = ka
                c.b = kb
                x = 0.0
                z = 0.0
                deepest = 0.0
                for k in range(2 if points > 1 else 1):
                    x += f[4 + 5 * k] + f[6 + 5 * k]
                    z += f[5 + 5 * k] + f[7 + 5 * k]
                    d = f[8 + 5 * k]  # negative while overlapping
                    if -d > deepest:
                        deepest = -d
                c.point[0] = x / (2.0 * points)
                c.point[1] = self.y[ra] if ra < self.n else 0.0
                c.point[2] = z / (2.0 * points)
                # pymunk's normal points from its body a toward b; ours from b to a
                sign = 1.0 if swap else -1.0
                c.normal[0] = sign * f[2]
                c.normal[1] = 0.0
                c.normal[2] = sign * f[3]
                c.depth = deepest
                c.impulse = sqrt(f[0] * f[0] + f[1] * f[1])
        out = np.empty(used, self.contact_dtype)
        pairs = np.empty((used, 2), np.int64)
        with nogil:
            self._sort_into(used, <Contact *>cnp.PyArray_DATA(out),
                            <int64_t *>cnp.PyArray_DATA(pairs))
        return out, pairs

    def islands(self, const unsigned char[::1] moving, Py_ssize_t[::1] labels,
                const int64_t[:, ::1] joints) -> None:
        """Each row's island (``labels``: rows of one island share one): rows tied by
        the step's touching arbiters (:meth:`arbiters`) between ``moving`` rows, or by
        ``joints`` ((m, 2) rows; -1: the world, which ties nothing), through a union-find
        (static geometry, and any row not moving, ties nothing together)."""
        cdef Py_ssize_t i, ra, rb
        if (moving.shape[0] != self.n or labels.shape[0] != self.n
                or (joints.shape[0] and joints.shape[1] != 2)):
            raise ValueError("islands: arrays do not match the rows")
        self.arbiters()
        with nogil:
            _islands(self.n, <const int64_t *>cnp.PyArray_DATA(self._arbiter_ints),
                     <const Py_ssize_t *>cnp.PyArray_DATA(self._pairs), self.m,
                     &moving[0] if self.n else NULL, &labels[0] if self.n else NULL, False)
            for i in range(joints.shape[0]):
                ra = joints[i, 0]
                rb = joints[i, 1]
                if ra < 0 or rb < 0 or ra >= self.n or rb >= self.n:
                    continue
                if not moving[ra] or not moving[rb]:
                    continue
                ra = _root(&labels[0], ra)
                rb = _root(&labels[0], rb)
                if ra != rb:
                    labels[max(ra, rb)] = min(ra, rb)
            for i in range(self.n):
                labels[i] = _root(&labels[0], i)

    cdef void _sort_into(self, Py_ssize_t used, Contact *out, int64_t *pairs) noexcept nogil:
        """The scratch's ``used`` records into ``out`` in (key a, key b, place) order, and
        their rows (a, b; -1 for the keyless world) into ``pairs``.

        Rows follow keys, so a counting sort by side-a row orders by key a in two
        passes; each body's few rows are then put in order by insertion.
        """
        cdef Py_ssize_t i, j, r, begin, total = 0, count, other
        cdef Py_ssize_t *end = self.run_end
        cdef const Contact *rows = self.scratch
        cdef const Py_ssize_t *side = self.scratch_a
        cdef Py_ssize_t *partner = self.scratch_b  # side b's rows, reordered here
        cdef Contact moving
        for r in range(self.n + 1):
            end[r] = 0
        for i in range(used):
            end[side[i]] += 1
        for r in range(self.n + 1):  # end[r]: where row r's run starts, then where it ends
            count = end[r]
            end[r] = total
            total += count
        for i in range(used):
            r = side[i]
            out[end[r]] = rows[i]
            pairs[2 * end[r] + 1] = partner[i]
            end[r] += 1
        begin = 0
        for r in range(self.n + 1):
            for i in range(begin + 1, end[r]):
                moving = out[i]
                other = pairs[2 * i + 1]
                j = i
                while j > begin and _before(&moving, &out[j - 1]):
                    out[j] = out[j - 1]
                    pairs[2 * j + 1] = pairs[2 * j - 1]
                    j -= 1
                out[j] = moving
                pairs[2 * j + 1] = other
            for i in range(begin, end[r]):
                pairs[2 * i] = r if r < self.n else -1
                if pairs[2 * i + 1] >= self.n:
                    pairs[2 * i + 1] = -1
            begin = end[r]


# Long: one typed pass over the pose table into the plane (C locals)
def planar_poses(const double[:, ::1] table, const double[:, ::1] rest,
                 const double[:, ::1] cog, double[:, ::1] out,
                 unsigned char[::1] flags) -> int:
    """State rows (BodyState's layout) as pymunk takes them, the inverse of
    :meth:`Rows.table`: ``out[i]`` = x, z, θ, the centre of mass's vx, vz and ω, and y,
    for a body of rest tilt ``rest[i]`` and centre of mass ``cog[i]`` (its body frame).

    θ is the turn about Y of :func:`planar.split_orientation`, in the same operations (a
    pose set one by one or in a batch is the same pose to the bit); ``flags[i]`` gets
    RETILT where what is left of the orientation is not the body's rest tilt (only the
    turn about Y applies) and OFF_PLANE where a velocity leaves the plane (only its part
    in it applies). Returns how many rows are flagged, or -(i + 1) for row ``i``, the
    first that is not finite or whose orientation is zero (nothing after it is done).
    """
    cdef Py_ssize_t i, k, n = table.shape[0]
    cdef const double *row
    cdef const double *r
    cdef double *o
    cdef double w, x, y, z, norm, twist, tw, ty, c, s, ox, oz, omega, total
    cdef double rest0, rest1, rest2, rest3
    cdef int flagged = 0
    if not (table.shape[1] == 13 and rest.shape[0] == n and rest.shape[1] == 4
            and cog.shape[0] == n and cog.shape[1] == 2 and out.shape[0] == n
            and out.shape[1] == 7 and flags.shape[0] == n):
        raise ValueError("planar_poses: arrays do not match the rows")
    for i in range(n):
        row = &table[i, 0]
        total = 0.0
        for k in range(13):
            total += row[k]
        w, x, y, z = row[3], row[4], row[5], row[6]
        norm = sqrt(w * w + x * x + y * y + z * z)
        if not isfinite(total) or not isfinite(norm) or norm == 0.0:
            return -(i + 1)
        w, x, y, z = w / norm, x / norm, y / norm, z / norm
        twist = hypot(w, y)
        if twist < 1e-12:  # a half turn about a horizontal axis: no Y twist to speak of
            tw, ty = 1.0, 0.0
        else:
            tw, ty = w / twist, y / twist
        rest0 = tw * w + ty * y
        rest1 = tw * x - ty * z
        rest2 = tw * y - ty * w
        rest3 = tw * z + ty * x
        if rest0 < 0.0:
            rest0, rest1, rest2, rest3 = -rest0, -rest1, -rest2, -rest3
        r = &rest[i, 0]
        flags[i] = 0
        if (fabs(rest0 - r[0]) > TILT_TOLERANCE or fabs(rest1 - r[1]) > TILT_TOLERANCE
                or fabs(rest2 - r[2]) > TILT_TOLERANCE or fabs(rest3 - r[3]) > TILT_TOLERANCE):
            flags[i] |= RETILT
        if row[8] != 0.0 or row[10] != 0.0 or row[12] != 0.0:
            flags[i] |= OFF_PLANE
        if flags[i]:
            flagged += 1
        o = &out[i, 0]
        o[0] = row[0]
        o[1] = row[2]
        o[2] = -(2.0 * atan2(ty, tw))
        omega = -row[11]
        sincos(o[2], &s, &c)  # v_cog = v_origin + ω × (cog − origin)
        ox = c * cog[i, 0] - s * cog[i, 1]
        oz = s * cog[i, 0] + c * cog[i, 1]
        o[3] = row[7] - omega * oz
        o[4] = row[9] + omega * ox
        o[5] = omega
        o[6] = row[1]
    return flagged


cdef Py_ssize_t _gather(list parts, Contact *c, int64_t *rows, int64_t *sub) except -1:
    """The substeps' contacts and their rows one after another into ``c``, ``rows``, and
    each one's substep into ``sub``; how many."""
    cdef Py_ssize_t at = 0, k, i, size
    cdef cnp.ndarray records, pairs
    for k, (records, pairs) in enumerate(parts):
        size = cnp.PyArray_DIM(records, 0)
        if (records.dtype.itemsize != sizeof(Contact) or not cnp.PyArray_IS_C_CONTIGUOUS(records)
                or cnp.PyArray_SIZE(pairs) != 2 * size):
            raise ValueError("merge_substeps: a substep's contacts are not contact rows")
        memcpy(&c[at], cnp.PyArray_DATA(records), size * sizeof(Contact))
        memcpy(&rows[2 * at], _numbers(pairs, cnp.NPY_INT64, 2 * size, "rows"),
               2 * size * sizeof(int64_t))
        for i in range(at, at + size):
            sub[i] = k
        at += size
    return at


cdef Py_ssize_t _pairs_of(const int64_t *rows, Py_ssize_t m, Py_ssize_t *pair,
                          uint64_t *keys, Py_ssize_t *slots, uint64_t size) noexcept nogil:
    """Each contact's pair of rows (a, b) as an index (open addressing over ``size``
    slots); how many pairs."""
    cdef Py_ssize_t i, pairs = 0
    cdef uint64_t s, key
    for s in range(size):
        slots[s] = -1
    for i in range(m):
        key = (<uint64_t>(rows[2 * i] + 1) << 32) ^ <uint64_t>(rows[2 * i + 1] + 1)
        s = _mix(key) & (size - 1)
        while slots[s] != -1 and keys[s] != key:
            s = (s + 1) & (size - 1)
        if slots[s] == -1:
            keys[s] = key
            slots[s] = pairs
            pairs += 1
        pair[i] = slots[s]
    return pairs


# Long: one typed pass over the contact rows (C locals)
def merge_substeps(list parts, contact_dtype):
    """backend._merge_contacts' arithmetic in C, to the bit: a step's contacts from its
    substeps' (each: contact rows and their rows (a, b)), each pair with the points of
    its last substep and the pair's total impulse over its substeps (summed in the
    contacts' order, as numpy's bincount sums) times each point's share of what that
    substep gave the pair (equal shares where it gave none). Returns (contacts, rows)."""
    cdef Py_ssize_t m = sum(len(part[0]) for part in parts), cap = max(m, 1), i, p, kept = 0
    cdef uint64_t size = 16
    while size < 2 * <uint64_t>cap:
        size <<= 1
    cdef cnp.ndarray gathered = np.empty(cap, contact_dtype), rows = np.empty((cap, 2), np.int64)
    cdef cnp.ndarray ints = np.empty((3, cap), np.int64), slots = np.empty(2 * size, np.int64)
    cdef cnp.ndarray sums = np.zeros((4, cap))  # per pair: total, own (kept), count, last
    cdef Contact *c = <Contact *>cnp.PyArray_DATA(gathered)
    cdef int64_t *r = <int64_t *>cnp.PyArray_DATA(rows)
    cdef int64_t *sub = <int64_t *>cnp.PyArray_DATA(ints)
    cdef Py_ssize_t *pair = <Py_ssize_t *>(sub + cap)
    cdef unsigned char *keep = <unsigned char *>(sub + 2 * cap)
    cdef double *total = <double *>cnp.PyArray_DATA(sums)
    cdef double *own = total + cap
    cdef double *count = own + cap
    cdef double *last = count + cap
    _gather(parts, c, r, sub)
    with nogil:
        for p in range(_pairs_of(r, m, pair, <uint64_t *>cnp.PyArray_DATA(slots),
                                 <Py_ssize_t *>cnp.PyArray_DATA(slots) + size, size)):
            last[p] = -1.0
        for i in range(m):
            total[pair[i]] += c[i].impulse
            last[pair[i]] = max(last[pair[i]], <double>sub[i])
        for i in range(m):
            p = pair[i]
            keep[i] = sub[i] == last[p]
            if keep[i]:
                own[p] += c[i].impulse
                count[p] += 1.0
                kept += 1
    cdef cnp.ndarray out = np.empty(kept, contact_dtype), out_rows = np.empty((kept, 2), np.int64)
    cdef Contact *o = <Contact *>cnp.PyArray_DATA(out)
    cdef int64_t *orow = <int64_t *>cnp.PyArray_DATA(out_rows)
    kept = 0
    with nogil:
        for i in range(m):
            if keep[i]:
                p = pair[i]
                o[kept] = c[i]
                o[kept].impulse = total[p] * (c[i].impulse / own[p] if own[p] > 0.0
                                              else 1.0 / count[p])
                orow[2 * kept] = r[2 * i]
                orow[2 * kept + 1] = r[2 * i + 1]
                kept += 1
    return out, out_rows


# Long: one typed pass over the contact rows (C locals)
def carried_down(const int64_t[::1] rows_a, const int64_t[::1] rows_b,
                 const double[:] impulse, const double[::1] normal_up,
                 const double[::1] load, int rounds) -> cnp.ndarray:
    """resting.carried_down's pass in C (the same sums in the same order: what it
    returns is the same to the bit)."""
    cdef Py_ssize_t m = impulse.shape[0], n = load.shape[0], i, k, used = 0, r
    cdef double u
    cdef bint same
    cdef cnp.ndarray result = np.empty(m)
    cdef double[::1] out = result
    if rows_a.shape[0] != m or rows_b.shape[0] != m or normal_up.shape[0] != m:
        raise ValueError("carried_down: arrays do not match the contacts")
    cdef Py_ssize_t *which = <Py_ssize_t *>malloc(max(m, 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t *held = <Py_ssize_t *>malloc(max(m, 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t *under = <Py_ssize_t *>malloc(max(m, 1) * sizeof(Py_ssize_t))
    cdef double *share = <double *>malloc(max(m, 1) * sizeof(double))
    cdef double *total = <double *>malloc(max(n, 1) * sizeof(double))
    cdef double *carried = <double *>malloc(max(n, 1) * sizeof(double))
    cdef double *more = <double *>malloc(max(n, 1) * sizeof(double))
    cdef double *swap
    try:
        if (which == NULL or held == NULL or under == NULL or share == NULL or total == NULL
                or carried == NULL or more == NULL):
            raise MemoryError("out of memory carrying the preloads down")
        with nogil:
            for i in range(m):
                out[i] = impulse[i]
                u = impulse[i] * normal_up[i]
                if u == 0.0:
                    continue
                r = rows_a[i] if u > 0.0 else rows_b[i]  # the row this contact holds up
                if r < 0:
                    continue
                which[used] = i
                held[used] = r
                under[used] = rows_b[i] if u > 0.0 else rows_a[i]
                share[used] = fabs(u)
                used += 1
            for r in range(n):
                total[r] = 0.0
                carried[r] = load[r]
            for k in range(used):
                total[held[k]] += share[k]
            for k in range(used):
                share[k] = share[k] / total[held[k]]
            for _ in range(rounds):
                for r in range(n):
                    total[r] = 0.0
                for k in range(used):
                    if under[k] >= 0:
                        total[under[k]] += share[k] * carried[held[k]]
                same = True
                for r in range(n):
                    more[r] = load[r] + total[r]
                    if not more[r] == carried[r]:
                        same = False
                if same:
                    break
                swap = carried
                carried = more
                more = swap
            for k in range(used):
                i = which[k]
                out[i] += share[k] * carried[held[k]] / fabs(normal_up[i])
        return result
    finally:
        free(which)
        free(held)
        free(under)
        free(share)
        free(total)
        free(carried)
        free(more)


cdef extern from "policy.h" nogil:
    ctypedef struct RpStep:
        const double *solved
        double mu
        double friction
        double grip
        double weight
        double share
        int preloaded
        int still
    int rp_stand(const RpStep *s, double *held, unsigned char *slid, const double *down,
                 int dim, double keep, double beta, double *lifts)
    int rp_count(int steps, int rests)
    void rp_ramp(Py_ssize_t n, const int64_t *points, const unsigned char *chosen,
                 const Py_ssize_t *label, const unsigned char *moving,
                 const unsigned char *unrest, const double *weight, double *ramp,
                 double up, double down, unsigned char *blocked)
    double REST_SUPPORT, REST_SLIP, REST_SMOOTHING, REST_STILL_LINEAR, REST_STILL_ANGULAR
    double REST_BASE_MARGIN


cdef inline void *_numbers(cnp.ndarray a, int typenum, Py_ssize_t size,
                           str name) except NULL:
    """:func:`_data` for the per-step calls: the type checked by its number (a dtype
    compared in Python cost more than the pass over 100 rows)."""
    if a is None or cnp.PyArray_TYPE(a) != typenum:
        raise ValueError(f"{name}: expected a {'bool' if typenum == cnp.NPY_BOOL else 'float64'}"
                         f" array, got {None if a is None else a.dtype}")
    if not cnp.PyArray_IS_C_CONTIGUOUS(a) or cnp.PyArray_SIZE(a) != size:
        raise ValueError(f"{name}: expected {size} contiguous items, got {np.shape(a)}")
    return cnp.PyArray_DATA(a)


cdef inline double *_state_rows(cnp.ndarray out, Py_ssize_t n) except NULL:
    """``out``'s data: a contiguous float64 table of at least ``n`` state rows (13)."""
    if not (cnp.PyArray_NDIM(out) == 2 and cnp.PyArray_DIM(out, 0) >= n
            and cnp.PyArray_DIM(out, 1) == 13):
        raise ValueError("table: arrays do not match the rows")
    return <double *>_numbers(out, cnp.NPY_DOUBLE, cnp.PyArray_SIZE(out), "out")


cdef inline void *_data(cnp.ndarray a, object dtype, Py_ssize_t size, str name) except NULL:
    """``a``'s data, after checking it is a contiguous array of ``size`` ``dtype`` items."""
    if (a.dtype != dtype or not cnp.PyArray_IS_C_CONTIGUOUS(a)
            or cnp.PyArray_SIZE(a) != size):
        raise ValueError(f"{name}: expected {size} contiguous {np.dtype(dtype).name}, got "
                         f"{a.dtype} {np.shape(a)}")
    return cnp.PyArray_DATA(a)


cdef class Resting:
    """The resting warm start's per-row arrays (resting.RestingSupport's own, written in
    place), bound once per layout of rows, and its two passes per step: the preload
    before the step (:meth:`preload`) and everything after it (:meth:`after`: what each
    row's contacts did, its standing by policy.h's rp_stand, the rows chosen, their
    islands and the ramps), each one call over chipmunk (through the rows)."""

    cdef Py_ssize_t n
    cdef object _keep  # the arrays behind the pointers
    cdef double *mu
    cdef double *mass
    cdef double *cog
    cdef unsigned char *jointed
    cdef unsigned char *kinematic
    cdef unsigned char *dynamic
    cdef double *held
    cdef int8_t *steps
    cdef unsigned char *slid
    cdef unsigned char *kept
    cdef unsigned char *still
    cdef double *base
    cdef double *reach
    cdef double *ramp
    cdef double *applied
    cdef double *lifted
    cdef double *force
    cdef double *friction
    cdef double *grip
    cdef int64_t *points
    cdef unsigned char *tilted
    cdef unsigned char *chosen
    cdef unsigned char *unrest
    cdef unsigned char *moving
    cdef unsigned char *blocked
    cdef Py_ssize_t *labels
    cdef public bint found  # labels hold this step's islands
    cdef public Py_ssize_t held_still  # rows held still by the last step's pass

    def __init__(self, dict arrays) -> None:
        n = self.n = len(arrays["ramp"])
        self._keep = arrays
        f8, u1, i8, ip = np.float64, np.uint8, np.int64, np.intp
        self.mu = <double *>_data(arrays["mu"], f8, n, "mu")
        self.mass = <double *>_data(arrays["mass"], f8, n, "mass")
        self.cog = <double *>_data(arrays["cog"], f8, 2 * n, "cog")
        self.jointed = <unsigned char *>_data(arrays["jointed"], u1, n, "jointed")
        self.kinematic = <unsigned char *>_data(arrays["kinematic"], u1, n, "kinematic")
        self.dynamic = <unsigned char *>_data(arrays["dynamic"], u1, n, "dynamic")
        self.held = <double *>_data(arrays["held"], f8, 2 * n, "held")
        self.steps = <int8_t *>_data(arrays["steps"], np.int8, n, "steps")
        self.slid = <unsigned char *>_data(arrays["slid"], u1, n, "slid")
        self.kept = <unsigned char *>_data(arrays["kept"], u1, n, "kept")
        self.still = <unsigned char *>_data(arrays["still"], u1, n, "still")
        self.base = <double *>_data(arrays["base"], f8, 2 * n, "base")
        self.reach = <double *>_data(arrays["reach"], f8, 2 * n, "reach")
        self.ramp = <double *>_data(arrays["ramp"], f8, n, "ramp")
        self.applied = <double *>_data(arrays["applied"], f8, n, "applied")
        self.lifted = <double *>_data(arrays["lifted"], f8, n, "lifted")
        self.force = <double *>_data(arrays["force"], f8, 2 * n, "force")
        self.friction = <double *>_data(arrays["friction"], f8, n, "friction")
        self.grip = <double *>_data(arrays["grip"], f8, n, "grip")
        self.points = <int64_t *>_data(arrays["points"], i8, n, "points")
        self.tilted = <unsigned char *>_data(arrays["tilted"], u1, n, "tilted")
        self.chosen = <unsigned char *>_data(arrays["chosen"], u1, n, "chosen")
        self.unrest = <unsigned char *>_data(arrays["unrest"], u1, n, "unrest")
        self.moving = <unsigned char *>_data(arrays["moving"], u1, n, "moving")
        self.blocked = <unsigned char *>_data(arrays["blocked"], u1, n, "blocked")
        self.labels = <Py_ssize_t *>_data(arrays["labels"], ip, n, "labels")
        self.found = False
        self.held_still = 0

    def preload(self, Rows rows, double beta, double gx, double gz) -> int:
        """Before a step: each awake row whose ramp is on given ``beta`` × ramp of its
        weight upward on top of the force it has (chipmunk's own, read and written back
        for those rows alone); the share each row got into ``applied`` and the upward
        force (N) into ``lifted`` (0 elsewhere). How many rows were preloaded. The
        arithmetic is body.force − m·gravity with m = share · mass, as a one-by-one loop
        would set it; an asleep row gets none (a force would wake it)."""
        cdef Py_ssize_t r, count = 0
        cdef double share, mass, lift = sqrt(gx * gx + gz * gz)
        cdef void *b
        cdef cpVect f
        cdef bint direct
        if rows.n != self.n:
            raise ValueError("Resting.preload: the rows were planned for other bodies")
        rows._bound()
        with nogil:
            direct = rows.space != NULL and _idle_unread(rows.space)
            for r in range(self.n):
                self.applied[r] = 0.0
                self.lifted[r] = 0.0
                if not (self.ramp[r] > 0.0) or rows.static[r]:
                    continue
                b = rows.bodies[r]
                if cp.sleeping(b):
                    continue
                share = beta * self.ramp[r]
                mass = share * self.mass[r]
                f = cp.force(b)
                f.x = f.x - mass * gx
                f.y = f.y - mass * gz
                _awake_force(b, f, direct)
                self.applied[r] = share
                self.lifted[r] = mass * lift
                count += 1
        return count

    def after(self, Rows rows, double dt, double gx, double gz, double beta,
              double ramp_up) -> int:
        """Everything the resting warm start does after a step: the bodies read (right
        after the step: ``rows.read()``'s read, into the same arrays, which the step's
        state read and the sleep rule take too), what each row's contacts did (the
        step's arbiters, read by ``rows`` if they were not yet), each row's
        standing (policy.h's rp_stand), the rows that may be preloaded (at rest two
        steps, or preloaded and still held up; slower than REST_SLIP, four times that to
        stay; on a face or on level ground; not jointed or touching a kinematic body),
        the islands when some are, and every row's ramp (up by ``ramp_up`` where chosen,
        down by twice that elsewhere). A row held still (preloaded, on a face, slower
        than REST_STILL_*) has its velocity zeroed in that read and in chipmunk
        (``held_still`` counts them). How many rows have their ramp on for the next
        step."""
        cdef Py_ssize_t r, on = 0
        cdef double g_size = sqrt(gx * gx + gz * gz)
        cdef double down[2]
        cdef double keep = exp(-dt / REST_SMOOTHING)
        cdef int chosen = 0
        cdef const int64_t *arb
        cdef const Py_ssize_t *pairs
        cdef const double *fl
        self.held_still = 0
        if rows.n != self.n:
            raise ValueError("Resting.after: the rows were planned for other bodies")
        rows._bound()
        with nogil:
            rows._look(True)
        if g_size == 0.0:
            return 0
        rows._arbiters(True)
        arb = <const int64_t *>cnp.PyArray_DATA(rows._arbiter_ints)
        pairs = <const Py_ssize_t *>cnp.PyArray_DATA(rows._pairs)
        fl = <const double *>cnp.PyArray_DATA(rows._arbiter_floats)
        down[0] = gx / g_size
        down[1] = gz / g_size
        with nogil:
            self._support(rows, arb, pairs, fl, rows.m, dt, down)
            chosen = self._stand(rows.raw, rows.awake, down, keep, beta, g_size)
            self.found = chosen > 0
            if self.found:
                _islands(self.n, arb, pairs, rows.m, self.moving, self.labels)
            rp_ramp(self.n, self.points, self.chosen, self.labels if self.found else NULL,
                    self.moving, self.unrest, self.mass, self.ramp, ramp_up,
                    -2.0 * ramp_up, self.blocked)
            for r in range(self.n):
                on += self.ramp[r] > 0.0
            if self.held_still:
                rows._set_velocities(self.still)
        return on

    cdef void _support(self, Rows rows, const int64_t *arb, const Py_ssize_t *pairs,
                       const double *fl, Py_ssize_t m, double dt,
                       const double *down) noexcept nogil:
        """What each row's contacts did this step: their net force on it (x, z; N), the
        friction they made and the most they could (a pair's μ is the geometric mean),
        its contact points, whether a normal is off the vertical, the span across gravity
        of the points of the contacts it lies on (their normal, a to b, has it above:
        ``reach``); and which rows touch a kinematic body (unrest, as are the jointed)."""
        cdef Py_ssize_t i, r, k, n = self.n
        cdef Py_ssize_t ends[2]
        cdef double sign[2]
        cdef double jx, jz, nx, nz, along, slide, pair_mu
        cdef const double *f
        cdef int n_points
        cdef bint off
        sign[0] = 1.0
        sign[1] = -1.0
        for r in range(n):
            self.force[2 * r] = 0.0
            self.force[2 * r + 1] = 0.0
            self.friction[r] = 0.0
            self.grip[r] = 0.0
            self.points[r] = 0
            self.tilted[r] = 0
            self.unrest[r] = self.jointed[r]
            self.reach[2 * r] = INFINITY
            self.reach[2 * r + 1] = -INFINITY
        for i in range(m):
            n_points = <int>arb[_AI * i + 2]
            if n_points <= 0:
                continue
            ends[0] = pairs[2 * i]
            ends[1] = pairs[2 * i + 1]
            f = &fl[_AF * i]
            # pymunk's total impulse is what its body a received (b the opposite)
            jx, jz, nx, nz = f[0] / dt, f[1] / dt, f[2], f[3]
            along = jx * nx + jz * nz
            slide = sqrt(max(jx * jx + jz * jz - along * along, 0.0))
            off = fabs(nx * down[0] + nz * down[1]) < 1.0 - 1e-9
            pair_mu = 1.0
            for k in range(2):
                r = ends[k]
                pair_mu = pair_mu * (sqrt(self.mu[r]) if r < n else 1.0)
            for k in range(2):
                r = ends[k]
                if r >= n:
                    continue
                self.force[2 * r] += sign[k] * jx
                self.force[2 * r + 1] += sign[k] * jz
                self.friction[r] += slide
                self.grip[r] += pair_mu * fabs(along)
                self.points[r] += n_points
                self.tilted[r] |= off
                if sign[k] * (nx * down[0] + nz * down[1]) > 1e-6:  # r lies on it
                    _reach(&self.reach[2 * r], f, n_points, down)
                if ends[1 - k] < n and self.kinematic[ends[1 - k]]:
                    self.unrest[r] = 1

    cdef int _stand(self, double *body, const unsigned char *a, const double *down,
                    double keep, double beta, double g_size) noexcept nogil:
        """Each row's standing (rp_stand) and whether it is chosen; how many are."""
        cdef Py_ssize_t i
        cdef RpStep s
        cdef double up
        cdef double *p
        cdef int rests, stays, count = 0
        for i in range(self.n):
            self._hold(i, &body[_BF * i], a[i], down)
            s.solved = &self.force[2 * i]
            s.mu = self.mu[i]
            s.friction = self.friction[i]
            s.grip = self.grip[i]
            # asleep: neither rests nor stays (its contacts hold nothing this step)
            s.weight = self.mass[i] * g_size if a[i] else 0.0
            s.share = 1.0 - self.applied[i]
            s.preloaded = self.applied[i] > 0.0
            s.still = self.still[i]
            rests = rp_stand(&s, &self.held[2 * i], &self.slid[i], down, 2, keep, beta, &up)
            self.steps[i] = rp_count(self.steps[i], rests)
            stays = s.weight > 0.0 and up >= 0.5 * REST_SUPPORT * s.share * s.weight
            self.kept[i] = s.preloaded and stays
            p = &body[_BF * i]
            self.chosen[i] = ((self.steps[i] >= 2 or self.kept[i])
                              and _slower(p[3], p[4],
                                          4.0 * REST_SLIP if self.kept[i] else REST_SLIP)
                              and not self.unrest[i]
                              and (self.points[i] >= 2 or self.tilted[i] == 0))
            self.moving[i] = self.dynamic[i] and a[i]
            count += self.chosen[i]
        return count

    cdef inline void _hold(self, Py_ssize_t i, double *p, bint awake,
                           const double *down) noexcept nogil:
        """Hold row ``i`` still where it was preloaded this step, rests on a face in
        equilibrium (:meth:`_balanced`) and moves across gravity and turns slower than
        REST_STILL_*: its spin and its velocity across gravity are zeroed in its read
        ``p``, and its velocity along gravity too where the whole is that slow. What motion
        it has is the solver's residue. ODE's cs_hold_still in the plane, after the step
        (which is before the next): chipmunk's sequential impulses leave a stack rocking on
        its base for ten seconds and more, above the sleep rule's steady band."""
        cdef double along = p[3] * down[0] + p[4] * down[1]
        cdef double whole = p[3] * p[3] + p[4] * p[4]
        cdef bint hold = (awake and self.applied[i] > 0.0
                          and whole - along * along < REST_STILL_LINEAR * REST_STILL_LINEAR
                          and p[5] * p[5] < REST_STILL_ANGULAR * REST_STILL_ANGULAR
                          and self._balanced(i, p, down))
        self.still[i] = hold
        if hold:
            if whole < REST_STILL_LINEAR * REST_STILL_LINEAR:
                along = 0.0
            p[3] = along * down[0]
            p[4] = along * down[1]
            p[5] = 0.0
            self.held_still += 1

    cdef inline bint _balanced(self, Py_ssize_t i, const double *p,
                               const double *down) noexcept nogil:
        """Whether row ``i`` (read ``p``) stands in equilibrium on its base: the line of
        gravity through its centre of mass (its position plus its turned centre of
        gravity) falls within the base, REST_BASE_MARGIN of its width in from either end.
        Its base is the span across gravity of this step's points of the contacts it lies
        on where they are two apart (a face); else, held still last step and with two
        points on any side or level contacts only, the base it was held on (a crate of a
        stack loses for a step the corner that lifts by a hair)."""
        cdef double *base = &self.base[2 * i]
        cdef const double *reach = &self.reach[2 * i]
        cdef const double *g = &self.cog[2 * i]
        cdef double c, s, cx, cz, at, margin
        if reach[1] > reach[0]:
            base[0] = reach[0]
            base[1] = reach[1]
        elif not (self.still[i] and (self.points[i] >= 2 or not self.tilted[i])):
            return False
        if g[0] == 0.0 and g[1] == 0.0 and isfinite(p[2]):
            # the turned centre of gravity is zeros (c·0 − s·0): the position, to the
            # sign of a zero, which the comparisons below do not tell apart
            cx = p[0]
            cz = p[1]
        else:
            c = cos(p[2])
            s = sin(p[2])
            cx = p[0] + c * g[0] - s * g[1]
            cz = p[1] + s * g[0] + c * g[1]
        at = -cx * down[1] + cz * down[0]
        margin = REST_BASE_MARGIN * (base[1] - base[0])
        return base[0] + margin <= at <= base[1] - margin


cdef inline bint _slower(double x, double y, double limit) noexcept nogil:
    """Whether hypot(x, y) < limit, as computed, with hypot only near the limit (where
    x² + y², within a few ulps of the square of it, could tell otherwise)."""
    cdef double q = x * x + y * y
    if q < 0.81 * limit * limit:
        return True
    if q > 1.21 * limit * limit:
        return False
    return hypot(x, y) < limit


cdef inline void _reach(double *span, const double *f, int n_points,
                        const double *down) noexcept nogil:
    """Widen ``span`` (least, most) by the across-gravity place of an arbiter's contact
    points (``f``: its floats; each point the midpoint of the two shapes' own)."""
    cdef int j
    cdef const double *q
    cdef double at
    for j in range(min(n_points, 2)):
        q = &f[4 + 5 * j]  # POINT_A_j (x, z), POINT_B_j (x, z), DISTANCE_j
        at = -0.5 * (q[0] + q[2]) * down[1] + 0.5 * (q[1] + q[3]) * down[0]
        span[0] = min(span[0], at)
        span[1] = max(span[1], at)


cdef void _islands(Py_ssize_t n, const int64_t *arb, const Py_ssize_t *pairs, Py_ssize_t m,
                   const unsigned char *moving, Py_ssize_t *labels,
                   bint flat=True) noexcept nogil:
    """Each of ``n`` rows' island: rows tied by touching arbiters (``arb``, their rows
    ``pairs``; n: the keyless world) between ``moving`` rows (a union-find; static
    geometry and rows not moving tie nothing together). ``flat``: every label its root
    (otherwise the caller ties more and flattens)."""
    cdef Py_ssize_t i, r, ra, rb
    for r in range(n):
        labels[r] = r
    for i in range(m):
        if arb[_AI * i + 2] <= 0:
            continue
        ra = pairs[2 * i]
        rb = pairs[2 * i + 1]
        if ra >= n or rb >= n or not moving[ra] or not moving[rb]:
            continue
        ra = _root(labels, ra)
        rb = _root(labels, rb)
        if ra != rb:
            labels[max(ra, rb)] = min(ra, rb)
    if flat:
        for r in range(n):
            labels[r] = _root(labels, r)
