/*
 * test_scurve.c: the sin² velocity change (firmware/profile/scurve.h).
 *  - Kombarov Table 1 with rule `paper`: every printed value within ±0.001 (Test 4's first J_P is printed 6.685,
 *    a typo: the algorithm and the paper's own dt2A = 0.136 give 9.626, which is what we check).
 *  - rule `strict`: no limit exceeded after correction, and no shorter whole-cycle profile exists (brute force).
 *  - boundary conditions, closed form against numeric integration of the jerk, deceleration symmetry,
 *    and every bad input with its error code.
 * Tolerances: double checks to 1e-9 relative; the float build to 2e-5 relative (24-bit mantissa).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "scurve.h"

#define REL_TOL (LSM_REAL_IS_FLOAT ? 2e-5 : 1e-9)
#define DT 0.001

typedef struct {
    double dF, A, J, DJ;
    double dt1j, dt1a, dt1f, dt1, jp0, dt2a, dt2f, dt2, ap, dt4f, dt4, tp, jp;
} table1_row;

/* Kombarov 2019, Table 1 (units m, s). Test 4's jp0 is 9.626 (printed 6.685: typo). */
static const table1_row k_table1[5] = {
    {0.22, 1.57, 16, 25132, 0.001, 0.009, 0.019, 0.001, 16.000, 0.097, 0.116, 0.097, 1.568, 0.041, 0.041, 0.239,
     16.035},
    {0.22, 1.57, 16, 560, 0.044, 0.066, 0.067, 0.044, 15.686, 0.056, 0.054, 0.054, 1.537, 0.001, 0.001, 0.285, 15.699},
    {0.08, 1.57, 16, 560, 0.044, 0.066, 0.048, 0.044, 15.686, 0.056, 0.009, 0.009, 0.831, -0.001, 0, 0.194, 15.561},
    {0.015, 1.57, 16, 560, 0.044, 0.066, 0.027, 0.027, 9.626, 0.136, 0.001, 0.001, 0.270, 0.001, 0.001, 0.111, 9.566},
    {0.15, 1.05, 24, 500, 0.075, 0.057, 0.061, 0.057, 18.144, 0, 0.01, 0, 1.034, 0.031, 0.031, 0.259, 18.149},
};

static void close3(double got, double want, const char *what, int test)
{
    if (fabs(got - want) > 0.001 + 1e-12) {
        print_error("Test %d %s: got %.6f, paper %.3f\n", test + 1, what, got, want);
        fail();
    }
}

static void test_table1_paper_rule(void **state)
{
    (void)state;
    for (int i = 0; i < 5; i++) {
        const table1_row *r = &k_table1[i];
        lsm_scurve_limits lim = {(lsm_real)r->A, (lsm_real)r->J, (lsm_real)r->DJ};
        lsm_scurve sc;
        lsm_scurve_info inf;
        assert_int_equal(lsm_scurve_plan(&sc, &lim, (lsm_real)DT, 0, (lsm_real)r->dF, LSM_SCURVE_RULE_PAPER, &inf),
                         LSM_OK);
        close3(inf.dt1j_s, r->dt1j, "dt1J", i);
        close3(inf.dt1a_s, r->dt1a, "dt1A", i);
        close3(inf.dt1f_s, r->dt1f, "dt1F", i);
        close3(sc.iv.n1_cycles * DT, r->dt1, "dt1", i);
        close3(inf.jp_initial_mm_s3, r->jp0, "J_P initial", i);
        close3(inf.dt2a_s, r->dt2a, "dt2A", i);
        close3(inf.dt2f_s, r->dt2f, "dt2F", i);
        close3(sc.iv.n2_cycles * DT, r->dt2, "dt2", i);
        close3(inf.ap_mm_s2, r->ap, "A_P", i);
        close3(inf.dt4f_s, r->dt4f, "dt4F", i);
        close3(sc.iv.n4_cycles * DT, r->dt4, "dt4", i);
        close3(lsm_scurve_duration_s(&sc), r->tp, "tp", i);
        close3(sc.jp_mm_s3, r->jp, "J_P corrected", i);
        /* the corrected jerk makes the velocity change exact (eq 34) */
        lsm_kin k;
        lsm_scurve_eval(&sc, lsm_scurve_duration_s(&sc), &k);
        assert_true(fabs(k.v_mm_s - r->dF) <= REL_TOL * r->dF);
    }
}

