# Included by _rows.pyx: the chipmunk functions its passes call, taken once at import from
# pymunk's own cffi library (``pymunk.cp``, ``pymunk.ffi``, which pymunk documents for
# such use), and where the fields of an arbiter and its contacts lie. The passes call the
# very functions ``pymunk.batch`` calls, so what they read is the same to the bit; what
# they save is pymunk.batch's Python per call and its growable buffers. An arbiter's
# bodies, contact count, normal and total impulse are read from its fields (cpArbiter and
# cpContact, which pymunk's cffi declares in full: their offsets are its build's),
# with the arithmetic of chipmunk's getters (cpArbiter.c) in the same order; its points
# and depths go through the getters (they add the bodies' centres of gravity, and cpBody's
# layout is not declared). Bodies are reached through their cpBody pointers
# (``Body._body``), kept per row while the rows stand. Each function's C type and each
# field's offset and type are checked against pymunk's declarations at import: a pymunk
# whose chipmunk differs fails there, by name, not later in C.

ctypedef struct cpVect:
    double x
    double y

ctypedef cpVect (*_BodyVect)(void *) noexcept nogil
ctypedef double (*_BodyFloat)(void *) noexcept nogil
ctypedef void (*_SetBodyVect)(void *, cpVect) noexcept nogil
ctypedef void (*_SetBodyFloat)(void *, double) noexcept nogil
ctypedef unsigned char (*_BodyBool)(void *) noexcept nogil
ctypedef double (*_SpaceFloat)(void *) noexcept nogil
ctypedef void *(*_BodyPointer)(void *) noexcept nogil
ctypedef void (*_ArbiterFunc)(void *, void *) noexcept nogil
ctypedef void (*_EachArbiter)(void *, _ArbiterFunc, void *) noexcept nogil
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
    _SpaceFloat sleep_threshold
    _EachArbiter each_cached_arbiter
    _ArbiterPoint point_a
    _ArbiterPoint point_b
    _ArbiterDepth depth
    _BodyVect cog


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
    ("cpSpaceGetSleepTimeThreshold", "double(*)(struct cpSpace *)"),
    ("cpSpaceEachCachedArbiter",
     "void(*)(struct cpSpace *, void(*)(struct cpArbiter *, void *), void *)"),
    ("cpArbiterGetPointA", "struct cpVect(*)(struct cpArbiter *, int)"),
    ("cpArbiterGetPointB", "struct cpVect(*)(struct cpArbiter *, int)"),
    ("cpArbiterGetDepth", "double(*)(struct cpArbiter *, int)"),
    ("cpBodyGetCenterOfGravity", "struct cpVect(*)(struct cpBody *)"),
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
    cp.sleep_threshold = <_SpaceFloat><uintptr_t>a[10]
    cp.each_cached_arbiter = <_EachArbiter><uintptr_t>a[11]
    cp.point_a = <_ArbiterPoint><uintptr_t>a[12]
    cp.point_b = <_ArbiterPoint><uintptr_t>a[13]
    cp.depth = <_ArbiterDepth><uintptr_t>a[14]
    cp.cog = <_BodyVect><uintptr_t>a[15]


_bind_chipmunk()


cdef struct _Layout:
    # byte offsets in chipmunk's cpArbiter and cpContact, as pymunk's cffi declares them
    Py_ssize_t body_a, body_b, count, contacts, n, swapped, state
    Py_ssize_t r1, r2, jn, jt, contact  # cpContact: r1, r2, jnAcc, jtAcc; its size
    int cached  # CP_ARBITER_STATE_CACHED: from it on an arbiter has no contacts


cdef _Layout arbiter

