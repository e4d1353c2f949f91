/*
 * test_node_app.c: what lissom-node's application (node_app.h) adds to the firmware's CANopen node and CiA 402
 * motion layer, driven without CAN or a clock: frames and object writes go in directly (lsm_co_od_set_int has the
 * same checks and hooks as an SDO download), time advances by one cycle per node_app_cycle. The motion layer's
 * own scenarios (PP profile limits, set-points, E-stop / quick-stop / bus-off stops and fault reset, the path
 * underrun restart, hold / resume / clear, dense polylines, CSP) are tested once, in tests/motion/test_motion.c;
 * here only the node's own wiring:
 *   - node_app_init: bad configurations refused; frames through node_app_rx (refused ones counted);
 *   - PP through the simulated drives: the drive's feedback (0x6064) follows the demand and settles on the
 *     target; the E-stop input: FAULT, EMCY 0x9000 out of node_app_tx_pop, drive
 *     enable off, the stop within the built-in machine's a and j (its limits reach the motion layer);
 *   - the configured master heartbeat (EMCY 0x8130) and node_app_bus_event (silence while bus-off, EMCY 0x8140);
 *   - both path executors chosen by the configuration, with the drives following to the exact end (the
 *     in-position output).
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

#include "cia402_test_od.h"
#include "node_app.h"

#define NID 3u

static node_app g_app; /* large: static storage */

typedef struct rec {
    double p[20000];
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
    while (node_app_tx_pop(&g_app, &f)) {
        if (g_n_sent < sizeof g_sent / sizeof g_sent[0])
            g_sent[g_n_sent++] = f;
    }
}

