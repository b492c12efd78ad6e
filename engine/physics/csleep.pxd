# The C declarations of sleep.h (the sleep rule's per-body pass and island decision), for
# the compiled pass (_sleep.pyx) and the ODE binding (ode3d/libode.pxd), which both run it.
from libc.stdint cimport uint8_t


cdef extern from "sleep.h" nogil:
    ctypedef struct SrRule:
        double* stack
        double* smoothing
        double* timer
        double* reference
        uint8_t* started
        uint8_t* awake
        const uint8_t* eligible
        const uint8_t* movable
        const double* bounds
        Py_ssize_t n
    bint sr_advance(SrRule*, double dt, double keep, double time, const uint8_t* woken)
    Py_ssize_t sr_settle(SrRule*, double time, const int* label, uint8_t* held,
                         Py_ssize_t* rows)
