# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Private raw binding over libode (0.16, double precision).

Everything that runs per step or per body lives here, in C: the near callback
that filters pairs and creates contact joints, the step itself (with the GIL
released), contact feedback, the non-finite check, batch state reads and writes
and the six-DOF drives. The typed, user-facing layer is ``engine.physics.ode3d``.

Bodies sit in a dense slot table (removal swaps the last slot in), so batch
reads are one C loop over ``n`` slots. A body's geoms carry a small ``GeomInfo``
(key, material, collision bits) that the near callback reads without Python.

Auto-sleep is ODE's auto-disable rule run by us (ODE's own is off), on counters
kept in our ``Rest`` table beside the slots, so a saved state can carry them:
each step, after collision and before QuickStep (where ODE runs its rule), every
awake body that may sleep and touches something (a joint or a contact) records
its linear and angular velocity; once the mean of its last ``SLEEP_SAMPLES``
samples stays within 0.05 m/s and 0.05 rad/s for ``SLEEP_STEPS`` steps in a row
it is disabled with its velocities zeroed. Waking (ODE re-enables a body that an
awake one touches; forces, poses, motors) works as before, and every explicit
wake restarts the count, as ``dBodyEnable`` does in ODE. One difference from
ODE: the mean adds the samples oldest first (ODE adds them in ring order), so the
samples saved oldest first reproduce it bit for bit.
"""

cimport cython
from libc.math cimport INFINITY, atan2, fabs, isfinite, sqrt
from libc.stdint cimport int64_t, intptr_t, uint32_t
from libc.stdlib cimport calloc, free, malloc, realloc
from libc.string cimport memcmp, memcpy, memset



cdef extern from "stdarg.h":
    ctypedef struct va_list:
        pass


cdef extern from "ode/ode.h" nogil:
    ctypedef double dReal
    ctypedef dReal dVector3[4]
    ctypedef dReal dMatrix3[12]
    ctypedef dReal dQuaternion[4]
    ctypedef uint32_t dTriIndex

    cdef struct dxWorld
    cdef struct dxSpace
    cdef struct dxBody
    cdef struct dxGeom
    cdef struct dxJoint
    cdef struct dxJointGroup
    cdef struct dxTriMeshData
    ctypedef dxWorld* dWorldID
    ctypedef dxSpace* dSpaceID
    ctypedef dxBody* dBodyID
    ctypedef dxGeom* dGeomID
    ctypedef dxJoint* dJointID
    ctypedef dxJointGroup* dJointGroupID
    ctypedef dxTriMeshData* dTriMeshDataID

    ctypedef struct dMass:
        dReal mass
        dVector3 c
        dMatrix3 I

    ctypedef struct dSurfaceParameters:
        int mode
        dReal mu, mu2, rho, rho2, rhoN, bounce, bounce_vel, soft_erp, soft_cfm
        dReal motion1, motion2, motionN, slip1, slip2

    ctypedef struct dContactGeom:
        dVector3 pos
        dVector3 normal
        dReal depth
        dGeomID g1
        dGeomID g2
        int side1, side2

    ctypedef struct dContact:
        dSurfaceParameters surface
        dContactGeom geom
        dVector3 fdir1

    ctypedef struct dJointFeedback:
        dVector3 f1
        dVector3 t1
        dVector3 f2
        dVector3 t2

    ctypedef void dNearCallback(void* data, dGeomID o1, dGeomID o2) noexcept nogil
    ctypedef void dMessageFunction(int errnum, const char* msg, va_list ap) noexcept nogil

    enum:
        dContactBounce, dContactSoftERP, dContactSoftCFM, dContactApprox1
        dJointTypeContact
        dAllocateMaskAll
        dAMotorUser
        dParamLoStop, dParamHiStop, dParamVel, dParamFMax
        dParamLoStop2, dParamHiStop2, dParamVel2, dParamFMax2
        dParamVel3, dParamFMax3

    int dInitODE2(unsigned int flags)
    int dAllocateODEDataForThread(unsigned int mask)
    void dSetMessageHandler(dMessageFunction* fn)
    void dRandSetSeed(unsigned long s)
    unsigned long dRandGetSeed()

    dWorldID dWorldCreate()
    void dWorldDestroy(dWorldID)
    void dWorldSetGravity(dWorldID, dReal, dReal, dReal)
    void dWorldSetERP(dWorldID, dReal)
    void dWorldSetCFM(dWorldID, dReal)
    void dWorldSetQuickStepNumIterations(dWorldID, int)
    int dWorldQuickStep(dWorldID, dReal)
    void dWorldSetAutoDisableFlag(dWorldID, int)
    void dWorldSetContactSurfaceLayer(dWorldID, dReal)
    void dWorldImpulseToForce(dWorldID, dReal stepsize, dReal ix, dReal iy, dReal iz,
                              dVector3 force)

    dSpaceID dHashSpaceCreate(dSpaceID)
    void dHashSpaceSetLevels(dSpaceID, int minlevel, int maxlevel)
    void dSpaceDestroy(dSpaceID)
    void dSpaceSetCleanup(dSpaceID, int)
    void dSpaceCollide(dSpaceID, void* data, dNearCallback* cb)
    void dSpaceCollide2(dGeomID, dGeomID, void* data, dNearCallback* cb)

    dJointGroupID dJointGroupCreate(int)
    void dJointGroupDestroy(dJointGroupID)
    void dJointGroupEmpty(dJointGroupID)

    dBodyID dBodyCreate(dWorldID)
    void dBodyDestroy(dBodyID)
    void dBodySetPosition(dBodyID, dReal, dReal, dReal)
    void dBodySetQuaternion(dBodyID, const dQuaternion)
    void dBodySetLinearVel(dBodyID, dReal, dReal, dReal)
    void dBodySetAngularVel(dBodyID, dReal, dReal, dReal)
    const dReal* dBodyGetPosition(dBodyID)
    const dReal* dBodyGetQuaternion(dBodyID)
    const dReal* dBodyGetRotation(dBodyID)
    const dReal* dBodyGetLinearVel(dBodyID)
    const dReal* dBodyGetAngularVel(dBodyID)
    void dBodySetMass(dBodyID, const dMass*)
    void dBodyAddForce(dBodyID, dReal, dReal, dReal)
    void dBodyAddForceAtPos(dBodyID, dReal, dReal, dReal, dReal, dReal, dReal)
    void dBodyAddTorque(dBodyID, dReal, dReal, dReal)
    void dBodyEnable(dBodyID)
    void dBodyDisable(dBodyID)
    int dBodyIsEnabled(dBodyID)
    void dBodySetData(dBodyID, void*)
    void* dBodyGetData(dBodyID)
    dJointID dBodyGetJoint(dBodyID, int index)
    void dBodySetKinematic(dBodyID)
    int dBodyIsKinematic(dBodyID)
    void dBodySetGravityMode(dBodyID, int)
    void dBodySetLinearDamping(dBodyID, dReal)
    const dReal* dBodyGetForce(dBodyID)
    const dReal* dBodyGetTorque(dBodyID)
    void dBodySetForce(dBodyID, dReal, dReal, dReal)
    void dBodySetTorque(dBodyID, dReal, dReal, dReal)
    void dBodyGetMass(dBodyID, dMass*)
    void dBodySetAngularDamping(dBodyID, dReal)

    void dMassSetZero(dMass*)
    void dMassSetSphere(dMass*, dReal density, dReal radius)
    void dMassSetBox(dMass*, dReal density, dReal lx, dReal ly, dReal lz)
    void dMassSetCapsule(dMass*, dReal density, int direction, dReal radius, dReal length)
    void dMassSetCylinder(dMass*, dReal density, int direction, dReal radius, dReal length)
    void dMassSetTrimesh(dMass*, dReal density, dGeomID)
    void dMassAdjust(dMass*, dReal)
    void dMassTranslate(dMass*, dReal, dReal, dReal)
    void dMassRotate(dMass*, const dMatrix3)
    void dMassAdd(dMass*, const dMass*)
    int dMassCheck(const dMass*)
    void dRfromQ(dMatrix3, const dQuaternion)
    void dNormalize4(dReal* q)

    dGeomID dCreateSphere(dSpaceID, dReal)
    dGeomID dCreateBox(dSpaceID, dReal, dReal, dReal)
    dGeomID dCreateCapsule(dSpaceID, dReal, dReal)
    dGeomID dCreateCylinder(dSpaceID, dReal, dReal)
    dGeomID dCreatePlane(dSpaceID, dReal, dReal, dReal, dReal)
    dGeomID dCreateRay(dSpaceID, dReal)
    dGeomID dCreateConvex(dSpaceID, const dReal* planes, unsigned int planecount,
                          const dReal* points, unsigned int pointcount,
                          const unsigned int* polygons)
    dTriMeshDataID dGeomTriMeshDataCreate()
    void dGeomTriMeshDataDestroy(dTriMeshDataID)
    void dGeomTriMeshDataBuildDouble(dTriMeshDataID, const void* vertices, int vstride,
                                     int vcount, const void* indices, int icount, int tstride)
    dGeomID dCreateTriMesh(dSpaceID, dTriMeshDataID, void*, void*, void*)
    void dGeomDestroy(dGeomID)
    void dGeomSetBody(dGeomID, dBodyID)
    dBodyID dGeomGetBody(dGeomID)
    void dGeomSetData(dGeomID, void*)
    void* dGeomGetData(dGeomID)
    void dGeomSetPosition(dGeomID, dReal, dReal, dReal)
    void dGeomSetQuaternion(dGeomID, const dQuaternion)
    void dGeomSetOffsetPosition(dGeomID, dReal, dReal, dReal)
    void dGeomSetOffsetQuaternion(dGeomID, const dQuaternion)
    void dGeomSetCategoryBits(dGeomID, unsigned long)
    void dGeomSetCollideBits(dGeomID, unsigned long)
    int dGeomIsSpace(dGeomID)
    void dGeomRaySet(dGeomID, dReal, dReal, dReal, dReal, dReal, dReal)
    void dGeomRaySetLength(dGeomID, dReal)
    void dGeomRaySetClosestHit(dGeomID, int)
    int dCollide(dGeomID, dGeomID, int flags, dContactGeom* contact, int skip)

    dJointID dJointCreateContact(dWorldID, dJointGroupID, const dContact*)
    dJointID dJointCreateHinge(dWorldID, dJointGroupID)
    dJointID dJointCreateBall(dWorldID, dJointGroupID)
    dJointID dJointCreateSlider(dWorldID, dJointGroupID)
    dJointID dJointCreateUniversal(dWorldID, dJointGroupID)
    dJointID dJointCreateHinge2(dWorldID, dJointGroupID)
    dJointID dJointCreateFixed(dWorldID, dJointGroupID)
    dJointID dJointCreateAMotor(dWorldID, dJointGroupID)
    dJointID dJointCreateLMotor(dWorldID, dJointGroupID)
    void dJointDestroy(dJointID)
    void dJointAttach(dJointID, dBodyID, dBodyID)
    void dJointSetFeedback(dJointID, dJointFeedback*)
    int dAreConnectedExcluding(dBodyID, dBodyID, int)

    void dJointSetHingeAnchor(dJointID, dReal, dReal, dReal)
    void dJointSetHingeAxis(dJointID, dReal, dReal, dReal)
    void dJointSetHingeParam(dJointID, int, dReal)
    dReal dJointGetHingeAngle(dJointID)
    dReal dJointGetHingeAngleRate(dJointID)
    void dJointSetBallAnchor(dJointID, dReal, dReal, dReal)
    void dJointSetSliderAxis(dJointID, dReal, dReal, dReal)
    void dJointSetSliderParam(dJointID, int, dReal)
    dReal dJointGetSliderPosition(dJointID)
    dReal dJointGetSliderPositionRate(dJointID)
    void dJointSetUniversalAnchor(dJointID, dReal, dReal, dReal)
    void dJointSetUniversalAxis1(dJointID, dReal, dReal, dReal)
    void dJointSetUniversalAxis2(dJointID, dReal, dReal, dReal)
    void dJointSetUniversalParam(dJointID, int, dReal)
    dReal dJointGetUniversalAngle1(dJointID)
    dReal dJointGetUniversalAngle1Rate(dJointID)
    void dJointSetHinge2Anchor(dJointID, dReal, dReal, dReal)
    void dJointSetHinge2Axes(dJointID, const dReal*, const dReal*)
    void dJointSetHinge2Param(dJointID, int, dReal)
    dReal dJointGetHinge2Angle1(dJointID)
    dReal dJointGetHinge2Angle1Rate(dJointID)
    void dJointSetFixed(dJointID)
    void dJointSetAMotorMode(dJointID, int)
    void dJointSetAMotorNumAxes(dJointID, int)
    void dJointSetAMotorAxis(dJointID, int anum, int rel, dReal, dReal, dReal)
    void dJointSetAMotorParam(dJointID, int, dReal)
    void dJointSetLMotorNumAxes(dJointID, int)
    void dJointSetLMotorAxis(dJointID, int anum, int rel, dReal, dReal, dReal)
    void dJointSetLMotorParam(dJointID, int, dReal)


# numpy comes after ODE: numpy's headers pull in complex.h, whose ``I`` macro breaks dMass.
cimport numpy as cnp
import numpy as np

cnp.import_array()

cdef extern from *:
    """
    #undef I  /* complex.h's imaginary unit; ODE names dMass's inertia I */
    """


# -- shared constants (mirrored by the Python layer) ----------------------------
BODY_DYNAMIC = 0
BODY_STATIC = 1
BODY_KINEMATIC = 2

GEOM_SPHERE = 0
GEOM_BOX = 1
GEOM_CAPSULE = 2
GEOM_CYLINDER = 3
GEOM_PLANE = 4
GEOM_MESH = 5
GEOM_HULL = 6

JOINT_HINGE = 0
JOINT_BALL = 1
JOINT_SLIDER = 2
JOINT_UNIVERSAL = 3
JOINT_HINGE2 = 4
JOINT_FIXED = 5
JOINT_AMOTOR = 6
JOINT_LMOTOR = 7
JOINT_SIX_DOF = 8

#: Columns of the material pair table handed to ``World.set_pairs``.
PAIR_COLUMNS = ("collide", "mode", "mu", "bounce", "bounce_vel", "soft_erp", "soft_cfm")
MODE_APPROX1 = dContactApprox1
MODE_BOUNCE = dContactBounce
MODE_SOFT = dContactSoftERP | dContactSoftCFM

cdef enum:
    FB_CHUNK = 4096
    BODY_DYNAMIC_C = 0
    REST_SAMPLES = 5      # velocity samples averaged by auto-sleep
    REST_STEPS = 20       # steps the mean must stay within the thresholds

#: Squared auto-sleep thresholds (0.05 m/s, 0.05 rad/s), squared as ODE squares them.
cdef double REST_LINEAR2 = 0.05 * 0.05
cdef double REST_ANGULAR2 = 0.05 * 0.05
SLEEP_SAMPLES = REST_SAMPLES
SLEEP_STEPS = REST_STEPS

#: Speed (m/s) and spin (rad/s) beyond which a body counts as exploded.
cdef double MAX_SPEED = 1e5
MAX_BODY_SPEED = MAX_SPEED


cdef inline double clamp_speed(double v) noexcept nogil:
    return max(-MAX_SPEED, min(MAX_SPEED, v))


cdef inline double norm3(const double* v) noexcept nogil:
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


# -- C-side records -----------------------------------------------------------
cdef struct GeomInfo:
    int64_t key          # body key, -1 for keyless static geometry
    int material
    uint32_t category
    uint32_t mask
    int movable          # 1 for dynamic bodies (kinematic and static never collide together)
    int kinematic


cdef struct Pair:
    int collide
    int mode
    double mu, bounce, bounce_vel, soft_erp, soft_cfm


cdef struct ContactRec:   # byte layout of engine.physics.backend.CONTACT_DTYPE
    int64_t a
    int64_t b
    double pos[3]
    double normal[3]
    double depth
    double impulse


cdef struct Slot:
    dBodyID body         # NULL for static bodies
    int64_t key
    int kind
    double pose[7]       # static bodies: entity pose (x y z w x y z)
    double com[3]        # centre of mass in the entity frame (ODE bodies sit at the COM)
    double good[7]       # last sane pose of the ODE body (position, quaternion)


cdef struct Rest:
    int can_sleep        # a dynamic body allowed to sleep
    int left             # idle steps still needed before it sleeps (ODE's adis_stepsleft)
    int next             # ring slot of the next velocity sample
    int ready            # the ring is full, so ``next`` is also the oldest sample
    double samples[30]   # REST_SAMPLES x (linear xyz, angular xyz)


cdef struct Ctx:
    dWorldID world
    dJointGroupID group
    Pair* pairs
    int nmat
    int max_contacts
    dContact* buf
    ContactRec* recs
    int nrec
    int caprec
    dJointFeedback** chunks
    int nchunks
    int oom


cdef struct RayCtx:
    dGeomID ray
    int64_t ignore
    uint32_t mask
    int hit
    int64_t key
    double pos[3]
    double normal[3]
    double depth


cdef void quiet(int errnum, const char* msg, va_list ap) noexcept nogil:
    """ODE's informational messages (e.g. LCP warnings) are not errors; keep stdout clean."""
    pass