#: The fields the passes read, each with its C type as pymunk's cffi declares it.
CHIPMUNK_FIELDS = (
    ("struct cpArbiter", "body_a", "struct cpBody *"),
    ("struct cpArbiter", "body_b", "struct cpBody *"),
    ("struct cpArbiter", "count", "int"),
    ("struct cpArbiter", "contacts", "struct cpContact *"),
    ("struct cpArbiter", "n", "struct cpVect"),
    ("struct cpArbiter", "swapped", "unsigned char"),
    ("struct cpArbiter", "state", "enum cpArbiterState"),
    ("struct cpContact", "r1", "struct cpVect"),
    ("struct cpContact", "r2", "struct cpVect"),
    ("struct cpContact", "jnAcc", "double"),
    ("struct cpContact", "jtAcc", "double"),
    ("struct cpVect", "x", "double"),
    ("struct cpVect", "y", "double"),
)


def chipmunk_layout(ffi) -> dict:
    """Each of CHIPMUNK_FIELDS' offsets in ``ffi``'s declarations (pymunk's), by
    "struct.field", with the size of cpContact and the value of CP_ARBITER_STATE_CACHED;
    ImportError naming what is missing or of another type."""
    import pymunk
    out = {}
    for struct, name, ctype in CHIPMUNK_FIELDS:
        try:
            fields = dict(ffi.typeof(struct).fields or ())
        except ffi.error:
            fields = {}
        if name not in fields:
            raise ImportError(f"pymunk {pymunk.version} declares no {struct} field {name}: "
                              "engine/physics/pymunk2d/_chipmunk.pxi reads it")
        if fields[name].type is not ffi.typeof(ctype) or fields[name].bitsize != -1:
            raise ImportError(f"pymunk {pymunk.version} declares {struct}'s {name} as "
                              f"{fields[name].type.cname}, not {ctype} "
                              "(engine/physics/pymunk2d/_chipmunk.pxi)")
        out[f"{struct}.{name}"] = fields[name].offset
    states = ffi.typeof("enum cpArbiterState").relements
    if (ffi.sizeof("struct cpVect") != sizeof(cpVect) or out["struct cpVect.y"] != sizeof(double)
            or ffi.sizeof("enum cpArbiterState") != sizeof(int)
            or "CP_ARBITER_STATE_CACHED" not in states):
        raise ImportError(f"pymunk {pymunk.version}: cpVect or cpArbiterState is not as "
                          "engine/physics/pymunk2d/_chipmunk.pxi reads them")
    out["contact"] = ffi.sizeof("struct cpContact")
    out["cached"] = states["CP_ARBITER_STATE_CACHED"]
    return out


cdef void _bind_layout() except *:
    import pymunk
    cdef dict o = chipmunk_layout(pymunk.ffi)
    arbiter.body_a = o["struct cpArbiter.body_a"]
    arbiter.body_b = o["struct cpArbiter.body_b"]
    arbiter.count = o["struct cpArbiter.count"]
    arbiter.contacts = o["struct cpArbiter.contacts"]
    arbiter.n = o["struct cpArbiter.n"]
    arbiter.swapped = o["struct cpArbiter.swapped"]
    arbiter.state = o["struct cpArbiter.state"]
    arbiter.r1 = o["struct cpContact.r1"]
    arbiter.r2 = o["struct cpContact.r2"]
    arbiter.jn = o["struct cpContact.jnAcc"]
    arbiter.jt = o["struct cpContact.jtAcc"]
    arbiter.contact = o["contact"]
    arbiter.cached = o["cached"]


_bind_layout()


cdef struct _BodyFields:
    # byte offsets in chipmunk's cpBody of v, f and w, found by :func:`probe_body`; -1
    # where it found no single answer (the setters are used)
    Py_ssize_t v, f, w


cdef _BodyFields body_fields

#: How many bytes of a cpBody the probe reads: its v, f and w lie at 80, 96 and 120 in
#: chipmunk 7, whose cpBody is 272 bytes (the struct ends with the sleeping fields).
BODY_WINDOW = 192


