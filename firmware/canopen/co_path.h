/*
 * co_path.h: coordinated path motion over CANopen (manufacturer objects 0x5000-0x5010): a buffer of
 * path blocks with sequence numbers, flow control, start / hold / resume / clear and an override.
 * The planner is not here: the application takes the blocks out of the buffer and runs them.
 *
 * Path block (object 0x5010, DOMAIN, written with one SDO download; little-endian):
 *
 *     offset  size  field
 *      0      4     seq        UNSIGNED32 sequence number, one more than the previous block's (wraps)
 *      4      1     type       1 line (G1), 2 arc clockwise (G2), 3 arc counter-clockwise (G3)
 *      5      1     plane      arcs: 0 XY (axes 0,1; G17), 1 ZX (axes 2,0; G18), 2 YZ (axes 1,2; G19); lines: 0
 *      6      1     n          number of axes in the block, must equal the node's axis count
 *      7      1     flags      reserved, 0
 *      8      4     feed       UNSIGNED32 path feed in µm/s, >= 1
 *     12      4     tolerance  UNSIGNED32 contour tolerance in µm, >= 1 (corner blending, arc chords)
 *     16      4·n   end        INTEGER32 per axis, absolute end position in counts
 *     16+4n   8     centre     arcs only: INTEGER32 ×2, absolute centre in counts on the plane's first and
 *                              second axis (XY: X,Y; ZX: Z,X; YZ: Y,Z); the third axis moves linearly (helix);
 *                              an arc that ends where it starts is a full circle
 *     length = 16 + 4n (line), 24 + 4n (arc); at most LSM_CO_PATH_BLOCK_MAX = 48 bytes for 6 axes.
 *
 * Because the SDO server applies a segmented download only when it is complete, a block is stored whole
 * or not at all, and the SDO response tells the master which. Checks, in this order, with their abort code:
 *   length < 16: 0x06070013;  type not 1..3, n != axis count, plane not 0..2 or an arc plane axis the node does
 *   not have, flags != 0: 0x06090030;  length != 16 + 4n (+8): 0x06070012 / 0x06070013;  feed or tolerance 0:
 *   0x06090032;  an arc whose end is its centre: 0x06090030;
 *   then the sequence number, relative to the last accepted one L (wrap-safe, as int32):
 *     seq <= L       duplicate (a retry after a lost response): acknowledged, NOT stored again, counted;
 *     seq >  L + 1   gap: refused with 0x06090031, counted; the master resends from L + 1 (read 0x5004);
 *     seq == L + 1   goes on:
 *   a line of zero length, an arc whose start is its centre (compared with the previous block's end, when
 *   there is one since the last clear): 0x06090030;  buffer full: 0x08000020 (nothing stored; retry when
 *   0x5003 free slots > 0);  else stored and L = seq;
 *   while STOPPING (a clear in progress): 0x08000022.
 * So no block is lost (every refusal is answered) and none is applied twice.
 *
 * States (0x5002):  IDLE --start--> RUNNING --hold--> HOLDING --(standstill)--> HELD --resume--> RUNNING
 *                   any --clear--> STOPPING --(standstill)--> IDLE   (clear at rest goes straight to IDLE)
 *   Commands (0x5000, UNSIGNED8): 1 start, 2 hold, 3 resume, 4 clear (flush the buffer, stop, forget the
 *   previous end), 0 no operation. Start/resume need every axis in OPERATION ENABLED, mode -1, no stop
 *   request (the node checks) and answer 0x08000022 otherwise, as does hold/resume from IDLE or STOPPING.
 *   Other values: 0x06090030. A node fault (E-stop, lost master, axis fault, halt) turns RUNNING into HOLDING
 *   with a quick stop along the path; the blocks stay, and resume continues after the master re-enables.
 *   The running state survives an empty buffer: the planner stops at the end of the last block and goes on
 *   when more arrive (the application counts such underruns in 0x5008 sub 4).
 * Override 0x5001: UNSIGNED8 percent of the programmed feed, 0..200 (above: 0x06090031).
 * Sequence resync 0x5004 (last accepted): writable only in IDLE with an empty buffer.
 * Telemetry (TPDO-mappable): 0x5002 state, 0x5003 free slots, 0x5004 last accepted sequence, 0x5005 sequence
 * of the block being executed, 0x5006 path feed in µm/s, 0x5008 counters (duplicates, gaps, refused, underruns).
 *
 * Epoch: each clear (and each block the planner refuses) increments `epoch`; the application drops the
 * blocks it took from the buffer under an older epoch.
 * Contexts: the path buffer is the tick's (canopen.h, "Contexts"): every call here. A 0x5010 block sent by SDO is
 * collected by the background's SDO server and appended by the tick when it applies the server's write access
 * (co_sdo.h), so the buffer has one writer; the motion layer's background gets the blocks through mpipe.h.
 */
#ifndef LSM_CO_PATH_H
#define LSM_CO_PATH_H

#include "lsm_config.h"
#include "status.h"

#define LSM_CO_PATH_BLOCK_MAX (24u + 4u * LSM_MAX_AXES)

typedef enum lsm_co_path_type {
    LSM_CO_PATH_LINE = 1,
    LSM_CO_PATH_ARC_CW = 2,
    LSM_CO_PATH_ARC_CCW = 3
} lsm_co_path_type;

typedef enum lsm_co_path_state {
    LSM_CO_PATH_IDLE = 0,
    LSM_CO_PATH_RUNNING = 1,
    LSM_CO_PATH_HOLDING = 2,
    LSM_CO_PATH_HELD = 3,
    LSM_CO_PATH_STOPPING = 4
} lsm_co_path_state;

