# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The pose codec's per-frame passes (:mod:`services.net.codec`), compiled.

One pass per side does what some forty numpy calls did, without the GIL (the server's
sender thread encodes beside the simulation, a node decodes beside its drawing):

* :func:`encode_changes` (server): each body's change from the nodes' copy (quantised),
  the bodies that moved, the copy brought to what the nodes will decode, and the message
  body (id differences, then the residuals zigzagged, in byte planes);
* :func:`decode_changes` (node): the reverse, on the node's copy.

Both ends bring their copy forward by :func:`_apply`, the same IEEE operations in the
same order (the module is compiled with ``-ffp-contract=off``: no fused multiply-add),
so the server's copy and the node's agree to the bit. After quantisation everything is
integer arithmetic, wrapping in 32 bits. tests/net/test_codec_kernel.py checks both
passes against a numpy formulation of the wire format, to the bit.
"""

from libc.math cimport rint, sqrt
from libc.stdint cimport int32_t, uint8_t, uint32_t
from libc.stdlib cimport free, malloc

#: Position step (m) and rotation units, as codec.py defines them.
cdef double STEP = 2.0 ** -13
cdef double SCALE = 32767.0
#: A change of position is clipped to this many steps (int32 holds it and its residual).
cdef double CLIP = 2.0 ** 30
#: Bytes of a body in a change's body: its id difference and six residuals.
ROW = 28


cdef inline void _mul(const double* p, const double* q, double* out) noexcept nogil:
    """Hamilton product ``p ⊗ q`` in engine.rotation.quat_multiply's order of operations."""
    out[0] = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3]
    out[1] = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2]
    out[2] = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1]
    out[3] = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0]


cdef inline void _apply(double* pose, const int32_t* change) noexcept nogil:
    """A pose after a change (three position steps, three rotation units): the
    arithmetic both ends do, so they agree to the bit."""
    cdef double turn[4]
    cdef double q[4]
    cdef double s, norm
    cdef int k
    turn[1] = change[3] / SCALE
    turn[2] = change[4] / SCALE
    turn[3] = change[5] / SCALE
    s = 1.0 - (turn[1] * turn[1] + turn[2] * turn[2] + turn[3] * turn[3])
    turn[0] = sqrt(0.0 if s < 0.0 else (1.0 if s > 1.0 else s))
    for k in range(3):
        pose[k] = pose[k] + change[k] * STEP
    _mul(&pose[3], turn, q)
    norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    for k in range(4):
        pose[3 + k] = q[k] / norm


cdef inline int32_t _quantised(double x) noexcept nogil:
    """``x`` rounded to an integer, clipped to +-CLIP; NaN is 0 (a pose that is not a
    number does not move the nodes' copy)."""
    x = rint(x)
    if x != x:
        return 0
    return <int32_t>(CLIP if x > CLIP else (-CLIP if x < -CLIP else x))


cdef inline void _to_planes(uint8_t* out, const uint32_t* rows, Py_ssize_t m,
                           int first, int count) noexcept nogil:
    """Columns ``first`` to ``first + count - 1`` of ``m`` rows of 7 uint32 as
    little-endian byte planes: byte 0 of the column in every row, then byte 1, ..."""
    cdef Py_ssize_t i
    cdef int c, b
    for c in range(first, first + count):
        for b in range(4):
            for i in range(m):
                out[i] = <uint8_t>(rows[i * 7 + c] >> (8 * b))
            out += m


cdef inline void _from_planes(const uint8_t* data, uint32_t* rows, Py_ssize_t m) noexcept nogil:
    """:func:`_to_planes` of all 7 columns undone."""
    cdef Py_ssize_t i
    cdef int c, b
    for i in range(m * 7):
        rows[i] = 0
    for c in range(7):
        for b in range(4):
            for i in range(m):
                rows[i * 7 + c] |= (<uint32_t>data[i]) << (8 * b)
            data += m


