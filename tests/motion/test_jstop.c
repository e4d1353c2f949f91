/*
 * test_jstop.c: the jerk-limited stop of jstop.h and the one-coordinate generator of axprof.h (motion layer).
 * Randomized: [seed] [count] from argv (default 1, 3000).
 * Per-cycle checks of every stop: |j| <= J, |a| <= max(|a0|, D), |dj| <= S dt (snap), the velocity is the
 * derivative of the position (no jump), the end is exact rest, and the duration is finite and plausible.
 * Built double and float: the tolerances below depend on the real type (rounding of float states and
 * positions), the checks are the same.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "lsm_test_rng.h"

#include "axprof.h"
#include "jstop.h"

#if LSM_REAL_IS_FLOAT
#define TOL_REL 1e-5    /* limits: relative rounding of a float state */
#define TOL_ABS 2e-5    /* small absolute quantities (mm, mm/s near 10) */
#define TOL_POS 8e-7    /* per-cycle position check: a few ulps of the positions compared */
#define TOL_CRUISE 1e-4 /* a and v at cruise (v = 50 mm/s: about 100 ulps) */
#define TOL_J_ABS 4e-3  /* sampled jerk near 2e4 mm/s³: about 100 ulps */
#else
#define TOL_REL 1e-9
#define TOL_ABS 1e-9
#define TOL_POS 1e-12
#define TOL_CRUISE 1e-6
#define TOL_J_ABS 1e-6
#endif

static unsigned g_seed = 1, g_count = 3000;

#define urand test_urand /* the shared generator (tests/common/lsm_test_rng.h) */

/* Runs a stop from (p, v, a, j) to its end; checks the limits cycle by cycle, the sampled jerk change also from
 * the starting jerk j to the first sample. Returns the number of cycles. */
static unsigned run_stop_j(double p, double v, double a, double j, const lsm_jstop_limits *l, double dt, double *p_end)
{
    lsm_jstop s;
    assert_int_equal(lsm_jstop_plan(&s, p, v, a, j, l), LSM_OK);
    /* the jerk release adds at most pi j² / (4 S) to |a| (jstop.h) */
    const double amax = fmax(fabs(a) + LSM_PI * j * j / (4 * l->snap_mm_s4), l->decel_mm_s2) * (1 + TOL_REL);
    const double jmax = fmax(fabs(j), l->jerk_mm_s3) * (1 + TOL_REL);
    double pp = p, pv = v, pj = j;
    bool first = false;
    unsigned n = 0;
    lsm_kin k;
    bool running = true;
    while (running) {
        running = lsm_jstop_step(&s, dt, &k);
        n++;
        assert_true(n < 10000000u);
        assert_true(fabs(k.j_mm_s3) <= jmax);
        assert_true(fabs(k.a_mm_s2) <= amax);
        if (!first && running) /* sampled jerk changes at most S per second */
            assert_true(fabs(k.j_mm_s3 - pj) <= l->snap_mm_s4 * dt * (1 + 1e-6) + TOL_REL * l->jerk_mm_s3);
        /* the position moves by the mean velocity of the cycle, within what the acceleration allows */
        const double dv_bound = amax * dt;
        const double step = k.s_mm - pp;
        assert_true(fabs(step - (pv + k.v_mm_s) / 2 * dt) <=
                    dv_bound * dt + TOL_POS * (fabs(p) + fabs(pp) + fabs(k.s_mm) + 1));
        pp = k.s_mm;
        pv = k.v_mm_s;
        pj = k.j_mm_s3;
        first = false;
    }
    assert_true(k.v_mm_s == 0 && k.a_mm_s2 == 0 && k.j_mm_s3 == 0);
    *p_end = k.s_mm;
    return n;
}

static unsigned run_stop(double p, double v, double a, const lsm_jstop_limits *l, double dt, double *p_end)
{
    return run_stop_j(p, v, a, 0, l, dt, p_end);
}

static void test_constant_jerk_limit(void **state)
{
    (void)state;
    /* huge D and S: the stop from (v, 0) is two constant-jerk ramps: t = 2 sqrt(v / J), distance v t / 2 */
    lsm_jstop_limits l = {1e12, 1000, 1e15};
    lsm_jstop s;
    assert_int_equal(lsm_jstop_plan(&s, 0, 10, 0, 0, &l), LSM_OK);
    assert_true(fabs(s.t_end_s - 2 * sqrt(10.0 / 1000)) < 1e-6);
    lsm_kin e;
    lsm_jstop_eval(&s, s.t_end_s, &e);
    assert_true(fabs(e.s_mm - 10 * s.t_end_s / 2) < 1e-6);
    assert_true(fabs(e.v_mm_s) < TOL_ABS);
}

