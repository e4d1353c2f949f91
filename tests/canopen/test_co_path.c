/*
 * test_co_path.c: the path block buffer (co_path.c) through SDO at frame level:
 *   - block encoding (line, arc) and every validation refusal with its abort code on the wire;
 *   - sequence numbers: duplicates acknowledged and not stored, gaps refused (0x06090031), wrap at 2^32,
 *     resync; buffer full (0x08000020) and flow control through 0x5003;
 *   - start / hold / resume / clear, their refusals (0x08000022, 0x06090030), the hold a fault or halt of an
 *     axis causes, the planner refusing a block (EMCY 0xFF01), override range, telemetry at SYNC;
 *   - a randomized lossy channel: request and response frames dropped at random, the master retrying
 *     (same block again, or re-reading 0x5004 and resuming), the application draining at random:
 *     every block arrives exactly once, in order. Usage: test_co_path [seed] [count].
 */
#include <stdio.h>
#include <stdlib.h>

#include "lsm_test_rng.h"

#include "co_test_util.h"

static test_node tn;
static unsigned long g_seed = 1;
static unsigned long g_count = 2000;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(tn_init(&tn, 3, PATHCAP), LSM_OK);
    return 0;
}

/* Encodes a block for n axes; returns its length. */
static size_t enc(uint8_t *b, uint32_t seq, uint8_t type, uint8_t plane, uint8_t n, uint32_t feed, uint32_t tol,
                  const int32_t *end, const int32_t *centre)
{
    memset(b, 0, 64);
    lsm_can_put_u32(&b[0], seq);
    b[4] = type;
    b[5] = plane;
    b[6] = n;
    b[7] = 0;
    lsm_can_put_u32(&b[8], feed);
    lsm_can_put_u32(&b[12], tol);
    for (size_t i = 0; i < n; i++)
        lsm_can_put_u32(&b[16 + 4 * i], (uint32_t)end[i]);
    size_t len = 16u + 4u * n;
    if (type != LSM_CO_PATH_LINE) {
        lsm_can_put_u32(&b[len], (uint32_t)centre[0]);
        lsm_can_put_u32(&b[len + 4], (uint32_t)centre[1]);
        len += 8;
    }
    return len;
}

static uint32_t send_line(uint32_t seq, int32_t x)
{
    uint8_t b[64];
    int32_t end[3] = {x, 2 * x, -x};
    size_t len = enc(b, seq, LSM_CO_PATH_LINE, 0, 3, 10000, 5, end, NULL);
    return sdo_dl(&tn, 0x5010, 0, b, len);
}

static uint64_t rd(uint16_t idx, uint8_t sub)
{
    uint64_t v = 0;
    assert_int_equal(sdo_read_u(&tn, idx, sub, &v), 0);
    return v;
}

static void test_decode(void **state)
{
    (void)state;
    uint8_t b[64];
    int32_t end[3] = {1000, -2000, 3000}, c[2] = {500, -2000};
    size_t len = enc(b, 1, LSM_CO_PATH_ARC_CCW, 0, 3, 25000, 10, end, c);
    assert_int_equal(len, 36);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), 0);
    lsm_co_path_block blk;
    assert_true(lsm_co_path_peek(&tn.node.path, 0, &blk));
    assert_int_equal(blk.seq, 1);
    assert_int_equal(blk.type, LSM_CO_PATH_ARC_CCW);
    assert_int_equal(blk.plane, 0);
    assert_int_equal(blk.feed_um_s, 25000);
    assert_int_equal(blk.tol_um, 10);
    assert_int_equal(blk.end[0], 1000);
    assert_int_equal(blk.end[1], -2000);
    assert_int_equal(blk.end[2], 3000);
    assert_int_equal(blk.centre[0], 500);
    assert_int_equal(blk.centre[1], -2000);
    assert_int_equal(rd(0x5004, 0), 1);
    assert_int_equal(rd(0x5003, 0), PATHCAP - 1);
    assert_int_equal(rd(0x5007, 0), PATHCAP);
    /* a 1-axis line is 20 bytes, a 6-axis arc the maximum 48 */
    assert_int_equal(LSM_CO_PATH_BLOCK_MAX, 48);
}

