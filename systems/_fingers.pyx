# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True
"""A fingered hand's per-frame arithmetic in C: its sample's joints read into the world,
its joints' tracked angles, its servos' rows, its palm's motion and its fingertips.
Every hand runs these every frame; in numpy each was a dozen small array calls whose
cost per call, not their arithmetic, was most of a hand's cost. Arrays are read through
their data pointers, checked once per call (float64, C order, large enough), which costs
a fraction of a typed memoryview's set-up.

The joint layout (which joints each bone spans, its parent's, the fingertips) is given
once by :func:`layout`, from :mod:`systems.hand_fingers`' tables: one definition.
"""

cimport numpy as cnp
from libc.math cimport atan2, fabs, sqrt

import numpy as np

cnp.import_array()

cdef int _STARTS[15]
cdef int _ENDS[15]
cdef int _PARENT_A[15]
cdef int _PARENT_B[15]
cdef int _TIPS[5]
cdef bint _LAID_OUT = False


def layout(starts, ends, parent_a, parent_b, tips) -> None:
    """The bones' joints (15 each: start, end, the parent's two) and the 5 fingertips."""
    global _LAID_OUT
    cdef int i
    for i in range(15):
        _STARTS[i], _ENDS[i] = starts[i], ends[i]
        _PARENT_A[i], _PARENT_B[i] = parent_a[i], parent_b[i]
    for i in range(5):
        _TIPS[i] = tips[i]
    _LAID_OUT = True


cdef double* _doubles(object a, Py_ssize_t n, bint write=False) except NULL:
    """The data of a float64 C-ordered array of at least ``n`` numbers (writable if
    ``write``)."""
    if not isinstance(a, cnp.ndarray):
        raise TypeError(f"expected a numpy array, got {type(a).__name__}")
    cdef cnp.ndarray arr = <cnp.ndarray>a
    if cnp.PyArray_TYPE(arr) != cnp.NPY_DOUBLE or not cnp.PyArray_IS_C_CONTIGUOUS(arr):
        raise ValueError("expected a C-ordered float64 array")
    if cnp.PyArray_SIZE(arr) < n:
        raise ValueError(f"expected at least {n} numbers, got {cnp.PyArray_SIZE(arr)}")
    if write and not cnp.PyArray_ISWRITEABLE(arr):
        raise ValueError("the array is read-only")
    return <double*>cnp.PyArray_DATA(arr)


cdef inline void _matrix(double w, double x, double y, double z, double *m) noexcept nogil:
    """A unit quaternion's rotation matrix, row-major (unnormalised: as it comes)."""
    m[0] = 1.0 - 2.0 * (y * y + z * z)
    m[1] = 2.0 * (x * y - w * z)
    m[2] = 2.0 * (x * z + w * y)
    m[3] = 2.0 * (x * y + w * z)
    m[4] = 1.0 - 2.0 * (x * x + z * z)
    m[5] = 2.0 * (y * z - w * x)
    m[6] = 2.0 * (x * z - w * y)
    m[7] = 2.0 * (y * z + w * x)
    m[8] = 1.0 - 2.0 * (x * x + y * y)


def read_joints(positions, orientations, frame_position=None, frame_orientation=None):
    """A sample's joint positions (n, 3) and orientations (n, 4) as arrays, in the world
    through a frame (position, orientation w x y z; None: none): ``R p + t`` and
    ``f ⊗ q``, ``R`` the frame's normalised rotation."""
    cdef Py_ssize_t n = len(positions), i = 0
    if len(orientations) != n:
        raise ValueError("a hand's positions and orientations differ in number")
    p, q = np.empty((n, 3)), np.empty((n, 4))
    cdef double *pp = _doubles(p, 3 * n, True)
    cdef double *qq = _doubles(q, 4 * n, True)
    for row in positions:
        pp[3 * i], pp[3 * i + 1], pp[3 * i + 2] = row
        i += 1
    i = 0
    for row in orientations:
        qq[4 * i], qq[4 * i + 1], qq[4 * i + 2], qq[4 * i + 3] = row
        i += 1
    if frame_position is not None:
        _through(pp, qq, n, frame_position, frame_orientation)
    return p, q


