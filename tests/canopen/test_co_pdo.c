/*
 * test_co_pdo.c: SYNC, RPDO and TPDO at frame level: the default mapping; TPDO telemetry at each SYNC
 * (type 1), every n-th SYNC (type n), acyclic synchronous (type 0), change-driven with inhibit time and
 * event timer (type 255); immediate vs synchronous RPDO; DLC errors (EMCY 0x8210 / 0x8220 once, 0x8240
 * for SYNC); no PDO outside OPERATIONAL; the CiA 301 mapping procedure over SDO with each refusal
 * (0x08000022, 0x06040041, 0x06040042, 0x06090031, 0x06090030) and the new mapping in use; 0x1005.
 */
#include "co_test_util.h"

static test_node tn;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(tn_init(&tn, 3, PATHCAP), LSM_OK);
    return 0;
}

static void sync_frame(void)
{
    assert_int_equal(tn_rx(&tn, mkframe(0x080, 0, NULL)), LSM_OK);
    drain(&tn);
}

static void proc(uint32_t t)
{
    tn.now_us = t;
    lsm_canopen_process(&tn.node, t);
    drain(&tn);
}

static void set_actual(size_t k, int32_t pos)
{
    lsm_cia402_feedback fb = {pos, pos, 0, true};
    lsm_cia402_update(lsm_canopen_axis(&tn.node, k), &fb, tn.now_us);
}

static void test_default_mapping(void **state)
{
    (void)state;
    static const struct {
        uint16_t idx;
        uint8_t sub;
        uint32_t v;
    } want[] = {
        {0x1400, 1, 0x205},      {0x1400, 2, 255},        {0x1600, 0, 1},          {0x1600, 1, 0x60400010},
        {0x1401, 1, 0x305},      {0x1401, 2, 1},          {0x1601, 0, 2},          {0x1601, 1, 0x607A0020},
        {0x1601, 2, 0x687A0020}, {0x1402, 1, 0x405},      {0x1602, 0, 1},          {0x1602, 1, 0x707A0020},
        {0x1403, 1, 0x505},      {0x1603, 0, 2},          {0x1603, 1, 0x68400010}, {0x1603, 2, 0x70400010},
        {0x1800, 1, 0x40000185}, {0x1800, 2, 255},        {0x1800, 5, 50},         {0x1A00, 0, 2},
        {0x1A00, 1, 0x60410010}, {0x1A00, 2, 0x60610008}, {0x1801, 1, 0x40000285}, {0x1801, 2, 1},
        {0x1A01, 0, 3},          {0x1A01, 1, 0x50020008}, {0x1A01, 2, 0x50030010}, {0x1A01, 3, 0x50040020},
        {0x1802, 1, 0x40000385}, {0x1A02, 0, 2},          {0x1A02, 1, 0x60640020}, {0x1A02, 2, 0x68640020},
        {0x1803, 1, 0x40000485}, {0x1A03, 0, 2},          {0x1A03, 1, 0x70640020}, {0x1A03, 2, 0x50050020},
        {0x1005, 0, 0x80},       {0x1400, 0, 2},          {0x1800, 0, 5},
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        uint64_t v = 0;
        assert_int_equal(sdo_read_u(&tn, want[i].idx, want[i].sub, &v), 0);
        if (v != want[i].v)
            fail_msg("0x%04X:%u is 0x%llX, expected 0x%X", want[i].idx, want[i].sub, (unsigned long long)v, want[i].v);
    }
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x1404, 1, &v), LSM_CO_ABORT_NO_OBJECT); /* only 4 RPDOs */
    assert_int_equal(sdo_read_u(&tn, 0x1800, 4, &v), LSM_CO_ABORT_NO_SUB);    /* reserved sub-index */
}

