/* How Colosseum steps a libode world: plain C, shared by the binding (_ode.pyx) and the
 * plain-C reference of `colosseum bench physics` (app/bench/bench_ode.c), so both solve the
 * same problem with the same settings.
 *
 * A step: the caller collides, every pair's contacts into cs_room's room and handed to
 * cs_keep (or copied in by cs_collect), which does not make joints yet; cs_solve then
 * finds the islands, makes the contact joints with their final surfaces, and steps;
 * afterwards s->forces holds what the solver found each contact to do, and
 * cs_whole_forces makes them the whole forces (a caller that reads them runs it: the
 * preloads put back).
 * Three things on top of ODE's own step, each chosen by measurement (app/bench/accuracy.py,
 * docs/PHYSICS.md):
 *
 * 1. Islands solved exactly. Islands held together by joints alone (a pendulum, a chain,
 *    a top on its pivot, a motorised arm) are stepped with dWorldStep, ODE's exact LCP
 *    solver, when they have at most `exact_rows` constraint rows: QuickStep's 20
 *    iterations leave a 1 m pendulum at 30 degrees 1.4 % slow at 100 Hz, dWorldStep 0.03 %.
 *    Islands with contacts always go to QuickStep: ODE's Dantzig solver fails on the
 *    degenerate, friction-bounded problems a pile of boxes makes (a 4-box stack falls
 *    through the floor). When both kinds are present the step runs twice, each pass with
 *    the other kind's bodies disabled (islands share no joint, so a pass never touches
 *    the other's bodies, and every body is integrated once). Likewise, where the
 *    settings ask islands with contacts for more QuickStep iterations than the world's
 *    (`contact_iterations`: hands pressing on things), those islands get a pass of
 *    their own (cs_pass).
 *
 * 2. Resting islands carry their weight over. QuickStep starts every step from zero
 *    force, and 20 iterations in random order do not carry the weight of a stack down to
 *    the floor: ten stacked crates rock, sink 2 cm and drift 2 to 10 cm in 20 s at
 *    100 Hz, and topple at 50 Hz. In an island at rest on its contacts, each body gets
 *    `beta` of its weight as an upward force before the solve. For a body at rest the
 *    contacts' whole force (normal and friction) is its weight, so the solver finds
 *    exactly (1 - beta) of every contact force, friction bounds included, and the motion
 *    is the same whenever it converges; it just has 10 times less to find. An island is
 *    at rest when it has no joints, touches no kinematic body, and no body of it is
 *    weightless or has a force or torque applied this step (a script's, a controller's):
 *    then each preloaded weight reaches the ground through contacts (a crate on a
 *    platform a force holds up would otherwise lift the platform). In it, a body is
 *    preloaded when it moves and slides slower than REST_SLIP and has been held up by its
 *    contacts for the last two steps (at least REST_SUPPORT of its weight) using little
 *    of its friction (REST_GRIP of what the solver could give, (1 - beta) of that to
 *    enter). An
 *    island pushed or lifted by hand is not preloaded that step; a body tilted onto a
 *    slope or starting to slide leaves it the next step, after one step at most with
 *    (1 - beta) of its friction. Contact forces reported are the whole forces: what the
 *    solver found, plus each preload carried down through the contacts under it.
 *    A preloaded body on a face that moves across gravity and turns slower than the
 *    sleep rule's limits is held still, before the step and after it (cs_hold_still):
 *    what motion it has is the solver's residue, which adds up to a sway.
 *
 * 3. Contact softness from the step and the masses. ODE's constraint force mixing is an
 *    absolute number: 1e-5 is rigid for a 1 kg ball and a sponge for a 125 kg crate, and
 *    the speed it takes off a bounce (CFM x force) grows as the step shrinks (Bounce 0.8
 *    returns 0.611 of the drop at 1 kHz instead of 0.64). A contact's CFM is made
 *    `softness` x dt x (1/m1 + 1/m2): the same share of the contact's own stiffness for
 *    every mass and step; a contact that bounces this step is rigid (CFM 0), so
 *    restitution does not depend on the step. An author's Softness overrides both, and
 *    such a contact is not preloaded (the preload would stiffen the spring it tuned).
 *
 * After the step, cs_sleep runs the engine's sleep rule (../sleep.h, engine/physics/sleep.py)
 * on the islands cs_solve found, so the binding and the reference sleep alike.
 */
#ifndef COLOSSEUM_STEPPER_H
#define COLOSSEUM_STEPPER_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <ode/ode.h>

#include "../policy.h" /* the resting rules and their constants, shared with pymunk */
#include "../sleep.h"

typedef struct {
    double beta;      /* share of a resting body's weight preloaded; 0: off */
    double softness;  /* contact CFM as a share of the step times the inverse masses */
    int exact_rows;   /* joint-only islands up to this many rows: dWorldStep; 0: never */
    int contact_iterations; /* islands with contacts: QuickStep with at least this many
                               iterations (the others: the world's); 0: the world's */
} CsSettings;

typedef struct {   /* one contact this step, kept until its joint is made */
    dContact contact;
    dBodyID b1, b2;
    int i1, i2;    /* their indices (body data; -1: the world), read once */
    int authored;  /* its softness is the author's */
} CsContact;

