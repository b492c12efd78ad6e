/* The resting warm start's rules, written once for both backends: what a body's contacts
 * did in a step turned into its standing (held up, pushed sideways, sliding, steps at
 * rest), on plain numbers a backend fills from its own library. The ODE binding's step
 * (ode3d/stepper.h, per body of its CsBody records, in 3D) and the pymunk backend's
 * compiled pass (pymunk2d/_rows.pyx, over its batch state table, in the plane) both call
 * rp_stand; the sleep rule, the other half of the stepping policy, is sleep.h, which both
 * run as well. What stays with a backend is what its library needs: ODE collects its
 * contacts and preloads before its solve inside its own step; pymunk reads chipmunk
 * through the functions pymunk's cffi library exports and ramps its preload in against
 * chipmunk's own warm start (rp_ramp).
 *
 * Why these rules and constants: stepper.h's header comment and docs/PHYSICS.md.
 */
#ifndef COLOSSEUM_POLICY_H
#define COLOSSEUM_POLICY_H

#include <stddef.h>
#include <stdint.h>

/* Contacts sliding faster than this (m/s) are not at rest. */
#define REST_SLIP 0.05
/* A body is held up when its contacts push it up with at least this share of its
 * weight (of the solver's share of it, when preloaded). */
#define REST_SUPPORT 0.5
/* Sideways force a resting body's contacts may hold it with (what pushes it or pulls it
 * along), as a share of what their friction can give: to stay at rest (preloaded); times
 * (1 - beta) to come to rest (the preload leaves it that). */
#define REST_GRIP 0.5
/* Contact normals at least this close to the vertical (cosine) are level. */
#define REST_LEVEL (1.0 - 1e-9)
/* A body whose contacts' friction reached this share of what they can give is sliding
 * (or about to): not at rest. */
#define REST_SLIDING 0.95
/* Seconds over which a body's contact force is averaged before the sideways part is
 * judged: a stack's solver noise pushes its crates back and forth, a lean does not. */
#define REST_SMOOTHING 0.2
/* A preloaded body resting on a face moving across gravity slower than this (m/s) and
 * turning slower than REST_STILL_ANGULAR (rad/s) is held still: its motion across gravity
 * and its spin are what the solver left unconverged (the sleep rule's limits, sleep.py:
 * under them the body would be frozen by its sleep anyway). ODE holds it before and after
 * its step (ode3d/stepper.h's cs_hold_still), pymunk after each step (pymunk2d/_rows.pyx). */
#define REST_STILL_LINEAR 0.03
#define REST_STILL_ANGULAR 0.0349
/* pymunk holds a body only where it is in equilibrium on its base: the line of gravity
 * through its centre of mass falls within the span (across gravity) of the contact points
 * it lies on, this share of the span in from either end. A block whose centre of mass
 * lies past its base starts at rest on both corners and tips slowly at first, under
 * REST_STILL_*: held, it would stand forever (tests/physics/test_mass_frame_and_springs.py;
 * ODE's hold lets that block tip without this test). */
#define REST_BASE_MARGIN 0.05

/* What a body's contacts did in one step, as the backend read it. */
typedef struct {
    const double *solved; /* their net force on it this step (dim numbers, N) */
    double mu;            /* the friction coefficient that bounds them */
    double friction;      /* the friction they made (N, summed over contacts) */
    double grip;          /* the most they could have made */
    double weight;        /* its weight (N); 0: not dynamic, or no gravity */
    double share;         /* of its weight the solver held: 1 - beta where preloaded */
    int preloaded;        /* it got its weight's share this step */
    int still;            /* the backend held it still this step (a preloaded body on a face
                           * moving slower than REST_STILL_*; pymunk: in equilibrium on it,
                           * REST_BASE_MARGIN) */
} RpStep;