def probe_body(Py_ssize_t window=BODY_WINDOW) -> dict:
    """Where a cpBody keeps its velocity ``v``, force ``f`` and spin ``w``: byte offsets
    in its first ``window`` bytes, by name, each -1 where no single answer was found.

    pymunk's cffi does not declare cpBody's fields, so they are found on a throwaway
    body: each is set through pymunk (chipmunk's setter) to distinctive values, twice, and
    must lie at one and the same aligned offset both times, and apart from the others; a
    value written there must then read back through chipmunk's getter."""
    import struct

    import pymunk
    ffi = pymunk.ffi
    body = pymunk.Body(1.0, 1.0)
    raw = ffi.cast("char *", body._body)
    fields = (("v", "velocity", ((-7.3e13, 2.9e-7), (5.1e-9, -3.7e15), (-1.25e11, 6.5e-5))),
              ("f", "force", ((3.3e-11, -8.1e12), (-6.7e14, 1.9e-6), (2.5e-3, -4.75e10))),
              ("w", "angular_velocity", ((-9.7e-12,), (4.3e16,), (-1.5e-8,))))
    out = {}
    for name, attribute, values in fields:
        found = set()
        for value in values[:2]:
            setattr(body, attribute, value if len(value) == 2 else value[0])
            seen = bytes(ffi.buffer(raw, window))
            pattern = struct.pack(f"<{len(value)}d", *value)
            at = [i for i in range(0, window - len(pattern) + 1, 8)
                  if seen[i:i + len(pattern)] == pattern]
            found.add(at[0] if len(at) == 1 else -1)
        out[name] = found.pop() if len(found) == 1 else -1
        if out[name] >= 0:
            ffi.cast("double *", raw + out[name])[0:len(values[2])] = values[2]
            back = getattr(body, attribute)
            if (tuple(back) if len(values[2]) == 2 else (back,)) != values[2]:
                out[name] = -1
    spans = sorted((at, at + (8 if name == "w" else 16)) for name, at in out.items() if at >= 0)
    if any(a[1] > b[0] for a, b in zip(spans, spans[1:])):
        return {name: -1 for name in out}
    return out


#: What :func:`probe_body` found at import: the offsets the passes write at.
BODY_FIELDS = probe_body()
body_fields.v = BODY_FIELDS["v"]
body_fields.f = BODY_FIELDS["f"]
body_fields.w = BODY_FIELDS["w"]


#: A space's sleep time threshold from which no idle time reaches it: an idle time is the
#: sum of a body's quiet steps (the backend's NEVER is 1e300; infinite: no sleeping).
IDLE_UNREACHED = 1e290
cdef double _idle_unreached = IDLE_UNREACHED


cdef inline bint _idle_unread(void *space) noexcept nogil:
    """Whether the direct writes are the setters to the bit for ``space``: the probe found
    every field and no idle time can decide anything there (see :func:`_awake_velocity`)."""
    return (body_fields.v >= 0 and body_fields.f >= 0 and body_fields.w >= 0
            and cp.sleep_threshold(space) >= _idle_unreached)


cdef inline void _awake_velocity(void *body, cpVect v, double w, bint direct) noexcept nogil:
    """Set a body's velocity and spin as cpBodySetVelocity and cpBodySetAngularVelocity
    do, written straight into it where ``direct`` (:func:`_idle_unread`) and it is not
    asleep: their cpBodyActivate, on a body that is not asleep, only zeroes idle times
    (its own and those of the dynamic bodies it touches, walking its arbiters; nothing for
    a kinematic or static body), and chipmunk reads idle times only to put a component to
    sleep (cpSpaceProcessComponents' ComponentActive: one under the space's threshold keeps
    it awake) and to tell a static body (cpBodyGetType: INFINITY). A body asleep goes
    through the setters (they wake it)."""
    if not direct or cp.sleeping(body):
        cp.set_velocity(body, v)
        cp.set_spin(body, w)
        return
    (<cpVect *>(<char *>body + body_fields.v))[0] = v
    (<double *>(<char *>body + body_fields.w))[0] = w


