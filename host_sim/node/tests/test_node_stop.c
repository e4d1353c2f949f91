/*
 * test_node_stop.c: the jerk-limited stop of node_stop.h and the profile generator of node_prof.h.
 * Randomized: [seed] [count] from argv (default 1, 3000).
 * Per-cycle checks of every stop: |j| <= J, |a| <= max(|a0|, D), |dj| <= S dt (snap), the velocity is the
 * derivative of the position (no jump), the end is exact rest, and the duration is finite and plausible.
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
#include "node_prof.h"
#include "node_stop.h"

static unsigned g_seed = 1, g_count = 3000;

static double urand(uint64_t *s) { return test_urand(s); } /* the shared generator (tests/common) */

/* Runs a stop to its end; checks the limits cycle by cycle. Returns the number of cycles. */
static unsigned run_stop(double p, double v, double a, const node_stop_limits *l, double dt, double *p_end)
{
    node_stop s;
    assert_int_equal(node_stop_plan(&s, p, v, a, l), LSM_OK);
    const double amax = fmax(fabs(a), l->decel) * (1 + 1e-9);
    double pp = p, pv = v, pj = 0;
    bool first = true;
    unsigned n = 0;
    lsm_kin k;
    bool running = true;
    while (running) {
        running = node_stop_step(&s, dt, &k);
        n++;
        assert_true(n < 10000000u);
        assert_true(fabs(k.j_mm_s3) <= l->jerk * (1 + 1e-9));
        assert_true(fabs(k.a_mm_s2) <= amax);
        if (!first && running) /* sampled jerk changes at most S per second */
            assert_true(fabs(k.j_mm_s3 - pj) <= l->snap * dt * (1 + 1e-6) + 1e-9 * l->jerk);
        /* the position moves by the mean velocity of the cycle, within what the acceleration allows */
        const double dv_bound = amax * dt;
        const double step = k.s_mm - pp;
        assert_true(fabs(step - (pv + k.v_mm_s) / 2 * dt) <= dv_bound * dt + 1e-12 * (fabs(p) + 1));
        pp = k.s_mm;
        pv = k.v_mm_s;
        pj = k.j_mm_s3;
        first = false;
    }
    assert_true(k.v_mm_s == 0 && k.a_mm_s2 == 0 && k.j_mm_s3 == 0);
    *p_end = k.s_mm;
    return n;
}

static void test_constant_jerk_limit(void **state)
{
    (void)state;
    /* huge D and S: the stop from (v, 0) is two constant-jerk ramps: t = 2 sqrt(v / J), distance v t / 2 */
    node_stop_limits l = {1e12, 1000, 1e15};
    node_stop s;
    assert_int_equal(node_stop_plan(&s, 0, 10, 0, &l), LSM_OK);
    assert_true(fabs(s.t_end - 2 * sqrt(10.0 / 1000)) < 1e-6);
    lsm_kin e;
    node_stop_eval(&s, s.t_end, &e);
    assert_true(fabs(e.s_mm - 10 * s.t_end / 2) < 1e-6);
    assert_true(fabs(e.v_mm_s) < 1e-9);
}

static void test_decel_plateau(void **state)
{
    (void)state;
    /* from 100 mm/s at rest acceleration, D = 1000, J = 1e5, S = 1e9: plateau at -D */
    node_stop_limits l = {1000, 1e5, 1e9};
    double pe;
    unsigned n = run_stop(5, 100, 0, &l, 0.001, &pe);
    /* lower bound of the time: v / D; the ramps add about D / J */
    assert_true(n >= 100 && n <= 100 + 2 * 10 + 10);
    assert_true(pe > 5 + 100 * 0.1 / 2 && pe < 5 + 100 * 0.13);
    /* and in the negative direction the mirror image */
    double pn;
    (void)run_stop(-5, -100, 0, &l, 0.001, &pn);
    assert_true(fabs((pn + 5) + (pe - 5)) < 1e-9);
}

static void test_at_rest(void **state)
{
    (void)state;
    node_stop_limits l = {1000, 1e5, 1e9};
    node_stop s;
    assert_int_equal(node_stop_plan(&s, 3, 0, 0, &l), LSM_OK);
    lsm_kin k;
    assert_false(node_stop_step(&s, 0.001, &k));
    assert_true(k.s_mm == 3 && k.v_mm_s == 0);
    node_stop_limits bad = {0, 1, 1};
    assert_int_equal(node_stop_plan(&s, 0, 1, 0, &bad), LSM_E_LIMIT);
    node_stop_limits nan_l = {NAN, 1, 1};
    assert_int_equal(node_stop_plan(&s, 0, 1, 0, &nan_l), LSM_E_NAN);
}

