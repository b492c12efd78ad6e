/* The sleep rule's per-body pass and its island decision (engine/physics/sleep.py), in
 * plain C: one copy shared by the compiled pass (_sleep.pyx, which SleepRule.update runs
 * for the pymunk backend), the ODE binding's step (ode3d/stepper.h's cs_sleep, with the
 * GIL released) and the plain-C reference of `colosseum bench physics`
 * (app/bench/bench_ode.c), so the reference sleeps the same bodies on the same steps as the
 * engine. The rule's definition, its constants and saved states stay in sleep.py; the
 * arrays here are SleepRule's own, written in place (tests/physics/test_sleep.py checks
 * this pass against the rule's numpy formulation to the bit).
 */
#ifndef COLOSSEUM_SLEEP_H
#define COLOSSEUM_SLEEP_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct {
    double *stack;         /* (3, 6, n): the smoothed velocity, its drift from the
                              reference, the velocity (rows of n) */
    double *smoothing;     /* (n): 1 where the next step averages, 0 where it snaps */
    double *timer;         /* (n): seconds quiet so far */
    double *reference;     /* (6, n): the smoothed velocity a quiet stretch began with */
    uint8_t *started;      /* (n): a quiet stretch is under way */
    uint8_t *awake;        /* (n): awake after the step (filled by the caller) */
    const uint8_t *eligible;  /* (n): dynamic and allowed to sleep */
    const uint8_t *movable;   /* (n): dynamic or kinematic: may hold an island awake */
    const double *bounds;  /* squared (linear, angular) bounds: slow, steady, at rest */
    ptrdiff_t n;
} SrRule;

/* Whether a 6-vector's linear and angular halves are each under a squared bound. */
static inline int sr_under(const double *x, double lin, double ang) {
    return x[0] * x[0] + x[1] * x[1] + x[2] * x[2] < lin &&
           x[3] * x[3] + x[4] * x[4] + x[5] * x[5] < ang;
}

/* Advance every body by a step of `dt` (SleepRule.update before the islands): the
 * smoothed velocity toward the velocity (`keep` = e^(-dt/SMOOTHING) where smoothing is 1),
 * the drift from the reference, whether each body smooths on, its quiet time and its
 * reference. `woken`: explicitly woken since the last step (NULL: none). Returns whether
 * some body has been quiet for `time`. */
static inline int sr_advance(SrRule *r, double dt, double keep, double time,
                             const uint8_t *woken) {
    ptrdiff_t i, j, n = r->n;
    double s[6], d[6], v[6], k;
    int calm, steady, rest, slow, ready = 0;
    double *smooth_rows = r->stack, *drift_rows = r->stack + 6 * n;
    const double *velocity_rows = r->stack + 12 * n, *b = r->bounds;
    for (i = 0; i < n; i++) {
        k = r->smoothing[i] * keep;
        for (j = 0; j < 6; j++) {
            v[j] = velocity_rows[j * n + i];
            /* where the last step said so the average snaps to the velocity: exactly, as
             * (v - s) * 0 is 0 */
            d[j] = (v[j] - smooth_rows[j * n + i]) * k;
            s[j] = v[j] - d[j]; /* s + (v - s)(1 - e^(-dt/tau)) */
            smooth_rows[j * n + i] = s[j];
            d[j] = s[j] - r->reference[j * n + i];
            drift_rows[j * n + i] = d[j];
        }
        calm = r->awake[i] && sr_under(s, b[0], b[1]);
        steady = sr_under(d, b[2], b[3]);
        rest = sr_under(v, b[4], b[5]);
        /* smooth on only while calm and not at rest */
        r->smoothing[i] = calm && !rest ? 1.0 : 0.0;
        slow = calm && r->eligible[i] && !(woken != NULL && woken[i]);
        steady = steady && slow && r->started[i];
        r->timer[i] = (r->timer[i] + dt) * (steady ? 1.0 : 0.0);
        if (slow && !steady) /* a quiet stretch starts (again) from here */
            for (j = 0; j < 6; j++) r->reference[j * n + i] = r->reference[j * n + i] + d[j];
        r->started[i] = (uint8_t)slow;
        if (r->timer[i] >= time) ready = 1;
    }
    return ready;
}

/* Row `i` starts afresh (SleepRule.forget): put to sleep. */
static inline void sr_forget(SrRule *r, ptrdiff_t i) {
    ptrdiff_t j;
    for (j = 0; j < 6; j++) r->stack[j * r->n + i] = 0.0;
    r->smoothing[i] = 0.0;
    r->timer[i] = 0.0;
    r->started[i] = 0;
}

/* The islands' say, after sr_advance found some body ready: `label[i]` names row i's
 * island (rows tied by the step's contacts and the joints through moving bodies share
 * one, in [0, n)). Every ready row whose island holds no awake moving body that is not
 * ready is forgotten and marked asleep, and written to `rows`; returns how many (the
 * caller puts their bodies to sleep). `held`: room for n flags. */
static inline ptrdiff_t sr_settle(SrRule *r, double time, const int *label, uint8_t *held,
                                  ptrdiff_t *rows) {
    ptrdiff_t i, count = 0, n = r->n;
    memset(held, 0, (size_t)n);
    for (i = 0; i < n; i++) /* awake and not ready: keeps its island awake */
        if (r->movable[i] && r->awake[i] && !(r->timer[i] >= time)) held[label[i]] = 1;
    for (i = 0; i < n; i++) {
        if (!(r->timer[i] >= time) || held[label[i]]) continue;
        rows[count++] = i;
        sr_forget(r, i);
        r->awake[i] = 0;
    }
    return count;
}

#endif