dInitODE2(0)
dAllocateODEDataForThread(dAllocateMaskAll)
dSetMessageHandler(quiet)

CONTACT_RECORD_SIZE = sizeof(ContactRec)


# -- small quaternion helpers (w, x, y, z) -----------------------------------------
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


cdef inline void qnormalize(double* q) noexcept nogil:
    cdef double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
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


# -- the near callback: pair filter, material lookup, contact joints, in C ------------
cdef inline dJointFeedback* feedback_slot(Ctx* c, int i) noexcept nogil:
    cdef int chunk = i // FB_CHUNK
    cdef dJointFeedback** grown
    if chunk >= c.nchunks:
        grown = <dJointFeedback**>realloc(c.chunks, (chunk + 1) * sizeof(dJointFeedback*))
        if grown == NULL:
            return NULL
        c.chunks = grown
        c.chunks[chunk] = <dJointFeedback*>malloc(FB_CHUNK * sizeof(dJointFeedback))
        if c.chunks[chunk] == NULL:
            return NULL
        c.nchunks = chunk + 1
    return &c.chunks[chunk][i % FB_CHUNK]


cdef void near_callback(void* data, dGeomID o1, dGeomID o2) noexcept nogil:
    cdef Ctx* c = <Ctx*>data
    cdef GeomInfo* g1
    cdef GeomInfo* g2
    cdef GeomInfo* gt
    cdef dBodyID b1
    cdef dBodyID b2
    cdef dBodyID bt
    cdef dGeomID ot
    cdef Pair* p
    cdef int n, i, k
    cdef double sign
    cdef dJointID j
    cdef dJointFeedback* fb
    cdef ContactRec* rec
    cdef ContactRec* grown
    if dGeomIsSpace(o1) or dGeomIsSpace(o2):
        dSpaceCollide2(o1, o2, data, near_callback)
        return
    g1 = <GeomInfo*>dGeomGetData(o1)
    g2 = <GeomInfo*>dGeomGetData(o2)
    if g1 == NULL or g2 == NULL or (g1.movable == 0 and g2.movable == 0):
        return
    if (g1.category & g2.mask) == 0 or (g2.category & g1.mask) == 0:
        return
    if g1.movable == 0:          # the moving body is always ``a``; static world is ``b``
        ot = o1
        o1 = o2
        o2 = ot
        gt = g1
        g1 = g2
        g2 = gt
    b1 = dGeomGetBody(o1)
    b2 = dGeomGetBody(o2)
    if b1 == b2:
        return
    if not dBodyIsEnabled(b1) and (b2 == NULL or not dBodyIsEnabled(b2)):
        return                   # both asleep (or asleep on static ground): nothing to solve
    if b2 != NULL and dAreConnectedExcluding(b1, b2, dJointTypeContact):
        return
    p = &c.pairs[g1.material * c.nmat + g2.material]
    if p.collide == 0:
        return
    n = dCollide(o1, o2, c.max_contacts, &c.buf[0].geom, sizeof(dContact))
    for i in range(n):
        if c.nrec >= c.caprec:
            k = c.caprec * 2 if c.caprec > 0 else 1024
            grown = <ContactRec*>realloc(c.recs, k * sizeof(ContactRec))
            if grown == NULL:
                c.oom = 1
                return
            c.recs = grown
            c.caprec = k
        fb = feedback_slot(c, c.nrec)
        if fb == NULL:
            c.oom = 1
            return
        c.buf[i].surface.mode = p.mode
        c.buf[i].surface.mu = p.mu
        c.buf[i].surface.bounce = p.bounce
        c.buf[i].surface.bounce_vel = p.bounce_vel
        c.buf[i].surface.soft_erp = p.soft_erp
        c.buf[i].surface.soft_cfm = p.soft_cfm
        j = dJointCreateContact(c.world, c.group, &c.buf[i])
        dJointAttach(j, b1, b2)
        memset(fb, 0, sizeof(dJointFeedback))
        dJointSetFeedback(j, fb)
        rec = &c.recs[c.nrec]
        rec.a = g1.key
        rec.b = g2.key
        for k in range(3):
            rec.pos[k] = c.buf[i].geom.pos[k]
            rec.normal[k] = c.buf[i].geom.normal[k]
        rec.depth = c.buf[i].geom.depth
        rec.impulse = 0.0
        c.nrec += 1


