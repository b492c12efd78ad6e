# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True
"""The per-step copy of a pymunk space into engine arrays, as C loops.

After every step the engine reads each body's pose and velocity, and the
contacts, into numpy tables. Right after a step the CPU caches hold the solver's
data, so every Python or numpy call costs microseconds whatever its size; done
with numpy the copy took a dozen of them, a tenth of the step at a few hundred
bodies. Here one call walks the bodies, and one the arbiters, calling chipmunk's
getters through the addresses pymunk's own cffi module exports (no second copy
of chipmunk, no headers), and writes the rows in their final layout.

A :class:`SpaceSync` is planned for a fixed list of bodies (the backend makes a
new one when bodies come or go). It holds raw pointers: the caller keeps the
pymunk space and bodies alive while it is in use.
"""

cimport numpy as cnp
from libc.math cimport cos, isfinite, sin, sqrt
from libc.stdint cimport int64_t, uint64_t, uintptr_t
from libc.stdlib cimport free, malloc, realloc

import numpy as np

cnp.import_array()

cdef struct cpVect:
    double x
    double y

ctypedef cpVect (*BodyVect)(void *) noexcept nogil
ctypedef double (*BodyReal)(void *) noexcept nogil
ctypedef int (*ArbCount)(void *) noexcept nogil
ctypedef void (*ArbBodies)(void *, void **, void **) noexcept nogil
ctypedef cpVect (*ArbVect)(void *) noexcept nogil
ctypedef cpVect (*ArbPoint)(void *, int) noexcept nogil
ctypedef double (*ArbDepth)(void *, int) noexcept nogil
ctypedef void (*ArbiterFunc)(void *, void *) noexcept nogil
ctypedef void (*EachArbiter)(void *, ArbiterFunc, void *) noexcept nogil

#: chipmunk functions whose addresses :class:`SpaceSync` needs, in this order.
FUNCTIONS = ("cpBodyGetPosition", "cpBodyGetAngle", "cpBodyGetVelocity",
             "cpBodyGetAngularVelocity", "cpSpaceEachCachedArbiter", "cpArbiterGetCount",
             "cpArbiterGetBodies", "cpArbiterTotalImpulse", "cpArbiterGetNormal",
             "cpArbiterGetPointA", "cpArbiterGetPointB", "cpArbiterGetDepth")

#: Keys in [−1, this) pack two to an int64 sort key.
cdef int64_t _KEY_LIMIT = (<int64_t>1) << 31


cdef struct Contact:
    # laid out as CONTACT_DTYPE: a, b, position (3), normal (3), depth, impulse
    int64_t a
    int64_t b
    double point[3]
    double normal[3]
    double depth
    double impulse


cdef struct Arbiters:
    # what the arbiter walk needs, passed through chipmunk's void* data
    ArbCount count
    ArbBodies bodies
    ArbVect impulse
    ArbVect normal
    ArbPoint point_a
    ArbPoint point_b
    ArbDepth depth
    const uintptr_t *slot_body
    const Py_ssize_t *slot_row
    uint64_t mask
    Py_ssize_t n
    const int64_t *keys_ext
    const unsigned char *static_ext
    const double *y_ext
    Contact *rows
    Py_ssize_t *row_a  # each collected row's side-a body row, for the sort
    Py_ssize_t used
    Py_ssize_t capacity
    bint failed


cdef inline uint64_t _mix(uint64_t h) noexcept nogil:
    """splitmix64's finaliser: pointers share their low bits, so spread every bit."""
    h = (h ^ (h >> 30)) * <uint64_t>0xBF58476D1CE4E5B9
    h = (h ^ (h >> 27)) * <uint64_t>0x94D049BB133111EB
    return h ^ (h >> 31)


cdef inline Py_ssize_t _row(const Arbiters *s, uintptr_t body) noexcept nogil:
    """A body's row; ``n`` (the keyless world's row) when it is not one of ours."""
    cdef uint64_t i = _mix(body) & s.mask
    while s.slot_row[i] != -1:
        if s.slot_body[i] == body:
            return s.slot_row[i]
        i = (i + 1) & s.mask
    return s.n