cdef inline void _awake_force(void *body, cpVect f, bint direct) noexcept nogil:
    """Set a body's force as cpBodySetForce does, written straight into it where
    ``direct`` and it is not asleep (see :func:`_awake_velocity`)."""
    if not direct or cp.sleeping(body):
        cp.set_force(body, f)
        return
    (<cpVect *>(<char *>body + body_fields.f))[0] = f


cdef inline void *_body_a(const char *arb) noexcept nogil:
    return (<void * const *>(arb + arbiter.body_a))[0]


cdef inline void *_body_b(const char *arb) noexcept nogil:
    return (<void * const *>(arb + arbiter.body_b))[0]


cdef inline bint _swapped(const char *arb) noexcept nogil:
    return (<const unsigned char *>(arb + arbiter.swapped))[0] != 0


cdef inline int _count(const char *arb) noexcept nogil:
    """cpArbiterGetCount: none once the arbiter is only cached (its shapes apart)."""
    if (<const int *>(arb + arbiter.state))[0] < arbiter.cached:
        return (<const int *>(arb + arbiter.count))[0]
    return 0


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


cdef struct _Known:
    # what an arbiter read knows of the rows: body id -> row, cpBody pointer -> row, each
    # row's id; and, where the rows' bodies were read right before (else NULL), that read
    # and whether each row's position there is its centre of gravity (chipmunk's body p)
    const _Table *table
    const _Table *by_body
    const int64_t *ids
    const double *raw
    const unsigned char *centred


cdef void _read_arbiters(void **arbiters, Py_ssize_t m, int64_t *ints, double *floats,
                         Py_ssize_t *pairs, const _Known *known) noexcept nogil:
    """Each of ``m`` arbiters into its ARBITER_INTS/ARBITER_FLOATS row (and its bodies'
    rows into ``pairs``): what pymunk.batch's pmSpaceArbiterIteratorFuncBatched reads,
    to the bit (an arbiter without contacts gets its ids and count only: nothing reads
    its floats). After chipmunk's step little of them is in the cache: the arbiters a few
    ahead, and their bodies, are asked for early (a hint only)."""
    cdef Py_ssize_t i
    cdef const char *ahead
    for i in range(m):
        if i + 8 < m:
            _prefetch(arbiters[i + 8])
            _prefetch(<char *>arbiters[i + 8] + 64)
            _prefetch(<char *>arbiters[i + 8] + 128)
        if i + 4 < m:
            ahead = <const char *>arbiters[i + 4]
            _ahead(_body_a(ahead))
            _ahead(_body_b(ahead))
            ahead = (<const char * const *>(ahead + arbiter.contacts))[0]  # its contacts
            _prefetch(ahead)
            _prefetch(ahead + 64)
            _prefetch(ahead + 128)
        _read_arbiter(<const char *>arbiters[i], &ints[_AI * i], &floats[_AF * i],
                      &pairs[2 * i], known)


cdef inline void _identify(void *body, int64_t *id, Py_ssize_t *row,
                           const _Known *known) noexcept nogil:
    """A body's id (chipmunk's user data) and row: ours by its cpBody pointer, any other
    (the space's own static body) by its user data."""
    row[0] = _row_of(known.by_body, <uint64_t><uintptr_t>body)
    if row[0] < known.by_body.n:
        id[0] = known.ids[row[0]]
    else:
        id[0] = <int64_t><uintptr_t>cp.user_data(body)
        row[0] = _row_of(known.table, <uint64_t>id[0])


