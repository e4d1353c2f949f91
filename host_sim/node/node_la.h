/*
 * node_la.h: the look-ahead path executor of lissom-node (node_la_*): the blocks of the CANopen path buffer
 * (co_path.h) go into the firmware's look-ahead planner (planner.h: sin² velocity profile across blocks, corner
 * blending with clothoid pairs within each block's tolerance, per-axis v/a/j limits) and its per-cycle
 * interpolator (interp.h) produces the axis set-points. This is the default executor (lissom-node
 * --path-exec planner); node_path.h is the exact-stop one.
 *
 * Mapping of the co_path commands and states:
 *   RUN (start / resume): blocks are moved from the co_path buffer into the planner while it has room
 *     (lsm_planner_free >= 3); a held interpolator resumes. Each block's tolerance is the corner tolerance at its
 *     end (G64 P); the override 0x5001 goes to lsm_interp_set_override (0 % holds).
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
 * Underrun: when the buffer ran dry the machine stops exactly on the end of the last block. WORKAROUND: with
 * interp.h as of this writing the interpolator may stay IDLE at such a stop although blocks are (or later get)
 * appended behind it. The executor keeps a copy of every co_path block it gave the planner; when the
 * interpolator is IDLE with blocks in the planner for two cycles while the path should run, it finds the block
 * whose end the axes stand on, restarts the planner empty there and appends the copies of the blocks after it
 * again (none is lost or run twice; the junction becomes an exact stop). If the axes stand on no block end, it
 * does nothing and counts it (stuck).
 *
 * Units: mm, s (block values in counts and µm are converted with each axis's 0x2001).
 */
#ifndef NODE_LA_H
#define NODE_LA_H

#include "co_path.h"
#include "interp.h"
#include "node_path.h"
#include "planner.h"

#ifndef NODE_LA_BLOCKS
#define NODE_LA_BLOCKS 256  /* largest planner block storage (look-ahead depth, corner transitions included) */
#endif

typedef struct node_la {
    uint8_t n_axes;
    double cycle_s;
    lsm_planner_config cfg;
    lsm_planner pl;
    lsm_pblock storage[NODE_LA_BLOCKS];
    uint32_t capacity;            /* blocks of storage used: LSM_PLANNER_MIN_BLOCKS .. NODE_LA_BLOCKS */
    lsm_interp ip;
    double pos[LSM_MAX_AXES];     /* set-points of the last cycle (mm) */
    double vel[LSM_MAX_AXES];     /* their velocity over the last cycle (mm/s) */
    uint16_t epoch;               /* co_path epoch of the blocks the planner holds */
    bool holding;                 /* lsm_interp_hold was requested */
    bool dirty;                   /* the planner holds blocks of an older epoch: restart it at rest */
    uint8_t override_pct;         /* last override passed on */
    uint32_t last_seq;            /* tag of the last block appended */
    uint32_t appended, rejected, restarts;
    uint32_t underrun_restarts;   /* planner restarted after an underrun stop (workaround above) */
    uint32_t stuck;               /* idle with blocks, not on a block end: left alone */
    uint32_t idle_cycles;         /* consecutive cycles IDLE with blocks while running */
    lsm_co_path_block saved[NODE_LA_BLOCKS]; /* copies of the blocks given to the planner, oldest first */
    uint32_t n_saved;
} node_la;

/* capacity: planner blocks (clamped to LSM_PLANNER_MIN_BLOCKS .. NODE_LA_BLOCKS; a block with a corner takes 3).
 * Errors: those of lsm_planner_init (limits, cycle). */
lsm_status node_la_init(node_la *la, uint8_t n_axes, double cycle_s, const node_axis_limits *lim, const double *pos,
                        uint32_t capacity);

/* The axes moved by other means: restart the (empty, idle) planner at these positions. Ignored while the planner
 * holds blocks or moves. */
void node_la_sync(node_la *la, const double *pos);

void node_la_step(node_la *la, lsm_co_path *cp, const double *cpm, lsm_co_path_report *rep);

bool node_la_moving(const node_la *la);

#endif /* NODE_LA_H */