static void test_validation(void **state)
{
    (void)state;
    uint8_t b[64];
    int32_t end[3] = {1000, 0, 0}, c[2] = {500, 0};
    size_t len = enc(b, 1, LSM_CO_PATH_LINE, 0, 3, 10000, 5, end, NULL);
    assert_int_equal(len, 28);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, 15), LSM_CO_ABORT_LENGTH_LOW);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len + 1), LSM_CO_ABORT_LENGTH_HIGH);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len - 1), LSM_CO_ABORT_LENGTH_LOW);
    b[4] = 0;
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    b[4] = 4;
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    b[4] = 1;
    b[6] = 2; /* axis count mismatch */
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    b[6] = 3;
    b[5] = 1; /* plane on a line */
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    b[5] = 0;
    b[7] = 1; /* reserved flags */
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    b[7] = 0;
    lsm_can_put_u32(&b[8], 0);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE_LOW);
    lsm_can_put_u32(&b[8], 10000);
    lsm_can_put_u32(&b[12], 0);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE_LOW);
    lsm_can_put_u32(&b[12], 5);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), 0); /* now fine */
    /* arcs: plane 3, end on the centre, start (previous end) on the centre */
    len = enc(b, 2, LSM_CO_PATH_ARC_CW, 3, 3, 10000, 5, end, c);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    int32_t on_c[3] = {500, 0, 0};
    len = enc(b, 2, LSM_CO_PATH_ARC_CW, 0, 3, 10000, 5, on_c, c);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    int32_t c_start[2] = {1000, 0};
    len = enc(b, 2, LSM_CO_PATH_ARC_CW, 0, 3, 10000, 5, end, c_start);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    /* a full circle (end == start) is fine */
    len = enc(b, 2, LSM_CO_PATH_ARC_CW, 0, 3, 10000, 5, end, c);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), 0);
    /* zero-length line */
    len = enc(b, 3, LSM_CO_PATH_LINE, 0, 3, 10000, 5, end, NULL);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), LSM_CO_ABORT_VALUE);
    /* ZX arc needs axis 2 (present here); on a 2-axis node it is refused */
    int32_t e2[3] = {0, 0, 1000}, cz[2] = {500, 0};
    len = enc(b, 3, LSM_CO_PATH_ARC_CCW, 1, 3, 10000, 5, e2, cz);
    assert_int_equal(sdo_dl(&tn, 0x5010, 0, b, len), 0);
    assert_int_equal(tn.node.path.n_refused, 14);
    assert_int_equal(lsm_co_path_count(&tn.node.path), 3);
    static test_node two;
    assert_int_equal(tn_init(&two, 2, PATHCAP), LSM_OK);
    int32_t e3[2] = {1000, 0}, c3[2] = {500, 0};
    len = enc(b, 1, LSM_CO_PATH_ARC_CCW, 1, 2, 10000, 5, e3, c3);
    lsm_co_path_block blk;
    assert_int_equal(lsm_co_path_decode(&two.node.path, b, len, &blk), LSM_CO_ABORT_VALUE);
    len = enc(b, 1, LSM_CO_PATH_ARC_CCW, 0, 2, 10000, 5, e3, c3); /* XY is fine */
    assert_int_equal(lsm_co_path_decode(&two.node.path, b, len, &blk), 0);
}

