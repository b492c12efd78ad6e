/* Plain C reference for `colosseum bench physics`: the "boxes" scene on libode.
 *
 * A ground plane and N boxes (1 m, 1 kg) in columns 10 high, columns 1.2 m
 * apart on a square grid, layers 1.1 m apart, the lowest centred at 0.55 m;
 * dt 1/60 s, QuickStep 20 iterations, at most 4 contacts per pair, Coulomb
 * friction mu 0.5 (dContactApprox1). World settings (ERP, CFM, contact surface
 * layer, hash-space levels) match what engine/physics/ode3d sets, so both sides
 * solve the same problem.
 *
 * Sleeping is ODE's own auto-disable set up as close to the engine's sleep rule
 * (engine/physics/sleep.py) as it goes: by time, not steps (AutoDisableSteps 0,
 * AutoDisableTime = SleepTime), on each step's velocity (AverageSamplesCount 1)
 * under the same linear and angular limits, passed in by tools/bench_physics.py.
 * What ODE lacks (the steady test, islands) is the engine's extra work.
 *
 * With FEEDBACK=1 every contact joint also gets a dJointFeedback and the
 * impulse |f|·dt of each contact is computed after the step, which is the
 * extra work the engine does to report contact impulses.
 *
 * Usage: bench_ode N STEPS SLEEP(0|1) FEEDBACK(0|1) SLEEP_TIME SLEEP_LINEAR SLEEP_ANGULAR
 * Prints: ms_per_step=<mean ms> mean_z=<mean box height at the end> contacts=<last step>
 *         impulse=<sum of the last step's contact impulses, 0 without feedback>
 * Built and run by tools/bench_physics.py (cc -O2 $(pkg-config --cflags --libs ode)).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include <ode/ode.h>

#define MAX_CONTACTS 4

static dWorldID world;
static dJointGroupID contacts;
static int ncontacts;
static dJointFeedback *feedback; /* NULL: no feedback */
static int feedback_cap;

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
    int n = dCollide(o1, o2, MAX_CONTACTS, &c[0].geom, sizeof(dContact));
    for (int i = 0; i < n; i++) {
        c[i].surface.mode = dContactApprox1;
        c[i].surface.mu = 0.5;
        dJointID j = dJointCreateContact(world, contacts, &c[i]);
        dJointAttach(j, b1, b2);
        if (feedback != NULL && ncontacts + i < feedback_cap)
            dJointSetFeedback(j, &feedback[ncontacts + i]);
    }
    ncontacts += n;
}

/* CPU time of this thread: on a shared machine it counts our work, not our waiting. */
static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

int main(int argc, char **argv) {
    if (argc != 8) {
        fprintf(stderr, "usage: %s N STEPS SLEEP FEEDBACK SLEEP_TIME SLEEP_LINEAR "
                "SLEEP_ANGULAR\n", argv[0]);
        return 2;
    }
    int n = atoi(argv[1]), steps = atoi(argv[2]), sleep = atoi(argv[3]);
    double sleep_time = atof(argv[5]), sleep_linear = atof(argv[6]);
    double sleep_angular = atof(argv[7]);
    if (atoi(argv[4])) {
        feedback_cap = 8 * n + 64; /* at most 4 contacts per pair, ~2 pairs per box */
        feedback = calloc((size_t)feedback_cap, sizeof(dJointFeedback));
    }
    const double dt = 1.0 / 60.0;

    dInitODE2(0);
    dAllocateODEDataForThread(dAllocateMaskAll);
    dRandSetSeed(0);
    world = dWorldCreate();
    dSpaceID space = dHashSpaceCreate(NULL);
    dHashSpaceSetLevels(space, -1, 6);
    contacts = dJointGroupCreate(0);
    dWorldSetGravity(world, 0, 0, -9.81);
    dWorldSetERP(world, 0.2);
    dWorldSetCFM(world, 1e-5);
    dWorldSetQuickStepNumIterations(world, 20);
    dWorldSetContactSurfaceLayer(world, 0.001);
    dWorldSetAutoDisableFlag(world, sleep);
    dWorldSetAutoDisableLinearThreshold(world, sleep_linear);
    dWorldSetAutoDisableAngularThreshold(world, sleep_angular);
    dWorldSetAutoDisableSteps(world, 0);
    dWorldSetAutoDisableTime(world, sleep_time);
    dWorldSetAutoDisableAverageSamplesCount(world, 1);
    dCreatePlane(space, 0, 0, 1, 0);

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
        bodies[i] = b;
    }

    double impulse = 0;
    double t0 = now_ms();
    for (int s = 0; s < steps; s++) {
        ncontacts = 0;
        dSpaceCollide(space, NULL, near_callback);
        dWorldQuickStep(world, dt);
        if (feedback != NULL) {
            int m = ncontacts < feedback_cap ? ncontacts : feedback_cap;
            impulse = 0;
            for (int i = 0; i < m; i++) {
                const dReal *f = feedback[i].f1;
                impulse += sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) * dt;
            }
        }
        dJointGroupEmpty(contacts);
    }
    double ms = (now_ms() - t0) / steps;

    double z = 0;
    for (int i = 0; i < n; i++) z += dBodyGetPosition(bodies[i])[2];
    printf("ms_per_step=%.6f mean_z=%.6f contacts=%d impulse=%.6f\n", ms, n ? z / n : 0.0,
           ncontacts, impulse);

    free(feedback);
    free(bodies);
    dJointGroupDestroy(contacts);
    dSpaceDestroy(space);
    dWorldDestroy(world);
    dCloseODE();
    return 0;
}
