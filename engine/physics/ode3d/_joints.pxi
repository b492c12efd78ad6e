# Joints: hinge, ball, slider, universal, hinge2, fixed, angular and linear motors, and
# the six-DOF drive (a linear and an angular motor aimed at a target pose each step).

cdef class _Drive:
    """A six-DOF drive: linear + angular velocity motors aiming a body at a target pose.

    Each step the motors ask for ``v = error / τ``: the error closes with time constant τ
    (at least the step; 0 means the step), the correction capped at ``max_speed`` and
    ``max_spin``. The motors' force and torque are bounded, so a blocked body pushes but
    never fights. With a second body the target rides on it (the relative pose at
    creation is kept) and the motors hold velocities relative to it, so its own motion is
    fed forward; without one the target is a world pose set by :func:`set_target`.
    """
    cdef dBodyID body
    cdef dBodyID other
    cdef double rel[7]       # body's COM pose in ``other``'s frame (position, quaternion)
    cdef dJointID lmotor
    cdef dJointID amotor
    cdef double target[7]
    cdef double max_force
    cdef double max_torque
    cdef double tau
    cdef double max_speed
    cdef double max_spin
    cdef double com[3]       # the body's centre of mass in its entity frame


cdef class _JointRec:
    cdef dJointID joint
    cdef int kind
    cdef double sign        # -1 where ODE's body order is the reverse of (body_a, body_b)
    cdef public object bodies   # (key_a, key_b or None)
    cdef _Drive drive


cdef void relative_pose(dBodyID base, dBodyID body, double* out) noexcept nogil:
    """``body``'s pose in ``base``'s frame: out = (R_b^T (p - p_b), q_b* q)."""
    cdef const dReal* pb = dBodyGetPosition(base)
    cdef const dReal* qb = dBodyGetQuaternion(base)
    cdef const dReal* p = dBodyGetPosition(body)
    cdef double conj[4]
    cdef double d[3]
    conj[0] = qb[0]
    conj[1] = -qb[1]
    conj[2] = -qb[2]
    conj[3] = -qb[3]
    d[0] = p[0] - pb[0]
    d[1] = p[1] - pb[1]
    d[2] = p[2] - pb[2]
    qrotate(conj, d, out)
    qmul(conj, dBodyGetQuaternion(body), &out[3])


