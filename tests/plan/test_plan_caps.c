/*
 * test_plan_caps.c: the one-pass placement of an accelerating ramp past the caps ahead (plan_ramp.c,
 * lsm_pl_accel_past_caps) against the ramp's full verification (lsm_pl_ramp_verify, the full walk). Built twice
 * (double, float).
 *
 *   test_plan_caps [seed] [count]      (default: seed 1, count 1000 programs)
 *
 * The placement bounds the ramp's start from below, block by block: a block whose cap c is below the ramp's end
 * speed is exceeded, as the verification tests it (each part of each phase at its higher end speed against every
 * block the part overlaps), by the parts from the first one above c on, so the ramp passes it exactly when that
 * part starts at or after the block's end. For random accelerating ramps (speeds up to above the caps, limits from
 * well below to well above the budgets at rest) from random points of random programs, the test requires:
 *   - soundness: at the start the placement returns, the full verification finds no speed above a cap;
 *   - tightness: where it moved the start, the full verification finds one a little before it (the placement is
 *     the earliest start, up to the nudge that covers the rounding of the positions);
 *   - a refusal only where a cap below the start speed lies ahead of the start, the ramp would end past the
 *     stretch, or it starts from rest (no lead cruise) and the verification finds a cap exceeded at its start.
 * It counts the cases, and requires some of each kind (placed at once, moved, refused): it must be able to fail
 * (a placement that bounds by the end of the first part above the cap instead of its start fails soundness; one that
 * stops at the first block it moves for fails soundness too).
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
    long ramps, at_once, moved, moves_blocks, refused, tight_checked;
} tally;

static lsm_status append_line(lsm_planner *pl, double p[3], const double d[3], double len, const lsm_planner_move *mv)
{
    lsm_real e[LSM_MAX_AXES] = {0};
    for (int i = 0; i < 3; i++)
        e[i] = (lsm_real)(p[i] + len * d[i]);
    const lsm_status s = lsm_planner_append_line(pl, e, mv);
    if (s == LSM_OK)
        for (int i = 0; i < 3; i++)
            p[i] = (double)e[i];
    return s;
}

/* One random line, arc or short dense polyline (0.1-0.5 mm chords of a curve) from p (updated to its end), at a
 * random feed (the feeds make the caps vary from block to block). */
static void append_one(lsm_planner *pl, uint64_t *st, double p[3])
{
    const lsm_planner_move mv = {(lsm_real)test_logu(st, 5, 300), (lsm_real)test_logu(st, 2e-3, 0.1), 0, 0};
    const double u = test_urand(st);
    if (u < 0.3) {
        (void)test_append_random_arc(pl, st, p, 0.1, 30, 4.0, &mv); /* (refused when it does not fit) */
        return;
    }
    double h = test_uni(st, 0, 6.283185307179586);
    if (u < 0.65) {
        const double d[3] = {cos(h), sin(h), test_urand(st) < 0.5 ? 0.0 : test_uni(st, -0.5, 0.5)};
        const double n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double dn[3] = {d[0] / n, d[1] / n, d[2] / n};
        (void)append_line(pl, p, dn, test_logu(st, 0.05, 20), &mv);
        return;
    }
    const double turn = test_uni(st, -0.08, 0.08);
    for (int k = 0; k < 8; k++) {
        h += turn;
        const double d[3] = {cos(h), sin(h), 0};
        (void)append_line(pl, p, d, test_uni(st, 0.1, 0.5), &mv);
    }
}

/* Is there a block over [xa, xb) (from the one that contains xa) whose cap is below v (with the verification's
 * slack)? */
static bool cap_below_in(pctx *pc, lsm_real xa, lsm_real xb, lsm_real v)
{
    lsm_pl_seek(pc, xa);
    uint32_t id = pc->cid;
    lsm_real x = pc->cx;
    for (;;) {
        if (cap_floor(pc->pl, id, blk(pc->pl, id), pc->floor) < v)
            return true;
        x += blk(pc->pl, id)->g.len;
        if (!(x < xb) || ++id == pc->id_end)
            return false;
    }
}

