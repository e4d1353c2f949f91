/*
 * test_motion.c: the CiA 402 motion layer (motion.h) on the firmware's CANopen node, with ideal feedback (the
 * actual position is the demand: no drive model), driven without CAN or a clock: frames and object writes go in
 * directly (lsm_co_od_set_int has the same checks and hooks as an SDO download), time advances by one cycle per
 * call. Built double and float (tolerances that depend on the type say so):
 *   - PP sin² move: exact end, |v|, |a|, |j| of the demand within the profile; a set of set-points runs both;
 *     a single set-point (change set immediately) retargets a running move;
 *   - E-stop during a move: FAULT REACTION ACTIVE -> FAULT, a stop within the machine's a, j;
 *   - master heartbeat loss: PRE-OPERATIONAL, quick stop within 0x6085 / 0x2060, EMCY 0x8130 queued;
 *   - bus-off: nothing sent while off, the communication-error stop, EMCY 0x8140 after recovery;
 *   - path (look-ahead feed and exact-stop executor): blocks through 0x5010, the end reached exactly,
 *     a block appended after an underrun stop restarts the motion, hold / resume, clear;
 *   - CSP: targets applied at SYNC and passed through.
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
#include "motion_test_node.h"

#define NID 3u

#if LSM_REAL_IS_FLOAT
#define TOL_REL 1e-5 /* limits: relative rounding of a float state */
#else
#define TOL_REL 1e-9
#endif

#define PATH_PLANNER LSM_MOTION_PATH_PLANNER
#define PATH_EXACT LSM_MOTION_PATH_EXACT

typedef struct app {
    lsm_canopen co;
    mtn_storage st;
    lsm_motion mo;
    uint32_t cycle_us;
    bool out_enable;
} app;
static app g_app; /* large: static storage */

/* The machine of lissom-node's built-in default: 250 mm/s, 3000 mm/s², 60000 mm/s³, 1.18e7 mm/s⁴. */
static const lsm_axis_limits k_lim = {250, 3000, 60000, 1.18e7};

static void app_cycle(bool estop, uint32_t now_us)
{
    lsm_canopen_estop(&g_app.co, estop, now_us);
    (void)lsm_canopen_process(&g_app.co, now_us);
    lsm_motion_cycle(&g_app.mo, &g_app.co);
    lsm_motion_feedback(&g_app.mo, &g_app.co, NULL, NULL, now_us);
    g_app.out_enable = lsm_canopen_drive_enable(&g_app.co);
}

typedef struct rec {
    double p[20000];
    double v[20000], a[20000], j[20000]; /* the demand's own v, a, j */
    uint8_t state[20000];
    size_t n;
} rec;
static rec g_rec;

static uint32_t g_now;
static lsm_can_frame g_sent[4096];
static size_t g_n_sent;

static void drain(void)
{
    lsm_can_frame f;
    while (lsm_canopen_tx_pop(&g_app.co, &f)) {
        if (g_n_sent < sizeof g_sent / sizeof g_sent[0])
            g_sent[g_n_sent++] = f;
    }
}

static void cycles(unsigned n, bool estop, unsigned axis)
{
    for (unsigned i = 0; i < n; i++) {
        g_now += g_app.cycle_us;
        app_cycle(estop, g_now);
        drain();
        if (g_rec.n < sizeof g_rec.p / sizeof g_rec.p[0]) {
            const lsm_kin *d = lsm_motion_demand(&g_app.mo, axis);
            g_rec.p[g_rec.n] = d->s_mm;
            g_rec.v[g_rec.n] = d->v_mm_s;
            g_rec.a[g_rec.n] = d->a_mm_s2;
            g_rec.j[g_rec.n] = d->j_mm_s3;
            g_rec.state[g_rec.n] = lsm_canopen_axis(&g_app.co, axis)->state;
            g_rec.n++;
        }
    }
}

static void rx(uint32_t id, uint8_t dlc, const uint8_t *d)
{
    lsm_can_frame f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    if (dlc)
        memcpy(f.data, d, dlc);
    (void)lsm_canopen_rx(&g_app.co, &f, g_now);
}

static void set(uint16_t idx, uint8_t sub, int64_t v)
{
    od_set(&g_app.co, g_now, idx, sub, v);
}

static int64_t get(uint16_t idx, uint8_t sub)
{
    return od_get(&g_app.co, idx, sub);
}

