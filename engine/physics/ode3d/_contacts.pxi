# Contacts: the near callback (pair filter, material lookup, contact records, each
# completed when read after the step), ray casts.

cdef struct RayCtx:
    dGeomID ray
    int64_t ignore
    uint32_t mask
    int hit
    int64_t key
    double pos[3]
    double normal[3]
    double depth


cdef inline bint culls_itself(int k) noexcept nogil:
    """Spheres touch at one point; ODE's box and plane colliders pick spread points
    themselves when asked for fewer than they find (``k``: the geom's class)."""
    return k == dSphereClass or k == dBoxClass or k == dPlaneClass


cdef inline double apart2(dContact* a, dContact* b) noexcept nogil:
    cdef double d0 = a.geom.pos[0] - b.geom.pos[0]
    cdef double d1 = a.geom.pos[1] - b.geom.pos[1]
    cdef double d2 = a.geom.pos[2] - b.geom.pos[2]
    return d0 * d0 + d1 * d1 + d2 * d2


cdef inline void swap_contacts(dContact* buf, double* near, int i, int j) noexcept nogil:
    cdef dContact t
    cdef double d
    if i == j:
        return
    memcpy(&t, &buf[i], sizeof(dContact))
    memcpy(&buf[i], &buf[j], sizeof(dContact))
    memcpy(&buf[j], &t, sizeof(dContact))
    d = near[i]
    near[i] = near[j]
    near[j] = d


cdef int spread_contacts(dContact* buf, int n, int keep) noexcept nogil:
    """Keep ``keep`` of ``n`` contacts spread over the contact patch — the deepest, then
    each time the one farthest from those kept — and not the first few a collider found,
    which may all lie on one side (a cylinder standing on a box then rocks forever)."""
    cdef double near[CANDIDATES]
    cdef int i, k, best
    cdef double d
    if n <= keep:
        return n
    near[0] = 0.0
    best = 0
    for i in range(1, n):
        if buf[i].geom.depth > buf[best].geom.depth:
            best = i
    swap_contacts(buf, near, 0, best)
    for i in range(1, n):
        near[i] = apart2(&buf[i], &buf[0])
    for k in range(1, keep):
        best = k
        for i in range(k + 1, n):
            if near[i] > near[best]:
                best = i
        swap_contacts(buf, near, k, best)
        for i in range(k + 1, n):
            d = apart2(&buf[i], &buf[k])
            if d < near[i]:
                near[i] = d
    return keep


cdef int collide(Ctx* c, dGeomID o1, int k1, dGeomID o2, int k2, int most) noexcept nogil:
    """dCollide into ``c.buf``, but a capsule against a triangle mesh as its parts: the
    cylinder between its caps and the two cap spheres, each collided with the mesh (libode's
    capsule-trimesh test throws a small mesh resting on a large capsule off it: the
    conformance scenes ColliderTypeMatrix 16 and 17; its sphere- and cylinder-trimesh tests
    hold it). The contacts of the three, up to ``most``, the caller thins as ever (``k1``,
    ``k2``: the geoms' classes)."""
    cdef dGeomID cap
    cdef dReal r, length
    cdef const dReal* p
    cdef const dReal* R
    cdef int n = 0
    cdef int i, part
    cdef double side
    cdef dGeomID proxy
    if not ((k1 == dCapsuleClass and k2 == dTriMeshClass) or
            (k1 == dTriMeshClass and k2 == dCapsuleClass)) or c.proxy == NULL:
        return dCollide(o1, o2, most, &c.buf[0].geom, sizeof(dContact))
    cap = o1 if k1 == dCapsuleClass else o2
    dGeomCapsuleGetParams(cap, &r, &length)
    p = dGeomGetPosition(cap)
    R = dGeomGetRotation(cap)   # 3x4, row-major: the axis (local Z) is column 2
    dGeomSphereSetRadius(c.proxy, r)
    dGeomSphereSetRadius(c.proxy_end, r)
    dGeomCylinderSetParams(c.proxy_body, r, length if length > 0 else 1e-9)
    dGeomSetPosition(c.proxy_body, p[0], p[1], p[2])
    dGeomSetRotation(c.proxy_body, R)
    for part in range(3):
        if n >= most:
            break
        if part == 0:
            proxy = c.proxy_body
        else:
            side = length / 2 if part == 1 else -length / 2
            proxy = c.proxy if part == 1 else c.proxy_end
            dGeomSetPosition(proxy, p[0] + side * R[2], p[1] + side * R[6], p[2] + side * R[10])
        if k1 == dCapsuleClass:
            n += dCollide(proxy, o2, most - n, &c.buf[n].geom, sizeof(dContact))
        else:
            n += dCollide(o1, proxy, most - n, &c.buf[n].geom, sizeof(dContact))
    for i in range(n):
        c.buf[i].geom.g1 = o1
        c.buf[i].geom.g2 = o2
    return n


