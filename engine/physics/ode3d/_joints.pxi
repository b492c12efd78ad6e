# Joints: hinge, ball, slider, universal, hinge2, fixed, angular and linear motors, and
# the six-DOF drive (a linear and an angular motor aimed at a target pose each step).

cdef class _Drive:
    """A six-DOF drive: linear + angular velocity motors aiming a body at a target pose.

    Each step the motors ask for the velocity that leaves ``e^(-dt/τ)`` of the error after
    the step, ``v = error (1 - e^(-dt/τ)) / dt``: the error closes as e^(-t/τ) at any step
    (``error / τ`` closed it faster, by 15 % at 1/120 s and τ = 30 ms; pymunk's bias is
    the same law; 0 means all of it in one step), the correction capped at ``max_speed`` and
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


cdef class _Spring:
    """A spring-damper on a hinge's or slider's free axis: an angular or linear motor of
    one axis beside the joint (which keeps its own limits and motor) whose row each step
    is the spring ``f = -k (x + a h v - target) - d v``, ``v`` the rate after the step:
    ODE's soft row ``J v = c - cfm f`` with ``cfm = 1 / (a h k + d)`` and
    ``c = -k (x - target) cfm``. ``a`` is 0 while the spring's period is resolved
    (``k h^2 / m <= 1``, m the row's mass): its pull is the one before the step, and ODE
    moving the bodies with the new velocity makes the step symplectic, so an undamped
    spring keeps its energy; a stiffer one takes ``a`` 1, the limit-stop spring of ODE's
    manual (implicit: stable at any stiffness, it loses a little energy a period)."""
    cdef dJointID motor
    cdef double stiffness   # N m / rad or N / m
    cdef double damping     # N m s / rad or N s / m
    cdef double target      # rad or m, as joint_state counts
    cdef double max_force
    cdef double axis[3]     # the free axis in ODE's body 1


cdef class _Servo:
    """A hinge's or universal joint's own motor aimed at a moving angle each step (a
    fingered hand's joints: :func:`set_servos`). Each step the motor of axis k asks for
    ``rate + (target - angle) (1 - e^(-dt/τ)) / dt`` (the correction capped at
    ``max_spin``; the error closes as e^(-t/τ), as the six-DOF drive's does) with at most
    ``max_torque``, and the target moves on by ``rate dt``: the tracked rate is fed
    forward, a blocked joint pushes with a bounded torque and never through, and the
    angle is ODE's own (the one its limits count), read where the step starts."""
    cdef double target[2]   # rad, as ODE counts the axis' angle (0 where the joint was made)
    cdef double rate[2]     # rad/s
    cdef double max_torque  # N m
    cdef double tau         # s (0: all of the error in one step)
    cdef double max_spin    # rad/s
    cdef int axes           # 1 (hinge) or 2 (universal)


cdef class _JointRec:
    cdef dJointID joint
    cdef int kind
    cdef double sign        # -1 where ODE's body order is the reverse of (body_a, body_b)
    cdef public object bodies   # (key_a, key_b or None)
    cdef _Drive drive
    cdef _Spring spring
    cdef _Servo servo
    cdef dJointFeedback feedback  # written by each step once asked for (joint_force)
    cdef bint watched


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


cdef double min_inertia(dBodyID body) noexcept:
    """The smallest diagonal moment of inertia of ``body`` (kg m²; a kinematic body's is
    infinite): how easily it turns about its easiest axis."""
    cdef dMass m
    if dBodyIsKinematic(body):
        return 1e300
    dBodyGetMass(body, &m)
    return min(m.I[0], m.I[5], m.I[10])


cdef class _JointBuild:
    """What a joint kind's builder needs: ODE's bodies in attach order (``bb`` NULL: the
    world), the anchor and axes in world coordinates; it sets ``sign`` where it attaches
    them the other way round, and ``drive`` for the six-DOF drive."""
    cdef dWorldID world
    cdef dBodyID ba
    cdef dBodyID bb
    cdef dReal anchor[3]
    cdef dReal a1[3]
    cdef dReal a2[3]
    cdef double com[3]       # ``ba``'s centre of mass in its entity frame (the drive's)
    cdef double max_force
    cdef double sign
    cdef _Drive drive


ctypedef dJointID (*JointBuilder)(_JointBuild b) except NULL

#: One builder per joint kind, indexed by the kind (JOINT_HINGE ... JOINT_ALIGN): each
#: creates its ODE joint(s) and attaches them; create_joint does what all kinds share.
cdef JointBuilder JOINT_BUILDERS[10]


cdef dJointID build_hinge(_JointBuild b) except NULL:
    cdef dJointID j = dJointCreateHinge(b.world, NULL)
    dJointAttach(j, b.ba, b.bb)
    dJointSetHingeAnchor(j, b.anchor[0], b.anchor[1], b.anchor[2])
    dJointSetHingeAxis(j, b.a1[0], b.a1[1], b.a1[2])
    return j


cdef dJointID build_ball(_JointBuild b) except NULL:
    cdef dJointID j = dJointCreateBall(b.world, NULL)
    dJointAttach(j, b.ba, b.bb)
    dJointSetBallAnchor(j, b.anchor[0], b.anchor[1], b.anchor[2])
    return j


cdef dJointID build_slider(_JointBuild b) except NULL:
    cdef dJointID j = dJointCreateSlider(b.world, NULL)
    dJointAttach(j, b.ba, b.bb)
    dJointSetSliderAxis(j, b.a1[0], b.a1[1], b.a1[2])
    return j


cdef dJointID build_universal(_JointBuild b) except NULL:
    cdef dJointID j = dJointCreateUniversal(b.world, NULL)
    dJointAttach(j, b.ba, b.bb)
    dJointSetUniversalAnchor(j, b.anchor[0], b.anchor[1], b.anchor[2])
    set_universal_axes(j, b.a1, b.a2)
    return j


cdef dJointID build_hinge2(_JointBuild b) except NULL:
    cdef dJointID j = dJointCreateHinge2(b.world, NULL)
    # ODE's hinge2 turns axis 1 (steering) with body 1 and axis 2 (spin) with body 2:
    # the chassis (body_b) goes first, the wheel (body_a) second.
    if b.bb != NULL:
        dJointAttach(j, b.bb, b.ba)
        b.sign = -1.0
    else:
        dJointAttach(j, b.ba, NULL)
    dJointSetHinge2Anchor(j, b.anchor[0], b.anchor[1], b.anchor[2])
    dJointSetHinge2Axes(j, b.a1, b.a2)
    return j


cdef dJointID build_fixed(_JointBuild b) except NULL:
    cdef dJointID j = dJointCreateFixed(b.world, NULL)
    # ODE holds the offset between the bodies as a lever on its first body's turning; on
    # a body that turns easily (a light hand gripping a 50 kg crate: 5000 times less
    # inertia) QuickStep cannot converge and the joint stretches by many cm. The body
    # harder to turn goes first (joint_force reads either).
    if b.bb != NULL and min_inertia(b.bb) > min_inertia(b.ba):
        dJointAttach(j, b.bb, b.ba)
    else:
        dJointAttach(j, b.ba, b.bb)
    dJointSetFixed(j)
    return j


cdef dJointID build_align(_JointBuild b) except NULL:
    # ODE's angular motor in Euler mode measures the three angles between the bodies
    # from where they are now; stops at 0 on all three hold them there
    cdef dJointID j = dJointCreateAMotor(b.world, NULL)
    dJointAttach(j, b.ba, b.bb)
    dJointSetAMotorMode(j, dAMotorEuler)
    dJointSetAMotorAxis(j, 0, 1, 1.0, 0.0, 0.0)
    dJointSetAMotorAxis(j, 2, 2 if b.bb != NULL else 0, 0.0, 0.0, 1.0)
    for stop in (dParamLoStop, dParamHiStop, dParamLoStop2, dParamHiStop2,
                 dParamLoStop3, dParamHiStop3):
        dJointSetAMotorParam(j, stop, 0.0)
    return j


cdef dJointID angular_motor(dWorldID world, dBodyID ba, dBodyID bb, const dReal* axis):
    """An angular motor of one axis (fixed in body 1), user mode."""
    cdef dJointID j = dJointCreateAMotor(world, NULL)
    dJointAttach(j, ba, bb)
    dJointSetAMotorMode(j, dAMotorUser)
    dJointSetAMotorNumAxes(j, 1)
    dJointSetAMotorAxis(j, 0, 1, axis[0], axis[1], axis[2])
    return j


cdef dJointID linear_motor(dWorldID world, dBodyID ba, dBodyID bb, const dReal* axis):
    """A linear motor of one axis (fixed in body 1)."""
    cdef dJointID j = dJointCreateLMotor(world, NULL)
    dJointAttach(j, ba, bb)
    dJointSetLMotorNumAxes(j, 1)
    dJointSetLMotorAxis(j, 0, 1, axis[0], axis[1], axis[2])
    return j


cdef dJointID build_amotor(_JointBuild b) except NULL:
    return angular_motor(b.world, b.ba, b.bb, b.a1)


cdef dJointID build_lmotor(_JointBuild b) except NULL:
    return linear_motor(b.world, b.ba, b.bb, b.a1)


cdef dJointID build_six_dof(_JointBuild b) except NULL:
    """The drive: a linear and an angular motor of three world axes each, aimed at the
    body's pose now; the joint it is known by is the linear motor."""
    cdef _Drive d = _Drive()
    cdef int k
    d.body = b.ba
    d.lmotor = dJointCreateLMotor(b.world, NULL)
    dJointAttach(d.lmotor, b.ba, b.bb)
    dJointSetLMotorNumAxes(d.lmotor, 3)
    d.amotor = dJointCreateAMotor(b.world, NULL)
    dJointAttach(d.amotor, b.ba, b.bb)
    dJointSetAMotorMode(d.amotor, dAMotorUser)
    dJointSetAMotorNumAxes(d.amotor, 3)
    for k in range(3):
        dJointSetLMotorAxis(d.lmotor, k, 0, k == 0, k == 1, k == 2)
        dJointSetAMotorAxis(d.amotor, k, 0, k == 0, k == 1, k == 2)
    memcpy(&d.target[0], dBodyGetPosition(b.ba), 3 * sizeof(double))
    memcpy(&d.target[3], dBodyGetQuaternion(b.ba), 4 * sizeof(double))
    d.max_force = b.max_force
    d.max_torque = b.max_force
    d.tau = 0.0
    d.max_speed = MAX_SPEED
    d.max_spin = MAX_SPEED
    memcpy(d.com, b.com, 3 * sizeof(double))
    d.other = b.bb
    if b.bb != NULL:
        relative_pose(b.bb, b.ba, d.rel)
    b.drive = d
    return d.lmotor


JOINT_BUILDERS[JOINT_HINGE] = build_hinge
JOINT_BUILDERS[JOINT_BALL] = build_ball
JOINT_BUILDERS[JOINT_SLIDER] = build_slider
JOINT_BUILDERS[JOINT_UNIVERSAL] = build_universal
JOINT_BUILDERS[JOINT_HINGE2] = build_hinge2
JOINT_BUILDERS[JOINT_FIXED] = build_fixed
JOINT_BUILDERS[JOINT_AMOTOR] = build_amotor
JOINT_BUILDERS[JOINT_LMOTOR] = build_lmotor
JOINT_BUILDERS[JOINT_SIX_DOF] = build_six_dof
JOINT_BUILDERS[JOINT_ALIGN] = build_align
#: Kinds without an axis, limits or motor of their own.
AXISLESS = (JOINT_BALL, JOINT_FIXED, JOINT_SIX_DOF, JOINT_ALIGN)


cdef check_joint(World w, key, int kind, key_a, key_b, axis, axis2, spring):
    """Refuse what ODE would abort the process on (see _errors.pxi), at the door."""
    if key in w.joints:
        raise ValueError(f"joint {key} already exists")
    if not 0 <= kind < 10:
        raise ValueError(f"unknown joint kind {kind}")
    if spring is not None and kind not in (JOINT_HINGE, JOINT_SLIDER):
        raise ValueError(f"joint {key}: only a hinge or a slider takes a spring")
    if key_b is not None and key_b == key_a:
        raise ValueError(f"joint {key}: a joint needs two different bodies")
    if (kind not in AXISLESS and not any(axis)) or (
            kind in (JOINT_UNIVERSAL, JOINT_HINGE2) and not any(axis2)):
        raise ValueError(f"joint {key}: a zero axis")
    if kind in (JOINT_UNIVERSAL, JOINT_HINGE2):  # ODE aborts on parallel hinge2 axes
        u, v = [float(x) for x in axis], [float(x) for x in axis2]
        cross = ((u[1] * v[2] - u[2] * v[1]) ** 2 + (u[2] * v[0] - u[0] * v[2]) ** 2
                 + (u[0] * v[1] - u[1] * v[0]) ** 2)
        if cross <= 1e-12 * sum(x * x for x in u) * sum(x * x for x in v):
            raise ValueError(f"joint {key}: axis and axis2 must not be parallel")


cdef _JointBuild joint_build(World w, key, int kind, int ia, int ib, anchor, axis, axis2,
                             double max_force):
    """The builder's input: a static first body swaps with the second (ODE attaches a
    body to the world as body 1 with body 2 NULL)."""
    cdef _JointBuild b = _JointBuild()
    cdef int k
    b.world = w.world
    b.ba = w.slots[ia].body
    b.bb = w.slots[ib].body if ib >= 0 else NULL
    if b.ba == NULL and b.bb != NULL:
        b.ba = b.bb
        b.bb = NULL
        ia = ib
    if b.ba == NULL:
        raise ValueError("a joint needs at least one non-static body")
    if kind == JOINT_HINGE2 and b.bb == NULL:
        raise ValueError(f"joint {key}: a hinge2 joint needs two bodies, neither static")
    for k in range(3):
        b.anchor[k] = anchor[k]
        b.a1[k] = axis[k]
        b.a2[k] = axis2[k]
    memcpy(b.com, w.slots[ia].com, 3 * sizeof(double))
    b.max_force = max_force
    b.sign = 1.0
    b.drive = None
    return b


cdef _Spring make_spring(_JointBuild b, int kind, spring):
    """A hinge's or slider's spring: a motor along its axis, fixed in ODE's body 1 as the
    joint's own axis is."""
    cdef _Spring sp = _Spring()
    sp.stiffness, sp.damping, sp.target, sp.max_force = spring
    inverse_rotate(dBodyGetQuaternion(b.ba), b.a1, sp.axis)
    if kind == JOINT_HINGE:
        sp.motor = angular_motor(b.world, b.ba, b.bb, b.a1)
    else:
        sp.motor = linear_motor(b.world, b.ba, b.bb, b.a1)
    return sp


def create_joint(World w, key, int kind, key_a, key_b, anchor, axis, axis2, low, high,
                 double velocity, double max_force, ref_a=None, ref_b=None,
                 spring=None) -> None:
    """Create a joint between two bodies (``key_b`` None or static: the world).

    ``ref_a``/``ref_b`` (entity poses x y z w x y z, or None: where the body is) are
    the poses the bodies had when the joint was first made: the joint is made as if
    they were there, so a saved state re-creates it exactly. ``spring`` (stiffness,
    damping, target, max force; a hinge or slider) pulls its free axis to the target.
    """
    cdef dJointID j = NULL
    cdef _Spring sp = None
    cdef _JointRec rec
    w.check()
    check_joint(w, key, kind, key_a, key_b, axis, axis2, spring)
    cdef int ia = w.slot(key_a)
    cdef int ib = -1 if key_b is None else w.slot(key_b)
    cdef _JointBuild b = joint_build(w, key, kind, ia, ib, anchor, axis, axis2, max_force)
    # ODE fixes the joint's body-frame anchors, axes and reference rotation from where
    # the bodies are now: make them where they were when the joint was first made.
    cdef double saved[14]
    cdef int moved = place_refs(w, ia, ib, ref_a, ref_b, saved)
    try:
        j = JOINT_BUILDERS[kind](b)
        if spring is not None:
            sp = make_spring(b, kind, spring)
    finally:
        restore_refs(w, ia, ib, moved, saved)
    rec = _JointRec()
    rec.joint = j
    rec.kind = kind
    rec.sign = b.sign
    rec.bodies = (key_a, key_b)
    rec.drive = b.drive
    rec.spring = sp
    w.joints[key] = rec
    relink(w)
    if b.sign < 0.0:
        low, high = (None if high is None else -high), (None if low is None else -low)
    if kind not in AXISLESS:
        if low is not None:
            joint_param(rec, dParamLoStop, low)
        if high is not None:
            joint_param(rec, dParamHiStop, high)
        if max_force > 0.0:
            set_motor(w, key, velocity, max_force)


cdef int place_refs(World w, int ia, int ib, ref_a, ref_b, double* saved) except -1:
    """Put the bodies at their reference poses (:func:`place`); bit 1 set if body a moved
    (its former pose in ``saved[0:7]``), bit 2 if body b did (``saved[7:14]``)."""
    cdef int moved = 0
    for ref in (ref_a, ref_b):
        if ref is not None and len(ref) != 7:
            raise ValueError(f"a reference pose is 7 numbers (x y z w x y z), got {ref!r}")
    if ref_a is not None and w.slots[ia].body != NULL and place(w, ia, ref_a, saved):
        moved |= 1
    if (ref_b is not None and ib >= 0 and w.slots[ib].body != NULL
            and place(w, ib, ref_b, &saved[7])):
        moved |= 2
    return moved


cdef void restore_refs(World w, int ia, int ib, int moved, double* saved) noexcept:
    """Put back what :func:`place_refs` moved, bit for bit."""
    if moved & 1:
        dBodySetPosition(w.slots[ia].body, saved[0], saved[1], saved[2])
        set_quaternion_exactly(w.slots[ia].body, &saved[3])
    if moved & 2:
        dBodySetPosition(w.slots[ib].body, saved[7], saved[8], saved[9])
        set_quaternion_exactly(w.slots[ib].body, &saved[10])


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


cdef void set_universal_axes(dJointID j, const dReal* a1, const dReal* a2):
    """Both axes of a new universal joint, in an order no step of which makes an axis
    parallel to the other one's current value (ODE works out the joint's rest turn at
    each step, and says "zero length vector in dRFrom2Axes" when they are parallel: a
    hand's flexion axis along ODE's default second axis did)."""
    cdef dVector3 now
    cdef double c[3]
    dJointGetUniversalAxis1(j, now)
    c[0] = a2[1] * now[2] - a2[2] * now[1]
    c[1] = a2[2] * now[0] - a2[0] * now[2]
    c[2] = a2[0] * now[1] - a2[1] * now[0]
    if c[0] * c[0] + c[1] * c[1] + c[2] * c[2] > 1e-4:
        dJointSetUniversalAxis2(j, a2[0], a2[1], a2[2])
        dJointSetUniversalAxis1(j, a1[0], a1[1], a1[2])
        return
    # a2 lies along the current axis 1: first an axis 2 across both, then axis 1, then a2
    c[0] = a1[1] * a2[2] - a1[2] * a2[1]
    c[1] = a1[2] * a2[0] - a1[0] * a2[2]
    c[2] = a1[0] * a2[1] - a1[1] * a2[0]
    dJointSetUniversalAxis2(j, c[0], c[1], c[2])
    dJointSetUniversalAxis1(j, a1[0], a1[1], a1[2])
    dJointSetUniversalAxis2(j, a2[0], a2[1], a2[2])


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
    elif rec.kind in (JOINT_BALL, JOINT_FIXED, JOINT_SIX_DOF, JOINT_ALIGN):
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


def joint_force(World w, key) -> np.ndarray:
    """The force (N, world frame) the joint put on its body_a in the last step (a drive:
    its linear motor's). ODE measures a joint from the first time it is asked: zero
    until a step has run since."""
    cdef _JointRec rec = joint_of(w, key)
    cdef dJointID j = rec.drive.lmotor if rec.drive is not None else rec.joint
    cdef dBodyID a = NULL
    if rec.bodies[0] in w.slot_of:
        a = w.slots[w.slot_of[rec.bodies[0]]].body
    if not rec.watched:
        memset(&rec.feedback, 0, sizeof(dJointFeedback))
        dJointSetFeedback(j, &rec.feedback)
        rec.watched = True
    cdef const dReal* f = &rec.feedback.f1[0]
    cdef double s = 1.0
    if a != NULL and dJointGetBody(j, 1) == a:
        f = &rec.feedback.f2[0]
    elif a == NULL or dJointGetBody(j, 0) != a:  # body_a is the world: the other's, reversed
        s = -1.0
    return np.array([s * f[0], s * f[1], s * f[2]])


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
    """Aim every six-DOF drive: v = error (1 - e^(-dt/τ)) / dt (capped), force bounded. The
    motors hold the
    body's velocity relative to ``other`` when there is one, so the target body's own
    motion is fed forward by the constraint itself."""
    cdef _Drive d
    cdef _JointRec rec
    cdef const dReal* p
    cdef double rv[3]
    cdef double lin[3]
    cdef double rate  # the share of the error corrected per second
    cdef int k
    for obj in w.joints.values():
        rec = <_JointRec>obj
        if rec.spring is not None:
            aim_spring(rec, dt)
        if rec.servo is not None:
            aim_servo(rec, dt)
        if rec.drive is None:
            continue
        d = rec.drive
        rate = (1.0 - exp(-dt / d.tau)) / dt if d.tau > 0.0 else 1.0 / dt
        if d.other != NULL:
            qmul(dBodyGetQuaternion(d.other), &d.rel[3], &d.target[3])
            qrotate(dBodyGetQuaternion(d.other), d.rel, d.target)
            p = dBodyGetPosition(d.other)
            for k in range(3):
                d.target[k] += p[k]
        p = dBodyGetPosition(d.body)
        for k in range(3):
            lin[k] = (d.target[k] - p[k]) * rate
        capped(lin, d.max_speed)
        rotvec_between(dBodyGetQuaternion(d.body), &d.target[3], rv)
        for k in range(3):
            rv[k] *= rate
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


cdef double inverse_moment(dBodyID b, const double* n) noexcept:
    """n^T M^-1 n for a body and a world direction: its inverse mass along a line (``n``
    None) or inverse inertia about an axis; 0 for a static or kinematic body."""
    cdef dMass m
    cdef double local[3]
    cdef double a, bb, c, d, e, f, det
    if b == NULL or dBodyIsKinematic(b):
        return 0.0
    dBodyGetMass(b, &m)
    if n == NULL:
        return 1.0 / m.mass
    inverse_rotate(dBodyGetQuaternion(b), n, local)
    a, bb, c = m.I[0], m.I[1], m.I[2]   # the symmetric tensor [[a b c] [b d e] [c e f]]
    d, e, f = m.I[5], m.I[6], m.I[10]
    det = a * (d * f - e * e) - bb * (bb * f - e * c) + c * (bb * e - d * c)
    if not det > 0.0:
        return 0.0
    return (local[0] * local[0] * (d * f - e * e) + local[1] * local[1] * (a * f - c * c)
            + local[2] * local[2] * (a * d - bb * bb)
            + 2.0 * local[0] * local[1] * (c * e - bb * f)
            + 2.0 * local[0] * local[2] * (bb * e - c * d)
            + 2.0 * local[1] * local[2] * (bb * c - a * e)) / det


cdef void aim_spring(_JointRec rec, double dt) noexcept:
    """Set the spring's row for this step from where the joint is now (see _Spring)."""
    cdef _Spring sp = rec.spring
    cdef dBodyID b1 = dJointGetBody(rec.joint, 0)
    cdef dBodyID b2 = dJointGetBody(rec.joint, 1)
    cdef double n[3]
    cdef double x, inv, soft
    cdef int hinge = rec.kind == JOINT_HINGE
    qrotate(dBodyGetQuaternion(b1), sp.axis, n)
    if hinge:
        x = dJointGetHingeAngle(rec.joint)
        inv = inverse_moment(b1, n) + inverse_moment(b2, n)
    else:
        x = dJointGetSliderPosition(rec.joint)
        inv = inverse_moment(b1, NULL) + inverse_moment(b2, NULL)
    if not isfinite(x):
        return  # a body gone wrong: the step's check stops it
    soft = sp.damping
    if sp.stiffness * dt * dt * inv > 1.0:
        soft += dt * sp.stiffness   # too stiff to follow explicitly: implicit
    # undamped: a row that all but only pulls (damping of 1e-6 h k; the velocity it aims
    # at is large, but the force, (c - v) / cfm, is the spring's)
    soft = max(soft, 1e-6 * dt * sp.stiffness)
    if hinge:
        dJointSetAMotorParam(sp.motor, dParamCFM, 1.0 / soft)
        dJointSetAMotorParam(sp.motor, dParamVel, -sp.stiffness * (x - sp.target) / soft)
        dJointSetAMotorParam(sp.motor, dParamFMax, sp.max_force)
    else:
        dJointSetLMotorParam(sp.motor, dParamCFM, 1.0 / soft)
        dJointSetLMotorParam(sp.motor, dParamVel, -sp.stiffness * (x - sp.target) / soft)
        dJointSetLMotorParam(sp.motor, dParamFMax, sp.max_force)


cdef void aim_servo(_JointRec rec, double dt) noexcept:
    """Set a servo's motor rows for this step from the joint's angles now (see _Servo)."""
    cdef _Servo sv = rec.servo
    cdef double rate = (1.0 - exp(-dt / sv.tau)) / dt if sv.tau > 0.0 else 1.0 / dt
    cdef double angle, fix
    cdef int k
    for k in range(sv.axes):
        if rec.kind == JOINT_HINGE:
            angle = dJointGetHingeAngle(rec.joint)
        elif k == 0:
            angle = dJointGetUniversalAngle1(rec.joint)
        else:
            angle = dJointGetUniversalAngle2(rec.joint)
        if not isfinite(angle):
            return  # a body gone wrong: the step's check stops it
        fix = max(-sv.max_spin, min(sv.max_spin, (sv.target[k] - angle) * rate))
        joint_param(rec, dParamVel + 0x100 * k, clamp_speed(sv.rate[k] + fix))
        joint_param(rec, dParamFMax + 0x100 * k, sv.max_torque)
        sv.target[k] += sv.rate[k] * dt


def set_servos(World w, const int64_t[::1] keys, const double[:, ::1] table) -> None:
    """Aim hinges' and universal joints' motors at moving angles (see _Servo): row i of
    ``table`` is joint ``keys[i]``'s target angles (2; a hinge's second unused), their
    rates, its torque bound, time constant and spin cap. One call for every joint of
    every fingered hand each frame; the rows were checked (SetServos)."""
    cdef _JointRec rec
    cdef _Servo sv
    cdef Py_ssize_t i
    cdef int k
    cdef dBodyID b
    if table.shape[0] != keys.shape[0] or table.shape[1] != 7:
        raise ValueError(f"set_servos: {keys.shape[0]} joints need a table of "
                         f"({keys.shape[0]}, 7)")
    for i in range(keys.shape[0]):
        rec = joint_of(w, keys[i])
        if rec.kind != JOINT_HINGE and rec.kind != JOINT_UNIVERSAL:
            raise ValueError(f"joint {keys[i]}: only a hinge or a universal joint takes a "
                             "servo")
        sv = rec.servo
        if sv is None:
            sv = rec.servo = _Servo()
            sv.axes = 1 if rec.kind == JOINT_HINGE else 2
        for k in range(2):
            sv.target[k] = table[i, k]
            sv.rate[k] = table[i, 2 + k]
        sv.max_torque = table[i, 4]
        sv.tau = table[i, 5]
        sv.max_spin = min(table[i, 6], MAX_SPEED)
        for k in range(2):
            b = dJointGetBody(rec.joint, k)
            if b != NULL:
                wake(w, b)


cdef void free_joint(_JointRec rec) noexcept:
    if rec.spring is not None:
        dJointDestroy(rec.spring.motor)
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
    relink(w)


cdef void relink(World w) except *:
    """The (body, static body) pairs joints hold together, for the near callback: bodies
    joined to each other never touch (ODE's dAreConnected), and a body joined to a static
    one (a joint to ODE's world) must not touch that static body's geoms either."""
    links = []
    for rec in w.joints.values():
        a, b = (<_JointRec>rec).bodies
        if b is None or a not in w.slot_of or b not in w.slot_of:
            continue
        if w.slots[w.slot_of[b]].body == NULL:
            links.append((a, b))
        elif w.slots[w.slot_of[a]].body == NULL:
            links.append((b, a))
    free(w.ctx.linked)
    w.ctx.linked = NULL
    w.ctx.nlinked = 0
    if not links:
        return
    w.ctx.linked = <int64_t*>malloc(2 * len(links) * sizeof(int64_t))
    if w.ctx.linked == NULL:
        raise MemoryError()
    for i, (a, b) in enumerate(links):
        w.ctx.linked[2 * i] = a
        w.ctx.linked[2 * i + 1] = b
    w.ctx.nlinked = len(links)


def has_joint(World w, key) -> bool:
    return key in w.joints