static void test_sequence(void **state)
{
    (void)state;
    assert_int_equal(send_line(1, 10), 0);
    assert_int_equal(send_line(1, 10), 0); /* retry after a lost response: acknowledged */
    assert_int_equal(lsm_co_path_count(&tn.node.path), 1);
    assert_int_equal(rd(0x5008, 1), 1);
    assert_int_equal(send_line(3, 30), LSM_CO_ABORT_VALUE_HIGH); /* gap */
    assert_int_equal(rd(0x5008, 2), 1);
    assert_int_equal(rd(0x5004, 0), 1);
    assert_int_equal(send_line(2, 20), 0);
    assert_int_equal(send_line(3, 30), 0);
    assert_int_equal(send_line(1, 10), 0); /* an old one: duplicate */
    assert_int_equal(rd(0x5008, 1), 2);
    assert_int_equal(lsm_co_path_count(&tn.node.path), 3);
    lsm_co_path_block blk;
    for (uint32_t s = 1; s <= 3; s++) {
        assert_int_equal(lsm_co_path_pop(&tn.node.path, &blk), LSM_OK);
        assert_int_equal(blk.seq, s);
        assert_int_equal(blk.end[0], (int32_t)(10 * s));
    }
    assert_int_equal(lsm_co_path_pop(&tn.node.path, &blk), LSM_E_EMPTY);
    /* resync near the wrap, then 0xFFFFFFFF, 0, 1 */
    assert_int_equal(sdo_write_u(&tn, 0x5004, 0, 0xFFFFFFFEu, 4), 0);
    assert_int_equal(send_line(0xFFFFFFFFu, 1), 0);
    assert_int_equal(send_line(0, 2), 0);
    assert_int_equal(send_line(0xFFFFFFFFu, 1), 0); /* duplicate across the wrap */
    assert_int_equal(send_line(1, 3), 0);
    assert_int_equal(lsm_co_path_count(&tn.node.path), 3);
    assert_int_equal(rd(0x5004, 0), 1);
    /* resync is refused with blocks in the buffer */
    assert_int_equal(sdo_write_u(&tn, 0x5004, 0, 0, 4), LSM_CO_ABORT_DEVICE_STATE);
}

static void test_full_buffer(void **state)
{
    (void)state;
    for (uint32_t s = 1; s <= PATHCAP; s++)
        assert_int_equal(send_line(s, (int32_t)s), 0);
    assert_int_equal(rd(0x5003, 0), 0);
    assert_int_equal(send_line(PATHCAP + 1, 99), LSM_CO_ABORT_STORE);
    assert_int_equal(rd(0x5004, 0), PATHCAP);
    assert_int_equal(send_line(PATHCAP, PATHCAP), 0); /* a duplicate needs no room */
    assert_int_equal(lsm_co_path_pop(&tn.node.path, NULL), LSM_OK);
    assert_int_equal(rd(0x5003, 0), 1);
    assert_int_equal(send_line(PATHCAP + 1, 99), 0);
}

static void path_axes_enable(void)
{
    for (size_t k = 0; k < 3; k++) {
        assert_int_equal(sdo_write_u(&tn, (uint16_t)(0x6060 + 0x800 * k), 0, 0xFF, 1), 0); /* mode -1 */
        enable_axis(&tn, k);
    }
}

static void report(bool standstill)
{
    lsm_co_path_report r = {0, 0, standstill, false};
    lsm_co_path_update(&tn.node.path, &r);
}

