/*
 * test_motion_pipe.c: the tick / background hand-off of the motion layer (motion.h, mpipe.h) under preemption.
 *
 * A path program (lines, arcs, a dense polyline; a feed hold and resume, override changes) runs on the firmware's
 * CANopen node with three path axes. Every event (a 0x5010 block written when the node's buffer has room, a 0x5000
 * command, a 0x5001 override) happens in the tick context at a fixed tick count, so the run is defined by the tick
 * counts alone. The demands of every tick (the three axes' positions, bit patterns) and the executing block are
 * recorded and must be bit-identical across:
 *   reference   one context: tick n (lsm_motion_tick), then the background until it has nothing to do;
 *   injector    one thread, seeded: between background steps a random number of ticks (0..3) is injected, the
 *               background lags the tick by a random amount up to the lead; for several seeds;
 *   threads     (LSM_TEST_THREADS, the ThreadSanitizer build: ctest motion_pipe_tsan) the tick in its own thread,
 *               the background in another, running truly in parallel, so the tick lands at any instruction of
 *               the background's work (appends, lsm_interp_prepare, the interpolator step).
 * The harness (not the firmware) delays a tick until its set-point exists, so no run underruns; the tick itself
 * never waits. A last case starves the background mid-motion: the tick must stop the path axes itself, within the
 * machine's limits, with no jump, drop the path (EMCY 0xFF01), and continue from where they stopped once the
 * background restarted its planner there.
 * Arguments: [seed] [count] (injector runs; tests/common/lsm_test_rng.h).
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

#include "canopen.h"
#include "cia402_test_od.h"
#include "lsm_test_rng.h"
#include "motion.h"
#include "motion_test_node.h"

#if LSM_TEST_THREADS
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#endif

#define NID 3u
#define AX(idx, k) ((uint16_t)((idx) + 0x800u * (k)))
#define LEAD 8u
#define N_TICKS 20000u
#define N_BLOCKS 120u

typedef struct app {
    lsm_canopen co;
    mtn_storage st;
    lsm_motion mo;
    uint32_t now_us;
    uint32_t next_block; /* program block to write next (1-based) */
    uint32_t emcy_ff01;
} app;
static app g_app;

typedef struct trace {
    lsm_real p[N_TICKS][3];
    uint32_t seq[N_TICKS];
} trace;
static trace g_ref, g_run;

static unsigned long long g_seed = 1u, g_count = 4u;

static unsigned rng_below(uint64_t *st, unsigned n)
{
    return (unsigned)(test_urand(st) * n);
}

static const lsm_axis_limits k_lim = {250, 3000, 60000, 1.18e7};

static void set(uint16_t idx, uint8_t sub, int64_t v)
{
    g_app.co.now_us = g_app.now_us;
    uint32_t ab = lsm_co_od_set_int(lsm_canopen_od(&g_app.co), idx, sub, v);
    if (ab != 0u)
        fail_msg("write 0x%04X sub %u = %lld: abort 0x%08X", idx, sub, (long long)v, ab);
}

/* Program block i (1-based): a polyline of lines, a few arcs and a dense stretch, all in XY, in counts. */
static void program_block(uint32_t i, uint8_t *type, int32_t end[3], int32_t centre[2], uint32_t *feed_um_s)
{
    const double x = 0.6 * i; /* mm */
    *type = 1;
    *feed_um_s = i < 60u ? 40000u : 20000u;
    end[0] = (int32_t)lround(1000.0 * x);
    end[1] = (int32_t)lround(1000.0 * (i < 60u ? 3.0 * (double)(i % 4u) : 2.0 * sin(x / 5.0)));
    end[2] = (int32_t)(i % 7u == 0u ? 500 : 0);
    if (i % 11u == 5u) { /* a CCW half circle from the previous end, in XY, back to y of the previous */
        double px = 0.6 * (i - 1u);
        double py = (i - 1u) < 60u ? 3.0 * (double)((i - 1u) % 4u) : 2.0 * sin(px / 5.0);
        *type = 3;
        end[0] = (int32_t)lround(1000.0 * (px + 2.0));
        end[1] = (int32_t)lround(1000.0 * py);
        end[2] = ((i - 1u) % 7u == 0u) ? 500 : 0;
        centre[0] = (int32_t)lround(1000.0 * (px + 1.0));
        centre[1] = (int32_t)lround(1000.0 * py);
    }
}

/* Writes program block i through 0x5010; returns the SDO abort code (0 = taken). */
static uint32_t write_block(uint32_t i)
{
    uint8_t type;
    int32_t end[3], centre[2] = {0, 0};
    uint32_t feed;
    program_block(i, &type, end, centre, &feed);
    return od_path_block_tol(&g_app.co, i, type, end, centre, feed, 20u);
}