cdef inline void _read_arbiter(const char *arb, int64_t *ints, double *f, Py_ssize_t *pair,
                               const _Known *known) noexcept nogil:
    """One arbiter (see :func:`_read_arbiters`). Its bodies as cpArbiterGetBodies gives
    them (b first where swapped), its normal as cpArbiterGetNormal (negated where
    swapped) and its total impulse as cpArbiterTotalImpulse (each contact's (jnAcc, jtAcc)
    turned by the unswapped normal and summed, negated where not swapped); its points and
    depths as cpArbiterGetPointA/B and cpArbiterGetDepth make them from the bodies'
    centres of gravity (body p, unswapped) and each contact's r1, r2, where the rows' read
    has both bodies' (:func:`_points`), else through those getters."""
    cdef bint swapped = _swapped(arb)
    cdef cpVect v, n, total
    cdef const char *contacts
    cdef const char *c
    cdef double jn, jt, sign
    cdef int count, k
    if swapped:
        _identify(_body_b(arb), &ints[0], &pair[0], known)
        _identify(_body_a(arb), &ints[1], &pair[1], known)
    else:
        _identify(_body_a(arb), &ints[0], &pair[0], known)
        _identify(_body_b(arb), &ints[1], &pair[1], known)
    count = _count(arb)
    ints[2] = count
    if count <= 0:
        for k in range(_AF):
            f[k] = 0.0
        return
    n = (<const cpVect *>(arb + arbiter.n))[0]
    contacts = (<const char * const *>(arb + arbiter.contacts))[0]
    total.x = 0.0
    total.y = 0.0
    for k in range(count):
        c = contacts + k * arbiter.contact
        jn = (<const double *>(c + arbiter.jn))[0]
        jt = (<const double *>(c + arbiter.jt))[0]
        total.x = total.x + (n.x * jn - n.y * jt)
        total.y = total.y + (n.x * jt + n.y * jn)
    f[0] = total.x if swapped else -total.x
    f[1] = total.y if swapped else -total.y
    sign = -1.0 if swapped else 1.0
    f[2] = n.x * sign
    f[3] = n.y * sign
    if _points(contacts, count, n, pair[1] if swapped else pair[0],
               pair[0] if swapped else pair[1], f, known):
        return
    for k in range(2 if count == 2 else 1):
        v = cp.point_a(<void *>arb, k)
        f[4 + 5 * k] = v.x
        f[5 + 5 * k] = v.y
        v = cp.point_b(<void *>arb, k)
        f[6 + 5 * k] = v.x
        f[7 + 5 * k] = v.y
        f[8 + 5 * k] = cp.depth(<void *>arb, k)
    if count != 2:
        for k in range(9, _AF):
            f[k] = 0.0


cdef inline bint _points(const char *contacts, int count, cpVect n, Py_ssize_t row_a,
                         Py_ssize_t row_b, double *f, const _Known *known) noexcept nogil:
    """An arbiter's points and depths from the rows' read, where it has both bodies'
    centres of gravity (``row_a``, ``row_b``: the rows of its unswapped bodies a and b):
    cpArbiterGetPointA is body a's p + r1, GetPointB body b's p + r2, GetDepth
    ((r2 − r1) + (p_b − p_a))·n, in those operations. Whether it could."""
    cdef const double *pa
    cdef const double *pb
    cdef const cpVect *r1
    cdef const cpVect *r2
    cdef const char *c
    cdef int k
    if (known.raw == NULL or row_a >= known.by_body.n or row_b >= known.by_body.n
            or not known.centred[row_a] or not known.centred[row_b]):
        return False
    pa = &known.raw[_BF * row_a]
    pb = &known.raw[_BF * row_b]
    for k in range(2 if count == 2 else 1):
        c = contacts + k * arbiter.contact
        r1 = <const cpVect *>(c + arbiter.r1)
        r2 = <const cpVect *>(c + arbiter.r2)
        f[4 + 5 * k] = pa[0] + r1.x
        f[5 + 5 * k] = pa[1] + r1.y
        f[6 + 5 * k] = pb[0] + r2.x
        f[7 + 5 * k] = pb[1] + r2.y
        f[8 + 5 * k] = (((r2.x - r1.x) + (pb[0] - pa[0])) * n.x
                        + ((r2.y - r1.y) + (pb[1] - pa[1])) * n.y)
    if count != 2:
        for k in range(9, _AF):
            f[k] = 0.0
    return True
