/*
 * test_co_sdo.c: the SDO server at frame level, as a CANopen master sees it: expedited and segmented
 * upload and download (with and without size indication), toggle handling, time-out, client abort,
 * block-transfer refusal, malformed request frames, and one test per abort code the server itself or the
 * dictionary produces (the PDO-mapping, consumer and path codes are in their modules' tests).
 */
#include "co_test_util.h"

static test_node tn;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(tn_init(&tn, 2, PATHCAP), LSM_OK);
    return 0;
}

static void test_expedited_upload(void **state)
{
    (void)state;
    uint64_t v = 0;
    assert_int_equal(sdo_read_u(&tn, 0x1000, 0, &v), 0);
    assert_int_equal(v, LSM_CANOPEN_DEVICE_TYPE);
    /* the exact response frame for a 1-byte object: 0x4F = expedited, size indicated, n = 3 */
    uint8_t d[8] = {0x40, 0x01, 0x10, 0x00, 0, 0, 0, 0};
    lsm_can_frame r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x4F);
    assert_int_equal(r.data[1], 0x01);
    assert_int_equal(r.data[2], 0x10);
    assert_int_equal(r.data[3], 0x00);
    assert_int_equal(r.data[4], tn.node.emcy.error_register);
    /* 2-byte object: 0x4B */
    lsm_can_put_u16(&d[1], 0x1017);
    r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x4B);
    /* INTEGER8 */
    assert_int_equal(sdo_read_u(&tn, 0x6060, 0, &v), 0);
    assert_int_equal(v, 1);
}

static void test_expedited_download(void **state)
{
    (void)state;
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 250, 2), 0);
    assert_int_equal(tn.node.nmt.producer_ms, 250);
    /* size not indicated (0x22): the server takes the object's own size */
    uint8_t d[8] = {0x22, 0x17, 0x10, 0x00, 0x2C, 0x01, 0xEE, 0xEE};
    lsm_can_frame r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x60);
    assert_int_equal(tn.node.nmt.producer_ms, 300);
    /* INTEGER32 negative */
    assert_int_equal(sdo_write_u(&tn, 0x607A, 0, (uint32_t)-123456, 4), 0);
    assert_int_equal(tn.node.axis[0].target, -123456);
    /* axis 1 answers at 0x6800 + 0x7A */
    assert_int_equal(sdo_write_u(&tn, 0x687A, 0, 777, 4), 0);
    assert_int_equal(tn.node.axis[1].target, 777);
    assert_int_equal(tn.node.axis[0].target, -123456);
}

static void test_segmented_upload(void **state)
{
    (void)state;
    uint8_t buf[64];
    size_t n = 0;
    assert_int_equal(sdo_ul(&tn, 0x1008, 0, buf, sizeof buf, &n), 0);
    const char *name = "Lissom test node with a long name";
    assert_int_equal(n, strlen(name));
    assert_memory_equal(buf, name, n);
    /* the initiate response announces the size */
    uint8_t d[8] = {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0};
    lsm_can_frame r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x41);
    assert_int_equal(lsm_can_get_u32(&r.data[4]), strlen(name));
    /* first segment: toggle 0, 7 bytes, not last */
    memset(d, 0, 8);
    d[0] = 0x60;
    r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x00);
    assert_memory_equal(&r.data[1], name, 7);
    /* second: toggle 1 */
    d[0] = 0x70;
    r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x10);
    assert_memory_equal(&r.data[1], name + 7, 7);
}

static void test_segmented_u64(void **state)
{
    (void)state;
    uint64_t j = 123456789012345ull;
    assert_int_equal(sdo_write_u(&tn, 0x2060, 0, j, 8), 0);
    assert_true(tn.node.axis[0].profile_jerk == j);
    uint64_t back = 0;
    assert_int_equal(sdo_read_u(&tn, 0x2060, 0, &back), 0);
    assert_true(back == j);
    /* segmented download without size indication (0x20) */
    uint8_t d[8] = {0x20, 0x61, 0x20, 0x00, 0, 0, 0, 0};
    lsm_can_frame r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x60);
    uint8_t v[8];
    lsm_can_put_le(v, 987654321ull, 8);
    memset(d, 0, 8);
    d[0] = 0x00; /* toggle 0, n = 0, more follows */
    memcpy(&d[1], v, 7);
    r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x20);
    memset(d, 0, 8);
    d[0] = (uint8_t)(0x10 | (6u << 1) | 1u); /* toggle 1, 1 byte, last */
    d[1] = v[7];
    r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x30);
    assert_true(tn.node.axis[0].profile_snap == 987654321ull);
}