cdef void _collect(void *arb, void *data) noexcept nogil:
    """One touching arbiter → one Contact row (see :meth:`SpaceSync.contacts`)."""
    cdef Arbiters *s = <Arbiters *>data
    cdef int count = s.count(arb), i
    if count <= 0 or s.failed:  # 0: separated, kept for a few steps in the cache
        return
    cdef Contact *grown
    cdef Py_ssize_t *grown_rows
    if s.used == s.capacity:
        s.capacity = 2 * s.capacity + 64
        grown = <Contact *>realloc(s.rows, s.capacity * sizeof(Contact))
        if grown != NULL:
            s.rows = grown
        grown_rows = <Py_ssize_t *>realloc(s.row_a, s.capacity * sizeof(Py_ssize_t))
        if grown_rows != NULL:
            s.row_a = grown_rows
        if grown == NULL or grown_rows == NULL:
            s.failed = True
            return
    cdef void *body_a
    cdef void *body_b
    s.bodies(arb, &body_a, &body_b)
    cdef Py_ssize_t ra = _row(s, <uintptr_t>body_a), rb = _row(s, <uintptr_t>body_b), t
    cdef int64_t ka = s.keys_ext[ra], kb = s.keys_ext[rb]
    cdef bint sa = s.static_ext[ra], sb = s.static_ext[rb]
    # side a is the moving body, or the lower key; b the static one (−1: the world)
    cdef bint swap = (sa and not sb) or (sa == sb and ka > kb)
    if swap:
        ka, kb = kb, ka
        t = ra
        ra = rb
        rb = t
    cdef Contact *c = &s.rows[s.used]
    s.row_a[s.used] = ra
    s.used += 1
    c.a = ka
    c.b = kb
    cdef cpVect p, q, v
    cdef double x = 0.0, z = 0.0, deepest = 0.0, d
    for i in range(count):  # the mean of the contact points on both surfaces
        p = s.point_a(arb, i)
        q = s.point_b(arb, i)
        x += p.x + q.x
        z += p.y + q.y
        d = s.depth(arb, i)  # negative while overlapping
        if -d > deepest:
            deepest = -d
    c.point[0] = x / (2.0 * count)
    c.point[1] = s.y_ext[ra]
    c.point[2] = z / (2.0 * count)
    # chipmunk's normal points from its body a toward b; ours from b toward a
    v = s.normal(arb)
    d = 1.0 if swap else -1.0
    c.normal[0] = d * v.x
    c.normal[1] = 0.0
    c.normal[2] = d * v.y
    c.depth = deepest
    v = s.impulse(arb)
    c.impulse = sqrt(v.x * v.x + v.y * v.y)


cdef inline bint _before(const Contact *a, const Contact *b) noexcept nogil:
    """Within one side-a body: by key b, then x, z and impulse (a pair may touch twice)."""
    if a.b != b.b:
        return a.b < b.b
    if a.point[0] != b.point[0]:
        return a.point[0] < b.point[0]
    if a.point[2] != b.point[2]:
        return a.point[2] < b.point[2]
    return a.impulse < b.impulse


cdef void _sort_into(const Arbiters *s, Contact *out, Py_ssize_t *end) noexcept nogil:
    """The collected rows into ``out`` in (key a, key b, place) order.

    Rows follow keys, so a counting sort by side-a row orders by key a in two
    passes; each body's few rows are then put in order by insertion. ``end``
    has room for n + 1 counters.
    """
    cdef Py_ssize_t i, j, r, begin, total = 0, count
    cdef Contact moving
    for r in range(s.n + 1):
        end[r] = 0
    for i in range(s.used):
        end[s.row_a[i]] += 1
    for r in range(s.n + 1):  # end[r]: where row r's run starts, then where it ends
        count = end[r]
        end[r] = total
        total += count
    for i in range(s.used):
        r = s.row_a[i]
        out[end[r]] = s.rows[i]
        end[r] += 1
    begin = 0
    for r in range(s.n + 1):
        for i in range(begin + 1, end[r]):
            moving = out[i]
            j = i
            while j > begin and _before(&moving, &out[j - 1]):
                out[j] = out[j - 1]
                j -= 1
            out[j] = moving
        begin = end[r]