/* The paper's rule exceeds its own limits after correction (NOTES.md); strict must not. */
static void test_table1_paper_exceeds_strict_does_not(void **state)
{
    (void)state;
    const table1_row *r = &k_table1[0];
    lsm_scurve_limits lim = {(lsm_real)r->A, (lsm_real)r->J, (lsm_real)r->DJ};
    lsm_scurve sc;
    lsm_scurve_info inf;
    assert_int_equal(lsm_scurve_plan(&sc, &lim, (lsm_real)DT, 0, (lsm_real)r->dF, LSM_SCURVE_RULE_PAPER, &inf), LSM_OK);
    assert_true(sc.jp_mm_s3 > lim.j_max_mm_s3); /* 16.035 > 16 */
    for (int i = 0; i < 5; i++) {
        r = &k_table1[i];
        lsm_scurve_limits l2 = {(lsm_real)r->A, (lsm_real)r->J, (lsm_real)r->DJ};
        assert_int_equal(lsm_scurve_plan(&sc, &l2, (lsm_real)DT, 0, (lsm_real)r->dF, LSM_SCURVE_RULE_STRICT, &inf),
                         LSM_OK);
        assert_true(sc.jp_mm_s3 <= l2.j_max_mm_s3);
        assert_true(inf.ap_final_mm_s2 <= l2.a_max_mm_s2);
        assert_true(inf.snap_final_mm_s4 <= l2.snap_max_mm_s4);
        lsm_kin k;
        lsm_scurve_eval(&sc, lsm_scurve_duration_s(&sc), &k);
        assert_true(fabs(k.v_mm_s - r->dF) <= REL_TOL * r->dF);
    }
}

/* No whole-cycle profile shorter than the strict one keeps the limits (brute force over a wide grid). */
static void test_strict_is_shortest(void **state)
{
    (void)state;
    uint32_t seed = 12345;
    for (int c = 0; c < (LSM_REAL_IS_FLOAT ? 40 : 200); c++) {
        seed = seed * 1664525u + 1013904223u;
        const double A = 0.5 + (seed % 1000) / 200.0;
        seed = seed * 1664525u + 1013904223u;
        const double J = 2 + (seed % 1000) / 20.0;
        seed = seed * 1664525u + 1013904223u;
        const double DJ = 100 + (seed % 10000) / 5.0;
        seed = seed * 1664525u + 1013904223u;
        const double dF = 0.001 + (seed % 1000) / 2000.0;
        const double dt = (c % 3 == 0) ? 0.004 : 0.001;
        lsm_scurve_limits lim = {(lsm_real)A, (lsm_real)J, (lsm_real)DJ};
        lsm_scurve_intervals iv;
        assert_true(lsm_scurve_strict_intervals(&lim, (lsm_real)dt, (lsm_real)dF, &iv));
        assert_true(lsm_scurve_fits(&lim, (lsm_real)dt, &iv, (lsm_real)dF));
        const uint32_t best = lsm_scurve_total_cycles(&iv);
        /* any shorter profile has 4 n1 + 2 n2 + n4 < best: enumerate all of them */
        for (uint32_t n1 = 1; 4 * n1 < best; n1++)
            for (uint32_t n2 = 0; 4 * n1 + 2 * n2 < best; n2++) {
                const uint32_t n4max = best - 1 - 4 * n1 - 2 * n2;
                lsm_scurve_intervals t = {n1, n2, n4max}; /* capacity grows with n4: the longest is enough */
                if (lsm_scurve_fits(&lim, (lsm_real)dt, &t, (lsm_real)dF)) {
                    print_error("case %d: %u+%u+%u (%u cycles) fits, strict gave %u\\n", c, n1, n2, n4max,
                                lsm_scurve_total_cycles(&t), best);
                    fail();
                }
            }
    }
}

