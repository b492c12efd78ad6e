# Batches: every slot's state into a table row (BodyState's layout) and back, and the
# post-step check that puts bodies gone non-finite, running away or leaving the world back
# where they were sane.

cdef inline void read_slot(World w, int i, double* out) noexcept nogil:
    """Entity-frame state: position, quaternion, linear (at origin) and angular velocity."""
    cdef Slot* s = &w.slots[i]
    cdef const dReal* p
    cdef const dReal* q
    cdef const dReal* v
    cdef const dReal* av
    cdef double wc[3]
    if s.body == NULL:
        memcpy(out, s.pose, 7 * sizeof(double))
        memset(&out[7], 0, 6 * sizeof(double))
        return
    p = dBodyGetPosition(s.body)
    q = dBodyGetQuaternion(s.body)
    v = dBodyGetLinearVel(s.body)
    av = dBodyGetAngularVel(s.body)
    memcpy(&out[3], q, 4 * sizeof(double))
    memcpy(&out[10], av, 3 * sizeof(double))
    if s.com[0] == 0.0 and s.com[1] == 0.0 and s.com[2] == 0.0:
        memcpy(out, p, 3 * sizeof(double))
        memcpy(&out[7], v, 3 * sizeof(double))
        return
    qrotate(q, s.com, wc)
    out[0] = p[0] - wc[0]
    out[1] = p[1] - wc[1]
    out[2] = p[2] - wc[2]
    # velocity of the entity origin: v_com + w x (origin - com) = v_com - w x R c
    out[7] = v[0] - (av[1] * wc[2] - av[2] * wc[1])
    out[8] = v[1] - (av[2] * wc[0] - av[0] * wc[2])
    out[9] = v[2] - (av[0] * wc[1] - av[1] * wc[0])


def read_state(World w) -> tuple:
    """Fresh (keys, table) for every body, table rows in BodyState's layout."""
    cdef cnp.ndarray[cnp.float64_t, ndim=2] table = np.empty((w.n, 13))
    read_state_into(w, table)
    return keys(w), table


def read_state_into(World w, double[:, ::1] out) -> None:
    """Every body's state into the first ``n`` rows of ``out`` (at least (n, 13))."""
    cdef int i
    if out.shape[0] < w.n or out.shape[1] != 13:
        raise ValueError(f"read_state_into needs a C-contiguous float64 array of at least "
                         f"({w.n}, 13), got ({out.shape[0]}, {out.shape[1]})")
    with nogil:
        for i in range(w.n):
            read_slot(w, i, &out[i, 0])


cdef double _preimage(double target, double a) noexcept nogil:
    """An x near target - a with x + a == target in floating point (target - a where none
    is near): the origin value that set_slot_pose/velocity turn into the body's own."""
    cdef double start = target - a
    cdef double up = start, down = start
    cdef int k
    for k in range(8):
        if up + a == target:
            return up
        if down + a == target:
            return down
        up = nextafter(up, INFINITY)
        down = nextafter(down, -INFINITY)
    return start


def read_state_exact(World w) -> tuple:
    """(keys, table) as read_state, each row chosen so that putting it back (set_pose,
    then set_velocity: what loading a saved state does) gives ODE its numbers to the bit:
    the orientation that both normalisations turn into the body's own, and the origin
    and origin velocity that adding the centre-of-mass offset turns into the centre's.
    read_state's rows differ from these by rounding, which a saved state's continuation
    would carry (and a chaotic contact amplify)."""
    cdef cnp.ndarray[cnp.float64_t, ndim=2] table = np.empty((w.n, 13))
    cdef double[:, ::1] out = table
    cdef double qin[4]
    cdef double wc[3]
    cdef double t[3]
    cdef const dReal* p
    cdef const dReal* q
    cdef const dReal* v
    cdef const dReal* av
    cdef Slot* s
    cdef int i, k
    for i in range(w.n):
        read_slot(w, i, &out[i, 0])
        s = &w.slots[i]
        if s.body == NULL:
            continue
        p = dBodyGetPosition(s.body)
        q = dBodyGetQuaternion(s.body)
        v = dBodyGetLinearVel(s.body)
        av = dBodyGetAngularVel(s.body)
        quat_preimage(q, qin)
        memcpy(&out[i, 3], qin, 4 * sizeof(double))
        # the origin and its velocity: putting a body back adds R c and w x R c, R the
        # turn it then has (q, when q_in lands on it)
        qrotate(q, s.com, wc)
        for k in range(3):
            out[i, k] = _preimage(p[k], wc[k])
        t[0] = av[1] * wc[2] - av[2] * wc[1]
        t[1] = av[2] * wc[0] - av[0] * wc[2]
        t[2] = av[0] * wc[1] - av[1] * wc[0]
        for k in range(3):
            out[i, 7 + k] = _preimage(v[k], t[k])
    return keys(w), table


