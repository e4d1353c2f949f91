/*
 * pathfeed.h: the look-ahead path feed (lsm_pathfeed_*): the blocks of the CANopen path buffer (co_path.h,
 * object 0x5010) go into the look-ahead planner (planner.h: sin² velocity profile across blocks, corner blending
 * with clothoid pairs within each block's tolerance, per-axis v/a/j limits after Beudaert) and its per-cycle
 * interpolator (interp.h) produces the axis set-points. This is the default path executor of the CiA 402 layer
 * (motion.h); pathexact.h is the exact-stop one.
 *
 * Mapping of the co_path commands and states:
 *   RUN (start / resume): blocks are moved from the co_path buffer into the planner while it has room
 *     (lsm_planner_free >= LSM_PATHFEED_FREE_MIN: a block with a blended corner takes 3); this is the flow
 *     control of 0x5010: the co_path buffer (0x5003 free slots) fills while the planner is full. A held
 *     interpolator resumes. Each block's tolerance is the corner tolerance at its end (G64 P); the override
 *     0x5001 goes to lsm_interp_set_override (0 % holds).
 *   HOLD (feed hold) and QUICK (fault, lost master, E-stop, clear): lsm_interp_hold: at the next point where the
 *     tangential acceleration is 0 the axes decelerate along the path with one verified sin² ramp to rest (the
 *     planner keeps every axis within its v, a, j limits while doing so). The stop is therefore jerk-limited and
 *     stays on the path; it is not the shortest possible stop (it may first finish a ramp in progress).
 *   clear (co_path epoch changes) or a refused block: once at rest, the planner is restarted empty at the
 *     present position (the blocks it held are dropped).
 * The co_path sequence number is each planner block's tag, so the executing block (0x5005) is the tag of the
 * block under the interpolator's cursor (corner transitions carry the tag of the block they lead into).
 * A block the planner refuses (arc geometry, an axis the machine does not have) is rejected through
 * lsm_co_path_reject (EMCY 0xFF01, quick stop, buffer flushed). Arcs move X Y Z only (planner.h); an arc block
 * that moves a fourth axis is refused.
 *
 * Underrun: when the buffer ran dry the machine stops exactly on the end of the last block. WORKAROUND: the
 * interpolator may stay IDLE at such a stop although blocks are (or later get) appended behind it. The feed
 * keeps a copy of the latest co_path blocks it gave the planner (a ring of caller storage); when the
 * interpolator is IDLE with blocks in the planner for two cycles while the path should run, it finds the block
 * whose end the axes stand on, restarts the planner empty there and appends the copies of the blocks after it
 * again (none is lost or run twice; the junction becomes an exact stop). If the axes stand on no block end, it
 * does nothing and counts it (stuck).
 *
 * Contexts: the whole feed (planner, interpolator, block copies) belongs to ONE context, the one that calls
 * lsm_pathfeed_background(_io) and lsm_pathfeed_tick(_io): planner.h / interp.h do not yet hand their state between
 * a preempting lsm_interp_step and the appends / lsm_interp_prepare (docs/planner.md, "Concurrency"), so the feed
 * never splits them. In the synchronous loop that context is the control cycle (lsm_pathfeed_step: background
 * half, then the step). In the CiA 402 layer's split (motion.h) it is the background, which runs the feed ahead of
 * the tick and hands each cycle's set-points over (mpipe.h): the tick then calls nothing here. lsm_pathfeed_init:
 * before either runs. Caller-owned memory (planner blocks and block copies), no allocation.
 *
 * Units: mm, s (block values in counts and µm are converted with each axis's counts per mm, 0x2001).
 */
#ifndef LSM_PATHFEED_H
#define LSM_PATHFEED_H

#include "axprof.h"
#include "co_path.h"
#include "interp.h"
#include "planner.h"

/* Planner blocks that must be free before a co_path block is appended: a block with a blended corner takes
 * two corner transitions and itself. */
#define LSM_PATHFEED_FREE_MIN 3u

typedef struct lsm_pathfeed {
    uint8_t n_axes;
    lsm_real cycle_s;
    lsm_planner_config cfg;
    lsm_planner pl;
    lsm_pblock *storage; /* caller's planner blocks */
    uint32_t capacity;   /* blocks of storage */
    lsm_interp ip;
    lsm_real pos_mm[LSM_MAX_AXES];   /* set-points of the last cycle */
    lsm_real vel_mm_s[LSM_MAX_AXES]; /* their velocity over the last cycle */
    uint16_t epoch;                  /* co_path epoch of the blocks the planner holds */
    bool holding;                    /* lsm_interp_hold was requested */
    bool dirty;                      /* the planner holds blocks of an older epoch: restart it at rest */
    uint8_t override_pct;            /* last override passed on */
    uint8_t motion;                  /* lsm_co_path_motion seen by the last lsm_pathfeed_background */
    uint32_t last_seq;               /* tag of the last block appended */
    uint32_t appended, rejected, restarts;
    uint32_t underrun_restarts;              /* planner restarted after an underrun stop (workaround above) */
    uint32_t stuck;                          /* idle with blocks, not on a block end: left alone */
    uint32_t idle_cycles;                    /* consecutive cycles IDLE with blocks while running */
    lsm_co_path_block *saved;                /* caller's ring of copies of the blocks given to the planner */
    uint32_t saved_cap, saved_head, n_saved; /* oldest copy at saved[saved_head] */
} lsm_pathfeed;

