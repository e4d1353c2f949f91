/*
 * canopen.h: the Lissom CANopen node: CiA 301 communication (NMT slave, heartbeat producer and consumer,
 * SDO server, SYNC consumer, RPDO/TPDO, EMCY) around n CiA 402 axes (cia402.h) and the coordinated path
 * buffer (co_path.h). Transport-agnostic: frames in, frames out, time as an argument.
 *
 * Using it (one node per CAN bus, all storage owned by the caller, no allocation, no globals):
 *
 *     static lsm_canopen node;                          // 2.5 KB on Cortex-M4F, see docs/canopen.md
 *     static lsm_can_frame txbuf[16];
 *     static lsm_co_path_block blocks[32];
 *     lsm_canopen_config cfg = lsm_canopen_default_config();
 *     cfg.node_id = 5; cfg.n_axes = 3; cfg.tx_storage = txbuf; cfg.tx_cap = 16;
 *     cfg.path_storage = blocks; cfg.path_cap = 32;
 *     lsm_canopen_init(&node, &cfg, now_us);            // queues the boot-up frame, PRE-OPERATIONAL
 *     every control cycle (e.g. 1 ms), the tick:
 *         while (port receives f)  lsm_canopen_rx(&node, &f, now_us);   // SDO requests: queued (sdo_background)
 *         lsm_canopen_estop(&node, estop_input, now_us);            // level; edges are detected inside
 *         lsm_canopen_process(&node, now_us);                       // timers, heartbeats, events, TPDOs
 *         for each axis k: ax = lsm_canopen_axis(&node, k)
 *             lsm_cia402_stop_request(ax, &req)   -> honour it first (jerk-limited stop)
 *             lsm_cia402_pp_fetch(ax, &sp)        -> PP: start / replace a move (S-curve engine)
 *             lsm_cia402_csp_fetch(ax, &target)   -> CSP: new cyclic set-point
 *         path = lsm_canopen_path(&node): lsm_co_path_get_motion, lsm_co_path_pop -> the planner
 *         run the motion, then report:
 *             lsm_cia402_update(ax, &fb, now_us);  lsm_co_path_update(path, &rep);
 *         GPIO: drive enable = lsm_canopen_drive_enable(), in position = lsm_canopen_in_position()
 *         while (lsm_canopen_tx_pop(&node, &f)) port sends f;
 *     the background (main loop), with cfg.sdo_background = true:
 *         lsm_canopen_sdo_background(&node, now_us);                // the SDO server
 *
 * Contexts. Two: the tick (the control cycle: an interrupt on a board) and the background (the main loop). The
 * node's state (every object, the axes of cia402.h, the path buffer of co_path.h, the TX queue) is the tick's: only
 * the tick calls the node, and nothing of it is written by the background. Frames are queued, never sent from
 * inside, so the port decides when and from where they go out.
 *   tick        lsm_canopen_rx, _process, _estop, _bus_event, _axis_fault, _tx_pop, _set_tick_stats, the
 *               accessors; SYNC, PDOs, NMT, heartbeats, EMCY and every object access (SDO ones included).
 *   background  lsm_canopen_sdo_background (cfg.sdo_background): the SDO server's protocol (co_sdo.h: expedited and
 *               segmented transfers, toggles, sizes, abort codes, timeouts).
 *   before both lsm_canopen_init, lsm_canopen_default_config (any context), lsm_canopen_od_table.
 * The SDO hand-off (sdo_background true; lsm_canopen_sdo_link, every field with one writer context):
 *   tick -> bg   requests  ring of SDO request frames (0x600 + node id) with their reception time and the SDO epoch,
 *                          pushed by lsm_canopen_rx when the NMT state allows SDO;
 *   bg -> tick   access    one mailbox (co_sdo.h: at most one object access outstanding): read, write or the checks
 *                          of a segmented download's initiate. The tick applies it in lsm_canopen_process, one per
 *                          cycle, so every object write and its side effects (controlword, modes, targets, 0x5010
 *                          path blocks, PDO mapping) still happen in the tick, as without the split; the server's
 *                          buffer goes with the access and comes back with the answer;
 *   bg -> tick   responses ring of response frames, moved into the TX queue by lsm_canopen_process.
 *   tick -> bg   epoch     bumped by every SDO reset of the node (NMT stopped, reset communication, reset node):
 *                          the server drops its transfer on seeing it; requests, accesses and responses of an older
 *                          epoch are dropped unanswered (what a stopped or resetting node answers: nothing).
 *   Barriers: plain stores of a slot, then a release store of the producer's count; acquire load of the count
 *   before the slot is read; the consumer frees it with a release store of its own count (lsm_atomic.h; compiler
 *   fences on the single-core M4). Nothing waits: a full request ring refuses the request at once with the SDO abort
 *   0x05040005 (out of memory; a client that keeps the protocol, one request outstanding, never fills it), a full
 *   response ring makes the server wait before taking the next request, an access waits for the next tick.
 *   A request costs the tick its push (~100 instructions) and at most one object access per cycle (a table search
 *   and a copy of at most LSM_CANOPEN_SDO_BUF bytes); a confirmed transfer step takes 1-2 cycles longer than when
 *   the tick served it (its response goes out in the tick after the background made it).
 *   Ordering: requests are served in their order; a response means its write was applied. An NMT stop followed by
 *   an SDO request still finds the node stopped (the tick checks the state when the request arrives).
 * Without sdo_background (the default) the node serves SDO in the tick inside lsm_canopen_rx / _process (one context,
 * the unit tests and the fuzzer). A synchronous loop with sdo_background (lissom-node) calls lsm_canopen_sdo_sync
 * after each received frame and before lsm_canopen_process: the same frames in the same order as one context.
 *
 * Reactions to faults and bad input (details and codes in docs/canopen.md):
 *   - malformed frame (wrong DLC for its service, RTR, 29-bit id): ignored, counted (`malformed`), and for
 *     PDOs and SYNC the CiA EMCY (0x8210, 0x8220, 0x8240); the call returns LSM_E_CO_FRAME;
 *   - unknown objects, wrong sizes, out-of-range values: SDO abort codes (co_od.h);
 *   - path block gaps / duplicates: co_path.h (refused with 0x06090031 / acknowledged without effect);
 *   - heartbeat loss of a monitored node (0x1016): EMCY 0x8130, the 0x1029 sub 1 NMT behaviour (0 enter
 *     PRE-OPERATIONAL [default], 1 no change, 2 enter STOPPED), the 0x6007 action on every axis (default 3:
 *     quick stop) and a quick path hold; leaving OPERATIONAL for any reason also applies 0x6007;
 *   - bus-off (lsm_canopen_bus_event): the same communication-error reaction; the TX queue is flushed and
 *     nothing is queued until the port reports the bus is back; then EMCY 0x8140 (recovered from bus-off);
 *   - E-stop (lsm_canopen_estop, rising edge): every axis enters FAULT REACTION ACTIVE (the fastest
 *     jerk-limited stop) then FAULT with 0x603F = 0x9000, EMCY 0x9000; a fault reset is refused while the
 *     input stays active; releasing it sends the EMCY error reset;
 *   - NMT reset node: motion is first brought to a quick, jerk-limited stop, then everything restarts
 *     with its defaults and a boot-up frame; reset communication restarts 0x1000-0x1FFF at once.
 */
