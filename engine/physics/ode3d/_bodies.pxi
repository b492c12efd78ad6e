# Bodies: slots, poses and velocities of the entity origin (ODE's body sits at the centre
# of mass), loads, and the switches for sleep, gravity and collisions.

cdef inline void wake(World w, dBodyID b) noexcept nogil:
    """Enable a body and mark it woken: an explicit wake restarts its quiet stretch."""
    dBodyEnable(b)
    w.slots[<intptr_t>dBodyGetData(b)].woken = 1


cdef void store_good(World w, int i) noexcept:
    cdef Slot* s = &w.slots[i]
    if s.body == NULL:
        return
    memcpy(&s.good[0], dBodyGetPosition(s.body), 3 * sizeof(double))
    memcpy(&s.good[3], dBodyGetQuaternion(s.body), 4 * sizeof(double))


def create_body(World w, int64_t key, int kind, double[::1] pos, double[::1] quat,
                double[::1] lin, double[::1] ang, double linear_damping,
                double angular_damping, bint gravity) -> None:
    """A body at entity pose ``pos``/``quat``; its shapes and mass follow (add_geom,
    finish_body)."""
    cdef Slot* s
    cdef dBodyID b = NULL
    cdef double q[4]
    w.check()
    if key in w.slot_of:
        raise ValueError(f"body {key} already exists")
    w.grow()
    memcpy(q, &quat[0], 4 * sizeof(double))
    qnormalize(q)
    s = &w.slots[w.n]
    memset(s, 0, sizeof(Slot))
    s.key = key
    s.kind = kind
    memcpy(s.pose, &pos[0], 3 * sizeof(double))
    memcpy(&s.pose[3], q, 4 * sizeof(double))
    if kind != KIND_STATIC:
        b = dBodyCreate(w.world)
        dBodySetPosition(b, pos[0], pos[1], pos[2])
        dBodySetQuaternion(b, q)
        dBodySetLinearVel(b, lin[0], lin[1], lin[2])
        dBodySetAngularVel(b, ang[0], ang[1], ang[2])
        dBodySetLinearDamping(b, linear_damping)
        dBodySetAngularDamping(b, angular_damping)
        dBodySetGravityMode(b, gravity)
        if kind == KIND_KINEMATIC:
            dBodySetKinematic(b)
        dBodySetData(b, <void*><intptr_t>w.n)   # slot index, for wake()
    s.body = b
    w.slot_of[key] = w.n
    cs_reset(&w.ctx.stepper, w.n)
    w.geoms.append([])
    w.pending_mass.append(bytearray(sizeof(dMass)))
    dMassSetZero(<dMass*><char*>w.pending_mass[w.n])
    w.n += 1
    store_good(w, w.n - 1)


def remove_body(World w, key) -> list:
    """Destroy a body, its geoms and the joints on it; returns the removed joint keys."""
    cdef int i = w.slot(key)
    cdef int last = w.n - 1
    gone = [jk for jk, rec in w.joints.items() if key in (<_JointRec>rec).bodies]
    for jk in gone:
        remove_joint(w, jk)
    wake_touching(w, i)
    free_geoms(w, i)
    if w.slots[i].body != NULL:
        dBodyDestroy(w.slots[i].body)
    if i != last:
        w.slots[i] = w.slots[last]
        if w.slots[i].body != NULL:
            dBodySetData(w.slots[i].body, <void*><intptr_t>i)
        w.geoms[i] = w.geoms[last]
        w.pending_mass[i] = w.pending_mass[last]
        w.slot_of[w.slots[i].key] = i
    w.geoms.pop()
    w.pending_mass.pop()
    del w.slot_of[key]
    w.n -= 1
    cs_move(&w.ctx.stepper, last, i)   # the last slot's resting standing follows it
    cs_reset(&w.ctx.stepper, last)
    return gone


def has_body(World w, key) -> bool:
    return key in w.slot_of


def body_count(World w) -> int:
    return w.n