static void boot(uint8_t path_exec, uint16_t master, uint16_t master_ms)
{
    memset(&g_app, 0, sizeof g_app);
    g_app.cycle_us = 1000;
    lsm_canopen_config cc = mtn_canopen_config(&g_app.st, NID, 3, 100);
    cc.master_node_id = (uint8_t)master;
    cc.master_timeout_ms = master_ms;
    g_now = 0;
    g_n_sent = 0;
    g_rec.n = 0;
    assert_int_equal(lsm_canopen_init(&g_app.co, &cc, g_now), LSM_OK);
    lsm_motion_config mc = mtn_motion_config(&g_app.st, 3, &k_lim, path_exec, 0);
    assert_int_equal(lsm_motion_init(&g_app.mo, &mc, &g_app.co), LSM_OK);
    drain();
    const uint8_t start[2] = {0x01, NID};
    rx(0, 2, start);
    cycles(2, false, 0);
    assert_int_equal(lsm_canopen_nmt_state(&g_app.co), LSM_CO_NMT_OPERATIONAL);
}

static void enable(unsigned k, int8_t mode)
{
    set(AX(0x6060, k), 0, mode);
    set(AX(0x6040, k), 0, 0x06);
    set(AX(0x6040, k), 0, 0x0F);
    cycles(2, false, k);
    assert_int_equal(lsm_canopen_axis(&g_app.co, k)->state, LSM_CIA402_OPERATION_ENABLED);
    assert_int_equal(lsm_canopen_axis(&g_app.co, k)->mode_display, mode);
}

/* Largest |v|, |a|, |j| of the demand over rec[from..to): the generator's own values, and in the double build
 * also the finite differences of order 1..3 of the positions (in float those are rounding noise). */
static void peaks(size_t from, size_t to, double dt, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    for (size_t i = from + 3; i < to; i++) {
        out[0] = fmax(out[0], fabs(g_rec.v[i]));
        out[1] = fmax(out[1], fabs(g_rec.a[i]));
        out[2] = fmax(out[2], fabs(g_rec.j[i]));
#if !LSM_REAL_IS_FLOAT
        const double *p = g_rec.p;
        double v = (p[i] - p[i - 1]) / dt;
        double a = (p[i] - 2 * p[i - 1] + p[i - 2]) / (dt * dt);
        double j = (p[i] - 3 * p[i - 1] + 3 * p[i - 2] - p[i - 3]) / (dt * dt * dt);
        out[0] = fmax(out[0], fabs(v));
        out[1] = fmax(out[1], fabs(a));
        out[2] = fmax(out[2], fabs(j));
#else
        (void)dt;
#endif
    }
}

static size_t count_sent(uint32_t id, uint16_t emcy_code)
{
    return frames_count(g_sent, g_n_sent, NID, id, emcy_code);
}

static void pp_profile(unsigned k)
{
    od_pp_profile(&g_app.co, g_now, k);
}

static void pp_go(unsigned k, int32_t target)
{
    od_pp_go(&g_app.co, g_now, k, target);
}

static void test_pp_and_estop(void **state)
{
    (void)state;
    boot(PATH_PLANNER, 0, 0);
    enable(0, LSM_CIA402_MODE_PP);
    pp_profile(0);
    size_t r0 = g_rec.n;
    pp_go(0, 40000);
    cycles(1500, false, 0);
    assert_true(get(0x6041, 0) & 0x0400);
    assert_int_equal(get(0x6062, 0), 40000);
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm == 40.0);
    double pk[3];
    peaks(r0, g_rec.n, 0.001, pk);
    assert_true(pk[0] <= 100 * (1 + TOL_REL) && pk[0] > 90);
    assert_true(pk[1] <= 1000 * (1 + 1e-6));
    assert_true(pk[2] <= 20000 * (1 + 1e-6));

    /* E-stop during a move back to 0 */
    pp_go(0, 0);
    cycles(300, false, 0);
    const double v_before = lsm_motion_demand(&g_app.mo, 0)->v_mm_s;
    assert_true(v_before < -50);
    size_t r1 = g_rec.n;
    cycles(1, true, 0);
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_FAULT_REACTION_ACTIVE);
    assert_true(count_sent(0x80u + NID, 0x9000) == 1);
    cycles(1000, true, 0);
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_FAULT);
    assert_int_equal(get(0x603F, 0), 0x9000);
    peaks(r1 - 3, g_rec.n, 0.001, pk); /* machine limits of the built-in machine: a 3000, j 60000 */
    assert_true(pk[1] <= 3000 * (1 + 1e-6));
    assert_true(pk[2] <= 60000 * (1 + 1e-6));
    assert_false(g_app.out_enable);
    /* fault reset refused while active, accepted after release */
    set(0x6040, 0, 0x00);
    set(0x6040, 0, 0x80);
    cycles(2, true, 0);
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_FAULT);
    cycles(2, false, 0);
    set(0x6040, 0, 0x00);
    set(0x6040, 0, 0x80);
    cycles(2, false, 0);
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_SWITCH_ON_DISABLED);
}

