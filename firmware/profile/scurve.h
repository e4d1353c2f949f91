/*
 * scurve.h: sin² S-curve velocity change with smoothly limited jerk (Kombarov et al. 2019, §3-§4).
 *
 * Model. A velocity change F0 -> F has seven intervals T1..T7 (eq 6):
 *
 *     J |   ____                            J_P: peak jerk          (mm/s^3)
 *       |  /    \                           A_P: peak acceleration  (mm/s^2)
 *       | / T2   \   T4                     DJ : peak snap = J_P*pi/(2*dt1)   (eq 22, mm/s^4)
 *       |/T1   T3 \________   T6            dt1 = dt3 = dt5 = dt7, dt2 = dt6  (eq 17)
 *       +------------------\    ____/--
 *                           \T5/ ...         tp = 4 dt1 + 2 dt2 + dt4         (eq 17)
 *
 *   T1: J = J_P sin²(w tau),  T2: J = J_P,  T3: J = J_P cos²(w tau),  T4: J = 0,
 *   T5..T7 mirror T1..T3 with -J_P; w = pi / (2 dt1) (eq 9), tau = time since the interval start (eq 7).
 *
 * Closed forms per unit jerk amplitude, derived here (the printed eqs 13-15 have typos: F_V uses tau²/4):
 *   rising  (T1, T5):  a = tau/2 - sin(2w tau)/(4w)          v = tau²/4 - sin²(w tau)/(4w²)
 *                      s = tau³/12 - tau/(8w²) + sin(2w tau)/(16w³)
 *   falling (T3, T7):  a = tau/2 + sin(2w tau)/(4w)          v = tau²/4 + sin²(w tau)/(4w²)
 *                      s = tau³/12 + tau/(8w²) - sin(2w tau)/(16w³)
 *   constant (T2, T6): a = tau, v = tau²/2, s = tau³/6
 * and the state at the start of each interval is carried over (s0 + v0 tau + a0 tau²/2 + J_P * shape).
 *
 * Interval selection (§4): dt1 = min(dt1J, dt1A, dt1F) (eqs 25, 26, 29, 35), J_P = 2/pi dt1 DJmax (eq 32),
 * dt2 = max(min(dt2A, dt2F), 0) (eqs 27, 30, 36), A_P = J_P (dt1 + dt2) (eq 23),
 * dt4F = dF/A_P - pi J_P/(2 DJmax) - A_P/J_P (eq 31, with the sign typo of the last term corrected),
 * dt4 = max(dt4F, 0) (eq 37). Every interval is a whole number of control cycles (eq 33) and J_P is then
 * corrected so that V(tp) = F exactly (eq 34):  J_P = dF / (2 dt1² + 3 dt1 dt2 + dt2² + dt4 (dt1 + dt2)).
 *
 * Two rounding rules:
 *   LSM_SCURVE_RULE_STRICT (default): the shortest whole-cycle (n1, n2, n4) for which the corrected J_P keeps
 *     J_P <= Jmax, J_P (dt1 + dt2) <= Amax and J_P pi / (2 dt1) <= DJmax. Never exceeds a limit.
 *   LSM_SCURVE_RULE_PAPER: reproduces Table 1: n1 = floor, n2 = max(min(floor(dt2A), nearest(dt2F)), 0),
 *     n4 = max(nearest(dt4F), 0), with J_P, dt2A/F, A_P, dt4F computed from the quantised dt1. It can exceed the
 *     limits slightly after correction (e.g. Test 1: J_P 16.035 > 16); kept for verification only.
 *
 * A deceleration (F < F0) uses the intervals of |F - F0| with a negative J_P. The travelled distance is
 * S(tp) = (F0 + F) tp / 2 exactly (the velocity is point-symmetric about tp/2).
 *
 * Units: mm, s, mm/s, mm/s^2, mm/s^3, mm/s^4; interval lengths in whole cycles (`_cycles`).
 */
#ifndef LSM_SCURVE_H
#define LSM_SCURVE_H

#include "lsm_config.h"
#include "status.h"

typedef enum lsm_scurve_rule {
    LSM_SCURVE_RULE_STRICT = 0, /* shortest whole-cycle profile that never exceeds a limit */
    LSM_SCURVE_RULE_PAPER = 1   /* Kombarov Table 1 rounding (may exceed limits slightly) */
} lsm_scurve_rule;