static void test_toggle_errors(void **state)
{
    (void)state;
    /* download: second segment repeats toggle 0 */
    uint8_t d[8] = {0x21, 0x60, 0x20, 0x00, 8, 0, 0, 0};
    lsm_can_frame r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x60);
    memset(d, 0, 8);
    d[0] = 0x00;
    r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x20);
    d[0] = (uint8_t)(0x00 | (6u << 1) | 1u);
    r = sdo_request(&tn, d);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_TOGGLE);
    assert_int_equal(lsm_can_get_u16(&r.data[1]), 0x2060);
    assert_true(tn.node.axis[0].profile_jerk == 10000000u); /* unchanged */
    /* upload: first segment with toggle 1 */
    uint8_t u[8] = {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0};
    r = sdo_request(&tn, u);
    assert_int_equal(r.data[0], 0x41);
    memset(u, 0, 8);
    u[0] = 0x70;
    r = sdo_request(&tn, u);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_TOGGLE);
}

static void test_out_of_sequence(void **state)
{
    (void)state;
    uint8_t d[8] = {0x00, 1, 2, 3, 4, 5, 6, 7};
    lsm_can_frame r = sdo_request(&tn, d); /* download segment, nothing open */
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
    d[0] = 0x60; /* upload segment, nothing open */
    r = sdo_request(&tn, d);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
    /* block download / block upload initiate, and ccs 7 */
    uint8_t b[8] = {0xC6, 0x08, 0x10, 0x00, 0, 0, 0, 0};
    r = sdo_request(&tn, b);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
    b[0] = 0xA4;
    r = sdo_request(&tn, b);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
    b[0] = 0xE0;
    r = sdo_request(&tn, b);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
    /* an upload segment while a download is open */
    uint8_t i[8] = {0x21, 0x60, 0x20, 0x00, 8, 0, 0, 0};
    r = sdo_request(&tn, i);
    assert_int_equal(r.data[0], 0x60);
    d[0] = 0x60;
    r = sdo_request(&tn, d);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
    assert_int_equal(lsm_can_get_u16(&r.data[1]), 0x2060);
}

static void test_timeout_and_client_abort(void **state)
{
    (void)state;
    uint8_t i[8] = {0x21, 0x60, 0x20, 0x00, 8, 0, 0, 0};
    lsm_can_frame r = sdo_request(&tn, i);
    assert_int_equal(r.data[0], 0x60);
    tn.now_us = LSM_CO_SDO_TIMEOUT_US; /* exactly at the deadline: not yet */
    lsm_canopen_process(&tn.node, tn.now_us);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x585, NULL), 0);
    tn.now_us = LSM_CO_SDO_TIMEOUT_US + 1u;
    lsm_canopen_process(&tn.node, tn.now_us);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x585, &r), 1);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_TIMEOUT);
    assert_int_equal(lsm_can_get_u16(&r.data[1]), 0x2060);
    /* the transfer is gone */
    uint8_t d[8] = {0x00, 1, 2, 3, 4, 5, 6, 7};
    r = sdo_request(&tn, d);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
    /* client abort: no answer, transfer dropped */
    r = sdo_request(&tn, i);
    assert_int_equal(r.data[0], 0x60);
    uint8_t a[8] = {0x80, 0x60, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05};
    assert_int_equal(tn_rx(&tn, mkframe(0x605, 8, a)), LSM_OK);
    drain(&tn);
    assert_int_equal(tn.n_out, 0);
    r = sdo_request(&tn, d);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
    /* no time-out fires later either */
    tn.now_us += 10u * LSM_CO_SDO_TIMEOUT_US;
    lsm_canopen_process(&tn.node, tn.now_us);
    drain(&tn);
    assert_int_equal(count_id(&tn, 0x585, NULL), 0);
}