/* An E-stop inside a jerk pulse of a PP move (the acceleration still rising) begins in the cycle it is seen in:
 * the stop releases the jerk at once (jstop.h) instead of waiting for the end of the pulse (up to one acceleration
 * ramp, axprof.h), so the acceleration falls within the release time pi |j0| / (2 S) (S = 1.18e7 mm/s⁴ of the
 * machine: under 3 ms here) and the speed stays within what the release adds. */
static void test_estop_in_jerk_pulse(void **state)
{
    (void)state;
    boot(PATH_PLANNER, 0, 0);
    enable(0, LSM_CIA402_MODE_PP);
    pp_profile(0);
    pp_go(0, 40000);
    cycles(20, false, 0);
    const lsm_kin k0 = *lsm_motion_demand(&g_app.mo, 0);
    assert_true(k0.j_mm_s3 > 1000 && k0.a_mm_s2 > 0 && k0.a_mm_s2 < 1000); /* inside the first jerk pulse */
    cycles(1, true, 0);
    assert_int_equal(g_app.mo.ax[0].prof.mode, LSM_AXPROF_STOP);
    double a_max = 0, v_max = 0;
    unsigned i_amax = 0;
    for (unsigned i = 0; i < 200u; i++) {
        const lsm_kin *d = lsm_motion_demand(&g_app.mo, 0);
        if (d->a_mm_s2 > a_max) {
            a_max = d->a_mm_s2;
            i_amax = i;
        }
        v_max = fmax(v_max, d->v_mm_s);
        cycles(1, true, 0);
    }
    assert_true(i_amax <= 3u); /* the acceleration falls from the release on */
    /* the release adds at most pi j0² / (4 S) to a (jstop.h) */
    assert_true(a_max <= k0.a_mm_s2 + k0.j_mm_s3 * 0.001 + 3.1416 * k0.j_mm_s3 * k0.j_mm_s3 / (4 * 1.18e7) + 1e-6);
    assert_true(v_max < k0.v_mm_s + 10.0);
    assert_true(fabs(lsm_motion_demand(&g_app.mo, 0)->v_mm_s) == 0);
}

/* Set of set-points (0x6040 bit 5 = 0): the second target waits and starts after the first is reached (a rest
 * at the first target); single set-point (bit 5 = 1): a new target replaces the running move. */
static void test_pp_setpoints(void **state)
{
    (void)state;
    boot(PATH_PLANNER, 0, 0);
    enable(0, LSM_CIA402_MODE_PP);
    pp_profile(0);
    size_t r0 = g_rec.n;
    set(AX(0x607A, 0), 0, 10000);
    set(AX(0x6040, 0), 0, 0x1F);
    set(AX(0x6040, 0), 0, 0x0F);
    cycles(5, false, 0);
    set(AX(0x607A, 0), 0, 20000);
    set(AX(0x6040, 0), 0, 0x1F);
    set(AX(0x6040, 0), 0, 0x0F);
    cycles(1500, false, 0);
    assert_true(get(0x6041, 0) & 0x0400);
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm == 20.0);
    bool rested_at_first = false;
    for (size_t i = r0; i < g_rec.n; i++)
        rested_at_first |= g_rec.p[i] == 10.0 && g_rec.v[i] == 0 && g_rec.a[i] == 0;
    assert_true(rested_at_first);
    double pk[3];
    peaks(r0, g_rec.n, 0.001, pk);
    assert_true(pk[0] <= 100 * (1 + TOL_REL));
    /* a single set-point replaces a running move: it ends on the new target, never beyond the old one */
    r0 = g_rec.n;
    pp_go(0, 60000);
    cycles(250, false, 0);
    assert_true(lsm_motion_demand(&g_app.mo, 0)->v_mm_s > 50);
    pp_go(0, 30000);
    cycles(1500, false, 0);
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm == 30.0);
    assert_true(get(0x6041, 0) & 0x0400);
    peaks(r0, g_rec.n, 0.001, pk);
    assert_true(pk[1] <= 1000 * (1 + 1e-6));
    assert_true(pk[2] <= 20000 * (1 + 1e-6));
    for (size_t i = r0; i < g_rec.n; i++)
        assert_true(g_rec.p[i] < 60.0);
}

