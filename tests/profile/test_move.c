/*
 * test_move.c: regression cases of lsm_move_plan (move.h) found by the soak (docs/reliability.md).
 *
 * Moves that were refused (LSM_E_INFEASIBLE) although a whole-cycle profile exists: D exceeds the direct
 * ramp v0 -> v1 by less than a shortest quantised ramp travels at the far feed, so neither a peak above
 * max(v0, v1) nor the coarse grid of cruise feeds fits; the exact shapes linger at a cruise feed close to an
 * end feed. Each must plan, keep every limit (analytic peaks of both ramps, the cruise under v_max), end
 * exactly on D with feed v1, and take no more cycles than an independent witness shape found by brute force.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "move.h"

#define REL_TOL (LSM_REAL_IS_FLOAT ? 2e-5 : 1e-9)
#define PI 3.14159265358979323846

typedef struct refused_case {
    double D, v0, v1, vmax, amax, jmax, snap, cycle;
    uint32_t witness_cycles; /* an exact whole-cycle shape within the limits that brute force found */
} refused_case;

static const refused_case CASES[] = {
    /* seed 1000 case 3854 of test_scurve_props (double) */
    {-249.34908966238203, 0, 674.78420807018404, 681.70101749344451, 10298.425470397606, 5004.3327426267615,
     8293597.4776195027, 0.0005, 1663},
    /* seed 1001 case 17123 */
    {-0.22738947365912424, 3.3216866485971086, 6.2196181694227013, 7.5313261694312867, 85.083428289161873,
     153954.73983474151, 14238792.994125878, 0.002, 25},
};

static void check_ramp(const lsm_scurve_intervals *iv, double jp, const lsm_axis_limits *L, double dt)
{
    if (iv->n1_cycles == 0) {
        assert_true(jp == 0);
        return;
    }
    const double t1 = iv->n1_cycles * dt, t2 = iv->n2_cycles * dt;
    assert_true(fabs(jp) <= L->j_max_mm_s3 * (1 + REL_TOL));
    assert_true(fabs(jp) * (t1 + t2) <= L->a_max_mm_s2 * (1 + REL_TOL));
    assert_true(fabs(jp) * PI / (2 * t1) <= L->snap_max_mm_s4 * (1 + REL_TOL));
}

static void test_refused_moves_now_plan(void **state)
{
    (void)state;
    for (unsigned c = 0; c < sizeof CASES / sizeof CASES[0]; c++) {
        const refused_case *k = &CASES[c];
        lsm_move_request r = {0};
        r.n_axes = 1;
        r.cycle_s = (lsm_real)k->cycle;
        r.rule = LSM_SCURVE_RULE_STRICT;
        r.distance_mm[0] = (lsm_real)k->D;
        r.v0_mm_s[0] = (lsm_real)k->v0;
        r.v1_mm_s[0] = (lsm_real)k->v1;
        r.lim[0] = (lsm_axis_limits){(lsm_real)k->vmax, (lsm_real)k->amax, (lsm_real)k->jmax, (lsm_real)k->snap};
        lsm_move mv;
        assert_int_equal(lsm_move_plan(&mv, &r), LSM_OK);
        const lsm_move_axis *ax = &mv.axis[0];
        check_ramp(&mv.acc, (double)ax->jp_acc_mm_s3, &r.lim[0], k->cycle);
        check_ramp(&mv.dec, (double)ax->jp_dec_mm_s3, &r.lim[0], k->cycle);
        assert_true(ax->vc_mm_s > 0 && ax->vc_mm_s <= r.lim[0].v_max_mm_s);
        assert_true(lsm_move_total_cycles(&mv) <= k->witness_cycles);
        assert_true(fabs((double)lsm_move_end_error_mm(&mv, 0)) <=
                    (LSM_REAL_IS_FLOAT ? 1e-5 : 1e-9) * (fabs(k->D) + 1));
        /* every sampled state within the limits; the terminal state exact */
        const uint32_t n = lsm_move_total_cycles(&mv);
        for (uint32_t i = 0; i < n; i++) {
            for (int q = 0; q < 4; q++) {
                lsm_kin kin;
                lsm_move_eval_cycle(&mv, 0, i, (lsm_real)(q / 4.0), &kin);
                assert_true(fabs((double)kin.v_mm_s) <= k->vmax * (1 + REL_TOL));
                assert_true(fabs((double)kin.a_mm_s2) <= k->amax * (1 + REL_TOL));
                assert_true(fabs((double)kin.j_mm_s3) <= k->jmax * (1 + REL_TOL));
            }
        }
        lsm_kin e;
        lsm_move_eval_cycle(&mv, 0, n, 0, &e);
        assert_true(e.s_mm == r.distance_mm[0] && e.v_mm_s == -r.v1_mm_s[0] && e.a_mm_s2 == 0 && e.j_mm_s3 == 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_refused_moves_now_plan),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