def create_joint(World w, key, int kind, key_a, key_b, anchor, axis, axis2, low, high,
                 double velocity, double max_force, ref_a=None, ref_b=None) -> None:
    """Create a joint between two bodies (``key_b`` None or static: the world).

    ``ref_a``/``ref_b`` (entity poses x y z w x y z, or None: where the body is) are
    the poses the bodies had when the joint was first made: the joint is made as if
    they were there, so a saved state re-creates it exactly.
    """
    cdef dBodyID ba = NULL
    cdef dBodyID bb = NULL
    cdef dJointID j = NULL
    cdef dReal a1[3]
    cdef dReal a2[3]
    cdef _JointRec rec
    cdef _Drive d
    cdef double sign = 1.0
    w.check()
    if key in w.joints:
        raise ValueError(f"joint {key} already exists")
    cdef int ia = w.slot(key_a)
    cdef int ib = -1 if key_b is None else w.slot(key_b)
    cdef int ia0 = ia
    cdef int ib0 = ib
    ba = w.slots[ia].body
    if ib >= 0:
        bb = w.slots[ib].body
    if ba == NULL and bb != NULL:
        ba = bb
        bb = NULL
        ia = ib
    if ba == NULL:
        raise ValueError("a joint needs at least one non-static body")
    # ODE fixes the joint's body-frame anchors, axes and reference rotation from where
    # the bodies are now: make them where they were when the joint was first made.
    cdef double saved[14]
    cdef int moved_a = 0
    cdef int moved_b = 0
    for ref in (ref_a, ref_b):
        if ref is not None and len(ref) != 7:
            raise ValueError(f"a reference pose is 7 numbers (x y z w x y z), got {ref!r}")
    if ref_a is not None and w.slots[ia0].body != NULL:
        moved_a = place(w, ia0, ref_a, saved)
    if ref_b is not None and ib0 >= 0 and w.slots[ib0].body != NULL:
        moved_b = place(w, ib0, ref_b, &saved[7])
    try:
        for k in range(3):
            a1[k] = axis[k]
            a2[k] = axis2[k]
        if kind == JOINT_HINGE:
            j = dJointCreateHinge(w.world, NULL)
            dJointAttach(j, ba, bb)
            dJointSetHingeAnchor(j, anchor[0], anchor[1], anchor[2])
            dJointSetHingeAxis(j, a1[0], a1[1], a1[2])
        elif kind == JOINT_BALL:
            j = dJointCreateBall(w.world, NULL)
            dJointAttach(j, ba, bb)
            dJointSetBallAnchor(j, anchor[0], anchor[1], anchor[2])
        elif kind == JOINT_SLIDER:
            j = dJointCreateSlider(w.world, NULL)
            dJointAttach(j, ba, bb)
            dJointSetSliderAxis(j, a1[0], a1[1], a1[2])
        elif kind == JOINT_UNIVERSAL:
            j = dJointCreateUniversal(w.world, NULL)
            dJointAttach(j, ba, bb)
            dJointSetUniversalAnchor(j, anchor[0], anchor[1], anchor[2])
            dJointSetUniversalAxis1(j, a1[0], a1[1], a1[2])
            dJointSetUniversalAxis2(j, a2[0], a2[1], a2[2])
        elif kind == JOINT_HINGE2:
            j = dJointCreateHinge2(w.world, NULL)
            # ODE's hinge2 turns axis 1 (steering) with body 1 and axis 2 (spin) with
            # body 2: the chassis (body_b) goes first, the wheel (body_a) second.
            if bb != NULL:
                dJointAttach(j, bb, ba)
                sign = -1.0
            else:
                dJointAttach(j, ba, NULL)
            dJointSetHinge2Anchor(j, anchor[0], anchor[1], anchor[2])
            dJointSetHinge2Axes(j, a1, a2)
        elif kind == JOINT_FIXED:
            j = dJointCreateFixed(w.world, NULL)
            dJointAttach(j, ba, bb)
            dJointSetFixed(j)
        elif kind == JOINT_AMOTOR:
            j = dJointCreateAMotor(w.world, NULL)
            dJointAttach(j, ba, bb)
            dJointSetAMotorMode(j, dAMotorUser)
            dJointSetAMotorNumAxes(j, 1)
            dJointSetAMotorAxis(j, 0, 1, a1[0], a1[1], a1[2])
        elif kind == JOINT_LMOTOR:
            j = dJointCreateLMotor(w.world, NULL)
            dJointAttach(j, ba, bb)
            dJointSetLMotorNumAxes(j, 1)
            dJointSetLMotorAxis(j, 0, 1, a1[0], a1[1], a1[2])
        elif kind == JOINT_SIX_DOF:
            d = _Drive()
            d.body = ba
            d.lmotor = dJointCreateLMotor(w.world, NULL)
            dJointAttach(d.lmotor, ba, bb)
            dJointSetLMotorNumAxes(d.lmotor, 3)
            d.amotor = dJointCreateAMotor(w.world, NULL)
            dJointAttach(d.amotor, ba, bb)
            dJointSetAMotorMode(d.amotor, dAMotorUser)
            dJointSetAMotorNumAxes(d.amotor, 3)
            for k in range(3):
                dJointSetLMotorAxis(d.lmotor, k, 0, k == 0, k == 1, k == 2)
                dJointSetAMotorAxis(d.amotor, k, 0, k == 0, k == 1, k == 2)
            memcpy(&d.target[0], dBodyGetPosition(ba), 3 * sizeof(double))
            memcpy(&d.target[3], dBodyGetQuaternion(ba), 4 * sizeof(double))
            d.max_force = max_force
            d.max_torque = max_force
            d.tau = 0.0
            d.max_speed = MAX_SPEED
            d.max_spin = MAX_SPEED
            memcpy(d.com, w.slots[ia].com, 3 * sizeof(double))
            d.other = bb
            if bb != NULL:
                relative_pose(bb, ba, d.rel)
            j = d.lmotor
        else:
            raise ValueError(f"unknown joint kind {kind}")
    finally:
        if moved_a:
            dBodySetPosition(w.slots[ia0].body, saved[0], saved[1], saved[2])
            dBodySetQuaternion(w.slots[ia0].body, &saved[3])
        if moved_b:
            dBodySetPosition(w.slots[ib0].body, saved[7], saved[8], saved[9])
            dBodySetQuaternion(w.slots[ib0].body, &saved[10])
    rec = _JointRec()
    rec.joint = j
    rec.kind = kind
    rec.sign = sign
    rec.bodies = (key_a, key_b)
    rec.drive = d if kind == JOINT_SIX_DOF else None
    w.joints[key] = rec
    if sign < 0.0:
        low, high = (None if high is None else -high), (None if low is None else -low)
    if kind not in (JOINT_BALL, JOINT_FIXED, JOINT_SIX_DOF):
        if low is not None:
            joint_param(rec, dParamLoStop, low)
        if high is not None:
            joint_param(rec, dParamHiStop, high)
        if max_force > 0.0:
            set_motor(w, key, velocity, max_force)