static void test_sync_telemetry(void **state)
{
    (void)state;
    set_actual(0, -1000);
    set_actual(1, 2000);
    set_actual(2, 300000);
    sync_frame(); /* PRE-OPERATIONAL: nothing */
    assert_int_equal(tn.n_out, 0);
    tn_nmt(&tn, 0x01, NODE_ID);
    for (int s = 0; s < 3; s++) {
        sync_frame();
        lsm_can_frame f;
        assert_int_equal(count_id(&tn, 0x285, &f), 1);
        assert_int_equal(f.dlc, 7);
        assert_int_equal(f.data[0], LSM_CO_PATH_IDLE);
        assert_int_equal(lsm_can_get_u16(&f.data[1]), PATHCAP);
        assert_int_equal(lsm_can_get_u32(&f.data[3]), 0);
        assert_int_equal(count_id(&tn, 0x385, &f), 1);
        assert_int_equal(f.dlc, 8);
        assert_int_equal((int32_t)lsm_can_get_u32(&f.data[0]), -1000);
        assert_int_equal((int32_t)lsm_can_get_u32(&f.data[4]), 2000);
        assert_int_equal(count_id(&tn, 0x485, &f), 1);
        assert_int_equal((int32_t)lsm_can_get_u32(&f.data[0]), 300000);
        assert_int_equal(count_id(&tn, 0x185, NULL), 0); /* event TPDO: not on SYNC */
    }
    assert_int_equal(lsm_canopen_sync_count(&tn.node), 3);
    /* type 2: every second SYNC */
    tn_nmt(&tn, 0x80, NODE_ID);
    assert_int_equal(sdo_write_u(&tn, 0x1802, 2, 2, 1), 0);
    tn_nmt(&tn, 0x01, NODE_ID);
    int sent = 0;
    for (int s = 0; s < 6; s++) {
        sync_frame();
        size_t c = count_id(&tn, 0x385, NULL);
        assert_int_equal(c, (s % 2 == 1) ? 1 : 0);
        sent += (int)c;
    }
    assert_int_equal(sent, 3);
}

static void test_acyclic_sync(void **state)
{
    (void)state;
    assert_int_equal(sdo_write_u(&tn, 0x1802, 2, 0, 1), 0);
    tn_nmt(&tn, 0x01, NODE_ID);
    sync_frame();
    assert_int_equal(count_id(&tn, 0x385, NULL), 1); /* first: sent */
    sync_frame();
    assert_int_equal(count_id(&tn, 0x385, NULL), 0); /* unchanged: not sent */
    set_actual(1, 55);
    assert_int_equal(count_id(&tn, 0x385, NULL), 0); /* a change alone sends nothing before SYNC */
    sync_frame();
    lsm_can_frame f;
    assert_int_equal(count_id(&tn, 0x385, &f), 1);
    assert_int_equal((int32_t)lsm_can_get_u32(&f.data[4]), 55);
}

static void test_event_tpdo(void **state)
{
    (void)state;
    /* TPDO1 (statusword + mode display, type 255): inhibit 10 ms, event timer 50 ms */
    assert_int_equal(sdo_write_u(&tn, 0x1800, 1, 0xC0000185u, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1800, 3, 100, 2), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1800, 5, 50, 2), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1800, 1, 0x40000185u, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1800, 3, 200, 2), LSM_CO_ABORT_DEVICE_STATE); /* while valid */
    tn_nmt(&tn, 0x01, NODE_ID);
    proc(0);
    lsm_can_frame f;
    assert_int_equal(count_id(&tn, 0x185, &f), 1); /* the first one at once */
    assert_int_equal(f.dlc, 3);
    assert_int_equal(lsm_can_get_u16(&f.data[0]), 0x0240); /* SWITCH ON DISABLED, remote */
    assert_int_equal((int8_t)f.data[2], 1);
    proc(1000);
    assert_int_equal(count_id(&tn, 0x185, NULL), 0);
    /* a state change at 2 ms is inside the inhibit time: sent at 10 ms */
    tn.now_us = 2000;
    uint8_t cw[2] = {0x06, 0};
    assert_int_equal(tn_rx(&tn, mkframe(0x205, 2, cw)), LSM_OK);
    proc(2000);
    assert_int_equal(count_id(&tn, 0x185, NULL), 0);
    proc(9999);
    assert_int_equal(count_id(&tn, 0x185, NULL), 0);
    proc(10000);
    assert_int_equal(count_id(&tn, 0x185, &f), 1);
    assert_int_equal(lsm_can_get_u16(&f.data[0]), 0x0231); /* READY TO SWITCH ON */
    /* nothing changes: the event timer sends it again 50 ms later */
    proc(59999);
    assert_int_equal(count_id(&tn, 0x185, NULL), 0);
    proc(60000);
    assert_int_equal(count_id(&tn, 0x185, NULL), 1);
    proc(60001);
    assert_int_equal(count_id(&tn, 0x185, NULL), 0);
}

