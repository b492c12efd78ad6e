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
from libc.math cimport atan2, fabs, hypot, isfinite, sqrt
from libc.stdint cimport int8_t, int64_t, uint64_t
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


cdef inline Py_ssize_t _root(Py_ssize_t *parent, Py_ssize_t r) noexcept nogil:
    """Union-find: ``r``'s root, halving the path on the way."""
    while parent[r] != r:
        parent[r] = parent[parent[r]]
        r = parent[r]
    return r


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

    def __cinit__(self) -> None:
        self.slot_id = NULL
        self.slot_row = NULL
        self.run_end = NULL
        self.scratch = NULL
        self.scratch_a = NULL
        self.scratch_b = NULL
        self.scratch_size = 0

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

    def islands(self, const int64_t[:, ::1] ints, const unsigned char[::1] moving,
                Py_ssize_t[::1] labels) -> None:
        """Each row's island (``labels``: rows of one island share one): rows tied by
        touching arbiters between ``moving`` rows, through a union-find over the
        arbiters (static geometry, and any row not moving, ties nothing together)."""
        cdef Py_ssize_t m = ints.shape[0], i, r, ra, rb
        if moving.shape[0] != self.n or labels.shape[0] != self.n or (m and ints.shape[1] < 3):
            raise ValueError("islands: arrays do not match the rows")
        with nogil:
            for r in range(self.n):
                labels[r] = r
            for i in range(m):
                if ints[i, 2] <= 0:
                    continue
                ra = self.row(<uint64_t>ints[i, 0])
                rb = self.row(<uint64_t>ints[i, 1])
                if ra >= self.n or rb >= self.n or not moving[ra] or not moving[rb]:
                    continue
                ra = _root(&labels[0], ra)
                rb = _root(&labels[0], rb)
                if ra != rb:
                    labels[max(ra, rb)] = min(ra, rb)
            for r in range(self.n):
                labels[r] = _root(&labels[0], r)

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


def preload(const double[:, ::1] forces, const Py_ssize_t[::1] gather,
            const Py_ssize_t[::1] rows, const double[::1] share, const double[::1] mass,
            const unsigned char[::1] awake, double gx, double gz, double g,
            double[:, ::1] out, double[::1] applied, double[::1] lifted) -> int:
    """The forces with the resting preloads added: ``forces`` (pymunk's list, as read)
    into ``out``, and each awake one of ``rows`` (row ``r`` at ``gather[r]``) given
    ``share[r]`` of its weight upward (``mass`` kg under gravity (gx, gz), of size
    ``g``); the share each got into ``applied`` and the upward force (N) into
    ``lifted`` (both zero elsewhere, as given). How many rows were preloaded.

    The arithmetic is the backend's one-by-one loop's (body.force − m·gravity with
    m = share · mass), so either gives the same forces to the bit."""
    cdef Py_ssize_t i, r, p, count = 0
    cdef double m
    if out.shape[0] != forces.shape[0] or forces.shape[1] != 2 or out.shape[1] != 2 or not (
            gather.shape[0] == share.shape[0] == mass.shape[0] == awake.shape[0]
            == applied.shape[0] == lifted.shape[0]):
        raise ValueError("preload: arrays do not match")
    with nogil:
        for i in range(forces.shape[0]):
            out[i, 0] = forces[i, 0]
            out[i, 1] = forces[i, 1]
        for i in range(rows.shape[0]):
            r = rows[i]
            if not awake[r]:  # asleep: left as it is (a force would wake it)
                continue
            p = gather[r]
            m = share[r] * mass[r]
            out[p, 0] = forces[p, 0] - m * gx
            out[p, 1] = forces[p, 1] - m * gz
            applied[r] = share[r]
            lifted[r] = m * g
            count += 1
    return count