cdef int place(World w, int i, ref, double* saved) except -1:
    """Put slot ``i``'s body at entity pose ``ref`` the way create_body and finish_body
    do (bit for bit); 1 and its former raw pose in ``saved`` if that moved it."""
    cdef Slot* s = &w.slots[i]
    cdef const dReal* cp = dBodyGetPosition(s.body)
    cdef const dReal* cq = dBodyGetQuaternion(s.body)
    cdef double q[4]
    cdef double qo[4]
    cdef double p[3]
    cdef double wc[3]
    cdef int k
    for k in range(4):
        q[k] = ref[3 + k]
    qnormalize(q)
    memcpy(qo, q, 4 * sizeof(double))
    dNormalize4(qo)      # what dBodySetQuaternion will make of q
    for k in range(3):
        p[k] = ref[k]
    if s.com[0] != 0.0 or s.com[1] != 0.0 or s.com[2] != 0.0:
        qrotate(qo, s.com, wc)
        for k in range(3):
            p[k] = p[k] + wc[k]
    if memcmp(p, cp, 3 * sizeof(double)) == 0 and memcmp(qo, cq, 4 * sizeof(double)) == 0:
        return 0         # already there (a joint made with its bodies): touch nothing
    memcpy(saved, cp, 3 * sizeof(double))
    memcpy(&saved[3], cq, 4 * sizeof(double))
    dBodySetPosition(s.body, p[0], p[1], p[2])
    dBodySetQuaternion(s.body, q)
    return 1


cdef void joint_param(_JointRec rec, int param, double value):
    cdef dJointID j = rec.joint
    if rec.kind == JOINT_HINGE:
        dJointSetHingeParam(j, param, value)
    elif rec.kind == JOINT_SLIDER:
        dJointSetSliderParam(j, param, value)
    elif rec.kind == JOINT_UNIVERSAL:
        dJointSetUniversalParam(j, param, value)
    elif rec.kind == JOINT_HINGE2:
        dJointSetHinge2Param(j, param, value)
    elif rec.kind == JOINT_AMOTOR:
        dJointSetAMotorParam(j, param, value)
    elif rec.kind == JOINT_LMOTOR:
        dJointSetLMotorParam(j, param, value)


cdef _JointRec joint_of(World w, key):
    try:
        return w.joints[key]
    except KeyError:
        raise KeyError(f"no joint with key {key}") from None


def set_motor(World w, key, double velocity, double max_force) -> None:
    """Drive the joint's motor axis (hinge2: the second, wheel axis) at ``velocity``."""
    cdef _JointRec rec = joint_of(w, key)
    if not (fabs(velocity) <= MAX_SPEED and max_force >= 0.0):
        raise ValueError(f"joint {key}: motor velocity must be within {MAX_SPEED:g} and "
                         f"max force >= 0, got {velocity}, {max_force}")
    if rec.kind == JOINT_HINGE2:
        joint_param(rec, dParamVel2, rec.sign * velocity)
        joint_param(rec, dParamFMax2, max_force)
    elif rec.kind in (JOINT_BALL, JOINT_FIXED, JOINT_SIX_DOF):
        raise ValueError("this joint kind has no motor")
    else:
        joint_param(rec, dParamVel, velocity)
        joint_param(rec, dParamFMax, max_force)
    wake_joint(w, rec)


cdef void wake_joint(World w, _JointRec rec):
    cdef dBodyID b
    for k in rec.bodies:
        if k is not None and k in w.slot_of:
            b = w.slots[w.slot_of[k]].body
            if b != NULL:
                wake(w, b)


def joint_state(World w, key) -> tuple:
    cdef _JointRec rec = joint_of(w, key)
    cdef dJointID j = rec.joint
    if rec.kind == JOINT_HINGE:
        return dJointGetHingeAngle(j), dJointGetHingeAngleRate(j)
    if rec.kind == JOINT_SLIDER:
        return dJointGetSliderPosition(j), dJointGetSliderPositionRate(j)
    if rec.kind == JOINT_UNIVERSAL:
        return dJointGetUniversalAngle1(j), dJointGetUniversalAngle1Rate(j)
    if rec.kind == JOINT_HINGE2:
        return rec.sign * dJointGetHinge2Angle1(j), rec.sign * dJointGetHinge2Angle1Rate(j)
    return 0.0, 0.0