/* The events of tick n, in the tick context: blocks while the node's buffer has room, commands at fixed ticks. */
static void events(uint32_t n)
{
    if (n == 20u)
        set(0x5000, 0, 1); /* run */
    if (n >= 20u && g_app.next_block <= N_BLOCKS && lsm_co_path_count(lsm_canopen_path(&g_app.co)) < 12u) {
        if (write_block(g_app.next_block) == 0u)
            g_app.next_block++;
    }
    if (n == 1500u)
        set(0x5001, 0, 60); /* override 60 % */
    if (n == 2300u)
        set(0x5000, 0, 2); /* hold */
    if (n == 2900u)
        set(0x5000, 0, 3); /* resume */
    if (n == 3400u)
        set(0x5001, 0, 130);
}

/* One tick of the node, in the tick context; records the demands. */
static void tick(uint32_t n, trace *tr, bool record)
{
    g_app.now_us += 1000u;
    events(n);
    (void)lsm_canopen_process(&g_app.co, g_app.now_us);
    lsm_motion_tick(&g_app.mo, &g_app.co);
    lsm_motion_feedback(&g_app.mo, &g_app.co, NULL, NULL, g_app.now_us);
    lsm_can_frame f;
    while (lsm_canopen_tx_pop(&g_app.co, &f)) {
        if (f.id == 0x80u + NID && f.dlc >= 2 && f.data[0] == 0x01 && f.data[1] == 0xFF)
            g_app.emcy_ff01++;
    }
    if (!record)
        return;
    for (unsigned k = 0; k < 3; k++)
        tr->p[n][k] = lsm_motion_demand(&g_app.mo, k)->s_mm;
    tr->seq[n] = g_app.co.path.active_seq;
}

static void boot_mode(int8_t mode, uint32_t lead)
{
    memset(&g_app, 0, sizeof g_app);
    g_app.next_block = 1u;
    lsm_canopen_config cc = mtn_canopen_config(&g_app.st, NID, 3, 0);
    assert_int_equal(lsm_canopen_init(&g_app.co, &cc, 0u), LSM_OK);
    lsm_motion_config mc = mtn_motion_config(&g_app.st, 3, &k_lim, LSM_MOTION_PATH_PLANNER, lead);
    assert_int_equal(lsm_motion_init(&g_app.mo, &mc, &g_app.co), LSM_OK);
    mtn_nmt_start(&g_app.co, NID, 0u);
    for (unsigned k = 0; k < 3; k++) {
        set(AX(0x6060, k), 0, mode);
        set(AX(0x6040, k), 0, 0x06);
        set(AX(0x6040, k), 0, 0x0F);
    }
}

static void boot(void)
{
    boot_mode(-1, LEAD);
}

/* The set-point of tick n exists (the harness's pacing: the firmware's tick never waits). */
static bool due_ready(uint32_t n)
{
    return n < LEAD || lsm_spsc_avail(&g_app.mo.pipe.out_idx) > 0u;
}

static void run_reference(void)
{
    boot();
    for (uint32_t n = 0; n < N_TICKS; n++) {
        tick(n, &g_ref, true);
        while (lsm_motion_background(&g_app.mo)) {
        }
    }
    assert_int_equal(g_app.mo.tk.underruns, 0);
    assert_int_equal(g_app.mo.tk.stalls, 0);
}

/* The first tick whose demands differ, or N_TICKS. */
static uint32_t first_diff(const trace *a, const trace *b)
{
    for (uint32_t n = 0; n < N_TICKS; n++) {
        if (memcmp(a->p[n], b->p[n], sizeof a->p[n]) != 0 || a->seq[n] != b->seq[n])
            return n;
    }
    return N_TICKS;
}

static void check_same(const char *what, uint64_t seed)
{
    const uint32_t d = first_diff(&g_ref, &g_run);
    if (d != N_TICKS)
        fail_msg("%s (seed %llu): tick %u differs: x %.17g / %.17g, seq %u / %u", what, (unsigned long long)seed, d,
                 (double)g_ref.p[d][0], (double)g_run.p[d][0], g_ref.seq[d], g_run.seq[d]);
    assert_int_equal(g_app.mo.tk.underruns, 0);
}

