/*
 * fuzz_canopen: the CANopen node (firmware/canopen) under a sequence of frames and port events.
 *
 * A node (id 5, 3 axes, heartbeat 10 ms, consumer of node 1's heartbeat with 50 ms, 8-block path buffer) is
 * driven by operations of 11 bytes each:
 *   op % 8 = 0..3  a received frame: the identifier is, by the next byte, a CANopen service of this node (NMT,
 *                  SYNC, RPDO1-4, SDO request, heartbeat of node 1, EMCY) or any 11-bit id; DLC 0..8; a flag
 *                  byte that may set RTR or a 29-bit id; 8 data bytes
 *            4     time passes (0 .. 25.5 ms) and lsm_canopen_process runs
 *            5     the E-stop input level
 *            6     a bus event (OK, error passive, bus-off, RX overrun)
 *            7     the application cycle: the stop requests, PP and CSP fetches of every axis, a path block
 *                  popped when the path runs, and the feedback reported (at rest on the demand)
 * Each input runs twice: once with the SDO server in the tick, once with it in the background (sdo_background,
 * canopen.h), whose steps the input schedules: after each operation, op byte 10 % 4 background steps (0: starved,
 * so requests pile up in the ring, accesses wait, resets overtake them).
 * After each operation every queued frame is taken. Checks: every return code is one the API documents; every
 * transmitted frame has an 11-bit id, DLC <= 8, no RTR; the TX queue never holds more than its capacity; the
 * path buffer never holds more than its capacity; popped path blocks have increasing sequence numbers between
 * resets of the buffer (no accepted block runs twice); the NMT state is one of the four. ASan and UBSan catch the
 * rest (SDO segment buffers, PDO mapping, OD writes of odd sizes).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canopen.h"

#define FZ_NODE 5u
#define FZ_TXCAP 32u
#define FZ_PATHCAP 8u
#define FZ_OP_BYTES 11
#define FZ_MAX_OPS 400

static void fail(const char *what, unsigned long v)
{
    fprintf(stderr, "FUZZ VIOLATION (canopen): %s (%lu)\n", what, v);
    abort();
}

static uint32_t pick_id(uint8_t sel, uint8_t lo)
{
    static const uint32_t k_fc[] = {0x000, 0x080, 0x200, 0x300, 0x400, 0x500, 0x600, 0x700, 0x701, 0x081};
    const size_t n = sizeof k_fc / sizeof k_fc[0];
    if (sel < 200) {
        const uint32_t base = k_fc[sel % n];
        if (base == 0x000 || base == 0x080 || base == 0x701 || base == 0x081)
            return base; /* NMT, SYNC, heartbeat of node 1, EMCY of node 1 */
        return base + FZ_NODE;
    }
    return ((uint32_t)(sel & 7) << 8 | lo) & 0x7FFu;
}

static void check_status(lsm_status st, const char *what, int split)
{
    if (st != LSM_OK && st != LSM_E_CO_FRAME && st != LSM_E_CO_NMT_STATE && st != LSM_E_CO_BUS_OFF &&
        !(split && st == LSM_E_FULL)) /* the background's request ring full: refused with an abort */
        fail(what, (unsigned long)(long)st);
}

typedef struct fz_co {
    lsm_canopen node;
    lsm_can_frame tx[FZ_TXCAP];
    lsm_co_path_block blocks[FZ_PATHCAP];
    uint32_t now_us;
    uint32_t last_seq;
    uint16_t epoch;
    int have_seq;
} fz_co;

static void drain(fz_co *c)
{
    lsm_can_frame f;
    size_t n = 0;
    while (lsm_canopen_tx_pop(&c->node, &f)) {
        if (f.dlc > 8 || (f.flags & LSM_CAN_FLAG_EXT) || (f.flags & LSM_CAN_FLAG_RTR) || f.id > 0x7FFu)
            fail("bad frame sent, id", f.id);
        if (++n > FZ_TXCAP)
            fail("more frames than the TX queue holds", n);
    }
}