/* Dynamic limits of one axis or of the path. All must be finite and > 0. */
typedef struct lsm_scurve_limits {
    lsm_real a_max_mm_s2;
    lsm_real j_max_mm_s3;
    lsm_real snap_max_mm_s4;
} lsm_scurve_limits;

/* Whole-cycle interval lengths of one velocity change: T1 = T3 = T5 = T7 = n1, T2 = T6 = n2, T4 = n4. */
typedef struct lsm_scurve_intervals {
    uint32_t n1_cycles;
    uint32_t n2_cycles;
    uint32_t n4_cycles;
} lsm_scurve_intervals;

/* One planned velocity change. */
typedef struct lsm_scurve {
    lsm_scurve_intervals iv;
    lsm_real cycle_s;
    lsm_real v0_mm_s;  /* F0 */
    lsm_real v1_mm_s;  /* F  */
    lsm_real jp_mm_s3; /* corrected peak jerk (eq 34), signed: negative for a deceleration */
} lsm_scurve;

/* The intermediate quantities of §4 (Table 1 rows), for reports and verification. */
typedef struct lsm_scurve_info {
    lsm_real dt1j_s, dt1a_s, dt1f_s; /* eqs 25, 26, 29 (unquantised) */
    lsm_real dt2a_s, dt2f_s;         /* eqs 27, 30, from the quantised dt1 */
    lsm_real dt4f_s;                 /* eq 31 (sign corrected), from quantised dt1, dt2 */
    lsm_real jp_initial_mm_s3;       /* eq 32 with the quantised dt1 (before correction) */
    lsm_real ap_mm_s2;               /* eq 23 with the initial J_P (Table 1's A_P row) */
    lsm_real ap_final_mm_s2;         /* |corrected J_P| (dt1 + dt2): the peak acceleration actually reached */
    lsm_real snap_final_mm_s4;       /* |corrected J_P| pi / (2 dt1): the peak snap actually reached */
} lsm_scurve_info;

/* Kinematic state at one instant. */
typedef struct lsm_kin {
    lsm_real s_mm;
    lsm_real v_mm_s;
    lsm_real a_mm_s2;
    lsm_real j_mm_s3;
} lsm_kin;

/* Validates limits (finite, > 0) and the cycle (finite, > 0). */
lsm_status lsm_scurve_check_limits(const lsm_scurve_limits *lim, lsm_real cycle_s);

/*
 * Plans the velocity change v0 -> v1 (both finite, >= 0). `info` may be NULL.
 * Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF, LSM_E_LIMIT, LSM_E_CYCLE, LSM_E_NEG_FEED, LSM_E_TOO_LONG,
 * LSM_E_ARG (unknown rule). v0 == v1 gives a zero-length change (all intervals 0).
 */
lsm_status lsm_scurve_plan(lsm_scurve *out, const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real v0_mm_s,
                           lsm_real v1_mm_s, lsm_scurve_rule rule, lsm_scurve_info *info);

/*
 * Strict whole-cycle intervals for a velocity change of magnitude dv_mm_s (>= 0), without validation (the
 * caller has validated limits and cycle). Returns false if a count would not fit in 32 bits.
 * This is the building block of moves and of the look-ahead planner.
 */
bool lsm_scurve_strict_intervals(const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real dv_mm_s,
                                 lsm_scurve_intervals *iv);

/*
 * The same sizing for many velocity changes with one set of limits and cycle (a move's axis, a planner's path):
 * lsm_scurve_sizer_init computes the dv-free constants once (eqs 25, 26 and the guide's jerk), and
 * lsm_scurve_sizer_intervals(sz, dv, iv) returns exactly what lsm_scurve_strict_intervals(lim, cycle, dv, iv)
 * returns. No validation (as there). Any context; the sizer is plain data, owned by the caller.
 */
typedef struct lsm_scurve_sizer {
    lsm_scurve_limits lim;
    lsm_real cycle_s;
    lsm_real t1_s;                            /* min(pi J / (2 DJ), sqrt(pi A / (2 DJ))) (eqs 25, 26) */
    lsm_real jc_mm_s3;                        /* 2 t1 DJ / pi (eq 32) */
    lsm_real t2a_s;                           /* A / jc - t1 (eq 27) */
    uint32_t c1_cycles;                       /* t1 rounded to cycles */
    lsm_real cbrt_skip_s3;                    /* eq 29 cannot bind while pi dv / (4 DJ) stays above this (about t1³) */
    lsm_real cbrt_x_per_dv;                   /* pi / (4 DJ), rounded down */
    lsm_real kj_per_dv, ka_per_dv, ks_per_dv; /* the sizing's lower bounds of total cycles, per unit dv */
} lsm_scurve_sizer;

