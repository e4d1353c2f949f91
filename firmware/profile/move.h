/*
 * move.h: cycle-quantised point-to-point moves with sin² S-curves, on one axis or synchronised on up to
 * LSM_MAX_AXES axes (lsm_move_*).
 *
 * Model. A move over distance D from feed v0 to feed v1 is an acceleration v0 -> vc (7 intervals, see
 * scurve.h), a cruise at vc for nc whole cycles, and a deceleration vc -> v1 (7 intervals):
 *
 *      v |      ______________ vc
 *        |     /              \
 *     v0 |____/                \____ v1         D = (v0 + vc) ta / 2 + vc tc + (vc + v1) td / 2     (1)
 *        +--ta--+-----tc------+--td--> t
 *
 * using S = (F0 + F) tp / 2 for each velocity change (point symmetry of the sin² ramp). With the whole-cycle
 * intervals fixed, (1) is linear in vc, so vc is solved exactly, and each ramp's peak jerk is then corrected
 * by Kombarov eq 34 for its actual velocity change. The move therefore ends exactly at D with feed v1 and
 * A = J = 0. When D is short the profile shortens: the peak feed vp < v_max is the largest whose quantised
 * ramps travel at most D, and the cruise may vanish. That distance is step-wise linear in vp (one line per pair
 * of ramp totals), so the search (move.c, strict rule) tries the roots of those lines, starting from rest at the
 * continuous model's peak: about 2.4 ramp sizings per axis. Where no cruise length makes that shape exact (short moves
 * between feeds), other intervals and cruise feeds are tried, and last a search over the two ramps' totals (whole
 * cycles, up to 256 each) with every cruise length: if such a plan exists, the move is planned (move.c,
 * search_totals; tests/profile/test_move_complete.c checks it against a brute force).
 *
 * Synchronisation: every axis has its own limits, distance and feeds. Each axis is first planned alone; all
 * axes then share the intervals (ta, tc, td split into n1, n2, n4) of the slowest one, and every axis gets its
 * own vc and its own corrected J_P per ramp. With v0 = v1 = 0 the axes stay proportional (a straight line).
 * If the shared intervals do not hold some axis's limits (a short, low-jerk axis next to a long, fast one),
 * they are widened interval by interval (capacity is monotone in n1, n2, n4) until every axis fits.
 *
 * Feeds are speeds along each axis's direction of travel (>= 0, <= v_max); distances are signed (mm).
 * Rule: LSM_SCURVE_RULE_STRICT never exceeds a limit; LSM_SCURVE_RULE_PAPER uses the paper's rounding for the
 * ramps (for comparison only: it can exceed limits slightly).
 */
#ifndef LSM_MOVE_H
#define LSM_MOVE_H

#include "scurve.h"

typedef struct lsm_axis_limits {
    lsm_real v_max_mm_s;
    lsm_real a_max_mm_s2;
    lsm_real j_max_mm_s3;
    lsm_real snap_max_mm_s4;
} lsm_axis_limits;

/* What a caller asks for. Unused axes (index >= n_axes) are ignored. */
typedef struct lsm_move_request {
    uint8_t n_axes;   /* 1 .. LSM_MAX_AXES */
    lsm_real cycle_s; /* control cycle */
    lsm_scurve_rule rule;
    lsm_real distance_mm[LSM_MAX_AXES]; /* signed */
    lsm_real v0_mm_s[LSM_MAX_AXES];     /* start feed along the direction of travel, >= 0 */
    lsm_real v1_mm_s[LSM_MAX_AXES];     /* end feed along the direction of travel, >= 0 */
    lsm_axis_limits lim[LSM_MAX_AXES];
} lsm_move_request;

/* One axis of a planned move. */
typedef struct lsm_move_axis {
    lsm_real distance_mm; /* signed target distance */
    lsm_real dir;         /* +1 or -1 (the sign of distance_mm; +1 for a still axis) */
    lsm_real v0_mm_s, v1_mm_s;
    lsm_real vc_mm_s;      /* corrected cruise feed */
    lsm_real jp_acc_mm_s3; /* corrected peak jerk of the first ramp (signed, travel frame) */
    lsm_real jp_dec_mm_s3; /* corrected peak jerk of the second ramp (signed, travel frame) */
} lsm_move_axis;

