# Geoms: a body's collision shapes (kept in ``World.geoms`` with what keeps their data
# alive), the mass they give it, and keyless static planes.


cdef class _GeomBuild:
    """What a shape kind's builder needs, and what it leaves: the mass the shape gives
    at ``density`` (about its own origin; none on a static body), the triangle data it
    owns (``td``) and the arrays that must live as long as the geom (``keep``)."""
    cdef dSpaceID space
    cdef double dims[4]
    cdef double density
    cdef bint dynamic        # on a body (not static): it has a mass
    cdef object vertices
    cdef object faces
    cdef object planes
    cdef object polygons
    cdef dMass m
    cdef dTriMeshDataID td
    cdef object keep


ctypedef dGeomID (*GeomBuilder)(_GeomBuild b) except NULL

#: One builder per shape kind, indexed by the kind (GEOM_SPHERE ... GEOM_HULL).
cdef GeomBuilder GEOM_BUILDERS[7]


cdef dGeomID build_sphere(_GeomBuild b) except NULL:
    dMassSetSphere(&b.m, b.density, b.dims[0])
    return dCreateSphere(b.space, b.dims[0])


cdef dGeomID build_box(_GeomBuild b) except NULL:
    dMassSetBox(&b.m, b.density, b.dims[0], b.dims[1], b.dims[2])
    return dCreateBox(b.space, b.dims[0], b.dims[1], b.dims[2])


cdef dGeomID build_capsule(_GeomBuild b) except NULL:
    dMassSetCapsule(&b.m, b.density, 3, b.dims[0], b.dims[1])
    return dCreateCapsule(b.space, b.dims[0], b.dims[1])


cdef dGeomID build_cylinder(_GeomBuild b) except NULL:
    dMassSetCylinder(&b.m, b.density, 3, b.dims[0], b.dims[1])
    return dCreateCylinder(b.space, b.dims[0], b.dims[1])


cdef dGeomID build_plane(_GeomBuild b) except NULL:
    if b.dynamic:
        raise ValueError("a plane is infinite and can only belong to a static body")
    return dCreatePlane(b.space, b.dims[0], b.dims[1], b.dims[2], b.dims[3])


cdef dTriMeshDataID triangles(cnp.ndarray verts, cnp.ndarray idx):
    """ODE's triangle data over ``verts`` (n x 3 float64) and ``idx`` (m x 3 uint32),
    which must outlive it."""
    cdef dTriMeshDataID td = dGeomTriMeshDataCreate()
    dGeomTriMeshDataBuildDouble(td, verts.data, 3 * sizeof(double), verts.shape[0],
                                idx.data, idx.shape[0] * 3, 3 * sizeof(dTriIndex))
    return td


cdef dGeomID build_mesh(_GeomBuild b) except NULL:
    cdef cnp.ndarray verts = np.ascontiguousarray(b.vertices, dtype=np.float64)
    cdef cnp.ndarray idx = np.ascontiguousarray(b.faces, dtype=np.uint32)
    b.td = triangles(verts, idx)
    # the edge angles convex-trimesh collision needs (without them ODE aborts the process
    # when a hull touches the mesh), and the concave edges capsules use
    dGeomTriMeshDataPreprocess2(b.td, (1 << dTRIDATAPREPROCESS_BUILD_FACE_ANGLES)
                                | (1 << dTRIDATAPREPROCESS_BUILD_CONCAVE_EDGES), NULL)
    cdef dGeomID g = dCreateTriMesh(b.space, b.td, NULL, NULL, NULL)
    if b.dynamic:
        dMassSetTrimesh(&b.m, b.density, g)
    b.keep = (verts, idx)
    return g


