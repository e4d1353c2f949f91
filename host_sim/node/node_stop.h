/*
 * node_stop.h: a jerk- and snap-limited stop of one coordinate from any kinematic state (node_stop_*).
 *
 * Model. From the state (v0, a0) at the moment the stop is requested, the coordinate is brought to v = a = 0
 * with the acceleration shaped like the sin² S-curve of scurve.h (Kombarov eq 6): three segments
 *
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
 * cycles); the state is evaluated in closed form at every cycle and the last cycle lands on the exact end.
 * No limit is ever exceeded: |a| <= max(|a0|, D), |j| <= J, |snap| <= S.
 *
 * Units: mm (or rad), s; limits D in u/s², J in u/s³, S in u/s⁴.
 */
#ifndef NODE_STOP_H
#define NODE_STOP_H

#include <stdbool.h>
#include <stdint.h>

#include "scurve.h"
#include "status.h"

typedef struct node_stop_limits {
    double decel;  /* D > 0 */
    double jerk;   /* J > 0 */
    double snap;   /* S > 0 */
} node_stop_limits;

#define NODE_STOP_PHASES 7

typedef struct node_stop {
    node_stop_limits lim;
    double dir;                        /* +1 / -1: travel frame -> axis frame */
    double origin;                     /* position at the start of the stop */
    double t;                          /* time since the start of this stage */
    double t_end;                      /* duration of this stage */
    unsigned n_phases;
    lsm_phase_shape shape[NODE_STOP_PHASES];
    double dur[NODE_STOP_PHASES];      /* s */
    double jerk[NODE_STOP_PHASES];     /* signed amplitude, travel frame */
    lsm_kin start[NODE_STOP_PHASES + 1]; /* travel-frame state at each phase start; [n_phases] = end */
    bool active;
} node_stop;

/* Plans a stop from (p, v, a). Errors: LSM_E_NULL, LSM_E_NAN/LSM_E_INF (state or limits), LSM_E_LIMIT
 * (a limit <= 0). A state at rest (v = a = 0) gives an inactive stop (nothing to do). */
lsm_status node_stop_plan(node_stop *s, double p, double v, double a, const node_stop_limits *lim);

/* Advances dt seconds and writes the state (axis frame). Returns true while stopping; at the end it writes
 * the exact rest state (v = a = j = 0) and returns false. */
bool node_stop_step(node_stop *s, double dt, lsm_kin *out);

/* Closed-form state at time t of the current stage (axis frame), without advancing. */
void node_stop_eval(const node_stop *s, double t, lsm_kin *out);

/* Duration of the shortest ramp of |da| within (J, S), and its peak jerk / rise time (t1) / plateau (t2). */
double node_stop_ramp_time(double da, double J, double S, double *jp, double *t1, double *t2);

#endif /* NODE_STOP_H */
