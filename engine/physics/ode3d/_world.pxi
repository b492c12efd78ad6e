# The World: one ODE world with its hash space, contact group and body slots; its
# settings and the step. The records every concept shares are declared here.

#: Contacts asked of a collider that does not spread its own (cylinders, capsules,
#: meshes, convex hulls), before ``spread_contacts`` keeps ``max_contacts`` of them.
cdef enum:
    CANDIDATES = 16

cdef struct GeomInfo:
    int64_t key          # body key, -1 for keyless static geometry
    int material
    uint32_t category
    uint32_t mask
    int movable          # 1 for dynamic bodies (kinematic and static never collide together)
    int geom_class       # dGeomGetClass, kept: the near callback asks it of every pair


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
    uint8_t woken        # explicitly woken since the sleep rule last looked (World.step)
    double pose[7]       # static bodies: entity pose (x y z w x y z)
    double com[3]        # centre of mass in the entity frame (ODE bodies sit at the COM)
    double good[7]       # last sane pose of the ODE body (position, quaternion)
    double target[7]     # kinematic target: entity pose it arrives at (x y z w x y z)
    double target_left   # s of stepping until it is there (0: no target; see aim_kinematic)


cdef struct Ctx:         # what the near callback needs, passed through ODE's void*
    dWorldID world
    dJointGroupID group
    Pair* pairs
    int nmat
    int max_contacts
    dContact* buf
    ContactRec* recs
    int nrec
    int caprec
    int oom
    bint records_owed    # recs hold only the keys of the last step's contacts yet (contacts())
    double dt            # the step in progress
    int64_t* linked      # (body key, static key) pairs a joint holds together: no contacts
    dGeomID proxy        # a sphere in no space: a capsule's stand-in against a triangle mesh
    dGeomID proxy_end    # another sphere, and a cylinder: with it, the capsule's other parts
    dGeomID proxy_body
    int nlinked
    CsState stepper      # stepper.h: the warm start's contacts, the islands
    CsSettings cfg


cdef struct StepJob:     # one step's collide-and-solve, run under the guard (_errors.pxi)
    Ctx* ctx
    dSpaceID space
    Slot* slots
    int n
    double dt


cdef int collide_and_solve(void* arg) noexcept nogil:
    """Collide and step (stepper.h); -1 out of memory."""
    cdef StepJob* job = <StepJob*>arg
    if cs_begin(&job.ctx.stepper, job.n) == 0 and cs_any_awake(&job.slots[0].body,
                                                               sizeof(Slot), job.n):
        dSpaceCollide(job.space, job.ctx, near_callback)
    return cs_solve(&job.ctx.stepper, &job.ctx.cfg, job.ctx.world, job.ctx.group,
                    &job.slots[0].body, sizeof(Slot), job.n, job.dt)


