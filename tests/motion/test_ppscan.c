/*
 * test_ppscan.c: a retarget (PP "change set immediately") and a halt requested at EVERY control cycle of a PP
 * move (axprof.h), for both profile types (0x6086 = 0 and 1), several profiles (the first is the HIL rig's
 * PROFILE of hil/tests/test_pp.py), long moves that cruise, short moves that never reach cruise, and moves in
 * both directions. Deterministic: no randomness, every request time is tried.
 *
 * Checked at every cycle, from the start of the move to rest:
 *   |v| <= V, |a| <= A, |j| <= J                      (the profile's limits)
 *   |j_k - j_k-1| <= S dt                              (snap; type 0: the effective S' of axprof.h)
 *   |a_k - a_k-1| <= J dt, |v_k - v_k-1| <= A dt       (no jump in a or v)
 *   |s_k - s_k-1 - (v_k-1 + v_k) dt / 2| <= J dt³ / 12 (no jump in s: the trapezoid error of a jerk <= J)
 * each with a noise allowance of NOISE_ULPS ulps of the real type relative to the limit's scale (the closed-form
 * states carry a few roundings of quantities of that size), and no more. The end: exactly the new target after a
 * retarget, exact rest (v = a = j = 0) after a halt.
 *
 * Built double and float (ctest). Prints the worst value of each ratio over the whole scan (the figures of the
 * report), and on failure the case and request cycle.
 */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cmocka.h>

#include "axprof.h"
#include "jstop.h"

/* Noise allowance: this many ulps of the real type, relative to each limit (see the header comment). */
#define NOISE_ULPS 8.0
#if LSM_REAL_IS_FLOAT
#define ULP_REL ((double)FLT_EPSILON)
#else
#define ULP_REL DBL_EPSILON
#endif
#define NOISE (NOISE_ULPS * ULP_REL)
#define CYCLE_S 0.001      /* the node's control cycle */
#define MAX_CYCLES 200000u /* guard: no scanned move or stop comes near it */

typedef struct profile {
    double v, a, j, snap;
} profile;

static const profile PROFILES[] = {
    {100.0, 1000.0, 20000.0, 2.0e6}, /* hil/tests/test_pp.py PROFILE */
    {50.0, 500.0, 1.0e4, 1.0e6},     /* slow, reaches a only after a long jerk plateau */
    {200.0, 3000.0, 1.0e5, 2.0e7},   /* fast: short ramps, many phases per few cycles */
};

/* Distances: a long move that cruises, short ones that never reach cruise, both directions (mm). */
static const double DISTANCES[] = {75.0, -40.0, 3.0, -0.8};

typedef enum { REQ_HALT, REQ_BACK, REQ_BEYOND } req_kind;

typedef struct worst {
    double v, a, j, snap, da, dv, ds; /* worst ratio to the allowed value (1 = at the limit) */
    unsigned bad;                     /* request times with any violation */
    unsigned rested;                  /* requests after which the axis came to rest before the end */
    unsigned runs;
} worst;

static worst g_worst[2][3]; /* [profile type][request kind] */

typedef struct checker {
    double V, A, J, S;
    lsm_kin prev;
    unsigned n; /* cycles checked */
    bool bad;
    worst *w;
} checker;

static double ratio(double x, double lim, double noise_scale)
{
    return fabs(x) / (lim + NOISE * noise_scale);
}

static void note(checker *c, double *slot, double r)
{
    if (r > 1 && !c->bad && c->w->bad < 3)
        printf("  ratio %.9g (field %d) at cycle %u: s %.9g v %.9g a %.9g j %.9g\n", r, (int)(slot - &c->w->v), c->n,
               (double)c->prev.s_mm, (double)c->prev.v_mm_s, (double)c->prev.a_mm_s2, (double)c->prev.j_mm_s3);
    if (r > *slot)
        *slot = r;
    if (r > 1)
        c->bad = true;
}

static void check_cycle(checker *c, const lsm_kin *k)
{
    const double dt = CYCLE_S;
    const lsm_kin *p = &c->prev;
    note(c, &c->w->v, ratio(k->v_mm_s, c->V, c->V));
    note(c, &c->w->a, ratio(k->a_mm_s2, c->A, c->A));
    note(c, &c->w->j, ratio(k->j_mm_s3, c->J, c->J));
    note(c, &c->w->snap, ratio(k->j_mm_s3 - p->j_mm_s3, c->S * dt, c->J));
    note(c, &c->w->da, ratio(k->a_mm_s2 - p->a_mm_s2, c->J * dt, c->A));
    note(c, &c->w->dv, ratio(k->v_mm_s - p->v_mm_s, c->A * dt, c->V));
    const double ds = k->s_mm - p->s_mm - (p->v_mm_s + k->v_mm_s) * dt / 2;
    note(c, &c->w->ds, ratio(ds, c->J * dt * dt * dt / 12, fabs(k->s_mm) + fabs(p->s_mm) + c->V * dt));
    c->prev = *k;
    c->n++;
}