#ifndef LSM_CANOPEN_H
#define LSM_CANOPEN_H

#include "can.h"
#include "cia402.h"
#include "co_emcy.h"
#include "co_nmt.h"
#include "co_od.h"
#include "co_path.h"
#include "co_pdo.h"
#include "co_sdo.h"
#include "lsm_atomic.h"

/* Compile-time settings (LSM_CANOPEN_SDO_BUF): lsm_config.h. */

/* CiA 301 device type 0x1000: profile 402, servo drive. */
#define LSM_CANOPEN_DEVICE_TYPE 0x00020192u

/* Events the port reports about its CAN controller. */
typedef enum lsm_can_bus_event {
    LSM_CAN_BUS_OK = 0,            /* error active again (after error passive or bus-off recovery) */
    LSM_CAN_BUS_ERROR_PASSIVE = 1, /* error passive: EMCY 0x8120 */
    LSM_CAN_BUS_OFF = 2,           /* bus-off: communication-error reaction */
    LSM_CAN_BUS_RX_OVERRUN = 3     /* the port lost received frames: EMCY 0x8110 */
} lsm_can_bus_event;

/* Statistics of the port's control tick, shown read-only in object 0x5F00 (sub 1..8). The port fills them
 * (lsm_canopen_set_tick_stats); the node only shows them, and keeps them across an NMT reset. Sub 9 and 10 are the
 * node's own SDO hand-off counts (lsm_canopen_sdo_stats: most requests waiting, requests refused; 0 in the
 * one-context mode). */
