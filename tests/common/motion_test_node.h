/*
 * motion_test_node.h: the storage and configuration of a CANopen node with the firmware's motion layer (canopen.h,
 * motion.h) as the motion tests boot it (tests/motion/: test_motion, test_motion_pipe, test_pp_midramp,
 * test_pp_props). Header-only, for tests. 1 ms cycle, the look-ahead feed on MTN_LA_BLOCKS planner blocks.
 */
#ifndef MOTION_TEST_NODE_H
#define MOTION_TEST_NODE_H

#include <string.h>

#include "canopen.h"
#include "motion.h"

#define MTN_TX_CAP 128u   /* node TX queue (frames) */
#define MTN_PATH_CAP 16u  /* co_path buffer (blocks) */
#define MTN_LA_BLOCKS 32u /* planner blocks of the look-ahead feed */

/* What the node and its motion layer run on (caller-owned; large: give it static storage). */
typedef struct mtn_storage {
    lsm_can_frame txbuf[MTN_TX_CAP];
    lsm_co_path_block blocks[MTN_PATH_CAP];
    lsm_pblock la_blocks[MTN_LA_BLOCKS];
    lsm_co_path_block la_saved[MTN_LA_BLOCKS + 1u];
} mtn_storage;

/* The node's configuration: id, axes, heartbeat (ms, 0: off), on st. */
static inline lsm_canopen_config mtn_canopen_config(mtn_storage *st, uint8_t nid, uint8_t n_axes, uint16_t heartbeat_ms)
{
    lsm_canopen_config cc = lsm_canopen_default_config();
    cc.node_id = nid;
    cc.n_axes = n_axes;
    cc.heartbeat_ms = heartbeat_ms;
    cc.tx_storage = st->txbuf;
    cc.tx_cap = MTN_TX_CAP;
    cc.path_storage = st->blocks;
    cc.path_cap = MTN_PATH_CAP;
    return cc;
}

/* The motion layer's configuration: n_axes with the limits lim (the same for every axis), 1 ms, the path executor,
 * the look-ahead feed on st, lead cycles. */
static inline lsm_motion_config mtn_motion_config(mtn_storage *st, uint8_t n_axes, const lsm_axis_limits *lim,
                                                  uint8_t path_exec, uint32_t lead)
{
    lsm_motion_config mc;
    memset(&mc, 0, sizeof mc);
    mc.n_axes = n_axes;
    mc.cycle_s = (lsm_real)0.001;
    for (unsigned k = 0; k < n_axes; k++)
        mc.lim[k] = *lim;
    mc.path_exec = path_exec;
    mc.feed.blocks = st->la_blocks;
    mc.feed.capacity = MTN_LA_BLOCKS;
    mc.feed.saved = st->la_saved;
    mc.feed.saved_cap = MTN_LA_BLOCKS + 1u;
    mc.lead_cycles = lead;
    return mc;
}

/* NMT start of node nid (received by co at now_us). */
static inline void mtn_nmt_start(lsm_canopen *co, uint8_t nid, uint32_t now_us)
{
    lsm_can_frame f;
    memset(&f, 0, sizeof f);
    f.dlc = 2;
    f.data[0] = 0x01;
    f.data[1] = nid;
    (void)lsm_canopen_rx(co, &f, now_us);
}

/* One control cycle at now_us in the synchronous order: the E-stop level, lsm_canopen_process, the motion tick,
 * the demand as feedback (ideal loopback), the TX queue drained, the background run until it is idle. */
static inline void mtn_sync_cycle(lsm_canopen *co, lsm_motion *mo, uint32_t now_us, bool estop)
{
    lsm_canopen_estop(co, estop, now_us);
    (void)lsm_canopen_process(co, now_us);
    lsm_motion_tick(mo, co);
    lsm_motion_feedback(mo, co, NULL, NULL, now_us);
    lsm_can_frame f;
    while (lsm_canopen_tx_pop(co, &f)) {
    }
    while (lsm_motion_background(mo)) {
    }
}

#endif /* MOTION_TEST_NODE_H */