typedef enum lsm_co_path_cmd {
    LSM_CO_PATH_CMD_NOP = 0,
    LSM_CO_PATH_CMD_START = 1,
    LSM_CO_PATH_CMD_HOLD = 2,
    LSM_CO_PATH_CMD_RESUME = 3,
    LSM_CO_PATH_CMD_CLEAR = 4
} lsm_co_path_cmd;

/* What the application's planner must do. */
typedef enum lsm_co_path_motion {
    LSM_CO_PATH_MOTION_IDLE = 0, /* no path motion */
    LSM_CO_PATH_MOTION_RUN = 1,  /* run the blocks, feed scaled by the override */
    LSM_CO_PATH_MOTION_HOLD = 2, /* feed hold: decelerate along the path with the planner's limits, resumable */
    LSM_CO_PATH_MOTION_QUICK = 3 /* stop along the path as fast as jerk-limited motion allows (fault, clear) */
} lsm_co_path_motion;

/* A decoded block. */
typedef struct lsm_co_path_block {
    uint32_t seq;
    uint32_t feed_um_s;        /* µm/s */
    uint32_t tol_um;           /* µm */
    int32_t end[LSM_MAX_AXES]; /* counts, absolute */
    int32_t centre[2];         /* counts, arcs only */
    uint8_t type;              /* lsm_co_path_type */
    uint8_t plane;             /* 0 XY, 1 ZX, 2 YZ */
} lsm_co_path_block;

/* What the application reports each cycle. */
typedef struct lsm_co_path_report {
    uint32_t active_seq; /* block being executed (0x5005) */
    uint32_t feed_um_s;  /* present path feed (0x5006) */
    bool standstill;     /* path motion at rest */
    bool starved;        /* the planner is stopping or stopped for lack of blocks */
} lsm_co_path_report;

typedef struct lsm_co_path {
    lsm_co_path_block *ring;
    uint16_t cap, head, count;
    uint8_t n_axes;
    /* object values */
    uint8_t command;      /* 0x5000: last command accepted */
    uint8_t override_pct; /* 0x5001 */
    uint8_t state;        /* 0x5002 */
    uint16_t free_slots;  /* 0x5003 */
    uint32_t last_seq;    /* 0x5004 */
    uint32_t active_seq;  /* 0x5005 */
    uint32_t feed_um_s;   /* 0x5006 */
    uint16_t capacity;    /* 0x5007 */
    uint16_t n_dup;       /* 0x5008 sub 1 */
    uint16_t n_gap;       /* 0x5008 sub 2 */
    uint16_t n_refused;   /* 0x5008 sub 3 */
    uint16_t n_underrun;  /* 0x5008 sub 4 */
    /* runtime */
    bool quick; /* HOLDING/STOPPING is a quick stop */
    bool standstill;
    bool starved;
    bool have_prev;
    bool reject_pending; /* the planner refused a block: the node sends EMCY 0xFF01 */
    uint32_t reject_seq;
    uint16_t epoch;
    int32_t prev_end[LSM_MAX_AXES];
} lsm_co_path;

/* Binds the buffer storage[cap] (1..65535 blocks) for n_axes axes. State IDLE, last sequence 0 (the first
 * block is 1), override 100 %. Errors: LSM_E_NULL, LSM_E_ARG (cap), LSM_E_CO_AXES. Tick. */
lsm_status lsm_co_path_init(lsm_co_path *p, lsm_co_path_block *storage, size_t cap, uint8_t n_axes);

/* Decodes a block and checks what does not depend on the buffer (format, enumerations, feed, tolerance, end
 * radius of arcs). No state change. Returns 0 or the abort code; *b filled on success. Tick. */
uint32_t lsm_co_path_decode(const lsm_co_path *p, const uint8_t *data, size_t len, lsm_co_path_block *b);

/* 0x5010 write. Returns 0 (stored or duplicate) or the abort code. *st (may be NULL) tells LSM_OK,
 * LSM_E_CO_SEQ_DUP, LSM_E_CO_SEQ_GAP, LSM_E_FULL, LSM_E_CO_BLOCK or LSM_E_STATE. Tick. */
uint32_t lsm_co_path_write_block(lsm_co_path *p, const uint8_t *data, size_t len, lsm_status *st);

/* 0x5000 write; axes_ready: every axis may run path motion now. Returns 0 or the abort code. Tick. */
uint32_t lsm_co_path_command(lsm_co_path *p, int64_t cmd, bool axes_ready);

/* 0x5004 write (resync). Returns 0 or 0x08000022. Tick. */
uint32_t lsm_co_path_resync(lsm_co_path *p, uint32_t last_seq);

/* Node: a fault or stop of the axes holds a running path with a quick stop. Tick. */
void lsm_co_path_hold(lsm_co_path *p, bool quick);

/* Application side. Tick (canopen.h: the node is the tick's), as every call here. */
lsm_co_path_motion lsm_co_path_get_motion(const lsm_co_path *p);
size_t lsm_co_path_count(const lsm_co_path *p);
/* i-th queued block, 0 = oldest (look-ahead without consuming). False when i >= count. Tick. */
bool lsm_co_path_peek(const lsm_co_path *p, size_t i, lsm_co_path_block *b);
/* Takes the oldest block out of the buffer. LSM_E_EMPTY when none. Tick. */
lsm_status lsm_co_path_pop(lsm_co_path *p, lsm_co_path_block *b);
void lsm_co_path_update(lsm_co_path *p, const lsm_co_path_report *r);
/* The planner refused block seq (geometry it cannot run): quick stop, buffer flushed, EMCY 0xFF01. Tick. */
void lsm_co_path_reject(lsm_co_path *p, uint32_t seq);

#endif /* LSM_CO_PATH_H */
