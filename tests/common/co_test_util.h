/*
 * co_test_util.h: frame-level helpers shared by the CANopen unit tests (test_co_*.c, test_cia402.c,
 * test_canopen.c). Header-only; every test file includes it once. The helpers play the CANopen master:
 * they build request frames, feed them to lsm_canopen_rx and collect what the node queued.
 */
#ifndef CO_TEST_UTIL_H
#define CO_TEST_UTIL_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "canopen.h"

#ifdef CO_TEST_SDO_SPLIT
/* The split build of a test file (tests/CMakeLists.txt, *_sdobg): the node runs its SDO server as in the firmware's
 * two contexts (cfg.sdo_background), driven by the synchronous loop of lissom-node: lsm_canopen_sdo_sync after each
 * SDO request and before each lsm_canopen_process. Every expectation of the one-context test must still hold. */
static inline lsm_status tn_split_rx(lsm_canopen *n, const lsm_can_frame *f, uint32_t now_us)
{
    const lsm_status st = lsm_canopen_rx(n, f, now_us);
    if (st == LSM_OK && n != NULL && f != NULL && f->id == n->sdo_cob_rx)
        lsm_canopen_sdo_sync(n, now_us);
    return st;
}

static inline lsm_status tn_split_process(lsm_canopen *n, uint32_t now_us)
{
    lsm_canopen_sdo_sync(n, now_us);
    return lsm_canopen_process(n, now_us);
}

static inline lsm_status tn_split_init(lsm_canopen *n, lsm_canopen_config *cfg, uint32_t now_us)
{
    if (cfg != NULL)
        cfg->sdo_background = true;
    return lsm_canopen_init(n, cfg, now_us);
}
#define lsm_canopen_rx(n, f, t) tn_split_rx((n), (f), (t))
#define lsm_canopen_process(n, t) tn_split_process((n), (t))
#define lsm_canopen_init(n, c, t) tn_split_init((n), (c), (t))
#endif

#define NODE_ID 5u
#define TXCAP 64u
#define PATHCAP 8u

typedef struct test_node {
    lsm_canopen node;
    lsm_can_frame tx[TXCAP];
    lsm_co_path_block blocks[PATHCAP];
    lsm_can_frame out[TXCAP]; /* frames collected by drain() */
    size_t n_out;
    uint32_t now_us;
} test_node;

static inline lsm_can_frame mkframe(uint32_t id, uint8_t dlc, const uint8_t *data)
{
    lsm_can_frame f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    if (data != NULL && dlc != 0u)
        memcpy(f.data, data, dlc);
    return f;
}

/* Pops every queued frame into tn->out. */
static inline size_t drain(test_node *tn)
{
    tn->n_out = 0;
    lsm_can_frame f;
    while (lsm_canopen_tx_pop(&tn->node, &f)) {
        if (tn->n_out < TXCAP)
            tn->out[tn->n_out++] = f;
    }
    return tn->n_out;
}

/* Number of collected frames with this id; *last gets the last one. */
static inline size_t count_id(const test_node *tn, uint32_t id, lsm_can_frame *last)
{
    size_t c = 0;
    for (size_t i = 0; i < tn->n_out; i++) {
        if (tn->out[i].id == id) {
            c++;
            if (last != NULL)
                *last = tn->out[i];
        }
    }
    return c;
}

static inline lsm_status tn_init(test_node *tn, uint8_t n_axes, uint8_t path_cap)
{
    memset(tn, 0, sizeof *tn);
    lsm_canopen_config c = lsm_canopen_default_config();
    c.node_id = NODE_ID;
    c.n_axes = n_axes;
    c.heartbeat_ms = 0u;
    c.tx_storage = tn->tx;
    c.tx_cap = TXCAP;
    c.path_storage = tn->blocks;
    c.path_cap = path_cap;
    c.device_name = "Lissom test node with a long name";
    lsm_status st = lsm_canopen_init(&tn->node, &c, 0u);
    drain(tn);
    return st;
}

static inline lsm_status tn_rx(test_node *tn, lsm_can_frame f)
{
    return lsm_canopen_rx(&tn->node, &f, tn->now_us);
}

static inline void tn_nmt(test_node *tn, uint8_t cmd, uint8_t node)
{
    uint8_t d[2] = {cmd, node};
    assert_int_equal(tn_rx(tn, mkframe(0x000, 2, d)), LSM_OK);
}

/* The SDO response to the last request (asserts exactly one). */
static inline lsm_can_frame sdo_response(test_node *tn)
{
    drain(tn);
    lsm_can_frame r;
    assert_int_equal(count_id(tn, 0x580u + NODE_ID, &r), 1);
    assert_int_equal(r.dlc, 8);
    return r;
}

static inline uint32_t abort_code(const lsm_can_frame *r)
{
    return r->data[0] == 0x80u ? lsm_can_get_u32(&r->data[4]) : 0u;
}

static inline lsm_can_frame sdo_request(test_node *tn, const uint8_t d[8])
{
    assert_int_equal(tn_rx(tn, mkframe(0x600u + NODE_ID, 8, d)), LSM_OK);
    return sdo_response(tn);
}

