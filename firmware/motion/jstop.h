/*
 * jstop.h: a jerk- and snap-limited stop of one coordinate from any kinematic state (lsm_jstop_*).
 *
 * Model. From the state (v0, a0, j0) at the moment the stop is requested, the coordinate is brought to
 * v = a = j = 0 with the acceleration shaped like the sin² S-curve of scurve.h (Kombarov eq 6). The jerk stays
 * continuous and |snap| <= S (eq 22). A stop requested inside a jerk phase (travel frame, v0 >= 0) first has a
 * lead-in:
 *   - inside a cos² fall of the jerk (lsm_jstop_plan_lead with the phase): the rest of that fall, as planned;
 *   - inside a sin² rise of a braking jerk (j0 < 0, amplitude within J): the rest of that rise, as planned;
 *   - otherwise a jerk j0 > 0 (it raises a) is released with a cos² fall within the snap limit (duration
 *     pi |j0| / (2 S)); a braking jerk j0 < 0 is kept.
 * The rest of the move's own phase never brakes later nor accelerates more than the move would. A stop that is
 * braking already (j1 < 0 after the lead-in) and needs to brake harder than the plain release of j1 does takes its
 * first ramp from j1: a sin² transition j1 -> jp (jp <= j1, duration pi (j1 - jp) / (2 S), a gain of
 * (j1² - jp²) pi / (4 S) in -a), a plateau at jp and a cos² fall (brakes_on, ramp_from in jstop.c); otherwise j1
 * is released first, and a coordinate still accelerating (a > 0 in the travel frame) first brings a to 0 by the
 * shortest ramp of that change (its own peak jerk, sqrt(2 S a / pi) or J): one ramp from a > 0 down to the
 * deceleration would have a higher peak jerk and therefore a slower sin² start (the snap of a rise grows as
 * S² t / J_P) and let the velocity pass what the move itself reaches. The stop is then planned from the state at
 * the end of that (v0', a0'), in three segments
 *      a |                                      A: ramp a0 -> a1   (jerk pulse: sin² rise, plateau, cos² fall)
 *     a0 |\                                     B: constant a1 for tB (only when a1 = -D is reached)
 *        | \                     ___            C: ramp a1 -> 0
 *      0 +--\-------------------/---> t
 *        |   \________________/                 in the travel frame (v0 >= 0; the axis frame is mirrored)
 *    -D  |      A       B       C
 *
 * A ramp that changes the acceleration by da with peak jerk Jp has a sin² rise of t1, a plateau of t2 and a
 * cos² fall of t1 (the T1-T3 intervals of scurve.h): da = Jp (t1 + t2), peak snap = Jp pi / (2 t1) (eq 22).
 * The shortest ramp within J (jerk) and S (snap): if da >= pi J² / (2 S): Jp = J, t1 = pi J / (2 S),
 * t2 = da / J - t1; else t2 = 0, t1 = sqrt(pi da / (2 S)), Jp = 2 S t1 / pi. Its duration is T(da) = 2 t1 + t2.
 * The acceleration is point-symmetric about the middle of a ramp, so its velocity change is (a_s + a_e) T / 2.
 * The end velocity with no plateau is
 *      f(a1) = v0 + (a0 + a1) T(|a0 - a1|) / 2 + a1 T(|a1|) / 2
 * If f(-D) >= 0 the deceleration reaches -D and the plateau lasts tB = f(-D) / D; otherwise a1 in (-D, 0] solves
 * f(a1) = 0 (bisection; f(-D) < 0 < f(0)). If f(0) <= 0 the coordinate was already braking harder than the
 * limits can undo in time: ramping the acceleration to 0 as fast as allowed takes it slightly through v = 0,
 * and a second stop (in the other direction) follows at once. The durations are real numbers (not whole
 * cycles); the state is evaluated in closed form (scurve.h's phase shapes, eq 15) at every cycle and the last
 * cycle lands on the exact end. No limit is ever exceeded: |a| <= max(|a0'|, D), |j| <= max(|j0|, J),
 * |snap| <= S, with |a0'| <= |a0| + pi j0² / (4 S) (a jerk release adds j0 pi |j0| / (4 S) to a; the rest of a
 * move's phase stays within the move's own a).
 * Time: the double build counts the time since the start of the stop; the float build counts it from the start
 * of the present phase, since a float clock of tens of seconds would make the steps uneven by a percent (the
 * ulp of 44 s is 4 µs) and the sampled jerk would step by more than S dt.
 *
 * Contexts: every call works on caller-owned memory only, allocates nothing and keeps no global state.
 * lsm_jstop_plan costs a bisection of up to ~60 (double) / ~30 (float) ramp-time evaluations: it is called from
 * the control cycle when a stop is requested (bounded time, no loop over the buffer); lsm_jstop_step /
 * lsm_jstop_eval are closed forms (control cycle). Nothing here is shared between contexts.
 *
 * Units: mm (or rad), s; limits D in mm/s², J in mm/s³, S in mm/s⁴ (u/s² .. for rotary axes).
 */
#ifndef LSM_JSTOP_H
#define LSM_JSTOP_H

#include <stdbool.h>
#include <stdint.h>

#include "lsm_config.h"
#include "scurve.h"
#include "status.h"

typedef struct lsm_jstop_limits {
    lsm_real decel_mm_s2; /* D > 0 */
    lsm_real jerk_mm_s3;  /* J > 0 */
    lsm_real snap_mm_s4;  /* S > 0 */
} lsm_jstop_limits;

/* At most: the lead-in (the rest of the present jerk phase), a release of the jerk, a ramp of a to 0 (3 phases),
 * the first ramp (3), the plateau and the last ramp (3). */
#define LSM_JSTOP_PHASES 12