static void test_heartbeat_loss_and_busoff(void **state)
{
    (void)state;
    boot(PATH_PLANNER, 0x10, 150);
    const uint8_t hb = 0x05;
    rx(0x710, 1, &hb);
    enable(0, LSM_CIA402_MODE_PP);
    pp_profile(0);
    set(0x6085, 0, 1500000); /* quick stop 1500 mm/s² */
    pp_go(0, 200000);
    for (int i = 0; i < 10; i++) {
        cycles(50, false, 0);
        rx(0x710, 1, &hb);
    }
    size_t r1 = g_rec.n;
    cycles(400, false, 0); /* no more heartbeats: lost after 150 ms */
    assert_int_equal(lsm_canopen_nmt_state(&g_app.co), LSM_CO_NMT_PRE_OPERATIONAL);
    assert_true(count_sent(0x80u + NID, 0x8130) == 1);
    cycles(1000, false, 0);
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_SWITCH_ON_DISABLED);
    double pk[3];
    peaks(r1, g_rec.n, 0.001, pk);
    assert_true(pk[1] <= 1500 * (1 + 1e-6));
    assert_true(pk[2] <= 20000 * (1 + 1e-6));
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm < 200.0);

    /* bus-off during a move: silence, a jerk-limited stop, EMCY 0x8140 after the restart */
    boot(PATH_PLANNER, 0, 0);
    enable(0, LSM_CIA402_MODE_PP);
    pp_profile(0);
    set(0x6085, 0, 2000000);
    pp_go(0, 200000);
    cycles(500, false, 0);
    lsm_canopen_bus_event(&g_app.co, LSM_CAN_BUS_OFF, g_now);
    size_t before = g_n_sent, r2 = g_rec.n;
    cycles(800, false, 0);
    assert_int_equal(g_n_sent, before); /* nothing sent while bus-off */
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_SWITCH_ON_DISABLED);
    peaks(r2, g_rec.n, 0.001, pk);
    assert_true(pk[1] <= 2000 * (1 + 1e-6));
    lsm_canopen_bus_event(&g_app.co, LSM_CAN_BUS_OK, g_now);
    cycles(200, false, 0);
    assert_true(count_sent(0x80u + NID, 0x8140) == 1);
    assert_true(count_sent(0x700u + NID, 0) >= 1);
}

static uint32_t block(uint32_t seq, uint8_t type, const int32_t end[3], const int32_t *centre, uint32_t feed_um_s)
{
    return od_path_block(&g_app.co, seq, type, end, centre, feed_um_s);
}