def keys(World w) -> np.ndarray:
    """Body keys in slot order (the rows of every batch read)."""
    cdef cnp.ndarray[cnp.int64_t, ndim=1] out = np.empty(w.n, np.int64)
    cdef int i
    for i in range(w.n):
        out[i] = w.slots[i].key
    return out


def kinds(World w) -> np.ndarray:
    """Each slot's body kind (BODY_DYNAMIC, BODY_STATIC, BODY_KINEMATIC)."""
    cdef cnp.ndarray[cnp.int8_t, ndim=1] out = np.empty(w.n, np.int8)
    cdef int i
    for i in range(w.n):
        out[i] = w.slots[i].kind
    return out


def slots_for(World w, keys) -> np.ndarray:
    """Slot index of every key (KeyError naming the first unknown one)."""
    slot_of = w.slot_of
    try:
        return np.fromiter((slot_of[k] for k in keys.tolist()), np.int64, len(keys))
    except KeyError as exc:
        raise KeyError(f"no body with key {exc.args[0]}") from None


# -- poses and velocities ---------------------------------------------------------------
cdef void set_quaternion_exactly(dBodyID b, const double* q) noexcept:
    """Give ``b`` the unit quaternion ``q`` to the bit (one ODE made: a body put back where
    it was), which dBodySetQuaternion's normalisation alone may move by an ulp."""
    cdef double c[4]
    quat_preimage(q, c)
    dBodySetQuaternion(b, c)


cdef void set_slot_pose(World w, int i, const double* pos, const double* quat,
                        bint wake_others=True) noexcept:
    cdef Slot* s = &w.slots[i]
    cdef double q[4]
    cdef double wc[3]
    memcpy(q, quat, 4 * sizeof(double))
    qnormalize(q)
    s.target_left = 0.0  # put somewhere else: no longer on its way to a target
    if wake_others:
        wake_touching(w, i)  # what it held up where it was
    if s.body == NULL:
        memcpy(s.pose, pos, 3 * sizeof(double))
        memcpy(&s.pose[3], q, 4 * sizeof(double))
        for entry in w.geoms[i]:
            place_static_geom(s, entry)
        return
    dBodySetQuaternion(s.body, q)
    qrotate(dBodyGetQuaternion(s.body), s.com, wc)  # the turn it has (ODE normalises too)
    dBodySetPosition(s.body, pos[0] + wc[0], pos[1] + wc[1], pos[2] + wc[2])
    wake(w, s.body)


cdef void set_slot_velocity(World w, int i, const double* lin, const double* ang) noexcept:
    """Entity-origin velocities -> COM velocity (v_com = v + w x R c)."""
    cdef Slot* s = &w.slots[i]
    cdef double wc[3]
    s.target_left = 0.0  # moving as told now, not toward a target
    if s.body == NULL:
        return
    qrotate(dBodyGetQuaternion(s.body), s.com, wc)
    dBodySetLinearVel(s.body, lin[0] + (ang[1] * wc[2] - ang[2] * wc[1]),
                      lin[1] + (ang[2] * wc[0] - ang[0] * wc[2]),
                      lin[2] + (ang[0] * wc[1] - ang[1] * wc[0]))
    dBodySetAngularVel(s.body, ang[0], ang[1], ang[2])
    wake(w, s.body)


def set_pose(World w, key, double[::1] pos, double[::1] quat) -> None:
    set_slot_pose(w, w.slot(key), &pos[0], &quat[0])


def set_velocity(World w, key, double[::1] lin, double[::1] ang) -> None:
    set_slot_velocity(w, w.slot(key), &lin[0], &ang[0])


def set_pose_values(World w, key, double x, double y, double z, double qw, double qx,
                    double qy, double qz) -> None:
    """``set_pose`` from seven numbers, checked finite here: a tracked body moved every
    step pays no array building (ValueError when one is not finite)."""
    cdef double pos[3]
    cdef double q[4]
    pos[0], pos[1], pos[2] = x, y, z
    q[0], q[1], q[2], q[3] = qw, qx, qy, qz
    if not (isfinite(x + y + z) and isfinite(qw + qx + qy + qz)):
        raise ValueError("a pose must be finite numbers")
    set_slot_pose(w, w.slot(key), pos, q)