def set_target(World w, key, double[::1] pos, double[::1] quat, double max_force,
               double max_torque) -> None:
    cdef _JointRec rec = joint_of(w, key)
    cdef _Drive d = rec.drive
    if d is None:
        raise ValueError(f"joint {key} is not a six_dof joint")
    if d.other != NULL:
        raise ValueError(f"six_dof joint {key} follows its body_b; move that body instead")
    cdef double wc[3]
    cdef int k
    for k in range(4):
        d.target[3 + k] = quat[k]
    qnormalize(&d.target[3])
    qrotate(&d.target[3], d.com, wc)
    for k in range(3):
        d.target[k] = pos[k] + wc[k]
    if max_force >= 0.0:
        d.max_force = max_force
    if max_torque >= 0.0:
        d.max_torque = max_torque
    wake(w, d.body)


def set_drive_limits(World w, key, double max_force, double max_torque, double tau=-1.0,
                     double max_speed=-1.0, double max_spin=-1.0) -> None:
    """Bound a drive's force and torque; a negative time constant or cap keeps its own."""
    cdef _JointRec rec = joint_of(w, key)
    cdef _Drive d = rec.drive
    if d is None:
        raise ValueError(f"joint {key} is not a six_dof joint")
    if not (max_force >= 0.0 and max_torque >= 0.0):
        raise ValueError("six_dof force and torque bounds must be >= 0")
    d.max_force = max_force
    d.max_torque = max_torque
    if tau >= 0.0:
        d.tau = tau
    if max_speed >= 0.0:
        d.max_speed = min(max_speed, MAX_SPEED)
    if max_spin >= 0.0:
        d.max_spin = min(max_spin, MAX_SPEED)
    wake(w, d.body)


cdef inline void capped(double* v, double cap) noexcept nogil:
    """Scale ``v`` (3) down to length ``cap`` if it is longer."""
    cdef double n = norm3(v)
    cdef int k
    if n > cap:
        for k in range(3):
            v[k] *= cap / n


cdef void drive_joints(World w, double dt):
    """Aim every six-DOF drive: v = error / τ (capped), force bounded. The motors hold the
    body's velocity relative to ``other`` when there is one, so the target body's own
    motion is fed forward by the constraint itself."""
    cdef _Drive d
    cdef _JointRec rec
    cdef const dReal* p
    cdef double rv[3]
    cdef double lin[3]
    cdef double tau
    cdef int k
    for obj in w.joints.values():
        rec = <_JointRec>obj
        if rec.drive is None:
            continue
        d = rec.drive
        tau = max(d.tau, dt)
        if d.other != NULL:
            qmul(dBodyGetQuaternion(d.other), &d.rel[3], &d.target[3])
            qrotate(dBodyGetQuaternion(d.other), d.rel, d.target)
            p = dBodyGetPosition(d.other)
            for k in range(3):
                d.target[k] += p[k]
        p = dBodyGetPosition(d.body)
        for k in range(3):
            lin[k] = (d.target[k] - p[k]) / tau
        capped(lin, d.max_speed)
        rotvec_between(dBodyGetQuaternion(d.body), &d.target[3], rv)
        for k in range(3):
            rv[k] /= tau
        capped(rv, d.max_spin)
        dJointSetLMotorParam(d.lmotor, dParamVel, clamp_speed(lin[0]))
        dJointSetLMotorParam(d.lmotor, dParamVel2, clamp_speed(lin[1]))
        dJointSetLMotorParam(d.lmotor, dParamVel3, clamp_speed(lin[2]))
        dJointSetAMotorParam(d.amotor, dParamVel, clamp_speed(rv[0]))
        dJointSetAMotorParam(d.amotor, dParamVel2, clamp_speed(rv[1]))
        dJointSetAMotorParam(d.amotor, dParamVel3, clamp_speed(rv[2]))
        for k in range(3):
            dJointSetLMotorParam(d.lmotor, dParamFMax + 0x100 * k, d.max_force)
            dJointSetAMotorParam(d.amotor, dParamFMax + 0x100 * k, d.max_torque)


cdef void free_joint(_JointRec rec) noexcept:
    if rec.drive is not None:
        dJointDestroy(rec.drive.lmotor)
        dJointDestroy(rec.drive.amotor)
    else:
        dJointDestroy(rec.joint)


def remove_joint(World w, key) -> None:
    cdef _JointRec rec = joint_of(w, key)
    wake_joint(w, rec)
    free_joint(rec)
    del w.joints[key]


def has_joint(World w, key) -> bool:
    return key in w.joints


def joint_bodies(World w) -> np.ndarray:
    """(M, 2) body keys of every joint (-1: the world), for the sleep rule's islands."""
    out = np.full((len(w.joints), 2), -1, np.int64)
    for row, rec in enumerate(w.joints.values()):
        a, b = (<_JointRec>rec).bodies
        out[row, 0] = a
        if b is not None:
            out[row, 1] = b
    return out
