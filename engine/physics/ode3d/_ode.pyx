# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Private raw binding over libode (0.16, double precision); the typed layer is
``engine.physics.ode3d``.

Only what runs per step or per body is here, in C: the near callback that filters
pairs and makes contact joints, the step itself (collision and QuickStep with the
GIL released), contact impulses from joint feedback, the non-finite and runaway
check, the six-DOF drives, batch state reads and writes. The step's policy is C too,
in ``stepper.h`` (shared with the plain-C benchmark, app/bench/bench_ode.c): which
islands are solved exactly, the resting bodies' warm start, each contact's softness.
Auto-sleep's rule is :mod:`engine.physics.sleep`, whose per-step pass (``sleep.h``,
over the rule's own arrays, bound by ``World.bind_sleep``) the step runs in C with the
GIL released, with ODE's own auto-disable off. The typed layer (``engine.physics.ode3d``)
checks arguments and turns scene settings into these calls.

One extension built from one file per concept, included here in dependency order
(one module, so the per-step paths inline across concepts and there is one copy of
ODE's process-wide state):

* ``_errors.pxi``: ODE's error, debug and message handlers, and the guard that turns
  an internal error inside the step into a Python exception instead of ``abort()``;
* ``_world.pxi``: the World (ODE world, space, contact group, body slots),
  settings, the step;
* ``_bodies.pxi``: bodies, their pose, velocity, loads, sleep, gravity and
  collision switches;
* ``_geoms.pxi``: collision shapes and the mass they give their body;
* ``_joints.pxi``: joints, motors and the six-DOF drive;
* ``_contacts.pxi``: the near callback, contact records, ray casts;
* ``_sync.pxi``: batch reads and writes of the state table, the post-step check.

Bodies sit in a dense slot table (removal swaps the last slot in), so batch reads
are one C loop over ``n`` slots and a slot is a row of the state table. A body's
geoms carry a small ``GeomInfo`` (key, material, collision bits) that the near
callback reads without Python. Functions take the World first; the Python layer
calls them as ``_ode.create_body(world, ...)``.
"""

cimport cython
from libc.math cimport INFINITY, atan2, exp, fabs, isfinite, nextafter, sqrt
from libc.stdint cimport int64_t, intptr_t, uint8_t, uint32_t
from libc.stdlib cimport calloc, free, malloc, realloc
from libc.string cimport memcmp, memcpy, memset

from engine.physics.ode3d.libode cimport *

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
JOINT_ALIGN = 9

#: Columns of the material pair table handed to ``World.set_pairs``.
PAIR_COLUMNS = ("collide", "mode", "mu", "bounce", "bounce_vel", "soft_erp", "soft_cfm")
MODE_APPROX1 = dContactApprox1
MODE_BOUNCE = dContactBounce
MODE_SOFT = dContactSoftERP | dContactSoftCFM

cdef enum:
    KIND_DYNAMIC = 0
    KIND_STATIC = 1
    KIND_KINEMATIC = 2

from engine.physics.backend import MAX_SPEED as _MAX_SPEED
from engine.physics.backend import WORLD_EXTENT as _WORLD_EXTENT

#: Speed (m/s) and spin (rad/s) beyond which a body counts as exploded (the protocol's).
cdef double MAX_SPEED = _MAX_SPEED
MAX_BODY_SPEED = MAX_SPEED

#: Why the post-step check stopped a body (``World.step`` returns (key, reason) pairs).
cdef enum:
    FAULT_NONFINITE_C = 0
    FAULT_RUNAWAY_C = 1
    FAULT_LEFT_WORLD_C = 2
FAULT_NONFINITE = FAULT_NONFINITE_C
FAULT_RUNAWAY = FAULT_RUNAWAY_C
FAULT_LEFT_WORLD = FAULT_LEFT_WORLD_C


include "_errors.pxi"

dInitODE2(0)
dAllocateODEDataForThread(dAllocateMaskAll)
install_handlers()


include "_quat.pxi"
include "_world.pxi"
include "_contacts.pxi"
include "_bodies.pxi"
include "_geoms.pxi"
include "_joints.pxi"
include "_sync.pxi"

CONTACT_RECORD_SIZE = sizeof(ContactRec)
