/*
 * test_pp_midramp.c: a change of set-point and a halt while a PP axis is still accelerating, on the firmware's
 * CiA 402 node and motion layer (motion.h), as the HIL rig's test_pp_setpoints does them (hil/tests/test_pp.py,
 * PROFILE v = 100 mm/s, a = d = 1000 mm/s², j = 20000 mm/s³, snap = 2e6 mm/s⁴, 1 ms cycle):
 *   retarget  moving 25 -> 100 mm, when the demand passes 27 mm a single set-point (0x6040 bit 5 = 1: REPLACE)
 *             to 30 mm; it must end on 30 mm exactly;
 *   halt      moving 30 -> 80 mm, when the demand passes 33 mm halt (bit 8); it must end at rest; released, the
 *             move goes on to 80 mm exactly.
 * Each is run with the request taken 0..LATENCY_MAX cycles after the demand passed the point (bus latency), with
 * the move plans in the tick (lead_cycles 0) and in the background (lead_cycles 24, as the controller image and
 * lissom-node run), and for both profile types (0x6086 = 1 sin², 0 linear ramp). A quick stop (0x6040 = 0x0B) at the
 * same points is run too.
 *
 * Checked at every cycle (tests/common/pp_check.h):
 *   the demand's own state   |v| <= V, |a| <= A, |j| <= J, and type 1: |j_k - j_k-1| <= S dt (snap);
 *   backward differences     of the demand positions, order n = 1..4 (v, a, j, snap; type 0 without the snap),
 *                            each within its limit. The n-th backward difference over dt^n is a weighted mean of
 *                            the n-th derivative over the last n cycles (B-spline kernel), so a profile within its
 *                            limits never exceeds them. In the float build order 1 only (PP_CHECK_DIFF_ORDER:
 *                            from order 2 on, the rounding of float positions is larger than the limits).
 * Noise bounds (never a tolerance): PP_NOISE_ULPS ulps of the real type relative to each limit on the demand's own
 * state, and for a backward difference of order n the rounding of the positions, 2^n PP_POS_ULPS ulp(|p|max) / dt^n.
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
#include "motion.h"
#include "pp_check.h"
#include "motion_test_node.h"

#define NID 3u
#define LEAD_NODE 24u    /* the controller image's and lissom-node's lead (ctl_motion_cia402.h) */
#define LATENCY_MAX 100u /* request cycles after the demand passed the point */
#define RUN_MAX 20000u   /* guard: cycles to rest */

/* The machine of lissom-node's built-in default: 250 mm/s, 3000 mm/s², 60000 mm/s³, 1.18e7 mm/s⁴. */
static const lsm_axis_limits k_lim = {250, 3000, 60000, 1.18e7};

typedef struct app {
    lsm_canopen co;
    mtn_storage st;
    lsm_motion mo;
    uint32_t now_us;
} app;
static app g_app; /* large: static storage */
static pp_checker g_chk;

static void set(uint16_t idx, uint8_t sub, int64_t v)
{
    od_set(&g_app.co, g_app.now_us, idx, sub, v);
}

static void cycle(void)
{
    g_app.now_us += 1000u;
    mtn_sync_cycle(&g_app.co, &g_app.mo, g_app.now_us, false);
    pp_check_kin(&g_chk, lsm_motion_demand(&g_app.mo, 0));
}

static void boot(uint32_t lead, int ptype)
{
    memset(&g_app, 0, sizeof g_app);
    lsm_canopen_config cc = mtn_canopen_config(&g_app.st, NID, 1, 0);
    assert_int_equal(lsm_canopen_init(&g_app.co, &cc, 0u), LSM_OK);
    lsm_motion_config mc = mtn_motion_config(&g_app.st, 1, &k_lim, LSM_MOTION_PATH_PLANNER, lead);
    assert_int_equal(lsm_motion_init(&g_app.mo, &mc, &g_app.co), LSM_OK);
    mtn_nmt_start(&g_app.co, NID, 0u);
    set(0x6060, 0, 1);
    set(0x6040, 0, 0x06);
    set(0x6040, 0, 0x0F);
    od_pp_profile(&g_app.co, g_app.now_us, 0);
    set(0x6086, 0, ptype);
    const double snap = ptype == 1 ? 2.0e6 : 0;
    pp_check_init(&g_chk, 0.001, 100.0, 1000.0, 20000.0, snap);
    for (int i = 0; i < 3; i++)
        cycle();
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_OPERATION_ENABLED);
}