static void cycles(unsigned n, bool estop, unsigned axis)
{
    for (unsigned i = 0; i < n; i++) {
        g_now += g_app.cfg.cycle_us;
        node_app_cycle(&g_app, estop, g_now);
        drain();
        if (g_rec.n < sizeof g_rec.p / sizeof g_rec.p[0]) {
            g_rec.p[g_rec.n] = lsm_motion_demand(&g_app.mo, axis)->s_mm;
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
    (void)node_app_rx(&g_app, &f, g_now);
}

static void set(uint16_t idx, uint8_t sub, int64_t v)
{
    od_set(&g_app.co, g_now, idx, sub, v);
}

static int64_t get(uint16_t idx, uint8_t sub)
{
    return od_get(&g_app.co, idx, sub);
}

static node_app_config config(uint8_t path_exec, uint16_t master, uint16_t master_ms)
{
    node_app_config c;
    memset(&c, 0, sizeof c);
    c.node_id = NID;
    c.n_axes = 3;
    c.cycle_us = 1000;
    c.heartbeat_ms = 100;
    c.master_id = (uint8_t)master;
    c.master_timeout_ms = master_ms;
    c.path_slots = 16;
    c.path_exec = path_exec;
    c.lookahead_blocks = 32;
    return c;
}

static void boot(uint8_t path_exec, uint16_t master, uint16_t master_ms)
{
    const node_app_config c = config(path_exec, master, master_ms);
    g_now = 0;
    g_n_sent = 0;
    g_rec.n = 0;
    assert_int_equal(node_app_init(&g_app, &c, g_now), LSM_OK);
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

/* Largest |finite difference| of order 1..3 of rec[from..to) (velocity, acceleration, jerk). */
static void peaks(size_t from, size_t to, double dt, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    for (size_t i = from + 3; i < to; i++) {
        const double *p = g_rec.p;
        double v = (p[i] - p[i - 1]) / dt;
        double a = (p[i] - 2 * p[i - 1] + p[i - 2]) / (dt * dt);
        double j = (p[i] - 3 * p[i - 1] + 3 * p[i - 2] - p[i - 3]) / (dt * dt * dt);
        out[0] = fmax(out[0], fabs(v));
        out[1] = fmax(out[1], fabs(a));
        out[2] = fmax(out[2], fabs(j));
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

static void test_init_and_rx(void **state)
{
    (void)state;
    const node_app_config good = config(NODE_APP_PATH_PLANNER, 0, 0);
    node_app_config c = good;
    c.n_axes = 0;
    assert_int_equal(node_app_init(&g_app, &c, 0), LSM_E_ARG);
    c = good;
    c.cycle_us = 50;
    assert_int_equal(node_app_init(&g_app, &c, 0), LSM_E_ARG);
    c = good;
    c.path_slots = NODE_APP_PATH_SLOTS_MAX + 1;
    assert_int_equal(node_app_init(&g_app, &c, 0), LSM_E_ARG);
    c = good;
    c.path_exec = 7;
    assert_int_equal(node_app_init(&g_app, &c, 0), LSM_E_ARG);
    sim_machine one;
    node_app_default_machine(&one, 1);
    c = good;
    c.machine = &one; /* 3 axes asked of a 1-axis machine */
    assert_int_equal(node_app_init(&g_app, &c, 0), LSM_E_ARG);
    c = good;
    c.node_id = 0;
    assert_int_equal(node_app_init(&g_app, &c, 0), LSM_E_CO_NODE_ID);

    g_now = 0;
    assert_int_equal(node_app_init(&g_app, &good, g_now), LSM_OK);
    const uint8_t d[8] = {0};
    rx(0x300 + NID, 8, d); /* PRE-OPERATIONAL: no PDOs */
    assert_int_equal(g_app.rx_errors, 1);
    const uint8_t start[2] = {0x01, NID};
    rx(0, 2, start);
    cycles(2, false, 0);
    assert_int_equal(lsm_canopen_nmt_state(&g_app.co), LSM_CO_NMT_OPERATIONAL);
    assert_int_equal(g_app.rx_errors, 1);
}

static void test_pp_drive_and_estop(void **state)
{
    (void)state;
    boot(NODE_APP_PATH_PLANNER, 0, 0);
    enable(0, LSM_CIA402_MODE_PP);
    assert_true(g_app.out_enable);
    pp_profile(0);
    pp_go(0, 40000);
    cycles(300, false, 0);
    /* the feedback is the simulated drive's, not the demand: a following error of some um (feed-forward on) */
    const double ferr = fabs(lsm_motion_demand(&g_app.mo, 0)->s_mm - g_app.actual[0]);
    assert_true(ferr > 1e-4 && ferr < 0.1);
    assert_int_equal(get(0x6064, 0), (int64_t)lround(1000.0 * g_app.actual[0]));
    cycles(1200, false, 0);
    assert_true(lsm_motion_demand(&g_app.mo, 0)->s_mm == 40.0);
    assert_true(get(0x6041, 0) & 0x0400);
    assert_true(llabs(get(0x6064, 0) - 40000) <= 5);

    /* the E-stop input during a move back to 0 */
    pp_go(0, 0);
    cycles(300, false, 0);
    assert_true(lsm_motion_demand(&g_app.mo, 0)->v_mm_s < -50);
    size_t r1 = g_rec.n;
    cycles(1, true, 0);
    assert_true(g_app.estop);
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_FAULT_REACTION_ACTIVE);
    assert_true(count_sent(0x80u + NID, 0x9000) == 1);
    cycles(1000, true, 0);
    assert_int_equal(lsm_canopen_axis(&g_app.co, 0)->state, LSM_CIA402_FAULT);
    double pk[3];
    peaks(r1 - 3, g_rec.n, 0.001, pk); /* the built-in machine: a 3000, j 60000 */
    assert_true(pk[1] <= 3000 * (1 + 1e-6) && pk[1] > 1000);
    assert_true(pk[2] <= 60000 * (1 + 1e-6));
    assert_false(g_app.out_enable);
}

static void test_heartbeat_loss_and_busoff(void **state)
{
    (void)state;
    boot(NODE_APP_PATH_PLANNER, 0x10, 150); /* the configured master: node 0x10, 150 ms */
    const uint8_t hb = 0x05;
    rx(0x710, 1, &hb);
    cycles(100, false, 0);
    assert_int_equal(lsm_canopen_nmt_state(&g_app.co), LSM_CO_NMT_OPERATIONAL);
    cycles(100, false, 0); /* no more heartbeats: lost after 150 ms */
    assert_int_equal(lsm_canopen_nmt_state(&g_app.co), LSM_CO_NMT_PRE_OPERATIONAL);
    assert_true(count_sent(0x80u + NID, 0x8130) == 1);

    boot(NODE_APP_PATH_PLANNER, 0, 0);
    cycles(200, false, 0);
    node_app_bus_event(&g_app, LSM_CAN_BUS_OFF, g_now);
    size_t before = g_n_sent;
    cycles(800, false, 0);
    assert_int_equal(g_n_sent, before); /* nothing sent while bus-off (8 heartbeats due) */
    node_app_bus_event(&g_app, LSM_CAN_BUS_OK, g_now);
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
    assert_true(llabs(get(0x6064, 0) - 10000) <= 5 && llabs(get(0x6864, 0) - 20000) <= 5); /* the drives followed */
    assert_true(g_app.out_inpos);
}

static void test_path_planner(void **state)
{
    (void)state;
    path_case(NODE_APP_PATH_PLANNER);
}

static void test_path_exact(void **state)
{
    (void)state;
    path_case(NODE_APP_PATH_EXACT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init_and_rx),
        cmocka_unit_test(test_pp_drive_and_estop),
        cmocka_unit_test(test_heartbeat_loss_and_busoff),
        cmocka_unit_test(test_path_planner),
        cmocka_unit_test(test_path_exact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