cdef void ray_callback(void* data, dGeomID o1, dGeomID o2) noexcept nogil:
    cdef RayCtx* r = <RayCtx*>data
    cdef dGeomID other = o2 if o1 == r.ray else o1
    cdef GeomInfo* g = <GeomInfo*>dGeomGetData(other)
    cdef dContactGeom cg
    cdef int k
    if g == NULL or (g.category & r.mask) == 0 or (g.key == r.ignore and g.key >= 0):
        return
    if dCollide(r.ray, other, 1, &cg, sizeof(dContactGeom)) < 1:
        return
    if r.hit and cg.depth >= r.depth:
        return
    r.hit = 1
    r.key = g.key
    r.depth = cg.depth
    for k in range(3):
        r.pos[k] = cg.pos[k]
        r.normal[k] = cg.normal[k]


cdef class _Drive:
    """A six-DOF drive: linear + angular velocity motors aiming a body at a target pose.

    With a second body the target rides on it (the relative pose at creation is
    kept, like a fixed joint whose force is bounded); without one the target is a
    world pose set by ``World.set_target``.
    """
    cdef dBodyID body
    cdef dBodyID other
    cdef double rel[7]       # body's COM pose in ``other``'s frame (position, quaternion)
    cdef dJointID lmotor
    cdef dJointID amotor
    cdef double target[7]
    cdef double max_force
    cdef double max_torque
    cdef double com[3]       # the body's centre of mass in its entity frame


cdef class _JointRec:
    cdef dJointID joint
    cdef int kind
    cdef double sign        # -1 where ODE's body order is the reverse of (body_a, body_b)
    cdef public object bodies   # (key_a, key_b or None)
    cdef _Drive drive