static void step_checked(checker *c, lsm_axprof *p)
{
    (void)lsm_axprof_step(p);
    check_cycle(c, &p->k);
}

/* Cycles of the undisturbed move (to know the request times to scan). */
static unsigned move_cycles(const lsm_axprof_limits *lim, double dist)
{
    lsm_axprof p;
    lsm_axprof_init(&p, CYCLE_S, 0);
    assert_int_equal(lsm_axprof_move(&p, dist, lim), LSM_OK);
    unsigned n = 0;
    while (!lsm_axprof_at_rest(&p) && n < MAX_CYCLES) {
        lsm_axprof_step(&p);
        n++;
    }
    assert_true(n < MAX_CYCLES && p.k.s_mm == (lsm_real)dist);
    return n;
}

/* One move of dist from 0, the request at cycle `at`, run to rest with every cycle checked. */
static void run_one(const lsm_axprof_limits *lim, double dist, unsigned at, req_kind rk)
{
    const lsm_axprof_limits e = lsm_axprof_effective(lim, CYCLE_S);
    checker c = {lim->v_max_mm_s,
                 lim->a_max_mm_s2,
                 lim->j_max_mm_s3,
                 e.snap_max_mm_s4,
                 {0, 0, 0, 0},
                 0,
                 false,
                 &g_worst[lim->profile_type][rk]};
    lsm_axprof p;
    lsm_axprof_init(&p, CYCLE_S, 0);
    assert_int_equal(lsm_axprof_move(&p, dist, lim), LSM_OK);
    for (unsigned i = 0; i < at; i++)
        step_checked(&c, &p);
    const double target = rk == REQ_BACK ? 0.1 * dist : 1.5 * dist;
    if (rk == REQ_HALT) {
        const lsm_jstop_limits sl = {e.a_max_mm_s2, e.j_max_mm_s3, e.snap_max_mm_s4};
        assert_int_equal(lsm_axprof_stop(&p, &sl, 1), LSM_OK);
    } else {
        assert_int_equal(lsm_axprof_move(&p, target, lim), LSM_OK);
    }
    unsigned n = 0;
    bool rested = false;
    while (!lsm_axprof_at_rest(&p) && n < MAX_CYCLES) {
        step_checked(&c, &p);
        rested |= p.k.v_mm_s == 0 && !lsm_axprof_at_rest(&p);
        n++;
    }
    assert_true(n < MAX_CYCLES);
    if (rested)
        c.w->rested++;
    const bool end_ok =
        p.k.v_mm_s == 0 && p.k.a_mm_s2 == 0 && p.k.j_mm_s3 == 0 && (rk == REQ_HALT || p.k.s_mm == (lsm_real)target);
    if (!end_ok || c.bad) {
        c.w->bad++;
        if (c.w->bad <= 3)
            printf("  violation: type %d V %g dist %g request %d at cycle %u (end s %.17g v %g)\n", lim->profile_type,
                   lim->v_max_mm_s, dist, (int)rk, at, (double)p.k.s_mm, (double)p.k.v_mm_s);
    }
    c.w->runs++;
}

static void test_scan(void **state)
{
    (void)state;
    for (size_t pi = 0; pi < sizeof PROFILES / sizeof PROFILES[0]; pi++) {
        for (int type = 0; type <= 1; type++) {
            const profile *pr = &PROFILES[pi];
            const lsm_axprof_limits lim = {pr->v, pr->a, pr->j, pr->snap, type};
            for (size_t di = 0; di < sizeof DISTANCES / sizeof DISTANCES[0]; di++) {
                const unsigned n = move_cycles(&lim, DISTANCES[di]);
                for (unsigned at = 0; at < n; at++)
                    for (int rk = REQ_HALT; rk <= REQ_BEYOND; rk++)
                        run_one(&lim, DISTANCES[di], at, (req_kind)rk);
            }
        }
    }
    static const char *names[3] = {"halt", "retarget back", "retarget beyond"};
    unsigned bad = 0;
    for (int t = 0; t <= 1; t++)
        for (int r = 0; r < 3; r++) {
            const worst *w = &g_worst[t][r];
            printf("type %d %-15s: %5u requests, %4u violating; worst/limit v %.9f a %.9f j %.9f snap %.9f "
                   "da %.9f dv %.9f ds %.9f; %u came to rest on the way\n",
                   t, names[r], w->runs, w->bad, w->v, w->a, w->j, w->snap, w->da, w->dv, w->ds, w->rested);
            bad += w->bad;
        }
    assert_int_equal(bad, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_scan)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