typedef struct lsm_canopen_tick_stats {
    uint32_t ticks;            /* sub 1: control ticks since the port started */
    uint32_t overruns;         /* sub 2: ticks that fell due while the one before still ran */
    uint32_t worst_instr;      /* sub 3: longest tick, instructions from the timer event to the end of its work */
    uint16_t bg_load_permille; /* sub 4: share of the CPU the background used over the last second, per mille */
    uint32_t late_wakes;       /* sub 5: ticks that started late because the sleeping CPU was woken late (an
                                   emulator's host scheduling; not overruns of the tick's own work) */
    uint32_t clock_ms;         /* sub 6: the port's clock (the now_us the node runs on) in ms, wraps */
    uint32_t path_underruns;   /* sub 7: ticks whose path set-point the background had not made in time while the
                                   path moved (the motion layer's abort stop, motion.h) */
    uint32_t path_min_ahead;   /* sub 8: fewest path set-points the background had ready ahead of a tick while the
                                   path moved (0xFFFFFFFF: never moved) */
} lsm_canopen_tick_stats;

typedef struct lsm_canopen_config {
    uint8_t node_id;            /* 1..127 */
    uint8_t n_axes;             /* 1..LSM_MAX_AXES */
    uint16_t heartbeat_ms;      /* 0x1017 default, 0 = off */
    uint8_t master_node_id;     /* 0x1016 sub 1 default: node whose heartbeat is monitored, 1..127, 0 = none */
    uint16_t master_timeout_ms; /* its consumer time (0 = not monitored) */
    uint32_t vendor_id;         /* 0x1018 sub 1..4 */
    uint32_t product_code;
    uint32_t revision;
    uint32_t serial;
    const char *device_name;   /* 0x1008 (NUL-terminated, caller-owned, at most 64 bytes shown) */
    uint32_t sdo_timeout_us;   /* 0 = LSM_CO_SDO_TIMEOUT_US */
    bool sdo_background;       /* the SDO server runs in the background (lsm_canopen_sdo_background); false: in the
                                  tick, inside lsm_canopen_rx / _process (see "Contexts") */
    lsm_can_frame *tx_storage; /* TX queue storage */
    size_t tx_cap;
    lsm_co_path_block *path_storage; /* path buffer storage */
    size_t path_cap;
} lsm_canopen_config;

/* An SDO request frame in flight from the tick to the background server. */
typedef struct lsm_canopen_sdo_req {
    lsm_can_frame f;
    uint32_t rx_us; /* the tick's time when it was received */
    uint32_t epoch; /* the SDO epoch it was received in */
} lsm_canopen_sdo_req;

/* A response frame in flight from the background server to the tick's TX queue. */
typedef struct lsm_canopen_sdo_res {
    lsm_can_frame f;
    uint32_t epoch; /* the epoch of the request it answers */
} lsm_canopen_sdo_res;

/* The SDO hand-off (see "Contexts"). Counts are free-running; a ring's slot is count % LSM_CANOPEN_SDO_QUEUE. */
typedef struct lsm_canopen_sdo_link {
    bool enabled; /* cfg.sdo_background, written once by lsm_canopen_init (read by both) */
    /* written by the tick */
    lsm_atomic_u32 epoch;    /* SDO resets so far */
    lsm_atomic_u32 req_head; /* requests pushed */
    lsm_atomic_u32 res_tail; /* responses taken */
    lsm_atomic_u32 acc_done; /* accesses applied (the answer is in acc) */
    uint32_t refused;        /* requests refused with 0x05040005: the ring was full (wraps) */
    uint32_t stale;          /* accesses and responses dropped: an SDO reset came in between (wraps) */
    uint32_t most_waiting;   /* most requests waiting in the ring, seen at a push (this one included) */
    /* written by the background */
    lsm_atomic_u32 req_tail;   /* requests taken */
    lsm_atomic_u32 res_head;   /* responses pushed */
    lsm_atomic_u32 acc_posted; /* accesses posted */
    uint32_t acc_epoch;        /* the epoch of the posted access (with acc's request part) */
    uint32_t bg_epoch;         /* the epoch the server runs in */
    uint32_t bg_dropped;       /* requests of an older epoch dropped by the server (wraps) */
    /* slots: written by the ring's producer before its count is published */
    lsm_canopen_sdo_req req[LSM_CANOPEN_SDO_QUEUE];
    lsm_canopen_sdo_res res[LSM_CANOPEN_SDO_QUEUE];
    lsm_co_sdo_access acc; /* request part by the background, answer by the tick (mailbox) */
} lsm_canopen_sdo_link;