typedef struct {   /* a body's standing with the resting preload */
    double solved[3]; /* the net force the solver found its contacts to make this step */
    double mu;        /* the smallest friction coefficient of its contacts this step */
    double friction;  /* the friction its contacts made this step (N, summed) */
    double grip;      /* the most they could have made (mu times their normal force) */
    double held[3];   /* its contacts' net force, averaged over REST_SMOOTHING seconds */
    int preloaded;    /* it got its weight's share this step */
    int slid;         /* it slid while preloaded, and has been pushed sideways since */
    int resting;      /* steps in a row it has been at rest (capped at 2) */
    int slipping;     /* a contact of it slides this step */
    int contacts;     /* contacts it has this step */
    int tilted;       /* one of them has a normal off the vertical */
    int still;        /* it was held still this step (cs_hold_still) */
} CsBody;

typedef struct {
    CsContact *contacts;
    int ncontacts, capcontacts;
    double *forces;   /* after cs_solve: each contact's whole force on body 1 */
    dJointFeedback *feedback;  /* each contact joint's record: the solver writes it */
    CsBody *bodies;
    int *parent, *kind, *rows;  /* per body: union-find parent; island kind and rows */
    int capbodies;
    /* cs_keep_preloads' and cs_whole_forces' work: the bodies highest first (kept from step to step: they
     * seldom change places, so an insertion sort puts them back in order), each body's
     * contacts as linked lists, and the loads carried down */
    struct CsHeight *order, *spare;  /* spare: the merge sort's room */
    int norder, *head, *next, *which, capnext;
    double *load, down[3];
    int owed;  /* bodies whose preloads cs_whole_forces has yet to put back (0: none) */
    int oom;
} CsState;

enum { CS_FREE = 0, CS_JOINTS = 1, CS_CONTACTS = 2, CS_UNREST = 4 };
/* An island of these is at rest: contacts, nothing else. */
#define CS_RESTING CS_CONTACTS

static inline void cs_init(CsState *s) { memset(s, 0, sizeof(CsState)); }

static inline void cs_free(CsState *s) {
    free(s->order);
    free(s->spare);
    free(s->head);
    free(s->next);
    free(s->which);
    free(s->load);
    free(s->contacts);
    free(s->forces);
    free(s->feedback);
    free(s->bodies);
    free(s->parent);
    free(s->kind);
    free(s->rows);
    cs_init(s);
}

/* Body `i` is new: it starts with no standing. */
static inline void cs_reset(CsState *s, int i) {
    if (i >= 0 && i < s->capbodies) memset(&s->bodies[i], 0, sizeof(CsBody));
}

/* The caller moved body `from` to index `to` (one was removed): its standing follows. */
static inline void cs_move(CsState *s, int from, int to) {
    if (from >= 0 && from < s->capbodies && to >= 0 && to < s->capbodies)
        s->bodies[to] = s->bodies[from];
}

/* The square of a body's centre-of-mass speed across `down` (a unit vector, or zero). */
static inline double cs_across2(dBodyID b, const double *down) {
    const dReal *v = dBodyGetLinearVel(b);
    double along = v[0] * down[0] + v[1] * down[1] + v[2] * down[2];
    return v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - along * along;
}

static inline int cs_body_index(dBodyID b) { return b ? (int)(intptr_t)dBodyGetData(b) : -1; }

/* The i-th of the body handles `stride` bytes apart from `bodies`. */
static inline dBodyID cs_body_at(const void *bodies, size_t stride, int i) {
    return *(const dBodyID *)((const char *)bodies + (size_t)i * stride);
}

static inline double cs_inverse_mass(dBodyID b) {
    dMass m;
    if (b == NULL || dBodyIsKinematic(b)) return 0.0;
    dBodyGetMass(b, &m);
    return m.mass > 0.0 ? 1.0 / m.mass : 0.0;
}

/* Where a body is and how it moves, read once for all the contacts of a pair. */
typedef struct {
    const dReal *pos, *lvel, *avel;  /* NULL: the world, at rest */
} CsMotion;

static inline CsMotion cs_motion(dBodyID b) {
    CsMotion m = {NULL, NULL, NULL};
    if (b) {
        m.pos = dBodyGetPosition(b);
        m.lvel = dBodyGetLinearVel(b);
        m.avel = dBodyGetAngularVel(b);
    }
    return m;
}

/* A body's velocity at `at`: dBodyGetPointVel's arithmetic in its order (the same bits),
 * without a call into libode per contact. */
static inline void cs_point_vel(const CsMotion *m, const dReal *at, dVector3 v) {
    double p0 = at[0] - m->pos[0], p1 = at[1] - m->pos[1], p2 = at[2] - m->pos[2];
    v[0] = (m->avel[1] * p2 - m->avel[2] * p1) + m->lvel[0];
    v[1] = (m->avel[2] * p0 - m->avel[0] * p2) + m->lvel[1];
    v[2] = (m->avel[0] * p1 - m->avel[1] * p0) + m->lvel[2];
}

/* Velocity of body 1 relative to body 2 at the contact: its normal part (negative:
 * closing) is returned, its tangential part's square stored in `slip2`. */
static inline double cs_relative_speed(const CsMotion *m1, const CsMotion *m2,
                                       const dContactGeom *g, double *slip2) {
    dVector3 v1, v2 = {0, 0, 0, 0};
    double v[3], along;
    int k;
    cs_point_vel(m1, g->pos, v1);
    if (m2->pos) cs_point_vel(m2, g->pos, v2);
    for (k = 0; k < 3; k++) v[k] = v1[k] - v2[k];
    along = v[0] * g->normal[0] + v[1] * g->normal[1] + v[2] * g->normal[2];
    *slip2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - along * along;
    return along;
}

