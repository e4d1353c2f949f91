/*
 * test_pp_props.c: seeded randomized property test of the PP engine (axprof.h, jstop.h) on the firmware's CiA 402
 * node and motion layer (motion.h): requests at any state of an axis, in particular mid-ramp and mid jerk pulse.
 *
 * Each case: random machine limits and a random PP profile within them (0x6081, 0x6083, 0x6084, 0x6085, 0x2060,
 * 0x2061, profile type 0x6086 = 0 or 1), the move plans in the tick (lead_cycles 0) or the background (24, as the
 * controller image runs them); then a random sequence of requests, each a random 0..150 cycles after the one before
 * (so most land inside an acceleration ramp or a jerk pulse): single set-points (bit 5 = 1, REPLACE), sets of
 * set-points (bit 5 = 0), halt on (bit 8) and off; the case ends with a quick stop, an E-stop, or the last set-point
 * run to its end.
 *
 * Checked (tests/common/pp_check.h) on every cycle: |v| <= V of the profile, |a|, |j|, snap (type 1) within the
 * limits in force, no jump (dv, da, and the backward differences of the positions); limits in force: the
 * profile's (A = 0x6084, the larger of the move's min(0x6083, 0x6084) and the halt's 0x6084), from a quick stop
 * on also its 0x6085, from an E-stop on the machine's a, j, snap (V stays the profile's). Type 0 has no snap check
 * (axprof.h). At the end: the last accepted set-point's target exactly (lsm_real of counts / 0x2001), or rest
 * (v = a = j = 0) after a stop.
 *
 * Arguments: [seed] [count] (tests/common/lsm_test_rng.h). A failing case prints its index and the seed, count
 * and replay command.
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
#include "pp_check.h"
#include "motion_test_node.h"

#define NID 3u
#define LEAD_NODE 24u       /* the controller image's lead (ctl_motion_cia402.h) */
#define EVENTS_MAX 12u      /* requests per case */
#define GAP_MAX 150u        /* cycles between requests */
#define SETTLE_CYCLES 30u   /* rest with nothing pending this long before a case ends */
#define CASE_CYCLES 400000u /* guard */
#define CPM 1000.0          /* counts per mm (the node's default 0x2001) */

static unsigned long long g_seed, g_count;

typedef struct app {
    lsm_canopen co;
    mtn_storage st;
    lsm_motion mo;
    uint32_t now_us;
    bool estop;
} app;
static app g_app;
static pp_checker g_chk;
static unsigned long g_cycles, g_ends[3], g_requests; /* for the report */

static void set(uint16_t idx, uint8_t sub, int64_t v)
{
    od_set(&g_app.co, g_app.now_us, idx, sub, v);
}

static void cycle(void)
{
    g_app.now_us += 1000u;
    mtn_sync_cycle(&g_app.co, &g_app.mo, g_app.now_us, g_app.estop);
    pp_check_kin(&g_chk, lsm_motion_demand(&g_app.mo, 0));
    g_cycles++;
}

typedef struct limits {
    double vm, am, jm, sm;    /* machine */
    double v, acc, dec, j, s; /* profile */
    double dq;                /* quick stop deceleration */
    int type;
} limits;

static void draw_limits(uint64_t *r, limits *l)
{
    l->vm = test_logu(r, 50, 500);
    l->am = test_logu(r, 300, 5000);
    l->jm = l->am * test_logu(r, 5, 100);
    l->sm = l->jm * test_logu(r, 20, 1000);
    l->v = floor(test_uni(r, 0.1, 1.0) * l->vm) + 1;
    l->dec = floor(test_logu(r, 0.1, 1.0) * l->am) + 1;
    l->acc = test_urand(r) < 0.5 ? l->dec : floor(test_logu(r, 0.1, 1.0) * l->am) + 1;
    l->j = floor(fmin(l->jm, 1e5) * test_logu(r, 0.05, 1.0)) + 1;
    l->s = floor(fmin(l->sm, 4e6) * test_logu(r, 0.02, 1.0)) + 1;
    l->dq = floor(fmin(l->am, l->dec * test_uni(r, 1.0, 1.5)));
    l->type = test_urand(r) < 0.5 ? 0 : 1;
}