/* The jerk phase a coordinate is in when the stop is requested (a planned move's phase, scurve.h): its shape, its
 * whole duration, the time already spent in it and its signed amplitude (axis frame). Lets the stop continue it. */
typedef struct lsm_jstop_lead {
    uint8_t shape;       /* lsm_phase_shape */
    lsm_real full_s;     /* the phase's whole duration, > 0 */
    lsm_real off_s;      /* time spent in it, in [0, full_s) */
    lsm_real jerk_mm_s3; /* signed amplitude, axis frame */
} lsm_jstop_lead;

typedef struct lsm_jstop {
    lsm_jstop_limits lim;
    lsm_real dir;       /* +1 / -1: travel frame -> axis frame */
    lsm_real origin_mm; /* position at the start of the stop */
    lsm_real t_s;       /* time since the start of this stage (double build) */
    unsigned ph;        /* present phase (float build: time kept within the phase, so the */
    lsm_real tau_s;     /*   steps keep their length on long stops); time into it */
    lsm_real t_end_s;   /* duration of this stage */
    unsigned n_phases;
    /* phase i: jerk(tau) = jb[i] + jerk[i] * shape_i(off[i] + tau) for tau in [0, dur[i]], shape_i the unit shape of
     * duration full[i] (scurve.h lsm_phase_unit); off = 0, full = dur, jb = 0 but for a lead-in or a jerk
     * transition (see above) */
    lsm_phase_shape shape[LSM_JSTOP_PHASES];
    lsm_real dur_s[LSM_JSTOP_PHASES];
    lsm_real full_s[LSM_JSTOP_PHASES];
    lsm_real off_s[LSM_JSTOP_PHASES];
    lsm_real jb_mm_s3[LSM_JSTOP_PHASES];   /* constant jerk added, travel frame */
    lsm_real jerk_mm_s3[LSM_JSTOP_PHASES]; /* signed amplitude, travel frame */
    lsm_kin start[LSM_JSTOP_PHASES + 1];   /* travel-frame state at each phase start; [n_phases] = end */
    bool active;
    bool settle;         /* lsm_jstop_plan_settle: it ends at a constant velocity, not at rest */
    lsm_real v_end_mm_s; /* settle: that velocity (axis frame) */
} lsm_jstop;

/* Plans a stop from (p, v, a, j). Errors: LSM_E_NULL, LSM_E_NAN/LSM_E_INF (state or limits), LSM_E_LIMIT
 * (a limit <= 0). A state at rest (v = a = j = 0) gives an inactive stop (nothing to do). Control cycle. */
lsm_status lsm_jstop_plan(lsm_jstop *s, lsm_real p_mm, lsm_real v_mm_s, lsm_real a_mm_s2, lsm_real j_mm_s3,
                          const lsm_jstop_limits *lim);

/* As lsm_jstop_plan, from inside a known jerk phase (lead, may be NULL: then as lsm_jstop_plan): the stop continues
 * it where the model above says so. Errors as lsm_jstop_plan, and LSM_E_ARG for a lead that is not a phase (shape,
 * full_s <= 0, off_s outside [0, full_s), not finite). Control cycle. */
lsm_status lsm_jstop_plan_lead(lsm_jstop *s, lsm_real p_mm, lsm_real v_mm_s, lsm_real a_mm_s2, lsm_real j_mm_s3,
                               const lsm_jstop_lead *lead, const lsm_jstop_limits *lim);

/* Settles the velocity: brings (v, a, j) to a = j = 0 as fast as the limits (J, S; D is not used) allow, with the
 * lead-in of a stop in the frame where a >= 0 (the rest of a cos² fall, the rest of a sin² rise that lowers a, a
 * jerk that lowers a kept, one that raises it released), then one ramp of a to 0 (from the kept jerk when that is
 * faster than releasing it). It ends at the velocity this gives, v_end_mm_s (set by the plan), which lies between v
 * and what the motion would reach by stopping its acceleration at once. A state with a = j = 0 gives an inactive
 * plan (v_end = v). Used by a retarget to reach a cruise the move planner starts from (axprof.h). Errors as
 * lsm_jstop_plan_lead. Control cycle. */
lsm_status lsm_jstop_plan_settle(lsm_jstop *s, lsm_real p_mm, lsm_real v_mm_s, lsm_real a_mm_s2, lsm_real j_mm_s3,
                                 const lsm_jstop_lead *lead, const lsm_jstop_limits *lim);

/* The jerk phase of a running stop at its present time, as a lead for the stop that replaces it. False when there is
 * none to continue (not running, or inside a jerk transition, which is no single shape). Control cycle. */
bool lsm_jstop_lead_now(const lsm_jstop *s, lsm_jstop_lead *out);

/* Advances dt_s seconds and writes the state (axis frame). Returns true while stopping; at the end it writes
 * the exact rest state (v = a = j = 0; a settle: v = v_end_mm_s) and returns false. Control cycle. */
bool lsm_jstop_step(lsm_jstop *s, lsm_real dt_s, lsm_kin *out);

/* Closed-form state at time t_s of the current stage (axis frame), without advancing. Any context. */
void lsm_jstop_eval(const lsm_jstop *s, lsm_real t_s, lsm_kin *out);

/* Duration (s) of the shortest ramp of |da| within (J, S), and its peak jerk / rise time (t1) / plateau (t2);
 * the out pointers may be NULL. Any context. */
lsm_real lsm_jstop_ramp_time(lsm_real da_mm_s2, lsm_real j_mm_s3, lsm_real snap_mm_s4, lsm_real *jp_mm_s3,
                             lsm_real *t1_s, lsm_real *t2_s);

#endif /* LSM_JSTOP_H */
