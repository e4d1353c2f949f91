/*
 * test_plan_memo.c: the piece memo (plan_piece.c, "The piece memo") changes no piece and no setpoint. Built twice
 * (double, float).
 *
 *   test_plan_memo [seed] [count]      (default: seed 1, count 200 programs)
 *
 * Each program is a random machine (unequal X Y Z limits, path limits on some, lsm_test_path.h), a look-ahead of 16
 * to 128 blocks, and random lines (corners blended), arcs and dense polylines appended while the interpolator runs
 * (whenever a few slots are free, as the M4 benchmark does, or in bursts), with override changes, a feed hold and
 * its resume, and cycles without lsm_interp_prepare (the step plans then) at random. It runs twice, with the memo and
 * without (lsm_planner_memo.off), and every setpoint (its bits), every piece taken and every piece planned into the
 * interpolator's second buffer (their bytes), and the counters of the planner (but the verifications, which the memo
 * saves) and of the interpolator must be the same. The memo must have answered some of the calls (it must be able to
 * fail). Measured (seed 1, 200 programs, both builds): it fails with the backward pass's lsm_pl_changed (bp_stop + 1)
 * left out, with no change invalidating the memo, and with the start speed left out of the key. Some invalidations
 * are not singled out by it: a push's (the backward pass after it covers it), the full pass's and the override's
 * (each covers the other), and the trim of the last block's and the node after the farthest candidate in the reach
 * (left out, the memo answered a few more calls here, with the same pieces: kept by the argument, not by this test).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "lsm_test_rng.h"
#include "interp.h"
#include "planner.h"
#include "lsm_test_path.h"

#define MAX_CAP 128
#define MAX_CYCLES 400000L

static unsigned long g_seed = 1;
static long g_count = 200;

typedef struct outcome {
    uint64_t h;          /* hash of every setpoint and piece, in order */
    long cycles, pieces; /* cycles run, pieces planned */
    uint32_t kept;       /* pieces the memo answered */
} outcome;

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const uint8_t *b = p;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= 1099511628211ull;
    }
    return h;
}

/* Program `prog`, with the memo or without. */
static void run(long prog, bool memo, outcome *out)
{
    static lsm_pblock store[MAX_CAP];
    static lsm_planner pl;
    static lsm_interp ip;
    uint64_t st;
    const uint32_t caps[4] = {16, 32, 64, 128};
    uint64_t pick = (uint64_t)g_seed * 0x2545F4914F6CDD1Dull + (uint64_t)prog + 1u;
    const uint32_t cap = caps[(uint32_t)(test_urand(&pick) * 4.0) % 4u];
    assert_int_equal(test_random_planner(&pl, store, cap, &st, g_seed, prog, 31u, 0.004), LSM_OK);
    assert_int_equal(lsm_interp_init(&ip, &pl), LSM_OK);
    pl.memo.off = memo ? 0u : 1u;
    const int n_items = 20 + (int)(test_urand(&st) * 60.0);
    const bool bursts = test_urand(&st) < 0.3; /* append until full, else one item when 12 slots are free */
    const double p_ovr = test_urand(&st) < 0.5 ? 0.002 : 0.0, p_noprep = test_urand(&st) < 0.3 ? 0.05 : 0.0;
    const long hold_at = test_urand(&st) < 0.3 ? (long)test_uni(&st, 10, 3000) : -1;
    const long resume_at = hold_at + (long)test_uni(&st, 1, 2000);
    double p[3] = {0, 0, 0};
    int items = 0;
    bool fin = false;
    uint64_t h = 1469598103934665603ull;
    uint32_t serial = ip.serial, planned = 0;
    long k = 0;
    for (; k < MAX_CYCLES; k++) {
        while (items < n_items && lsm_planner_free(&pl) >= 12u) {
            test_append_random_item(&pl, &st, p);
            items++;
            if (!bursts)
                break;
        }
        if (items == n_items && !fin && lsm_planner_finish(&pl) == LSM_OK)
            fin = true;
        if (test_urand(&st) < p_ovr)
            (void)lsm_interp_set_override(&ip, (lsm_real)test_uni(&st, 0.3, 1.5));
        if (k == hold_at)
            lsm_interp_hold(&ip);
        if (k == resume_at)
            lsm_interp_resume(&ip);
        if (!(test_urand(&st) < p_noprep))
            (void)lsm_interp_prepare(&ip);
        if (ip.prepared + ip.tick_plans != planned && ip.prep.ready) /* the piece just planned ahead */
            h = fnv(h, &ip.pcs[ip.cur ^ 1u], sizeof ip.pcs[0]);
        lsm_real pos[LSM_MAX_AXES];
        const lsm_interp_state s = lsm_interp_step(&ip, pos);
        h = fnv(h, pos, sizeof pos);
        if (ip.serial != serial) /* a piece taken (planned in the step, or prepared) */
            h = fnv(h, &ip.pcs[ip.cur], sizeof ip.pcs[0]);
        serial = ip.serial;
        planned = ip.prepared + ip.tick_plans;
        if (s == LSM_INTERP_DONE && fin)
            break;
    }
    lsm_planner_stats ps = pl.stats;
    out->kept = ps.pieces_kept;
    ps.checks = 0; /* (what the memo saves) */
    ps.pieces_kept = 0;
    h = fnv(h, &ps, sizeof ps);
    const uint32_t ic[5] = {ip.replans, ip.plan_errors, ip.serial, ip.prepared, ip.tick_plans};
    h = fnv(h, ic, sizeof ic);
    out->h = h;
    out->cycles = k;
    out->pieces = (long)ps.pieces;
}

static void test_memo_same_pieces(void **state)
{
    (void)state;
    long kept = 0, pieces = 0, cycles = 0;
    for (long prog = 0; prog < g_count; prog++) {
        outcome on, off;
        run(prog, true, &on);
        run(prog, false, &off);
        if (on.h != off.h || on.cycles != off.cycles)
            fail_msg("program %ld: with the memo %016llx (%ld cycles), without %016llx (%ld cycles)", prog,
                     (unsigned long long)on.h, on.cycles, (unsigned long long)off.h, off.cycles);
        assert_int_equal(off.kept, 0);
        kept += on.kept;
        pieces += on.pieces;
        cycles += on.cycles;
    }
    print_message("%ld programs, %ld cycles, %ld pieces, %ld of them kept by the memo\n", g_count, cycles, pieces,
                  kept);
    assert_true(kept * 20 > pieces); /* the memo answered some calls: it could have changed something */
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, 1);
    g_count = (long)test_arg_u(argc, argv, 2, 200);
    print_message("seed %lu, count %ld\n", g_seed, g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_memo_same_pieces),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