def rest_standing(const double[:, ::1] force, const double[::1] friction,
                  const double[::1] grip, const int64_t[::1] points,
                  const unsigned char[::1] tilted, const double[::1] applied,
                  const double[::1] weight, const double[::1] mu,
                  const unsigned char[::1] awake, const unsigned char[::1] unrest,
                  const double[:, ::1] raw, const Py_ssize_t[::1] gather,
                  double[:, ::1] held, int8_t[::1] steps, unsigned char[::1] slid,
                  unsigned char[::1] kept, unsigned char[::1] chosen, double down_x,
                  double down_z, double keep, double loose, double support,
                  double stay_support, double grip_share, double sliding_share,
                  double slip, double kept_slip) -> int:
    """RestingSupport's update and the first half of its choice, one pass per row
    (see resting.py for the rules): the standing after a step (``held``, ``steps``,
    ``slid``, ``kept``, in place) and the rows that may be preloaded, islands aside
    (``chosen``); how many those are.

    ``keep`` is the smoothing's share kept per step, ``loose`` (1 − warm start) the
    grip left to a body that slid while preloaded, ``support``/``stay_support`` the
    shares of its weight that hold a body up to enter/stay, ``grip_share`` and
    ``sliding_share`` REST_GRIP and REST_SLIDING, ``slip``/``kept_slip`` the speeds
    under which a body may enter/stay; ``raw`` the read (pymunk's list, row r at
    ``gather[r]``). Each number is worked out in the operations and order of the
    numpy formulation this replaced, the dot products with ``down`` as a plain sum of
    two products (numpy's matmul, in BLAS, may fuse them: the same to the bit while
    gravity is vertical, within an ulp otherwise)."""
    cdef Py_ssize_t n = force.shape[0], i
    cdef double share, up, h0, h1, held_up, s0, s1, limit, speed, fresh = 1.0 - keep
    cdef bint pushed, sliding, rests, stays, was_applied
    cdef int count = 0
    if not (force.shape[1] == 2 and held.shape[1] == 2 and raw.shape[1] == 6
            and friction.shape[0] == grip.shape[0] == points.shape[0] == tilted.shape[0]
            == applied.shape[0] == weight.shape[0] == mu.shape[0] == awake.shape[0]
            == unrest.shape[0] == gather.shape[0] == held.shape[0] == steps.shape[0]
            == slid.shape[0] == kept.shape[0] == chosen.shape[0] == n):
        raise ValueError("rest_standing: arrays do not match the rows")
    with nogil:
        for i in range(n):
            share = 1.0 - applied[i]
            up = -(force[i, 0] * down_x + force[i, 1] * down_z)
            h0 = held[i, 0] * keep
            h1 = held[i, 1] * keep
            h0 = h0 + fresh * force[i, 0] / share
            h1 = h1 + fresh * force[i, 1] / share
            held[i, 0] = h0
            held[i, 1] = h1
            held_up = -(h0 * down_x + h1 * down_z)
            s0 = h0 + held_up * down_x
            s1 = h1 + held_up * down_z
            limit = grip_share * (loose if slid[i] else 1.0) * mu[i] * held_up
            pushed = s0 * s0 + s1 * s1 > limit * limit
            sliding = friction[i] >= sliding_share * grip[i]
            was_applied = applied[i] > 0
            slid[i] = (slid[i] or (was_applied and sliding)) and pushed
            rests = (weight[i] > 0 and awake[i] and not pushed
                     and up >= support * share * weight[i] and not sliding)
            steps[i] = (steps[i] + 1 if steps[i] < 2 else 2) if rests else 0
            stays = weight[i] > 0 and awake[i] and up >= stay_support * share * weight[i]
            kept[i] = was_applied and stays
            speed = hypot(raw[gather[i], 3], raw[gather[i], 4])
            chosen[i] = ((steps[i] >= 2 or kept[i]) and speed < (kept_slip if kept[i]
                                                                 else slip)
                         and not unrest[i] and (points[i] >= 2 or tilted[i] == 0))
            count += chosen[i]
    return count


def rest_ramp(const int64_t[::1] points, const unsigned char[::1] chosen, labels,
              const unsigned char[::1] moving, const unsigned char[::1] unrest,
              const double[::1] weight, double[::1] ramp, double up, double down) -> None:
    """Each row's preload ramp for the next step (in place): up by ``up`` where chosen,
    down by ``down`` elsewhere, within [0, 1]; off at once where no contact is left or
    its island (``labels``, or None: not found, nothing is blocked) holds a moving row
    that is unrest or weightless."""
    cdef Py_ssize_t n = ramp.shape[0], i
    cdef Py_ssize_t[::1] label
    cdef unsigned char *blocked = NULL
    cdef double v
    cdef bint off
    if not (points.shape[0] == chosen.shape[0] == moving.shape[0] == unrest.shape[0]
            == weight.shape[0] == n):
        raise ValueError("rest_ramp: arrays do not match the rows")
    if labels is not None:
        label = labels
        if label.shape[0] != n:
            raise ValueError("rest_ramp: labels do not match the rows")
        blocked = <unsigned char *>malloc(max(n, 1))
        if blocked == NULL:
            raise MemoryError("out of memory for the resting islands")
    try:
        with nogil:
            if blocked != NULL:
                for i in range(n):
                    blocked[i] = 0
                for i in range(n):
                    if moving[i] and points[i] > 0 and (unrest[i] or weight[i] <= 0):
                        blocked[label[i]] = 1
            for i in range(n):
                off = points[i] <= 0 or (blocked != NULL and blocked[label[i]])
                if off:
                    ramp[i] = 0.0
                else:
                    v = ramp[i] + (up if chosen[i] else down)
                    ramp[i] = 1.0 if v > 1.0 else (0.0 if v < 0.0 else v)
    finally:
        free(blocked)


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