/* Expedited download of len (1..4) bytes with the size indicated. Returns the abort code or 0. */
static inline uint32_t sdo_dl_exp(test_node *tn, uint16_t index, uint8_t sub, const uint8_t *data, size_t len)
{
    uint8_t d[8] = {0};
    d[0] = (uint8_t)(0x23u | ((4u - len) << 2));
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
    memcpy(&d[4], data, len);
    lsm_can_frame r = sdo_request(tn, d);
    if (r.data[0] == 0x80u)
        return abort_code(&r);
    assert_int_equal(r.data[0], 0x60);
    assert_int_equal(lsm_can_get_u16(&r.data[1]), index);
    assert_int_equal(r.data[3], sub);
    return 0u;
}

/* Segmented download (size indicated). Returns the abort code (at initiate or at any segment) or 0. */
static inline uint32_t sdo_dl_seg(test_node *tn, uint16_t index, uint8_t sub, const uint8_t *data, size_t len)
{
    uint8_t d[8] = {0x21u, 0, 0, 0, 0, 0, 0, 0};
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
    lsm_can_put_u32(&d[4], (uint32_t)len);
    lsm_can_frame r = sdo_request(tn, d);
    if (r.data[0] == 0x80u)
        return abort_code(&r);
    assert_int_equal(r.data[0], 0x60);
    size_t pos = 0;
    uint8_t t = 0;
    do {
        size_t n = len - pos > 7u ? 7u : len - pos;
        bool last = pos + n == len;
        memset(d, 0, sizeof d);
        d[0] = (uint8_t)(t | ((7u - n) << 1) | (last ? 1u : 0u));
        memcpy(&d[1], &data[pos], n);
        r = sdo_request(tn, d);
        if (r.data[0] == 0x80u)
            return abort_code(&r);
        assert_int_equal(r.data[0], 0x20u | t);
        pos += n;
        t ^= 0x10u;
    } while (pos < len);
    return 0u;
}

static inline uint32_t sdo_dl(test_node *tn, uint16_t index, uint8_t sub, const uint8_t *data, size_t len)
{
    return (len >= 1u && len <= 4u) ? sdo_dl_exp(tn, index, sub, data, len) : sdo_dl_seg(tn, index, sub, data, len);
}

static inline uint32_t sdo_write_u(test_node *tn, uint16_t index, uint8_t sub, uint64_t v, size_t len)
{
    uint8_t b[8];
    lsm_can_put_le(b, v, len);
    return sdo_dl(tn, index, sub, b, len);
}

/* Upload, expedited or segmented. Returns the abort code or 0; *len = bytes read. */
static inline uint32_t sdo_ul(test_node *tn, uint16_t index, uint8_t sub, uint8_t *buf, size_t cap, size_t *len)
{
    uint8_t d[8] = {0x40u, 0, 0, 0, 0, 0, 0, 0};
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
    lsm_can_frame r = sdo_request(tn, d);
    if (r.data[0] == 0x80u)
        return abort_code(&r);
    assert_int_equal(lsm_can_get_u16(&r.data[1]), index);
    assert_int_equal(r.data[3], sub);
    if (r.data[0] & 0x02u) { /* expedited */
        assert_true(r.data[0] & 0x01u);
        size_t n = 4u - ((r.data[0] >> 2) & 3u);
        assert_true(n <= cap);
        memcpy(buf, &r.data[4], n);
        *len = n;
        return 0u;
    }
    assert_int_equal(r.data[0], 0x41);
    size_t total = lsm_can_get_u32(&r.data[4]);
    size_t pos = 0;
    uint8_t t = 0;
    for (;;) {
        memset(d, 0, sizeof d);
        d[0] = (uint8_t)(0x60u | t);
        r = sdo_request(tn, d);
        if (r.data[0] == 0x80u)
            return abort_code(&r);
        assert_int_equal(r.data[0] & 0x10u, t);
        size_t n = 7u - ((r.data[0] >> 1) & 7u);
        assert_true(pos + n <= cap);
        memcpy(&buf[pos], &r.data[1], n);
        pos += n;
        t ^= 0x10u;
        if (r.data[0] & 0x01u)
            break;
    }
    assert_int_equal(pos, total);
    *len = pos;
    return 0u;
}

static inline uint32_t sdo_read_u(test_node *tn, uint16_t index, uint8_t sub, uint64_t *v)
{
    uint8_t b[64];
    size_t n = 0;
    uint32_t ab = sdo_ul(tn, index, sub, b, sizeof b, &n);
    if (ab == 0u)
        *v = lsm_can_get_le(b, n);
    return ab;
}

/* Reports every axis at rest at its demand position (the application loop in miniature). */
static inline void axes_at_rest(test_node *tn)
{
    for (size_t k = 0; k < tn->node.n_axes; k++) {
        lsm_cia402 *ax = lsm_canopen_axis(&tn->node, k);
        lsm_cia402_feedback fb = {ax->pos_demand, ax->pos_demand, 0, true};
        lsm_cia402_update(ax, &fb, tn->now_us);
    }
}

/* Brings axis k to OPERATION ENABLED through SDO writes of the controlword. */
static inline void enable_axis(test_node *tn, size_t k)
{
    uint16_t idx = (uint16_t)(0x6040u + 0x800u * k);
    assert_int_equal(sdo_write_u(tn, idx, 0, 0x06, 2), 0);
    assert_int_equal(sdo_write_u(tn, idx, 0, 0x07, 2), 0);
    assert_int_equal(sdo_write_u(tn, idx, 0, 0x0F, 2), 0);
    assert_int_equal(lsm_canopen_axis(&tn->node, k)->state, LSM_CIA402_OPERATION_ENABLED);
}

#endif /* CO_TEST_UTIL_H */