/* Numeric integration of the jerk (composite Simpson per sub-step, fine steps) against the closed form. */
static void test_closed_form_vs_integration(void **state)
{
    (void)state;
    for (int i = 0; i < 5; i++) {
        const table1_row *r = &k_table1[i];
        lsm_scurve_limits lim = {(lsm_real)r->A, (lsm_real)r->J, (lsm_real)r->DJ};
        lsm_scurve sc;
        assert_int_equal(lsm_scurve_plan(&sc, &lim, (lsm_real)DT, (lsm_real)0.05, (lsm_real)(0.05 + r->dF),
                                         LSM_SCURVE_RULE_STRICT, NULL),
                         LSM_OK);
        const double tp = lsm_scurve_duration_s(&sc);
        /* steps aligned with the cycles, so every kink of the jerk falls on a step boundary */
        const int steps = (int)lsm_scurve_total_cycles(&sc.iv) * 64;
        const double h = tp / steps;
        double a = 0, v = 0.05, s = 0;
        for (int k = 0; k < steps; k++) {
            /* exact integration of the quadratic through j(0), j(h/2), j(h) (Lagrange weights) */
            lsm_kin k0, km, k1;
            lsm_scurve_eval(&sc, (lsm_real)(k * h), &k0);
            lsm_scurve_eval(&sc, (lsm_real)((k + 0.5) * h), &km);
            lsm_scurve_eval(&sc, (lsm_real)((k + 1) * h), &k1);
            const double j0 = k0.j_mm_s3, jm = km.j_mm_s3, j1 = k1.j_mm_s3;
            s += v * h + a * h * h / 2 + h * h * h * (3 * j0 / 40 + jm / 10 - j1 / 120);
            v += a * h + h * h * (j0 / 6 + jm / 3);
            a += h * (j0 + 4 * jm + j1) / 6;
        }
        lsm_kin e;
        lsm_scurve_eval(&sc, (lsm_real)tp, &e);
        const double tol = LSM_REAL_IS_FLOAT ? 1e-5 : 1e-9;
        assert_true(fabs(a - e.a_mm_s2) <= tol * r->A);
        assert_true(fabs(v - e.v_mm_s) <= tol * (0.05 + r->dF));
        assert_true(fabs(s - e.s_mm) <= tol * e.s_mm);
        assert_true(fabs(e.s_mm - lsm_scurve_distance_mm(&sc)) <= tol * e.s_mm);
    }
}

static void test_boundary_conditions(void **state)
{
    (void)state;
    lsm_scurve_limits lim = {1.57, 16, 560};
    const double pairs[4][2] = {{0, 0.22}, {0.22, 0}, {0.1, 0.115}, {0.3, 0.05}};
    for (int i = 0; i < 4; i++) {
        lsm_scurve sc;
        assert_int_equal(lsm_scurve_plan(&sc, &lim, (lsm_real)DT, (lsm_real)pairs[i][0], (lsm_real)pairs[i][1],
                                         LSM_SCURVE_RULE_STRICT, NULL),
                         LSM_OK);
        lsm_kin k0, k1;
        lsm_scurve_eval(&sc, 0, &k0);
        lsm_scurve_eval(&sc, lsm_scurve_duration_s(&sc), &k1);
        assert_true(fabs(k0.v_mm_s - (lsm_real)pairs[i][0]) <= 1e-12);
        assert_true(fabs(k0.a_mm_s2) <= 1e-12 && fabs(k0.j_mm_s3) <= 1e-12 && fabs(k0.s_mm) <= 1e-12);
        assert_true(fabs(k1.v_mm_s - pairs[i][1]) <= REL_TOL * 0.3);
        assert_true(fabs(k1.a_mm_s2) <= REL_TOL * 1.57);
        assert_true(fabs(k1.j_mm_s3) <= REL_TOL * 16);
        /* continuity: J, A, V, S continuous at every interval boundary */
        const uint32_t b[7] = {sc.iv.n1_cycles, sc.iv.n2_cycles, sc.iv.n1_cycles, sc.iv.n4_cycles,
                               sc.iv.n1_cycles, sc.iv.n2_cycles, sc.iv.n1_cycles};
        double t = 0;
        for (int p = 0; p < 6; p++) {
            t += b[p] * DT;
            lsm_kin lo, hi;
            lsm_scurve_eval(&sc, (lsm_real)(t - 1e-9), &lo);
            lsm_scurve_eval(&sc, (lsm_real)(t + 1e-9), &hi);
            assert_true(fabs(lo.j_mm_s3 - hi.j_mm_s3) <= (LSM_REAL_IS_FLOAT ? 1e-3 : 1e-4) * 16);
            assert_true(fabs(lo.a_mm_s2 - hi.a_mm_s2) <= 1e-5);
            assert_true(fabs(lo.v_mm_s - hi.v_mm_s) <= 1e-6);
        }
        /* distance is (F0 + F) tp / 2 */
        assert_true(fabs(k1.s_mm - lsm_scurve_distance_mm(&sc)) <= REL_TOL * (k1.s_mm + 1e-3));
    }
}

