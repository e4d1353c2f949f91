/*
 * test_canopen.c: the node as a whole, for the inputs that are not SDO/PDO traffic:
 *   - malformed frames at the node's entrance (RTR, 29-bit, DLC > 8, id > 0x7FF) and frames for others;
 *   - the E-stop edge: fastest jerk-limited stop on every axis, FAULT 0x9000, one EMCY, fault reset refused
 *     while the input stays active, release sends the error reset, a running path holds;
 *   - bus-off and recovery: communication-error reaction, nothing queued while off, EMCY 0x8140 after;
 *     error passive and RX overrun EMCYs; the TX-queue overrun EMCY;
 *   - drive-enable and in-position outputs; NULL arguments.
 */
#include "co_test_util.h"

static test_node tn;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(tn_init(&tn, 2, PATHCAP), LSM_OK);
    return 0;
}

static void proc(void)
{
    lsm_canopen_process(&tn.node, tn.now_us);
    drain(&tn);
}

static void test_malformed_entrance(void **state)
{
    (void)state;
    uint8_t d[8] = {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
    lsm_can_frame f = mkframe(0x605, 8, d);
    f.flags = LSM_CAN_FLAG_EXT;
    assert_int_equal(tn_rx(&tn, f), LSM_E_CO_FRAME);
    f.flags = LSM_CAN_FLAG_RTR;
    assert_int_equal(tn_rx(&tn, f), LSM_E_CO_FRAME);
    f.flags = 0;
    f.dlc = 9;
    assert_int_equal(tn_rx(&tn, f), LSM_E_CO_FRAME);
    f = mkframe(0x805, 8, d);
    assert_int_equal(tn_rx(&tn, f), LSM_E_CO_FRAME);
    drain(&tn);
    assert_int_equal(tn.n_out, 0);
    assert_int_equal(tn.node.malformed, 4);
    /* frames for other nodes or unknown ids: ignored quietly */
    assert_int_equal(tn_rx(&tn, mkframe(0x606, 8, d)), LSM_OK);
    assert_int_equal(tn_rx(&tn, mkframe(0x123, 3, d)), LSM_OK);
    drain(&tn);
    assert_int_equal(tn.n_out, 0);
    assert_int_equal(tn.node.malformed, 4);
    assert_int_equal(lsm_canopen_rx(NULL, &f, 0), LSM_E_NULL);
    assert_int_equal(lsm_canopen_rx(&tn.node, NULL, 0), LSM_E_NULL);
    assert_int_equal(lsm_canopen_process(NULL, 0), LSM_E_NULL);
}

static void test_estop(void **state)
{
    (void)state;
    tn_nmt(&tn, 0x01, NODE_ID);
    for (size_t k = 0; k < 2; k++) {
        assert_int_equal(sdo_write_u(&tn, (uint16_t)(0x6060 + 0x800 * k), 0, 0xFF, 1), 0);
        enable_axis(&tn, k);
    }
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_START, 1), 0);
    lsm_co_path_report rep = {0, 1000, false, false};
    lsm_co_path_update(&tn.node.path, &rep);
    lsm_cia402_feedback moving = {0, 0, 100, false};
    for (size_t k = 0; k < 2; k++)
        lsm_cia402_update(lsm_canopen_axis(&tn.node, k), &moving, 0);
    lsm_canopen_estop(&tn.node, false, 0); /* level low: nothing */
    drain(&tn);
    assert_int_equal(tn.n_out, 0);
    /* the edge */
    lsm_canopen_estop(&tn.node, true, 0);
    lsm_canopen_estop(&tn.node, true, 0); /* the level staying high is not a new edge */
    proc();
    lsm_can_frame e;
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x9000);
    assert_int_equal(e.data[3], 0xFF);
    assert_true(tn.node.machine_status & 0x01u);
    for (size_t k = 0; k < 2; k++) {
        lsm_cia402 *ax = lsm_canopen_axis(&tn.node, k);
        assert_int_equal(ax->state, LSM_CIA402_FAULT_REACTION_ACTIVE);
        assert_int_equal(lsm_cia402_stop_request(ax, NULL), LSM_CIA402_STOP_EMERGENCY);
        assert_int_equal(ax->error_code, 0x9000);
    }
    assert_int_equal(lsm_co_path_get_motion(&tn.node.path), LSM_CO_PATH_MOTION_QUICK);
    assert_true(lsm_canopen_drive_enable(&tn.node)); /* powered until stopped */
    axes_at_rest(&tn);
    rep.standstill = true;
    lsm_co_path_update(&tn.node.path, &rep);
    proc();
    assert_false(lsm_canopen_drive_enable(&tn.node));
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_FAULT);
    assert_int_equal(tn.node.path.state, LSM_CO_PATH_HELD); /* blocks kept */
    /* fault reset refused while the input is active */
    assert_int_equal(sdo_write_u(&tn, 0x6040, 0, 0x00, 2), 0);
    assert_int_equal(sdo_write_u(&tn, 0x6040, 0, 0x80, 2), 0);
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_FAULT);
    /* release: error reset EMCY; now the reset works */
    lsm_canopen_estop(&tn.node, false, 0);
    proc();
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x0000);
    assert_false(tn.node.machine_status & 0x01u);
    assert_int_equal(sdo_write_u(&tn, 0x6040, 0, 0x00, 2), 0);
    assert_int_equal(sdo_write_u(&tn, 0x6040, 0, 0x80, 2), 0);
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_SWITCH_ON_DISABLED);
    assert_int_equal(tn.node.axis[0].error_code, 0);
}