cdef dGeomID build_hull(_GeomBuild b) except NULL:
    cdef cnp.ndarray pl = np.ascontiguousarray(b.planes, dtype=np.float64)
    cdef cnp.ndarray verts = np.ascontiguousarray(b.vertices, dtype=np.float64)
    cdef cnp.ndarray poly = np.ascontiguousarray(b.polygons, dtype=np.uint32)
    cdef cnp.ndarray idx
    cdef dTriMeshDataID td
    cdef int saved
    cdef char text[16384]
    cdef CFILE* printed = stdout_begin(&saved)  # ODE prints its checks of the data
    cdef dGeomID g = dCreateConvex(b.space, <dReal*>pl.data, pl.shape[0],
                                   <dReal*>verts.data, verts.shape[0],
                                   <unsigned int*>poly.data)
    keep_printed(text, stdout_end(printed, saved, text, sizeof(text)))
    b.keep = (pl, verts, poly)
    if b.dynamic:
        # ODE has no convex mass; the same triangles as a mesh give it exactly.
        idx = np.ascontiguousarray(b.faces, dtype=np.uint32)
        td = triangles(verts, idx)
        tmp = dCreateTriMesh(NULL, td, NULL, NULL, NULL)
        dMassSetTrimesh(&b.m, b.density, tmp)
        dGeomDestroy(tmp)
        dGeomTriMeshDataDestroy(td)
    return g


GEOM_BUILDERS[GEOM_SPHERE] = build_sphere
GEOM_BUILDERS[GEOM_BOX] = build_box
GEOM_BUILDERS[GEOM_CAPSULE] = build_capsule
GEOM_BUILDERS[GEOM_CYLINDER] = build_cylinder
GEOM_BUILDERS[GEOM_PLANE] = build_plane
GEOM_BUILDERS[GEOM_MESH] = build_mesh
GEOM_BUILDERS[GEOM_HULL] = build_hull


cdef add_mass(World w, int i, _GeomBuild b, dGeomID g, const double* q, double[::1] offset):
    """The shape's mass, turned and moved to its place, joins the body's pending mass; a
    shape without volume is destroyed and refused."""
    cdef dMatrix3 R
    if not dMassCheck(&b.m) or not b.m.mass > 0.0:
        dGeomDestroy(g)
        if b.td != NULL:
            dGeomTriMeshDataDestroy(b.td)
        raise ValueError("shape has no positive volume (is the mesh closed and "
                         "consistently wound?)")
    dRfromQ(R, q)
    dMassRotate(&b.m, R)
    dMassTranslate(&b.m, offset[0], offset[1], offset[2])
    dMassAdd(<dMass*><char*>w.pending_mass[i], &b.m)


def add_geom(World w, key, int kind, double[::1] dims, double[::1] offset, double[::1] rotation,
             double density, int material, uint32_t category, uint32_t mask,
             vertices=None, faces=None, planes=None, polygons=None) -> None:
    """Add one collision shape to a body; its mass (at ``density``) joins the body's."""
    cdef int i = w.slot(key)
    cdef Slot* s = &w.slots[i]
    cdef double q[4]
    cdef GeomInfo* info
    cdef int k
    if not 0 <= kind < 7:
        raise ValueError(f"unknown geom kind {kind}")
    cdef _GeomBuild b = _GeomBuild()
    b.space = w.space
    for k in range(min(4, dims.shape[0])):
        b.dims[k] = dims[k]
    b.density = density
    b.dynamic = s.body != NULL
    b.vertices, b.faces, b.planes, b.polygons = vertices, faces, planes, polygons
    b.td = NULL
    dMassSetZero(&b.m)
    for k in range(4):
        q[k] = rotation[k]
    qnormalize(q)
    cdef dGeomID g = GEOM_BUILDERS[kind](b)
    if b.dynamic and kind != GEOM_PLANE:
        add_mass(w, i, b, g, q, offset)
    info = <GeomInfo*>malloc(sizeof(GeomInfo))
    info.key = key
    info.material = material
    info.category = category
    info.mask = mask
    info.movable = 1 if s.kind == KIND_DYNAMIC else 0
    info.geom_class = dGeomGetClass(g)
    dGeomSetData(g, info)
    dGeomSetCategoryBits(g, category)
    dGeomSetCollideBits(g, mask)
    entry = [<size_t>g, <size_t>b.td, b.keep, (offset[0], offset[1], offset[2]),
             (q[0], q[1], q[2], q[3]), kind]
    w.geoms[i].append(entry)
    if b.dynamic:
        dGeomSetBody(g, s.body)
        if (offset[0] != 0.0 or offset[1] != 0.0 or offset[2] != 0.0 or q[0] != 1.0):
            # geoms at the body origin skip ODE's per-step offset transform
            dGeomSetOffsetQuaternion(g, q)
            dGeomSetOffsetPosition(g, offset[0], offset[1], offset[2])
    elif kind != GEOM_PLANE:
        place_static_geom(s, entry)


