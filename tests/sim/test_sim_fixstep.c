/*
 * test_sim_fixstep.c: the integer-only evaluator (fixstep.h) against the double reference (double build only).
 *   test_sim_fixstep [seed] [count]     (default seed 1, count 600 moves)
 * Every cycle of every random move (1-6 axes, random counts/mm and start counts): the integer position is
 * within 1 count of the double reference start + s(k) * counts_per_mm, and the last cycle is exactly the
 * target count. Bad input to the compiler returns its codes.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include "lsm_test_rng.h"
#include <stdlib.h>
#include <string.h>

#include "fixprog.h"
#include "stepgen.h"

static unsigned long g_seed = 1;
static long g_count = 600;
static uint64_t rs;
static double urand(void)
{
    return test_urand(&rs);
}
static double logu(double lo, double hi)
{
    return test_logu(&rs, lo, hi);
}

static void test_integer_matches_double(void **state)
{
    (void)state;
    rs = 0x2545F4914F6CDD1Dull ^ (uint64_t)g_seed;
    long ran = 0, cycles = 0;
    double worst = 0;
    for (long c = 0; c < g_count; c++) {
        lsm_move_request r;
        memset(&r, 0, sizeof r);
        r.n_axes = (uint8_t)(1 + (int)(urand() * 6) % 6);
        r.cycle_s = urand() < 0.5 ? 0.001 : 0.00025;
        r.rule = LSM_SCURVE_RULE_STRICT;
        lsm_real cpm[LSM_MAX_AXES];
        int64_t start[LSM_MAX_AXES];
        for (unsigned i = 0; i < r.n_axes; i++) {
            r.lim[i] = (lsm_axis_limits){logu(10, 1000), logu(200, 20000), logu(2000, 1e6), logu(1e5, 1e9)};
            const double d = logu(0.01, 500);
            r.distance_mm[i] = urand() < 0.5 ? -d : d;
            cpm[i] = logu(100, 20000);
            start[i] = (int64_t)((urand() - 0.5) * 2e8);
        }
        lsm_move mv;
        if (lsm_move_plan(&mv, &r) != LSM_OK)
            continue;
        lsm_fixprog prog;
        lsm_status st = lsm_fixprog_compile(&prog, &mv, cpm, start);
        if (st == LSM_E_RANGE)
            continue; /* a ramp longer than the integer build accepts, or counts out of range */
        assert_int_equal(st, LSM_OK);
        ran++;
        lsm_fixstep fx;
        lsm_stepgen g;
        assert_int_equal(lsm_fixstep_init(&fx, &prog), LSM_OK);
        lsm_real origin[LSM_MAX_AXES] = {0};
        lsm_stepgen_init(&g, &mv, origin);
        const uint32_t n = lsm_move_total_cycles(&mv);
        int64_t pc[LSM_MAX_AXES];
        lsm_real pd[LSM_MAX_AXES];
        for (uint32_t k = 1; k <= n; k++) {
            const bool a = lsm_fixstep_next(&fx, pc);
            const bool b = lsm_stepgen_next(&g, pd);
            assert_int_equal(a, b);
            cycles++;
            for (unsigned i = 0; i < r.n_axes; i++) {
                const double ref = (double)start[i] + (double)pd[i] * cpm[i];
                const double err = fabs((double)pc[i] - ref);
                if (err > worst)
                    worst = err;
                if (err > 1.0) {
                    print_error("move %ld axis %u cycle %u/%u (phase %u, m %u of %u): %lld counts vs reference %.3f\n",
                                c, i, k, n, fx.phase, fx.m,
                                prog.phase[fx.phase < LSM_FIX_PHASES ? fx.phase : 0].n_cycles, (long long)pc[i], ref);
                    fail();
                }
            }
        }
        for (unsigned i = 0; i < r.n_axes; i++) {
            const int64_t want = start[i] + llround((double)r.distance_mm[i] * cpm[i]);
            assert_true(pc[i] == want);
            assert_true(pc[i] == prog.target_counts[i]);
        }
    }
    print_message("integer build: %ld moves, %ld cycles, worst deviation %.3f counts\n", ran, cycles, worst);
    assert_true(ran > g_count / 2);
}

static void test_compile_bad_input(void **state)
{
    (void)state;
    lsm_move_request r;
    memset(&r, 0, sizeof r);
    r.n_axes = 1;
    r.cycle_s = 0.001;
    r.distance_mm[0] = 10;
    r.lim[0] = (lsm_axis_limits){100, 1000, 10000, 1e6};
    lsm_move mv;
    assert_int_equal(lsm_move_plan(&mv, &r), LSM_OK);
    lsm_fixprog prog;
    lsm_real cpm = 1000;
    int64_t start = 0;
    assert_int_equal(lsm_fixprog_compile(NULL, &mv, &cpm, &start), LSM_E_NULL);
    lsm_real bad = 0;
    assert_int_equal(lsm_fixprog_compile(&prog, &mv, &bad, &start), LSM_E_LIMIT);
    bad = NAN;
    assert_int_equal(lsm_fixprog_compile(&prog, &mv, &bad, &start), LSM_E_LIMIT);
    int64_t far = (int64_t)1 << 40;
    assert_int_equal(lsm_fixprog_compile(&prog, &mv, &cpm, &far), LSM_E_RANGE);
    lsm_fixstep fx;
    assert_int_equal(lsm_fixstep_init(&fx, NULL), LSM_E_NULL);
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_integer_matches_double),
        cmocka_unit_test(test_compile_bad_input),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