static void test_deceleration_mirrors_acceleration(void **state)
{
    (void)state;
    lsm_scurve_limits lim = {1.57, 16, 560};
    lsm_scurve up, down;
    assert_int_equal(lsm_scurve_plan(&up, &lim, (lsm_real)DT, 0, (lsm_real)0.22, LSM_SCURVE_RULE_STRICT, NULL), LSM_OK);
    assert_int_equal(lsm_scurve_plan(&down, &lim, (lsm_real)DT, (lsm_real)0.22, 0, LSM_SCURVE_RULE_STRICT, NULL),
                     LSM_OK);
    assert_int_equal(up.iv.n1_cycles, down.iv.n1_cycles);
    assert_int_equal(up.iv.n2_cycles, down.iv.n2_cycles);
    assert_int_equal(up.iv.n4_cycles, down.iv.n4_cycles);
    assert_true(fabs(up.jp_mm_s3 + down.jp_mm_s3) <= 1e-12 * 16);
    const double tp = lsm_scurve_duration_s(&up);
    for (int k = 0; k <= 20; k++) {
        lsm_kin a, b;
        lsm_scurve_eval(&up, (lsm_real)(tp * k / 20), &a);
        lsm_scurve_eval(&down, (lsm_real)(tp * k / 20), &b);
        assert_true(fabs(a.v_mm_s + b.v_mm_s - 0.22) <= REL_TOL);
    }
}

static void test_zero_change(void **state)
{
    (void)state;
    lsm_scurve_limits lim = {1, 1, 1};
    lsm_scurve sc;
    assert_int_equal(lsm_scurve_plan(&sc, &lim, (lsm_real)DT, 3, 3, LSM_SCURVE_RULE_STRICT, NULL), LSM_OK);
    assert_int_equal(lsm_scurve_total_cycles(&sc.iv), 0);
    assert_true(sc.jp_mm_s3 == 0);
}

static void test_bad_input(void **state)
{
    (void)state;
    lsm_scurve sc;
    const lsm_scurve_limits ok = {1.57, 16, 560};
    lsm_scurve_limits l = ok;
    const lsm_real nan_ = (lsm_real)NAN, inf_ = (lsm_real)INFINITY;
    assert_int_equal(lsm_scurve_plan(NULL, &ok, (lsm_real)DT, 0, 1, 0, NULL), LSM_E_NULL);
    assert_int_equal(lsm_scurve_plan(&sc, NULL, (lsm_real)DT, 0, 1, 0, NULL), LSM_E_NULL);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, (lsm_real)DT, nan_, 1, 0, NULL), LSM_E_NAN);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, (lsm_real)DT, 0, inf_, 0, NULL), LSM_E_INF);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, (lsm_real)DT, 0, -inf_, 0, NULL), LSM_E_INF);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, nan_, 0, 1, 0, NULL), LSM_E_NAN);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, 0, 0, 1, 0, NULL), LSM_E_CYCLE);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, -1, 0, 1, 0, NULL), LSM_E_CYCLE);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, (lsm_real)DT, -1, 1, 0, NULL), LSM_E_NEG_FEED);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, (lsm_real)DT, 0, -1, 0, NULL), LSM_E_NEG_FEED);
    assert_int_equal(lsm_scurve_plan(&sc, &ok, (lsm_real)DT, 0, 1, (lsm_scurve_rule)7, NULL), LSM_E_ARG);
    lsm_real *fields[3] = {&l.a_max_mm_s2, &l.j_max_mm_s3, &l.snap_max_mm_s4};
    for (int i = 0; i < 3; i++) {
        l = ok;
        *fields[i] = 0;
        assert_int_equal(lsm_scurve_plan(&sc, &l, (lsm_real)DT, 0, 1, 0, NULL), LSM_E_LIMIT);
        *fields[i] = -2;
        assert_int_equal(lsm_scurve_plan(&sc, &l, (lsm_real)DT, 0, 1, 0, NULL), LSM_E_LIMIT);
        *fields[i] = nan_;
        assert_int_equal(lsm_scurve_plan(&sc, &l, (lsm_real)DT, 0, 1, 0, NULL), LSM_E_NAN);
        *fields[i] = inf_;
        assert_int_equal(lsm_scurve_plan(&sc, &l, (lsm_real)DT, 0, 1, 0, NULL), LSM_E_INF);
    }
    /* a change that would need more cycles than the counter holds */
    l = ok;
    l.a_max_mm_s2 = (lsm_real)1e-9;
    assert_int_equal(lsm_scurve_plan(&sc, &l, (lsm_real)1e-6, 0, (lsm_real)1e6, 0, NULL), LSM_E_TOO_LONG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table1_paper_rule),   cmocka_unit_test(test_table1_paper_exceeds_strict_does_not),
        cmocka_unit_test(test_strict_is_shortest),  cmocka_unit_test(test_closed_form_vs_integration),
        cmocka_unit_test(test_boundary_conditions), cmocka_unit_test(test_deceleration_mirrors_acceleration),
        cmocka_unit_test(test_zero_change),         cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
