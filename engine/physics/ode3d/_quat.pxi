# Small quaternion helpers (w, x, y, z) and vector norms, inlined into the per-step paths.

cdef inline double norm3(const double* v) noexcept nogil:
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


cdef inline double clamp_speed(double v) noexcept nogil:
    return max(-MAX_SPEED, min(MAX_SPEED, v))


cdef inline void qmul(const double* a, const double* b, double* out) noexcept nogil:
    cdef double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3]
    cdef double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2]
    cdef double y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1]
    cdef double z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]
    out[0] = w
    out[1] = x
    out[2] = y
    out[3] = z


cdef inline void qrotate(const double* q, const double* v, double* out) noexcept nogil:
    """out = q v q*, written out (t = 2 q.xyz x v; v + w t + q.xyz x t)."""
    cdef double tx = 2.0 * (q[2] * v[2] - q[3] * v[1])
    cdef double ty = 2.0 * (q[3] * v[0] - q[1] * v[2])
    cdef double tz = 2.0 * (q[1] * v[1] - q[2] * v[0])
    out[0] = v[0] + q[0] * tx + q[2] * tz - q[3] * ty
    out[1] = v[1] + q[0] * ty + q[3] * tx - q[1] * tz
    out[2] = v[2] + q[0] * tz + q[1] * ty - q[2] * tx


cdef inline void inverse_rotate(const double* q, const double* v, double* out) noexcept nogil:
    """out = q* v q: a world vector in the frame ``q`` turns onto the world."""
    cdef double c[4]
    c[0] = q[0]
    c[1] = -q[1]
    c[2] = -q[2]
    c[3] = -q[3]
    qrotate(c, v, out)


cdef inline void qnormalize(double* q) noexcept nogil:
    """q made unit; one unit to rounding already is kept to the bit (a saved state's)."""
    cdef double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if fabs(n - 1.0) <= 1e-12:
        return
    if n > 0.0 and isfinite(n):
        q[0] /= n
        q[1] /= n
        q[2] /= n
        q[3] /= n
    else:
        q[0] = 1.0
        q[1] = 0.0
        q[2] = 0.0
        q[3] = 0.0


cdef inline void rotvec_between(const double* qcur, const double* qtarget, double* out) noexcept nogil:
    """Rotation vector (axis * angle, world frame) taking ``qcur`` to ``qtarget``."""
    cdef double conj[4]
    cdef double d[4]
    cdef double s, angle
    conj[0] = qcur[0]
    conj[1] = -qcur[1]
    conj[2] = -qcur[2]
    conj[3] = -qcur[3]
    qmul(qtarget, conj, d)
    if d[0] < 0.0:
        d[0] = -d[0]
        d[1] = -d[1]
        d[2] = -d[2]
        d[3] = -d[3]
    s = sqrt(d[1] * d[1] + d[2] * d[2] + d[3] * d[3])
    if s < 1e-12:
        out[0] = 2.0 * d[1]
        out[1] = 2.0 * d[2]
        out[2] = 2.0 * d[3]
        return
    angle = 2.0 * atan2(s, d[0])   # not acos(w): that turns an ulp of w into 1e-8 rad
    out[0] = d[1] / s * angle
    out[1] = d[2] / s * angle
    out[2] = d[3] / s * angle


cdef bint _quat_lands(const double* q_in, const double* q) noexcept nogil:
    """Whether putting ``q_in`` back (our normalisation, then ODE's own in
    dBodySetQuaternion) gives ``q`` to the bit."""
    cdef double c[4]
    memcpy(c, q_in, 4 * sizeof(double))
    qnormalize(c)
    dNormalize4(c)
    return c[0] == q[0] and c[1] == q[1] and c[2] == q[2] and c[3] == q[3]


cdef void quat_preimage(const double* q, double* out) noexcept nogil:
    """A quaternion that putting back turns into the unit ``q`` to the bit (``q`` where none
    is found). ODE's normalisation is not idempotent, so ``q`` itself may come back an ulp
    off; ``q`` scaled a little (as the integrated quaternion it normalised was) lands."""
    cdef double scale
    cdef int k, sign
    memcpy(out, q, 4 * sizeof(double))
    if _quat_lands(out, q):
        return
    for k in range(1, 2049):
        for sign in range(2):
            scale = 1.0 + (k if sign == 0 else -k) * 2.220446049250313e-16
            out[0] = q[0] * scale
            out[1] = q[1] * scale
            out[2] = q[2] * scale
            out[3] = q[3] * scale
            if _quat_lands(out, q):
                return
    memcpy(out, q, 4 * sizeof(double))
