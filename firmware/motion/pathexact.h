/*
 * pathexact.h: the exact-stop path executor (lsm_pathexact_*): runs the blocks of the CANopen path buffer
 * (co_path.h: lines and arcs with a feed and a tolerance) on the axes, every block on its own.
 *
 * Model. The arc length s of the block goes from 0 to L with a rest-to-rest S-curve (axprof.h, sin² profile,
 * move.h engine) and the axes follow the block's geometry at s. The feed is not blended across blocks: the path
 * stops at every block end (no corner is cut, the tolerance is not used for blending; the look-ahead executor
 * pathfeed.h does that). Limits along the block:
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
 * Feed hold (0x5000 = 2) and quick holds: a jerk-limited stop of s with the block's limits (jstop.h), so the
 * axes stay on the path; resume plans the rest of the block from rest. Clear: the block is dropped at rest.
 * Override 0x5001 scales F when a block (or its remainder after a hold) is planned; 0 % starts nothing.
 *
 * Contexts: control cycle (lsm_pathexact_step plans a block's move when it takes it: one move plan, bounded).
 * The executor and the co_path buffer it pops are owned by the control cycle. Caller-owned memory.
 *
 * Units: mm, s (block values in counts and µm are converted with each axis's counts per mm, 0x2001).
 */
#ifndef LSM_PATHEXACT_H
#define LSM_PATHEXACT_H

#include "axprof.h"
#include "co_path.h"

typedef struct lsm_pathexact {
    uint8_t n_axes;
    lsm_real cycle_s;
    lsm_axis_limits lim[LSM_MAX_AXES];
    lsm_real pos_mm[LSM_MAX_AXES];   /* axis positions commanded by the path */
    lsm_real vel_mm_s[LSM_MAX_AXES]; /* their velocity over the last cycle */
    lsm_axprof s;                    /* arc length within the active block */
    bool active;                     /* a block is being executed (or held) */
    lsm_co_path_block blk;
    uint16_t epoch; /* co_path epoch when the block was taken */
    uint8_t type;
    lsm_real start_mm[LSM_MAX_AXES], end_mm[LSM_MAX_AXES], length_mm;
    uint8_t pa, pb; /* arc: plane axes (first, second) */
    lsm_real c_mm[2], r0_mm, r1_mm, th0_rad, sweep_rad;
    lsm_axprof_limits plim; /* limits along the block (feed without override) */
    lsm_real feed_mm_s;     /* programmed feed */
    uint32_t last_seq;      /* last block finished */
    uint32_t blocks_done;
    uint32_t rejected;
} lsm_pathexact;

/* n_axes 1..LSM_MAX_AXES, lim[n_axes], pos_mm[n_axes] or NULL (all 0). Errors: LSM_E_NULL, LSM_E_ARG.
 * Before the control cycle runs. */
lsm_status lsm_pathexact_init(lsm_pathexact *np, uint8_t n_axes, lsm_real cycle_s, const lsm_axis_limits *lim,
                              const lsm_real *pos_mm);

/* The axes moved by other means: take their positions as the start of the next block (only at rest with no
 * active block; otherwise ignored). Control cycle. */
void lsm_pathexact_sync(lsm_pathexact *np, const lsm_real *pos_mm);

/* One cycle: takes blocks, runs them, honours hold / quick / clear, fills the report for lsm_co_path_update.
 * cpm[k] = counts per mm of axis k (0x2001). Control cycle. */
void lsm_pathexact_step(lsm_pathexact *np, lsm_co_path *cp, const lsm_real *cpm, lsm_co_path_report *rep);

/* True while the executor commands motion (a block runs or stops). Control cycle. */
bool lsm_pathexact_moving(const lsm_pathexact *np);

#endif /* LSM_PATHEXACT_H */
