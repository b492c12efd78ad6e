# Geoms: a body's collision shapes (kept in ``World.geoms`` with what keeps their data
# alive), the mass they give it, and keyless static planes.


def add_geom(World w, key, int kind, double[::1] dims, double[::1] offset, double[::1] rotation,
             double density, int material, uint32_t category, uint32_t mask,
             vertices=None, faces=None, planes=None, polygons=None) -> None:
    """Add one collision shape to a body; its mass (at ``density``) joins the body's."""
    cdef int i = w.slot(key)
    cdef Slot* s = &w.slots[i]
    cdef dGeomID g = NULL
    cdef dTriMeshDataID td = NULL
    cdef dMass m
    cdef dMatrix3 R
    cdef double q[4]
    cdef GeomInfo* info
    cdef cnp.ndarray verts
    cdef cnp.ndarray idx
    cdef cnp.ndarray pl
    cdef cnp.ndarray poly
    cdef CFILE* printed
    cdef int saved
    cdef char text[16384]
    keep = None
    q[0] = rotation[0]
    q[1] = rotation[1]
    q[2] = rotation[2]
    q[3] = rotation[3]
    qnormalize(q)
    dMassSetZero(&m)
    if kind == GEOM_SPHERE:
        g = dCreateSphere(w.space, dims[0])
        dMassSetSphere(&m, density, dims[0])
    elif kind == GEOM_BOX:
        g = dCreateBox(w.space, dims[0], dims[1], dims[2])
        dMassSetBox(&m, density, dims[0], dims[1], dims[2])
    elif kind == GEOM_CAPSULE:
        g = dCreateCapsule(w.space, dims[0], dims[1])
        dMassSetCapsule(&m, density, 3, dims[0], dims[1])
    elif kind == GEOM_CYLINDER:
        g = dCreateCylinder(w.space, dims[0], dims[1])
        dMassSetCylinder(&m, density, 3, dims[0], dims[1])
    elif kind == GEOM_PLANE:
        if s.body != NULL:
            raise ValueError("a plane is infinite and can only belong to a static body")
        g = dCreatePlane(w.space, dims[0], dims[1], dims[2], dims[3])
    elif kind == GEOM_MESH:
        verts = np.ascontiguousarray(vertices, dtype=np.float64)
        idx = np.ascontiguousarray(faces, dtype=np.uint32)
        td = dGeomTriMeshDataCreate()
        dGeomTriMeshDataBuildDouble(td, verts.data, 3 * sizeof(double), verts.shape[0],
                                    idx.data, idx.shape[0] * 3, 3 * sizeof(dTriIndex))
        # the edge angles convex-trimesh collision needs (without them ODE aborts the
        # process when a hull touches the mesh), and the concave edges capsules use
        dGeomTriMeshDataPreprocess2(td, (1 << dTRIDATAPREPROCESS_BUILD_FACE_ANGLES)
                                    | (1 << dTRIDATAPREPROCESS_BUILD_CONCAVE_EDGES), NULL)
        g = dCreateTriMesh(w.space, td, NULL, NULL, NULL)
        if s.body != NULL:
            dMassSetTrimesh(&m, density, g)
        keep = (verts, idx)
    elif kind == GEOM_HULL:
        pl = np.ascontiguousarray(planes, dtype=np.float64)
        verts = np.ascontiguousarray(vertices, dtype=np.float64)
        poly = np.ascontiguousarray(polygons, dtype=np.uint32)
        printed = stdout_begin(&saved)  # ODE prints its checks of the data to stdout
        g = dCreateConvex(w.space, <dReal*>pl.data, pl.shape[0], <dReal*>verts.data,
                          verts.shape[0], <unsigned int*>poly.data)
        keep_printed(text, stdout_end(printed, saved, text, sizeof(text)))
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
        dMassAdd(<dMass*><char*>w.pending_mass[i], &m)
    info = <GeomInfo*>malloc(sizeof(GeomInfo))
    info.key = key
    info.material = material
    info.category = category
    info.mask = mask
    info.movable = 1 if s.kind == KIND_DYNAMIC else 0
    dGeomSetData(g, info)
    dGeomSetCategoryBits(g, category)
    dGeomSetCollideBits(g, mask)
    entry = [<size_t>g, <size_t>td, keep, (offset[0], offset[1], offset[2]),
             (q[0], q[1], q[2], q[3]), kind]
    w.geoms[i].append(entry)
    if s.body != NULL:
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
    cdef double wc[3]
    cdef double q[4]
    cdef int k
    cdef const dReal* p
    cdef const dReal* v
    cdef const dReal* av
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
    if c[0] == 0.0 and c[1] == 0.0 and c[2] == 0.0:
        store_good(w, i)
        return
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
    store_good(w, i)


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
    dGeomSetData(g, info)
    dGeomSetCategoryBits(g, category)
    dGeomSetCollideBits(g, mask)
    w.static_geoms.append([<size_t>g, 0, None, None, None, GEOM_PLANE])