static void test_estop_survives_reset_node(void **state)
{
    (void)state;
    lsm_canopen_estop(&tn.node, true, 0);
    tn_nmt(&tn, 0x81, NODE_ID);
    proc();
    lsm_can_frame b;
    assert_int_equal(count_id(&tn, 0x705, &b), 1); /* rebooted */
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_FAULT);
    assert_int_equal(tn.node.axis[0].error_code, 0x9000);
    assert_true(lsm_co_emcy_is_active(&tn.node.emcy, 0x9000, 0xFF));
}

static void test_bus_off(void **state)
{
    (void)state;
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 10, 2), 0);
    tn_nmt(&tn, 0x01, NODE_ID);
    enable_axis(&tn, 0);
    lsm_canopen_bus_event(&tn.node, LSM_CAN_BUS_OFF, 1000);
    assert_true(tn.node.machine_status & 0x04u);
    /* communication error: 0x1029 = 0 -> PRE-OPERATIONAL, 0x6007 = 3 -> quick stop (at rest: SOD) */
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_PRE_OPERATIONAL);
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_SWITCH_ON_DISABLED);
    /* nothing is queued while off: heartbeats, SDO answers */
    for (uint32_t t = 2000; t <= 50000; t += 1000) {
        tn.now_us = t;
        assert_int_equal(lsm_canopen_process(&tn.node, t), LSM_E_CO_BUS_OFF);
        drain(&tn);
        assert_int_equal(tn.n_out, 0);
    }
    uint8_t d[8] = {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
    assert_int_equal(tn_rx(&tn, mkframe(0x605, 8, d)), LSM_OK);
    drain(&tn);
    assert_int_equal(tn.n_out, 0);
    assert_true(tn.node.emcy.error_register & LSM_CO_ERREG_COMM);
    /* recovery: EMCY 0x8140, then the error reset; traffic again */
    lsm_canopen_bus_event(&tn.node, LSM_CAN_BUS_OK, 51000);
    drain(&tn);
    assert_int_equal(tn.n_out, 2);
    assert_int_equal(tn.out[0].id, 0x085);
    assert_int_equal(lsm_can_get_u16(&tn.out[0].data[0]), 0x8140);
    assert_int_equal(lsm_can_get_u16(&tn.out[1].data[0]), 0x0000);
    assert_int_equal(tn.node.emcy.error_register, 0);
    tn.now_us = 60000;
    assert_int_equal(lsm_canopen_process(&tn.node, tn.now_us), LSM_OK);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x705, NULL), 1);
    /* the master brings it back */
    tn_nmt(&tn, 0x01, NODE_ID);
    assert_int_equal(lsm_canopen_nmt_state(&tn.node), LSM_CO_NMT_OPERATIONAL);
}

