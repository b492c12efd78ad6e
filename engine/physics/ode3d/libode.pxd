"""Declarations of the libode 0.16 API (double precision) that the binding uses."""

from libc.stdint cimport uint8_t, uint32_t

from engine.physics.csleep cimport SrRule


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
        dAMotorEuler
        dParamLoStop, dParamHiStop, dParamVel, dParamFMax
        dParamLoStop2, dParamHiStop2, dParamVel2, dParamFMax2
        dParamLoStop3, dParamHiStop3
        dParamVel3, dParamFMax3, dParamCFM

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
    void dBodySetKinematic(dBodyID)
    int dBodyIsKinematic(dBodyID)
    void dBodySetGravityMode(dBodyID, int)
    int dBodyGetGravityMode(dBodyID)
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
    void dMassSetParameters(dMass*, dReal themass, dReal cgx, dReal cgy, dReal cgz,
                            dReal I11, dReal I22, dReal I33, dReal I12, dReal I13, dReal I23)
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
    int dGeomTriMeshDataPreprocess2(dTriMeshDataID, unsigned int build, const void* extra)
    enum:
        dTRIDATAPREPROCESS_BUILD_CONCAVE_EDGES
        dTRIDATAPREPROCESS_BUILD_FACE_ANGLES
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
    void dGeomEnable(dGeomID)
    void dGeomDisable(dGeomID)
    int dGeomIsEnabled(dGeomID)
    int dGeomIsSpace(dGeomID)
    void dGeomRaySet(dGeomID, dReal, dReal, dReal, dReal, dReal, dReal)
    void dGeomRaySetLength(dGeomID, dReal)
    void dGeomRaySetClosestHit(dGeomID, int)
    int dCollide(dGeomID, dGeomID, int flags, dContactGeom* contact, int skip)
    int dGeomGetClass(dGeomID)
    enum:
        dSphereClass
        dBoxClass
        dCapsuleClass
        dPlaneClass
        dTriMeshClass
    void dGeomGetAABB(dGeomID, dReal aabb[6])
    const dReal* dGeomGetPosition(dGeomID)
    const dReal* dGeomGetRotation(dGeomID)
    void dGeomCapsuleGetParams(dGeomID, dReal* radius, dReal* length)
    void dGeomSphereSetRadius(dGeomID, dReal)
    void dGeomSetRotation(dGeomID, const dMatrix3)
    void dGeomCylinderSetParams(dGeomID, dReal radius, dReal length)

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
    dBodyID dJointGetBody(dJointID, int index)
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
    void dJointGetUniversalAxis1(dJointID, dVector3)
    void dJointSetUniversalParam(dJointID, int, dReal)
    dReal dJointGetUniversalAngle1(dJointID)
    dReal dJointGetUniversalAngle1Rate(dJointID)
    dReal dJointGetUniversalAngle2(dJointID)
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


cdef extern from "stepper.h" nogil:
    ctypedef struct CsSettings:
        double beta
        double softness
        int exact_rows
        int contact_iterations

    ctypedef struct CsBody:
        double held[3]
        int resting
        int preloaded
        int slid

    ctypedef struct CsContact:
        dContact contact

    ctypedef struct CsState:
        int oom
        CsContact* contacts
        int ncontacts
        double* forces
        CsBody* bodies
        int capbodies

    void cs_init(CsState*)
    void cs_free(CsState*)
    void cs_reset(CsState*, int)
    void cs_move(CsState*, int, int)
    int cs_begin(CsState*, int)
    int cs_any_awake(const void*, size_t, int)
    int cs_collect(CsState*, const CsSettings*, const dContact*, int, dBodyID, dBodyID, double)
    CsContact* cs_room(CsState*, int)
    void cs_keep(CsState*, const CsSettings*, int, dBodyID, dBodyID, double)
    int cs_solve(CsState*, const CsSettings*, dWorldID, dJointGroupID, const void*, size_t, int,
                 double)
    void cs_whole_forces(CsState*)
    void cs_disable(dBodyID)
    int cs_sleep(CsState*, SrRule*, const void*, size_t, int, double, double, double,
                 const uint8_t*)
