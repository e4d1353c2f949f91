/*
 * test_co_nmt.c: NMT slave and heartbeats at frame level, with time as an argument:
 *   boot-up frame; every NMT command (addressed, broadcast, other node, unknown, malformed); which services
 *   run in which state; reset communication vs reset node (and that reset node first stops the motion);
 *   heartbeat producer period to the microsecond, late calls, period changes, 32-bit time wrap;
 *   heartbeat consumer: not monitored before the first heartbeat, timeout exactly after the consumer time,
 *   EMCY 0x8130 and its reset, the 0x1029 NMT reaction (0/1/2) and the 0x6007 axis reaction (0/1/2/3),
 *   malformed heartbeats, 0x1016 validation (0x06040043, 0x06090030).
 */
#include "co_test_util.h"

static test_node tn;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(tn_init(&tn, 1, PATHCAP), LSM_OK);
    return 0;
}

static void step_to(uint32_t t)
{
    tn.now_us = t;
    lsm_canopen_process(&tn.node, t);
    drain(&tn);
}

static void test_bootup(void **state)
{
    (void)state;
    memset(&tn, 0, sizeof tn);
    lsm_canopen_config c = lsm_canopen_default_config();
    c.node_id = NODE_ID;
    c.tx_storage = tn.tx;
    c.tx_cap = TXCAP;
    c.path_storage = tn.blocks;
    c.path_cap = PATHCAP;
    assert_int_equal(lsm_canopen_init(&tn.node, &c, 1234), LSM_OK);
    drain(&tn);
    assert_int_equal(tn.n_out, 1);
    assert_int_equal(tn.out[0].id, 0x705);
    assert_int_equal(tn.out[0].dlc, 1);
    assert_int_equal(tn.out[0].data[0], 0x00);
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_PRE_OPERATIONAL);
    /* default heartbeat 100 ms: first one a period after boot-up, with the pre-operational state */
    step_to(1234 + 99999);
    assert_int_equal(count_id(&tn, 0x705, NULL), 0);
    step_to(1234 + 100000);
    lsm_can_frame hb;
    assert_int_equal(count_id(&tn, 0x705, &hb), 1);
    assert_int_equal(hb.data[0], 0x7F);
    /* bad configurations */
    c.node_id = 0;
    assert_int_equal(lsm_canopen_init(&tn.node, &c, 0), LSM_E_CO_NODE_ID);
    c.node_id = 128;
    assert_int_equal(lsm_canopen_init(&tn.node, &c, 0), LSM_E_CO_NODE_ID);
    c.node_id = 1;
    c.n_axes = 0;
    assert_int_equal(lsm_canopen_init(&tn.node, &c, 0), LSM_E_CO_AXES);
    c.n_axes = LSM_MAX_AXES + 1;
    assert_int_equal(lsm_canopen_init(&tn.node, &c, 0), LSM_E_CO_AXES);
    c.n_axes = 1;
    c.tx_cap = 0;
    assert_int_equal(lsm_canopen_init(&tn.node, &c, 0), LSM_E_ARG);
    c.tx_cap = TXCAP;
    c.path_storage = NULL;
    assert_int_equal(lsm_canopen_init(&tn.node, &c, 0), LSM_E_NULL);
}

static void test_nmt_commands(void **state)
{
    (void)state;
    tn_nmt(&tn, 0x01, NODE_ID);
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_OPERATIONAL);
    tn_nmt(&tn, 0x80, NODE_ID);
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_PRE_OPERATIONAL);
    tn_nmt(&tn, 0x02, 0); /* broadcast */
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_STOPPED);
    tn_nmt(&tn, 0x01, NODE_ID + 1); /* another node */
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_STOPPED);
    tn_nmt(&tn, 0x03, NODE_ID); /* unknown command: ignored */
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_STOPPED);
    tn_nmt(&tn, 0x01, 0);
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_OPERATIONAL);
    /* malformed NMT frames change nothing */
    uint8_t d[3] = {0x02, NODE_ID, 0};
    assert_int_equal(tn_rx(&tn, mkframe(0x000, 1, d)), LSM_E_CO_FRAME);
    assert_int_equal(tn_rx(&tn, mkframe(0x000, 3, d)), LSM_E_CO_FRAME);
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_OPERATIONAL);
    assert_int_equal(tn.node.nmt.malformed, 2);
    drain(&tn);
}