cdef void _through(double *p, double *q, Py_ssize_t n, position, orientation) except *:
    """Joints taken from a frame's coordinates into the world, in place."""
    cdef double tx, ty, tz, fw, fx, fy, fz, k, a, b, c, w, x, y, z
    cdef double m[9]
    tx, ty, tz = position
    fw, fx, fy, fz = orientation
    k = sqrt(fw * fw + fx * fx + fy * fy + fz * fz)
    _matrix(fw / k, fx / k, fy / k, fz / k, m)
    cdef Py_ssize_t i
    for i in range(n):
        a, b, c = p[3 * i], p[3 * i + 1], p[3 * i + 2]
        p[3 * i] = m[0] * a + m[1] * b + m[2] * c + tx
        p[3 * i + 1] = m[3] * a + m[4] * b + m[5] * c + ty
        p[3 * i + 2] = m[6] * a + m[7] * b + m[8] * c + tz
        w, x, y, z = q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]
        q[4 * i] = fw * w - fx * x - fy * y - fz * z
        q[4 * i + 1] = fw * x + fx * w + fy * z - fz * y
        q[4 * i + 2] = fw * y - fx * z + fy * w + fz * x
        q[4 * i + 3] = fw * z + fx * y - fy * x + fz * w


cdef inline void _in_wrist(const double *p, int head, int tail, const double *m,
                           double *out) noexcept nogil:
    """The vector from joint ``tail`` to joint ``head`` in the wrist's frame (``Rᵀ v``)."""
    cdef double a = p[3 * head] - p[3 * tail]
    cdef double b = p[3 * head + 1] - p[3 * tail + 1]
    cdef double c = p[3 * head + 2] - p[3 * tail + 2]
    out[0] = a * m[0] + b * m[3] + c * m[6]
    out[1] = a * m[1] + b * m[4] + c * m[7]
    out[2] = a * m[2] + b * m[5] + c * m[8]


