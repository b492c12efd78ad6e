# Batches: every slot's state into a table row (BodyState's layout) and back, what the
# sleep rule reads each step and the sleep it orders, and the post-step check that puts
# non-finite or runaway bodies back where they were sane.

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


def read_motion(World w, double[:, ::1] velocity, uint8_t[::1] awake,
                uint8_t[::1] woken) -> None:
    """What the sleep rule reads after a step, per slot: centre-of-mass linear and angular
    velocity (world frame) as the columns of ``velocity`` (6, n), whether the body is
    awake, and whether it was woken explicitly since the last call (the marks are then
    cleared)."""
    cdef int i, k
    cdef Slot* s
    cdef const dReal* v
    cdef const dReal* av
    if velocity.shape[0] != 6 or velocity.shape[1] != w.n or awake.shape[0] != w.n \
            or woken.shape[0] != w.n:
        raise ValueError(f"read_motion needs (6, {w.n}) and ({w.n},) arrays")
    with nogil:
        for i in range(w.n):
            s = &w.slots[i]
            woken[i] = s.woken
            s.woken = 0
            if s.body == NULL:
                for k in range(6):
                    velocity[k, i] = 0.0
                awake[i] = 0
                continue
            v = dBodyGetLinearVel(s.body)
            av = dBodyGetAngularVel(s.body)
            for k in range(3):
                velocity[k, i] = v[k]
                velocity[3 + k, i] = av[k]
            awake[i] = dBodyIsEnabled(s.body)


def sleep_slots(World w, cnp.int64_t[::1] slots) -> None:
    """Put the bodies at ``slots`` to sleep, at rest (what the sleep rule decided)."""
    cdef Py_ssize_t i
    for i in range(slots.shape[0]):
        if not 0 <= slots[i] < w.n or w.slots[slots[i]].body == NULL:
            raise IndexError(f"sleep_slots: no moving body in slot {slots[i]}")
    with nogil:
        for i in range(slots.shape[0]):
            disable(w.slots[slots[i]].body)


def write_state(World w, cnp.int64_t[::1] slots, double[:, ::1] pos, double[:, ::1] quat,
                double[:, ::1] lin, double[:, ::1] ang) -> None:
    """Set pose and velocity of the bodies at ``slots`` (row i -> slots[i])."""
    cdef Py_ssize_t i
    for i in range(slots.shape[0]):
        set_slot_pose(w, <int>slots[i], &pos[i, 0], &quat[i, 0])
        set_slot_velocity(w, <int>slots[i], &lin[i, 0], &ang[i, 0])


cdef void reset_slot(Slot* s) noexcept nogil:
    """Put a runaway body back where it last was sane, at rest, and disable it."""
    dBodySetPosition(s.body, s.good[0], s.good[1], s.good[2])
    dBodySetQuaternion(s.body, &s.good[3])
    dBodySetForce(s.body, 0.0, 0.0, 0.0)
    dBodySetTorque(s.body, 0.0, 0.0, 0.0)
    disable(s.body)


cdef int check_bodies(World w) noexcept nogil:
    """Reset and disable bodies gone non-finite or past MAX_SPEED (their slots go in
    ``w.faults``); remember every other moving body's pose as its last good one."""
    cdef int i, k, nf = 0
    cdef Slot* s
    cdef const dReal* p
    cdef const dReal* q
    cdef const dReal* v
    cdef const dReal* av
    cdef int ok
    for i in range(w.n):
        s = &w.slots[i]
        if s.body == NULL or not dBodyIsEnabled(s.body):
            continue         # static or asleep: nothing moved
        p = dBodyGetPosition(s.body)
        q = dBodyGetQuaternion(s.body)
        v = dBodyGetLinearVel(s.body)
        av = dBodyGetAngularVel(s.body)
        ok = 1
        for k in range(3):
            if not (isfinite(p[k]) and isfinite(v[k]) and isfinite(av[k])):
                ok = 0
        for k in range(4):
            if not isfinite(q[k]):
                ok = 0
        if ok and (norm3(v) > MAX_SPEED or norm3(av) > MAX_SPEED):
            ok = 0   # finite but runaway: the next step would overflow
        if ok:
            memcpy(&s.good[0], p, 3 * sizeof(double))
            memcpy(&s.good[3], q, 4 * sizeof(double))
        else:
            reset_slot(s)
            w.faults[nf] = i
            nf += 1
    return nf