static void test_rpdo_sync_vs_immediate(void **state)
{
    (void)state;
    tn_nmt(&tn, 0x01, NODE_ID);
    uint8_t d[8];
    lsm_can_put_u32(&d[0], 111);
    lsm_can_put_u32(&d[4], (uint32_t)-222);
    assert_int_equal(tn_rx(&tn, mkframe(0x305, 8, d)), LSM_OK); /* RPDO2, synchronous */
    assert_int_equal(tn.node.axis[0].target, 0);
    assert_int_equal(tn.node.axis[1].target, 0);
    sync_frame();
    assert_int_equal(tn.node.axis[0].target, 111);
    assert_int_equal(tn.node.axis[1].target, -222);
    /* applied once: a second SYNC without a new RPDO keeps the values */
    tn.node.axis[0].target = 5;
    sync_frame();
    assert_int_equal(tn.node.axis[0].target, 5);
    /* RPDO4 (controlwords of axes 1 and 2, immediate) */
    uint8_t c[4] = {0x06, 0x00, 0x06, 0x00};
    assert_int_equal(tn_rx(&tn, mkframe(0x505, 4, c)), LSM_OK);
    assert_int_equal(tn.node.axis[1].state, LSM_CIA402_READY_TO_SWITCH_ON);
    assert_int_equal(tn.node.axis[2].state, LSM_CIA402_READY_TO_SWITCH_ON);
    assert_int_equal(tn.node.axis[0].state, LSM_CIA402_SWITCH_ON_DISABLED);
    /* a refused value in an RPDO is skipped and counted: mode 5 through a remapped RPDO */
    tn_nmt(&tn, 0x80, NODE_ID);
    assert_int_equal(sdo_write_u(&tn, 0x1403, 1, 0x80000505u, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1603, 0, 0, 1), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1603, 1, 0x60600008u, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1603, 2, 0x68600008u, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1603, 0, 2, 1), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1403, 1, 0x00000505u, 4), 0);
    tn_nmt(&tn, 0x01, NODE_ID);
    uint8_t m[2] = {5, 8};
    uint32_t refused = tn.node.pdo.rx_refused;
    assert_int_equal(tn_rx(&tn, mkframe(0x505, 2, m)), LSM_OK);
    assert_int_equal(tn.node.axis[0].mode, 1);
    assert_int_equal(tn.node.axis[1].mode, 8);
    assert_int_equal(tn.node.pdo.rx_refused, refused + 1);
}