cdef inline bint linked_to_static(Ctx* c, int64_t body, int64_t static) noexcept nogil:
    cdef int i
    for i in range(c.nlinked):
        if c.linked[2 * i] == body and c.linked[2 * i + 1] == static:
            return True
    return False


cdef inline void set_surface(dSurfaceParameters* f, Pair* p) noexcept nogil:
    f.mode = p.mode
    f.mu = p.mu
    f.bounce = p.bounce
    f.bounce_vel = p.bounce_vel
    f.soft_erp = p.soft_erp
    f.soft_cfm = p.soft_cfm


cdef int make_contacts(Ctx* c, dGeomID o1, GeomInfo* g1, dGeomID o2, GeomInfo* g2,
                       dBodyID b1, dBodyID b2, Pair* p) noexcept nogil:
    """A pair's contacts, their surfaces from ``p``, kept by stepper.h; how many, or -1
    out of memory. Where both geoms pick their own points (boxes, spheres, planes: most
    pairs), ODE collides straight into stepper.h's room; the others collide into
    ``c.buf``, thinned to ``max_contacts`` spread points, and are copied there."""
    cdef CsContact* room
    cdef int n, i
    if culls_itself(g1.geom_class) and culls_itself(g2.geom_class):
        room = cs_room(&c.stepper, c.max_contacts)
        if room == NULL:
            return -1
        n = dCollide(o1, o2, c.max_contacts, &room[0].contact.geom, sizeof(CsContact))
        for i in range(n):
            set_surface(&room[i].contact.surface, p)
        if n:
            cs_keep(&c.stepper, &c.cfg, n, b1, b2, c.dt)
        return n
    if c.max_contacts >= CANDIDATES:
        n = collide(c, o1, g1.geom_class, o2, g2.geom_class, c.max_contacts)
    else:
        n = spread_contacts(c.buf, collide(c, o1, g1.geom_class, o2, g2.geom_class,
                                           CANDIDATES), c.max_contacts)
    for i in range(n):
        set_surface(&c.buf[i].surface, p)
    if n and cs_collect(&c.stepper, &c.cfg, c.buf, n, b1, b2, c.dt) < 0:
        return -1
    return n


cdef void near_callback(void* data, dGeomID o1, dGeomID o2) noexcept nogil:
    cdef Ctx* c = <Ctx*>data
    cdef GeomInfo* g1
    cdef GeomInfo* g2
    cdef GeomInfo* gt
    cdef dBodyID b1
    cdef dBodyID b2
    cdef dGeomID ot
    cdef Pair* p
    cdef int n, i, k
    cdef ContactRec* grown
    g1 = <GeomInfo*>dGeomGetData(o1)
    g2 = <GeomInfo*>dGeomGetData(o2)
    if g1 == NULL or g2 == NULL:   # a space (it has no GeomInfo), or a geom not ours
        if dGeomIsSpace(o1) or dGeomIsSpace(o2):
            dSpaceCollide2(o1, o2, data, near_callback)
        return
    if g1.movable == 0 and g2.movable == 0:
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
    if b2 == NULL and c.nlinked and linked_to_static(c, g1.key, g2.key):
        return                   # jointed to this static body: no contacts, as between bodies
    p = &c.pairs[g1.material * c.nmat + g2.material]
    if p.collide == 0:
        return
    n = make_contacts(c, o1, g1, o2, g2, b1, b2, p)
    if n < 0:
        c.oom = 1
        return
    if c.nrec + n > c.caprec:
        k = c.caprec * 2 if c.caprec > 0 else 1024
        while k < c.nrec + n:
            k *= 2
        grown = <ContactRec*>realloc(c.recs, k * sizeof(ContactRec))
        if grown == NULL:
            c.oom = 1
            return
        c.recs = grown
        c.caprec = k
    for i in range(c.nrec, c.nrec + n):
        c.recs[i].a = g1.key     # the rest of each record when read (complete_records)
        c.recs[i].b = g2.key
    c.nrec += n


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


cdef struct OverlapCtx:
    dGeomID geom
    int64_t key
    uint32_t category
    uint32_t mask
    int64_t found[16]
    int n


cdef void overlap_callback(void* data, dGeomID o1, dGeomID o2) noexcept nogil:
    cdef OverlapCtx* o = <OverlapCtx*>data
    cdef dGeomID other = o2 if o1 == o.geom else o1
    cdef GeomInfo* g = <GeomInfo*>dGeomGetData(other)
    cdef dContactGeom cg
    if g == NULL or (g.key == o.key and g.key >= 0) or o.n >= 16:
        return
    if (g.category & o.mask) == 0 or (o.category & g.mask) == 0:
        return
    if dCollide(o.geom, other, 1, &cg, sizeof(dContactGeom)) > 0:
        o.found[o.n] = g.key
        o.n += 1