static void test_services_per_state(void **state)
{
    (void)state;
    uint8_t up[8] = {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
    uint8_t rp[2] = {0x06, 0x00};
    uint32_t before = tn.node.axis[0].controlword;
    /* PRE-OPERATIONAL: SDO yes, RPDO no */
    assert_int_equal(tn_rx(&tn, mkframe(0x605, 8, up)), LSM_OK);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x585, NULL), 1);
    assert_int_equal(tn_rx(&tn, mkframe(0x205, 2, rp)), LSM_E_CO_NMT_STATE);
    assert_int_equal(tn.node.axis[0].controlword, before);
    /* STOPPED: no SDO answer, heartbeats still go out with state 4 */
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 10, 2), 0);
    tn_nmt(&tn, 0x02, NODE_ID);
    assert_int_equal(tn_rx(&tn, mkframe(0x605, 8, up)), LSM_E_CO_NMT_STATE);
    drain(&tn);
    assert_int_equal(tn.n_out, 0);
    step_to(10000);
    lsm_can_frame hb;
    assert_int_equal(count_id(&tn, 0x705, &hb), 1);
    assert_int_equal(hb.data[0], 0x04);
    /* OPERATIONAL: RPDO applied */
    tn_nmt(&tn, 0x01, NODE_ID);
    assert_int_equal(tn_rx(&tn, mkframe(0x205, 2, rp)), LSM_OK);
    assert_int_equal(tn.node.axis[0].controlword, 0x06);
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_READY_TO_SWITCH_ON);
    step_to(20000);
    assert_int_equal(count_id(&tn, 0x705, &hb), 1);
    assert_int_equal(hb.data[0], 0x05);
}

static void test_producer_timing(void **state)
{
    (void)state;
    tn.now_us = 5000;
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 100, 2), 0); /* restarts the timer at 5 ms */
    step_to(104999);
    assert_int_equal(count_id(&tn, 0x705, NULL), 0);
    step_to(105000);
    assert_int_equal(count_id(&tn, 0x705, NULL), 1);
    step_to(105000); /* same instant again: nothing */
    assert_int_equal(count_id(&tn, 0x705, NULL), 0);
    step_to(205000);
    assert_int_equal(count_id(&tn, 0x705, NULL), 1);
    /* called late (350 ms later): one frame, not a burst, and the next a full period later */
    step_to(555000);
    assert_int_equal(count_id(&tn, 0x705, NULL), 1);
    step_to(654999);
    assert_int_equal(count_id(&tn, 0x705, NULL), 0);
    step_to(655000);
    assert_int_equal(count_id(&tn, 0x705, NULL), 1);
    /* 0 switches the producer off */
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 0, 2), 0);
    step_to(2000000);
    assert_int_equal(count_id(&tn, 0x705, NULL), 0);
}

static void test_time_wrap(void **state)
{
    (void)state;
    uint32_t t0 = 0xFFFFFFFFu - 30000u; /* 30 ms before the 32-bit clock wraps */
    tn.now_us = t0;
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 50, 2), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1016, 1, (0x7Fu << 16) | 40u, 4), 0);
    uint8_t s = 0x05;
    tn.now_us = t0 + 10000u;
    assert_int_equal(tn_rx(&tn, mkframe(0x77F, 1, &s)), LSM_OK);
    step_to(t0 + 49999u);
    assert_int_equal(count_id(&tn, 0x705, NULL), 0);
    step_to(t0 + 50000u); /* after the wrap */
    assert_true(t0 + 50000u < t0);
    assert_int_equal(count_id(&tn, 0x705, NULL), 1);
    assert_int_equal(count_id(&tn, 0x085, NULL), 0); /* consumer: 40 ms since 10 ms: not late yet */
    step_to(t0 + 50001u);
    assert_int_equal(count_id(&tn, 0x085, NULL), 1); /* now it is */
}

static void test_reset_communication(void **state)
{
    (void)state;
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 77, 2), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1800, 1, 0xC0000185u, 4), 0); /* TPDO1 off */
    assert_int_equal(sdo_write_u(&tn, 0x6081, 0, 4242, 4), 0);        /* an application object */
    tn_nmt(&tn, 0x01, NODE_ID);
    tn_nmt(&tn, 0x82, NODE_ID);
    drain(&tn);
    lsm_can_frame f;
    assert_int_equal(count_id(&tn, 0x705, &f), 1);
    assert_int_equal(f.data[0], 0x00);
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_PRE_OPERATIONAL);
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x1017, 0, &v), 0);
    assert_int_equal(v, 0); /* tn_init's default */
    assert_int_equal(sdo_read_u(&tn, 0x1800, 1, &v), 0);
    assert_int_equal(v, 0x40000185u);
    assert_int_equal(sdo_read_u(&tn, 0x6081, 0, &v), 0);
    assert_int_equal(v, 4242); /* untouched by a communication reset */
}

