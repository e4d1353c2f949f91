/*
 * axprof.h: one coordinate's motion generator (lsm_axprof_*): rest-to-rest S-curve moves planned by the move
 * engine (move.h, per-cycle positions from stepgen.h) and jerk-limited stops from any state (jstop.h). Used for
 * every Profile Position axis of the CiA 402 layer (motion.h) and for the arc length along a path block
 * (pathexact.h).
 *
 * Profile types (CiA 402 object 0x6086):
 *   1  sin² ramp: the 15-phase move of move.h (Kombarov eqs 25-37) with the jerk limit J and the snap limit S.
 *   0  linear ramp, as generated here: the same engine with the snap limit replaced by S' = 1.0001 pi J / (2 dt)
 *      (dt = control cycle; eq 22 with a rise of one cycle), which makes every sin² jerk rise and fall (T1, T3,
 *      T5, T7) exactly one cycle long. The jerk is therefore a plateau of constant height J_P <= J (T2, T6)
 *      switched on and off within one cycle: the classic constant-jerk 7-segment profile with a trapezoidal
 *      acceleration, quantised to whole cycles like the sin² profile. The snap limit 0x2061 is not used. (A
 *      linear velocity ramp with a step in acceleration is not offered: motion here is always jerk-limited.)
 * Acceleration: move.h has one acceleration limit for both ramps; a PP move uses min(0x6083, 0x6084).
 *
 * Retargeting a running move (PP "change set immediately"), in the cycle of the request:
 *   - cruising (a = 0) towards the new target at no more than the new velocity limit: the new move is planned from
 *     that velocity (move.h v0 > 0);
 *   - else, with the target ahead: the velocity settles (lsm_jstop_plan_settle: a and j brought to 0 as fast as the
 *     new J and S allow, continuing the present jerk phase) to a cruise v_e, and the new move is planned from that
 *     cruise (mode CRUISE until then; with plan_outside the owner plans it, after_due), if v_e is within the new
 *     velocity limit and the target lies past the settle's end by at least the stop distance from v_e plus
 *     AXPROF_SETTLE_LEAD_CYCLES of cruise (axprof.c); a move from the cruise that still fails stops from it;
 *   - otherwise the coordinate stops (jerk-limited, with the new set-point's deceleration) and then starts the new
 *     move from rest.
 * (test_ppscan, HIL profile: of the retargets beyond the target requested at every cycle of the scanned moves, 361
 * of 5821 (type 1) and 636 of 5628 (type 0) come to rest on the way; the others settle or cruise on.)
 *
 * A stop or a retarget starts in the cycle it is requested in, from any state (v, a, j; also inside a jerk pulse
 * with the jerk changing): the stop (jstop.h) continues the move's present jerk phase where that keeps the move's
 * own bounds (the rest of a cos² fall of the jerk; the rest of a sin² rise of a braking jerk), goes on from a
 * braking jerk, and releases a jerk that raises |a| with a cos² fall at the snap limit (no faster release exists
 * within S, and it gains no more acceleration than the move's own fall would). The jerk stays continuous and
 * |snap| <= S (type 1); |v| <= V, |a| <= max(A, D), |j| <= max(J, |j0|) (tests/motion/test_ppscan: every request
 * cycle of a move; test_pp_midramp; test_pp_props: random requests at random cycles). (Before, a request inside a
 * jerk pulse waited for the pulse's end, up to one acceleration ramp, and an urgent stop released the jerk at once:
 * 100.54 mm/s against 100 on the HIL profile.)
 *
 * Contexts: lsm_axprof_step runs in the control cycle. lsm_axprof_move and lsm_axprof_stop plan (a move plan
 * is ~100 k instructions on the M4, a stop a bisection): they are called where the set-point or the stop
 * request is taken, in the control cycle of the CiA 402 layer (motion.h). The generator is owned by one
 * context; nothing here is shared. Caller-owned memory, no allocation.
 *
 * Units: mm (or rad), s.
 */
#ifndef LSM_AXPROF_H
#define LSM_AXPROF_H