/* One body's standing after a step: `held` (dim numbers, its contacts' net force averaged
 * over REST_SMOOTHING; `keep` = e^(-dt/REST_SMOOTHING)) and `slid` updated in place;
 * returns whether it was at rest this step: held up by REST_SUPPORT of its weight (to come
 * to rest, by the share the solver held this step; to stay preloaded, by the whole force
 * averaged: the solver's (1 - beta) share alone is too noisy at few iterations, and a
 * crate falling out of the preload met its whole weight unprepared), not pushed sideways
 * beyond REST_GRIP of its friction (beyond (1 - beta) of that once it slid while
 * preloaded, until the push is gone), its friction short of REST_SLIDING of what it could
 * give (unless the backend held it still: then friction at its bound is the solver's
 * unconverged rest, not a slide). `down`: gravity's direction (unit, dim numbers);
 * `lifts`: how hard the contacts pushed it up this step (N), for the caller's own use.
 * The arithmetic is in one fixed order, so every caller gets the same bits. */
static inline int rp_stand(const RpStep *s, double *held, uint8_t *slid, const double *down,
                           int dim, double keep, double beta, double *lifts) {
    double up = 0.0, held_up = 0.0, side2 = 0.0, side, grip;
    int k, pushed, sliding;
    for (k = 0; k < dim; k++) up -= s->solved[k] * down[k];
    for (k = 0; k < dim; k++) { /* the whole force, as the solver found `share` of it */
        held[k] = held[k] * keep;
        held[k] = held[k] + (1.0 - keep) * s->solved[k] / s->share;
    }
    for (k = 0; k < dim; k++) held_up -= held[k] * down[k];
    for (k = 0; k < dim; k++) {
        side = held[k] + held_up * down[k];
        side2 += side * side;
    }
    /* one that slid while preloaded comes back only when the preload cannot make it
     * slide again: held sideways by less than (1 - beta) of the grip */
    grip = REST_GRIP * (*slid ? 1.0 - beta : 1.0) * s->mu * held_up;
    pushed = side2 > grip * grip;
    sliding = !s->still && s->friction >= REST_SLIDING * s->grip;
    *slid = (uint8_t)((*slid || (s->preloaded && sliding)) && pushed);
    *lifts = up;
    return s->weight > 0.0 && !pushed && !sliding &&
           (s->preloaded ? held_up >= REST_SUPPORT * s->weight
                         : up >= REST_SUPPORT * s->share * s->weight);
}

/* Steps in a row at rest, capped at 2: what a body needs to be preloaded. */
static inline int rp_count(int steps, int rests) { return rests ? (steps < 2 ? steps + 1 : 2) : 0; }

/* Each row's preload ramp for the next step (in place), for a library that carries its
 * own impulses over from step to step (chipmunk): up by `up` where `chosen`, by `down`
 * (negative) elsewhere, within [0, 1]; off at once where no contact is left (`points`
 * 0) or the row's island (`label`, or NULL: none found) holds a moving row that is
 * `unrest` or weightless. `blocked`: room for n flags. */
static inline void rp_ramp(ptrdiff_t n, const int64_t *points, const uint8_t *chosen,
                           const ptrdiff_t *label, const uint8_t *moving,
                           const uint8_t *unrest, const double *weight, double *ramp,
                           double up, double down, uint8_t *blocked) {
    ptrdiff_t i;
    double v;
    if (label != NULL) {
        for (i = 0; i < n; i++) blocked[i] = 0;
        for (i = 0; i < n; i++)
            if (moving[i] && points[i] > 0 && (unrest[i] || weight[i] <= 0.0))
                blocked[label[i]] = 1;
    }
    for (i = 0; i < n; i++) {
        if (points[i] <= 0 || (label != NULL && blocked[label[i]])) {
            ramp[i] = 0.0;
            continue;
        }
        v = ramp[i] + (chosen[i] ? up : down);
        ramp[i] = v > 1.0 ? 1.0 : (v < 0.0 ? 0.0 : v);
    }
}

#endif