static void test_reset_node_stops_first(void **state)
{
    (void)state;
    assert_int_equal(sdo_write_u(&tn, 0x6081, 0, 4242, 4), 0);
    enable_axis(&tn, 0);
    lsm_cia402 *ax = lsm_canopen_axis(&tn.node, 0);
    lsm_cia402_feedback moving = {100, 100, 5000, false};
    lsm_cia402_update(ax, &moving, tn.now_us);
    tn_nmt(&tn, 0x81, 0);
    step_to(1000);
    assert_int_equal(count_id(&tn, 0x705, NULL), 0); /* not yet: the axis is still moving */
    lsm_cia402_stop_req req;
    assert_int_equal(lsm_cia402_stop_request(ax, &req), LSM_CIA402_STOP_QUICK);
    assert_int_equal(req.decel, ax->quick_stop_decel);
    lsm_cia402_feedback rest = {180, 180, 0, true};
    lsm_cia402_update(ax, &rest, tn.now_us);
    step_to(2000);
    lsm_can_frame f;
    assert_int_equal(count_id(&tn, 0x705, &f), 1);
    assert_int_equal(f.data[0], 0x00);
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x6081, 0, &v), 0);
    assert_int_equal(v, 10000); /* back to its default */
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_SWITCH_ON_DISABLED);
}

static void consumer_setup(uint32_t hb_ms)
{
    assert_int_equal(sdo_write_u(&tn, 0x1016, 1, (0x7Fu << 16) | hb_ms, 4), 0);
}

static void heartbeat_from_master(uint32_t t)
{
    uint8_t s = 0x05;
    tn.now_us = t;
    assert_int_equal(tn_rx(&tn, mkframe(0x77F, 1, &s)), LSM_OK);
}

static void test_consumer_timeout_reaction(void **state)
{
    (void)state;
    consumer_setup(50);
    tn_nmt(&tn, 0x01, NODE_ID);
    enable_axis(&tn, 0);
    step_to(1000000); /* no heartbeat yet: not monitored, no timeout however long */
    assert_int_equal(count_id(&tn, 0x085, NULL), 0);
    heartbeat_from_master(1010000);
    step_to(1060000); /* exactly the consumer time: still fine */
    assert_int_equal(count_id(&tn, 0x085, NULL), 0);
    heartbeat_from_master(1060000);
    step_to(1110000);
    assert_int_equal(count_id(&tn, 0x085, NULL), 0);
    step_to(1110001);
    lsm_can_frame e;
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x8130);
    assert_true(e.data[2] & LSM_CO_ERREG_COMM);
    assert_int_equal(e.data[3], 0x7F); /* which node was lost */
    assert_true(tn.node.machine_status & 0x02u);
    /* 0x1029 = 0: OPERATIONAL -> PRE-OPERATIONAL; 0x6007 = 3: quick stop (at rest: at once to SOD) */
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_PRE_OPERATIONAL);
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_SWITCH_ON_DISABLED);
    step_to(1200000); /* reported once */
    assert_int_equal(count_id(&tn, 0x085, NULL), 0);
    /* the master comes back: error reset EMCY */
    heartbeat_from_master(1250000);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x0000);
    assert_int_equal(e.data[2], 0);
    step_to(1250001);
    assert_false(tn.node.machine_status & 0x02u);
}

static void lose_master(void)
{
    heartbeat_from_master(10000);
    step_to(10000 + 50001);
    assert_int_equal(count_id(&tn, 0x085, NULL), 1);
}

static void test_comm_error_behaviour(void **state)
{
    (void)state;
    consumer_setup(50);
    assert_int_equal(sdo_write_u(&tn, 0x1029, 1, 1, 1), 0); /* no change */
    tn_nmt(&tn, 0x01, NODE_ID);
    lose_master();
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_OPERATIONAL);
    heartbeat_from_master(100000);
    assert_int_equal(sdo_write_u(&tn, 0x1029, 1, 2, 1), 0); /* stopped */
    heartbeat_from_master(200000);
    step_to(250001);
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_STOPPED);
}