@cython.no_gc_clear  # __dealloc__ walks the geoms and joints to free their C memory
cdef class World:
    """One ODE world with its hash space, contact group and body slots."""

    cdef dWorldID world
    cdef dSpaceID space
    cdef Ctx ctx
    cdef Slot* slots
    cdef int n
    cdef int cap
    cdef int* faults           # slots stopped by the last step, times 4, plus FAULT_* why
    cdef unsigned long seed
    cdef double last_dt
    cdef double extent         # bodies stay within +-extent on every axis (m)
    cdef str broken            # ODE failed inside a step: why; the world is abandoned
    cdef dict slot_of          # key -> slot index
    cdef list geoms            # slot -> list of (geom address, keep-alive object or None)
    cdef dict joints           # key -> _JointRec
    cdef list pending_mass     # slot -> dMass accumulated by add_geom (as a bytes buffer)
    cdef list static_geoms     # keyless static geometry, kept until close
    cdef SrRule rule           # the sleep rule's arrays (bind_sleep), stepped in the step
    cdef tuple rule_arrays     # ... kept alive here
    cdef uint8_t* woken        # per slot: woken explicitly since the last step (the rule's)
    cdef double sleep_time, sleep_smoothing
    cdef bint unsure           # a body was put to sleep since this step's collision other
                               # than by the rule: a sleeper may touch an awake body

    def __cinit__(self) -> None:
        self.world = dWorldCreate()
        self.space = dHashSpaceCreate(NULL)
        dHashSpaceSetLevels(self.space, -1, 6)
        dSpaceSetCleanup(self.space, 0)
        memset(&self.ctx, 0, sizeof(Ctx))
        cs_init(&self.ctx.stepper)
        self.ctx.world = self.world
        self.ctx.group = dJointGroupCreate(0)
        self.ctx.max_contacts = 4
        self.ctx.proxy = dCreateSphere(NULL, 1.0)
        self.ctx.proxy_end = dCreateSphere(NULL, 1.0)
        self.ctx.proxy_body = dCreateCylinder(NULL, 1.0, 1.0)
        self.ctx.buf = <dContact*>calloc(CANDIDATES, sizeof(dContact))
        self.ctx.nmat = 1
        self.ctx.pairs = <Pair*>calloc(1, sizeof(Pair))
        self.ctx.pairs[0].collide = 1
        self.ctx.pairs[0].mode = dContactApprox1
        self.ctx.pairs[0].mu = 0.5
        self.slots = NULL
        self.faults = NULL
        self.n = 0
        self.cap = 0
        self.seed = 0
        self.last_dt = 1.0 / 60.0
        self.extent = _WORLD_EXTENT
        self.broken = None
        self.slot_of = {}
        self.geoms = []
        self.joints = {}
        self.pending_mass = []
        self.static_geoms = []
        memset(&self.rule, 0, sizeof(SrRule))
        self.rule_arrays = None
        self.woken = NULL
        self.unsure = False
        dWorldSetContactSurfaceLayer(self.world, 0.001)
        dWorldSetAutoDisableFlag(self.world, 0)   # bodies sleep by engine.physics.sleep

    def __dealloc__(self) -> None:
        self._destroy()

    cdef void _destroy(self) noexcept:
        cdef int i
        if self.world == NULL:
            return
        if self.broken is not None:  # ODE was left mid-call: calling it again may abort
            self.world = NULL
            return
        for rec in self.joints.values():
            free_joint(<_JointRec>rec)
        self.joints.clear()
        for i in range(self.n):
            free_geoms(self, i)
            if self.slots[i].body != NULL:
                dBodyDestroy(self.slots[i].body)
        for entry in self.static_geoms:
            free_geom(entry)
        self.static_geoms = []
        dJointGroupDestroy(self.ctx.group)
        if self.ctx.proxy != NULL:
            dGeomDestroy(self.ctx.proxy)
            dGeomDestroy(self.ctx.proxy_end)
            dGeomDestroy(self.ctx.proxy_body)
            self.ctx.proxy = NULL
        dSpaceDestroy(self.space)
        dWorldDestroy(self.world)
        self.world = NULL
        cs_free(&self.ctx.stepper)
        free(self.ctx.recs)
        free(self.ctx.buf)
        free(self.ctx.pairs)
        free(self.ctx.linked)
        self.ctx.linked = NULL
        self.ctx.nlinked = 0
        free(self.slots)
        free(self.faults)
        free(self.woken)
        self.woken = NULL
        self.rule_arrays = None
        self.n = 0

    def close(self) -> None:
        self._destroy()

    cdef void check(self) except *:
        if self.broken is not None:
            raise OdeFailure(self.broken)
        if self.world == NULL:
            raise RuntimeError("the ODE world is closed")

    cdef int slot(self, key) except -1:
        try:
            return self.slot_of[key]
        except KeyError:
            raise KeyError(f"no body with key {key}") from None

    cdef void grow(self) except *:
        """Room for one more slot."""
        cdef int newcap
        cdef Slot* grown
        cdef int* fgrown
        if self.n < self.cap:
            return
        newcap = max(64, self.cap * 2)
        grown = <Slot*>realloc(self.slots, newcap * sizeof(Slot))
        if grown == NULL:
            raise MemoryError()
        self.slots = grown
        fgrown = <int*>realloc(self.faults, newcap * sizeof(int))
        if fgrown == NULL:
            raise MemoryError()
        self.faults = fgrown
        self.cap = newcap

    # -- settings -------------------------------------------------------------------
    def configure(self, gravity, double erp, double cfm, int iterations,
                  int max_contacts, double warm_start, double softness,
                  int exact_rows, double extent=_WORLD_EXTENT,
                  int contact_iterations=0) -> None:
        """World settings; ``warm_start``, ``softness``, ``exact_rows`` and
        ``contact_iterations`` are stepper.h's (the resting contacts' preload, the
        contacts' CFM share, the exact islands, the iterations of islands with contacts);
        ``extent`` bounds every body's position on each axis."""
        self.check()
        if max_contacts < 1:
            raise ValueError(f"max_contacts must be at least 1, got {max_contacts}")
        if not 0.0 <= warm_start < 1.0:
            raise ValueError(f"warm start must be in [0, 1), got {warm_start}")
        if not softness >= 0.0:
            raise ValueError(f"contact softness must be >= 0, got {softness}")
        if not (extent > 0.0 and isfinite(extent)):
            raise ValueError(f"the world's extent must be a positive number, got {extent}")
        self.extent = extent
        dWorldSetGravity(self.world, gravity[0], gravity[1], gravity[2])
        dWorldSetERP(self.world, erp)
        dWorldSetCFM(self.world, cfm)
        dWorldSetQuickStepNumIterations(self.world, iterations)
        self.ctx.cfg.beta = warm_start
        self.ctx.cfg.softness = softness
        self.ctx.cfg.exact_rows = max(exact_rows, 0)
        self.ctx.cfg.contact_iterations = max(contact_iterations, 0)
        free(self.ctx.buf)
        self.ctx.buf = <dContact*>calloc(max(max_contacts, CANDIDATES), sizeof(dContact))
        self.ctx.max_contacts = max_contacts

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

    @property
    def solver_seed(self) -> int:
        """ODE's random state for this world (QuickStep shuffles constraints with it)."""
        return self.seed

    @solver_seed.setter
    def solver_seed(self, unsigned long value) -> None:
        self.seed = value

    def bind_sleep(self, double[:, :, ::1] stack, double[::1] smoothing, double[::1] timer,
                   double[:, ::1] reference, uint8_t[::1] started, uint8_t[::1] awake,
                   const uint8_t[::1] eligible, const uint8_t[::1] movable,
                   const double[::1] bounds, double time, double smoothing_time) -> None:
        """The sleep rule's arrays (:class:`engine.physics.sleep.SleepRule`'s own, laid out
        over the current slots), which ``step(dt, sleep=True)`` advances in place; bound
        again whenever the rule lays its rows out anew or is configured."""
        cdef int n = self.n
        cdef uint8_t* marks
        if (stack.shape[0] != 3 or stack.shape[1] != 6 or stack.shape[2] != n
                or reference.shape[0] != 6 or reference.shape[1] != n
                or smoothing.shape[0] != n or timer.shape[0] != n or started.shape[0] != n
                or awake.shape[0] != n or eligible.shape[0] != n or movable.shape[0] != n
                or bounds.shape[0] != 6):
            raise ValueError(f"bind_sleep: the sleep rule's arrays must have {n} rows")
        if not (time > 0.0 and smoothing_time > 0.0):
            raise ValueError(f"bind_sleep: times must be positive, got {time}, "
                             f"{smoothing_time}")
        marks = <uint8_t*>realloc(self.woken, max(n, 1))
        if marks == NULL:
            raise MemoryError()
        self.woken = marks
        self.rule_arrays = (stack, smoothing, timer, reference, started, awake, eligible,
                            movable, bounds)
        self.rule.n = n
        if n:
            self.rule.stack, self.rule.smoothing = &stack[0, 0, 0], &smoothing[0]
            self.rule.timer, self.rule.reference = &timer[0], &reference[0, 0]
            self.rule.started, self.rule.awake = &started[0], &awake[0]
            self.rule.eligible, self.rule.movable = &eligible[0], &movable[0]
        self.rule.bounds = &bounds[0]
        self.sleep_time, self.sleep_smoothing = time, smoothing_time

    # -- the step -------------------------------------------------------------------
    # Long: the step as one sequence, the GIL released once around it
    def step(self, double dt, bint sleep=False) -> list:
        """Aim the drives, collide and step (stepper.h: exact islands, warm-started
        contacts) with the GIL released and ODE's failures guarded, then check every moving
        body (the contacts are recorded when read: :func:`contacts`); with
        ``sleep``, the sleep rule bound by :meth:`bind_sleep` then puts quiet islands to
        sleep (stepper.h's cs_sleep, over the islands of this step). Returns (key, FAULT_*) of the bodies stopped. Raises
        OdeFailure when ODE fails inside (the world is then abandoned)."""
        cdef int nf = 0, failed, solved = 0, i, slept = 0
        cdef double keep = 0.0
        cdef bint unbound
        cdef StepJob job
        self.check()
        if not dt > 0.0:
            raise ValueError(f"dt must be positive, got {dt}")
        unbound = sleep and (self.rule_arrays is None or self.rule.n != self.n)
        if unbound:  # (raised after the step, so a failure inside ODE is told first)
            sleep = False
        if sleep:
            keep = exp(-dt / self.sleep_smoothing)
        dAllocateODEDataForThread(dAllocateMaskAll)
        dJointGroupEmpty(self.ctx.group)
        self.ctx.nrec = 0
        self.ctx.records_owed = 0
        self.ctx.oom = 0
        self.last_dt = dt
        self.ctx.dt = dt
        if self.joints:
            drive_joints(self, dt)
        dRandSetSeed(self.seed)
        self.unsure = False  # the collision wakes every sleeper an awake body touches
        with nogil:
            kinematic_lead(self, dt)
            job.ctx = &self.ctx
            job.space = self.space
            job.slots = self.slots
            job.n = self.n
            job.dt = dt
            failed = guarded(collide_and_solve, &job, &solved)
            if not failed:
                if solved < 0:
                    self.ctx.oom = 1
                kinematic_arrive(self, dt)
                self.ctx.records_owed = 1  # completed when read: contacts()
                nf = check_bodies(self)
                if sleep and self.n and not self.ctx.stepper.oom:
                    for i in range(self.n):
                        self.woken[i] = self.slots[i].woken
                        self.slots[i].woken = 0
                    slept = cs_sleep(&self.ctx.stepper, &self.rule, &self.slots[0].body,
                                     sizeof(Slot), self.n, dt, keep, self.sleep_time,
                                     self.woken)
        if failed:
            self.ctx.nrec = 0  # the world is abandoned: no contact of this step is told
            self.broken = (f"ODE error {ode_failure_code()}: "
                           f"{ode_failure().decode('utf-8', 'replace')}")
            raise OdeFailure(self.broken)
        self.seed = dRandGetSeed()
        if self.ctx.oom or self.ctx.stepper.oom:
            raise MemoryError("out of memory while recording contacts")
        if slept < 0:
            raise MemoryError("out of memory while putting bodies to sleep")
        if unbound:
            raise RuntimeError("step(sleep=True): the sleep rule is not bound to the "
                               "current bodies (bind_sleep)")
        return [(self.slots[self.faults[k] >> 2].key, self.faults[k] & 3) for k in range(nf)]