/* Where lsm_pathfeed_background_io takes the co_path commands and blocks from: the node's co_path buffer in the
 * synchronous loop (lsm_pathfeed_background), or the motion layer's hand-off from the tick (motion.h). peek: the
 * next block (false: none); pop: drop it (appended or refused); reject: the planner refused block seq (the owner
 * of co_path calls lsm_co_path_reject); pending: blocks waiting upstream (0: the planner may emit the G1 points it
 * holds for arc fitting). All called from the context that runs lsm_pathfeed_background_io. */
typedef struct lsm_pathfeed_io {
    uint16_t epoch;       /* co_path epoch */
    uint8_t override_pct; /* 0x5001 */
    uint8_t motion;       /* lsm_co_path_motion */
    bool (*peek)(void *ctx, lsm_co_path_block *b);
    void (*pop)(void *ctx);
    void (*reject)(void *ctx, uint32_t seq);
    size_t (*pending)(void *ctx);
    void *ctx;
} lsm_pathfeed_io;

/* The feed's storage, owned by the caller for the feed's lifetime. blocks: planner storage (capacity
 * >= LSM_PLANNER_MIN_BLOCKS; a block with a corner takes 3). saved: block copies for the underrun workaround,
 * saved_cap > capacity (the planner never holds more blocks than its capacity; one more for the block the axes
 * stand on). */
typedef struct lsm_pathfeed_storage {
    lsm_pblock *blocks;
    uint32_t capacity;
    lsm_co_path_block *saved;
    uint32_t saved_cap;
} lsm_pathfeed_storage;

/* lim[n_axes]: the machine's axis limits; pos_mm[n_axes] or NULL (all 0). Errors: LSM_E_NULL, LSM_E_ARG (axes,
 * storage sizes), those of lsm_planner_init (limits, cycle). Background, before the cycle runs. */
lsm_status lsm_pathfeed_init(lsm_pathfeed *pf, uint8_t n_axes, lsm_real cycle_s, const lsm_axis_limits *lim,
                             const lsm_real *pos_mm, const lsm_pathfeed_storage *mem);

/* The axes moved by other means: restart the (empty, idle) planner at these positions. Ignored while the
 * planner holds blocks or moves. The feed's context. */
void lsm_pathfeed_sync(lsm_pathfeed *pf, const lsm_real *pos_mm);

/* One control cycle of the synchronous loop: lsm_pathfeed_background then lsm_pathfeed_tick. cpm[k] = counts
 * per mm of axis k (0x2001). Fills the report for lsm_co_path_update. The feed's context (which owns cp too). */
void lsm_pathfeed_step(lsm_pathfeed *pf, lsm_co_path *cp, const lsm_real *cpm, lsm_co_path_report *rep);

/* The co_path commands (epoch, override, run / hold), the block appends and the underrun workaround, then
 * lsm_interp_prepare, reading the node's co_path buffer directly. The feed's context, which must then own cp too
 * (the synchronous loop). */
void lsm_pathfeed_background(lsm_pathfeed *pf, lsm_co_path *cp, const lsm_real *cpm);

/* The same from any block source (lsm_pathfeed_io above). The context that owns the feed's planner: the
 * background (motion.h). */
void lsm_pathfeed_background_io(lsm_pathfeed *pf, const lsm_pathfeed_io *io, const lsm_real *cpm);

/* One interpolator step: the set-points pos_mm / vel_mm_s and the report. The context that steps the
 * interpolator: the control cycle in the synchronous loop; the background in motion.h's split, which runs the
 * interpolator ahead of the tick and hands its set-points over. */
void lsm_pathfeed_tick(lsm_pathfeed *pf, const lsm_co_path *cp, lsm_co_path_report *rep);

/* The same with the count of blocks waiting upstream given (the report's starved flag). Same context. */
void lsm_pathfeed_tick_io(lsm_pathfeed *pf, size_t pending, lsm_co_path_report *rep);

/* Restarts the (emptied) planner at rest at pos_mm[n_axes]: the blocks it held are dropped. Errors: those of
 * lsm_planner_init. The context that owns the feed. */
lsm_status lsm_pathfeed_restart_at(lsm_pathfeed *pf, const lsm_real *pos_mm);

/* True while the interpolator moves. The feed's context. */
bool lsm_pathfeed_moving(const lsm_pathfeed *pf);

#endif /* LSM_PATHFEED_H */
