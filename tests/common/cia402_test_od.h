/*
 * cia402_test_od.h: object-dictionary helpers shared by the tests that drive a CiA 402 node without CAN
 * (tests/motion/test_motion.c on the firmware's node and motion layer, host_sim/node/tests/test_node_app.c on
 * lissom-node's application). Header-only. Writes go through lsm_co_od_set_int / lsm_co_od_write, which have the
 * same checks and hooks as an SDO download. Positions are counts (1000 per mm), axis k's objects are 0x800 k
 * above axis 0's (CiA 402 multi-axis offset).
 */
#ifndef CIA402_TEST_OD_H
#define CIA402_TEST_OD_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "canopen.h"

#define AX(idx, k) ((uint16_t)((idx) + 0x800u * (k)))

/* Writes an object at time now_us (the hooks see that time); a refused write fails the test with its abort code. */
static inline void od_set(lsm_canopen *co, uint32_t now_us, uint16_t idx, uint8_t sub, int64_t v)
{
    co->now_us = now_us;
    uint32_t ab = lsm_co_od_set_int(lsm_canopen_od(co), idx, sub, v);
    if (ab != 0u)
        fail_msg("write 0x%04X sub %u = %lld: abort 0x%08X", idx, sub, (long long)v, ab);
}

static inline int64_t od_get(lsm_canopen *co, uint16_t idx, uint8_t sub)
{
    int64_t v = 0;
    assert_int_equal(lsm_co_od_get_int(lsm_canopen_od(co), idx, sub, &v), 0);
    return v;
}

/* PP profile of axis k: 100 mm/s, 1000 mm/s², 2e4 mm/s³, 2e6 mm/s⁴, sin² (in counts). */
static inline void od_pp_profile(lsm_canopen *co, uint32_t now_us, unsigned k)
{
    od_set(co, now_us, AX(0x6081, k), 0, 100000);
    od_set(co, now_us, AX(0x6083, k), 0, 1000000);
    od_set(co, now_us, AX(0x6084, k), 0, 1000000);
    od_set(co, now_us, AX(0x2060, k), 0, 20000000);
    od_set(co, now_us, AX(0x2061, k), 0, 2000000000);
    od_set(co, now_us, AX(0x6086, k), 0, 1);
}

/* A PP target for axis k, started at once (single set-point: control word 0x3F, then 0x2F). */
static inline void od_pp_go(lsm_canopen *co, uint32_t now_us, unsigned k, int32_t target)
{
    od_set(co, now_us, AX(0x607A, k), 0, target);
    od_set(co, now_us, AX(0x6040, k), 0, 0x3F);
    od_set(co, now_us, AX(0x6040, k), 0, 0x2F);
}

/* One 0x5010 path block (type 1 line, 2/3 arc with a centre in X Y; 3 axes; blend tolerance tol_um) through the
 * dictionary's hook, like the SDO download. Returns the abort code (0: taken). */
static inline uint32_t od_path_block_tol(lsm_canopen *co, uint32_t seq, uint8_t type, const int32_t end[3],
                                         const int32_t *centre, uint32_t feed_um_s, uint32_t tol_um)
{
    uint8_t b[40];
    size_t n = 16 + 12 + (type != 1 ? 8 : 0);
    memset(b, 0, sizeof b);
    lsm_can_put_u32(&b[0], seq);
    b[4] = type;
    b[6] = 3;
    lsm_can_put_u32(&b[8], feed_um_s);
    lsm_can_put_u32(&b[12], tol_um);
    for (int k = 0; k < 3; k++)
        lsm_can_put_u32(&b[16 + 4 * k], (uint32_t)end[k]);
    if (type != 1) {
        lsm_can_put_u32(&b[28], (uint32_t)centre[0]);
        lsm_can_put_u32(&b[32], (uint32_t)centre[1]);
    }
    lsm_co_od_ref ref;
    assert_int_equal(lsm_co_od_find(lsm_canopen_od(co), 0x5010, 0, &ref), 0);
    return lsm_co_od_write(lsm_canopen_od(co), &ref, b, n);
}

/* od_path_block_tol with a 10 um tolerance. */
static inline uint32_t od_path_block(lsm_canopen *co, uint32_t seq, uint8_t type, const int32_t end[3],
                                     const int32_t *centre, uint32_t feed_um_s)
{
    return od_path_block_tol(co, seq, type, end, centre, feed_um_s, 10u);
}

/* Frames with this id among sent[0..n); for the EMCY id of node `nid`, only those with this error code. */
static inline size_t frames_count(const lsm_can_frame *sent, size_t n, uint8_t nid, uint32_t id, uint16_t emcy_code)
{
    size_t c = 0;
    for (size_t i = 0; i < n; i++) {
        if (sent[i].id != id)
            continue;
        if (id == 0x80u + nid && sent[i].dlc == 8u && (uint16_t)(sent[i].data[0] | (sent[i].data[1] << 8)) != emcy_code)
            continue;
        c++;
    }
    return c;
}

#endif /* CIA402_TEST_OD_H */
