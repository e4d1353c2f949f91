/*
 * float_noise.h: the one noise bound of the float build's setpoints, shared by every check of backward differences of
 * positions against axis limits: the PP checker (pp_check.h), the path fuzz targets (tests/fuzz/fz_path.h) and the
 * float path tests (tests/plan/test_interp_noise.c). Header-only, for tests. Nothing in the double build (its
 * rounding, 2^-52 relative, is below the checks' relative slack).
 *
 * Model. Each float setpoint q_k is within K u of the exact curve q*(t_k) of its plan (the float plan's parameters
 * evaluated exactly, at the exact time of the sample), u = FLT_EPSILON x S, S the largest |position| seen:
 *     |q_k - q*(t_k)| <= K u.
 * The n-th backward difference of q* over dt^n is a B-spline mean of the n-th derivative (pp_check.h), within the
 * limit L_n; the error's n-th difference is at most 2^n K u. So
 *     |D_n q| / dt^n <= L_n + 2^n K u / dt^n          (n = 1 v, 2 a, 3 j, 4 snap).
 *
 * K = FLOAT_NOISE_POS_ULPS = 4. Analysis of the interpolator's float evaluation (firmware/plan/interp.c), in u:
 *   the setpoint's own rounding 1/2; a line p0 + dir off + dir off_lo: the product dir off (|dir off| <= 2 S) 1,
 *   the sums 1/2; an arc p_a + (cos d - 1) A + sin d B + L ds: the anchor p_a from the exact angle (two_prod and a
 *   rotation: a few ulp of 1 rad times the chord, <= 1.5), the polynomial terms (sin d B <= 0.25 r) 1/2, the sums 1;
 *   the travel: the cursor is an exact (compensated) sum of per-cycle steps ds (phase_step: dt times the cycle's
 *   mean rate, a few ulp of ds each), the phases' lengths are their own closed forms (summed exactly) and the
 *   piece's rounding is spread over it (ds_stretch), so the travel's error is a slow drift, not noise (under 1/2
 *   per cycle's difference).
 *   So at most about 2.5 (lines) and 3.5 (arcs); K = 4 holds them with half an ulp to spare.
 * Measurement (scripts/fuzz_float_noise.py over the 479 fuzz_planner_float inputs of the 1 h run, FZ_MEASURE in
 *   tests/fuzz/fz_measure.h, at 012c2c0+): the error's own differences |D_n e| / 2^n u (e = q - q* at the exact
 *   time, lines and arcs) at most 2.67 (n = 1), 1.84 (n = 2), 1.60 (n = 3); |q - q*(cursor)| at most 3.28 (3.64 merged with
 *   765b5ef, the rest the same); and
 *   over every input, clothoids included, the largest excess of |D_n q| over L_n dt^n is 1.49 x 2 u (n = 1),
 *   0.80 x 4 u, 1.23 x 8 u. Before the fixes of interp.c (on 7cc6ed6: a phase clock summed per cycle, the travel
 *   v tau - sloc rounded to ulp of the phase's travel, the arc's angle rounded to ulp(phi), the cursor's low part
 *   left out, switch points not scaled like the travel, the planner's phase lengths (ulp of the piece) and a
 *   piece's rounding snapped at its end) the same inputs' error differences reached 74.8 u (n = 1; 15 inputs
 *   over 16 u), 14.7 (n = 2), 14.6 (n = 3), |q - q*(cursor)| 22.3 u, and the excess over the limits 6.33 x 8 u.
 *   tests/plan/test_interp_noise.c checks the bound on random paths (75 000 of them pass: seeds 1, 12, 13,
 *   20-41 x 3000; several of those failed before the last fixes: the phase lengths and the stretch).
 * The old bounds were 1 u (fz_path.h: 2, 4, 8 x 1.2e-7 S) and 4 u (pp_check.h): one bound now, 4 u.
 */
#ifndef FLOAT_NOISE_H
#define FLOAT_NOISE_H

#include <float.h>
#include <math.h>

#include "lsm_config.h"

#define FLOAT_NOISE_POS_ULPS 4.0 /* K: a float setpoint is within K u of the exact curve (derivation above) */

/* u: the unit of the bound at positions up to |pos_scale| (FLT_EPSILON x S in the float build, DBL_EPSILON x S in
 * the double build, where the bound is below every check's relative slack). */
static inline double float_noise_unit(double pos_scale)
{
#if LSM_REAL_IS_FLOAT
    return (double)FLT_EPSILON * fabs(pos_scale);
#else
    return DBL_EPSILON * fabs(pos_scale);
#endif
}

/* The allowance of the n-th backward difference over dt^n (n >= 1): 2^n K u / dt^n. */
static inline double float_noise_diff(double pos_scale, int order, double dt)
{
    return ldexp(FLOAT_NOISE_POS_ULPS * float_noise_unit(pos_scale), order) / pow(dt, order);
}

#endif