/* The reference run itself: the program ran (every block, the hold held, it ended at rest on the last block). */
static void test_reference_runs(void **state)
{
    (void)state;
    run_reference();
    assert_int_equal(g_app.next_block, N_BLOCKS + 1u);
    assert_int_equal(g_app.emcy_ff01, 0);
    assert_int_equal(g_ref.seq[N_TICKS - 1u], N_BLOCKS);
    assert_false(g_app.mo.path_moving);
    uint8_t type;
    int32_t end[3], centre[2];
    uint32_t feed;
    program_block(N_BLOCKS, &type, end, centre, &feed);
    for (unsigned k = 0; k < 3; k++) { /* the programmed end, exactly (no lagging demand fed back into the feed) */
        int64_t v = 0;
        assert_int_equal(lsm_co_od_get_int(lsm_canopen_od(&g_app.co), AX(0x6062, k), 0, &v), 0);
        assert_int_equal(v, end[k]);
    }
    assert_true(memcmp(g_ref.p[2600], g_ref.p[2800], sizeof g_ref.p[0]) == 0); /* held */
    assert_true(memcmp(g_ref.p[1000], g_ref.p[1001], sizeof g_ref.p[0]) != 0); /* moving */
}

/* Seeded injector: background steps with ticks injected between them at random. */
static void test_injector(void **state)
{
    (void)state;
    run_reference();
    for (unsigned long long c = 0; c < g_count; c++) {
        const uint64_t seed = g_seed + c;
        uint64_t rng = seed * 0x9E3779B97F4A7C15ull + 1u;
        boot();
        memset(&g_run, 0, sizeof g_run);
        uint32_t n = 0;
        while (n < N_TICKS) {
            const unsigned burst = (unsigned)rng_below(&rng, 4u);
            for (unsigned i = 0; i < burst && n < N_TICKS && due_ready(n); i++, n++)
                tick(n, &g_run, true);
            const unsigned steps = (unsigned)rng_below(&rng, 3u);
            for (unsigned i = 0; i < steps; i++)
                (void)lsm_motion_background(&g_app.mo);
            if (!due_ready(n)) /* the background must catch up before the next tick */
                (void)lsm_motion_background(&g_app.mo);
        }
        check_same("injector", seed);
    }
}

#if LSM_TEST_THREADS
static atomic_bool g_stop;

static void *background_thread(void *arg)
{
    (void)arg;
    while (!atomic_load(&g_stop)) {
        if (!lsm_motion_background(&g_app.mo))
            sched_yield();
    }
    return NULL;
}

/* The tick in this thread, the background in another. */
static void test_threads(void **state)
{
    (void)state;
    run_reference();
    for (unsigned r = 0; r < 3u; r++) {
        boot();
        memset(&g_run, 0, sizeof g_run);
        atomic_store(&g_stop, false);
        pthread_t th;
        assert_int_equal(pthread_create(&th, NULL, background_thread, NULL), 0);
        for (uint32_t n = 0; n < N_TICKS; n++) {
            while (!due_ready(n))
                sched_yield();
            for (volatile unsigned spin = (n * 2654435761u) % 3000u; spin > 0u; spin--) {
            }
            tick(n, &g_run, true);
        }
        atomic_store(&g_stop, true);
        assert_int_equal(pthread_join(th, NULL), 0);
        check_same("threads", r);
    }
}
#endif

/* The background stops mid-motion: the tick stops the path axes itself and nothing jumps. */
static void test_underrun_stop(void **state)
{
    (void)state;
    boot();
    uint32_t n = 0;
    for (; n < 700u; n++) { /* moving at 40 mm/s along the first lines */
        tick(n, &g_run, true);
        while (lsm_motion_background(&g_app.mo)) {
        }
    }
    assert_true(g_app.mo.path_moving);
    const lsm_real dt = (lsm_real)0.001;
    lsm_real v_prev = 0, a_prev = 0;
    for (; n < 1400u; n++) { /* starved: no background */
        tick(n, &g_run, true);
        const lsm_real v = (g_run.p[n][0] - g_run.p[n - 1u][0]) / dt;
        const lsm_real a = (v - v_prev) / dt;
        /* the stop starts from the state estimated from the last set-points (motion.c abort_state): within the
         * machine's a, and its j to the estimate's error (the sampled jerk of the path plus the release) */
        if (n > 702u && (fabs((double)a) > 3000.0 * 1.01 || fabs((double)(a - a_prev)) / 0.001 > 60000.0 * 1.25))
            fail_msg("tick %u: a %g, j %g", n, (double)a, (double)(a - a_prev) / 0.001);
        assert_true(fabs((double)v) <= 250.0);
        v_prev = v;
        a_prev = a;
    }
    assert_int_equal(g_app.mo.tk.underruns, 1);
    assert_true(g_app.mo.tk.aborting);
    assert_false(g_app.mo.path_moving);
    assert_int_equal(g_app.emcy_ff01, 1);
    const lsm_real x_stop = g_run.p[n - 1u][0];
    for (; n < 1700u; n++) { /* the background is back: it restarts where the axes stand; no jump */
        while (lsm_motion_background(&g_app.mo)) {
        }
        tick(n, &g_run, true);
        assert_true(fabs((double)(g_run.p[n][0] - x_stop)) < 1e-9);
    }
    assert_false(g_app.mo.tk.aborting);
    assert_int_equal(g_app.mo.tk.underruns, 1);
}

