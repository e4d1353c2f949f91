/*
 * node_path.h: the path executor of lissom-node (node_path_*): runs the blocks of the CANopen path buffer
 * (co_path.h: lines and arcs with a feed and a tolerance) on the axes.
 *
 * INTERIM (documented in docs/hil.md): the look-ahead planner (firmware/plan/planner.h) was not available when this
 * was written, so every block is run on its own as an exact-stop move: the arc length s of the block goes from 0
 * to L with a rest-to-rest S-curve (node_prof.h, sin² profile, move.h engine) and the axes follow the block's
 * geometry at s. The feed is not blended across blocks: the path stops at every block end (no corner is cut,
 * the tolerance is not used for blending). Limits along the block:
 *   line, unit direction u:   v <= min(F, v_i / |u_i|), a <= a_i / |u_i|, j <= j_i / |u_i|, snap <= snap_i / |u_i|
 *                             over the axes that move (F = programmed feed x override);
 *   arc of radius r (plane axes p, q, smallest limits of the two): v <= min(F, v_pq, sqrt(a_pq r / 2),
 *                             cbrt(j_pq r² / 2), (snap_pq r³ / 2)^(1/4)); tangential a <= a_pq / 2, j <= j_pq / 2,
 *                             snap <= snap_pq / 2 (half the budget goes to the centripetal terms; the cross terms of
 *                             the axis jerk along a curve are not bounded exactly: arcs are approximate);
 *                             the other axes (helix) move linearly with s and limit it like a line does.
 * Arcs: the start is where the axes are, the centre is the block's; the radius goes linearly from the start
 * radius to the end radius (a small mismatch from rounding is absorbed); a mismatch larger than
 * max(tolerance, 2 counts) is refused (lsm_co_path_reject: EMCY 0xFF01, quick stop, buffer flushed). An arc
 * that ends where it starts is a full circle.
 * Feed hold (0x5000 = 2) and quick holds: a jerk-limited stop of s with the block's limits (node_stop.h), so the
 * axes stay on the path; resume plans the rest of the block from rest. Clear: the block is dropped at rest.
 * Override 0x5001 scales F when a block (or its remainder after a hold) is planned; 0 % starts nothing.
 *
 * Units: mm, s (block values in counts and µm are converted with each axis's 0x2001).
 */
#ifndef NODE_PATH_H
#define NODE_PATH_H

#include "co_path.h"
#include "node_prof.h"

typedef struct node_axis_limits {
    double v_max, a_max, j_max, snap_max;   /* mm/s .. mm/s⁴ */
} node_axis_limits;

typedef struct node_path {
    uint8_t n_axes;
    double cycle_s;
    node_axis_limits lim[LSM_MAX_AXES];
    double pos[LSM_MAX_AXES];       /* axis positions commanded by the path (mm) */
    double vel[LSM_MAX_AXES];       /* their velocity over the last cycle (mm/s) */
    node_prof s;                    /* arc length within the active block */
    bool active;                    /* a block is being executed (or held) */
    lsm_co_path_block blk;
    uint16_t epoch;                 /* co_path epoch when the block was taken */
    uint8_t type;
    double start[LSM_MAX_AXES], end[LSM_MAX_AXES], length;
    uint8_t pa, pb;                 /* arc: plane axes (first, second) */
    double c[2], r0, r1, th0, sweep;
    node_prof_limits plim;          /* limits along the block (feed without override) */
    double feed;                    /* programmed feed (mm/s) */
    uint32_t last_seq;              /* last block finished */
    uint32_t blocks_done;
    uint32_t rejected;
} node_path;

void node_path_init(node_path *np, uint8_t n_axes, double cycle_s, const node_axis_limits *lim, const double *pos);

/* The axes moved by other means: take their positions as the start of the next block (only at rest with no
 * active block; otherwise ignored). */
void node_path_sync(node_path *np, const double *pos);

/* One cycle: takes blocks, runs them, honours hold / quick / clear, fills the report for lsm_co_path_update.
 * cpm[k] = counts per mm of axis k (0x2001). */
void node_path_step(node_path *np, lsm_co_path *cp, const double *cpm, lsm_co_path_report *rep);

/* True while the executor commands motion (a block runs or stops). */
bool node_path_moving(const node_path *np);

#endif /* NODE_PATH_H */