static void test_commands(void **state)
{
    (void)state;
    lsm_co_path *p = lsm_canopen_path(&tn.node);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_START, 1), LSM_CO_ABORT_DEVICE_STATE);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_HOLD, 1), LSM_CO_ABORT_DEVICE_STATE);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_RESUME, 1), LSM_CO_ABORT_DEVICE_STATE);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, 9, 1), LSM_CO_ABORT_VALUE);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_NOP, 1), 0);
    path_axes_enable();
    assert_true(lsm_canopen_axes_ready_for_path(&tn.node));
    assert_int_equal(send_line(1, 100), 0);
    assert_int_equal(send_line(2, 200), 0);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_START, 1), 0);
    assert_int_equal(rd(0x5002, 0), LSM_CO_PATH_RUNNING);
    assert_int_equal(lsm_co_path_get_motion(p), LSM_CO_PATH_MOTION_RUN);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_START, 1), 0); /* idempotent */
    report(false);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_HOLD, 1), 0);
    assert_int_equal(rd(0x5002, 0), LSM_CO_PATH_HOLDING);
    assert_int_equal(lsm_co_path_get_motion(p), LSM_CO_PATH_MOTION_HOLD);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_START, 1), LSM_CO_ABORT_DEVICE_STATE);
    report(true);
    assert_int_equal(rd(0x5002, 0), LSM_CO_PATH_HELD);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_RESUME, 1), 0);
    assert_int_equal(rd(0x5002, 0), LSM_CO_PATH_RUNNING);
    /* clear while moving: quick stop, buffer flushed at once, IDLE at rest */
    report(false);
    uint16_t epoch = p->epoch;
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_CLEAR, 1), 0);
    assert_int_equal(rd(0x5002, 0), LSM_CO_PATH_STOPPING);
    assert_int_equal(lsm_co_path_get_motion(p), LSM_CO_PATH_MOTION_QUICK);
    assert_int_equal(lsm_co_path_count(p), 0);
    assert_int_equal(p->epoch, epoch + 1);
    assert_int_equal(send_line(3, 300), LSM_CO_ABORT_DEVICE_STATE); /* no blocks while stopping */
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_RESUME, 1), LSM_CO_ABORT_DEVICE_STATE);
    report(true);
    assert_int_equal(rd(0x5002, 0), LSM_CO_PATH_IDLE);
    /* numbering continues after a clear; the previous end is forgotten (same end is not zero-length) */
    assert_int_equal(rd(0x5004, 0), 2);
    assert_int_equal(send_line(3, 200), 0);
    /* override */
    assert_int_equal(sdo_write_u(&tn, 0x5001, 0, 150, 1), 0);
    assert_int_equal(p->override_pct, 150);
    assert_int_equal(sdo_write_u(&tn, 0x5001, 0, 201, 1), LSM_CO_ABORT_VALUE_HIGH);
    assert_int_equal(sdo_write_u(&tn, 0x5001, 0, 0, 1), 0);
}

static void test_axis_events_hold_path(void **state)
{
    (void)state;
    lsm_co_path *p = lsm_canopen_path(&tn.node);
    path_axes_enable();
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_START, 1), 0);
    report(false);
    /* halt on axis 1: a feed hold */
    assert_int_equal(sdo_write_u(&tn, 0x6840, 0, 0x10F, 2), 0);
    lsm_canopen_process(&tn.node, 0);
    assert_int_equal(p->state, LSM_CO_PATH_HOLDING);
    assert_int_equal(lsm_co_path_get_motion(p), LSM_CO_PATH_MOTION_HOLD);
    /* resume is refused while the halt stays */
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_RESUME, 1), LSM_CO_ABORT_DEVICE_STATE);
    assert_int_equal(sdo_write_u(&tn, 0x6840, 0, 0x0F, 2), 0);
    assert_int_equal(sdo_write_u(&tn, 0x5000, 0, LSM_CO_PATH_CMD_RESUME, 1), 0);
    /* a fault on axis 2: the hold becomes a quick stop along the path */
    report(false);
    lsm_canopen_axis_fault(&tn.node, 2, 0x7300);
    lsm_canopen_process(&tn.node, 0);
    assert_int_equal(p->state, LSM_CO_PATH_HOLDING);
    assert_int_equal(lsm_co_path_get_motion(p), LSM_CO_PATH_MOTION_QUICK);
}

