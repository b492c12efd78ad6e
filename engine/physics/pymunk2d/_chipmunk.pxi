# Included by _rows.pyx: the chipmunk functions its passes call, taken once at import from
# pymunk's own cffi library (``pymunk.cp``, ``pymunk.ffi``, which pymunk documents for
# such use). The passes call the very functions ``pymunk.batch`` calls, so what they read
# is the same to the bit; what they save is pymunk.batch's Python per call and its
# growable buffers, and they read one arbiter in a third of the calls. Bodies are reached
# through their cpBody pointers (``Body._body``), kept per row while the rows stand.
# Each function's C type is checked against pymunk's declaration of it at import: a
# pymunk whose chipmunk differs fails there, by name, not later in C.

ctypedef struct cpVect:
    double x
    double y

ctypedef cpVect (*_BodyVect)(void *) noexcept nogil
ctypedef double (*_BodyFloat)(void *) noexcept nogil
ctypedef void (*_SetBodyVect)(void *, cpVect) noexcept nogil
ctypedef void (*_SetBodyFloat)(void *, double) noexcept nogil
ctypedef unsigned char (*_BodyBool)(void *) noexcept nogil
ctypedef void *(*_BodyPointer)(void *) noexcept nogil
ctypedef void (*_ArbiterFunc)(void *, void *) noexcept nogil
ctypedef void (*_EachArbiter)(void *, _ArbiterFunc, void *) noexcept nogil
ctypedef void (*_ArbiterBodies)(void *, void **, void **) noexcept nogil
ctypedef int (*_ArbiterInt)(void *) noexcept nogil
ctypedef cpVect (*_ArbiterVect)(void *) noexcept nogil
ctypedef cpVect (*_ArbiterPoint)(void *, int) noexcept nogil
ctypedef double (*_ArbiterDepth)(void *, int) noexcept nogil


cdef struct _Chipmunk:
    _BodyVect position
    _BodyFloat angle
    _BodyVect velocity
    _BodyFloat spin
    _BodyVect force
    _SetBodyVect set_force
    _SetBodyVect set_velocity
    _SetBodyFloat set_spin
    _BodyBool sleeping
    _BodyPointer user_data
    _EachArbiter each_cached_arbiter
    _ArbiterBodies arbiter_bodies
    _ArbiterInt arbiter_count
    _ArbiterVect total_impulse
    _ArbiterVect normal
    _ArbiterPoint point_a
    _ArbiterPoint point_b
    _ArbiterDepth depth


cdef _Chipmunk cp

#: The chipmunk functions the passes call, in _Chipmunk's order, each with its C type as
#: pymunk's cffi declares it.
CHIPMUNK_FUNCTIONS = (
    ("cpBodyGetPosition", "struct cpVect(*)(struct cpBody *)"),
    ("cpBodyGetAngle", "double(*)(struct cpBody *)"),
    ("cpBodyGetVelocity", "struct cpVect(*)(struct cpBody *)"),
    ("cpBodyGetAngularVelocity", "double(*)(struct cpBody *)"),
    ("cpBodyGetForce", "struct cpVect(*)(struct cpBody *)"),
    ("cpBodySetForce", "void(*)(struct cpBody *, struct cpVect)"),
    ("cpBodySetVelocity", "void(*)(struct cpBody *, struct cpVect)"),
    ("cpBodySetAngularVelocity", "void(*)(struct cpBody *, double)"),
    ("cpBodyIsSleeping", "unsigned char(*)(struct cpBody *)"),
    ("cpBodyGetUserData", "void *(*)(struct cpBody *)"),
    ("cpSpaceEachCachedArbiter",
     "void(*)(struct cpSpace *, void(*)(struct cpArbiter *, void *), void *)"),
    ("cpArbiterGetBodies", "void(*)(struct cpArbiter *, struct cpBody * *, struct cpBody * *)"),
    ("cpArbiterGetCount", "int(*)(struct cpArbiter *)"),
    ("cpArbiterTotalImpulse", "struct cpVect(*)(struct cpArbiter *)"),
    ("cpArbiterGetNormal", "struct cpVect(*)(struct cpArbiter *)"),
    ("cpArbiterGetPointA", "struct cpVect(*)(struct cpArbiter *, int)"),
    ("cpArbiterGetPointB", "struct cpVect(*)(struct cpArbiter *, int)"),
    ("cpArbiterGetDepth", "double(*)(struct cpArbiter *, int)"),
)


def _chipmunk_addresses() -> list:
    """Each of CHIPMUNK_FUNCTIONS' addresses in pymunk's library, its C type checked."""
    import pymunk
    ffi, lib = pymunk.ffi, pymunk.cp
    out = []
    for name, ctype in CHIPMUNK_FUNCTIONS:
        try:
            function = ffi.addressof(lib, name)
        except (AttributeError, KeyError):
            raise ImportError(f"pymunk {pymunk.version} has no chipmunk function {name}: "
                              "engine/physics/pymunk2d/_chipmunk.pxi needs one") from None
        if ffi.typeof(function) is not ffi.typeof(ctype):
            raise ImportError(f"pymunk {pymunk.version} declares {name} as "
                              f"{ffi.typeof(function).cname}, not {ctype} "
                              "(engine/physics/pymunk2d/_chipmunk.pxi)")
        address = int(ffi.cast("uintptr_t", function))
        if not address:
            raise ImportError(f"pymunk {pymunk.version}: {name} is not linked in")
        out.append(address)
    return out