static void test_decel_plateau(void **state)
{
    (void)state;
    /* from 100 mm/s at rest acceleration, D = 1000, J = 1e5, S = 1e9: plateau at -D */
    lsm_jstop_limits l = {1000, 1e5, 1e9};
    double pe;
    unsigned n = run_stop(5, 100, 0, &l, 0.001, &pe);
    /* lower bound of the time: v / D; the ramps add about D / J */
    assert_true(n >= 100 && n <= 100 + 2 * 10 + 10);
    assert_true(pe > 5 + 100 * 0.1 / 2 && pe < 5 + 100 * 0.13);
    /* and in the negative direction the mirror image */
    double pn;
    (void)run_stop(-5, -100, 0, &l, 0.001, &pn);
    assert_true(fabs((pn + 5) + (pe - 5)) < TOL_ABS);
}

static void test_at_rest(void **state)
{
    (void)state;
    lsm_jstop_limits l = {1000, 1e5, 1e9};
    lsm_jstop s;
    assert_int_equal(lsm_jstop_plan(&s, 3, 0, 0, 0, &l), LSM_OK);
    lsm_kin k;
    assert_false(lsm_jstop_step(&s, 0.001, &k));
    assert_true(k.s_mm == 3 && k.v_mm_s == 0);
    lsm_jstop_limits bad = {0, 1, 1};
    assert_int_equal(lsm_jstop_plan(&s, 0, 1, 0, 0, &bad), LSM_E_LIMIT);
    lsm_jstop_limits nan_l = {NAN, 1, 1};
    assert_int_equal(lsm_jstop_plan(&s, 0, 1, 0, 0, &nan_l), LSM_E_NAN);
    assert_int_equal(lsm_jstop_plan(&s, 0, 1, 0, NAN, &l), LSM_E_NAN);
}

static void test_random_states(void **state)
{
    (void)state;
    uint64_t r = 0x9E3779B97F4A7C15ull ^ g_seed;
    for (unsigned i = 0; i < g_count; i++) {
        lsm_jstop_limits l;
        l.decel_mm_s2 = pow(10, 1 + 3 * urand(&r));
        l.jerk_mm_s3 = l.decel_mm_s2 * pow(10, 0.5 + 2 * urand(&r));
        l.snap_mm_s4 = l.jerk_mm_s3 * pow(10, 0.5 + 2.5 * urand(&r));
        const double v = (urand(&r) - 0.5) * 2 * pow(10, 3 * urand(&r));
        /* the acceleration of a state a limited profile can reach: |a| up to 1.5 D, either sign */
        const double a = (urand(&r) - 0.5) * 3 * l.decel_mm_s2 * (urand(&r) < 0.2 ? 0 : 1);
        /* a stop requested inside a jerk phase of a move: |j| up to J, either sign */
        const double j = (urand(&r) - 0.5) * 2 * l.jerk_mm_s3 * (urand(&r) < 0.3 ? 0 : 1);
        const double dt = urand(&r) < 0.5 ? 0.001 : 0.00025;
        double pe;
        unsigned n = run_stop_j(0, v, a, j, &l, dt, &pe);
        /* an upper bound of the stop time: release j, ramp a to -D, brake at D from at most |v| + a^2/(2J)
         * (with a and v after the release) */
        const double t_rel = LSM_PI * fabs(j) / (2 * l.snap_mm_s4);
        const double a_rel = fabs(a) + fabs(j) * t_rel / 2;
        const double v_rel = fabs(v) + a_rel * t_rel;
        double t_bound = t_rel +
                         2 * lsm_jstop_ramp_time(a_rel + l.decel_mm_s2, l.jerk_mm_s3, l.snap_mm_s4, NULL, NULL, NULL) +
                         (v_rel + a_rel * a_rel / l.jerk_mm_s3) / l.decel_mm_s2 + 4 * dt;
        assert_true((double)n * dt <= t_bound * 2 + 0.01);
    }
}