static void test_new_initiate_replaces(void **state)
{
    (void)state;
    uint8_t i[8] = {0x21, 0x60, 0x20, 0x00, 8, 0, 0, 0};
    lsm_can_frame r = sdo_request(&tn, i);
    assert_int_equal(r.data[0], 0x60);
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x1000, 0, &v), 0); /* a new request: the old transfer is dropped */
    uint8_t d[8] = {0x00, 1, 2, 3, 4, 5, 6, 7};
    r = sdo_request(&tn, d);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_CMD);
}

static void test_malformed_request(void **state)
{
    (void)state;
    uint8_t d[8] = {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
    uint32_t before = tn.node.malformed;
    for (uint8_t dlc = 0; dlc < 8; dlc++) {
        assert_int_equal(tn_rx(&tn, mkframe(0x605, dlc, d)), LSM_E_CO_FRAME);
        drain(&tn);
        assert_int_equal(tn.n_out, 0); /* no answer at all */
    }
    assert_int_equal(tn.node.malformed - before, 8);
    /* an RTR frame on the SDO id */
    lsm_can_frame f = mkframe(0x605, 8, d);
    f.flags = LSM_CAN_FLAG_RTR;
    assert_int_equal(tn_rx(&tn, f), LSM_E_CO_FRAME);
    drain(&tn);
    assert_int_equal(tn.n_out, 0);
    /* the server still works */
    uint64_t v;
    assert_int_equal(sdo_read_u(&tn, 0x1000, 0, &v), 0);
}

static void test_abort_codes(void **state)
{
    (void)state;
    uint64_t v;
    uint8_t b[64] = {0};
    size_t n;
    assert_int_equal(sdo_read_u(&tn, 0x1234, 0, &v), LSM_CO_ABORT_NO_OBJECT);
    assert_int_equal(sdo_write_u(&tn, 0x1234, 0, 1, 1), LSM_CO_ABORT_NO_OBJECT);
    assert_int_equal(sdo_read_u(&tn, 0x1018, 9, &v), LSM_CO_ABORT_NO_SUB);
    assert_int_equal(sdo_write_u(&tn, 0x1018, 9, 1, 4), LSM_CO_ABORT_NO_SUB);
    assert_int_equal(sdo_ul(&tn, 0x5010, 0, b, sizeof b, &n), LSM_CO_ABORT_WRITE_ONLY);
    assert_int_equal(sdo_write_u(&tn, 0x1000, 0, 1, 4), LSM_CO_ABORT_READ_ONLY);
    assert_int_equal(sdo_write_u(&tn, 0x1018, 0, 1, 1), LSM_CO_ABORT_READ_ONLY); /* const */
    assert_int_equal(sdo_write_u(&tn, 0x6041, 0, 1, 2), LSM_CO_ABORT_READ_ONLY);
    /* sizes */
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 1, 4), LSM_CO_ABORT_LENGTH_HIGH);
    assert_int_equal(sdo_write_u(&tn, 0x1017, 0, 1, 1), LSM_CO_ABORT_LENGTH_LOW);
    assert_int_equal(sdo_dl_seg(&tn, 0x2060, 0, b, 9), LSM_CO_ABORT_LENGTH_HIGH); /* refused at initiate */
    assert_int_equal(sdo_dl_seg(&tn, 0x2060, 0, b, 4), LSM_CO_ABORT_LENGTH_LOW);
    assert_int_equal(sdo_dl_seg(&tn, 0x5010, 0, b, 49), LSM_CO_ABORT_LENGTH_HIGH);
    /* announced 8 bytes, the last segment comes after 7: 0x06070010 */
    uint8_t d[8] = {0x21, 0x60, 0x20, 0x00, 8, 0, 0, 0};
    lsm_can_frame r = sdo_request(&tn, d);
    assert_int_equal(r.data[0], 0x60);
    memset(d, 0, 8);
    d[0] = 0x01; /* 7 bytes, last */
    r = sdo_request(&tn, d);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_LENGTH);
    /* more bytes than announced */
    uint8_t e[8] = {0x21, 0x60, 0x20, 0x00, 5, 0, 0, 0};
    r = sdo_request(&tn, e);
    assert_int_equal(abort_code(&r), LSM_CO_ABORT_LENGTH_LOW); /* 5 < 8 at initiate */
    /* values */
    assert_int_equal(sdo_write_u(&tn, 0x6060, 0, 5, 1), LSM_CO_ABORT_VALUE); /* mode 5 unsupported */
    assert_int_equal(sdo_write_u(&tn, 0x6086, 0, 2, 2), LSM_CO_ABORT_VALUE); /* profile type 2 */
    assert_int_equal(sdo_write_u(&tn, 0x605A, 0, 0, 2), LSM_CO_ABORT_VALUE); /* coast: refused */
    assert_int_equal(sdo_write_u(&tn, 0x6007, 0, 4, 2), LSM_CO_ABORT_VALUE_HIGH);
    assert_int_equal(sdo_write_u(&tn, 0x6007, 0, (uint16_t)-1, 2), LSM_CO_ABORT_VALUE_LOW);
    assert_int_equal(sdo_write_u(&tn, 0x6081, 0, 0, 4), LSM_CO_ABORT_VALUE_LOW);    /* zero velocity */
    assert_int_equal(sdo_write_u(&tn, 0x2061, 0, 0, 8), LSM_CO_ABORT_VALUE_LOW);    /* zero snap */
    assert_int_equal(sdo_write_u(&tn, 0x5001, 0, 201, 1), LSM_CO_ABORT_VALUE_HIGH); /* override */
    assert_int_equal(sdo_write_u(&tn, 0x1029, 1, 3, 1), LSM_CO_ABORT_VALUE_HIGH);
    /* device state: scaling while the axis is enabled */
    assert_int_equal(sdo_write_u(&tn, 0x2001, 0, 2000, 4), 0);
    enable_axis(&tn, 0);
    assert_int_equal(sdo_write_u(&tn, 0x2001, 0, 1000, 4), LSM_CO_ABORT_DEVICE_STATE);
    assert_int_equal(tn.node.axis[0].counts_per_mm, 2000);
    /* every refusal above changed nothing */
    assert_int_equal(tn.node.axis[0].mode, 1);
    assert_int_equal(tn.node.axis[0].profile_type, 1);
    assert_int_equal(tn.node.axis[0].abort_option, 3);
    assert_int_equal(tn.node.axis[0].profile_velocity, 10000);
    assert_int_equal(tn.node.path.override_pct, 100);
    /* the abort frame layout: 0x80, index, sub, code */
    uint8_t q[8] = {0x40, 0x18, 0x10, 0x09, 0, 0, 0, 0};
    r = sdo_request(&tn, q);
    assert_int_equal(r.data[0], 0x80);
    assert_int_equal(r.data[1], 0x18);
    assert_int_equal(r.data[2], 0x10);
    assert_int_equal(r.data[3], 0x09);
    assert_int_equal(lsm_can_get_u32(&r.data[4]), 0x06090011u);
}

