# cython: language_level=3
"""The skeleton's last passes in one loop each, the GIL released: every node's local
translate · rotate · scale composed down the hierarchy into model-frame matrices, and
the joints' palettes (model matrix times inverse bind). numpy took a pass per column and
one fancy-indexed matrix product per depth of the tree; here each node is one 3×4 product.

A node's rotation is that of ``q / |q|``, worked with ``2 / |q|²`` in place of the square
root (:func:`engine.rotation.quat_to_matrix` normalises first: the same to rounding).
"""

cdef inline void _trs(const double *p, double *m) noexcept nogil:
    """A pose row (translation xyz_, quaternion wxyz, scale xyz_) as a 3×4 matrix."""
    cdef double w = p[4], x = p[5], y = p[6], z = p[7]
    cdef double sx = p[8], sy = p[9], sz = p[10]
    cdef double k = 2.0 / (w * w + x * x + y * y + z * z)
    cdef double xk = x * k, yk = y * k, zk = z * k
    cdef double xx = x * xk, yy = y * yk, zz = z * zk
    cdef double xy = x * yk, xz = x * zk, yz = y * zk
    cdef double wx = w * xk, wy = w * yk, wz = w * zk
    m[0] = (1.0 - (yy + zz)) * sx
    m[1] = (xy - wz) * sy
    m[2] = (xz + wy) * sz
    m[3] = p[0]
    m[4] = (xy + wz) * sx
    m[5] = (1.0 - (xx + zz)) * sy
    m[6] = (yz - wx) * sz
    m[7] = p[1]
    m[8] = (xz - wy) * sx
    m[9] = (yz + wx) * sy
    m[10] = (1.0 - (xx + yy)) * sz
    m[11] = p[2]


def compose(const double[:, ::1] pose, const long long[::1] parent,
            const long long[::1] order, double[:, :, ::1] world) -> None:
    """``world[r]`` (4×4) for every node row ``r`` of ``pose`` ``(n, 12)``: its local
    matrix, after its ``parent``'s (-1: a root) in ``order`` (parents before children)."""
    cdef Py_ssize_t n = pose.shape[0], i, r, p, a, b
    cdef double local[12]
    cdef double *out
    cdef const double *up
    if pose.shape[1] != 12 or parent.shape[0] != n or order.shape[0] != n or \
            world.shape[0] != n or world.shape[1] != 4 or world.shape[2] != 4:
        raise ValueError("compose: arrays do not match")
    for i in range(n):
        r = order[i]
        p = parent[r]
        if not (0 <= r < n and -1 <= p < n):
            raise ValueError("compose: a row or parent out of range")
    with nogil:
        for i in range(n):
            r = order[i]
            p = parent[r]
            out = &world[r, 0, 0]
            _trs(&pose[r, 0], local)
            if p < 0:
                for a in range(12):
                    out[a] = local[a]
            else:
                up = &world[p, 0, 0]
                for a in range(3):
                    for b in range(4):
                        out[4 * a + b] = (up[4 * a] * local[b] + up[4 * a + 1] * local[4 + b]
                                          + up[4 * a + 2] * local[8 + b])
                    out[4 * a + 3] += up[4 * a + 3]
            out[12] = 0.0
            out[13] = 0.0
            out[14] = 0.0
            out[15] = 1.0


def palettes(const double[:, :, ::1] world, const long long[::1] rows,
             const double[:, :, ::1] inverse_bind, double[:, :, ::1] out) -> None:
    """``out[j] = world[rows[j]] @ inverse_bind[j]`` (4×4 each; ``world``'s last rows are
    0 0 0 1, ``inverse_bind``'s are taken as they are)."""
    cdef Py_ssize_t m = rows.shape[0], j, a, b, r
    cdef const double *w
    cdef const double *ib
    cdef double *o
    if inverse_bind.shape[0] != m or out.shape[0] != m or world.shape[1] != 4 or \
            inverse_bind.shape[1] != 4 or out.shape[1] != 4:
        raise ValueError("palettes: arrays do not match")
    for j in range(m):
        if not 0 <= rows[j] < world.shape[0]:
            raise ValueError("palettes: a row out of range")
    with nogil:
        for j in range(m):
            r = rows[j]
            w = &world[r, 0, 0]
            ib = &inverse_bind[j, 0, 0]
            o = &out[j, 0, 0]
            for a in range(3):
                for b in range(4):
                    o[4 * a + b] = (w[4 * a] * ib[b] + w[4 * a + 1] * ib[4 + b]
                                    + w[4 * a + 2] * ib[8 + b] + w[4 * a + 3] * ib[12 + b])
            for b in range(4):
                o[12 + b] = ib[12 + b]