void lsm_scurve_sizer_init(lsm_scurve_sizer *sz, const lsm_scurve_limits *lim, lsm_real cycle_s);
bool lsm_scurve_sizer_intervals(const lsm_scurve_sizer *sz, lsm_real dv_mm_s, lsm_scurve_intervals *iv);

/* Intervals for |dv| by either rule (the paper rule's as in Table 1). Returns false on overflow. */
bool lsm_scurve_rule_intervals(const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real dv_mm_s, lsm_scurve_rule rule,
                               lsm_scurve_intervals *iv);

/* True if the intervals make |dv| with a corrected peak jerk that keeps every limit (dv = 0 always fits). */
bool lsm_scurve_fits(const lsm_scurve_limits *lim, lsm_real cycle_s, const lsm_scurve_intervals *iv, lsm_real dv_mm_s);

/* Denominator of eq 34 for given intervals: dv = J_P * lsm_scurve_jerk_den(...)  (s^2). */
lsm_real lsm_scurve_jerk_den(const lsm_scurve_intervals *iv, lsm_real cycle_s);

/* Largest |dv| (mm/s) that the intervals can make without exceeding any limit (0 for empty intervals). */
lsm_real lsm_scurve_dv_capacity(const lsm_scurve_limits *lim, lsm_real cycle_s, const lsm_scurve_intervals *iv);

/* Total number of cycles 4 n1 + 2 n2 + n4 (eq 17). */
uint32_t lsm_scurve_total_cycles(const lsm_scurve_intervals *iv);

/* Duration tp (s) and travelled distance S(tp) = (v0 + v1) tp / 2 (mm). */
lsm_real lsm_scurve_duration_s(const lsm_scurve *sc);
lsm_real lsm_scurve_distance_mm(const lsm_scurve *sc);

/*
 * Closed-form J, A, V, S at time t_s since the start (clamped to [0, tp]; beyond tp it continues at constant
 * velocity v1). s_mm is measured from the start of the change.
 */
void lsm_scurve_eval(const lsm_scurve *sc, lsm_real t_s, lsm_kin *out);

/*
 * The same at cycle k plus a fraction frac in [0, 1) of a cycle. Phases are located with integer cycle
 * counts, so this stays precise in float however long the profile is (prefer it to a float time).
 */
void lsm_scurve_eval_cycle(const lsm_scurve *sc, uint32_t k, lsm_real frac, lsm_kin *out);

/* ---- Building blocks shared with moves and the per-cycle evaluators ---- */

/* Shape of one interval's jerk: sin² rise (T1, T5), constant (T2, T4, T6, cruise), cos² fall (T3, T7). */
typedef enum lsm_phase_shape { LSM_PHASE_RISE = 0, LSM_PHASE_CONST = 1, LSM_PHASE_FALL = 2 } lsm_phase_shape;

/* One interval: its length, jerk shape and signed jerk amplitude (0 for T4 and cruise). */
typedef struct lsm_phase {
    uint32_t n_cycles;
    uint8_t shape; /* lsm_phase_shape */
    lsm_real jerk_mm_s3;
} lsm_phase;

/* Writes the 7 phases of a velocity change with the given intervals and signed peak jerk. */
void lsm_scurve_phases(const lsm_scurve_intervals *iv, lsm_real jp_mm_s3, lsm_phase out[7]);

/*
 * Unit-amplitude shape functions of a phase at time tau_s into it (duration T_s = n * cycle; only used for
 * the sin phases, where w = pi / (2 T_s)). Writes j, a, v, s per unit jerk amplitude.
 */
void lsm_phase_unit(lsm_phase_shape shape, lsm_real T_s, lsm_real tau_s, lsm_real out_javs[4]);

/*
 * Closed-form state after k + frac cycles of a phase sequence that starts in `start`. Beyond the last phase
 * the state continues at constant velocity.
 */
void lsm_phases_eval_cycle(const lsm_phase *ph, unsigned n_phases, lsm_real cycle_s, const lsm_kin *start, uint32_t k,
                           lsm_real frac, lsm_kin *out);

/* The state at the end of a phase, from its start state, with exact boundary values (no trigonometry). */
void lsm_phase_end(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_kin *out);

/* Advances a kinematic state through tau_s of a phase (closed form). */
void lsm_phase_advance(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_real tau_s, lsm_kin *out);

#endif /* LSM_SCURVE_H */