static void test_rpdo_length_errors(void **state)
{
    (void)state;
    tn_nmt(&tn, 0x01, NODE_ID);
    uint8_t d[8] = {0x06, 0x00, 0xAA, 0, 0, 0, 0, 0};
    /* short: not processed, EMCY 0x8210 once */
    assert_int_equal(tn_rx(&tn, mkframe(0x205, 1, d)), LSM_E_CO_FRAME);
    drain(&tn);
    lsm_can_frame e;
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x8210);
    assert_int_equal(e.data[3], 0); /* RPDO number */
    assert_int_equal(tn.node.axis[0].controlword, 0);
    assert_int_equal(tn_rx(&tn, mkframe(0x205, 1, d)), LSM_E_CO_FRAME);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x085, NULL), 0); /* not again */
    /* a good frame re-arms it */
    assert_int_equal(tn_rx(&tn, mkframe(0x205, 2, d)), LSM_OK);
    assert_int_equal(tn.node.axis[0].controlword, 0x06);
    /* long: processed, EMCY 0x8220 */
    d[0] = 0x00;
    assert_int_equal(tn_rx(&tn, mkframe(0x205, 3, d)), LSM_E_CO_FRAME);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x8220);
    assert_int_equal(tn.node.axis[0].controlword, 0x00);
    /* the length events are one-shot: they do not latch the error register */
    assert_int_equal(tn.node.emcy.error_register, 0);
    /* 0x1003 recorded them, newest first */
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x1003, 0, &v), 0);
    assert_int_equal(v, 2);
    assert_int_equal(sdo_read_u(&tn, 0x1003, 1, &v), 0);
    assert_int_equal(v & 0xFFFF, 0x8220);
    assert_int_equal(sdo_write_u(&tn, 0x1003, 0, 1, 1), LSM_CO_ABORT_VALUE);
    assert_int_equal(sdo_write_u(&tn, 0x1003, 0, 0, 1), 0);
    assert_int_equal(sdo_read_u(&tn, 0x1003, 0, &v), 0);
    assert_int_equal(v, 0);
}

static void test_sync_length_error(void **state)
{
    (void)state;
    tn_nmt(&tn, 0x01, NODE_ID);
    uint8_t c = 1;
    assert_int_equal(tn_rx(&tn, mkframe(0x080, 1, &c)), LSM_E_CO_FRAME);
    drain(&tn);
    lsm_can_frame e;
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0x8240);
    assert_int_equal(count_id(&tn, 0x285, NULL), 0); /* not processed */
    assert_int_equal(lsm_canopen_sync_count(&tn.node), 0);
}

static void test_mapping_procedure(void **state)
{
    (void)state;
    /* TPDO3 valid: its mapping may not change */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 0, 1), LSM_CO_ABORT_DEVICE_STATE);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 1, 0x60410010, 4), LSM_CO_ABORT_DEVICE_STATE);
    assert_int_equal(sdo_write_u(&tn, 0x1802, 1, 0xC0000385u, 4), 0);
    /* entries only while sub 0 is 0 */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 1, 0x60410010, 4), LSM_CO_ABORT_DEVICE_STATE);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 0, 1), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 1, 0x12340010, 4), LSM_CO_ABORT_NOT_MAPPABLE); /* no object */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 1, 0x60410020, 4), LSM_CO_ABORT_NOT_MAPPABLE); /* wrong length */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 1, 0x60400010, 4), LSM_CO_ABORT_NOT_MAPPABLE); /* RPDO-only */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 1, 0x10000020, 4), LSM_CO_ABORT_NOT_MAPPABLE); /* not mappable */
    assert_int_equal(sdo_write_u(&tn, 0x1602, 1, 0x60410010, 4), LSM_CO_ABORT_DEVICE_STATE); /* RPDO3 valid */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 9, 0x60410010, 4), LSM_CO_ABORT_NO_SUB);
    /* 3 x 32 bits > 64 */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 1, 0x60640020, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 2, 0x68640020, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 3, 0x70640020, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 3, 1), LSM_CO_ABORT_PDO_LENGTH);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 3, 0x10010008, 4), 0); /* 32 + 32 + 8 = 72 bits: one byte too many */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 3, 1), LSM_CO_ABORT_PDO_LENGTH);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 2, 1), 0); /* 64 bits exactly: fine */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 0, 1), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 9, 1), LSM_CO_ABORT_VALUE_HIGH);
    /* sub 0 = 4 with entry 4 empty */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 3, 0x60410010, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 4, 1), LSM_CO_ABORT_NOT_MAPPABLE);
    /* a valid new mapping: statuswords of axes 0, 1, 2 + error register, 7 bytes */
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 1, 0x60410010, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 2, 0x68410010, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 3, 0x70410010, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 4, 0x10010008, 4), 0);
    assert_int_equal(sdo_write_u(&tn, 0x1A02, 0, 4, 1), 0);
    /* COB-ID checks */
    assert_int_equal(sdo_write_u(&tn, 0x1802, 1, 0x20000385u, 4), LSM_CO_ABORT_VALUE); /* 29-bit */
    assert_int_equal(sdo_write_u(&tn, 0x1802, 1, 0x00000701u, 4), LSM_CO_ABORT_VALUE); /* restricted */
    assert_int_equal(sdo_write_u(&tn, 0x1802, 1, 0x00000000u, 4), LSM_CO_ABORT_VALUE);
    assert_int_equal(sdo_write_u(&tn, 0x1802, 2, 245, 1), LSM_CO_ABORT_VALUE);         /* reserved type */
    assert_int_equal(sdo_write_u(&tn, 0x1802, 2, 253, 1), LSM_CO_ABORT_VALUE);         /* RTR only */
    assert_int_equal(sdo_write_u(&tn, 0x1802, 1, 0x00000390u, 4), 0);                  /* new id, valid */
    assert_int_equal(sdo_write_u(&tn, 0x1802, 1, 0x00000391u, 4), LSM_CO_ABORT_VALUE); /* change while valid */
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x1802, 1, &v), 0);
    assert_int_equal(v, 0x40000390u);
    /* the new mapping in use */
    tn_nmt(&tn, 0x01, NODE_ID);
    sync_frame();
    lsm_can_frame f;
    assert_int_equal(count_id(&tn, 0x385, NULL), 0);
    assert_int_equal(count_id(&tn, 0x390, &f), 1);
    assert_int_equal(f.dlc, 7);
    for (int k = 0; k < 3; k++)
        assert_int_equal(lsm_can_get_u16(&f.data[2 * k]), 0x0240);
    assert_int_equal(f.data[6], 0);
}

