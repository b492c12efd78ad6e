/* Plain C reference for `colosseum bench physics`: the "boxes" scene on libode.
 *
 * A ground plane and N boxes (1 m, 1 kg) in columns 10 high, columns 1.2 m
 * apart on a square grid, layers 1.1 m apart, the lowest centred at 0.55 m;
 * dt 1/60 s, at most 4 contacts per pair, Coulomb friction mu 0.5
 * (dContactApprox1). World settings (ERP, CFM, iterations, contact surface layer,
 * hash-space levels) match what engine/physics/ode3d sets, and the step is the
 * engine's own (engine/physics/ode3d/stepper.h: exact joint islands, resting
 * islands' weight carried over, contact softness from the step and masses, with the
 * settings passed in), so both sides solve the same problem.
 *
 * Sleeping is the engine's own rule (engine/physics/sleep.py), run as the engine's step
 * runs it: stepper.h's cs_sleep after each step, the per-body pass of sleep.h over the
 * rule's arrays and the islands of the step, with the limits app/bench/physics.py
 * passes in (SleepTime, SleepLinear, SleepAngular, the steady share and the smoothing
 * time). ODE's own auto-disable stays off, as in the engine, so both sides put the same
 * boxes to sleep on the same steps and do the same work.
 *
 * The engine's step reads every contact's force back (the resting rules judge each body by
 * them), so feedback is always attached here; FEEDBACK=1 also puts the preloads back into
 * them (cs_whole_forces) and sums the impulses |f|·dt after the step, the rest of the work
 * the engine does when its contact reports are read.
 *
 * With POLICY=0 (the optional last argument) the program is plain libode instead, the
 * reference the engine's policy is priced against (`colosseum bench pareto`): each pair's
 * contacts become contact joints in the collision callback, as ODE's own demos make them
 * (Approx1 friction, the world's CFM, no feedback), and dWorldQuickStep steps the world:
 * no islands, no resting preload, no contact softness, no forces read back, no sleep rule
 * (SLEEP and FEEDBACK are ignored).
 *
 * Usage: bench_ode N STEPS SLEEP(0|1) FEEDBACK(0|1) SLEEP_TIME SLEEP_LINEAR SLEEP_ANGULAR
 *                  STEADY_SHARE SMOOTHING ITERATIONS ERP CFM WARM_START SOFTNESS EXACT_ROWS
 *                  [POLICY(0|1), default 1] [DT, default 1/60]
 * Prints: ms_per_step=<mean ms> mean_z=<mean box height at the end> contacts=<last step>
 *         impulse=<sum of the last step's contact impulses, 0 without feedback>
 *         asleep=<bodies asleep at the end>
 * Built and run by app/bench/physics.py
 * (cc -O2 -I engine/physics/ode3d $(pkg-config --cflags --libs ode)).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ode/ode.h>

#include "stepper.h"

#define MAX_CONTACTS 4

static CsState stepper;
static CsSettings settings;
static double dt = 1.0 / 60.0;
static int policy = 1;              /* 0: plain libode, contact joints made right here */
static dWorldID plain_world;
static dJointGroupID plain_group;
static int plain_contacts;          /* contacts made this step (plain) */

static void near_callback(void *data, dGeomID o1, dGeomID o2) {
    dBodyID b1 = dGeomGetBody(o1), b2 = dGeomGetBody(o2);
    dContact c[MAX_CONTACTS];
    (void)data;
    if (b1 == NULL) { /* keep the moving body first, like the engine */
        dGeomID og = o1; o1 = o2; o2 = og;
        dBodyID ob = b1; b1 = b2; b2 = ob;
    }
    if (b1 == NULL || b1 == b2) return;
    if (!dBodyIsEnabled(b1) && (b2 == NULL || !dBodyIsEnabled(b2))) return;
    if (b2 != NULL && dAreConnectedExcluding(b1, b2, dJointTypeContact)) return;
    if (policy) { /* as the engine: straight into stepper.h's room */
        CsContact *room = cs_room(&stepper, MAX_CONTACTS);
        if (room == NULL) return; /* stepper.oom: the step loop stops */
        int n = dCollide(o1, o2, MAX_CONTACTS, &room[0].contact.geom, sizeof(CsContact));
        for (int i = 0; i < n; i++) {
            room[i].contact.surface.mode = dContactApprox1;
            room[i].contact.surface.mu = 0.5;
        }
        cs_keep(&stepper, &settings, n, b1, b2, dt);
        return;
    }
    int n = dCollide(o1, o2, MAX_CONTACTS, &c[0].geom, sizeof(dContact));
    for (int i = 0; i < n; i++) {
        c[i].surface.mode = dContactApprox1;
        c[i].surface.mu = 0.5;
        dJointAttach(dJointCreateContact(plain_world, plain_group, &c[i]), b1, b2);
    }
    plain_contacts += n;
}

/* CPU time of this thread: on a shared machine it counts our work, not our waiting. */
static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* The sleep rule's arrays for `n` dynamic bodies, all awake, all allowed to sleep, with
 * the squared bounds sleep.py's _bounds makes (slow, steady, at rest). 0, or -1 out of
 * memory. */