static void test_bus_warnings(void **state)
{
    (void)state;
    lsm_canopen_bus_event(&tn.node, LSM_CAN_BUS_ERROR_PASSIVE, 0);
    lsm_canopen_bus_event(&tn.node, LSM_CAN_BUS_ERROR_PASSIVE, 0); /* once per entry */
    drain(&tn);
    assert_int_equal(tn.n_out, 1);
    assert_int_equal(lsm_can_get_u16(&tn.out[0].data[0]), 0x8120);
    lsm_canopen_bus_event(&tn.node, LSM_CAN_BUS_OK, 0);
    lsm_canopen_bus_event(&tn.node, LSM_CAN_BUS_ERROR_PASSIVE, 0);
    lsm_canopen_bus_event(&tn.node, LSM_CAN_BUS_RX_OVERRUN, 0);
    drain(&tn);
    assert_int_equal(tn.n_out, 2);
    assert_int_equal(lsm_can_get_u16(&tn.out[1].data[0]), 0x8110);
    assert_int_equal(tn.out[1].data[3], 1);
}

static void test_tx_overrun(void **state)
{
    (void)state;
    /* fill the queue with SDO answers that nobody drains */
    uint8_t d[8] = {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
    for (size_t i = 0; i < TXCAP + 5; i++)
        assert_int_equal(tn_rx(&tn, mkframe(0x605, 8, d)), LSM_OK);
    assert_int_equal(tn.node.txq.dropped, 5);
    lsm_canopen_process(&tn.node, 0); /* no room yet: no EMCY either */
    lsm_can_frame f;
    size_t n = 0;
    while (lsm_canopen_tx_pop(&tn.node, &f))
        n++;
    assert_int_equal(n, TXCAP);
    proc();
    lsm_can_frame e;
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x8110);
    assert_int_equal(lsm_can_get_u32(&e.data[4]), 5);
    proc();
    assert_int_equal(count_id(&tn, 0x085, NULL), 0); /* reported once */
}

static void test_outputs(void **state)
{
    (void)state;
    assert_false(lsm_canopen_drive_enable(&tn.node));
    assert_false(lsm_canopen_in_position(&tn.node));
    enable_axis(&tn, 0);
    assert_true(lsm_canopen_drive_enable(&tn.node));
    assert_false(lsm_canopen_in_position(&tn.node)); /* axis 1 is not enabled */
    enable_axis(&tn, 1);
    assert_true(lsm_canopen_in_position(&tn.node));
    lsm_cia402_feedback off = {100, 50, 0, true};
    lsm_cia402_update(lsm_canopen_axis(&tn.node, 1), &off, 0);
    assert_false(lsm_canopen_in_position(&tn.node));
    assert_null(lsm_canopen_axis(&tn.node, 2));
    assert_non_null(lsm_canopen_od(&tn.node));
    size_t n = 0;
    assert_non_null(lsm_canopen_od_table(&n));
    assert_true(n > 50);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_malformed_entrance, setup),
        cmocka_unit_test_setup(test_estop, setup),
        cmocka_unit_test_setup(test_estop_survives_reset_node, setup),
        cmocka_unit_test_setup(test_bus_off, setup),
        cmocka_unit_test_setup(test_bus_warnings, setup),
        cmocka_unit_test_setup(test_tx_overrun, setup),
        cmocka_unit_test_setup(test_outputs, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