/* A single set-point (change set immediately), with halt (bit 8) as given. */
static void go(double target_mm, bool halt)
{
    const int64_t h = halt ? 0x100 : 0;
    set(0x607A, 0, (int64_t)lround(target_mm * 1000.0));
    set(0x6040, 0, 0x3F | h);
    cycle();
    set(0x6040, 0, 0x2F | h);
}

static void run_to_rest(void)
{
    unsigned n = 0;
    const lsm_motion_axis *a = &g_app.mo.ax[0];
    while (!lsm_motion_at_rest(&g_app.mo) || a->pp_wait || a->prof.have_after || n < 30u) { /* a plan may wait */
        cycle();
        assert_true(++n < RUN_MAX);
    }
}

/* Moves to from_mm and rests there; then starts the move to to_mm and returns once the demand passed at_mm and
 * `latency` more cycles ran. */
static void approach(double from_mm, double to_mm, double at_mm, unsigned latency)
{
    go(from_mm, false);
    run_to_rest();
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm == (lsm_real)from_mm);
    go(to_mm, false);
    unsigned n = 0;
    while ((double)lsm_motion_demand(&g_app.mo, 0)->s_mm < at_mm) {
        cycle();
        assert_true(++n < RUN_MAX);
    }
    for (unsigned i = 0; i < latency; i++)
        cycle();
}

static void report(const char *what, uint32_t lead, int ptype, unsigned latency)
{
    if (g_chk.bad)
        fail_msg("%s, lead %u, profile type %d, latency %u cycles: %s", what, lead, ptype, latency, g_chk.msg);
}

static void retarget_case(uint32_t lead, int ptype, unsigned latency)
{
    boot(lead, ptype);
    approach(25.0, 100.0, 27.0, latency);
    go(30.0, false);
    run_to_rest();
    report("retarget 25 -> 100 mm, at 27 mm to 30 mm", lead, ptype, latency);
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm == (lsm_real)30.0);
}

static void halt_case(uint32_t lead, int ptype, unsigned latency)
{
    boot(lead, ptype);
    approach(30.0, 80.0, 33.0, latency);
    set(0x6040, 0, 0x10F); /* halt */
    run_to_rest();
    const lsm_kin k = *lsm_motion_demand(&g_app.mo, 0);
    assert_true(k.v_mm_s == 0 && k.a_mm_s2 == 0 && k.j_mm_s3 == 0);
    assert_true(k.s_mm > 33.0 && k.s_mm < 80.0);
    set(0x6040, 0, 0x0F); /* released: the move goes on */
    run_to_rest();
    report("halt 30 -> 80 mm at 33 mm", lead, ptype, latency);
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm == (lsm_real)80.0);
}

static void quick_stop_case(uint32_t lead, int ptype, unsigned latency)
{
    boot(lead, ptype);
    set(0x6085, 0, 1000000); /* quick stop deceleration 1000 mm/s² (the profile's) */
    approach(30.0, 80.0, 33.0, latency);
    set(0x6040, 0, 0x0B); /* quick stop */
    run_to_rest();
    report("quick stop 30 -> 80 mm at 33 mm", lead, ptype, latency);
    const lsm_kin k = *lsm_motion_demand(&g_app.mo, 0);
    assert_true(k.v_mm_s == 0 && k.a_mm_s2 == 0 && k.j_mm_s3 == 0);
}

static void test_retarget_accelerating(void **state)
{
    (void)state;
    for (int ptype = 1; ptype >= 0; ptype--)
        for (uint32_t lead = 0; lead <= LEAD_NODE; lead += LEAD_NODE)
            for (unsigned lat = 0; lat <= LATENCY_MAX; lat++)
                retarget_case(lead, ptype, lat);
}

static void test_halt_accelerating(void **state)
{
    (void)state;
    for (int ptype = 1; ptype >= 0; ptype--)
        for (uint32_t lead = 0; lead <= LEAD_NODE; lead += LEAD_NODE)
            for (unsigned lat = 0; lat <= LATENCY_MAX; lat++)
                halt_case(lead, ptype, lat);
}

static void test_quick_stop_accelerating(void **state)
{
    (void)state;
    for (int ptype = 1; ptype >= 0; ptype--)
        for (uint32_t lead = 0; lead <= LEAD_NODE; lead += LEAD_NODE)
            for (unsigned lat = 0; lat <= LATENCY_MAX; lat++)
                quick_stop_case(lead, ptype, lat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_retarget_accelerating),
        cmocka_unit_test(test_halt_accelerating),
        cmocka_unit_test(test_quick_stop_accelerating),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
