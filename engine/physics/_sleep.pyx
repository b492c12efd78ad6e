# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The per-body step of the sleep rule (:mod:`engine.physics.sleep`), compiled.

One pass over the bodies does what twenty numpy calls over (6, N) columns did: right
after a physics step the caches are cold and each numpy call costs microseconds, so the
pass takes a few microseconds for 500 bodies where the calls took some 90. The
arithmetic is the rule's, in the same order, so the results are the same to the bit
(tests/physics/test_sleep.py checks it against the numpy formulation); it is written
once, in ``sleep.h``, which the ODE binding's step and the plain-C reference of ``bench
physics`` run too. The rule's definition, its constants and its islands stay in sleep.py.
"""

from libc.stdint cimport uint8_t

import numpy as np

from engine.physics.csleep cimport SrRule, sr_advance, sr_settle


cdef class Pass:
    """The rule's arrays for its current rows, held so a step is one cheap call (binding
    ten arrays anew each step would cost more than the pass itself). Made again whenever
    the rule lays its rows out anew; the arrays are the rule's own, written in place."""

    cdef double[:, :, ::1] stack
    cdef double[::1] smoothing, timer, bounds
    cdef double[:, ::1] reference
    cdef uint8_t[::1] started, awake, eligible, movable
    cdef Py_ssize_t n

    def __init__(self, double[:, :, ::1] stack, double[::1] smoothing, double[::1] timer,
                 double[:, ::1] reference, uint8_t[::1] started, uint8_t[::1] awake,
                 uint8_t[::1] eligible, double[::1] bounds, uint8_t[::1] movable=None) -> None:
        n = timer.shape[0]
        if (stack.shape[0] != 3 or stack.shape[1] != 6 or stack.shape[2] != n
                or reference.shape[0] != 6 or reference.shape[1] != n
                or smoothing.shape[0] != n or started.shape[0] != n or awake.shape[0] != n
                or eligible.shape[0] != n or bounds.shape[0] != 6
                or (movable is not None and movable.shape[0] != n)):
            raise ValueError("the sleep rule's arrays do not agree on the number of bodies")
        self.stack, self.smoothing, self.timer, self.bounds = stack, smoothing, timer, bounds
        self.reference, self.started, self.awake, self.eligible = (reference, started, awake,
                                                                    eligible)
        self.movable = movable
        self.n = n

    def advance(self, double dt, double keep, double time, const uint8_t[::1] woken=None) -> bint:
        """Advance every body by a step of ``dt`` (sleep.py's SleepRule.update, before the
        islands): the smoothed velocity ``stack[0]`` toward the velocity ``stack[2]``
        (``keep`` = e^(-dt/SMOOTHING) where ``smoothing`` is 1), the drift from the
        reference into ``stack[1]``, whether each body smooths on, its quiet time and its
        reference. ``bounds``: squared (linear, angular) limits for slow, steady and at
        rest. ``woken``: explicitly woken since the last step (None: none). Whether some
        body has been quiet for ``time``."""
        cdef SrRule rule
        cdef bint ready
        cdef const uint8_t* marks = NULL
        if woken is not None and woken.shape[0] != self.n:
            raise ValueError(f"woken must have {self.n} rows, got {woken.shape[0]}")
        if self.n == 0:
            return False
        if woken is not None:
            marks = &woken[0]
        self._fill(&rule)
        with nogil:
            ready = sr_advance(&rule, dt, keep, time, marks)
        return ready

    cdef void _fill(self, SrRule *rule):
        rule.stack, rule.smoothing = &self.stack[0, 0, 0], &self.smoothing[0]
        rule.timer, rule.reference = &self.timer[0], &self.reference[0, 0]
        rule.started, rule.awake = &self.started[0], &self.awake[0]
        rule.eligible, rule.bounds = &self.eligible[0], &self.bounds[0]
        rule.movable = &self.movable[0] if self.movable is not None else NULL
        rule.n = self.n

    def settle(self, double time, const int[::1] labels) -> object:
        """The islands' say after :meth:`advance` found some body ready (sleep.h's
        sr_settle): every ready row whose island (``labels``, in [0, n)) holds no awake
        movable row that is not ready is forgotten and marked asleep; those rows, in
        order (int64)."""
        cdef SrRule rule
        cdef Py_ssize_t count, i
        if self.movable is None:
            raise ValueError("settle needs the rows' movable flags")
        if labels.shape[0] != self.n:
            raise ValueError(f"labels must have {self.n} rows, got {labels.shape[0]}")
        for i in range(self.n):
            if not 0 <= labels[i] < self.n:
                raise ValueError(f"island label {labels[i]} of row {i} is not in [0, {self.n})")
        rows = np.empty(self.n, np.intp)
        held = np.empty(self.n, np.uint8)
        cdef Py_ssize_t[::1] out = rows
        cdef uint8_t[::1] marks = held
        if self.n == 0:
            return rows.astype(np.int64)
        self._fill(&rule)
        with nogil:
            count = sr_settle(&rule, time, &labels[0], &marks[0], &out[0])
        return rows[:count].astype(np.int64)