static void test_abort_connection_options(void **state)
{
    (void)state;
    consumer_setup(50);
    assert_int_equal(sdo_write_u(&tn, 0x1029, 1, 1, 1), 0);
    lsm_cia402 *ax = lsm_canopen_axis(&tn.node, 0);
    lsm_cia402_feedback moving = {0, 0, 1000, false};
    lsm_cia402_feedback rest = {0, 0, 0, true};

    /* 0: no action */
    assert_int_equal(sdo_write_u(&tn, 0x6007, 0, 0, 2), 0);
    enable_axis(&tn, 0);
    lose_master();
    assert_int_equal(ax->state, LSM_CIA402_OPERATION_ENABLED);
    assert_int_equal(lsm_cia402_stop_request(ax, NULL), LSM_CIA402_STOP_NONE);

    /* 1: fault 0x8130 through fault reaction (emergency stop) */
    assert_true(setup(NULL) == 0);
    consumer_setup(50);
    assert_int_equal(sdo_write_u(&tn, 0x6007, 0, 1, 2), 0);
    enable_axis(&tn, 0);
    lsm_cia402_update(ax, &moving, 0);
    lose_master();
    assert_int_equal(ax->state, LSM_CIA402_FAULT_REACTION_ACTIVE);
    assert_int_equal(lsm_cia402_stop_request(ax, NULL), LSM_CIA402_STOP_EMERGENCY);
    lsm_cia402_update(ax, &rest, tn.now_us);
    assert_int_equal(ax->state, LSM_CIA402_FAULT);
    assert_int_equal(ax->error_code, 0x8130);

    /* 2: disable voltage: quick stop, then SWITCH ON DISABLED */
    assert_true(setup(NULL) == 0);
    consumer_setup(50);
    assert_int_equal(sdo_write_u(&tn, 0x6007, 0, 2, 2), 0);
    enable_axis(&tn, 0);
    lsm_cia402_update(ax, &moving, 0);
    lose_master();
    assert_int_equal(ax->state, LSM_CIA402_OPERATION_ENABLED);
    assert_int_equal(lsm_cia402_stop_request(ax, NULL), LSM_CIA402_STOP_QUICK);
    lsm_cia402_update(ax, &rest, tn.now_us);
    assert_int_equal(ax->state, LSM_CIA402_SWITCH_ON_DISABLED);

    /* 3 (default): quick stop -> QUICK STOP ACTIVE, then SOD (0x605A = 2) */
    assert_true(setup(NULL) == 0);
    consumer_setup(50);
    enable_axis(&tn, 0);
    lsm_cia402_update(ax, &moving, 0);
    lose_master();
    assert_int_equal(ax->state, LSM_CIA402_QUICK_STOP_ACTIVE);
    assert_int_equal(lsm_cia402_stop_request(ax, NULL), LSM_CIA402_STOP_QUICK);
    lsm_cia402_update(ax, &rest, tn.now_us);
    assert_int_equal(ax->state, LSM_CIA402_SWITCH_ON_DISABLED);
}

static void test_malformed_heartbeat(void **state)
{
    (void)state;
    consumer_setup(50);
    heartbeat_from_master(0);
    uint8_t s[2] = {0x05, 0x00};
    tn.now_us = 40000;
    assert_int_equal(tn_rx(&tn, mkframe(0x77F, 0, s)), LSM_E_CO_FRAME);
    assert_int_equal(tn_rx(&tn, mkframe(0x77F, 2, s)), LSM_E_CO_FRAME);
    step_to(50001); /* the malformed ones did not count */
    assert_int_equal(count_id(&tn, 0x085, NULL), 1);
}

static void test_consumer_validation(void **state)
{
    (void)state;
    assert_int_equal(sdo_write_u(&tn, 0x1016, 1, (0x10u << 16) | 100u, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1016, 2, (0x10u << 16) | 200u, 4), LSM_CO_ABORT_PARAM_INCOMPAT);
    assert_int_equal(sdo_write_u(&tn, 0x1016, 2, (0x10u << 16) | 0u, 4), 0); /* time 0: disabled, allowed */
    assert_int_equal(sdo_write_u(&tn, 0x1016, 2, (0x11u << 16) | 200u, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1016, 2, 0x01110000u | 200u, 4), LSM_CO_ABORT_VALUE);
    assert_int_equal(sdo_write_u(&tn, 0x1016, 2, (0x80u << 16) | 200u, 4), LSM_CO_ABORT_VALUE);
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x1016, 0, &v), 0);
    assert_int_equal(v, 2);
    assert_int_equal(sdo_read_u(&tn, 0x1016, 2, &v), 0);
    assert_int_equal(v, (0x11u << 16) | 200u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bootup),
        cmocka_unit_test_setup(test_nmt_commands, setup),
        cmocka_unit_test_setup(test_services_per_state, setup),
        cmocka_unit_test_setup(test_producer_timing, setup),
        cmocka_unit_test_setup(test_time_wrap, setup),
        cmocka_unit_test_setup(test_reset_communication, setup),
        cmocka_unit_test_setup(test_reset_node_stops_first, setup),
        cmocka_unit_test_setup(test_consumer_timeout_reaction, setup),
        cmocka_unit_test_setup(test_comm_error_behaviour, setup),
        cmocka_unit_test_setup(test_abort_connection_options, setup),
        cmocka_unit_test_setup(test_malformed_heartbeat, setup),
        cmocka_unit_test_setup(test_consumer_validation, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
