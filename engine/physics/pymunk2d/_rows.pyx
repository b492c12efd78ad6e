# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""pymunk.batch buffers into engine rows, as C loops.

``pymunk.batch`` (pymunk's public batch API) hands every body's and every arbiter's
numbers over in one buffer each, in chipmunk's order. Turning them into our rows
(the state table; sorted contact records) with numpy costs a few dozen array
operations of a microsecond or more each, which at a few hundred bodies is a tenth
of a step; here each is one pass. Nothing here touches pymunk or chipmunk: the
inputs are plain arrays.

A :class:`Rows` is planned for a fixed list of bodies, identified by their pymunk
``Body.id`` (the backend plans a new one when bodies come or go).
"""

cimport numpy as cnp
from libc.math cimport fabs, isfinite, sqrt
from libc.stdint cimport int64_t, uint64_t
from libc.stdlib cimport free, malloc
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


cdef struct Contact:
    # laid out as CONTACT_DTYPE: a, b, position (3), normal (3), depth, impulse
    int64_t a
    int64_t b
    double point[3]
    double normal[3]
    double depth
    double impulse


cdef inline uint64_t _mix(uint64_t h) noexcept nogil:
    """splitmix64's finaliser: ids share their low bits, so spread every bit."""
    h = (h ^ (h >> 30)) * <uint64_t>0xBF58476D1CE4E5B9
    h = (h ^ (h >> 27)) * <uint64_t>0x94D049BB133111EB
    return h ^ (h >> 31)


cdef inline bint _before(const Contact *a, const Contact *b) noexcept nogil:
    """Within one side-a body: by key b, then x, z and impulse (a pair may touch twice)."""
    if a.b != b.b:
        return a.b < b.b
    if a.point[0] != b.point[0]:
        return a.point[0] < b.point[0]
    if a.point[2] != b.point[2]:
        return a.point[2] < b.point[2]
    return a.impulse < b.impulse


cdef class Rows:
    """Rows of one list of bodies (row ``i`` is the body with ``ids[i]``), keys in
    increasing order.

    ``y`` holds each row's Y (kept as authored; the backend writes it in place),
    ``rest`` (n, 4) each body's fixed tilt, applied after the turn about Y, ``cog``
    (n, 2) its centre of mass in the body frame (pymunk keeps that point's velocity;
    ours is the origin's), ``static`` whether each row is a static body.
    """

    cdef Py_ssize_t n
    cdef uint64_t mask
    cdef uint64_t *slot_id
    cdef Py_ssize_t *slot_row
    cdef Py_ssize_t *run_end
    cdef bint any_rest, any_cog
    cdef object contact_dtype
    # the arrays behind the raw pointers below, kept alive
    cdef cnp.ndarray _keys, _static, _y, _rest, _cog
    cdef const int64_t *keys
    cdef const unsigned char *static
    cdef const double *y
    cdef const double *rest
    cdef const double *cog

    def __cinit__(self) -> None:
        self.slot_id = NULL
        self.slot_row = NULL
        self.run_end = NULL

    def __init__(self, ids, keys, static, y, rest, cog, contact_dtype) -> None:
        cdef Py_ssize_t i, n = len(ids)
        cdef uint64_t size = 16, s
        if np.dtype(contact_dtype).itemsize != sizeof(Contact):
            raise ValueError("contact dtype does not match the Contact record")
        if not (len(keys) == len(static) == len(y) == len(rest) == len(cog) == n):
            raise ValueError("Rows: arrays do not match the bodies")
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
        # id -> row: open addressing with linear probing, at most a quarter full
        while size < 4 * <uint64_t>n:
            size <<= 1
        self.mask = size - 1
        self.slot_id = <uint64_t *>malloc(size * sizeof(uint64_t))
        self.slot_row = <Py_ssize_t *>malloc(size * sizeof(Py_ssize_t))
        self.run_end = <Py_ssize_t *>malloc((n + 1) * sizeof(Py_ssize_t))
        if self.slot_id == NULL or self.slot_row == NULL or self.run_end == NULL:
            raise MemoryError
        for s in range(size):
            self.slot_row[s] = -1
        for i in range(n):
            s = _mix(<uint64_t>ids[i]) & self.mask
            while self.slot_row[s] != -1:
                s = (s + 1) & self.mask
            self.slot_id[s] = <uint64_t>ids[i]
            self.slot_row[s] = i

    def __dealloc__(self) -> None:
        free(self.slot_id)
        free(self.slot_row)
        free(self.run_end)

    cdef inline Py_ssize_t row(self, uint64_t body_id) noexcept nogil:
        """A body's row; ``n`` (the keyless world) when it is not one of ours."""
        cdef uint64_t s = _mix(body_id) & self.mask
        while self.slot_row[s] != -1:
            if self.slot_id[s] == body_id:
                return self.slot_row[s]
            s = (s + 1) & self.mask
        return self.n

    def order(self, const int64_t[::1] ids, Py_ssize_t[::1] gather) -> int:
        """Where each row sits in pymunk's list ``ids`` (into ``gather``); how many of
        the listed bodies are not ours."""
        cdef Py_ssize_t i, r, others = 0
        for i in range(ids.shape[0]):
            r = self.row(<uint64_t>ids[i])
            if r == self.n:
                others += 1
            else:
                gather[r] = i
        return others

    def table(self, const double[:, ::1] raw, const Py_ssize_t[::1] gather,
              double[:, ::1] out, double[:, ::1] keep) -> bool:
        """Rows of ``raw`` (pymunk's list: x, z, θ, vx, vz, ω) into state rows in ``out``
        (BodyState's layout), and as they are into ``keep`` (n, 6) in row order; whether
        all of them were finite.

        The turn θ about pymunk's axis is a quaternion about −Y (pymunk turns X toward Z;
        a right-handed turn about +Y turns Z toward X), the rest tilt after it; the
        velocity is the origin's; the angular velocity is (0, −ω, 0).
        """
        cdef Py_ssize_t i
        cdef const double *p
        cdef const double *r
        cdef const double *g
        cdef double *row
        cdef double c, s, ox, oz, total = 0.0
        with nogil:
            for i in range(self.n):
                p = &raw[gather[i], 0]
                row = &out[i, 0]
                memcpy(&keep[i, 0], p, 6 * sizeof(double))
                total += p[0] + p[1] + p[2] + p[3] + p[4] + p[5]
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
        return bool(isfinite(total))

    def motion(self, const double[:, ::1] raw, const Py_ssize_t[::1] gather,
               double[:, ::1] velocity) -> None:
        """Centre-of-mass velocities as the sleep rule keeps them: columns of (6, n),
        (vx, 0, vz) then (0, −ω, 0)."""
        cdef Py_ssize_t i
        cdef const double *p
        with nogil:
            for i in range(self.n):
                p = &raw[gather[i], 0]
                velocity[0, i] = p[3]
                velocity[1, i] = 0.0
                velocity[2, i] = p[4]
                velocity[3, i] = 0.0
                velocity[4, i] = -p[5]
                velocity[5, i] = 0.0

    def contacts(self, const int64_t[:, ::1] ints, const double[:, ::1] floats):
        """One CONTACT_DTYPE row per touching arbiter, sorted by keys then place.

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
        cdef Contact *sorted_rows
        cdef cnp.ndarray out
        cdef Contact *rows = <Contact *>malloc(max(m, 1) * sizeof(Contact))
        cdef Py_ssize_t *side = <Py_ssize_t *>malloc(max(m, 1) * sizeof(Py_ssize_t))
        if rows == NULL or side == NULL:
            free(rows)
            free(side)
            raise MemoryError("out of memory collecting contacts")
        try:
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
                    side[used] = ra
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
            sorted_rows = <Contact *>cnp.PyArray_DATA(out)
            with nogil:
                self._sort_into(rows, side, used, sorted_rows)
            return out
        finally:
            free(rows)
            free(side)

    def support(self, const int64_t[:, ::1] ints, const double[:, ::1] floats,
                const double[::1] mu, double dt, double down_x, double down_z,
                double[:, ::1] force, double[::1] friction, double[::1] grip,
                int64_t[::1] points, unsigned char[::1] tilted) -> None:
        """What each row's contacts did this step, for the resting warm start (see the
        backend's RestingSupport): their net force on it (x, z; N) into ``force``, the
        friction they made and the most they could (``mu`` per row; a pair's is the
        geometric mean) summed into ``friction`` and ``grip``, its contact points, and
        whether one of its contact normals is off the vertical (``down``). Every output is
        overwritten."""
        cdef Py_ssize_t m = ints.shape[0], i, r, k
        cdef Py_ssize_t ends[2]
        cdef double sign[2]
        cdef double jx, jz, nx, nz, along, slide, pair_mu
        cdef const double *f
        cdef int n_points
        cdef bint off
        with nogil:
            for r in range(self.n):
                force[r, 0] = 0.0
                force[r, 1] = 0.0
                friction[r] = 0.0
                grip[r] = 0.0
                points[r] = 0
                tilted[r] = 0
            for i in range(m):
                n_points = <int>ints[i, 2]
                if n_points <= 0:
                    continue
                ends[0] = self.row(<uint64_t>ints[i, 0])
                ends[1] = self.row(<uint64_t>ints[i, 1])
                f = &floats[i, 0]
                # pymunk's total impulse is what its body a received (b the opposite)
                jx, jz, nx, nz = f[0] / dt, f[1] / dt, f[2], f[3]
                along = jx * nx + jz * nz
                slide = sqrt(max(jx * jx + jz * jz - along * along, 0.0))
                off = fabs(nx * down_x + nz * down_z) < 1.0 - 1e-9
                pair_mu = 1.0
                sign[0] = 1.0
                sign[1] = -1.0
                for k in range(2):
                    r = ends[k]
                    pair_mu = pair_mu * (sqrt(mu[r]) if r < self.n else 1.0)
                for k in range(2):
                    r = ends[k]
                    if r >= self.n:
                        continue
                    force[r, 0] += sign[k] * jx
                    force[r, 1] += sign[k] * jz
                    friction[r] += slide
                    grip[r] += pair_mu * fabs(along)
                    points[r] += n_points
                    tilted[r] |= off

    cdef void _sort_into(self, const Contact *rows, const Py_ssize_t *side, Py_ssize_t used,
                         Contact *out) noexcept nogil:
        """``rows`` into ``out`` in (key a, key b, place) order.

        Rows follow keys, so a counting sort by side-a row orders by key a in two
        passes; each body's few rows are then put in order by insertion.
        """
        cdef Py_ssize_t i, j, r, begin, total = 0, count
        cdef Py_ssize_t *end = self.run_end
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
            end[r] += 1
        begin = 0
        for r in range(self.n + 1):
            for i in range(begin + 1, end[r]):
                moving = out[i]
                j = i
                while j > begin and _before(&moving, &out[j - 1]):
                    out[j] = out[j - 1]
                    j -= 1
                out[j] = moving
            begin = end[r]