typedef struct lsm_canopen {
    /* node objects */
    uint32_t device_type;              /* 0x1000 */
    uint32_t cycle_period_us;          /* 0x1006 (the master's SYNC period, for CSP; 0 = unknown) */
    const char *device_name;           /* 0x1008 */
    uint32_t identity[4];              /* 0x1018 sub 1..4 */
    uint32_t sdo_cob_rx, sdo_cob_tx;   /* 0x1200 sub 1, 2 */
    uint8_t comm_error_behaviour;      /* 0x1029 sub 1 */
    uint8_t machine_status;            /* 0x5020: bit 0 E-stop, bit 1 a monitored heartbeat lost, bit 2 bus-off */
    lsm_canopen_tick_stats tick_stats; /* 0x5F00, written by the port */
    uint8_t n_axes;
    uint8_t node_id;
    /* modules */
    lsm_co_od od;
    lsm_co_nmt nmt;
    lsm_co_emcy emcy;
    lsm_co_pdo pdo;
    lsm_co_pdo pdo_boot; /* the default PDOs as built at init, restored by the resets */
    bool pdo_boot_valid;
    lsm_co_path path;
    lsm_cia402 axis[LSM_MAX_AXES];
    lsm_can_txq txq;
    /* runtime */
    lsm_canopen_config cfg; /* kept for resets */
    uint32_t now_us;        /* time of the call being served */
    uint32_t malformed;     /* frames ignored as malformed (wraps) */
    uint32_t tx_dropped_seen;
    uint8_t pending_reset; /* lsm_co_nmt_cmd waiting for standstill, or 0 */
    bool estop;
    bool bus_off;
    bool error_passive;
    /* The SDO server and its hand-off, last: an NMT reset node clears everything before sdo_link and nothing from it
     * on (with sdo_background they are not the tick's; the reset reaches the server through the epoch). */
    lsm_canopen_sdo_link sdo_link;
    lsm_co_sdo sdo;                       /* the server: the background's with sdo_background, else the tick's */
    uint8_t sdo_buf[LSM_CANOPEN_SDO_BUF]; /* its buffer: the server's, the tick's while an access is out */
} lsm_canopen;

/* A configuration with the documented defaults: node id 1, 1 axis, heartbeat 100 ms, no consumer, no
 * storage (the caller must set tx_storage/tx_cap and path_storage/path_cap). */
lsm_canopen_config lsm_canopen_default_config(void); /* any context */

/*
 * Builds the node and boots it: every object at its default, default PDO mapping (docs/canopen.md), the
 * boot-up frame queued, NMT PRE-OPERATIONAL. Errors: LSM_E_NULL (node, cfg, storage), LSM_E_CO_NODE_ID,
 * LSM_E_CO_AXES, LSM_E_ARG (a capacity 0 or > 65535, master_node_id > 127), LSM_E_CO_OD (internal table check
 * failed: a bug). Before the tick and the background run (their hand-off is set up here).
 */
lsm_status lsm_canopen_init(lsm_canopen *node, const lsm_canopen_config *cfg, uint32_t now_us);

/*
 * Serves one received frame. Returns LSM_OK (served, or not addressed to this node), LSM_E_CO_FRAME
 * (malformed: ignored; PDO/SYNC length errors also send their EMCY), LSM_E_CO_NMT_STATE (the service is not
 * available in the present NMT state: ignored), LSM_E_FULL (sdo_background: the SDO request ring was full, the
 * request was answered with the abort 0x05040005), LSM_E_NULL. With sdo_background an SDO request is only queued for
 * the background server. Tick.
 */
