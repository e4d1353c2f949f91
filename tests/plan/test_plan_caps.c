/*
 * test_plan_caps.c: the one-pass placement of an accelerating ramp past the caps ahead (plan_ramp.c,
 * lsm_pl_accel_past_caps) against the ramp's full verification (lsm_pl_ramp_verify, the full walk). Built twice
 * (double, float).
 *
 *   test_plan_caps [seed] [count]      (default: seed 1, count 1000 programs)
 *
 * The placement moves the ramp's start past every block whose cap the ramp would exceed there, as the verification
 * tests the caps (each part of each phase at its higher end speed against every block the part overlaps), in one pass
 * over the blocks. For random accelerating ramps (speeds up to above the caps, limits from well below to well above
 * the budgets at rest) from random points of random programs, it must equal the reference built from the full
 * verification alone (ref_place: verify, start after the first block it exceeds, again until none), up to the
 * rounding of the block ends: the same start, or the same refusal (a cap below the start speed, from rest, past the
 * end of the stretch); and at its start the full verification finds no speed above a cap (but for a block end that
 * the verification's cursor rounds the other way: rare, counted, and the fitting then moves the ramp past it).
 * It counts the cases, and requires some of each kind (placed at once, moved, refused): it must be able to fail
 * (a placement at the earliest start, the block's end less where the ramp exceeds its cap, fails it; so does one that
 * stops after the first block it moves for, or that takes each part's lower end speed).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "lsm_test_rng.h"
#include "planner.h"
#include "planner_int.h"
#include "lsm_test_path.h"

#define CAP 96
#define RAMPS_PER_PROGRAM 120

static unsigned long g_seed = 1;
static long g_count = 1000;

typedef struct tally {
    long ramps, at_once, moved, refused, rounding;
} tally;


/* The reference placement, from the full verification alone: from X0, verify; after a speed above a cap, start at
 * the end of that block (the first one it exceeds), and again, until none. 1 (the start in *xs), or a refusal: -1 a
 * cap below v0, -2 from rest (no lead cruise), -3 past the end of the stretch, -4 no progress (rounding). */
static int ref_place(const pctx *pc0, const ramp *r, lsm_real X0, lsm_real *xs)
{
    lsm_real x = X0;
    for (int it = 0; it < 100000; it++) {
        pctx q = *pc0;
        lsm_pl_verdict f;
        lsm_pl_ramp_verify(&q, r, x, false, &f);
        if (!f.vviol) {
            *xs = x;
            return 1;
        }
        if (f.vcap < r->v0 * (R1 - CAP_SLACK))
            return -1;
        if (!(r->v0 > R0))
            return -2;
        if (!(f.vx1 > x))
            return -4;
        x = f.vx1;
        if (x + r->dist > pc0->D + LEN_EPS * (R1 + pc0->D))
            return -3;
    }
    return -4;
}

/* The rounding of a block end, computed by the pass and by the verification's cursor along other paths. */
static lsm_real pos_tol(const pctx *pc)
{
    return LSM_R(256.0) * LSM_REAL_EPS * (R1 + pc->D);
}

static void one_ramp(const pctx *pc0, const ramp *r, lsm_real X0, long prog, long k, tally *t)
{
    pctx pc = *pc0;
    lsm_real xs = X0, xr = X0;
    t->ramps++;
    const bool placed = lsm_pl_accel_past_caps(&pc, r, X0, pc.D, &xs);
    const int ref = ref_place(pc0, r, X0, &xr);
    if (!placed) {
        t->refused++;
        if (ref == 1 && !(xr + r->dist > pc.D))
            fail_msg("program %ld ramp %ld: refused at %.9g (v0 %.9g v1 %.9g, length %.9g of %.9g), the reference "
                     "places it at %.9g",
                     prog, k, (double)X0, (double)r->v0, (double)r->v1, (double)r->dist, (double)pc.D, (double)xr);
        return;
    }
    if (xs < X0)
        fail_msg("program %ld ramp %ld: moved back from %.17g to %.17g", prog, k, (double)X0, (double)xs);
    if (xs + r->dist > pc.D)
        return; /* (runs past the stretch: the fitting refuses it on its length) */
    if (ref != 1 || lsm_fabs(xs - xr) > pos_tol(pc0))
        fail_msg("program %ld ramp %ld: placed at %.17g (from %.17g), the reference %s %.17g", prog, k, (double)xs,
                 (double)X0, ref == 1 ? "at" : "refuses it, code", ref == 1 ? (double)xr : (double)ref);
    pctx q = *pc0;
    lsm_pl_verdict f;
    lsm_pl_ramp_verify(&q, r, xs, false, &f);
    if (f.vviol) {
        /* only by the rounding of that block's end: the verification's own end of it is the start */
        t->rounding++;
        if (!(lsm_fabs(f.vx1 - xs) <= pos_tol(pc0)))
            fail_msg("program %ld ramp %ld: placed at %.17g (from %.17g), the verification finds %.9g mm/s above the "
                     "cap %.9g of [%.9g, %.9g]",
                     prog, k, (double)xs, (double)X0, (double)r->v1, (double)f.vcap, (double)f.vx0, (double)f.vx1);
    }
    if (xs > X0)
        t->moved++;
    else
        t->at_once++;
}

