# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The per-body step of the sleep rule (:mod:`engine.physics.sleep`), compiled.

One pass over the bodies does what twenty numpy calls over (6, N) columns did: right
after a physics step the caches are cold and each numpy call costs microseconds, so the
pass takes a few microseconds for 500 bodies where the calls took some 90. The
arithmetic is the rule's, in the same order, so the results are the same to the bit
(tests/physics/test_sleep.py checks it against the numpy formulation). The rule's
definition, its constants and its islands stay in sleep.py.
"""

from libc.stdint cimport uint8_t


cdef inline bint under(const double* x, double lin, double ang) noexcept nogil:
    """Whether a 6-vector's linear and angular halves are each under a squared bound."""
    return (x[0] * x[0] + x[1] * x[1] + x[2] * x[2] < lin and
            x[3] * x[3] + x[4] * x[4] + x[5] * x[5] < ang)


cdef class Pass:
    """The rule's arrays for its current rows, held so a step is one cheap call (binding
    ten arrays anew each step would cost more than the pass itself). Made again whenever
    the rule lays its rows out anew; the arrays are the rule's own, written in place."""

    cdef double[:, :, ::1] stack
    cdef double[::1] smoothing, timer, bounds
    cdef double[:, ::1] reference
    cdef uint8_t[::1] started, awake, eligible
    cdef Py_ssize_t n

    def __init__(self, double[:, :, ::1] stack, double[::1] smoothing, double[::1] timer,
                 double[:, ::1] reference, uint8_t[::1] started, uint8_t[::1] awake,
                 uint8_t[::1] eligible, double[::1] bounds) -> None:
        n = timer.shape[0]
        if (stack.shape[0] != 3 or stack.shape[1] != 6 or stack.shape[2] != n
                or reference.shape[0] != 6 or reference.shape[1] != n
                or smoothing.shape[0] != n or started.shape[0] != n or awake.shape[0] != n
                or eligible.shape[0] != n or bounds.shape[0] != 6):
            raise ValueError("the sleep rule's arrays do not agree on the number of bodies")
        self.stack, self.smoothing, self.timer, self.bounds = stack, smoothing, timer, bounds
        self.reference, self.started, self.awake, self.eligible = (reference, started, awake,
                                                                    eligible)
        self.n = n

    def advance(self, double dt, double keep, double time, const uint8_t[::1] woken=None) -> bint:
        """Advance every body by a step of ``dt`` (sleep.py's SleepRule.update, before the
        islands): the smoothed velocity ``stack[0]`` toward the velocity ``stack[2]``
        (``keep`` = e^(-dt/SMOOTHING) where ``smoothing`` is 1), the drift from the
        reference into ``stack[1]``, whether each body smooths on, its quiet time and its
        reference. ``bounds``: squared (linear, angular) limits for slow, steady and at
        rest. ``woken``: explicitly woken since the last step (None: none). Whether some
        body has been quiet for ``time``."""
        cdef Py_ssize_t i, j, n = self.n
        cdef double s[6]
        cdef double d[6]
        cdef double v[6]
        cdef double k
        cdef bint calm, steady, rest, slow, ready = False, has_woken = woken is not None
        cdef double* smooth_rows
        cdef double* drift_rows
        cdef double* velocity_rows
        cdef double* reference_rows
        cdef double* smoothing
        cdef double* timer
        cdef const double* bounds = &self.bounds[0]
        cdef uint8_t* started
        cdef const uint8_t* awake
        cdef const uint8_t* eligible
        if has_woken and woken.shape[0] != n:
            raise ValueError(f"woken must have {n} rows, got {woken.shape[0]}")
        if n == 0:
            return False
        # rows of (6, n) tables reached by pointer: the pass is a few loads per body
        smooth_rows, drift_rows = &self.stack[0, 0, 0], &self.stack[1, 0, 0]
        velocity_rows, reference_rows = &self.stack[2, 0, 0], &self.reference[0, 0]
        smoothing, timer = &self.smoothing[0], &self.timer[0]
        started, awake, eligible = &self.started[0], &self.awake[0], &self.eligible[0]
        with nogil:
            for i in range(n):
                k = smoothing[i] * keep
                for j in range(6):
                    v[j] = velocity_rows[j * n + i]
                    # where the last step said so the average snaps to the velocity:
                    # exactly, as (v - s) * 0 is 0
                    d[j] = (v[j] - smooth_rows[j * n + i]) * k
                    s[j] = v[j] - d[j]  # s + (v - s)(1 - e^(-dt/τ))
                    smooth_rows[j * n + i] = s[j]
                    d[j] = s[j] - reference_rows[j * n + i]
                    drift_rows[j * n + i] = d[j]
                calm = awake[i] and under(s, bounds[0], bounds[1])
                steady = under(d, bounds[2], bounds[3])
                rest = under(v, bounds[4], bounds[5])
                # smooth on only while calm and not at rest
                smoothing[i] = 1.0 if calm and not rest else 0.0
                slow = calm and eligible[i] and not (has_woken and woken[i])
                steady = steady and slow and started[i]
                timer[i] = (timer[i] + dt) * (1.0 if steady else 0.0)
                if slow and not steady:  # a quiet stretch starts (again) from here
                    for j in range(6):
                        reference_rows[j * n + i] = reference_rows[j * n + i] + d[j]
                started[i] = slow
                if timer[i] >= time:
                    ready = True
        return ready
