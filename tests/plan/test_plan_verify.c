/*
 * test_plan_verify.c: the shortcuts of a ramp's verification (plan_ramp.c, ramp_check) leave what the ramp fitting
 * uses exactly as the full walk has it. Built twice (double, float).
 *
 *   test_plan_verify [seed] [count]      (default: seed 1, count 2000 programs)
 *
 * The full walk checks every phase of the ramp as a whole and, where the whole fails, in parts (eighths): the
 * budgets and the caps of every block each part crosses. The shortcuts: a phase whose whole exceeds a cap has its
 * parts' speeds tested before their budgets; once the ramp fails, a phase whose whole's ratios cover those found so
 * far (capped at 1, parts_covered) has only its parts' speeds tested. What the fitting uses, and this test compares
 * bit for bit: the verdict; whether a speed exceeds a cap and that block's extent and cap; the ratios of a passing
 * ramp (its tune-up takes them); the ratios of a failing one, capped at 1 (its rescale takes those below 1); and the
 * state of the position cursor after the walk (its rounding depends on its path: later positions start from it).
 *
 * Each program is a random machine (unequal X Y Z limits, path limits on some) and random lines (corners blended:
 * clothoid pairs), arcs (G17/18/19, some helical) and dense polylines; on it, random ramps (speeds up to above the
 * caps, limits from well below to well above the budgets at rest) placed at random points. The test also counts
 * the cases each shortcut decides, and requires some of each: it must be able to fail.
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
#define RAMPS_PER_PROGRAM 160

static unsigned long g_seed = 1;
static long g_count = 2000;

typedef struct tally {
    long ramps, ok, fail, vviol, fail_both; /* fail_both: failing on a and on j */
} tally;


static double fmin1(lsm_real r)
{
    return r < (lsm_real)1 ? (double)r : 1.0;
}

/* The shortcut walk against the full one on ramp r at x_s, both from the cursor of pc. */
static void compare(const pctx *pc, const ramp *r, lsm_real x_s, long prog, long k, tally *t)
{
    lsm_pl_verdict q, f;
    pctx pq = *pc, pf = *pc;
    lsm_pl_ramp_verify(&pf, r, x_s, false, &f);
    lsm_pl_ramp_verify(&pq, r, x_s, true, &q);
    t->ramps++;
    if (q.ok != f.ok || q.vviol != f.vviol)
        fail_msg("program %ld ramp %ld: verdict %d (above a cap %d), full walk %d (%d)", prog, k, q.ok, q.vviol, f.ok,
                 f.vviol);
    if (pq.cid != pf.cid || pq.cx != pf.cx)
        fail_msg("program %ld ramp %ld: cursor at block %u, x %.17g; full walk %u, %.17g", prog, k, (unsigned)pq.cid,
                 (double)pq.cx, (unsigned)pf.cid, (double)pf.cx);
    if (f.vviol) {
        t->vviol++;
        if (q.vx0 != f.vx0 || q.vx1 != f.vx1 || q.vcap != f.vcap)
            fail_msg("program %ld ramp %ld: cap record [%.17g %.17g] %.17g, full walk [%.17g %.17g] %.17g", prog, k,
                     (double)q.vx0, (double)q.vx1, (double)q.vcap, (double)f.vx0, (double)f.vx1, (double)f.vcap);
    } else if (f.ok) {
        t->ok++;
        if (q.ra != f.ra || q.rj != f.rj || q.rs != f.rs)
            fail_msg("program %ld ramp %ld: passing ratios %.17g %.17g %.17g, full walk %.17g %.17g %.17g", prog, k,
                     (double)q.ra, (double)q.rj, (double)q.rs, (double)f.ra, (double)f.rj, (double)f.rs);
    } else {
        t->fail++;
        if (fmin1(q.ra) != fmin1(f.ra) || fmin1(q.rj) != fmin1(f.rj) || fmin1(q.rs) != fmin1(f.rs))
            fail_msg("program %ld ramp %ld: failing ratios %.17g %.17g %.17g, full walk %.17g %.17g %.17g", prog, k,
                     fmin1(q.ra), fmin1(q.rj), fmin1(q.rs), fmin1(f.ra), fmin1(f.rj), fmin1(f.rs));
        if (fmin1(f.ra) < 1.0 && fmin1(f.rj) < 1.0)
            t->fail_both++;
    }
}

/* Random ramps on the program in pl: from a random block, speeds up to 1.1 x its cap (a quarter: the highest cap),
 * limits 0.1-4 x the budgets at rest there, at random points of the piece (some running past its end). */
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
        const lsm_real vtop = test_urand(st) < 0.25 ? vmax : cap_of(pl, id0); /* (mostly the caps where it starts) */
        const lsm_real v0 = (lsm_real)(test_urand(st) < 0.2 ? 0.0 : test_uni(st, 0, 1.1) * vtop);
        const lsm_real v1 = (lsm_real)(test_uni(st, 0, 1.1) * vtop);
        ramp r;
        if (!lsm_pl_ramp_plan(&r, dt, v0, v1, a * (lsm_real)test_logu(st, 0.1, 4), j * (lsm_real)test_logu(st, 0.1, 4),
                              s * (lsm_real)test_logu(st, 0.1, 4)))
            continue;
        const lsm_real x_s = (lsm_real)(test_urand(st) * (double)pc.D);
        compare(&pc, &r, x_s, prog, k, t);
    }
}

static void test_shortcuts_exact(void **state)
{
    (void)state;
    tally t;
    memset(&t, 0, sizeof t);
    static lsm_pblock store[CAP];
    static lsm_planner pl;
    for (long prog = 0; prog < g_count; prog++) {
        uint64_t st;
        assert_int_equal(test_random_planner(&pl, store, CAP, &st, g_seed, prog, 7u, 0.004), LSM_OK);
        double p[3] = {0, 0, 0};
        for (int m = 0; m < 24 && lsm_planner_free(&pl) > 24; m++)
            test_append_random_item(&pl, &st, p);
        assert_int_equal(lsm_planner_flush(&pl), LSM_OK);
        ramps_on(&pl, &st, prog, &t);
    }
    print_message("ramps %ld: pass %ld, fail on the budgets %ld (on a and j %ld), above a cap %ld\n", t.ramps, t.ok,
                  t.fail, t.fail_both, t.vviol);
    /* every kind of outcome was exercised (each shortcut decides one of them) */
    assert_true(t.fail_both * 100 > t.ramps);
    assert_true(t.ok * 20 > t.ramps);
    assert_true(t.fail * 20 > t.ramps);
    assert_true(t.vviol * 20 > t.ramps);
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, 1);
    g_count = (long)test_arg_u(argc, argv, 2, 2000);
    print_message("seed %lu, count %ld\n", g_seed, g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shortcuts_exact),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
