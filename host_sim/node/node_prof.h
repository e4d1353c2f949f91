/*
 * node_prof.h: one coordinate's motion generator for lissom-node (node_prof_*): rest-to-rest S-curve moves
 * planned by the firmware's move engine (move.h, per-cycle positions from stepgen.h) and stops from any state
 * (node_stop.h). Used for every Profile Position axis and for the arc length along a path block.
 *
 * Profile types (CiA 402 object 0x6086):
 *   1  sin² ramp: the 15-phase move of move.h with the jerk limit J and the snap limit S as given.
 *   0  linear ramp, as generated here: the same engine with the snap limit replaced by S' = 1.0001 pi J / (2 dt)
 *      (dt = control cycle), which makes every sin² jerk rise and fall (T1, T3, T5, T7) exactly one cycle long.
 *      The jerk is therefore a plateau of constant height J_P <= J (T2, T6) switched on and off within one
 *      cycle: the classic constant-jerk 7-segment profile with a trapezoidal acceleration, quantised to whole
 *      cycles like the sin² profile. The snap limit 0x2061 is not used. (A linear velocity ramp with a step in
 *      acceleration is not offered: motion here is always jerk-limited.)
 * Acceleration: move.h has one acceleration limit for both ramps; a PP move uses min(0x6083, 0x6084).
 *
 * Retargeting a running move (PP "change set immediately"): if the coordinate cruises (a = 0) towards the new
 * target at no more than the new velocity limit, the new move is planned from that velocity (move.h v0 > 0);
 * otherwise the coordinate stops (jerk-limited, with the new set-point's deceleration) and then starts the new
 * move from rest.
 *
 * Units: mm (or rad), s.
 */
#ifndef NODE_PROF_H
#define NODE_PROF_H

#include "move.h"
#include "node_stop.h"
#include "stepgen.h"

typedef enum node_prof_mode {
    NODE_PROF_IDLE = 0,   /* at rest */
    NODE_PROF_MOVE = 1,   /* running a planned move */
    NODE_PROF_STOP = 2    /* running a stop */
} node_prof_mode;

typedef struct node_prof_limits {
    double v_max, a_max, j_max, snap_max;   /* u/s .. u/s⁴, all > 0 */
    int profile_type;                       /* 1 sin², 0 linear ramp */
} node_prof_limits;

typedef struct node_prof {
    double cycle_s;
    lsm_kin k;               /* present state: s_mm = position (axis frame), v, a, j */
    uint8_t mode;            /* node_prof_mode */
    uint8_t stop_kind;       /* caller's label of the running stop (bigger = stronger), 0 = none */
    lsm_move mv;
    lsm_stepgen gen;
    uint32_t cycle;          /* cycles of the move emitted */
    double origin;           /* move start position */
    double target;           /* move target */
    node_stop stop;
    bool have_after;         /* a move waits for the end of the stop (retarget) */
    double after_target;
    node_prof_limits after_lim;
} node_prof;

void node_prof_init(node_prof *p, double cycle_s, double pos);

/* Plans a move to target from the present state (see the header comment for a running coordinate). Returns
 * LSM_OK (moving, or already there: then mode stays IDLE), or the planner's error (nothing changed). */
lsm_status node_prof_move(node_prof *p, double target, const node_prof_limits *lim);

/* Starts a stop with these limits from the present state p->k, unless a stop at least as strong (kind) already
 * runs. Cancels a pending retarget. At rest (IDLE with v = a = 0): nothing. Returns LSM_OK or a node_stop_plan error (then the state is held: it cannot
 * happen with validated limits). */
lsm_status node_prof_stop(node_prof *p, const node_stop_limits *lim, uint8_t kind);

/* One cycle. Returns true if the coordinate moved during it. */
bool node_prof_step(node_prof *p);

static inline bool node_prof_at_rest(const node_prof *p)
{
    return p->mode == NODE_PROF_IDLE;
}

/* Limits for profile type 0 (see above): snap_max replaced. */
node_prof_limits node_prof_effective(const node_prof_limits *lim, double cycle_s);

#endif /* NODE_PROF_H */