#include "jstop.h"
#include "move.h"
#include "stepgen.h"

typedef enum lsm_axprof_mode {
    LSM_AXPROF_IDLE = 0,  /* at rest (or moved by the caller: CSP, path) */
    LSM_AXPROF_MOVE = 1,  /* running a planned move */
    LSM_AXPROF_STOP = 2,  /* running a stop, or a retarget's settle of the velocity (stop.settle) */
    LSM_AXPROF_CRUISE = 3 /* at the constant velocity a settle ended at, until the retarget's move is planned */
} lsm_axprof_mode;

/* The limits of one machine axis are move.h's lsm_axis_limits (v, a, j, snap; every requested value is clamped
 * to them). */

#define LSM_AXPROF_TYPE_LINEAR 0 /* 0x6086 = 0 */
#define LSM_AXPROF_TYPE_SIN2 1   /* 0x6086 = 1 */

typedef struct lsm_axprof_limits {
    lsm_real v_max_mm_s, a_max_mm_s2, j_max_mm_s3, snap_max_mm_s4; /* all > 0 */
    int profile_type;                                              /* LSM_AXPROF_TYPE_* */
} lsm_axprof_limits;

typedef struct lsm_axprof {
    lsm_real cycle_s;
    lsm_kin k;         /* present state: s_mm = position (axis frame), v, a, j */
    uint8_t mode;      /* lsm_axprof_mode */
    uint8_t stop_kind; /* caller's label of the running stop (bigger = stronger), 0 = none */
    lsm_move mv;
    lsm_stepgen gen;
    uint32_t cycle;     /* cycles of the move emitted */
    lsm_real origin_mm; /* move start position */
    lsm_real target_mm; /* move target */
    lsm_jstop stop;
    bool have_after;   /* a move waits for the end of the stop (retarget) */
    bool plan_outside; /* set by the owner: the waiting move is not planned inside lsm_axprof_step; at its
                                   time after_due is raised and the owner plans it (motion.h: in the background) */
    bool after_due;    /* plan_outside: the waiting move (after_target_mm, after_lim) is due now */
    lsm_real after_target_mm;
    lsm_axprof_limits after_lim;
    lsm_real cruise_origin_mm, cruise_v_mm_s; /* CRUISE: where it began, its velocity */
    uint32_t cruise_cycles;                   /* CRUISE: cycles run */
} lsm_axprof;

/* At rest at pos_mm. Any context (before the generator is in use). */
void lsm_axprof_init(lsm_axprof *p, lsm_real cycle_s, lsm_real pos_mm);

/* Plans a move to target_mm from the present state (see the header comment for a running coordinate). Returns
 * LSM_OK (moving, or already there: then mode stays IDLE), or the move engine's error (nothing changed).
 * Control cycle (the context that steps the generator). */
lsm_status lsm_axprof_move(lsm_axprof *p, lsm_real target_mm, const lsm_axprof_limits *lim);

/* Starts a stop with these limits from the present state p->k, in this cycle (also inside a jerk pulse of a move,
 * see above), unless a stop at least as strong (kind) already runs. Cancels a pending retarget. At rest (IDLE with
 * v = a = 0): nothing. Returns LSM_OK or a lsm_jstop_plan error (then the state is held: it cannot happen with
 * validated limits). Control cycle. */
lsm_status lsm_axprof_stop(lsm_axprof *p, const lsm_jstop_limits *lim, uint8_t kind);

/* One cycle. Returns true if the coordinate moved during it. Control cycle. */
bool lsm_axprof_step(lsm_axprof *p);

/* True when no move or stop runs. Any context of the owner. */
static inline bool lsm_axprof_at_rest(const lsm_axprof *p)
{
    return p->mode == LSM_AXPROF_IDLE;
}

/* Limits for profile type 0 (see above): snap_max replaced. Any context. */
lsm_axprof_limits lsm_axprof_effective(const lsm_axprof_limits *lim, lsm_real cycle_s);

#endif /* LSM_AXPROF_H */