def set_velocity_values(World w, key, double vx, double vy, double vz, double wx,
                        double wy, double wz) -> None:
    """``set_velocity`` from six numbers, checked finite and under MAX_SPEED here
    (ValueError otherwise)."""
    cdef double lin[3]
    cdef double ang[3]
    lin[0], lin[1], lin[2] = vx, vy, vz
    ang[0], ang[1], ang[2] = wx, wy, wz
    if not (sqrt(vx * vx + vy * vy + vz * vz) <= MAX_SPEED
            and sqrt(wx * wx + wy * wy + wz * wz) <= MAX_SPEED):  # NaN fails too
        raise ValueError("velocities must be finite and under MAX_SPEED")
    set_slot_velocity(w, w.slot(key), lin, ang)


def aim_kinematic(World w, key, double[::1] pos, double[::1] quat, double[::1] lin,
                  double[::1] ang, double dt) -> None:
    """Give a body the velocities ``lin``/``ang`` that carry it to ``pos``/``quat`` in
    ``dt`` s. A kinematic one is then put exactly there and stopped by the step that
    reaches it (``kinematic_arrive``), unless another command moves it first."""
    cdef int i = w.slot(key)
    cdef Slot* s = &w.slots[i]
    set_slot_velocity(w, i, &lin[0], &ang[0])
    if s.kind != KIND_KINEMATIC or not dt > 0.0:
        return
    memcpy(s.target, &pos[0], 3 * sizeof(double))
    memcpy(&s.target[3], &quat[0], 4 * sizeof(double))
    qnormalize(&s.target[3])
    s.target_left = dt


#: A target this close to its time (a share of the step) counts as reached this step:
#: a sum of steps meets a target's time only to rounding.
cdef double ARRIVE_SLACK = 1e-6


cdef void kinematic_lead(World w, double dt) noexcept nogil:
    """Bodies whose target is due within this step slow down to arrive with it, not past."""
    cdef int i
    cdef Slot* s
    cdef double f
    cdef const dReal* v
    for i in range(w.n):
        s = &w.slots[i]
        if s.target_left > 0.0 and s.target_left < dt * (1.0 - ARRIVE_SLACK):
            f = s.target_left / dt
            v = dBodyGetLinearVel(s.body)
            dBodySetLinearVel(s.body, v[0] * f, v[1] * f, v[2] * f)
            v = dBodyGetAngularVel(s.body)
            dBodySetAngularVel(s.body, v[0] * f, v[1] * f, v[2] * f)


cdef void kinematic_arrive(World w, double dt) noexcept nogil:
    """Bodies whose target was due in this step: exactly at it, at rest."""
    cdef int i
    cdef Slot* s
    cdef double wc[3]
    for i in range(w.n):
        s = &w.slots[i]
        if s.target_left <= 0.0:
            continue
        s.target_left -= dt
        if s.target_left > dt * ARRIVE_SLACK:
            continue
        s.target_left = 0.0
        qrotate(&s.target[3], s.com, wc)
        dBodySetPosition(s.body, s.target[0] + wc[0], s.target[1] + wc[1],
                         s.target[2] + wc[2])
        dBodySetQuaternion(s.body, &s.target[3])
        dBodySetLinearVel(s.body, 0.0, 0.0, 0.0)
        dBodySetAngularVel(s.body, 0.0, 0.0, 0.0)


def pose(World w, key) -> tuple:
    """(position, orientation) of one body's entity frame."""
    cdef double out[13]
    read_slot(w, w.slot(key), out)
    return np.array([out[0], out[1], out[2]]), np.array([out[3], out[4], out[5], out[6]])


# -- loads ------------------------------------------------------------------------------
cdef dBodyID body_of(World w, key) except? NULL:
    return w.slots[w.slot(key)].body


