# Contacts: the near callback (pair filter, material lookup, contact joints with
# feedback, contact records), the impulses read back after the step, ray casts.

cdef struct RayCtx:
    dGeomID ray
    int64_t ignore
    uint32_t mask
    int hit
    int64_t key
    double pos[3]
    double normal[3]
    double depth


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
        c.buf[i].surface.mode = p.mode
        c.buf[i].surface.mu = p.mu
        c.buf[i].surface.bounce = p.bounce
        c.buf[i].surface.bounce_vel = p.bounce_vel
        c.buf[i].surface.soft_erp = p.soft_erp
        c.buf[i].surface.soft_cfm = p.soft_cfm
    if n and cs_collect(&c.stepper, &c.cfg, c.buf, n, b1, b2, c.dt) < 0:
        c.oom = 1
        return
    for i in range(n):
        if c.nrec >= c.caprec:
            k = c.caprec * 2 if c.caprec > 0 else 1024
            grown = <ContactRec*>realloc(c.recs, k * sizeof(ContactRec))
            if grown == NULL:
                c.oom = 1
                return
            c.recs = grown
            c.caprec = k
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


cdef dJointFeedback* contact_feedback(void* ctx, int i) noexcept nogil:
    """Contact i's feedback record (stepper.h attaches it to the contact's joint)."""
    return feedback_slot(<Ctx*>ctx, i)


cdef void record_impulses(Ctx* c, double dt) noexcept nogil:
    """Each contact's impulse, |f|·dt of its whole force (stepper.h adds what it
    preloaded to what the solver found)."""
    cdef int i
    if c.oom or c.stepper.oom:
        return
    for i in range(c.nrec):
        c.recs[i].impulse = norm3(&c.stepper.forces[3 * i]) * dt


def contacts(World w) -> np.ndarray:
    """The last step's contacts as raw bytes shaped for CONTACT_DTYPE (caller views them)."""
    cdef cnp.ndarray[cnp.uint8_t, ndim=1] out = np.empty(
        w.ctx.nrec * sizeof(ContactRec), np.uint8)
    if w.ctx.nrec:
        memcpy(out.data, w.ctx.recs, w.ctx.nrec * sizeof(ContactRec))
    return out


def raycast(World w, double ox, double oy, double oz, double dx, double dy, double dz,
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
        dSpaceCollide2(r.ray, <dGeomID>w.space, &r, ray_callback)
    dGeomDestroy(r.ray)
    if not r.hit:
        return None
    nx, ny, nz = r.normal[0], r.normal[1], r.normal[2]
    if nx * dx + ny * dy + nz * dz > 0.0:
        nx, ny, nz = -nx, -ny, -nz
    return (r.key, (r.pos[0], r.pos[1], r.pos[2]), (nx, ny, nz), r.depth)