static int make_rule(SrRule *r, int n, double linear, double angular, double steady,
                     double *bounds) {
    double share[3] = {1.0, steady, steady * steady};
    uint8_t *flags = calloc((size_t)(4 * n + 1), 1);
    for (int k = 0; k < 3; k++) {
        bounds[2 * k] = linear * linear * (share[k] * share[k]);
        bounds[2 * k + 1] = angular * angular * (share[k] * share[k]);
    }
    r->stack = calloc((size_t)(18 * n + 1), sizeof(double));
    r->smoothing = calloc((size_t)(n + 1), sizeof(double));
    r->timer = calloc((size_t)(n + 1), sizeof(double));
    r->reference = calloc((size_t)(6 * n + 1), sizeof(double));
    if (!flags || !r->stack || !r->smoothing || !r->timer || !r->reference) return -1;
    r->started = flags;
    r->awake = flags + n;
    memset(flags + 2 * n, 1, (size_t)(2 * n)); /* eligible, movable */
    r->eligible = flags + 2 * n;
    r->movable = flags + 3 * n;
    r->bounds = bounds;
    r->n = n;
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 16 || argc > 18) {
        fprintf(stderr, "usage: %s N STEPS SLEEP FEEDBACK SLEEP_TIME SLEEP_LINEAR "
                "SLEEP_ANGULAR STEADY_SHARE SMOOTHING ITERATIONS ERP CFM WARM_START SOFTNESS "
                "EXACT_ROWS [POLICY] [DT]\n", argv[0]);
        return 2;
    }
    int n = atoi(argv[1]), steps = atoi(argv[2]), sleep = atoi(argv[3]);
    int sum_impulses = atoi(argv[4]);
    double sleep_time = atof(argv[5]), sleep_linear = atof(argv[6]);
    double sleep_angular = atof(argv[7]), steady = atof(argv[8]), smoothing = atof(argv[9]);
    int iterations = atoi(argv[10]);
    double erp = atof(argv[11]), cfm = atof(argv[12]);
    settings.beta = atof(argv[13]);
    settings.softness = atof(argv[14]);
    settings.exact_rows = atoi(argv[15]);
    if (argc > 16) policy = atoi(argv[16]);
    if (argc > 17) dt = atof(argv[17]);
    if (!policy) sleep = sum_impulses = 0;
    SrRule rule;
    double bounds[6];
    cs_init(&stepper);
    if (make_rule(&rule, n, sleep_linear, sleep_angular, steady, bounds) < 0) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }

    dInitODE2(0);
    dAllocateODEDataForThread(dAllocateMaskAll);
    dRandSetSeed(0);
    dWorldID world = dWorldCreate();
    dSpaceID space = dHashSpaceCreate(NULL);
    dHashSpaceSetLevels(space, -1, 6);
    dJointGroupID contacts = dJointGroupCreate(0);
    dWorldSetGravity(world, 0, 0, -9.81);
    dWorldSetERP(world, erp);
    dWorldSetCFM(world, cfm);
    dWorldSetQuickStepNumIterations(world, iterations);
    dWorldSetContactSurfaceLayer(world, 0.001);
    dWorldSetAutoDisableFlag(world, 0); /* bodies sleep by the engine's rule */
    dCreatePlane(space, 0, 0, 1, 0);
    plain_world = world;
    plain_group = contacts;

    int columns = (n + 9) / 10;
    int side = (int)ceil(sqrt((double)columns));
    dBodyID *bodies = malloc(sizeof(dBodyID) * (size_t)n);
    for (int i = 0; i < n; i++) {
        int col = i / 10, level = i % 10;
        dBodyID b = dBodyCreate(world);
        dMass m;
        dMassSetBoxTotal(&m, 1.0, 1.0, 1.0, 1.0);
        dBodySetMass(b, &m);
        dBodySetPosition(b, 1.2 * (col % side), 1.2 * (col / side), 0.55 + 1.1 * level);
        dGeomID g = dCreateBox(space, 1.0, 1.0, 1.0);
        dGeomSetBody(g, b);
        dBodySetData(b, (void *)(intptr_t)i); /* its index, as stepper.h reads it */
        bodies[i] = b;
    }

    double impulse = 0;
    double t0 = now_ms();
    int ncontacts = 0;
    for (int s = 0; s < steps; s++) {
        dJointGroupEmpty(contacts);
        if (!policy) { /* plain libode: collide (joints made there), step */
            plain_contacts = 0;
            dSpaceCollide(space, NULL, near_callback);
            dWorldQuickStep(world, dt);
            ncontacts = plain_contacts;
            continue;
        }
        cs_begin(&stepper, n);
        if (cs_any_awake(bodies, sizeof(dBodyID), n)) /* all asleep: no pair can touch */
            dSpaceCollide(space, NULL, near_callback);
        if (stepper.oom) {
            fprintf(stderr, "out of memory\n");
            return 1;
        }
        cs_solve(&stepper, &settings, world, contacts, bodies, sizeof(dBodyID), n, dt);
        if (sleep && cs_sleep(&stepper, &rule, bodies, sizeof(dBodyID), n, dt,
                              exp(-dt / smoothing), sleep_time, NULL) < 0) {
            fprintf(stderr, "out of memory\n");
            return 1;
        }
        ncontacts = stepper.ncontacts;
        if (sum_impulses) {
            cs_whole_forces(&stepper); /* the preloads put back, as the engine reports them */
            impulse = 0;
            for (int i = 0; i < ncontacts; i++) {
                const double *f = &stepper.forces[3 * i];
                impulse += sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) * dt;
            }
        }
    }
    double ms = (now_ms() - t0) / steps;

    double z = 0;
    int asleep = 0;
    for (int i = 0; i < n; i++) {
        z += dBodyGetPosition(bodies[i])[2];
        asleep += !dBodyIsEnabled(bodies[i]);
    }
    printf("ms_per_step=%.6f mean_z=%.6f contacts=%d impulse=%.6f asleep=%d\n", ms,
           n ? z / n : 0.0, ncontacts, impulse, asleep);

    cs_free(&stepper);
    free((void *)rule.started);
    free(rule.stack);
    free(rule.smoothing);
    free(rule.timer);
    free(rule.reference);
    free(bodies);
    dJointGroupDestroy(contacts);
    dSpaceDestroy(space);
    dWorldDestroy(world);
    dCloseODE();
    return 0;
}