static void test_prof_move_and_stop(void **state)
{
    (void)state;
    lsm_axprof p;
    lsm_axprof_init(&p, 0.001, 2.0);
    lsm_axprof_limits lim = {50, 500, 1e4, 1e6, 1};
    assert_int_equal(lsm_axprof_move(&p, 12.0, &lim), LSM_OK);
    unsigned n = 0;
    double vmax = 0;
    while (!lsm_axprof_at_rest(&p) && n < 100000) {
        lsm_axprof_step(&p);
        vmax = fmax(vmax, fabs(p.k.v_mm_s));
        assert_true(fabs(p.k.a_mm_s2) <= 500 * (1 + TOL_REL));
        assert_true(fabs(p.k.j_mm_s3) <= 1e4 * (1 + TOL_REL));
        n++;
    }
    assert_true(p.k.s_mm == 12.0);
    assert_true(vmax <= 50 * (1 + TOL_REL) && vmax > 40);
    /* linear type: faster than sin² for the same J (its jerk rises in one cycle) */
    lsm_axprof q;
    lsm_axprof_init(&q, 0.001, 2.0);
    lim.profile_type = 0;
    assert_int_equal(lsm_axprof_move(&q, 12.0, &lim), LSM_OK);
    unsigned m = 0;
    while (!lsm_axprof_at_rest(&q) && m < 100000) {
        lsm_axprof_step(&q);
        m++;
    }
    assert_true(q.k.s_mm == 12.0 && m < n);
    /* a stop in the middle of a move: jerk-limited, at rest short of the target */
    lsm_axprof_init(&p, 0.001, 0.0);
    lim.profile_type = 1;
    assert_int_equal(lsm_axprof_move(&p, 100.0, &lim), LSM_OK);
    for (int i = 0; i < 300; i++)
        lsm_axprof_step(&p);
    const double v_at = p.k.v_mm_s;
    assert_true(v_at > 10);
    lsm_jstop_limits sl = {800, 2e4, 2e6};
    assert_int_equal(lsm_axprof_stop(&p, &sl, 3), LSM_OK);
    double pj = p.k.j_mm_s3;
    while (!lsm_axprof_at_rest(&p)) {
        lsm_axprof_step(&p);
        assert_true(fabs(p.k.j_mm_s3) <= 2e4 * (1 + TOL_REL));
        assert_true(fabs(p.k.j_mm_s3 - pj) <= 2e6 * 0.001 * (1 + 1e-6) + TOL_J_ABS);
        pj = p.k.j_mm_s3;
    }
    assert_true(p.k.s_mm < 100.0 && p.k.v_mm_s == 0);
    /* a stop inside the first jerk phase of a move (it waits for the end of the pulse, axprof.h): the jerk never jumps */
    lsm_axprof_init(&p, 0.001, 0.0);
    assert_int_equal(lsm_axprof_move(&p, 100.0, &lim), LSM_OK);
    for (int i = 0; i < 12; i++)
        lsm_axprof_step(&p);
    assert_true(fabs(p.k.j_mm_s3) > 1e3);
    assert_int_equal(lsm_axprof_stop(&p, &sl, 3), LSM_OK);
    pj = p.k.j_mm_s3;
    while (!lsm_axprof_at_rest(&p)) {
        lsm_axprof_step(&p);
        assert_true(fabs(p.k.j_mm_s3) <= 2e4 * (1 + TOL_REL));
        assert_true(fabs(p.k.j_mm_s3 - pj) <= 2e6 * 0.001 * (1 + 1e-6) + TOL_J_ABS);
        pj = p.k.j_mm_s3;
    }
    assert_true(p.k.v_mm_s == 0 && p.k.s_mm > 0);
    /* retarget while cruising: continues without stopping (the velocity never drops to 0 before the end) */
    lsm_axprof_init(&p, 0.001, 0.0);
    assert_int_equal(lsm_axprof_move(&p, 100.0, &lim), LSM_OK);
    for (int i = 0; i < 500; i++)
        lsm_axprof_step(&p);
    assert_true(fabs(p.k.a_mm_s2) < TOL_CRUISE && fabs(p.k.v_mm_s - 50) < TOL_CRUISE);
    assert_int_equal(lsm_axprof_move(&p, 60.0, &lim), LSM_OK);
    assert_int_equal(p.mode, LSM_AXPROF_MOVE);
    double vmin = 1e9;
    while (!lsm_axprof_at_rest(&p)) {
        lsm_axprof_step(&p);
        if (!lsm_axprof_at_rest(&p))
            vmin = fmin(vmin, p.k.v_mm_s);
    }
    assert_true(p.k.s_mm == 60.0 && vmin > 0);
    /* retarget backwards while moving: stop first, then go */
    lsm_axprof_init(&p, 0.001, 0.0);
    assert_int_equal(lsm_axprof_move(&p, 100.0, &lim), LSM_OK);
    for (int i = 0; i < 200; i++)
        lsm_axprof_step(&p);
    assert_int_equal(lsm_axprof_move(&p, -5.0, &lim), LSM_OK);
    assert_int_equal(p.mode, LSM_AXPROF_STOP);
    n = 0;
    while (!lsm_axprof_at_rest(&p) && n < 100000) {
        lsm_axprof_step(&p);
        assert_true(fabs(p.k.a_mm_s2) <= 500 * (1 + TOL_REL));
        n++;
    }
    assert_true(p.k.s_mm == -5.0);
}