def write_state(World w, cnp.int64_t[::1] slots, double[:, ::1] pos, double[:, ::1] quat,
                double[:, ::1] lin, double[:, ::1] ang) -> None:
    """Set pose and velocity of the bodies at ``slots`` (row i -> slots[i])."""
    cdef Py_ssize_t i
    cdef bint asleep = False  # no sleeper to wake (the usual case): no neighbour search
    for i in range(w.n):
        if w.slots[i].body != NULL and not dBodyIsEnabled(w.slots[i].body):
            asleep = True
            break
    for i in range(slots.shape[0]):
        set_slot_pose(w, <int>slots[i], &pos[i, 0], &quat[i, 0], asleep)
        set_slot_velocity(w, <int>slots[i], &lin[i, 0], &ang[i, 0])


cdef void reset_slot(Slot* s) noexcept nogil:
    """Put a runaway body back where it last was sane, at rest, and disable it."""
    dBodySetPosition(s.body, s.good[0], s.good[1], s.good[2])
    dBodySetQuaternion(s.body, &s.good[3])
    dBodySetForce(s.body, 0.0, 0.0, 0.0)
    dBodySetTorque(s.body, 0.0, 0.0, 0.0)
    disable(s.body)


cdef inline int body_fault(const dReal* p, const dReal* q, const dReal* v, const dReal* av,
                           double extent) noexcept nogil:
    """FAULT_*_C of a body's state, or -1 when it is sane."""
    cdef int k
    cdef int why = -1
    for k in range(3):
        if not (isfinite(p[k]) and isfinite(v[k]) and isfinite(av[k])):
            why = FAULT_NONFINITE_C
    for k in range(4):
        if not isfinite(q[k]):
            why = FAULT_NONFINITE_C
    if why < 0 and (norm3(v) > MAX_SPEED or norm3(av) > MAX_SPEED):
        why = FAULT_RUNAWAY_C   # finite but runaway: the next step would overflow
    if why < 0 and (fabs(p[0]) > extent or fabs(p[1]) > extent or fabs(p[2]) > extent):
        why = FAULT_LEFT_WORLD_C
    return why


cdef inline bint plainly_sane(const dReal* p, const dReal* q, const dReal* v,
                              const dReal* av, double extent) noexcept nogil:
    """What body_fault finds -1 for nearly every body, at a fraction of its cost: one
    finite sum (a non-finite term makes it non-finite), squared speeds well inside
    MAX_SPEED (no square roots) and a position inside the world. False sends the body
    to body_fault, which decides."""
    cdef double total = (p[0] + p[1] + p[2] + q[0] + q[1] + q[2] + q[3] + v[0] + v[1] +
                         v[2] + av[0] + av[1] + av[2])
    cdef double bound = 0.98 * MAX_SPEED * MAX_SPEED
    return (isfinite(total) and v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < bound and
            av[0] * av[0] + av[1] * av[1] + av[2] * av[2] < bound and
            fabs(p[0]) <= extent and fabs(p[1]) <= extent and fabs(p[2]) <= extent)


cdef int check_bodies(World w) noexcept nogil:
    """Reset and disable bodies gone non-finite, past MAX_SPEED or out of the world
    (``w.faults`` gets slot * 4 + FAULT_*); remember every other moving body's pose as its
    last good one, so one leaving the world stops at its last pose inside."""
    cdef int i, nf = 0
    cdef Slot* s
    cdef const dReal* p
    cdef const dReal* q
    cdef const dReal* v
    cdef const dReal* av
    cdef int why
    cdef double extent = w.extent
    for i in range(w.n):
        s = &w.slots[i]
        if s.body == NULL or not dBodyIsEnabled(s.body):
            continue         # static or asleep: nothing moved
        p = dBodyGetPosition(s.body)
        q = dBodyGetQuaternion(s.body)
        v = dBodyGetLinearVel(s.body)
        av = dBodyGetAngularVel(s.body)
        why = -1 if plainly_sane(p, q, v, av, extent) else body_fault(p, q, v, av, extent)
        if why < 0:
            memcpy(&s.good[0], p, 3 * sizeof(double))
            memcpy(&s.good[3], q, 4 * sizeof(double))
        else:
            reset_slot(s)
            w.unsure = True
            w.faults[nf] = i * 4 + why
            nf += 1
    return nf