/* Room for `n` more contacts after the kept ones, or NULL out of memory. A caller may
 * collide straight into it (dCollide into &room->contact.geom, sizeof(CsContact) apart),
 * set the surfaces and hand them to cs_keep: no copy of each contact. */
static inline CsContact *cs_room(CsState *s, int n) {
    if (s->ncontacts + n > s->capcontacts) {
        int cap = s->capcontacts ? 2 * s->capcontacts : 1024;
        CsContact *grown;
        double *forces = NULL;
        dJointFeedback *feedback = NULL;
        while (cap < s->ncontacts + n) cap *= 2;
        /* (no joint points at a feedback record now: the last step's were emptied) */
        grown = (CsContact *)realloc(s->contacts, (size_t)cap * sizeof(CsContact));
        if (grown) s->contacts = grown;
        forces = grown ? (double *)realloc(s->forces, (size_t)cap * 3 * sizeof(double)) : NULL;
        if (forces) s->forces = forces;
        feedback = forces ? (dJointFeedback *)realloc(s->feedback,
                                                      (size_t)cap * sizeof(dJointFeedback))
                          : NULL;
        if (!feedback) {
            s->oom = 1;
            return NULL;
        }
        s->feedback = feedback;
        s->capcontacts = cap;
    }
    return &s->contacts[s->ncontacts];
}

/* Keep the `n` contacts in cs_room's room that bodies b1 (moving) and b2 (NULL: the
 * world) made this step, their surfaces set by the caller from the pair's materials;
 * their softness is set here. Their joints are made by cs_solve, in this order. */
static inline void cs_keep(CsState *s, const CsSettings *cfg, int n, dBodyID b1,
                           dBodyID b2, double dt) {
    double soft = cfg->softness * dt * (cs_inverse_mass(b1) + cs_inverse_mass(b2));
    int i, i1 = cs_body_index(b1), i2 = cs_body_index(b2);
    CsMotion m1 = cs_motion(b1), m2 = cs_motion(b2);
    for (i = 0; i < n; i++) {
        CsContact *k = &s->contacts[s->ncontacts++];
        dSurfaceParameters *f = &k->contact.surface;
        double slip2, closing;
        k->b1 = b1;
        k->b2 = b2;
        k->i1 = i1;
        k->i2 = i2;
        k->authored = (f->mode & dContactSoftCFM) != 0;
        closing = -cs_relative_speed(&m1, &m2, &k->contact.geom, &slip2);
        if (slip2 > REST_SLIP * REST_SLIP) {
            if (i1 >= 0 && i1 < s->capbodies) s->bodies[i1].slipping = 1;
            if (i2 >= 0 && i2 < s->capbodies) s->bodies[i2].slipping = 1;
        }
        if (k->authored) continue;
        f->mode |= dContactSoftCFM;
        f->soft_cfm = (f->mode & dContactBounce) && f->bounce > 0.0 && closing > f->bounce_vel
                          ? 0.0 : soft;
    }
}

/* cs_keep for `n` contacts made elsewhere (copied in). Returns 0, or -1 out of memory. */
static inline int cs_collect(CsState *s, const CsSettings *cfg, const dContact *contacts,
                             int n, dBodyID b1, dBodyID b2, double dt) {
    CsContact *room = cs_room(s, n);
    int i;
    if (room == NULL) return -1;
    for (i = 0; i < n; i++) room[i].contact = contacts[i];
    cs_keep(s, cfg, n, b1, b2, dt);
    return 0;
}

/* Start a step for `n` bodies: contacts forgotten, room for every body's standing.
 * Returns 0, or -1 out of memory. */
static inline int cs_begin(CsState *s, int n) {
    int i;
    s->ncontacts = 0;
    s->owed = 0;
    if (n > s->capbodies) {
        int cap = n > 2 * s->capbodies ? n : 2 * s->capbodies;
        CsBody *b = (CsBody *)realloc(s->bodies, (size_t)cap * sizeof(CsBody));
        int *p = b ? (int *)realloc(s->parent, (size_t)cap * sizeof(int)) : NULL;
        int *kd = p ? (int *)realloc(s->kind, (size_t)cap * sizeof(int)) : NULL;
        int *rw = kd ? (int *)realloc(s->rows, (size_t)cap * sizeof(int)) : NULL;
        if (b) {
            memset(b + s->capbodies, 0, (size_t)(cap - s->capbodies) * sizeof(CsBody));
            s->bodies = b;
        }
        if (p) s->parent = p;
        if (kd) s->kind = kd;
        if (!rw) {
            s->oom = 1;
            return -1;
        }
        s->rows = rw;
        s->capbodies = cap;
    }
    for (i = 0; i < n; i++) s->bodies[i].slipping = 0;
    return 0;
}

/* Whether some of the `n` bodies is awake (enabled). With none, no pair can make a contact
 * (a pair of sleepers, or a sleeper and static geometry, makes none), so the caller need
 * not collide at all: a settled scene asleep otherwise spends most of its step hashing
 * its geometry (500 boxes: 60 % of such a step). */
static inline int cs_any_awake(const void *bodies, size_t stride, int n) {
    int i;
    for (i = 0; i < n; i++) {
        dBodyID b = cs_body_at(bodies, stride, i);
        if (b != NULL && dBodyIsEnabled(b)) return 1;
    }
    return 0;
}