cdef void _angles(const double *p, const double *q, const double *forms,
                  const double *thumb, double *out) noexcept nogil:
    """:func:`angles` into ``out`` (15 × 2, zeroed)."""
    cdef double m[9]
    cdef double a[3]
    cdef double b[3]
    cdef double y, x, ab
    cdef int row, i, u
    _matrix(q[4], q[5], q[6], q[7], m)  # the wrist's, joint 1
    for row in range(20):
        i = row if row < 15 else 3 * (row - 15)
        if i == 0:
            a[0], a[1], a[2] = thumb[0], thumb[1], thumb[2]
        else:
            _in_wrist(p, _PARENT_B[i], _PARENT_A[i], m, a)
        _in_wrist(p, _ENDS[i], _STARTS[i], m, b)
        y = x = 0.0
        for u in range(9):
            ab = a[u // 3] * b[u % 3]
            y += ab * forms[18 * row + 2 * u]
            x += ab * forms[18 * row + 2 * u + 1]
        if row < 15:
            out[2 * row] = atan2(y, x)
        else:
            out[2 * i + 1] = atan2(y, x)


def angles(p, q, forms, thumb):
    """Each joint's tracked angles (15, 2): :func:`systems.hand_fingers.joint_angles`'
    atan2 of two quadratic forms (``forms``, 20 × 9 × 2) of each angle's two bones in the
    wrist's frame (the parent bone, or ``thumb``, the thumb's rest heading, for the
    thumb's first bone; then the bone): rows 0–14 the flexions, 15–19 the spreads at
    each finger's base."""
    if not _LAID_OUT:
        raise RuntimeError("systems._fingers.layout was not called")
    out = np.zeros((15, 2))
    _angles(_doubles(p, 78), _doubles(q, 104), _doubles(forms, 360), _doubles(thumb, 3),
            _doubles(out, 30, True))
    return out


def aim(fingers, p, q, thumb, double t, bint stale, double bound,
        double max_spin) -> float:
    """One hand's frame (:func:`systems.hand_fingers.aim`): its joints' tracked angles;
    on a newer sample its bones' tracked centres and orientations, their velocities and
    the joints' rates by finite difference from the last (zero when ``stale``); its
    tracked tips and palm; its servos' rows (:func:`servo_rows`). Returns the fastest of
    its bones' velocity components (m/s)."""
    if not _LAID_OUT:
        raise RuntimeError("systems._fingers.layout was not called")
    cdef const double *pp = _doubles(p, 78)
    cdef const double *qq = _doubles(q, 104)
    forms = fingers.forms[0]
    now = np.zeros((15, 2))
    cdef double *a1 = _doubles(now, 30, True)
    _angles(pp, qq, _doubles(forms, 360), _doubles(thumb, 3), a1)
    previous = fingers.sample
    if previous is None or t > previous[0]:
        fingers.sample = _noted(fingers, pp, qq, a1, t, previous)
        fingers.angles = (t, now)
    cdef double *v = _doubles(fingers.velocity, 45, True)
    cdef double *r = _doubles(fingers.rates, 30, True)
    cdef double fastest = 0.0
    cdef int i, k
    for i in range(45):
        if stale:
            v[i] = 0.0
        elif fabs(v[i]) > fastest:
            fastest = fabs(v[i])
    if stale:
        for i in range(30):
            r[i] = 0.0
    tips, palm = np.empty((5, 3)), np.empty(3)
    cdef double *tt = _doubles(tips, 15, True)
    cdef double *pm = _doubles(palm, 3, True)
    for i in range(5):
        for k in range(3):
            tt[3 * i + k] = pp[3 * _TIPS[i] + k]
    pm[0], pm[1], pm[2] = pp[0], pp[1], pp[2]
    fingers.tips, fingers.palm = tips, palm
    servo_rows(fingers.servos, now, fingers.zero, fingers.rates, fingers.levers, bound,
               fingers.time_constant, max_spin)
    return fastest


cdef tuple _noted(fingers, const double *p, const double *q, const double *a1, double t,
                  previous):
    """A newer sample's bones' centres (15, 3) and start orientations (15, 4), and, from
    the last one, the bones' velocities and the joints' rates (in place)."""
    centres, quats = np.empty((15, 3)), np.empty((15, 4))
    cdef double *c = _doubles(centres, 45, True)
    cdef double *turns = _doubles(quats, 60, True)
    cdef int i, k
    cdef double dt
    cdef const double *c0
    cdef const double *a0
    cdef double *v
    cdef double *r
    for i in range(15):
        for k in range(3):
            c[3 * i + k] = (p[3 * _STARTS[i] + k] + p[3 * _ENDS[i] + k]) * 0.5
        for k in range(4):
            turns[4 * i + k] = q[4 * _STARTS[i] + k]
    if previous is not None:
        dt = t - <double>previous[0]
        c0, a0 = _doubles(previous[1], 45), _doubles(fingers.angles[1], 30)
        v, r = _doubles(fingers.velocity, 45, True), _doubles(fingers.rates, 30, True)
        for i in range(45):
            v[i] = (c[i] - c0[i]) / dt
        for i in range(30):
            r[i] = (a1[i] - a0[i]) / dt
    return (t, centres, quats)


def servo_rows(rows, angles, zero, rates, levers, double bound, double time_constant,
               double max_spin) -> None:
    """The servos' rows (15, 7) in place: target angles counted from ``zero``, the
    tracked rates, the torque bound (``bound`` times each joint's lever), the time
    constant and the spin cap."""
    cdef double *o = _doubles(rows, 105, True)
    cdef const double *a = _doubles(angles, 30)
    cdef const double *z = _doubles(zero, 30)
    cdef const double *r = _doubles(rates, 30)
    cdef const double *lever = _doubles(levers, 15)
    cdef int i
    for i in range(15):
        o[7 * i] = a[2 * i] - z[2 * i]
        o[7 * i + 1] = a[2 * i + 1] - z[2 * i + 1]
        o[7 * i + 2], o[7 * i + 3] = r[2 * i], r[2 * i + 1]
        o[7 * i + 4] = bound * lever[i]
        o[7 * i + 5], o[7 * i + 6] = time_constant, max_spin


def palm_motion(p, q, double t, previous, bint stale):
    """The palm joint's pose and velocities ``(t, p, q, v, w)``: the velocities by finite
    difference from ``previous`` (kept while no newer sample came; zero when
    ``stale``), the angular one the short way round (a rotation vector over the time)."""
    cdef const double *pp = _doubles(p, 3)
    cdef const double *qq = _doubles(q, 4)
    out = np.zeros(13)
    cdef double *o = _doubles(out, 13, True)
    cdef double dt
    cdef int k
    for k in range(3):
        o[k] = pp[k]
    for k in range(4):
        o[3 + k] = qq[k]
    cdef const double *v0
    cdef const double *w0
    if previous is not None:
        dt = t - <double>previous[0]
        if dt > 0.0:
            _palm_velocities(o, _doubles(previous[1], 3), _doubles(previous[2], 4), dt)
        else:  # no newer sample: as it was
            v0, w0 = _doubles(previous[3], 3), _doubles(previous[4], 3)
            for k in range(3):
                o[7 + k], o[10 + k] = v0[k], w0[k]
    if stale:
        for k in range(7, 13):
            o[k] = 0.0
    return (t, out[0:3], out[3:7], out[7:10], out[10:13])


cdef void _palm_velocities(double *o, const double *p0, const double *q0,
                           double dt) noexcept nogil:
    """The palm's velocity and spin (o[7:13]) from its last pose to this one (o[0:7])."""
    cdef double dw, dx, dy, dz, s, scale
    cdef const double *q = o + 3
    cdef int k
    for k in range(3):
        o[7 + k] = (o[k] - p0[k]) / dt
    # q ⊗ conj(q0): the turn from the last orientation to this one
    dw = q[0] * q0[0] + q[1] * q0[1] + q[2] * q0[2] + q[3] * q0[3]
    dx = -q[0] * q0[1] + q[1] * q0[0] - q[2] * q0[3] + q[3] * q0[2]
    dy = -q[0] * q0[2] + q[1] * q0[3] + q[2] * q0[0] - q[3] * q0[1]
    dz = -q[0] * q0[3] - q[1] * q0[2] + q[2] * q0[1] + q[3] * q0[0]
    if dw < 0.0:
        dw, dx, dy, dz = -dw, -dx, -dy, -dz
    s = sqrt(dx * dx + dy * dy + dz * dz)
    scale = 2.0 if s < 1e-12 else 2.0 * atan2(s, dw) / s
    o[10], o[11], o[12] = dx * scale / dt, dy * scale / dt, dz * scale / dt


cdef const long long* _rows_of(object rows, Py_ssize_t n) except NULL:
    """The data of ``n`` row indices, a C-ordered int64 array."""
    if not isinstance(rows, cnp.ndarray) or cnp.PyArray_TYPE(<cnp.ndarray>rows) != \
            cnp.NPY_INT64 or not cnp.PyArray_IS_C_CONTIGUOUS(<cnp.ndarray>rows) or \
            cnp.PyArray_SIZE(<cnp.ndarray>rows) != n:
        raise ValueError(f"expected {n} row indices, a C-ordered int64 array")
    return <const long long*>cnp.PyArray_DATA(<cnp.ndarray>rows)


cdef const double* _pose(const double *table, Py_ssize_t height, long long row) except NULL:
    """Row ``row`` of a pose table ``height`` rows of 13 (position, quaternion w x y z,
    velocities)."""
    if not 0 <= row < height:
        raise IndexError(f"row {row} is outside the pose table ({height} rows)")
    return table + 13 * row


cdef inline void _far_end(const double *pose, double length, double *out) noexcept nogil:
    """The far end of a bone ``length`` long along its x axis, at ``pose``: its position
    plus half its length along the first column of its quaternion's matrix."""
    cdef double w = pose[3], x = pose[4], y = pose[5], z = pose[6]
    cdef double h = length * 0.5
    out[0] = pose[0] + (w * w + x * x - y * y - z * z) * h
    out[1] = pose[1] + 2.0 * (x * y + w * z) * h
    out[2] = pose[2] + 2.0 * (x * z - w * y) * h


def far_ends(table, lengths, rows=None):
    """The far ends (n, 3) of bones ``lengths`` long along their x axes, at rows ``rows``
    of the pose ``table`` (n × 13; None: its first n rows, in order)."""
    lengths = np.ascontiguousarray(lengths, np.float64)
    cdef Py_ssize_t n = cnp.PyArray_SIZE(<cnp.ndarray>lengths), i
    cdef const double *poses = _doubles(table, 13)
    cdef Py_ssize_t height = cnp.PyArray_SIZE(<cnp.ndarray>table) // 13
    cdef const long long *picked = NULL
    if rows is not None:
        picked = _rows_of(np.ascontiguousarray(rows, np.int64), n)
    cdef const double *length = _doubles(lengths, n)
    out = np.empty((n, 3))
    cdef double *o = _doubles(out, 3 * n, True)
    for i in range(n):
        _far_end(_pose(poses, height, i if picked == NULL else picked[i]), length[i],
                 o + 3 * i)
    return out


def deviations(table, rows, lengths, tips) -> tuple:
    """Each physical fingertip's distance (m) from its tracked one (``tips``, 5 × 3): a
    fingertip is its distal bone's far end (:func:`far_ends`), the bones' poses at
    ``rows`` (15, base to tip, each finger's three) of the pose ``table`` (n × 13)."""
    cdef const double *poses = _doubles(table, 13)
    cdef Py_ssize_t height = cnp.PyArray_SIZE(<cnp.ndarray>table) // 13
    cdef const long long *row = _rows_of(rows, 15)
    cdef const double *length = _doubles(lengths, 15)
    cdef const double *tracked = _doubles(tips, 15)
    cdef double out[5]
    cdef double end[3]
    cdef double dx, dy, dz
    cdef int k
    for k in range(5):
        _far_end(_pose(poses, height, row[3 * k + 2]), length[3 * k + 2], end)
        dx, dy, dz = end[0] - tracked[3 * k], end[1] - tracked[3 * k + 1], \
            end[2] - tracked[3 * k + 2]
        out[k] = sqrt(dx * dx + dy * dy + dz * dz)
    return (out[0], out[1], out[2], out[3], out[4])