static void path_case(uint8_t exec)
{
    boot(exec, 0, 0);
    for (unsigned k = 0; k < 3; k++)
        enable(k, LSM_CIA402_MODE_PATH);
    set(0x5000, 0, 1);
    const int32_t e1[3] = {20000, 0, 0}, e2[3] = {20000, 10000, 0}, e3[3] = {10000, 20000, 0}, c3[2] = {10000, 10000};
    assert_int_equal(block(1, 1, e1, NULL, 40000), 0);
    assert_int_equal(block(2, 1, e2, NULL, 40000), 0);
    assert_int_equal(block(3, 3, e3, c3, 30000), 0);
    cycles(3000, false, 0);
    assert_int_equal(get(0x6062, 0), 10000);
    assert_int_equal(get(0x6862, 0), 20000);
    assert_int_equal(get(0x5005, 0), 3);
    assert_true(g_app.co.path.n_underrun >= 1);
    /* after the underrun stop, a new block starts the motion again */
    const int32_t e4[3] = {0, 20000, 0};
    assert_int_equal(block(4, 1, e4, NULL, 40000), 0);
    cycles(50, false, 0);
    assert_true(g_app.mo.path_moving);
    cycles(1500, false, 0);
    assert_int_equal(get(0x6062, 0), 0);
    /* hold and resume on a long line, then clear while moving */
    const int32_t e5[3] = {0, 0, 0}, e6[3] = {60000, 0, 0};
    assert_int_equal(block(5, 1, e5, NULL, 40000), 0);
    cycles(200, false, 0);
    set(0x5000, 0, 2);
    cycles(400, false, 0);
    assert_int_equal(get(0x5002, 0), 3); /* HELD */
    const int64_t y_held = get(0x6862, 0);
    assert_true(y_held > 0 && y_held < 20000 && get(0x6062, 0) == 0);
    set(0x5000, 0, 3);
    cycles(1500, false, 0);
    assert_int_equal(get(0x6862, 0), 0);
    assert_int_equal(block(6, 1, e6, NULL, 40000), 0);
    cycles(400, false, 0);
    assert_true(g_app.mo.path_moving);
    set(0x5000, 0, 4);
    cycles(600, false, 0);
    assert_int_equal(get(0x5002, 0), 0);
    assert_false(g_app.mo.path_moving);
    const int64_t x_stop = get(0x6062, 0);
    assert_true(x_stop > 0 && x_stop < 60000);
}

static void test_path_planner(void **state)
{
    (void)state;
    path_case(PATH_PLANNER);
}

static void test_path_exact(void **state)
{
    (void)state;
    path_case(PATH_EXACT);
}

/* A dense G1 polyline (a gentle sine in XY, 0.5 mm steps at 5 mm/s, as CAM writes it) streamed with the flow control:
 * the planner holds points for arc fitting and answers LSM_E_FULL for a point it cannot take yet ("append it
 * again"); the feed must keep that block and retry it, never reject it. Every block runs once, the end is exact. */
static void test_path_dense_polyline(void **state)
{
    (void)state;
    boot(PATH_PLANNER, 0, 0);
    for (unsigned k = 0; k < 3; k++)
        enable(k, LSM_CIA402_MODE_PATH);
    set(0x5000, 0, 1);
    enum { N_POINTS = 200 };
    int32_t end[3] = {0, 0, 0};
    for (uint32_t i = 1; i <= N_POINTS; i++) {
        const double x_mm = 0.5 * i; /* 1000 counts/mm */
        end[0] = (int32_t)lround(1000.0 * x_mm);
        end[1] = (int32_t)lround(1000.0 * 2.0 * sin(x_mm / 8.0));
        unsigned waited = 0;
        while (block(i, 1, end, NULL, 5000) != 0) { /* the node's buffer is full: let it run */
            cycles(1, false, 0);
            assert_true(++waited < 5000u);
        }
    }
    cycles(25000, false, 0);
    assert_int_equal(count_sent(0x80u + NID, 0xFF01), 0); /* no block refused */
    assert_int_equal(g_app.mo.feed.rejected, 0);
    assert_int_equal(get(0x5005, 0), N_POINTS);
    assert_int_equal(get(0x6062, 0), end[0]);
    assert_int_equal(get(0x6862, 0), end[1]);
    assert_false(g_app.mo.path_moving);
}

static void test_csp(void **state)
{
    (void)state;
    boot(PATH_PLANNER, 0, 0);
    set(0x60C2, 1, 4); /* 4 ms */
    enable(0, LSM_CIA402_MODE_CSP);
    for (int i = 1; i <= 50; i++) {
        uint8_t d[8];
        lsm_can_put_u32(&d[0], (uint32_t)(i * 100));
        lsm_can_put_u32(&d[4], 0);
        rx(0x300 + NID, 8, d); /* RPDO2: 0x607A of axes 0, 1, applied at SYNC */
        rx(0x80, 0, NULL);
        cycles(4, false, 0);
        assert_int_equal(get(0x6062, 0), i * 100); /* reached at the end of each period */
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pp_and_estop),
        cmocka_unit_test(test_pp_setpoints),
        cmocka_unit_test(test_estop_in_jerk_pulse),
        cmocka_unit_test(test_heartbeat_loss_and_busoff),
        cmocka_unit_test(test_path_planner),
        cmocka_unit_test(test_path_exact),
        cmocka_unit_test(test_csp),
        cmocka_unit_test(test_path_dense_polyline),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