lsm_status lsm_canopen_rx(lsm_canopen *node, const lsm_can_frame *f, uint32_t now_us);

/* Timers (heartbeat, SDO timeout, event TPDOs), consumer timeouts, axis EMCY events, path/axis coupling,
 * pending NMT reset; with sdo_background: the SDO server's object access (one per call) and its responses into the
 * TX queue (the SDO timeout is then the server's). Call once per control cycle. Returns LSM_OK, LSM_E_CO_BUS_OFF
 * (done, but the controller is bus-off: nothing was queued) or LSM_E_NULL. Tick. */
lsm_status lsm_canopen_process(lsm_canopen *node, uint32_t now_us);

/*
 * The background SDO server (cfg.sdo_background): drops the transfer after an SDO reset of the tick, takes the answer
 * of its object access, serves the waiting requests until one needs an object access or the response ring is full,
 * then aborts an overdue transfer. now_us: the tick's clock as the tick published it after queueing that tick's
 * requests (ctl_app.h: release / acquire), so that every request received up to now_us is served before the
 * timeout is checked. True when something was done. Background (main loop), never the tick; false and nothing done
 * without sdo_background.
 */
bool lsm_canopen_sdo_background(lsm_canopen *node, uint32_t now_us);

/* The synchronous loop (one context owns both sides, e.g. lissom-node): lsm_canopen_sdo_background and the tick's
 * side of the hand-off alternately until nothing is left, so the responses are queued in the same order as without
 * the split. Call after each received frame and before lsm_canopen_process. The one context. */
void lsm_canopen_sdo_sync(lsm_canopen *node, uint32_t now_us);

/* The hand-off's diagnostics: requests waiting for the server now, most ever waiting, refused (ring full). Any
 * pointer may be NULL. Tick. */
void lsm_canopen_sdo_stats(lsm_canopen *node, uint32_t *waiting, uint32_t *most_waiting, uint32_t *refused);

/* Takes the next frame to send. False when none. Tick. */
bool lsm_canopen_tx_pop(lsm_canopen *node, lsm_can_frame *out);

/* Port-level controller events (see lsm_can_bus_event). Tick. */
void lsm_canopen_bus_event(lsm_canopen *node, lsm_can_bus_event ev, uint32_t now_us);

/* E-stop input level (true = stop requested); call every cycle, edges are detected here. Tick. */
void lsm_canopen_estop(lsm_canopen *node, bool active, uint32_t now_us);

/* An application fault on axis k (drive error, limit switch, ...): fault reaction with `code` in 0x603F
 * and its EMCY. Errors: LSM_E_NULL, LSM_E_ARG (k). Tick. */
lsm_status lsm_canopen_axis_fault(lsm_canopen *node, size_t k, uint16_t code);

/* Stores the port's tick statistics for object 0x5F00 (a port without them leaves it at 0). Tick. */
void lsm_canopen_set_tick_stats(lsm_canopen *node, const lsm_canopen_tick_stats *stats);

/* Accessors. lsm_canopen_axis returns NULL for k >= n_axes. Tick. */
lsm_cia402 *lsm_canopen_axis(lsm_canopen *node, size_t k);
lsm_co_path *lsm_canopen_path(lsm_canopen *node);
lsm_co_od *lsm_canopen_od(lsm_canopen *node);
lsm_co_nmt_state lsm_canopen_nmt_state(const lsm_canopen *node);
uint32_t lsm_canopen_sync_count(const lsm_canopen *node);
bool lsm_canopen_drive_enable(const lsm_canopen *node); /* some axis has its power stage on */
bool lsm_canopen_in_position(const lsm_canopen *node);  /* every axis in position */
/* True when every axis may run path motion (OPERATION ENABLED, mode -1, no stop). */
bool lsm_canopen_axes_ready_for_path(const lsm_canopen *node);

/* The node's dictionary table (for tools that list it, e.g. the EDS check). Constant: any context. */
const lsm_co_od_entry *lsm_canopen_od_table(size_t *n_entries);

#endif /* LSM_CANOPEN_H */