static void boot(const limits *l, uint32_t lead)
{
    memset(&g_app, 0, sizeof g_app);
    lsm_canopen_config cc = mtn_canopen_config(&g_app.st, NID, 1, 0);
    assert_int_equal(lsm_canopen_init(&g_app.co, &cc, 0u), LSM_OK);
    const lsm_axis_limits lim = {(lsm_real)l->vm, (lsm_real)l->am, (lsm_real)l->jm, (lsm_real)l->sm};
    lsm_motion_config mc = mtn_motion_config(&g_app.st, 1, &lim, LSM_MOTION_PATH_PLANNER, lead);
    assert_int_equal(lsm_motion_init(&g_app.mo, &mc, &g_app.co), LSM_OK);
    mtn_nmt_start(&g_app.co, NID, 0u);
    set(0x6060, 0, 1);
    set(0x6040, 0, 0x06);
    set(0x6040, 0, 0x0F);
    set(0x6081, 0, (int64_t)(l->v * CPM));
    set(0x6083, 0, (int64_t)(l->acc * CPM));
    set(0x6084, 0, (int64_t)(l->dec * CPM));
    set(0x6085, 0, (int64_t)(l->dq * CPM));
    set(0x2060, 0, (int64_t)(l->j * CPM));
    set(0x2061, 0, (int64_t)(l->s * CPM));
    set(0x6086, 0, l->type);
    pp_check_init(&g_chk, 0.001, l->v, fmin(l->dec, l->am), fmin(l->j, l->jm), l->type == 1 ? fmin(l->s, l->sm) : 0);
    for (int i = 0; i < 3; i++)
        cycle();
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_OPERATION_ENABLED);
}

static void cycles(unsigned n)
{
    for (unsigned i = 0; i < n && !g_chk.bad; i++)
        cycle();
}

static bool settled(void)
{
    const lsm_motion_axis *a = &g_app.mo.ax[0];
    return lsm_motion_at_rest(&g_app.mo) && !a->pp_wait && !a->prof.have_after && !a->pp_running;
}

/* Runs until the axis rests with nothing pending for SETTLE_CYCLES cycles. */
static void run_settled(unsigned long ci)
{
    unsigned quiet = 0, n = 0;
    while (quiet < SETTLE_CYCLES && !g_chk.bad) {
        cycle();
        quiet = settled() ? quiet + 1u : 0u;
        if (++n >= CASE_CYCLES)
            fail_msg("case %lu: not at rest after %u cycles", ci, n);
    }
}

static int32_t draw_target(uint64_t *r, int32_t from)
{
    const double u = test_urand(r);
    double d;
    if (u < 0.2)
        d = test_uni(r, -1.0, 1.0); /* short: never reaches the profile velocity */
    else if (u < 0.4)
        d = test_uni(r, -10.0, 10.0);
    else
        d = test_uni(r, -200.0, 200.0);
    return from + (int32_t)lround(d * CPM);
}