cdef void check_load(World w, key, dBodyID b) except *:
    """Refuse a force or torque that would fling the body past MAX_SPEED in one step.

    ODE aborts the process on a non-finite quaternion, so absurd loads are
    stopped at the door (the accumulators are cleared) rather than in the step.
    """
    cdef dMass m
    cdef double inertia
    dBodyGetMass(b, &m)
    inertia = min(m.I[0], min(m.I[5], m.I[10]))
    if (norm3(dBodyGetForce(b)) * w.last_dt < MAX_SPEED * m.mass
            and norm3(dBodyGetTorque(b)) * w.last_dt < MAX_SPEED * inertia):
        return
    dBodySetForce(b, 0.0, 0.0, 0.0)
    dBodySetTorque(b, 0.0, 0.0, 0.0)
    raise ValueError(f"body {key}: force or torque would push it past "
                     f"{MAX_SPEED:g} m/s (or rad/s) in one step; load discarded")


def add_force(World w, key, double fx, double fy, double fz, point=None) -> None:
    cdef dBodyID b = body_of(w, key)
    if b == NULL or dBodyIsKinematic(b):
        return
    wake(w, b)
    if point is None:
        dBodyAddForce(b, fx, fy, fz)
    else:
        dBodyAddForceAtPos(b, fx, fy, fz, point[0], point[1], point[2])
    check_load(w, key, b)


def add_torque(World w, key, double tx, double ty, double tz) -> None:
    cdef dBodyID b = body_of(w, key)
    if b == NULL or dBodyIsKinematic(b):
        return
    wake(w, b)
    dBodyAddTorque(b, tx, ty, tz)
    check_load(w, key, b)


def add_impulse(World w, key, double ix, double iy, double iz, point=None) -> None:
    """Impulse as the force that delivers it over the next step (of the last step's dt)."""
    cdef dVector3 f
    dWorldImpulseToForce(w.world, w.last_dt, ix, iy, iz, f)
    add_force(w, key, f[0], f[1], f[2], point)


# -- switches ---------------------------------------------------------------------------
cdef inline void disable(dBodyID b) noexcept nogil:
    """Asleep, at rest: a sleeping body reports zero velocity (stepper.h)."""
    cs_disable(b)


def set_sleeping(World w, key, bint sleeping) -> None:
    """Put a dynamic body to sleep at rest, or wake it (an explicit wake)."""
    cdef dBodyID b = body_of(w, key)
    if b == NULL or w.slots[w.slot(key)].kind != KIND_DYNAMIC:
        return
    if sleeping:
        disable(b)
        w.unsure = True
    else:
        wake(w, b)


def restore_sleeping(World w, key, bint sleeping) -> None:
    """Asleep or awake as a saved state says. Not a wake, and neither were the wakes
    that making the saved state's bodies and joints caused: every mark is dropped."""
    cdef int i
    cdef int slot = w.slot(key)
    cdef dBodyID b = w.slots[slot].body
    for i in range(w.n):
        w.slots[i].woken = 0
    w.unsure = True
    if b == NULL or w.slots[slot].kind != KIND_DYNAMIC:
        return
    if sleeping:
        disable(b)
    else:
        dBodyEnable(b)


def wake_all(World w) -> None:
    """Every body awake (sleeping turned off); not counted as explicit wakes."""
    cdef int i
    for i in range(w.n):
        if w.slots[i].body != NULL:
            dBodyEnable(w.slots[i].body)
            w.slots[i].woken = 0


def is_sleeping(World w, key) -> bool:
    cdef dBodyID b = body_of(w, key)
    return b != NULL and not dBodyIsEnabled(b)


def sleeping_count(World w) -> int:
    cdef int i, c = 0
    for i in range(w.n):
        if w.slots[i].body != NULL and not dBodyIsEnabled(w.slots[i].body):
            c += 1
    return c


def set_gravity(World w, key, bint enabled) -> None:
    cdef dBodyID b = body_of(w, key)
    if b == NULL:
        return
    dBodySetGravityMode(b, enabled)
    wake(w, b)