static void test_planner_reject(void **state)
{
    (void)state;
    tn_nmt(&tn, 0x01, NODE_ID);
    assert_int_equal(send_line(1, 100), 0);
    assert_int_equal(send_line(2, 200), 0);
    lsm_co_path_reject(&tn.node.path, 2);
    lsm_canopen_process(&tn.node, 0);
    drain(&tn);
    lsm_can_frame e;
    assert_int_equal(count_id(&tn, 0x085, &e), 1);
    assert_int_equal(lsm_can_get_u16(&e.data[0]), 0xFF01);
    assert_int_equal(lsm_can_get_u32(&e.data[4]), 2);
    assert_int_equal(lsm_co_path_count(&tn.node.path), 0);
}

static void test_telemetry(void **state)
{
    (void)state;
    tn_nmt(&tn, 0x01, NODE_ID);
    assert_int_equal(send_line(1, 100), 0);
    assert_int_equal(send_line(2, 200), 0);
    lsm_co_path_report r = {7, 12345, false, false};
    lsm_co_path_update(&tn.node.path, &r);
    assert_int_equal(tn_rx(&tn, mkframe(0x080, 0, NULL)), LSM_OK);
    drain(&tn);
    lsm_can_frame f;
    assert_int_equal(count_id(&tn, 0x285, &f), 1);
    assert_int_equal(f.data[0], LSM_CO_PATH_IDLE);
    assert_int_equal(lsm_can_get_u16(&f.data[1]), PATHCAP - 2);
    assert_int_equal(lsm_can_get_u32(&f.data[3]), 2);
    assert_int_equal(count_id(&tn, 0x485, &f), 1);
    assert_int_equal(lsm_can_get_u32(&f.data[4]), 7);
    assert_int_equal(rd(0x5006, 0), 12345);
    /* underrun counted on the rising edge of `starved` while running */
    tn.node.path.state = LSM_CO_PATH_RUNNING;
    r.starved = true;
    lsm_co_path_update(&tn.node.path, &r);
    lsm_co_path_update(&tn.node.path, &r);
    assert_int_equal(rd(0x5008, 4), 1);
}

/* ---- randomized lossy channel ---- */

static uint64_t g_rng;
static uint32_t rnd(void)
{
    g_rng ^= g_rng << 13;
    g_rng ^= g_rng >> 7;
    g_rng ^= g_rng << 17;
    return (uint32_t)(g_rng >> 11);
}
static bool chance(uint32_t permille)
{
    return rnd() % 1000u < permille;
}

static uint32_t g_drop; /* per-mille of frames lost each way */

/* One request/response over the lossy channel: false if either frame is lost. */
static bool lossy(const uint8_t d[8], lsm_can_frame *resp)
{
    tn.now_us += 100;
    if (chance(g_drop))
        return false;
    assert_int_equal(tn_rx(&tn, mkframe(0x605, 8, d)), LSM_OK);
    drain(&tn);
    if (count_id(&tn, 0x585, resp) != 1)
        return false;
    return !chance(g_drop);
}

/* Sends a block once: 1 accepted (or duplicate), 0 lost somewhere, -1 refused (abort code in *ab). */
static int lossy_block(const uint8_t *b, size_t len, uint32_t *ab)
{
    uint8_t d[8] = {0x21, 0x10, 0x50, 0x00, 0, 0, 0, 0};
    lsm_can_put_u32(&d[4], (uint32_t)len);
    lsm_can_frame r;
    if (!lossy(d, &r))
        return 0;
    if (r.data[0] == 0x80) {
        *ab = abort_code(&r);
        return -1;
    }
    size_t pos = 0;
    uint8_t t = 0;
    while (pos < len) {
        size_t n = len - pos > 7 ? 7 : len - pos;
        memset(d, 0, 8);
        d[0] = (uint8_t)(t | ((7u - n) << 1) | (pos + n == len ? 1u : 0u));
        memcpy(&d[1], &b[pos], n);
        if (!lossy(d, &r))
            return 0; /* the master gives up this attempt */
        if (r.data[0] == 0x80) {
            *ab = abort_code(&r);
            return -1;
        }
        pos += n;
        t ^= 0x10;
    }
    return 1;
}