/* Random accelerating ramps on the program in pl: from a random block, v0 up to its cap (a fifth from rest), v1 0.3
 * to 1.1 x its cap or (half of them) the highest cap, limits 0.1-4 x the budgets at rest there, from random points
 * of its first half (30 % at its start). */
static void ramps_on(lsm_planner *pl, uint64_t *st, long prog, tally *t)
{
    const uint32_t n = lsm_planner_count(pl);
    lsm_real vmax = 0;
    for (uint32_t id = pl->head; id != pl->tail; id++)
        vmax = lsm_max2(vmax, cap_of(pl, id));
    if (n == 0 || !(vmax > 0))
        return;
    const lsm_real dt = pl->cfg.cycle_s;
    for (long k = 0; k < RAMPS_PER_PROGRAM; k++) {
        const uint32_t id0 = pl->head + (uint32_t)(test_urand(st) * n) % n;
        pctx pc;
        lsm_pl_pctx_init(&pc, pl, id0, 0, pl->tail);
        lsm_real a, j, s;
        lsm_pl_guess_limits(&pc, 0, &a, &j, &s);
        const lsm_real v0 = (lsm_real)(test_urand(st) < 0.2 ? 0.0 : test_uni(st, 0, 1.0) * (double)cap_of(pl, id0));
        const double vtop = test_urand(st) < 0.5 ? (double)cap_of(pl, id0) : (double)vmax;
        const lsm_real v1 = (lsm_real)(test_uni(st, 0.3, 1.1) * vtop);
        if (!(v1 > v0))
            continue;
        ramp r;
        if (!lsm_pl_ramp_plan(&r, dt, v0, v1, a * (lsm_real)test_logu(st, 0.1, 4), j * (lsm_real)test_logu(st, 0.1, 4),
                              s * (lsm_real)test_logu(st, 0.1, 4)))
            continue;
        const lsm_real X0 = (lsm_real)(test_urand(st) < 0.3 ? 0.0 : test_urand(st) * 0.5 * (double)pc.D);
        one_ramp(&pc, &r, X0, prog, k, t);
    }
}

static void test_accel_past_caps(void **state)
{
    (void)state;
    tally t;
    memset(&t, 0, sizeof t);
    static lsm_pblock store[CAP];
    static lsm_planner pl;
    for (long prog = 0; prog < g_count; prog++) {
        uint64_t st;
        assert_int_equal(test_random_planner(&pl, store, CAP, &st, g_seed, prog, 11u, 0.004), LSM_OK);
        double p[3] = {0, 0, 0};
        for (int m = 0; m < 24 && lsm_planner_free(&pl) > 24; m++)
            test_append_random_item(&pl, &st, p);
        assert_int_equal(lsm_planner_flush(&pl), LSM_OK);
        ramps_on(&pl, &st, prog, &t);
    }
    print_message("ramps %ld: placed at once %ld, moved %ld, refused %ld; a block end found past it by rounding %ld\n",
                  t.ramps, t.at_once, t.moved, t.refused, t.rounding);
    assert_true(t.at_once * 10 > t.ramps);
    assert_true(t.moved * 80 > t.ramps);
    assert_true(t.refused * 10 > t.ramps);
    assert_true(t.rounding * 1000 < t.moved + 1);
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, 1);
    g_count = (long)test_arg_u(argc, argv, 2, 1000);
    print_message("seed %lu, count %ld\n", g_seed, g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_accel_past_caps),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