/* 0x05040005: an object larger than the server's buffer (a server with an 8-byte buffer on its own OD). */
typedef struct small {
    const char *s;
    uint8_t dummy;
} small;
static uint32_t small_hook(void *ctx, const lsm_co_od_ref *ref, const uint8_t *data, size_t len, int64_t v)
{
    (void)ctx, (void)ref, (void)data, (void)len, (void)v;
    return 0;
}

static void test_out_of_memory(void **state)
{
    (void)state;
    static const lsm_co_od_entry tab[] = {
        {0x2000, 0, LSM_CO_T_VSTRING, LSM_CO_OD_R | LSM_CO_OD_STRPTR, 0, 0, 32, offsetof(small, s)},
        {0x2001, 0, LSM_CO_T_DOMAIN, LSM_CO_OD_W | LSM_CO_OD_HOOK, 0, 0, 32, 0},
    };
    small obj = {"0123456789", 0};
    lsm_co_od_config c;
    memset(&c, 0, sizeof c);
    c.table = tab;
    c.n_entries = 2;
    c.base = &obj;
    c.base_size = sizeof obj;
    c.write_hook = small_hook;
    lsm_co_od od;
    assert_int_equal(lsm_co_od_init(&od, &c), LSM_OK);
    lsm_co_sdo sdo;
    uint8_t buf[8];
    assert_int_equal(lsm_co_sdo_init(&sdo, &od, 3, buf, 4, 0), LSM_E_ARG); /* smaller than a u64 */
    assert_int_equal(lsm_co_sdo_init(&sdo, &od, 0, buf, 8, 0), LSM_E_CO_NODE_ID);
    assert_int_equal(lsm_co_sdo_init(&sdo, &od, 3, buf, sizeof buf, 0), LSM_OK);
    lsm_can_frame store[4];
    lsm_can_txq q;
    assert_int_equal(lsm_can_txq_init(&q, store, 4), LSM_OK);
    uint8_t d[8] = {0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0};
    lsm_can_frame f = mkframe(0x603, 8, d), r;
    assert_int_equal(lsm_co_sdo_rx(&sdo, &f, 0, &q), LSM_OK);
    assert_true(lsm_can_txq_pop(&q, &r));
    assert_int_equal(lsm_can_get_u32(&r.data[4]), LSM_CO_ABORT_NO_MEM);
    /* segmented download without size into the domain: the 2nd segment overflows the 8-byte buffer */
    uint8_t i[8] = {0x20, 0x01, 0x20, 0x00, 0, 0, 0, 0};
    f = mkframe(0x603, 8, i);
    assert_int_equal(lsm_co_sdo_rx(&sdo, &f, 0, &q), LSM_OK);
    assert_true(lsm_can_txq_pop(&q, &r));
    assert_int_equal(r.data[0], 0x60);
    uint8_t s0[8] = {0x00, 1, 2, 3, 4, 5, 6, 7};
    f = mkframe(0x603, 8, s0);
    assert_int_equal(lsm_co_sdo_rx(&sdo, &f, 0, &q), LSM_OK);
    assert_true(lsm_can_txq_pop(&q, &r));
    assert_int_equal(r.data[0], 0x20);
    s0[0] = 0x10;
    f = mkframe(0x603, 8, s0);
    assert_int_equal(lsm_co_sdo_rx(&sdo, &f, 0, &q), LSM_OK);
    assert_true(lsm_can_txq_pop(&q, &r));
    assert_int_equal(lsm_can_get_u32(&r.data[4]), LSM_CO_ABORT_NO_MEM);
    /* a full transmit queue: the answer is dropped and counted, the call says LSM_E_FULL */
    lsm_can_frame filler = mkframe(0x100, 0, NULL);
    for (int k = 0; k < 4; k++)
        assert_int_equal(lsm_can_txq_push(&q, &filler), LSM_OK);
    f = mkframe(0x603, 8, d);
    assert_int_equal(lsm_co_sdo_rx(&sdo, &f, 0, &q), LSM_E_FULL);
    assert_int_equal(q.dropped, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_expedited_upload, setup),
        cmocka_unit_test_setup(test_expedited_download, setup),
        cmocka_unit_test_setup(test_segmented_upload, setup),
        cmocka_unit_test_setup(test_segmented_u64, setup),
        cmocka_unit_test_setup(test_toggle_errors, setup),
        cmocka_unit_test_setup(test_out_of_sequence, setup),
        cmocka_unit_test_setup(test_timeout_and_client_abort, setup),
        cmocka_unit_test_setup(test_new_initiate_replaces, setup),
        cmocka_unit_test_setup(test_malformed_request, setup),
        cmocka_unit_test_setup(test_abort_codes, setup),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