def add_scaled_gravity(World w, int64_t[::1] keys, double[::1] factors, double gx, double gy,
                       double gz) -> None:
    """Gravity times ``factors - 1`` on each body (mass times g): with ODE's own gravity,
    gravity times the factor (KHR's gravityFactor). Bodies asleep, kinematic or with
    gravity off get nothing, and nothing is woken."""
    cdef int k
    cdef dBodyID b
    cdef dMass m
    cdef double f
    for k in range(keys.shape[0]):
        if keys[k] not in w.slot_of:
            continue
        b = w.slots[w.slot_of[keys[k]]].body
        if b == NULL or dBodyIsKinematic(b) or not dBodyIsEnabled(b) or \
                not dBodyGetGravityMode(b):
            continue
        dBodyGetMass(b, &m)
        f = (factors[k] - 1.0) * m.mass
        dBodyAddForce(b, f * gx, f * gy, f * gz)


def set_collision(World w, key, bint enabled) -> None:
    """Every geom of the body in or out of collision (ODE skips disabled geoms in
    dSpaceCollide and ray casts); the body itself moves on."""
    cdef int i = w.slot(key)
    cdef dGeomID g
    if not enabled:
        wake_touching(w, i)  # what rests on it falls through
    for entry in w.geoms[i]:
        g = <dGeomID><size_t>entry[0]
        if enabled:
            dGeomEnable(g)
        else:
            dGeomDisable(g)
    if w.slots[i].body != NULL:
        wake(w, w.slots[i].body)


def sleeping(World w) -> np.ndarray:
    """Per slot, whether a moving body is asleep (disabled) now."""
    cdef cnp.ndarray[cnp.uint8_t, ndim=1] out = np.zeros(w.n, np.uint8)
    cdef int i
    for i in range(w.n):
        if w.slots[i].body != NULL:
            out[i] = not dBodyIsEnabled(w.slots[i].body)
    return out.view(bool)


def rest_standing(World w) -> tuple:
    """Per slot, the resting preload's standing (stepper.h): steps held up at rest (0 to
    2), whether it slid while preloaded, the averaged force its contacts hold it with
    (n, 3), N, and whether it was preloaded at the last step."""
    cdef cnp.ndarray[cnp.int8_t, ndim=1] steps = np.zeros(w.n, np.int8)
    cdef cnp.ndarray[cnp.uint8_t, ndim=1] slid = np.zeros(w.n, np.uint8)
    cdef cnp.ndarray[cnp.uint8_t, ndim=1] preloaded = np.zeros(w.n, np.uint8)
    cdef cnp.ndarray[cnp.float64_t, ndim=2] held = np.zeros((w.n, 3))
    cdef int i, k
    for i in range(min(w.n, w.ctx.stepper.capbodies)):
        steps[i] = w.ctx.stepper.bodies[i].resting
        slid[i] = w.ctx.stepper.bodies[i].slid
        preloaded[i] = w.ctx.stepper.bodies[i].preloaded
        for k in range(3):
            held[i, k] = w.ctx.stepper.bodies[i].held[k]
    return steps, slid.view(bool), held, preloaded.view(bool)


def set_rest_standing(World w, key, int steps, bint slid, double[::1] held,
                      bint preloaded) -> None:
    """Put a body's resting standing back (a saved state's)."""
    cdef int i = w.slot(key), k
    if not 0 <= steps <= 2:
        raise ValueError(f"body {key}: rest steps must be 0, 1 or 2, got {steps}")
    if w.ctx.stepper.capbodies <= i and cs_begin(&w.ctx.stepper, w.n) < 0:
        raise MemoryError()
    w.ctx.stepper.bodies[i].resting = steps
    w.ctx.stepper.bodies[i].slid = slid
    w.ctx.stepper.bodies[i].preloaded = preloaded
    for k in range(3):
        w.ctx.stepper.bodies[i].held[k] = held[k]