/* PP with the move plans in the background (lead > 0): a move from rest is the synchronous loop's move, bit for bit,
 * started MO_PP_PLAN_CYCLES (8) cycles later; a retarget while moving (planned from the state the background
 * forecasts for its first cycle) ends exactly on the new target. */
static lsm_real g_pp[2][3000];

static void pp_run(uint32_t lead, lsm_real *out)
{
    boot_mode(1, lead);
    set(AX(0x6081, 0), 0, 100000); /* 100 mm/s, 1000 mm/s², 2e4 mm/s³, 2e6 mm/s⁴ (1000 counts/mm), sin² */
    set(AX(0x6083, 0), 0, 1000000);
    set(AX(0x6084, 0), 0, 1000000);
    set(AX(0x2060, 0), 0, 20000000);
    set(AX(0x2061, 0), 0, 2000000000);
    set(AX(0x6086, 0), 0, 1);
    for (uint32_t n = 0; n < 3000u; n++) {
        if (n == 10u) {
            set(AX(0x607A, 0), 0, 40000);
            set(AX(0x6040, 0), 0, 0x3F);
        }
        if (n == 12u)
            set(AX(0x6040, 0), 0, 0x2F);
        g_app.now_us += 1000u;
        mtn_sync_cycle(&g_app.co, &g_app.mo, g_app.now_us, false);
        out[n] = lsm_motion_demand(&g_app.mo, 0)->s_mm;
    }
}

static void test_pp_background(void **state)
{
    (void)state;
    pp_run(0u, g_pp[0]);
    pp_run(LEAD, g_pp[1]);
    assert_true(g_pp[0][2000] == 40.0);
    for (uint32_t n = 0; n + 8u < 3000u; n++) {
        if (memcmp(&g_pp[0][n], &g_pp[1][n + 8u], sizeof(lsm_real)) != 0)
            fail_msg("tick %u: %.17g (synchronous) / %.17g (background plan, 8 later)", n, (double)g_pp[0][n],
                     (double)g_pp[1][n + 8u]);
    }
    assert_int_equal(g_app.mo.ax[0].pp_late, 0);
    /* retarget while moving (single set-point): planned in the background from the forecast state */
    set(AX(0x607A, 0), 0, 0);
    set(AX(0x6040, 0), 0, 0x3F);
    lsm_real prev = lsm_motion_demand(&g_app.mo, 0)->s_mm, vprev = 0;
    for (uint32_t n = 0; n < 3000u; n++) {
        if (n == 2u)
            set(AX(0x6040, 0), 0, 0x2F);
        if (n == 300u) { /* moving back at speed: retarget to -10 mm */
            set(AX(0x607A, 0), 0, -10000);
            set(AX(0x6040, 0), 0, 0x3F);
        }
        if (n == 302u)
            set(AX(0x6040, 0), 0, 0x2F);
        g_app.now_us += 1000u;
        (void)lsm_canopen_process(&g_app.co, g_app.now_us);
        lsm_motion_tick(&g_app.mo, &g_app.co);
        lsm_motion_feedback(&g_app.mo, &g_app.co, NULL, NULL, g_app.now_us);
        lsm_can_frame f;
        while (lsm_canopen_tx_pop(&g_app.co, &f)) {
        }
        while (lsm_motion_background(&g_app.mo)) {
        }
        const lsm_real p = lsm_motion_demand(&g_app.mo, 0)->s_mm;
        const lsm_real v = (p - prev) / (lsm_real)0.001;
        assert_true(fabs((double)v) <= 100.0 * 1.0001);                      /* no jump at the swap */
        assert_true(fabs((double)(v - vprev)) / 0.001 <= 1000.0 * 1.01 + 1); /* within a */
        prev = p;
        vprev = v;
    }
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm == -10.0);
    assert_int_equal(g_app.mo.ax[0].pp_late, 0);
}

int main(int argc, char **argv)
{
    g_seed = test_arg_u(argc, argv, 1, 1u);
    g_count = test_arg_u(argc, argv, 2, 4u);
    const struct CMUnitTest tests[] =
    { cmocka_unit_test(test_reference_runs),
      cmocka_unit_test(test_injector),
#if LSM_TEST_THREADS
      cmocka_unit_test(test_threads),
#endif
      cmocka_unit_test(test_underrun_stop),
      cmocka_unit_test(test_pp_background),
    };
    const int rc = cmocka_run_group_tests(tests, NULL, NULL);
    return test_seed_finish(argv[0], g_seed, g_count, rc);
}
