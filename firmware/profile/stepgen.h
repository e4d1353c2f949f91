/*
 * stepgen.h: per-cycle evaluator of a planned move (lsm_stepgen_*): one call per control cycle gives every
 * axis's position setpoint.
 *
 * Model. Within a phase of n cycles, at tau = m * dt (m = 0..n), every axis is
 *     s(tau) = s0 + v0 tau + a0 tau²/2 + J * f(tau)
 * with the shape function f of scurve.h, which is the same for every axis because all axes share the
 * intervals (move.h). So the per-cycle work is: one basis (tau, tau²/2, f) shared by all axes, then four
 * multiply-adds per axis. The sin² phases need sin(phi), phi = pi m / n1 (= 2 w tau, Kombarov eq 9); it comes
 * from a rotation recurrence (cos, sin) <- (cos, sin) * (cos d, sin d), d = pi / n1, restarted exactly at
 * every phase start, so there is no trigonometric call per cycle (two per move, at init, for cos d and sin d).
 * Phase start states are computed once at init (lsm_move_phase_starts: exact boundary values, the second ramp
 * taken backward from the exact end), so rounding never accumulates across phases and a phase change costs no
 * more than an ordinary cycle. Integer cycle counters throughout.
 * The last cycle returns the exact target (the plan's terminal state).
 *
 * Units: mm, s; positions are absolute (start position + the move's travel).
 */
#ifndef LSM_STEPGEN_H
#define LSM_STEPGEN_H

#include "move.h"

typedef struct lsm_stepgen {
    const lsm_move *mv;      /* the plan (caller-owned, must outlive the generator) */
    uint32_t k;              /* cycles emitted so far */
    uint32_t total;          /* total cycles of the move */
    uint8_t phase;           /* current phase 0..LSM_MOVE_PHASES-1 */
    uint32_t m;              /* cycles into the current phase */
    lsm_real c, s;           /* cos(phi), sin(phi) of the current sin² phase */
    lsm_real cd_acc, sd_acc; /* rotation step of the first ramp (cos, sin of pi / n1) */
    lsm_real cd_dec, sd_dec; /* rotation step of the second ramp */
    lsm_real k8, k16;        /* 1/(8 w²), 1/(16 w³) of the current sin² phase (s², s³) */
    lsm_real origin_mm[LSM_MAX_AXES];
    lsm_kin start[LSM_MAX_AXES];                  /* state at the current phase start (travel frame) */
    lsm_real st_s[LSM_MOVE_PHASES][LSM_MAX_AXES]; /* every phase's start: s, v, a (from init, travel frame) */
    lsm_real st_v[LSM_MOVE_PHASES][LSM_MAX_AXES];
    lsm_real st_a[LSM_MOVE_PHASES][LSM_MAX_AXES];
    lsm_real jerk[LSM_MAX_AXES]; /* jerk amplitude of the current phase (travel frame) */
} lsm_stepgen;

/* Starts at the move's first cycle. start_mm may be NULL (all zero). Errors: LSM_E_NULL. */
lsm_status lsm_stepgen_init(lsm_stepgen *g, const lsm_move *mv, const lsm_real *start_mm);

/*
 * Advances one cycle and writes every axis's absolute position (mm) to pos_mm[0 .. n_axes-1].
 * Returns true while the move runs; after the last cycle it keeps returning the target and false.
 */
bool lsm_stepgen_next(lsm_stepgen *g, lsm_real *pos_mm);

#endif /* LSM_STEPGEN_H */