cdef class SpaceSync:
    """Reads one space's bodies (row ``i`` is ``bodies[i]``, a ``cpBody*``) and contacts.

    ``y_ext`` holds each row's Y (kept as authored) then 0.0 for the keyless world;
    the backend writes it in place. ``rest`` (n, 4) is each body's fixed tilt,
    applied after the turn about Y; ``cog`` (n, 2) its centre of mass in the body
    frame, whose velocity pymunk keeps (ours is the origin's). ``keys_ext`` and
    ``static_ext`` (n + 1) give each row's key and whether it is static, the last
    row standing for bodies that are not ours (−1, static); rows must be in
    increasing key order (the contacts are sorted by row).
    """

    cdef BodyVect _position, _velocity
    cdef BodyReal _angle, _angular_velocity
    cdef EachArbiter _each_arbiter
    cdef uintptr_t _space
    cdef uintptr_t *_bodies
    cdef Py_ssize_t *_run_end
    cdef Arbiters _arbiters
    cdef bint _any_rest, _any_cog
    cdef object _contact_dtype
    # the arrays behind the raw pointers below, kept alive
    cdef cnp.ndarray _y_ext, _rest, _cog, _keys_ext, _static_ext
    cdef const double *_y
    cdef const double *_rest_p
    cdef const double *_cog_p

    def __cinit__(self) -> None:
        self._bodies = NULL
        self._run_end = NULL
        self._arbiters.slot_body = NULL
        self._arbiters.slot_row = NULL
        self._arbiters.rows = NULL
        self._arbiters.row_a = NULL

    def __init__(self, functions, uintptr_t space, bodies, cnp.ndarray y_ext,
                 cnp.ndarray rest, cnp.ndarray cog, cnp.ndarray keys_ext,
                 cnp.ndarray static_ext, contact_dtype) -> None:
        cdef Py_ssize_t i, n = len(bodies)
        cdef uint64_t size = 16, s
        cdef Arbiters *a = &self._arbiters
        cdef uintptr_t f[12]
        if len(functions) != 12:
            raise ValueError("SpaceSync needs the 12 addresses named in FUNCTIONS")
        for i in range(12):
            f[i] = functions[i]
        self._position = <BodyVect>f[0]
        self._angle = <BodyReal>f[1]
        self._velocity = <BodyVect>f[2]
        self._angular_velocity = <BodyReal>f[3]
        self._each_arbiter = <EachArbiter>f[4]
        a.count = <ArbCount>f[5]
        a.bodies = <ArbBodies>f[6]
        a.impulse = <ArbVect>f[7]
        a.normal = <ArbVect>f[8]
        a.point_a = <ArbPoint>f[9]
        a.point_b = <ArbPoint>f[10]
        a.depth = <ArbDepth>f[11]
        self._space = space
        self._contact_dtype = contact_dtype
        if np.dtype(contact_dtype).itemsize != sizeof(Contact):
            raise ValueError("contact dtype does not match the Contact record")
        if not (len(y_ext) == len(keys_ext) == len(static_ext) == n + 1
                and rest.shape[0] == cog.shape[0] == n):
            raise ValueError("SpaceSync: arrays do not match the bodies")
        if n > 1 and not np.all(np.diff(keys_ext[:n]) > 0):
            raise ValueError("SpaceSync: rows must be in increasing key order")
        self._y_ext = np.ascontiguousarray(y_ext, np.float64)
        if self._y_ext is not y_ext:
            raise ValueError("y_ext must be a contiguous float64 array (it is written in place)")
        self._rest = np.ascontiguousarray(rest, np.float64)
        self._cog = np.ascontiguousarray(cog, np.float64)
        self._keys_ext = np.ascontiguousarray(keys_ext, np.int64)
        self._static_ext = np.ascontiguousarray(static_ext, np.uint8)
        self._y = <const double *>cnp.PyArray_DATA(self._y_ext)
        self._rest_p = <const double *>cnp.PyArray_DATA(self._rest)
        self._cog_p = <const double *>cnp.PyArray_DATA(self._cog)
        self._any_rest = bool(n) and not np.all(self._rest[:, 0] == 1.0)
        self._any_cog = bool(np.any(self._cog))
        self._bodies = <uintptr_t *>malloc(max(n, 1) * sizeof(uintptr_t))
        self._run_end = <Py_ssize_t *>malloc((n + 1) * sizeof(Py_ssize_t))
        if self._bodies == NULL or self._run_end == NULL:
            raise MemoryError
        for i in range(n):
            self._bodies[i] = <uintptr_t>bodies[i]
        # body pointer → row: open addressing with linear probing, at most a quarter full
        while size < 4 * <uint64_t>n:
            size <<= 1
        a.mask = size - 1
        a.slot_body = <uintptr_t *>malloc(size * sizeof(uintptr_t))
        a.slot_row = <Py_ssize_t *>malloc(size * sizeof(Py_ssize_t))
        if a.slot_body == NULL or a.slot_row == NULL:
            raise MemoryError
        cdef uintptr_t *slot_body = <uintptr_t *>a.slot_body
        cdef Py_ssize_t *slot_row = <Py_ssize_t *>a.slot_row
        for s in range(size):
            slot_row[s] = -1
        for i in range(n):
            s = _mix(self._bodies[i]) & a.mask
            while slot_row[s] != -1:
                s = (s + 1) & a.mask
            slot_body[s] = self._bodies[i]
            slot_row[s] = i
        a.n = n
        a.keys_ext = <const int64_t *>cnp.PyArray_DATA(self._keys_ext)
        a.static_ext = <const unsigned char *>cnp.PyArray_DATA(self._static_ext)
        a.y_ext = self._y
        a.capacity = 0
        a.used = 0

    def __dealloc__(self) -> None:
        free(self._bodies)
        free(self._run_end)
        free(self._arbiters.row_a)
        free(<void *>self._arbiters.slot_body)
        free(<void *>self._arbiters.slot_row)
        free(self._arbiters.rows)

    def read(self):
        """A fresh (n, 13) table of every body's state (BodyState's layout), and whether
        it is all finite.

        Row ``i``: x Y z (Y as authored), the turn θ about pymunk's axis as a quaternion
        about −Y (pymunk turns X toward Z; a right-handed turn about +Y turns Z toward
        X), the origin's linear velocity, then the angular velocity (0, −ω, 0).
        """
        cdef Py_ssize_t i, n = self._arbiters.n
        cdef cnp.npy_intp dims[2]
        dims[0] = n
        dims[1] = 13
        table = cnp.PyArray_EMPTY(2, dims, cnp.NPY_DOUBLE, 0)
        cdef double *row = <double *>cnp.PyArray_DATA(table)
        cdef const double *r
        cdef const double *g
        cdef cpVect pos, vel
        cdef double theta, omega, c, s, ox, oz, total = 0.0
        cdef void *body
        with nogil:
            for i in range(n):
                body = <void *>self._bodies[i]
                pos = self._position(body)
                theta = self._angle(body)
                vel = self._velocity(body)
                omega = self._angular_velocity(body)
                total += pos.x + pos.y + theta + vel.x + vel.y + omega
                row[0] = pos.x
                row[1] = self._y[i]
                row[2] = pos.y
                c = cos(-0.5 * theta)
                s = sin(-0.5 * theta)
                if self._any_rest:  # (c, 0, s, 0) ⊗ rest
                    r = &self._rest_p[4 * i]
                    row[3] = c * r[0] - s * r[2]
                    row[4] = c * r[1] + s * r[3]
                    row[5] = c * r[2] + s * r[0]
                    row[6] = c * r[3] - s * r[1]
                else:
                    row[3] = c
                    row[4] = 0.0
                    row[5] = s
                    row[6] = 0.0
                if self._any_cog:  # v_origin = v_cog + ω × (origin − cog)
                    g = &self._cog_p[2 * i]
                    c = cos(theta)
                    s = sin(theta)
                    ox = c * g[0] - s * g[1]
                    oz = s * g[0] + c * g[1]
                    row[7] = vel.x + omega * oz
                    row[9] = vel.y - omega * ox
                else:
                    row[7] = vel.x
                    row[9] = vel.y
                row[8] = 0.0
                row[10] = 0.0
                row[11] = -omega
                row[12] = 0.0
                row += 13
        return table, bool(isfinite(total))

    def contacts(self):
        """One CONTACT_DTYPE row per touching shape pair, sorted by keys then place.

        Side "a" is the moving body or the lower key, "b" the static one (−1: the
        keyless world); the normal points from b toward a; the point is the mean of
        the contact points on both surfaces (Y: side a's); depth is the deepest
        overlap; impulse the magnitude of the pair's total impulse this step.
        """
        cdef Arbiters *a = &self._arbiters
        a.used = 0
        a.failed = False
        with nogil:
            self._each_arbiter(<void *>self._space, _collect, a)
        if a.failed:
            raise MemoryError("out of memory collecting contacts")
        out = np.empty(a.used, self._contact_dtype)
        with nogil:
            _sort_into(a, <Contact *>cnp.PyArray_DATA(<cnp.ndarray>out), self._run_end)
        return out
