/*
 * fixprog.h: turns a planned move (move.h, floating point) into the integer program that fixstep.h runs
 * (lsm_fixprog_*). This is the only place where the integer build meets floating point: on a host, or on a
 * core with an FPU that plans, before handing the program to an integer-only interpolator.
 *
 * Per phase and axis it takes the closed-form start state (lsm_move_phase_start, so no rounding accumulates
 * across phases) and scales it to counts and cycle units: V0 = v cpm dt, A0h = a cpm dt² / 2,
 * J = j cpm dt³ (see fixstep.h for the polynomial). Units: counts_per_mm (counts/mm), start_counts (counts).
 */
#ifndef LSM_FIXPROG_H
#define LSM_FIXPROG_H

#include "fixstep.h"
#include "move.h"

/*
 * Errors: LSM_E_NULL; LSM_E_LIMIT (counts_per_mm not finite and > 0); LSM_E_RANGE (a position beyond +/-2^31
 * counts, or a phase with jerk or acceleration longer than LSM_FIX_MAX_RAMP_CYCLES cycles).
 * The target of each axis is start_counts + round(distance * counts_per_mm).
 */
lsm_status lsm_fixprog_compile(lsm_fixprog *out, const lsm_move *mv, const lsm_real *counts_per_mm,
                               const int64_t *start_counts);

#endif /* LSM_FIXPROG_H */