static void app_cycle(fz_co *c)
{
    for (size_t k = 0; k < c->node.n_axes; k++) {
        lsm_cia402 *ax = &c->node.axis[k];
        lsm_cia402_stop_req req;
        (void)lsm_cia402_stop_request(ax, &req);
        lsm_cia402_setpoint sp;
        if (lsm_cia402_pp_peek_next(ax, &sp))
            lsm_cia402_pp_done(ax);
        int32_t target;
        (void)lsm_cia402_csp_fetch(ax, &target);
        const lsm_cia402_feedback fb = {0, 0, 0, true};
        lsm_cia402_update(ax, &fb, c->now_us);
    }
    lsm_co_path *p = &c->node.path;
    if (lsm_co_path_count(p) > FZ_PATHCAP)
        fail("path buffer over its capacity", lsm_co_path_count(p));
    if (p->epoch != c->epoch || p->last_seq < c->last_seq)
        c->have_seq = 0; /* the buffer was cleared, reset or resynchronised: numbering starts again */
    c->epoch = p->epoch;
    lsm_co_path_report rep = {0, 0, true, true};
    if (lsm_co_path_get_motion(p) == LSM_CO_PATH_MOTION_RUN) {
        lsm_co_path_block b;
        if (lsm_co_path_pop(p, &b) == LSM_OK) {
            if (c->have_seq && b.seq <= c->last_seq)
                fail("a path block popped twice or out of order, seq", b.seq);
            c->last_seq = b.seq;
            c->have_seq = 1;
            rep.active_seq = b.seq;
            rep.standstill = false;
            rep.starved = false;
        }
    }
    lsm_co_path_update(p, &rep);
}

static void run(const uint8_t *data, size_t size, int split)
{
    static fz_co c;
    memset(&c, 0, sizeof c);
    lsm_canopen_config cfg = lsm_canopen_default_config();
    cfg.node_id = FZ_NODE;
    cfg.n_axes = 3;
    cfg.heartbeat_ms = 10;
    cfg.master_node_id = 1;
    cfg.master_timeout_ms = 50;
    cfg.tx_storage = c.tx;
    cfg.tx_cap = FZ_TXCAP;
    cfg.path_storage = c.blocks;
    cfg.path_cap = FZ_PATHCAP;
    cfg.device_name = "fuzz";
    cfg.sdo_background = split != 0;
    if (lsm_canopen_init(&c.node, &cfg, 0) != LSM_OK)
        fail("init", 0);
    drain(&c);
    size_t nops = size / FZ_OP_BYTES;
    if (nops > FZ_MAX_OPS)
        nops = FZ_MAX_OPS;
    for (size_t i = 0; i < nops; i++) {
        const uint8_t *o = data + i * FZ_OP_BYTES;
        const int op = o[0] % 8;
        if (op <= 3) {
            lsm_can_frame f;
            memset(&f, 0, sizeof f);
            f.id = pick_id(o[1], o[2]);
            f.dlc = (uint8_t)(o[0] >> 3) % 9u;
            if ((o[2] & 0xF0) == 0xF0)
                f.flags = (o[2] & 1) ? LSM_CAN_FLAG_RTR : LSM_CAN_FLAG_EXT;
            memcpy(f.data, o + 3, 8);
            check_status(lsm_canopen_rx(&c.node, &f, c.now_us), "rx status", split);
        } else if (op == 4) {
            c.now_us += (uint32_t)o[1] * 100u;
            check_status(lsm_canopen_process(&c.node, c.now_us), "process status", split);
        } else if (op == 5) {
            lsm_canopen_estop(&c.node, (o[1] & 1) != 0, c.now_us);
        } else if (op == 6) {
            lsm_canopen_bus_event(&c.node, (lsm_can_bus_event)(o[1] % 4), c.now_us);
        } else {
            app_cycle(&c);
        }
        const int s = (int)c.node.nmt.state;
        if (s != LSM_CO_NMT_INITIALISING && s != LSM_CO_NMT_PRE_OPERATIONAL && s != LSM_CO_NMT_OPERATIONAL &&
            s != LSM_CO_NMT_STOPPED)
            fail("NMT state", (unsigned long)s);
        drain(&c);
        for (int k = split ? o[FZ_OP_BYTES - 1] % 4 : 0; k > 0; k--)
            (void)lsm_canopen_sdo_background(&c.node, c.now_us);
        uint32_t waiting = 0;
        lsm_canopen_sdo_stats(&c.node, &waiting, NULL, NULL);
        if (waiting > LSM_CANOPEN_SDO_QUEUE)
            fail("SDO requests waiting beyond the ring", waiting);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    run(data, size, 0);
    run(data, size, 1);
    return 0;
}