/* lsm_jstop_plan_settle from random states, with and without a lead-in phase: it ends with a = j = 0 at a constant
 * velocity (v_end_mm_s, then held), the jerk continuous (|dj| <= S dt from the starting jerk on), |j| <= max(|j0|,
 * J), |a| <= |a0| + pi jl² / (2 S) with jl the larger of |j0| and the lead's amplitude (the rest of a rise of the
 * jerk, then its release: a random lead need not belong to a move that keeps a within its limits; a move's own lead
 * does, axprof.h), and v within what that acceleration and the ramps can add. */
static void test_settle_random(void **state)
{
    (void)state;
    uint64_t r = 0x5DEECE66Dull ^ g_seed;
    for (unsigned i = 0; i < g_count; i++) {
        lsm_jstop_limits l;
        l.decel_mm_s2 = pow(10, 1 + 3 * urand(&r));
        l.jerk_mm_s3 = l.decel_mm_s2 * pow(10, 0.5 + 2 * urand(&r));
        l.snap_mm_s4 = l.jerk_mm_s3 * pow(10, 0.5 + 2.5 * urand(&r));
        const double v = (urand(&r) - 0.5) * 2 * pow(10, 3 * urand(&r));
        const double a = (urand(&r) - 0.5) * 2 * l.decel_mm_s2;
        const double dt = 0.001;
        /* a lead: a sin² rise or cos² fall of the jerk of amplitude up to J, entered part way */
        lsm_jstop_lead lead;
        lead.shape = urand(&r) < 0.5 ? LSM_PHASE_RISE : LSM_PHASE_FALL;
        lead.jerk_mm_s3 = (lsm_real)((urand(&r) - 0.5) * 2 * l.jerk_mm_s3);
        lead.full_s = (lsm_real)(LSM_PI * fabs((double)lead.jerk_mm_s3) / (2 * l.snap_mm_s4) + 1e-9);
        lead.off_s = (lsm_real)(urand(&r) * 0.99 * (double)lead.full_s);
        lsm_real u[4];
        lsm_phase_unit((lsm_phase_shape)lead.shape, lead.full_s, lead.off_s, u);
        const double j = (double)(lead.jerk_mm_s3 * u[0]);
        const bool with_lead = urand(&r) < 0.7 && j != 0;
        lsm_jstop s;
        assert_int_equal(lsm_jstop_plan_settle(&s, 0, v, a, j, with_lead ? &lead : NULL, &l), LSM_OK);
        const double jmax = fmax(fabs(j), l.jerk_mm_s3) * (1 + TOL_REL) + TOL_J_ABS;
        const double jl = fmax(fabs(j), with_lead ? fabs((double)lead.jerk_mm_s3) : 0);
        const double amax = (fabs(a) + LSM_PI * jl * jl / (2 * l.snap_mm_s4)) * (1 + TOL_REL) + TOL_ABS;
        const double vspan = amax * amax / l.jerk_mm_s3 + amax * (LSM_PI * l.jerk_mm_s3 / l.snap_mm_s4 + 4 * dt);
        double pj = j;
        lsm_kin k;
        unsigned n = 0;
        bool running = s.active;
        while (running) {
            running = lsm_jstop_step(&s, dt, &k);
            assert_true(++n < 10000000u);
            assert_true(fabs(k.j_mm_s3) <= jmax);
            assert_true(fabs(k.a_mm_s2) <= amax);
            assert_true(fabs(k.v_mm_s - v) <= vspan * (1 + TOL_REL) + TOL_ABS * (1 + fabs(v)));
            if (running)
                assert_true(fabs(k.j_mm_s3 - pj) <= l.snap_mm_s4 * dt * (1 + 1e-6) + TOL_REL * l.jerk_mm_s3);
            pj = k.j_mm_s3;
        }
        if (n > 0) {
            assert_true(k.a_mm_s2 == 0 && k.j_mm_s3 == 0);
            assert_true(k.v_mm_s == s.v_end_mm_s);
        } else {
            assert_true(a == 0 && j == 0 && (double)s.v_end_mm_s == (double)(lsm_real)v);
        }
    }
}

int main(int argc, char **argv)
{
    g_seed = (unsigned)test_arg_u(argc, argv, 1, g_seed);
    g_count = (unsigned)test_arg_u(argc, argv, 2, g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_jerk_limit),
        cmocka_unit_test(test_decel_plateau),
        cmocka_unit_test(test_at_rest),
        cmocka_unit_test(test_random_states),
        cmocka_unit_test(test_settle_random),
        cmocka_unit_test(test_prof_move_and_stop),
    };
    return test_seed_finish(argv[0], g_seed, g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