def encode_changes(const uint32_t[::1] ids, const double[:, ::1] poses,
                   double[:, ::1] mirror, int32_t[:, ::1] last, uint8_t[::1] out) -> int:
    """The change message's body for ``poses`` (n, 7) against the nodes' copy ``mirror``
    (n, 7), written into ``out`` (at least ``ROW * n`` bytes); returns how many bodies
    moved (``m``: the body is ``out[:ROW * m]``). ``mirror`` becomes what the nodes will
    decode, ``last`` (n, 6) each body's change this frame (0 where it did not move)."""
    cdef Py_ssize_t n = ids.shape[0], i, m = 0
    cdef int k
    cdef double turn[4]
    cdef double conj[4]
    cdef double sign
    cdef int32_t change[6]
    cdef uint32_t previous = 0, residual
    cdef uint32_t* rows
    cdef bint moved
    if (poses.shape[0] != n or mirror.shape[0] != n or last.shape[0] != n
            or poses.shape[1] != 7 or mirror.shape[1] != 7 or last.shape[1] != 6
            or out.shape[0] < ROW * n):
        raise ValueError("the codec's arrays do not agree on the number of bodies")
    if n == 0:
        return 0
    rows = <uint32_t*>malloc(n * 7 * sizeof(uint32_t))
    if rows == NULL:
        raise MemoryError()
    with nogil:
        for i in range(n):
            for k in range(3):
                change[k] = _quantised((poses[i, k] - mirror[i, k]) / STEP)
            conj[0] = mirror[i, 3]
            for k in range(1, 4):
                conj[k] = -mirror[i, 3 + k]
            _mul(conj, &poses[i, 3], turn)
            sign = -1.0 if turn[0] < 0.0 else 1.0  # the same rotation with w >= 0
            for k in range(3):
                change[3 + k] = _quantised(turn[1 + k] * sign * SCALE)
            moved = False
            for k in range(6):
                moved = moved or change[k] != 0
            if not moved:
                for k in range(6):
                    last[i, k] = 0
                continue
            _apply(&mirror[i, 0], change)
            rows[m * 7] = ids[i] - previous
            previous = ids[i]
            for k in range(6):
                # the residual from the change before, wrapping in 32 bits as the node's
                # sum does, zigzagged (0, -1, 1, -2, ... -> 0, 1, 2, 3, ...)
                residual = <uint32_t>change[k] - <uint32_t>last[i, k]
                rows[m * 7 + 1 + k] = (residual << 1) ^ <uint32_t>(<int32_t>residual >> 31)
                last[i, k] = change[k]
            m += 1
        _to_planes(&out[0], rows, m, 0, 1)
        _to_planes(&out[4 * m], rows, m, 1, 6)
    free(rows)
    return m


cdef bint _find_held(const uint32_t* rows, Py_ssize_t m, const uint32_t[::1] held,
                     uint32_t[::1] ids, Py_ssize_t* where) noexcept nogil:
    """Each row's body (its ID a running sum of the rows' first words) into ``ids`` and
    its place among ``held`` into ``where``; False when one is not held. Both are
    sorted: one walk finds every row."""
    cdef Py_ssize_t n = held.shape[0], j = 0, k
    cdef uint32_t total = 0
    for k in range(m):
        total = total + rows[k * 7]
        ids[k] = total
        while j < n and held[j] < total:
            j += 1
        if j == n or held[j] != total:
            return False
        where[k] = j
        j += 1
    return True


cdef void _apply_rows(const uint32_t* rows, const Py_ssize_t* where, Py_ssize_t m,
                      double[:, ::1] poses, int32_t[:, ::1] last,
                      double[:, ::1] moved) noexcept nogil:
    """Each named body's change (zigzag-decoded, added to its last change) applied to
    its pose, copied into ``moved``; a body not named has no change this time."""
    cdef Py_ssize_t n = poses.shape[0], j, k = 0
    cdef int c
    cdef uint32_t z
    cdef int32_t change[6]
    for j in range(n):
        if k < m and where[k] == j:
            for c in range(6):
                z = rows[k * 7 + 1 + c]
                change[c] = <int32_t>(((z >> 1) ^ (<uint32_t>0 - (z & 1)))
                                      + <uint32_t>last[j, c])
                last[j, c] = change[c]
            _apply(&poses[j, 0], change)
            for c in range(7):
                moved[k, c] = poses[j, c]
            k += 1
        else:
            for c in range(6):
                last[j, c] = 0


def decode_changes(const uint8_t[::1] body, const uint32_t[::1] held, double[:, ::1] poses,
                   int32_t[:, ::1] last, uint32_t[::1] ids, double[:, ::1] moved) -> bool:
    """A change message's ``body`` (``ROW * m`` bytes, m = ``len(ids)``) applied to the
    node's copy ``poses`` (n, 7) of the bodies ``held`` (n, sorted): ``ids`` and
    ``moved`` (m, 7) become the bodies it names and their poses now, ``last`` (n, 6)
    each body's change. False, and nothing changed, when it names a body not held (or
    one twice)."""
    cdef Py_ssize_t m = ids.shape[0], n = held.shape[0], j
    cdef int c
    cdef uint32_t* rows
    cdef Py_ssize_t* where
    cdef bint known = True
    if (body.shape[0] != ROW * m or poses.shape[0] != n or poses.shape[1] != 7
            or last.shape[0] != n or last.shape[1] != 6 or moved.shape[0] != m
            or moved.shape[1] != 7):
        raise ValueError("the codec's arrays do not agree on the number of bodies")
    if m == 0:
        with nogil:
            for j in range(n):
                for c in range(6):
                    last[j, c] = 0
        return True
    rows = <uint32_t*>malloc(m * 7 * sizeof(uint32_t))
    where = <Py_ssize_t*>malloc(m * sizeof(Py_ssize_t))
    if rows == NULL or where == NULL:
        free(rows)
        free(where)
        raise MemoryError()
    with nogil:
        _from_planes(&body[0], rows, m)
        known = _find_held(rows, m, held, ids, where)
        if known:
            _apply_rows(rows, where, m, poses, last, moved)
    free(rows)
    free(where)
    return known