@cython.no_gc_clear  # __dealloc__ walks the geoms and joints to free their C memory
cdef class World:
    """One ODE world with its hash space, contact group and body slots."""

    cdef dWorldID world
    cdef dSpaceID space
    cdef Ctx ctx
    cdef Slot* slots
    cdef Rest* rest            # slot -> auto-sleep counters (swapped along with the slots)
    cdef int n
    cdef int cap
    cdef int* faults
    cdef int nfaults
    cdef unsigned long seed
    cdef double last_dt
    cdef dict slot_of          # key -> slot index
    cdef list geoms            # slot -> list of (geom address, keep-alive object or None)
    cdef dict joints           # key -> _JointRec
    cdef list pending_mass     # slot -> dMass accumulated by add_geom (as a bytes buffer)
    cdef list static_geoms     # keyless static geometry, kept until close
    cdef int auto_sleep

    def __cinit__(self) -> None:
        self.world = dWorldCreate()
        self.space = dHashSpaceCreate(NULL)
        dHashSpaceSetLevels(self.space, -1, 6)
        dSpaceSetCleanup(self.space, 0)
        memset(&self.ctx, 0, sizeof(Ctx))
        self.ctx.world = self.world
        self.ctx.group = dJointGroupCreate(0)
        self.ctx.max_contacts = 4
        self.ctx.buf = <dContact*>calloc(4, sizeof(dContact))
        self.ctx.nmat = 1
        self.ctx.pairs = <Pair*>calloc(1, sizeof(Pair))
        self.ctx.pairs[0].collide = 1
        self.ctx.pairs[0].mode = dContactApprox1
        self.ctx.pairs[0].mu = 0.5
        self.slots = NULL
        self.rest = NULL
        self.faults = NULL
        self.n = 0
        self.cap = 0
        self.seed = 0
        self.last_dt = 1.0 / 60.0
        self.slot_of = {}
        self.geoms = []
        self.joints = {}
        self.pending_mass = []
        self.static_geoms = []
        self.auto_sleep = 1
        dWorldSetContactSurfaceLayer(self.world, 0.001)
        dWorldSetAutoDisableFlag(self.world, 0)   # bodies sleep by our rule (_auto_sleep)

    def __dealloc__(self) -> None:
        self._destroy()

    cdef void _destroy(self) noexcept:
        cdef int i
        if self.world == NULL:
            return
        for rec in self.joints.values():
            self._free_joint(<_JointRec>rec)
        self.joints.clear()
        for i in range(self.n):
            self._free_geoms(i)
            if self.slots[i].body != NULL:
                dBodyDestroy(self.slots[i].body)
        for entry in self.static_geoms:
            self._free_geom(entry)
        self.static_geoms = []
        dJointGroupDestroy(self.ctx.group)
        dSpaceDestroy(self.space)
        dWorldDestroy(self.world)
        self.world = NULL
        for i in range(self.ctx.nchunks):
            free(self.ctx.chunks[i])
        free(self.ctx.chunks)
        free(self.ctx.recs)
        free(self.ctx.buf)
        free(self.ctx.pairs)
        free(self.slots)
        free(self.rest)
        free(self.faults)
        self.n = 0

    def close(self) -> None:
        self._destroy()

    cdef void _check(self) except *:
        if self.world == NULL:
            raise RuntimeError("the ODE world is closed")

    # -- world settings ---------------------------------------------------------
    def configure(self, gravity, double erp, double cfm, int iterations, int max_contacts,
                  bint auto_sleep) -> None:
        self._check()
        if max_contacts < 1:
            raise ValueError(f"max_contacts must be at least 1, got {max_contacts}")
        dWorldSetGravity(self.world, gravity[0], gravity[1], gravity[2])
        dWorldSetERP(self.world, erp)
        dWorldSetCFM(self.world, cfm)
        dWorldSetQuickStepNumIterations(self.world, iterations)
        free(self.ctx.buf)
        self.ctx.buf = <dContact*>calloc(max_contacts, sizeof(dContact))
        self.ctx.max_contacts = max_contacts
        self.auto_sleep = auto_sleep
        if auto_sleep:
            return
        for i in range(self.n):   # as ODE's dBodySetAutoDisableFlag(b, 0): awake, counts reset
            if self.slots[i].kind == BODY_DYNAMIC:
                self._enable(self.slots[i].body)
                self.rest[i].next = 0
                self.rest[i].ready = 0

    def set_pairs(self, cnp.ndarray[cnp.float64_t, ndim=3] table) -> None:
        """Install the (M, M, 7) material pair table (columns: ``PAIR_COLUMNS``)."""
        cdef int m = table.shape[0]
        cdef int i, k
        cdef Pair* pairs = <Pair*>calloc(m * m, sizeof(Pair))
        if pairs == NULL:
            raise MemoryError()
        for i in range(m):
            for k in range(m):
                pairs[i * m + k].collide = <int>table[i, k, 0]
                pairs[i * m + k].mode = <int>table[i, k, 1]
                pairs[i * m + k].mu = table[i, k, 2]
                pairs[i * m + k].bounce = table[i, k, 3]
                pairs[i * m + k].bounce_vel = table[i, k, 4]
                pairs[i * m + k].soft_erp = table[i, k, 5]
                pairs[i * m + k].soft_cfm = table[i, k, 6]
        free(self.ctx.pairs)
        self.ctx.pairs = pairs
        self.ctx.nmat = m

    # -- bodies -----------------------------------------------------------------
    cdef int _slot(self, key) except -1:
        try:
            return self.slot_of[key]
        except KeyError:
            raise KeyError(f"no body with key {key}") from None

    def has_body(self, key) -> bool:
        return key in self.slot_of

    def create_body(self, int64_t key, int kind, double[::1] pos, double[::1] quat,
                    double[::1] lin, double[::1] ang, double linear_damping,
                    double angular_damping, bint gravity, bint can_sleep) -> None:
        cdef Slot* s
        cdef dBodyID b = NULL
        cdef double q[4]
        cdef Slot* grown
        cdef Rest* rgrown
        cdef int* fgrown
        self._check()
        if key in self.slot_of:
            raise ValueError(f"body {key} already exists")
        if self.n == self.cap:
            newcap = max(64, self.cap * 2)
            grown = <Slot*>realloc(self.slots, newcap * sizeof(Slot))
            if grown == NULL:
                raise MemoryError()
            self.slots = grown
            fgrown = <int*>realloc(self.faults, newcap * sizeof(int))
            if fgrown == NULL:
                raise MemoryError()
            self.faults = fgrown
            rgrown = <Rest*>realloc(self.rest, newcap * sizeof(Rest))
            if rgrown == NULL:
                raise MemoryError()
            self.rest = rgrown
            self.cap = newcap
        q[0] = quat[0]
        q[1] = quat[1]
        q[2] = quat[2]
        q[3] = quat[3]
        qnormalize(q)
        s = &self.slots[self.n]
        memset(s, 0, sizeof(Slot))
        s.key = key
        s.kind = kind
        s.pose[0] = pos[0]
        s.pose[1] = pos[1]
        s.pose[2] = pos[2]
        memcpy(&s.pose[3], q, 4 * sizeof(double))
        if kind != BODY_STATIC:
            b = dBodyCreate(self.world)
            dBodySetPosition(b, pos[0], pos[1], pos[2])
            dBodySetQuaternion(b, q)
            dBodySetLinearVel(b, lin[0], lin[1], lin[2])
            dBodySetAngularVel(b, ang[0], ang[1], ang[2])
            dBodySetLinearDamping(b, linear_damping)
            dBodySetAngularDamping(b, angular_damping)
            dBodySetGravityMode(b, gravity)
            if kind == BODY_KINEMATIC:
                dBodySetKinematic(b)
            dBodySetData(b, <void*><intptr_t>self.n)   # slot index, for _enable
        s.body = b
        memset(&self.rest[self.n], 0, sizeof(Rest))
        self.rest[self.n].can_sleep = kind == BODY_DYNAMIC and can_sleep
        self.rest[self.n].left = REST_STEPS
        self.slot_of[key] = self.n
        self.geoms.append([])
        self.pending_mass.append(bytearray(sizeof(dMass)))
        dMassSetZero(<dMass*><char*>self.pending_mass[self.n])
        self.n += 1
        self._store_good(self.n - 1)

    cdef inline void _enable(self, dBodyID b) noexcept nogil:
        """Wake a body and restart its idle count, as ODE's own dBodyEnable does."""
        dBodyEnable(b)
        self.rest[<intptr_t>dBodyGetData(b)].left = REST_STEPS

    cdef void _store_good(self, int i) noexcept:
        cdef Slot* s = &self.slots[i]
        if s.body == NULL:
            return
        memcpy(&s.good[0], dBodyGetPosition(s.body), 3 * sizeof(double))
        memcpy(&s.good[3], dBodyGetQuaternion(s.body), 4 * sizeof(double))

    def add_geom(self, key, int kind, double[::1] dims, double[::1] offset, double[::1] rotation,
                 double density, int material, uint32_t category, uint32_t mask,
                 vertices=None, faces=None, planes=None, polygons=None) -> None:
        """Add one collision shape to a body; its mass (at ``density``) joins the body's."""
        cdef int i = self._slot(key)
        cdef Slot* s = &self.slots[i]
        cdef dGeomID g = NULL
        cdef dTriMeshDataID td = NULL
        cdef dMass m
        cdef dMatrix3 R
        cdef double q[4]
        cdef double wpos[3]
        cdef double wq[4]
        cdef GeomInfo* info
        cdef cnp.ndarray verts
        cdef cnp.ndarray idx
        cdef cnp.ndarray pl
        cdef cnp.ndarray poly
        keep = None
        q[0] = rotation[0]
        q[1] = rotation[1]
        q[2] = rotation[2]
        q[3] = rotation[3]
        qnormalize(q)
        dMassSetZero(&m)
        if kind == GEOM_SPHERE:
            g = dCreateSphere(self.space, dims[0])
            dMassSetSphere(&m, density, dims[0])
        elif kind == GEOM_BOX:
            g = dCreateBox(self.space, dims[0], dims[1], dims[2])
            dMassSetBox(&m, density, dims[0], dims[1], dims[2])
        elif kind == GEOM_CAPSULE:
            g = dCreateCapsule(self.space, dims[0], dims[1])
            dMassSetCapsule(&m, density, 3, dims[0], dims[1])
        elif kind == GEOM_CYLINDER:
            g = dCreateCylinder(self.space, dims[0], dims[1])
            dMassSetCylinder(&m, density, 3, dims[0], dims[1])
        elif kind == GEOM_PLANE:
            if s.body != NULL:
                raise ValueError("a plane is infinite and can only belong to a static body")
            g = dCreatePlane(self.space, dims[0], dims[1], dims[2], dims[3])
        elif kind == GEOM_MESH:
            verts = np.ascontiguousarray(vertices, dtype=np.float64)
            idx = np.ascontiguousarray(faces, dtype=np.uint32)
            td = dGeomTriMeshDataCreate()
            dGeomTriMeshDataBuildDouble(td, verts.data, 3 * sizeof(double), verts.shape[0],
                                        idx.data, idx.shape[0] * 3, 3 * sizeof(dTriIndex))
            g = dCreateTriMesh(self.space, td, NULL, NULL, NULL)
            if s.body != NULL:
                dMassSetTrimesh(&m, density, g)
            keep = (verts, idx)
        elif kind == GEOM_HULL:
            pl = np.ascontiguousarray(planes, dtype=np.float64)
            verts = np.ascontiguousarray(vertices, dtype=np.float64)
            poly = np.ascontiguousarray(polygons, dtype=np.uint32)
            g = dCreateConvex(self.space, <dReal*>pl.data, pl.shape[0], <dReal*>verts.data,
                              verts.shape[0], <unsigned int*>poly.data)
            keep = (pl, verts, poly)
            if s.body != NULL:
                # ODE has no convex mass; the same triangles as a mesh give it exactly.
                idx = np.ascontiguousarray(faces, dtype=np.uint32)
                td = dGeomTriMeshDataCreate()
                dGeomTriMeshDataBuildDouble(td, verts.data, 3 * sizeof(double), verts.shape[0],
                                            idx.data, idx.shape[0] * 3, 3 * sizeof(dTriIndex))
                tmp = dCreateTriMesh(NULL, td, NULL, NULL, NULL)
                dMassSetTrimesh(&m, density, tmp)
                dGeomDestroy(tmp)
                dGeomTriMeshDataDestroy(td)
                td = NULL
        else:
            raise ValueError(f"unknown geom kind {kind}")
        if s.body != NULL and kind != GEOM_PLANE:
            if not dMassCheck(&m) or not m.mass > 0.0:
                if td != NULL:
                    dGeomDestroy(g)
                    dGeomTriMeshDataDestroy(td)
                else:
                    dGeomDestroy(g)
                raise ValueError("shape has no positive volume (is the mesh closed and "
                                 "consistently wound?)")
            dRfromQ(R, q)
            dMassRotate(&m, R)
            dMassTranslate(&m, offset[0], offset[1], offset[2])
            dMassAdd(<dMass*><char*>self.pending_mass[i], &m)
        info = <GeomInfo*>malloc(sizeof(GeomInfo))
        info.key = key
        info.material = material
        info.category = category
        info.mask = mask
        info.movable = 1 if s.kind == BODY_DYNAMIC else 0
        info.kinematic = 1 if s.kind == BODY_KINEMATIC else 0
        dGeomSetData(g, info)
        dGeomSetCategoryBits(g, category)
        dGeomSetCollideBits(g, mask)
        entry = [<size_t>g, <size_t>td, keep, (offset[0], offset[1], offset[2]),
                 (q[0], q[1], q[2], q[3]), kind]
        self.geoms[i].append(entry)
        if s.body != NULL:
            dGeomSetBody(g, s.body)
            if (offset[0] != 0.0 or offset[1] != 0.0 or offset[2] != 0.0 or q[0] != 1.0):
                # geoms at the body origin skip ODE's per-step offset transform
                dGeomSetOffsetQuaternion(g, q)
                dGeomSetOffsetPosition(g, offset[0], offset[1], offset[2])
        elif kind != GEOM_PLANE:
            self._place_static_geom(s, entry)

    cdef void _place_static_geom(self, Slot* s, list entry):
        cdef dGeomID g = <dGeomID><size_t>entry[0]
        cdef double off[3]
        cdef double rq[4]
        cdef double w[3]
        cdef double wq[4]
        if entry[5] == GEOM_PLANE:
            return
        for k in range(3):
            off[k] = entry[3][k]
        for k in range(4):
            rq[k] = entry[4][k]
        qrotate(&s.pose[3], off, w)
        qmul(&s.pose[3], rq, wq)
        dGeomSetPosition(g, s.pose[0] + w[0], s.pose[1] + w[1], s.pose[2] + w[2])
        dGeomSetQuaternion(g, wq)

    def finish_body(self, key, double mass) -> None:
        """Give the body its mass (``mass`` > 0 rescales the shapes' total) at its COM."""
        cdef int i = self._slot(key)
        cdef Slot* s = &self.slots[i]
        cdef dMass* m = <dMass*><char*>self.pending_mass[i]
        cdef double c[3]
        cdef double wc[3]
        cdef double q[4]
        cdef int k
        cdef const dReal* p
        cdef const dReal* v
        cdef const dReal* w
        if s.body == NULL:
            return
        if m.mass <= 0.0:
            if mass <= 0.0:
                raise ValueError("a dynamic body needs a shape with volume or a mass")
            dMassSetSphere(m, 1.0, 0.5)   # shapeless: a unit-size sphere's inertia
        if mass > 0.0:
            dMassAdjust(m, mass)
        c[0] = m.c[0]
        c[1] = m.c[1]
        c[2] = m.c[2]
        dMassTranslate(m, -c[0], -c[1], -c[2])
        if not dMassCheck(m):
            raise ValueError("the body's shapes give an invalid mass distribution")
        dBodySetMass(s.body, m)
        if s.kind == BODY_KINEMATIC:
            dBodySetKinematic(s.body)  # setting a mass makes a body dynamic again
        memcpy(s.com, c, 3 * sizeof(double))
        if c[0] == 0.0 and c[1] == 0.0 and c[2] == 0.0:
            self._store_good(i)
            return
        for entry in self.geoms[i]:
            off = entry[3]
            rot = entry[4]
            for k in range(4):
                q[k] = rot[k]
            dGeomSetOffsetQuaternion(<dGeomID><size_t>entry[0], q)
            dGeomSetOffsetPosition(<dGeomID><size_t>entry[0], off[0] - c[0], off[1] - c[1],
                                   off[2] - c[2])
        p = dBodyGetPosition(s.body)
        qrotate(dBodyGetQuaternion(s.body), c, wc)
        dBodySetPosition(s.body, p[0] + wc[0], p[1] + wc[1], p[2] + wc[2])
        # the body was given its entity origin's velocity: move it to the COM too
        v = dBodyGetLinearVel(s.body)
        w = dBodyGetAngularVel(s.body)
        dBodySetLinearVel(s.body, v[0] + w[1] * wc[2] - w[2] * wc[1],
                          v[1] + w[2] * wc[0] - w[0] * wc[2],
                          v[2] + w[0] * wc[1] - w[1] * wc[0])
        self._store_good(i)

    cdef void _free_geom(self, list entry) noexcept:
        cdef dGeomID g = <dGeomID><size_t>entry[0]
        cdef dTriMeshDataID td = <dTriMeshDataID><size_t>entry[1]
        free(dGeomGetData(g))
        dGeomDestroy(g)
        if td != NULL:
            dGeomTriMeshDataDestroy(td)

    cdef void _free_geoms(self, int i) noexcept:
        for entry in self.geoms[i]:
            self._free_geom(entry)
        self.geoms[i] = []

    def remove_body(self, key) -> list:
        """Destroy a body, its geoms and the joints on it; returns the removed joint keys."""
        cdef int i = self._slot(key)
        cdef int last = self.n - 1
        gone = [jk for jk, rec in self.joints.items() if key in (<_JointRec>rec).bodies]
        for jk in gone:
            self.remove_joint(jk)
        self._free_geoms(i)
        if self.slots[i].body != NULL:
            dBodyDestroy(self.slots[i].body)
        if i != last:
            self.slots[i] = self.slots[last]
            self.rest[i] = self.rest[last]
            if self.slots[i].body != NULL:
                dBodySetData(self.slots[i].body, <void*><intptr_t>i)
            self.geoms[i] = self.geoms[last]
            self.pending_mass[i] = self.pending_mass[last]
            self.slot_of[self.slots[i].key] = i
        self.geoms.pop()
        self.pending_mass.pop()
        del self.slot_of[key]
        self.n -= 1
        return gone

    def body_count(self) -> int:
        return self.n

    def keys(self) -> np.ndarray:
        cdef cnp.ndarray[cnp.int64_t, ndim=1] out = np.empty(self.n, np.int64)
        cdef int i
        for i in range(self.n):
            out[i] = self.slots[i].key
        return out

    def is_static(self, key) -> bool:
        return self.slots[self._slot(key)].body == NULL

    def is_kinematic(self, key) -> bool:
        return self.slots[self._slot(key)].kind == BODY_KINEMATIC

    cdef void _set_slot_pose(self, int i, const double* pos, const double* quat) noexcept:
        cdef Slot* s = &self.slots[i]
        cdef double q[4]
        cdef double wc[3]
        memcpy(q, quat, 4 * sizeof(double))
        qnormalize(q)
        if s.body == NULL:
            memcpy(s.pose, pos, 3 * sizeof(double))
            memcpy(&s.pose[3], q, 4 * sizeof(double))
            for entry in self.geoms[i]:
                self._place_static_geom(s, entry)
            return
        qrotate(q, s.com, wc)
        dBodySetPosition(s.body, pos[0] + wc[0], pos[1] + wc[1], pos[2] + wc[2])
        dBodySetQuaternion(s.body, q)
        self._enable(s.body)

    cdef void _set_slot_velocity(self, int i, const double* lin, const double* ang) noexcept:
        """Entity-origin velocities -> COM velocity (v_com = v + w x R c)."""
        cdef Slot* s = &self.slots[i]
        cdef double wc[3]
        if s.body == NULL:
            return
        qrotate(dBodyGetQuaternion(s.body), s.com, wc)
        dBodySetLinearVel(s.body, lin[0] + ang[1] * wc[2] - ang[2] * wc[1],
                          lin[1] + ang[2] * wc[0] - ang[0] * wc[2],
                          lin[2] + ang[0] * wc[1] - ang[1] * wc[0])
        dBodySetAngularVel(s.body, ang[0], ang[1], ang[2])
        self._enable(s.body)

    def set_pose(self, key, double[::1] pos, double[::1] quat) -> None:
        cdef int i = self._slot(key)
        self._set_slot_pose(i, &pos[0], &quat[0])

    def set_velocity(self, key, double[::1] lin, double[::1] ang) -> None:
        cdef int i = self._slot(key)
        self._set_slot_velocity(i, &lin[0], &ang[0])

    def pose(self, key) -> tuple:
        """(position, orientation) of one body's entity frame."""
        cdef int i = self._slot(key)
        cdef double out[13]
        self._read_slot(i, out)
        return np.array([out[0], out[1], out[2]]), np.array([out[3], out[4], out[5], out[6]])

    cdef inline void _read_slot(self, int i, double* out) noexcept nogil:
        """Entity-frame state: position, quaternion, linear (at origin) and angular velocity."""
        cdef Slot* s = &self.slots[i]
        cdef const dReal* p
        cdef const dReal* q
        cdef const dReal* v
        cdef const dReal* w
        cdef double wc[3]
        if s.body == NULL:
            memcpy(out, s.pose, 7 * sizeof(double))
            memset(&out[7], 0, 6 * sizeof(double))
            return
        p = dBodyGetPosition(s.body)
        q = dBodyGetQuaternion(s.body)
        v = dBodyGetLinearVel(s.body)
        w = dBodyGetAngularVel(s.body)
        out[3] = q[0]
        out[4] = q[1]
        out[5] = q[2]
        out[6] = q[3]
        out[10] = w[0]
        out[11] = w[1]
        out[12] = w[2]
        if s.com[0] == 0.0 and s.com[1] == 0.0 and s.com[2] == 0.0:
            out[0] = p[0]
            out[1] = p[1]
            out[2] = p[2]
            out[7] = v[0]
            out[8] = v[1]
            out[9] = v[2]
            return
        qrotate(q, s.com, wc)
        out[0] = p[0] - wc[0]
        out[1] = p[1] - wc[1]
        out[2] = p[2] - wc[2]
        # velocity of the entity origin: v_com + w x (origin - com) = v_com - w x R c
        out[7] = v[0] - (w[1] * wc[2] - w[2] * wc[1])
        out[8] = v[1] - (w[2] * wc[0] - w[0] * wc[2])
        out[9] = v[2] - (w[0] * wc[1] - w[1] * wc[0])

    def read_state(self) -> tuple:
        """Fresh (keys, table) for every body: table rows are x y z, w x y z, linear and
        angular velocity (BodyState's layout)."""
        cdef int n = self.n
        cdef cnp.ndarray[cnp.int64_t, ndim=1] keys = np.empty(n, np.int64)
        cdef cnp.ndarray[cnp.float64_t, ndim=2] table = np.empty((n, 13))
        cdef int64_t* kp = <int64_t*>keys.data
        cdef double* tp = <double*>table.data
        cdef int i
        with nogil:
            for i in range(n):
                self._read_slot(i, &tp[13 * i])
                kp[i] = self.slots[i].key
        return keys, table

    def read_poses(self, double[:, ::1] out) -> None:
        """Write every body's pose as rows (x y z w x y z) into ``out`` (N, 7), no allocation."""
        cdef int i
        cdef double st[13]
        if out.shape[0] < self.n or out.shape[1] != 7:
            raise ValueError(f"read_poses needs an ({self.n}, 7) array")
        with nogil:
            for i in range(self.n):
                self._read_slot(i, st)
                memcpy(&out[i, 0], st, 7 * sizeof(double))

    def write_state(self, cnp.int64_t[::1] slots, double[:, ::1] pos, double[:, ::1] quat,
                    double[:, ::1] lin, double[:, ::1] ang) -> None:
        """Set pose and velocity of the bodies at ``slots`` (row i -> slots[i])."""
        cdef Py_ssize_t i
        for i in range(slots.shape[0]):
            self._set_slot_pose(<int>slots[i], &pos[i, 0], &quat[i, 0])
            self._set_slot_velocity(<int>slots[i], &lin[i, 0], &ang[i, 0])

    def slots_for(self, keys) -> np.ndarray:
        """Slot index of every key (KeyError naming the first unknown one)."""
        slot_of = self.slot_of
        try:
            return np.fromiter((slot_of[k] for k in keys.tolist()), np.int64, len(keys))
        except KeyError as exc:
            raise KeyError(f"no body with key {exc.args[0]}") from None

    # -- forces -----------------------------------------------------------------------
    cdef dBodyID _body(self, key) except? NULL:
        cdef int i = self._slot(key)
        return self.slots[i].body

    cdef void _check_load(self, key, dBodyID b) except *:
        """Refuse a force or torque that would fling the body past MAX_SPEED in one step.

        ODE aborts the process on a non-finite quaternion, so absurd loads are
        stopped at the door (the accumulators are cleared) rather than in the step.
        """
        cdef dMass m
        cdef double inertia
        dBodyGetMass(b, &m)
        inertia = min(m.I[0], min(m.I[5], m.I[10]))
        if (norm3(dBodyGetForce(b)) * self.last_dt < MAX_SPEED * m.mass
                and norm3(dBodyGetTorque(b)) * self.last_dt < MAX_SPEED * inertia):
            return
        dBodySetForce(b, 0.0, 0.0, 0.0)
        dBodySetTorque(b, 0.0, 0.0, 0.0)
        raise ValueError(f"body {key}: force or torque would push it past "
                         f"{MAX_SPEED:g} m/s (or rad/s) in one step; load discarded")

    def add_force(self, key, double fx, double fy, double fz, point=None) -> None:
        cdef dBodyID b = self._body(key)
        if b == NULL or dBodyIsKinematic(b):
            return
        self._enable(b)
        if point is None:
            dBodyAddForce(b, fx, fy, fz)
        else:
            dBodyAddForceAtPos(b, fx, fy, fz, point[0], point[1], point[2])
        self._check_load(key, b)

    def add_torque(self, key, double tx, double ty, double tz) -> None:
        cdef dBodyID b = self._body(key)
        if b == NULL or dBodyIsKinematic(b):
            return
        self._enable(b)
        dBodyAddTorque(b, tx, ty, tz)
        self._check_load(key, b)

    def add_impulse(self, key, double ix, double iy, double iz, point=None) -> None:
        """Impulse as the force that delivers it over the next step (of the last step's dt)."""
        cdef dVector3 f
        dWorldImpulseToForce(self.world, self.last_dt, ix, iy, iz, f)
        self.add_force(key, f[0], f[1], f[2], point)

    def set_sleeping(self, key, bint sleeping) -> None:
        cdef dBodyID b = self._body(key)
        if b == NULL:
            return
        if sleeping:
            dBodyDisable(b)
        else:
            self._enable(b)

    def is_sleeping(self, key) -> bool:
        cdef dBodyID b = self._body(key)
        return b != NULL and not dBodyIsEnabled(b)

    def sleeping_count(self) -> int:
        cdef int i, c = 0
        for i in range(self.n):
            if self.slots[i].body != NULL and not dBodyIsEnabled(self.slots[i].body):
                c += 1
        return c

    def sleep_states(self) -> tuple:
        """Auto-sleep state of every moving body: (keys, asleep, idle steps, sample counts,
        samples (N, SLEEP_SAMPLES, 6) oldest first, unused rows zero).

        Idle steps count toward ``SLEEP_STEPS`` (a body woken by a touch keeps its count);
        a sample is (linear m/s, angular rad/s) at the centre of mass, world frame.
        """
        cdef int i, j, m = 0, start
        for i in range(self.n):
            if self.slots[i].body != NULL:
                m += 1
        cdef cnp.ndarray[cnp.int64_t, ndim=1] keys = np.empty(m, np.int64)
        cdef cnp.ndarray[cnp.uint8_t, ndim=1] asleep = np.empty(m, np.uint8)
        cdef cnp.ndarray[cnp.int64_t, ndim=1] idle = np.empty(m, np.int64)
        cdef cnp.ndarray[cnp.int64_t, ndim=1] counts = np.empty(m, np.int64)
        cdef cnp.ndarray[cnp.float64_t, ndim=3] samples = np.zeros((m, REST_SAMPLES, 6))
        cdef Rest* r
        m = 0
        for i in range(self.n):
            if self.slots[i].body == NULL:
                continue
            r = &self.rest[i]
            keys[m] = self.slots[i].key
            asleep[m] = not dBodyIsEnabled(self.slots[i].body)
            idle[m] = REST_STEPS - r.left
            counts[m] = REST_SAMPLES if r.ready else r.next
            start = r.next if r.ready else 0
            for j in range(counts[m]):
                memcpy(&samples[m, j, 0], &r.samples[6 * ((start + j) % REST_SAMPLES)],
                       6 * sizeof(double))
            m += 1
        return keys, asleep.astype(bool), idle, counts, samples

    def set_sleep_state(self, key, bint asleep, int idle_steps,
                        double[:, ::1] samples) -> None:
        """Restore what :meth:`sleep_states` reported for one body (``samples``: (k, 6),
        oldest first, k <= SLEEP_SAMPLES), so a loaded state sleeps when the saved run did."""
        cdef int i = self._slot(key)
        cdef int k = samples.shape[0]
        cdef int j
        cdef Rest* r = &self.rest[i]
        if self.slots[i].body == NULL:
            return               # a static body never moves: nothing to restore
        if k > REST_SAMPLES or (k and samples.shape[1] != 6) or idle_steps < 0:
            raise ValueError(f"body {key}: sleep state needs idle steps >= 0 and at most "
                             f"{REST_SAMPLES} samples of 6 numbers")
        for j in range(k):
            memcpy(&r.samples[6 * j], &samples[j, 0], 6 * sizeof(double))
        r.next = k % REST_SAMPLES
        r.ready = k == REST_SAMPLES
        r.left = REST_STEPS - idle_steps
        if asleep:
            dBodyDisable(self.slots[i].body)
        else:
            dBodyEnable(self.slots[i].body)   # not _enable: that would restart the count

    # -- keyless static geometry -----------------------------------------------------------
    def add_static_plane(self, double a, double b, double c, double d, int material,
                         uint32_t category, uint32_t mask) -> None:
        cdef dGeomID g = dCreatePlane(self.space, a, b, c, d)
        cdef GeomInfo* info = <GeomInfo*>malloc(sizeof(GeomInfo))
        info.key = -1
        info.material = material
        info.category = category
        info.mask = mask
        info.movable = 0
        info.kinematic = 0
        dGeomSetData(g, info)
        dGeomSetCategoryBits(g, category)
        dGeomSetCollideBits(g, mask)
        self.static_geoms.append([<size_t>g, 0, None, None, None, GEOM_PLANE])

    # -- stepping ---------------------------------------------------------------------------
    @property
    def solver_seed(self) -> int:
        """ODE's random state for this world (QuickStep shuffles constraints with it)."""
        return self.seed

    @solver_seed.setter
    def solver_seed(self, unsigned long value) -> None:
        self.seed = value

    def step(self, double dt) -> list:
        """Collide and QuickStep with the GIL released; returns the keys of bodies reset."""
        cdef int nf
        self._check()
        if not dt > 0.0:
            raise ValueError(f"dt must be positive, got {dt}")
        dAllocateODEDataForThread(dAllocateMaskAll)
        dJointGroupEmpty(self.ctx.group)
        self.ctx.nrec = 0
        self.ctx.oom = 0
        self.last_dt = dt
        if self.joints:
            self._drive(dt)
        dRandSetSeed(self.seed)
        with nogil:
            dSpaceCollide(self.space, &self.ctx, near_callback)
            if self.auto_sleep:
                self._auto_sleep()
            dWorldQuickStep(self.world, dt)
            nf = self._after_step(dt)
        self.seed = dRandGetSeed()
        if self.ctx.oom:
            raise MemoryError("out of memory while recording contacts")
        return [(self.slots[self.faults[k]].key) for k in range(nf)]

    cdef void _auto_sleep(self) noexcept nogil:
        """ODE's auto-disable rule on our counters (see the module doc), before QuickStep."""
        cdef int i, j, k, idx
        cdef Rest* r
        cdef dBodyID b
        cdef const dReal* v
        cdef const dReal* w
        cdef double* x
        cdef double mean[6]
        cdef int idle
        for i in range(self.n):
            r = &self.rest[i]
            b = self.slots[i].body
            # asleep, or touching nothing (never freeze in mid-air): nothing to count
            if not r.can_sleep or not dBodyIsEnabled(b) or dBodyGetJoint(b, 0) == NULL:
                continue
            v = dBodyGetLinearVel(b)
            w = dBodyGetAngularVel(b)
            x = &r.samples[6 * r.next]
            x[0] = v[0]
            x[1] = v[1]
            x[2] = v[2]
            x[3] = w[0]
            x[4] = w[1]
            x[5] = w[2]
            r.next += 1
            if r.next >= REST_SAMPLES:
                r.next = 0
                r.ready = 1
            idle = 0
            if r.ready:
                memcpy(mean, &r.samples[6 * r.next], 6 * sizeof(double))
                for j in range(1, REST_SAMPLES):
                    idx = 6 * ((r.next + j) % REST_SAMPLES)
                    for k in range(6):
                        mean[k] += r.samples[idx + k]
                for k in range(6):
                    mean[k] *= 1.0 / REST_SAMPLES
                idle = (mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]
                        <= REST_LINEAR2 and
                        mean[3] * mean[3] + mean[4] * mean[4] + mean[5] * mean[5]
                        <= REST_ANGULAR2)
            if idle:
                r.left -= 1
            else:
                r.left = REST_STEPS
            if r.left <= 0:
                dBodyDisable(b)
                dBodySetLinearVel(b, 0.0, 0.0, 0.0)
                dBodySetAngularVel(b, 0.0, 0.0, 0.0)

    cdef void _reset(self, int i) noexcept nogil:
        """Put a runaway body back where it last was sane, at rest, and disable it."""
        cdef Slot* s = &self.slots[i]
        dBodySetPosition(s.body, s.good[0], s.good[1], s.good[2])
        dBodySetQuaternion(s.body, &s.good[3])
        dBodySetLinearVel(s.body, 0.0, 0.0, 0.0)
        dBodySetAngularVel(s.body, 0.0, 0.0, 0.0)
        dBodySetForce(s.body, 0.0, 0.0, 0.0)
        dBodySetTorque(s.body, 0.0, 0.0, 0.0)
        dBodyDisable(s.body)

    cdef int _after_step(self, double dt) noexcept nogil:
        """Contact impulses from joint feedback; reset and disable runaway bodies."""
        cdef int i, k, nf = 0
        cdef dJointFeedback* fb
        cdef double f1, f2
        cdef Slot* s
        cdef const dReal* p
        cdef const dReal* q
        cdef const dReal* v
        cdef const dReal* w
        cdef int ok
        for i in range(self.ctx.nrec):
            fb = &self.ctx.chunks[i // FB_CHUNK][i % FB_CHUNK]
            f1 = sqrt(fb.f1[0] * fb.f1[0] + fb.f1[1] * fb.f1[1] + fb.f1[2] * fb.f1[2])
            f2 = sqrt(fb.f2[0] * fb.f2[0] + fb.f2[1] * fb.f2[1] + fb.f2[2] * fb.f2[2])
            self.ctx.recs[i].impulse = (f1 if f1 > f2 else f2) * dt
        for i in range(self.n):
            s = &self.slots[i]
            if s.body == NULL or not dBodyIsEnabled(s.body):
                continue         # static or asleep: nothing moved
            p = dBodyGetPosition(s.body)
            q = dBodyGetQuaternion(s.body)
            v = dBodyGetLinearVel(s.body)
            w = dBodyGetAngularVel(s.body)
            ok = 1
            for k in range(3):
                if not (isfinite(p[k]) and isfinite(v[k]) and isfinite(w[k])):
                    ok = 0
            for k in range(4):
                if not isfinite(q[k]):
                    ok = 0
            if ok and (norm3(v) > MAX_SPEED or norm3(w) > MAX_SPEED):
                ok = 0   # finite but runaway: the next step would overflow
            if ok:
                memcpy(&s.good[0], p, 3 * sizeof(double))
                memcpy(&s.good[3], q, 4 * sizeof(double))
            else:
                self._reset(i)
                self.faults[nf] = i
                nf += 1
        return nf

    def contacts(self) -> np.ndarray:
        """The last step's contacts as raw bytes shaped for CONTACT_DTYPE (caller views them)."""
        cdef cnp.ndarray[cnp.uint8_t, ndim=1] out = np.empty(
            self.ctx.nrec * sizeof(ContactRec), np.uint8)
        if self.ctx.nrec:
            memcpy(out.data, self.ctx.recs, self.ctx.nrec * sizeof(ContactRec))
        return out

    def contact_count(self) -> int:
        return self.ctx.nrec

    # -- ray casts -------------------------------------------------------------------------
    def raycast(self, double ox, double oy, double oz, double dx, double dy, double dz,
                double length, int64_t ignore, uint32_t mask):
        """Closest hit as (key, position, normal, distance) or None; (dx, dy, dz) is unit."""
        cdef RayCtx r
        memset(&r, 0, sizeof(RayCtx))
        r.ray = dCreateRay(NULL, length)
        r.ignore = ignore
        r.mask = mask
        dGeomRaySet(r.ray, ox, oy, oz, dx, dy, dz)
        dGeomRaySetClosestHit(r.ray, 1)
        with nogil:
            dSpaceCollide2(r.ray, <dGeomID>self.space, &r, ray_callback)
        dGeomDestroy(r.ray)
        if not r.hit:
            return None
        nx, ny, nz = r.normal[0], r.normal[1], r.normal[2]
        if nx * dx + ny * dy + nz * dz > 0.0:
            nx, ny, nz = -nx, -ny, -nz
        return (r.key, (r.pos[0], r.pos[1], r.pos[2]), (nx, ny, nz), r.depth)

    # -- joints -------------------------------------------------------------------------
    def create_joint(self, key, int kind, key_a, key_b, anchor, axis, axis2, low, high,
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
        self._check()
        if key in self.joints:
            raise ValueError(f"joint {key} already exists")
        cdef int ia = self._slot(key_a)
        cdef int ib = -1 if key_b is None else self._slot(key_b)
        cdef int ia0 = ia
        cdef int ib0 = ib
        ba = self.slots[ia].body
        if ib >= 0:
            bb = self.slots[ib].body
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
        if ref_a is not None and self.slots[ia0].body != NULL:
            moved_a = self._place(ia0, ref_a, saved)
        if ref_b is not None and ib0 >= 0 and self.slots[ib0].body != NULL:
            moved_b = self._place(ib0, ref_b, &saved[7])
        try:
            for k in range(3):
                a1[k] = axis[k]
                a2[k] = axis2[k]
            if kind == JOINT_HINGE:
                j = dJointCreateHinge(self.world, NULL)
                dJointAttach(j, ba, bb)
                dJointSetHingeAnchor(j, anchor[0], anchor[1], anchor[2])
                dJointSetHingeAxis(j, a1[0], a1[1], a1[2])
            elif kind == JOINT_BALL:
                j = dJointCreateBall(self.world, NULL)
                dJointAttach(j, ba, bb)
                dJointSetBallAnchor(j, anchor[0], anchor[1], anchor[2])
            elif kind == JOINT_SLIDER:
                j = dJointCreateSlider(self.world, NULL)
                dJointAttach(j, ba, bb)
                dJointSetSliderAxis(j, a1[0], a1[1], a1[2])
            elif kind == JOINT_UNIVERSAL:
                j = dJointCreateUniversal(self.world, NULL)
                dJointAttach(j, ba, bb)
                dJointSetUniversalAnchor(j, anchor[0], anchor[1], anchor[2])
                dJointSetUniversalAxis1(j, a1[0], a1[1], a1[2])
                dJointSetUniversalAxis2(j, a2[0], a2[1], a2[2])
            elif kind == JOINT_HINGE2:
                j = dJointCreateHinge2(self.world, NULL)
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
                j = dJointCreateFixed(self.world, NULL)
                dJointAttach(j, ba, bb)
                dJointSetFixed(j)
            elif kind == JOINT_AMOTOR:
                j = dJointCreateAMotor(self.world, NULL)
                dJointAttach(j, ba, bb)
                dJointSetAMotorMode(j, dAMotorUser)
                dJointSetAMotorNumAxes(j, 1)
                dJointSetAMotorAxis(j, 0, 1, a1[0], a1[1], a1[2])
            elif kind == JOINT_LMOTOR:
                j = dJointCreateLMotor(self.world, NULL)
                dJointAttach(j, ba, bb)
                dJointSetLMotorNumAxes(j, 1)
                dJointSetLMotorAxis(j, 0, 1, a1[0], a1[1], a1[2])
            elif kind == JOINT_SIX_DOF:
                d = _Drive()
                d.body = ba
                d.lmotor = dJointCreateLMotor(self.world, NULL)
                dJointAttach(d.lmotor, ba, bb)
                dJointSetLMotorNumAxes(d.lmotor, 3)
                d.amotor = dJointCreateAMotor(self.world, NULL)
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
                memcpy(d.com, self.slots[ia].com, 3 * sizeof(double))
                d.other = bb
                if bb != NULL:
                    relative_pose(bb, ba, d.rel)
                j = d.lmotor
            else:
                raise ValueError(f"unknown joint kind {kind}")
        finally:
            if moved_a:
                dBodySetPosition(self.slots[ia0].body, saved[0], saved[1], saved[2])
                dBodySetQuaternion(self.slots[ia0].body, &saved[3])
            if moved_b:
                dBodySetPosition(self.slots[ib0].body, saved[7], saved[8], saved[9])
                dBodySetQuaternion(self.slots[ib0].body, &saved[10])
        rec = _JointRec()
        rec.joint = j
        rec.kind = kind
        rec.sign = sign
        rec.bodies = (key_a, key_b)
        rec.drive = d if kind == JOINT_SIX_DOF else None
        self.joints[key] = rec
        if sign < 0.0:
            low, high = (None if high is None else -high), (None if low is None else -low)
        if kind not in (JOINT_BALL, JOINT_FIXED, JOINT_SIX_DOF):
            if low is not None:
                self._param(rec, dParamLoStop, low)
            if high is not None:
                self._param(rec, dParamHiStop, high)
            if max_force > 0.0:
                self.set_motor(key, velocity, max_force)

    cdef int _place(self, int i, ref, double* saved) except -1:
        """Put slot ``i``'s body at entity pose ``ref`` the way create_body and finish_body
        do (bit for bit); 1 and its former raw pose in ``saved`` if that moved it."""
        cdef Slot* s = &self.slots[i]
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

    cdef void _param(self, _JointRec rec, int param, double value):
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

    cdef _JointRec _joint(self, key):
        try:
            return self.joints[key]
        except KeyError:
            raise KeyError(f"no joint with key {key}") from None

    def set_motor(self, key, double velocity, double max_force) -> None:
        """Drive the joint's motor axis (hinge2: the second, wheel axis) at ``velocity``."""
        cdef _JointRec rec = self._joint(key)
        if not (fabs(velocity) <= MAX_SPEED and max_force >= 0.0):
            raise ValueError(f"joint {key}: motor velocity must be within {MAX_SPEED:g} and "
                             f"max force >= 0, got {velocity}, {max_force}")
        if rec.kind == JOINT_HINGE2:
            self._param(rec, dParamVel2, rec.sign * velocity)
            self._param(rec, dParamFMax2, max_force)
        elif rec.kind in (JOINT_BALL, JOINT_FIXED, JOINT_SIX_DOF):
            raise ValueError("this joint kind has no motor")
        else:
            self._param(rec, dParamVel, velocity)
            self._param(rec, dParamFMax, max_force)
        self._wake(rec)

    cdef void _wake(self, _JointRec rec):
        cdef dBodyID b
        for k in rec.bodies:
            if k is not None and k in self.slot_of:
                b = self.slots[self.slot_of[k]].body
                if b != NULL:
                    self._enable(b)

    def joint_state(self, key) -> tuple:
        cdef _JointRec rec = self._joint(key)
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

    def set_target(self, key, double[::1] pos, double[::1] quat, double max_force,
                   double max_torque) -> None:
        cdef _JointRec rec = self._joint(key)
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
        self._enable(d.body)

    def set_drive_limits(self, key, double max_force, double max_torque) -> None:
        cdef _JointRec rec = self._joint(key)
        cdef _Drive d = rec.drive
        if d is None:
            raise ValueError(f"joint {key} is not a six_dof joint")
        if not (max_force >= 0.0 and max_torque >= 0.0):
            raise ValueError("six_dof force and torque bounds must be >= 0")
        d.max_force = max_force
        d.max_torque = max_torque
        self._enable(d.body)

    cdef void _drive(self, double dt):
        """Aim every six-DOF drive: velocity = pose error / dt, force bounded by the motors."""
        cdef _Drive d
        cdef _JointRec rec
        cdef const dReal* p
        cdef double rv[3]
        cdef int k
        for obj in self.joints.values():
            rec = <_JointRec>obj
            if rec.drive is None:
                continue
            d = rec.drive
            if d.other != NULL:
                qmul(dBodyGetQuaternion(d.other), &d.rel[3], &d.target[3])
                qrotate(dBodyGetQuaternion(d.other), d.rel, d.target)
                p = dBodyGetPosition(d.other)
                for k in range(3):
                    d.target[k] += p[k]
            p = dBodyGetPosition(d.body)
            rotvec_between(dBodyGetQuaternion(d.body), &d.target[3], rv)
            dJointSetLMotorParam(d.lmotor, dParamVel, clamp_speed((d.target[0] - p[0]) / dt))
            dJointSetLMotorParam(d.lmotor, dParamVel2, clamp_speed((d.target[1] - p[1]) / dt))
            dJointSetLMotorParam(d.lmotor, dParamVel3, clamp_speed((d.target[2] - p[2]) / dt))
            dJointSetAMotorParam(d.amotor, dParamVel, rv[0] / dt)
            dJointSetAMotorParam(d.amotor, dParamVel2, rv[1] / dt)
            dJointSetAMotorParam(d.amotor, dParamVel3, rv[2] / dt)
            for k in range(3):
                dJointSetLMotorParam(d.lmotor, dParamFMax + 0x100 * k, d.max_force)
                dJointSetAMotorParam(d.amotor, dParamFMax + 0x100 * k, d.max_torque)

    cdef void _free_joint(self, _JointRec rec) noexcept:
        if rec.drive is not None:
            dJointDestroy(rec.drive.lmotor)
            dJointDestroy(rec.drive.amotor)
        else:
            dJointDestroy(rec.joint)

    def remove_joint(self, key) -> None:
        cdef _JointRec rec = self._joint(key)
        self._wake(rec)
        self._free_joint(rec)
        del self.joints[key]

    def has_joint(self, key) -> bool:
        return key in self.joints