static void test_sync_cob_id(void **state)
{
    (void)state;
    assert_int_equal(sdo_write_u(&tn, 0x1005, 0, 0x40000080u, 4), LSM_CO_ABORT_VALUE); /* producer */
    assert_int_equal(sdo_write_u(&tn, 0x1005, 0, 0x20000080u, 4), LSM_CO_ABORT_VALUE);
    assert_int_equal(sdo_write_u(&tn, 0x1005, 0, 0x00000081u, 4), 0);
    tn_nmt(&tn, 0x01, NODE_ID);
    sync_frame();
    assert_int_equal(count_id(&tn, 0x285, NULL), 0);
    assert_int_equal(tn_rx(&tn, mkframe(0x081, 0, NULL)), LSM_OK);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x285, NULL), 1);
}

static void test_configure_api(void **state)
{
    (void)state;
    uint32_t m[2] = {0x60410010u, 0x12340008u};
    assert_int_equal(lsm_co_pdo_configure(&tn.node.pdo, true, LSM_CO_N_TPDO, 1, m, 1, true), LSM_E_ARG);
    assert_int_equal(lsm_co_pdo_configure(&tn.node.pdo, true, 0, 1, m, LSM_CO_PDO_MAX_MAP + 1, true), LSM_E_ARG);
    assert_int_equal(lsm_co_pdo_configure(&tn.node.pdo, true, 0, 246, m, 1, true), LSM_E_ARG);
    assert_int_equal(lsm_co_pdo_configure(&tn.node.pdo, true, 0, 1, m, 2, true), LSM_E_CO_MAPPING);
    assert_int_equal(lsm_co_pdo_configure(&tn.node.pdo, true, 0, 1, m, 1, true), LSM_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_default_mapping, setup),
        cmocka_unit_test_setup(test_sync_telemetry, setup),
        cmocka_unit_test_setup(test_acyclic_sync, setup),
        cmocka_unit_test_setup(test_event_tpdo, setup),
        cmocka_unit_test_setup(test_rpdo_sync_vs_immediate, setup),
        cmocka_unit_test_setup(test_rpdo_length_errors, setup),
        cmocka_unit_test_setup(test_sync_length_error, setup),
        cmocka_unit_test_setup(test_mapping_procedure, setup),
        cmocka_unit_test_setup(test_sync_cob_id, setup),
        cmocka_unit_test_setup(test_configure_api, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