static inline int cs_root(int *parent, int i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static inline void cs_union(CsState *s, int a, int b) {
    a = cs_root(s->parent, a);
    b = cs_root(s->parent, b);
    if (a == b) return;
    s->parent[b] = a;
    s->kind[a] |= s->kind[b];
    s->rows[a] += s->rows[b];
}

/* Rows a joint of this type may add (ODE's getInfo1 at most, with a motor or limit). */
static inline int cs_joint_rows(dJointID j) {
    switch (dJointGetType(j)) {
    case dJointTypeBall:
    case dJointTypeAMotor:
    case dJointTypeLMotor: return 3;
    default: return 6;
    }
}

/* Whether an island is solved exactly: held by joints alone, and small enough. */
static inline int cs_exact(const CsState *s, int exact_rows, int root) {
    return (s->kind[root] & (CS_JOINTS | CS_CONTACTS)) == CS_JOINTS &&
           s->rows[root] <= exact_rows;
}

/* Which pass steps an island: ODE's exact solver (cs_exact), QuickStep at the world's
 * iterations, or — when the settings ask islands with contacts for more iterations than
 * the world's (`more`) — QuickStep at `contact_iterations`: a hand pressing on a cup on
 * a table needs 40 iterations not to sink and jitter, a hand's fingers moving in the air
 * (a chain of 16 bodies, 96 rows) follow as well at 20, for half the cost. */
enum { CS_PASS_EXACT = 0, CS_PASS_QUICK = 1, CS_PASS_CONTACT = 2 };

static inline int cs_pass(const CsState *s, const CsSettings *cfg, int more, int root) {
    if (cs_exact(s, cfg->exact_rows, root)) return CS_PASS_EXACT;
    return more && (s->kind[root] & CS_CONTACTS) ? CS_PASS_CONTACT : CS_PASS_QUICK;
}

/* Disable (off) or re-enable (on) the enabled bodies of the islands one pass steps;
 * `mark` remembers which were enabled, so re-enabling wakes nobody asleep. */
static inline void cs_switch(CsState *s, const CsSettings *cfg, int more, const void *bodies,
                             size_t stride, int n, int pass, int off, unsigned char *mark) {
    int i;
    for (i = 0; i < n; i++) {
        dBodyID b = cs_body_at(bodies, stride, i);
        if (b == NULL || cs_pass(s, cfg, more, cs_root(s->parent, i)) != pass) continue;
        if (off) {
            mark[i] = (unsigned char)dBodyIsEnabled(b);
            if (mark[i]) dBodyDisable(b);
        } else if (mark[i]) {
            dBodyEnable(b);
        }
    }
}

/* Step one pass's islands: exactly, or by QuickStep at `iterations` (the world's put
 * back after). */
static inline void cs_step_pass(dWorldID world, double dt, int pass, int iterations) {
    int its = dWorldGetQuickStepNumIterations(world);
    if (pass == CS_PASS_EXACT) {
        dWorldStep(world, dt);
        return;
    }
    if (iterations != its) dWorldSetQuickStepNumIterations(world, iterations);
    dWorldQuickStep(world, dt);
    if (iterations != its) dWorldSetQuickStepNumIterations(world, its);
}

/* Hold a body still when it moves and turns slower than REST_STILL_*: its spin and its
 * velocity across gravity are taken away, and with `whole` its velocity along gravity
 * too. Returns whether it did. For a preloaded body on a face: across gravity before the
 * step (along it, the contacts meet gravity), whole after it (the velocity along gravity
 * the contacts' corrections leave kept a column of 1 kg boxes above the sleep rule's
 * steady band, 3 mm/s, and awake): QuickStep's few iterations leave a stack's crates a few
 * mm/s and mrad/s of motion each step, which add up to a sway; the stack at 1/60 s drifted
 * 14 to 28 mm in 20 s with it, 0.5 to 3 mm without (app/bench/accuracy.py). A body
 * slower than this is one the sleep rule would freeze anyway (PhysX's stabilisation
 * damps bodies near their sleep threshold alike). */
static inline int cs_hold_still(dBodyID b, const double *down, int whole) {
    const dReal *v = dBodyGetLinearVel(b), *w = dBodyGetAngularVel(b);
    double along = whole ? 0.0 : v[0] * down[0] + v[1] * down[1] + v[2] * down[2];
    if (w[0] * w[0] + w[1] * w[1] + w[2] * w[2] >= REST_STILL_ANGULAR * REST_STILL_ANGULAR ||
        (whole ? v[0] * v[0] + v[1] * v[1] + v[2] * v[2] : cs_across2(b, down)) >=
            REST_STILL_LINEAR * REST_STILL_LINEAR)
        return 0;
    dBodySetAngularVel(b, 0.0, 0.0, 0.0);
    dBodySetLinearVel(b, along * down[0], along * down[1], along * down[2]);
    return 1;
}

typedef struct CsHeight { double height; int index; } CsHeight;

/* Whether `x` goes before `y`, highest first (ties by index): a total order. */
static inline int cs_higher_first(const CsHeight *x, const CsHeight *y) {
    return x->height > y->height || (!(x->height < y->height) && x->index < y->index);
}

/* Room for cs_keep_preloads' and cs_whole_forces' work over `n` bodies and `nc` contacts; a new `n` starts the
 * order afresh. Returns 0, or -1 out of memory. */
static inline int cs_reserve_preloads(CsState *s, int n, int nc) {
    int i;
    if (s->norder != n) {
        CsHeight *order = (CsHeight *)realloc(s->order, (size_t)(n + 1) * sizeof(CsHeight));
        CsHeight *spare = order ? (CsHeight *)realloc(s->spare, (size_t)(n + 1) *
                                                      sizeof(CsHeight)) : NULL;
        int *head = spare ? (int *)realloc(s->head, (size_t)(n + 1) * sizeof(int)) : NULL;
        double *load = head ? (double *)realloc(s->load, (size_t)(3 * n + 3) * sizeof(double))
                            : NULL;
        if (order) s->order = order;
        if (spare) s->spare = spare;
        if (head) s->head = head;
        s->norder = 0;
        if (!load) return -1;
        s->load = load;
        for (i = 0; i < n; i++) s->order[i].index = i;
        s->norder = n;
    }
    if (2 * nc + 1 > s->capnext) {
        int cap = 2 * nc + 1 > 2 * s->capnext ? 2 * nc + 1 : 2 * s->capnext;
        int *next = (int *)realloc(s->next, (size_t)cap * sizeof(int));
        int *which = next ? (int *)realloc(s->which, (size_t)cap * sizeof(int)) : NULL;
        if (next) s->next = next;
        if (!which) return -1;
        s->which = which;
        s->capnext = cap;
    }
    return 0;
}

/* Merge sort of `n` heights (cs_higher_first), `spare` room for as many. */
static inline void cs_merge_sort(CsHeight *order, CsHeight *spare, int n) {
    int width, lo, i, j, k, mid, hi;
    CsHeight *from = order, *to = spare, *swap;
    for (lo = 0; lo < n; lo += 8) {  /* runs of 8 by insertion */
        hi = lo + 8 < n ? lo + 8 : n;
        for (i = lo + 1; i < hi; i++) {
            CsHeight x = order[i];
            for (j = i - 1; j >= lo && cs_higher_first(&x, &order[j]); j--) order[j + 1] = order[j];
            order[j + 1] = x;
        }
    }
    for (width = 8; width < n; width *= 2) {
        for (lo = 0; lo < n; lo += 2 * width) {
            mid = lo + width < n ? lo + width : n;
            hi = lo + 2 * width < n ? lo + 2 * width : n;
            for (i = lo, j = mid, k = lo; k < hi; k++)
                to[k] = j >= hi || (i < mid && !cs_higher_first(&from[j], &from[i]))
                            ? from[i++] : from[j++];
        }
        swap = from, from = to, to = swap;
    }
    if (from != order) memcpy(order, from, (size_t)n * sizeof(CsHeight));
}

/* The bodies highest first: last step's order sorted again by insertion (bodies seldom
 * change places from one step to the next), or by a merge sort when many did (the
 * bodies of a layer of columns swap places with the solver's jitter every step). The
 * same total order either way (ties by index). */
static inline void cs_sort_heights(CsHeight *order, CsHeight *spare, int n) {
    int i, j, unsorted = 0;
    for (i = 1; i < n; i++) unsorted += cs_higher_first(&order[i], &order[i - 1]);
    if (unsorted > n / 16 + 1) {
        cs_merge_sort(order, spare, n);
        return;
    }
    for (i = 1; i < n && unsorted; i++) {
        CsHeight x = order[i];
        for (j = i - 1; j >= 0 && cs_higher_first(&x, &order[j]); j--) order[j + 1] = order[j];
        order[j + 1] = x;
    }
}

/* Put the forces the preload stood in for back into the contacts that carry them, so a
 * contact reports its whole force: each preloaded body's beta m g (upward) goes into the
 * contacts holding it up, in proportion to what the solver found each to carry, and on
 * through the bodies under them, highest first, down to the ground. (Scaling a contact
 * by 1 / (1 - beta) for its preloaded body is right only when everything it carries is
 * preloaded too: a crate set on a resting stack reported ten times its weight on every
 * contact below it, an impact a contact sound heard.)
 *
 * In two parts, so that a step whose forces nobody reads does not pay for them (the
 * physics never reads them: the resting rules read what the solver found). cs_solve
 * keeps what the step leaves (cs_keep_preloads: each preloaded body's load and every
 * body's height, as they were at the step); cs_whole_forces, run by a caller that reads
 * s->forces, does the rest, once per step. Returns -1 when out of memory (the forces
 * are then the solver's alone). */
static inline int cs_keep_preloads(CsState *s, const CsSettings *cfg, const dReal *gravity,
                                   const double *down, const void *bodies, size_t stride,
                                   int n) {
    int i, k, any = 0;
    s->owed = 0;
    for (i = 0; i < n && !any; i++) any = s->bodies[i].preloaded;
    if (!any || cfg->beta <= 0.0) return 0;
    if (cs_reserve_preloads(s, n, s->ncontacts) < 0) return -1;
    memset(s->load, 0, (size_t)(3 * n) * sizeof(double));
    for (i = 0; i < n; i++) {
        dBodyID b = cs_body_at(bodies, stride, i);
        CsHeight *o = &s->order[i];
        const dReal *pos = o->index >= 0 && cs_body_at(bodies, stride, o->index)
                               ? dBodyGetPosition(cs_body_at(bodies, stride, o->index)) : NULL;
        o->height = pos ? -(pos[0] * down[0] + pos[1] * down[1] + pos[2] * down[2]) : 0.0;
        if (b != NULL && s->bodies[i].preloaded) {
            dMass m;
            dBodyGetMass(b, &m);
            for (k = 0; k < 3; k++) s->load[3 * i + k] = -cfg->beta * m.mass * gravity[k];
        }
    }
    for (k = 0; k < 3; k++) s->down[k] = down[k];
    s->owed = n;
    return 0;
}

/* The whole forces in s->forces (see cs_keep_preloads): a no-op unless the last cs_solve
 * preloaded some body and they have not been put back since. */
static inline void cs_whole_forces(CsState *s) {
    int i, e, n = s->owed, nc = s->ncontacts;
    int *head = s->head, *next = s->next, *which = s->which;
    double *load = s->load;
    const double *down = s->down;
    if (n <= 0) return;
    s->owed = 0;
    for (i = 0; i < n; i++) head[i] = -1;
    for (e = 0, i = 0; i < nc; i++) {  /* each body's contacts, as linked lists */
        int a = s->contacts[i].i1, b = s->contacts[i].i2;
        which[e] = i; next[e] = head[a]; head[a] = e++;
        if (b >= 0) { which[e] = i; next[e] = head[b]; head[b] = e++; }
    }
    cs_sort_heights(s->order, s->spare, n);
    for (i = 0; i < n; i++) {
        int u = s->order[i].index, k;
        double *l = &load[3 * u], total = 0.0;
        if (l[0] == 0.0 && l[1] == 0.0 && l[2] == 0.0) continue;
        for (e = head[u]; e >= 0; e = next[e]) {  /* what holds it up, and how much */
            int c = which[e];
            double sign = s->contacts[c].i1 == u ? 1.0 : -1.0, *f = &s->forces[3 * c];
            double up = -sign * (f[0] * down[0] + f[1] * down[1] + f[2] * down[2]);
            if (up > 0.0) total += up;
        }
        if (total <= 0.0) continue;  /* nothing holds it up: nothing to put back */
        for (e = head[u]; e >= 0; e = next[e]) {
            int c = which[e], a = s->contacts[c].i1;
            int v = a == u ? s->contacts[c].i2 : a;
            double sign = a == u ? 1.0 : -1.0, *f = &s->forces[3 * c], share;
            double up = -sign * (f[0] * down[0] + f[1] * down[1] + f[2] * down[2]);
            if (up <= 0.0) continue;
            share = up / total;
            for (k = 0; k < 3; k++) f[k] += sign * share * l[k];
            if (v >= 0)  /* the body under it carries that too */
                for (k = 0; k < 3; k++) load[3 * v + k] += share * l[k];
        }
    }
}

static inline int cs_solve(CsState *s, const CsSettings *cfg, dWorldID world,
                           dJointGroupID group, const void *bodies, size_t stride, int n,
                           double dt) {
    dVector3 gravity;
    double g, down[3], keep;
    int i, k, status = 0, passes = 0, present[3] = {0, 0, 0};
    int its = dWorldGetQuickStepNumIterations(world);
    int more = cfg->contact_iterations > its;
    dWorldGetGravity(world, gravity);
    g = sqrt(gravity[0] * gravity[0] + gravity[1] * gravity[1] + gravity[2] * gravity[2]);
    for (k = 0; k < 3; k++) down[k] = g > 0.0 ? gravity[k] / g : 0.0;
    for (i = 0; i < n; i++) {
        dBodyID b = cs_body_at(bodies, stride, i);
        s->parent[i] = i;
        s->rows[i] = 0;
        /* a kinematic body may push what it touches: its island is not at rest */
        s->kind[i] = b != NULL && dBodyIsKinematic(b) ? CS_UNREST : CS_FREE;
    }
    for (i = 0; i < n; i++) s->bodies[i].contacts = s->bodies[i].tilted = 0;
    for (i = 0; i < s->ncontacts; i++) {
        const CsContact *c = &s->contacts[i];
        const double *nrm = c->contact.geom.normal;
        int a = c->i1, b = c->i2;
        int tilted = fabs(nrm[0] * down[0] + nrm[1] * down[1] + nrm[2] * down[2]) < REST_LEVEL;
        s->bodies[a].contacts++;
        s->bodies[a].tilted |= tilted;
        if (b >= 0) {
            s->bodies[b].contacts++;
            s->bodies[b].tilted |= tilted;
        }
        if (c->authored) s->kind[cs_root(s->parent, a)] |= CS_UNREST;
        if (b >= 0) cs_union(s, a, b);
    }
    for (i = 0; i < n; i++)  /* (once a body, not once a contact: a union merges kinds) */
        if (s->bodies[i].contacts) s->kind[cs_root(s->parent, i)] |= CS_CONTACTS;
    for (i = 0; i < n; i++) {  /* the joints (contact joints are not made yet) */
        dBodyID b = cs_body_at(bodies, stride, i);
        int nj;
        if (b == NULL) continue;
        nj = dBodyGetNumJoints(b);
        for (k = 0; k < nj; k++) {
            dJointID j = dBodyGetJoint(b, k);
            dBodyID o0 = dJointGetBody(j, 0), o1 = dJointGetBody(j, 1);
            int r;
            if (!dJointIsEnabled(j) || (o0 != b && !(o0 == NULL && o1 == b)))
                continue;  /* each joint once, from its first body */
            if (o0 != NULL && o1 != NULL) cs_union(s, i, cs_body_index(o1));
            r = cs_root(s->parent, i);
            s->kind[r] |= CS_JOINTS;
            s->rows[r] += cs_joint_rows(j);
        }
    }
    /* a preloaded body's weight must reach the ground through contacts: an island with a
     * body that something other than its contacts holds or moves (a script's force or
     * torque, no gravity; joints and kinematic bodies above) is not preloaded at all.
     * Such a body would take the preload of what rests on it instead: a crate on a
     * platform a force held up lifted the platform (both rose at 5 m/s^2). (A body not at
     * rest but on the ground passes the weight of what rests on it on as the solver finds
     * it.) */
    if (cfg->beta > 0.0) {
        for (i = 0; i < n; i++) {
            dBodyID b = cs_body_at(bodies, stride, i);
            const dReal *f, *t;
            if (b == NULL || !dBodyIsEnabled(b) || dBodyIsKinematic(b)) continue;
            f = dBodyGetForce(b);
            t = dBodyGetTorque(b);
            if (!dBodyGetGravityMode(b) || f[0] != 0.0 ||
                f[1] != 0.0 || f[2] != 0.0 || t[0] != 0.0 || t[1] != 0.0 || t[2] != 0.0)
                s->kind[cs_root(s->parent, i)] |= CS_UNREST;
        }
    }
    /* resting islands: each body's weight, (beta of it) preloaded */
    for (i = 0; i < n; i++) {
        dBodyID b = cs_body_at(bodies, stride, i);
        CsBody *st = &s->bodies[i];
        /* how fast it may move across gravity and be preloaded: four times that to stay
         * so (a stack's solver jitter is not a slide) */
        double moving = (st->preloaded ? 4.0 : 1.0) * REST_SLIP;
        int r, was_still = st->still;
        memset(st->solved, 0, sizeof st->solved);
        st->mu = dInfinity;
        st->friction = st->grip = 0.0;
        st->preloaded = st->still = 0;
        if (b == NULL) continue;
        r = cs_root(s->parent, i);
        if (dBodyIsEnabled(b)) present[cs_pass(s, cfg, more, r)] = 1;
        /* the upward push only where it leaves nothing free to move: a body resting on a
         * face (three contacts or more: friction holds it whole), or touching only level
         * ground (it may roll, but not downhill); one not carried along itself (a crate
         * riding a sliding box, its contacts still, took its weight off the floor's
         * friction: the pair slid six times too far) */
        if (cfg->beta > 0.0 && s->kind[r] == CS_RESTING && dBodyIsEnabled(b) &&
            st->resting >= 2 && !st->slipping && (st->contacts >= 3 || !st->tilted) &&
            cs_across2(b, down) < moving * moving) {
            dMass m;
            dBodyGetMass(b, &m);
            dBodyAddForce(b, -cfg->beta * m.mass * gravity[0], -cfg->beta * m.mass * gravity[1],
                          -cfg->beta * m.mass * gravity[2]);
            st->preloaded = 1;
            /* on a face; or, held still last step, on level contacts only: a crate resting on
             * another within the contact layer keeps 1 or 2 of its 4 contacts some steps */
            if (st->contacts >= 3 || (was_still && !st->tilted))
                st->still = cs_hold_still(b, down, 0);
        }
    }
    for (i = 0; i < s->ncontacts; i++) {  /* the contact joints */
        CsContact *c = &s->contacts[i];
        dJointFeedback *fb = &s->feedback[i];
        dJointID j;
        j = dJointCreateContact(world, group, &c->contact);
        dJointAttach(j, c->b1, c->b2);
        /* the solver writes every field of a stepped joint's record; f1, the one read
         * back, starts at zero for a joint it does not step */
        fb->f1[0] = fb->f1[1] = fb->f1[2] = 0.0;
        dJointSetFeedback(j, fb);
    }
    passes = present[0] + present[1] + present[2];
    if (passes <= 1) {
        k = present[CS_PASS_EXACT] ? CS_PASS_EXACT :
            present[CS_PASS_CONTACT] ? CS_PASS_CONTACT : CS_PASS_QUICK;
        cs_step_pass(world, dt, k, k == CS_PASS_CONTACT ? cfg->contact_iterations : its);
    } else {
        /* each pass with the other passes' bodies disabled (islands share no joint, so a
         * pass never touches the others' bodies, and every body is integrated once) */
        unsigned char *mark = (unsigned char *)calloc((size_t)n, 1);
        if (mark == NULL) {
            cs_step_pass(world, dt, CS_PASS_QUICK, more ? cfg->contact_iterations : its);
            status = -1;
        } else {
            int other;
            for (k = 0; k < 3; k++) {
                if (!present[k]) continue;
                for (other = 0; other < 3; other++)
                    if (other != k && present[other])
                        cs_switch(s, cfg, more, bodies, stride, n, other, 1, mark);
                cs_step_pass(world, dt, k, k == CS_PASS_CONTACT ? cfg->contact_iterations : its);
                for (other = 0; other < 3; other++)
                    if (other != k && present[other])
                        cs_switch(s, cfg, more, bodies, stride, n, other, 0, mark);
            }
            free(mark);
        }
    }
    for (i = 0; i < n; i++)  /* what the step left of a still body's motion */
        if (s->bodies[i].still) cs_hold_still(cs_body_at(bodies, stride, i), down, 1);
    /* forces: what the solver found (the preloads put back after this loop) */
    for (i = 0; i < s->ncontacts; i++) {
        const CsContact *c = &s->contacts[i];
        const dJointFeedback *fb = &s->feedback[i];
        const double *nrm = c->contact.geom.normal;
        double *f = &s->forces[3 * i], mu = c->contact.surface.mu, along, slide2, friction, grip;
        int a = c->i1, b = c->i2;
        for (k = 0; k < 3; k++) {
            f[k] = fb->f1[k];
            s->bodies[a].solved[k] += fb->f1[k];
            if (b >= 0) s->bodies[b].solved[k] -= fb->f1[k];
        }
        along = fb->f1[0] * nrm[0] + fb->f1[1] * nrm[1] + fb->f1[2] * nrm[2];
        slide2 = fb->f1[0] * fb->f1[0] + fb->f1[1] * fb->f1[1] + fb->f1[2] * fb->f1[2] -
                 along * along;
        friction = slide2 > 0.0 ? sqrt(slide2) : 0.0;
        grip = mu < dInfinity && along > 0.0 ? mu * along : (mu < dInfinity ? 0.0 : dInfinity);
        if (mu < s->bodies[a].mu) s->bodies[a].mu = mu;
        s->bodies[a].friction += friction;
        s->bodies[a].grip += grip;
        if (b >= 0) {
            if (mu < s->bodies[b].mu) s->bodies[b].mu = mu;
            s->bodies[b].friction += friction;
            s->bodies[b].grip += grip;
        }
    }
    if (cs_keep_preloads(s, cfg, gravity, down, bodies, stride, n) < 0) status = -1;
    /* each body's standing for the next step */
    keep = exp(-dt / REST_SMOOTHING);
    for (i = 0; i < n; i++) {
        dBodyID b = cs_body_at(bodies, stride, i);
        CsBody *st = &s->bodies[i];
        double up;
        RpStep step;
        uint8_t slid;
        int rests;
        dMass m;
        if (b == NULL || dBodyIsKinematic(b)) continue;
        if (!dBodyIsEnabled(b)) {  /* asleep: it starts afresh when woken */
            st->resting = 0;
            continue;
        }
        dBodyGetMass(b, &m);
        step.solved = st->solved;
        step.mu = st->mu;
        step.friction = st->friction;
        step.grip = st->grip;
        step.weight = m.mass * g;
        step.share = st->preloaded ? 1.0 - cfg->beta : 1.0; /* of its weight the solver held */
        step.preloaded = st->preloaded;
        step.still = st->still;
        slid = (uint8_t)st->slid;
        rests = rp_stand(&step, st->held, &slid, down, 3, keep, cfg->beta, &up);
        st->resting = rp_count(st->resting, rests && st->contacts > 0);
        st->slid = slid;
    }
    return status;
}

/* A body asleep, at rest: a sleeping body reports zero velocity. */
static inline void cs_disable(dBodyID b) {
    dBodyDisable(b);
    dBodySetLinearVel(b, 0.0, 0.0, 0.0);
    dBodySetAngularVel(b, 0.0, 0.0, 0.0);
}

/* The sleep rule's step (sleep.h) after cs_solve: every body's centre-of-mass velocity and
 * whether it is awake into the rule, the rule advanced by `dt` (`keep`: e^(-dt/SMOOTHING);
 * `woken`: bodies woken explicitly since the last step, or NULL), and when some body has
 * been quiet for `time`, the islands cs_solve found for this step (its contacts and the
 * joints, through moving bodies: the ties SleepRule's islands are made of) decide which
 * bodies fall asleep, and they are put to sleep. `bodies` as for cs_solve, the rule laid
 * out over the same `n` rows. Returns how many fell asleep, or -1 out of memory (none
 * did). */
static inline int cs_sleep(CsState *s, SrRule *r, const void *bodies, size_t stride, int n,
                           double dt, double keep, double time, const uint8_t *woken) {
    double *velocity = r->stack + 12 * (ptrdiff_t)n;
    int i, k, *label;
    uint8_t *held;
    ptrdiff_t *rows, slept;
    if (n <= 0 || r->n != n) return 0;
    for (i = 0; i < n; i++) {
        dBodyID b = cs_body_at(bodies, stride, i);
        const dReal *v, *w;
        if (b == NULL) {
            for (k = 0; k < 6; k++) velocity[k * n + i] = 0.0;
            r->awake[i] = 0;
            continue;
        }
        v = dBodyGetLinearVel(b);
        w = dBodyGetAngularVel(b);
        for (k = 0; k < 3; k++) {
            velocity[k * n + i] = v[k];
            velocity[(3 + k) * n + i] = w[k];
        }
        r->awake[i] = (uint8_t)dBodyIsEnabled(b);
    }
    if (!sr_advance(r, dt, keep, time, woken)) return 0;
    label = (int *)malloc((size_t)n * sizeof(int));
    held = (uint8_t *)malloc((size_t)n);
    rows = (ptrdiff_t *)malloc((size_t)n * sizeof(ptrdiff_t));
    if (!label || !held || !rows || s->capbodies < n) {
        free(label);
        free(held);
        free(rows);
        return -1;
    }
    for (i = 0; i < n; i++) label[i] = cs_root(s->parent, i);
    slept = sr_settle(r, time, label, held, rows);
    for (i = 0; i < slept; i++) cs_disable(cs_body_at(bodies, stride, (int)rows[i]));
    free(label);
    free(held);
    free(rows);
    return (int)slept;
}

#endif