cdef void _bind_chipmunk() except *:
    cdef list a = _chipmunk_addresses()
    cp.position = <_BodyVect><uintptr_t>a[0]
    cp.angle = <_BodyFloat><uintptr_t>a[1]
    cp.velocity = <_BodyVect><uintptr_t>a[2]
    cp.spin = <_BodyFloat><uintptr_t>a[3]
    cp.force = <_BodyVect><uintptr_t>a[4]
    cp.set_force = <_SetBodyVect><uintptr_t>a[5]
    cp.set_velocity = <_SetBodyVect><uintptr_t>a[6]
    cp.set_spin = <_SetBodyFloat><uintptr_t>a[7]
    cp.sleeping = <_BodyBool><uintptr_t>a[8]
    cp.user_data = <_BodyPointer><uintptr_t>a[9]
    cp.each_cached_arbiter = <_EachArbiter><uintptr_t>a[10]
    cp.arbiter_bodies = <_ArbiterBodies><uintptr_t>a[11]
    cp.arbiter_count = <_ArbiterInt><uintptr_t>a[12]
    cp.total_impulse = <_ArbiterVect><uintptr_t>a[13]
    cp.normal = <_ArbiterVect><uintptr_t>a[14]
    cp.point_a = <_ArbiterPoint><uintptr_t>a[15]
    cp.point_b = <_ArbiterPoint><uintptr_t>a[16]
    cp.depth = <_ArbiterDepth><uintptr_t>a[17]


_bind_chipmunk()


def chipmunk_pointer(handle) -> int:
    """The address behind a pymunk object's cffi pointer (``Space._space``,
    ``Body._body``)."""
    import pymunk
    return int(pymunk.ffi.cast("uintptr_t", handle))


cdef extern from *:
    void _prefetch "__builtin_prefetch"(const void *address) noexcept nogil


cdef inline void _ahead(void *body) noexcept nogil:
    """Ask for a body's state early (a hint: after chipmunk's step little of it is
    cached; what is read is read through chipmunk's functions)."""
    _prefetch(<char *>body + 64)
    _prefetch(<char *>body + 128)
    _prefetch(<char *>body + 192)


cdef struct _Collect:
    void **arbiters
    Py_ssize_t used
    Py_ssize_t size


cdef void _collect(void *arb, void *data) noexcept nogil:
    """chipmunk's cached arbiters, in its order, into ``arbiters`` (past its end: only
    counted; the caller grows it and collects again)."""
    cdef _Collect *c = <_Collect *>data
    if c.used < c.size:
        c.arbiters[c.used] = arb
    c.used += 1


cdef void _read_arbiters(void **arbiters, Py_ssize_t m, int64_t *ints, double *floats,
                         Py_ssize_t *pairs, const _Table *table) noexcept nogil:
    """Each of ``m`` arbiters into its ARBITER_INTS/ARBITER_FLOATS row (and its bodies'
    rows into ``pairs``), as pymunk.batch's pmSpaceArbiterIteratorFuncBatched reads it
    (the same calls; an arbiter without contacts gets its ids and count only: nothing
    reads its floats). After chipmunk's step little of them is in the cache: the arbiters
    a few ahead, and their bodies, are asked for early (a hint only: what is read is
    read through chipmunk's functions)."""
    cdef Py_ssize_t i
    cdef void *a
    cdef void *b
    for i in range(m):
        if i + 8 < m:
            _prefetch(arbiters[i + 8])
            _prefetch(<char *>arbiters[i + 8] + 64)
            _prefetch(<char *>arbiters[i + 8] + 128)
        if i + 4 < m:
            cp.arbiter_bodies(arbiters[i + 4], &a, &b)
            _ahead(a)
            _ahead(b)
        _read_arbiter(arbiters[i], &ints[_AI * i], &floats[_AF * i], &pairs[2 * i], table)


cdef inline void _read_arbiter(void *arb, int64_t *ints, double *f, Py_ssize_t *pair,
                               const _Table *table) noexcept nogil:
    """One arbiter (see :func:`_read_arbiters`)."""
    cdef void *a
    cdef void *b
    cdef cpVect v
    cdef int count, k
    cp.arbiter_bodies(arb, &a, &b)
    ints[0] = <int64_t><uintptr_t>cp.user_data(a)
    ints[1] = <int64_t><uintptr_t>cp.user_data(b)
    pair[0] = _row_of(table, <uint64_t>ints[0])
    pair[1] = _row_of(table, <uint64_t>ints[1])
    count = cp.arbiter_count(arb)
    ints[2] = count
    if count <= 0:
        for k in range(_AF):
            f[k] = 0.0
        return
    v = cp.total_impulse(arb)
    f[0] = v.x
    f[1] = v.y
    v = cp.normal(arb)
    f[2] = v.x
    f[3] = v.y
    for k in range(2 if count == 2 else 1):
        v = cp.point_a(arb, k)
        f[4 + 5 * k] = v.x
        f[5 + 5 * k] = v.y
        v = cp.point_b(arb, k)
        f[6 + 5 * k] = v.x
        f[7 + 5 * k] = v.y
        f[8 + 5 * k] = cp.depth(arb, k)
    if count != 2:
        for k in range(9, _AF):
            f[k] = 0.0