static void test_random_states(void **state)
{
    (void)state;
    uint64_t r = 0x9E3779B97F4A7C15ull ^ g_seed;
    for (unsigned i = 0; i < g_count; i++) {
        node_stop_limits l;
        l.decel = pow(10, 1 + 3 * urand(&r));
        l.jerk = l.decel * pow(10, 0.5 + 2 * urand(&r));
        l.snap = l.jerk * pow(10, 0.5 + 2.5 * urand(&r));
        const double v = (urand(&r) - 0.5) * 2 * pow(10, 3 * urand(&r));
        /* the acceleration of a state a limited profile can reach: |a| up to 1.5 D, either sign */
        const double a = (urand(&r) - 0.5) * 3 * l.decel * (urand(&r) < 0.2 ? 0 : 1);
        const double dt = urand(&r) < 0.5 ? 0.001 : 0.00025;
        double pe;
        unsigned n = run_stop(0, v, a, &l, dt, &pe);
        /* an upper bound of the stop time: ramp a to -D, brake at D from at most |v| + a^2/(2J) */
        double t_bound = 2 * node_stop_ramp_time(fabs(a) + l.decel, l.jerk, l.snap, NULL, NULL, NULL) +
                         (fabs(v) + a * a / l.jerk) / l.decel + 4 * dt;
        assert_true((double)n * dt <= t_bound * 2 + 0.01);
    }
}

static void test_prof_move_and_stop(void **state)
{
    (void)state;
    node_prof p;
    node_prof_init(&p, 0.001, 2.0);
    node_prof_limits lim = {50, 500, 1e4, 1e6, 1};
    assert_int_equal(node_prof_move(&p, 12.0, &lim), LSM_OK);
    unsigned n = 0;
    double vmax = 0;
    while (!node_prof_at_rest(&p) && n < 100000) {
        node_prof_step(&p);
        vmax = fmax(vmax, fabs(p.k.v_mm_s));
        assert_true(fabs(p.k.a_mm_s2) <= 500 * (1 + 1e-9));
        assert_true(fabs(p.k.j_mm_s3) <= 1e4 * (1 + 1e-9));
        n++;
    }
    assert_true(p.k.s_mm == 12.0);
    assert_true(vmax <= 50 * (1 + 1e-9) && vmax > 40);
    /* linear type: faster than sin² for the same J (its jerk rises in one cycle) */
    node_prof q;
    node_prof_init(&q, 0.001, 2.0);
    lim.profile_type = 0;
    assert_int_equal(node_prof_move(&q, 12.0, &lim), LSM_OK);
    unsigned m = 0;
    while (!node_prof_at_rest(&q) && m < 100000) {
        node_prof_step(&q);
        m++;
    }
    assert_true(q.k.s_mm == 12.0 && m < n);
    /* a stop in the middle of a move: jerk-limited, at rest short of the target */
    node_prof_init(&p, 0.001, 0.0);
    lim.profile_type = 1;
    assert_int_equal(node_prof_move(&p, 100.0, &lim), LSM_OK);
    for (int i = 0; i < 300; i++)
        node_prof_step(&p);
    const double v_at = p.k.v_mm_s;
    assert_true(v_at > 10);
    node_stop_limits sl = {800, 2e4, 2e6};
    assert_int_equal(node_prof_stop(&p, &sl, 3), LSM_OK);
    double pj = p.k.j_mm_s3;
    while (!node_prof_at_rest(&p)) {
        node_prof_step(&p);
        assert_true(fabs(p.k.j_mm_s3) <= 2e4 * (1 + 1e-9));
        assert_true(fabs(p.k.j_mm_s3 - pj) <= 2e6 * 0.001 * (1 + 1e-6) + 1e-6);
        pj = p.k.j_mm_s3;
    }
    assert_true(p.k.s_mm < 100.0 && p.k.v_mm_s == 0);
    /* retarget while cruising: continues without stopping (the velocity never drops to 0 before the end) */
    node_prof_init(&p, 0.001, 0.0);
    assert_int_equal(node_prof_move(&p, 100.0, &lim), LSM_OK);
    for (int i = 0; i < 500; i++)
        node_prof_step(&p);
    assert_true(fabs(p.k.a_mm_s2) < 1e-6 && fabs(p.k.v_mm_s - 50) < 1e-6);
    assert_int_equal(node_prof_move(&p, 60.0, &lim), LSM_OK);
    assert_int_equal(p.mode, NODE_PROF_MOVE);
    double vmin = 1e9;
    while (!node_prof_at_rest(&p)) {
        node_prof_step(&p);
        if (!node_prof_at_rest(&p))
            vmin = fmin(vmin, p.k.v_mm_s);
    }
    assert_true(p.k.s_mm == 60.0 && vmin > 0);
    /* retarget backwards while moving: stop first, then go */
    node_prof_init(&p, 0.001, 0.0);
    assert_int_equal(node_prof_move(&p, 100.0, &lim), LSM_OK);
    for (int i = 0; i < 200; i++)
        node_prof_step(&p);
    assert_int_equal(node_prof_move(&p, -5.0, &lim), LSM_OK);
    assert_int_equal(p.mode, NODE_PROF_STOP);
    n = 0;
    while (!node_prof_at_rest(&p) && n < 100000) {
        node_prof_step(&p);
        assert_true(fabs(p.k.a_mm_s2) <= 500 * (1 + 1e-9));
        n++;
    }
    assert_true(p.k.s_mm == -5.0);
}

int main(int argc, char **argv)
{
    g_seed = (unsigned)test_arg_u(argc, argv, 1, g_seed);
    g_count = (unsigned)test_arg_u(argc, argv, 2, g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_jerk_limit), cmocka_unit_test(test_decel_plateau),
        cmocka_unit_test(test_at_rest), cmocka_unit_test(test_random_states),
        cmocka_unit_test(test_prof_move_and_stop),
    };
    return test_seed_finish(argv[0], g_seed, g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