cdef void place_static_geom(Slot* s, list entry) noexcept:
    cdef dGeomID g = <dGeomID><size_t>entry[0]
    cdef double off[3]
    cdef double rq[4]
    cdef double wo[3]
    cdef double wq[4]
    cdef int k
    if entry[5] == GEOM_PLANE:
        return
    for k in range(3):
        off[k] = entry[3][k]
    for k in range(4):
        rq[k] = entry[4][k]
    qrotate(&s.pose[3], off, wo)
    qmul(&s.pose[3], rq, wq)
    dGeomSetPosition(g, s.pose[0] + wo[0], s.pose[1] + wo[1], s.pose[2] + wo[2])
    dGeomSetQuaternion(g, wq)


def finish_body(World w, key, double mass, com=None, inertia=None) -> None:
    """Give the body its mass (``mass`` > 0 rescales the shapes' total) at its COM: the
    shapes' centroid, or ``com`` (entity frame) with the shapes' inertia about their
    centroid; ``inertia`` (9 numbers, row-major: the tensor about the COM in the entity
    frame) replaces theirs."""
    cdef int i = w.slot(key)
    cdef Slot* s = &w.slots[i]
    cdef dMass* m = <dMass*><char*>w.pending_mass[i]
    cdef double c[3]
    cdef int k
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
    if com is not None:
        for k in range(3):
            c[k] = com[k]
    if inertia is not None:
        dMassSetParameters(m, m.mass, 0.0, 0.0, 0.0, inertia[0], inertia[4], inertia[8],
                           inertia[1], inertia[2], inertia[5])
    if not dMassCheck(m):
        raise ValueError("the body's shapes give an invalid mass distribution"
                         if inertia is None else "its inertia is not positive definite")
    dBodySetMass(s.body, m)
    if s.kind == KIND_KINEMATIC:
        dBodySetKinematic(s.body)  # setting a mass makes a body dynamic again
    memcpy(s.com, c, 3 * sizeof(double))
    if c[0] != 0.0 or c[1] != 0.0 or c[2] != 0.0:
        move_to_com(w, i, c)
    store_good(w, i)


cdef void move_to_com(World w, int i, const double* c):
    """ODE's body sits at its centre of mass ``c`` (entity frame): its geoms' offsets move
    back by ``c``, and the body and its velocity (given at the entity origin) forward."""
    cdef Slot* s = &w.slots[i]
    cdef double wc[3]
    cdef double q[4]
    cdef int k
    cdef const dReal* p
    cdef const dReal* v
    cdef const dReal* av
    for entry in w.geoms[i]:
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
    av = dBodyGetAngularVel(s.body)
    dBodySetLinearVel(s.body, v[0] + (av[1] * wc[2] - av[2] * wc[1]),
                      v[1] + (av[2] * wc[0] - av[0] * wc[2]),
                      v[2] + (av[0] * wc[1] - av[1] * wc[0]))


cdef void free_geom(list entry) noexcept:
    cdef dGeomID g = <dGeomID><size_t>entry[0]
    cdef dTriMeshDataID td = <dTriMeshDataID><size_t>entry[1]
    free(dGeomGetData(g))
    dGeomDestroy(g)
    if td != NULL:
        dGeomTriMeshDataDestroy(td)


cdef void free_geoms(World w, int i) noexcept:
    for entry in w.geoms[i]:
        free_geom(entry)
    w.geoms[i] = []


def add_static_plane(World w, double a, double b, double c, double d, int material,
                     uint32_t category, uint32_t mask) -> None:
    cdef dGeomID g = dCreatePlane(w.space, a, b, c, d)
    cdef GeomInfo* info = <GeomInfo*>malloc(sizeof(GeomInfo))
    info.key = -1
    info.material = material
    info.category = category
    info.mask = mask
    info.movable = 0
    info.geom_class = dGeomGetClass(g)
    dGeomSetData(g, info)
    dGeomSetCategoryBits(g, category)
    dGeomSetCollideBits(g, mask)
    w.static_geoms.append([<size_t>g, 0, None, None, None, GEOM_PLANE])