typedef struct lsm_move {
    lsm_real cycle_s;
    uint8_t n_axes;
    uint8_t slowest_axis;          /* whose intervals the others share */
    lsm_scurve_intervals acc, dec; /* shared whole-cycle intervals of the two ramps */
    uint32_t cruise_cycles;
    lsm_move_axis axis[LSM_MAX_AXES];
} lsm_move;

#define LSM_MOVE_PHASES 15 /* 7 ramp intervals, cruise, 7 ramp intervals */

/*
 * Plans a move. Errors: LSM_E_NULL, LSM_E_ARG (n_axes, rule), LSM_E_NAN, LSM_E_INF, LSM_E_LIMIT, LSM_E_CYCLE,
 * LSM_E_NEG_FEED, LSM_E_FEED_ABOVE_VMAX, LSM_E_ZERO_LENGTH (no axis moves), LSM_E_RANGE (a distance too large
 * to represent: |D| / cycle beyond the cycle counter at v_max), LSM_E_INFEASIBLE (D too short to go from v0
 * to v1 within the limits, or a still axis with a non-zero feed), LSM_E_TOO_LONG.
 */
lsm_status lsm_move_plan(lsm_move *mv, const lsm_move_request *req);

uint32_t lsm_move_total_cycles(const lsm_move *mv);
lsm_real lsm_move_duration_s(const lsm_move *mv);

/* The 15 phases of one axis (travel frame: multiply by dir for the axis frame). */
void lsm_move_phases(const lsm_move *mv, unsigned axis, lsm_phase out[LSM_MOVE_PHASES]);

/*
 * Closed-form state of one axis at time t_s (axis frame, s_mm measured from the start). From the last cycle on
 * it returns the exact terminal state (s = distance, v = v1, a = j = 0). In the cruise, s follows the position
 * feed and v is the planned cruise feed vc (lsm_move_phase_start). Each call evaluates only the ramp that
 * holds t_s (both in the cruise): at most 7 closed-form phase ends (14 in the cruise), no trigonometry but that of
 * the phase itself.
 */
void lsm_move_eval(const lsm_move *mv, unsigned axis, lsm_real t_s, lsm_kin *out);

/* The same at cycle k plus frac in [0, 1) of a cycle (integer phase location: precise in float). */
void lsm_move_eval_cycle(const lsm_move *mv, unsigned axis, uint32_t k, lsm_real frac, lsm_kin *out);

/*
 * State at the start of phase p (0..14) of one axis, travel frame, as the position generators advance from it
 * (stepgen.c, fixprog.c). The first ramp is evaluated forward from the start, the second backward from the exact
 * end state (reversed in time it is the standard ramp v1 -> vc). So in float the rounding does not pile up towards
 * the end of a long move: the last cycles are as precise as the first. The cruise's v (p = 7) is its position
 * feed (s8 - s7) / tc, which joins the two ramps' positions exactly; it differs from the ramps' own end velocity by
 * the rounding of those two positions over tc (in float a few ulp(D) / tc: 0.1 mm/s and more over one cycle at
 * 500 mm). That difference is position rounding: the velocity of the state (lsm_move_eval, lsm_move_eval_cycle) is
 * in the cruise the planned vc (<= v_max exactly), which both ramps' evaluated ends meet within a few ulps of vc, so
 * it has no step where the cruise joins the ramps; the cruise's positions follow the feed, each within a few ulps of
 * the exact curve.
 */
void lsm_move_phase_start(const lsm_move *mv, unsigned axis, unsigned p, lsm_kin *out);

/* All 15 phase start states of one axis in one pass (no trigonometry: exact phase-end values). */
void lsm_move_phase_starts(const lsm_move *mv, unsigned axis, lsm_kin out[LSM_MOVE_PHASES]);

/*
 * Where the closed form itself lands at the end (before the terminal state takes over): s(T) - D in mm.
 * A measure of the plan's exactness (rounding only, ~1e-12 relative in double).
 */
lsm_real lsm_move_end_error_mm(const lsm_move *mv, unsigned axis);

#endif /* LSM_MOVE_H */