static void run_case(uint64_t *r, unsigned long ci)
{
    limits l;
    draw_limits(r, &l);
    const uint32_t lead = test_urand(r) < 0.5 ? 0u : LEAD_NODE;
    boot(&l, lead);
    int32_t final_target = 0, last = 0;
    bool halted = false, any = false;
    const unsigned n_ev = 1u + (unsigned)(test_urand(r) * EVENTS_MAX);
    for (unsigned e = 0; e < n_ev && !g_chk.bad; e++) {
        const double u = test_urand(r);
        const uint16_t halt = halted ? 0x100 : 0;
        if (u < 0.55 || !any) { /* a set-point; bit 5 from the draw */
            const bool imm = test_urand(r) < 0.65;
            last = draw_target(r, last);
            const uint16_t ignored = lsm_canopen_axis(&g_app.co, 0)->sp_ignored;
            set(0x607A, 0, last);
            set(0x6040, 0, (uint16_t)(0x1F | (imm ? 0x20 : 0) | halt));
            cycle();
            set(0x6040, 0, (uint16_t)(0x0F | (imm ? 0x20 : 0) | halt));
            if (lsm_canopen_axis(&g_app.co, 0)->sp_ignored == ignored)
                final_target = last;
            else
                last = final_target; /* the buffer was full: not taken */
            any = true;
        } else if (u < 0.8) {
            halted = !halted;
            set(0x6040, 0, halted ? 0x10F : 0x0F);
        }
        g_requests++;
        cycles((unsigned)(test_urand(r) * GAP_MAX));
    }
    const double end = test_urand(r);
    g_ends[end < 0.25 ? 0 : end < 0.5 ? 1 : 2]++;
    if (end < 0.25 && !g_chk.bad) { /* quick stop */
        pp_check_limits(&g_chk, l.v, fmin(fmax(l.dec, l.dq), l.am), fmin(l.j, l.jm), g_chk.S);
        set(0x6040, 0, 0x0B);
        run_settled(ci);
    } else if (end < 0.5 && !g_chk.bad) { /* E-stop: the machine's limits */
        pp_check_limits(&g_chk, l.v, l.am, l.jm, l.type == 1 ? l.sm : 0);
        g_app.estop = true;
        run_settled(ci);
    } else if (!g_chk.bad) {
        if (halted)
            set(0x6040, 0, 0x0F);
        run_settled(ci);
        if (!g_chk.bad && lsm_motion_demand(&g_app.mo, 0)->s_mm != (lsm_real)final_target / (lsm_real)CPM)
            fail_msg("case %lu: ends at %.17g, not on the target %d counts", ci,
                     (double)lsm_motion_demand(&g_app.mo, 0)->s_mm, final_target);
    }
    const lsm_kin k = *lsm_motion_demand(&g_app.mo, 0);
    if (g_chk.bad)
        fail_msg("case %lu (type %d, lead %u; V %g A %g/%g Dq %g J %g S %g; machine %g %g %g %g): %s", ci, l.type, lead,
                 l.v, l.acc, l.dec, l.dq, l.j, l.s, l.vm, l.am, l.jm, l.sm, g_chk.msg);
    if (!(k.v_mm_s == 0 && k.a_mm_s2 == 0 && k.j_mm_s3 == 0))
        fail_msg("case %lu: not at rest at the end (v %g a %g j %g)", ci, (double)k.v_mm_s, (double)k.a_mm_s2,
                 (double)k.j_mm_s3);
}

static void test_props(void **state)
{
    (void)state;
    uint64_t r = 0x2545F4914F6CDD1Dull ^ (g_seed * 0x9E3779B97F4A7C15ull);
    double worst[10] = {0};
    for (unsigned long i = 0; i < g_count; i++) {
        run_case(&r, i);
        for (int k = 0; k < 10; k++)
            worst[k] = fmax(worst[k], g_chk.worst[k]);
    }
    printf("%llu cases, %lu requests, %lu cycles; ends: %lu quick stops, %lu E-stops, %lu at the target\n", g_count,
           g_requests, g_cycles, g_ends[0], g_ends[1], g_ends[2]);
    printf("%llu cases; worst/allowed v %.9f a %.9f j %.9f snap %.9f dv %.9f da %.9f D1 %.9f D2 %.9f D3 %.9f D4 %.9f\n",
           g_count, worst[0], worst[1], worst[2], worst[3], worst[4], worst[5], worst[6], worst[7], worst[8], worst[9]);
}

int main(int argc, char **argv)
{
    g_seed = test_arg_u(argc, argv, 1, 1u);
    g_count = test_arg_u(argc, argv, 2, 600u);
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_props)};
    return test_seed_finish(argv[0], g_seed, g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