static bool lossy_read_last(uint32_t *last)
{
    uint8_t d[8] = {0x40, 0x04, 0x50, 0x00, 0, 0, 0, 0};
    lsm_can_frame r;
    if (!lossy(d, &r) || r.data[0] == 0x80)
        return false;
    *last = lsm_can_get_u32(&r.data[4]);
    return true;
}

static void test_lossy_channel(void **state)
{
    (void)state;
    unsigned long dups = 0, blocks = 0, full = 0;
    for (unsigned long run = 0; run < g_count; run++) {
        setup(NULL);
        g_rng = 0x9E3779B97F4A7C15ull ^ ((uint64_t)(g_seed * 1000003ul + run) * 0xD1B54A32D192ED03ull);
        if (g_rng == 0)
            g_rng = 1;
        g_drop = rnd() % 300u; /* up to 30 % of the frames lost */
        uint32_t n_blocks = 5u + rnd() % 60u;
        uint32_t next = 1, popped = 0, attempts = 0;
        while (popped < n_blocks) {
            if (++attempts > 200000u)
                fail_msg("run %lu: no progress (seed %lu)", run, g_seed);
            /* the application drains at random */
            if (chance(300)) {
                lsm_co_path_block blk;
                if (lsm_co_path_pop(&tn.node.path, &blk) == LSM_OK) {
                    if (blk.seq != popped + 1u || blk.end[0] != (int32_t)(blk.seq * 7u))
                        fail_msg("run %lu: popped seq %u (end %d), expected %u", run, blk.seq, blk.end[0], popped + 1u);
                    popped++;
                }
            }
            if (next > n_blocks)
                continue;
            uint8_t b[64];
            int32_t end[3] = {(int32_t)(next * 7u), (int32_t)next, 0};
            size_t len = enc(b, next, LSM_CO_PATH_LINE, 0, 3, 5000, 3, end, NULL);
            uint32_t ab = 0;
            int res = lossy_block(b, len, &ab);
            if (res == 1) {
                next++;
            } else if (res == -1) {
                if (ab != LSM_CO_ABORT_STORE && ab != LSM_CO_ABORT_VALUE_HIGH)
                    fail_msg("run %lu: unexpected abort 0x%08X", run, ab);
                full += ab == LSM_CO_ABORT_STORE;
                /* full: wait; gap: resync from the node's last accepted */
                uint32_t last;
                if (ab == LSM_CO_ABORT_VALUE_HIGH && lossy_read_last(&last))
                    next = last + 1u;
            } else if (chance(500)) {
                /* lost: either retry the same block, or ask the node where it is */
                uint32_t last;
                if (lossy_read_last(&last))
                    next = last + 1u;
            }
        }
        assert_int_equal(lsm_co_path_count(&tn.node.path), 0);
        assert_int_equal(tn.node.path.last_seq, n_blocks);
        assert_int_equal(tn.node.path.n_gap, 0);
        dups += tn.node.path.n_dup;
        blocks += n_blocks;
    }
    printf("lossy channel: %lu blocks, %lu duplicates acknowledged, %lu refusals for a full buffer\n", blocks, dups,
           full);
    if (g_count >= 100) /* the runs must actually have exercised retries and flow control */
        assert_true(dups > 0 && full > 0);
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, g_seed);
    g_count = (unsigned long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    printf("test_co_path: seed %lu, %lu lossy runs\n", g_seed, g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_decode, setup),
        cmocka_unit_test_setup(test_validation, setup),
        cmocka_unit_test_setup(test_sequence, setup),
        cmocka_unit_test_setup(test_full_buffer, setup),
        cmocka_unit_test_setup(test_commands, setup),
        cmocka_unit_test_setup(test_axis_events_hold_path, setup),
        cmocka_unit_test_setup(test_planner_reject, setup),
        cmocka_unit_test_setup(test_telemetry, setup),
        cmocka_unit_test(test_lossy_channel),
    };
    return test_seed_finish(argv[0], g_seed, g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