def overlapping(World w, key) -> list:
    """Keys of what the body's geoms intersect now (-1: static geometry), whether its own
    collisions are on or off: a body passing through things asks before it collides again."""
    cdef int i = w.slot(key)
    cdef OverlapCtx o
    cdef GeomInfo* info
    cdef dGeomID g
    cdef int enabled, k
    found = set()
    for entry in w.geoms[i]:
        g = <dGeomID><size_t>entry[0]
        info = <GeomInfo*>dGeomGetData(g)
        memset(&o, 0, sizeof(OverlapCtx))
        o.geom = g
        o.key = info.key
        o.category = info.category
        o.mask = info.mask
        enabled = dGeomIsEnabled(g)
        dGeomEnable(g)
        dSpaceCollide2(g, <dGeomID>w.space, &o, overlap_callback)
        if not enabled:
            dGeomDisable(g)
        for k in range(o.n):
            found.add(o.found[k])
    return sorted(found)


cdef struct WakeCtx:
    dGeomID geom
    dBodyID own
    Slot* slots
    uint32_t category
    uint32_t mask


cdef void wake_callback(void* data, dGeomID o1, dGeomID o2) noexcept nogil:
    cdef WakeCtx* c = <WakeCtx*>data
    cdef dGeomID other = o2 if o1 == c.geom else o1
    cdef GeomInfo* g = <GeomInfo*>dGeomGetData(other)
    cdef dBodyID b = dGeomGetBody(other)
    if other == c.geom or g == NULL or b == NULL or b == c.own or dBodyIsEnabled(b):
        return
    if (g.category & c.mask) == 0 or (c.category & g.mask) == 0:
        return
    dBodyEnable(b)  # an explicit wake: its quiet stretch starts over
    c.slots[<intptr_t>dBodyGetData(b)].woken = 1


cdef void wake_touching(World w, int i):
    """Wake the sleepers whose geoms' bounds overlap slot ``i``'s: what rested on it or
    against it before it is removed, moved or made to pass through things. ODE wakes a
    sleeper only through a contact made in a step, which a body gone from under it never
    makes (a crate asleep on a removed box hung in the air).

    The search is ODE's, against every geom of the space (its hash space has no local
    query): 0.1 ms a body among 5,000. It is skipped where it can find nothing: a dynamic
    body awake since the last step (not woken since, by hand or by this search) touches
    no sleeper, for a step's collision woke every sleeper an awake body touched and the
    sleep rule puts touching bodies to sleep together, unless a body was put to sleep
    some other way since (``unsure``: by hand, a saved state, a body stopped)."""
    cdef WakeCtx c
    cdef GeomInfo* info
    cdef dGeomID g
    cdef int enabled
    cdef Slot* s = &w.slots[i]
    if (s.body != NULL and s.kind == KIND_DYNAMIC and dBodyIsEnabled(s.body) and
            not s.woken and not w.unsure):
        return
    for entry in w.geoms[i]:
        g = <dGeomID><size_t>entry[0]
        info = <GeomInfo*>dGeomGetData(g)
        c.geom = g
        c.own = w.slots[i].body
        c.slots = w.slots
        c.category = info.category
        c.mask = info.mask
        enabled = dGeomIsEnabled(g)
        dGeomEnable(g)
        dSpaceCollide2(g, <dGeomID>w.space, &c, wake_callback)
        if not enabled:
            dGeomDisable(g)


cdef void complete_records(Ctx* c, double dt) noexcept nogil:
    """Each contact's point, normal, depth and impulse, |f|·dt of its whole force
    (stepper.h's cs_whole_forces adds what it preloaded to what the solver found), from
    the step's contacts, which stepper.h keeps until the next step (the near callback
    recorded only the pair's keys: a geom may be gone by now). Run when the records are
    first read after a step, not by the step: a step whose contacts nobody reads does not
    pay for them (the resting rules read what the solver found, not these)."""
    cdef int i, k
    cdef ContactRec* rec
    cdef const dContactGeom* g
    c.records_owed = 0
    for i in range(min(c.nrec, c.stepper.ncontacts)):
        rec = &c.recs[i]
        g = &c.stepper.contacts[i].contact.geom
        for k in range(3):
            rec.pos[k] = g.pos[k]
            rec.normal[k] = g.normal[k]
        rec.depth = g.depth
        rec.impulse = 0.0
    if c.oom or c.stepper.oom:
        return
    cs_whole_forces(&c.stepper)
    for i in range(c.nrec):
        c.recs[i].impulse = norm3(&c.stepper.forces[3 * i]) * dt


def contacts(World w) -> np.ndarray:
    """The last step's contacts as raw bytes shaped for CONTACT_DTYPE (caller views them),
    completed on the first read after the step."""
    if w.ctx.records_owed:
        complete_records(&w.ctx, w.ctx.dt)
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
