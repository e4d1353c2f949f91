/*
 * ctl_app.h: the controller application (ctl_app_*): the Lissom CANopen node (canopen.h: CiA 301 + the CiA 402
 * axes + the path buffer) with a motion layer (ctl_motion.h), reached over a serial line that speaks the slcan
 * protocol of USB-CAN adapters (slcan.h). Portable: the board gives it a character link and calls it from two
 * contexts; time is counted in control cycles.
 *
 * Contexts (an MCU: the tick is the periodic timer interrupt, the background is the main loop):
 *   ctl_app_init         main loop, before the tick starts.
 *   ctl_app_tick         the control tick, once per cycle. In this order:
 *                          1. the slcan lines received since the last tick, at most CTL_RX_CHARS_PER_TICK
 *                             characters (the rest waits for the next tick): commands answered, frames served
 *                             by lsm_canopen_rx in arrival order (NMT, SYNC, RPDO, heartbeat; SDO requests are
 *                             queued for the background's SDO server);
 *                          2. lsm_canopen_estop, lsm_canopen_process (timers, heartbeats, TPDOs at SYNC, EMCY; the
 *                             SDO server's object access of this cycle and its responses into the TX queue);
 *                          3. ctl_motion_tick (demands, feedback);
 *                          4. the node's frames up the link as slcan lines while the link has room (a frame that
 *                             finds no room waits for the next tick; while the channel is closed, the frames are
 *                             dropped, as an adapter drops bus traffic nobody opened it for).
 *                        The tick owns the node and its object dictionary: canopen.h, "Contexts".
 *   ctl_app_background   the main loop: the SDO server (lsm_canopen_sdo_background: the protocol of expedited and
 *                        segmented transfers, aborts and timeouts; its object accesses are applied by the tick, so
 *                        every object write and its side effects stay in the tick) and ctl_motion_background (the
 *                        path feed: planner appends, lsm_interp_prepare, the interpolator run ahead of the tick;
 *                        motion.h, mpipe.h).
 * Hand-offs: canopen.h (SDO: request ring, one access mailbox, response ring, reset epoch), mpipe.h (motion), and
 * clock_us (the tick's now_us for the SDO server's timeouts: one word, release / acquire). An SDO transfer step is
 * answered 1-2 ticks after its request arrives (its response leaves in the tick after the background made it).
 * The tick never waits on the background.
 * Time: now_us comes from the board's clock (a hardware timer, as lsm_port_time_us), not from counting ticks: a
 * tick that comes late (or is lost) delays the motion by a cycle but not the node's timers (heartbeats, SDO and
 * heartbeat-consumer timeouts).
 */
#ifndef CTL_APP_H
#define CTL_APP_H

#include "canopen.h"
#include "ctl_motion.h"
#include "slcan.h"

#ifndef CTL_TXQ
#define CTL_TXQ 64u /* node TX queue (frames): TPDOs, EMCY, heartbeat, SDO answers of one tick */
#endif
#ifndef CTL_PATH_SLOTS
#define CTL_PATH_SLOTS 64u /* co_path buffer (blocks, 0x5007) */
#endif
#ifndef CTL_RX_CHARS_PER_TICK
#define CTL_RX_CHARS_PER_TICK 512u /* bound of the tick's slcan parsing: ~20 frame lines, ~30 k instructions */
#endif

/* The board's character link (a UART). getc: next received character or -1; write: queues all n characters or
 * none (false); room: characters write can take now. All called from the tick only. */
typedef struct ctl_link {
    int (*getc)(void *ctx);
    bool (*write)(void *ctx, const char *s, size_t n);
    size_t (*room)(void *ctx);
    void *ctx;
} ctl_link;

typedef struct ctl_app_config {
    uint8_t node_id;         /* 1..127 */
    uint8_t n_axes;          /* 1..LSM_MAX_AXES */
    uint32_t cycle_us;       /* control cycle, 100..100000 */
    uint16_t heartbeat_ms;   /* 0x1017 default */
    const char *device_name; /* 0x1008 */
    ctl_motion *motion;      /* the motion layer's state (ctl_motion.h), caller-owned */
    ctl_link link;
} ctl_app_config;

typedef struct ctl_app_counters {
    uint32_t cycles;         /* ticks run */
    uint32_t frames_in;      /* frames from the host served by the node */
    uint32_t frames_refused; /* ... that lsm_canopen_rx refused (malformed, wrong NMT state) */
    uint32_t frames_out;     /* frames sent up the link */
    uint32_t frames_closed;  /* frames dropped while the channel was closed */
    uint32_t link_waits;     /* ticks that left a frame waiting for room on the link */
    uint32_t replies_lost;   /* command replies that found no room on the link */
} ctl_app_counters;

typedef struct ctl_app {
    lsm_canopen co;
    lsm_can_frame txbuf[CTL_TXQ];
    lsm_co_path_block blocks[CTL_PATH_SLOTS];
    lsm_slcan sl;
    ctl_motion *motion;
    ctl_link link;
    uint32_t cycle_us;
    uint32_t now_us;
    lsm_atomic_u32 clock_us; /* the tick's now_us, for the background's SDO timeouts (tick-written, release) */
    lsm_can_frame pending;   /* a frame taken from the node that waits for room on the link */
    bool have_pending;
    ctl_app_counters n;
} ctl_app;

/* Boots the node (boot-up frame queued; the channel is closed until the host sends O) and the motion layer.
 * Errors: LSM_E_NULL, LSM_E_ARG (cycle, link functions), those of lsm_canopen_init and ctl_motion_init.
 * Main loop, before the tick. */
lsm_status ctl_app_init(ctl_app *a, const ctl_app_config *cfg);

/* One control cycle (see above) at time now_us (the board's µs clock, wrapping). estop_active: the E-stop input;
 * stats: the port's tick statistics for 0x5F00 (may be NULL). Control tick. */
void ctl_app_tick(ctl_app *a, uint32_t now_us, bool estop_active, const lsm_canopen_tick_stats *stats);

/* The background's share of the work: the SDO server, then the motion layer's background; true when something was
 * done. Main loop. */
bool ctl_app_background(ctl_app *a);

#endif /* CTL_APP_H */