static void one_ramp(const pctx *pc0, const ramp *r, lsm_real X0, long prog, long k, tally *t)
{
    pctx pc = *pc0;
    lsm_real xs = X0;
    t->ramps++;
    if (!lsm_pl_accel_past_caps(&pc, r, X0, pc.D, &xs)) {
        t->refused++;
        /* a refusal: a cap below v0 ahead (from X0 to the end of the stretch), or the ramp runs past the stretch */
        pctx q = *pc0;
        if (!(r->v0 > R0)) { /* from rest: only where it cannot start at X0 */
            lsm_pl_verdict f;
            lsm_pl_ramp_verify(&q, r, X0, false, &f);
            if (!f.vviol)
                fail_msg("program %ld ramp %ld: from rest, refused at %.9g where every cap holds", prog, k,
                         (double)X0);
            return;
        }
        if (!cap_below_in(&q, X0, pc.D, r->v0 * (R1 - CAP_SLACK)) && !(xs + r->dist > pc.D))
            fail_msg("program %ld ramp %ld: refused at %.9g (v0 %.9g v1 %.9g, length %.9g of %.9g) with no cap below "
                     "v0 ahead",
                     prog, k, (double)X0, (double)r->v0, (double)r->v1, (double)r->dist, (double)pc.D);
        return;
    }
    if (xs < X0)
        fail_msg("program %ld ramp %ld: moved back from %.17g to %.17g", prog, k, (double)X0, (double)xs);
    if (xs + r->dist > pc.D)
        return; /* (runs past the stretch: the fitting refuses it on its length) */
    pctx q = *pc0;
    lsm_pl_verdict f;
    lsm_pl_ramp_verify(&q, r, xs, false, &f);
    if (f.vviol)
        fail_msg("program %ld ramp %ld: placed at %.17g (from %.17g), the verification finds %.9g mm/s above the cap "
                 "%.9g of [%.9g, %.9g]",
                 prog, k, (double)xs, (double)X0, (double)r->v1, (double)f.vcap, (double)f.vx0, (double)f.vx1);
    if (!(xs > X0)) {
        t->at_once++;
        return;
    }
    t->moved++;
    /* the earliest: a little before (beyond the nudge) the verification finds a speed above a cap */
#if LSM_REAL_IS_FLOAT
    const lsm_real delta = LSM_R(2e-4) * (R1 + pc.D);
#else
    const lsm_real delta = LSM_R(1e-9) * (R1 + pc.D);
#endif
    if (xs - delta < X0)
        return;
    t->tight_checked++;
    pctx e = *pc0;
    lsm_pl_ramp_verify(&e, r, xs - delta, false, &f);
    if (!f.vviol)
        fail_msg("program %ld ramp %ld: placed at %.17g (from %.17g), but %.3g earlier passes every cap", prog, k,
                 (double)xs, (double)X0, (double)delta);
}

/* Random accelerating ramps on the program in pl: from a random block, v0 up to its cap (a fifth from rest), v1 0.3
 * to 1.1 x its cap or (half of them) the highest cap, limits 0.1-4 x the budgets at rest there, from random points of the stretch. */
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
            append_one(&pl, &st, p);
        assert_int_equal(lsm_planner_flush(&pl), LSM_OK);
        ramps_on(&pl, &st, prog, &t);
    }
    print_message("ramps %ld: placed at once %ld, moved %ld (tightness checked on %ld), refused %ld\n", t.ramps,
                  t.at_once, t.moved, t.tight_checked, t.refused);
    assert_true(t.at_once * 10 > t.ramps);
    assert_true(t.moved * 80 > t.ramps);
    assert_true(t.tight_checked * 80 > t.ramps);
    assert_true(t.refused * 10 > t.ramps);
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
