/*
 * corner.h: G2 (curvature-continuous) corner smoothing for the look-ahead planner (lsm_corner_*).
 *
 * Why (Shahzadeh et al.): where lines and arcs meet, the curvature jumps; under a jerk limit the
 * machine must stop there, because the centripetal jerk is c v^3 (eq 6) and a jump has c = inf.
 * A clothoid transition makes the path G2, so the feed is only limited by eq 7, sqrt(a_max/kappa_max),
 * and eq 8, cbrt(j_max/c_max), with kappa_max and c_max reported here.
 *
 * Model. Two consecutive blocks (line or arc) meet at the corner point V with the deflection angle
 * delta (0 < delta < pi) and the curvatures k1 (end of block 1) and k2 (start of block 2), signed
 * in the corner plane. The corner is replaced by a pair of clothoids A, B of equal length L:
 *     kappa: k1 --(A, length L)--> km --(B, length L)--> k2,
 * starting on block 1 at arc length d1 before V and ending on block 2 at d2 after V (the trims).
 * The start is G2 by construction (position, tangent and curvature of block 1 at that point); the
 * turning condition (k1 + km) L/2 + (km + k2) L/2 = delta + k1 d1 + k2 d2 gives km; the two position
 * equations "end of B = block 2 at d2" are solved for (d1, d2) by a damped 2x2 Newton iteration
 * whose Jacobian comes from the moments int t^j e^{i psi}, j <= 2, of the same Taylor series that
 * gives the positions (clothoid.h). L is the free scale: it is chosen so that the deviation equals
 * the tolerance (a safeguarded secant in log L - log D), or smaller when the trims would exceed
 * their limits. Two lines give the symmetric pair in closed form (no iteration): with
 * X + iY = int_0^1 e^{i delta u^2 / 2} du, half-length L = eps cos(delta/2) / Y,
 * trims d = L (X + Y tan(delta/2)), sharpness delta / L^2, kappa_max = delta / L.
 *
 * Deviation (what the tolerance eps bounds, like LinuxCNC's G64 P and the "corner deviation" of
 * other controls): deviation = max(vertex distance, path distance), where the vertex distance is the
 * distance from the programmed corner point V to the transition, and the path distance is the
 * largest distance of a transition point from the programmed path (the two blocks, untrimmed). For
 * two lines the vertex distance is the larger one, L Y / cos(delta/2); for a tangent line-arc joint
 * (delta = 0, a curvature jump only) it is the path distance, about 0.0235 |k2 - k1| L^2.
 * With arcs both are measured on 4 samples per clothoid (stepped with the local series), refined by a
 * safeguarded Newton iteration (vertex distance) and, for the path distance around the largest sampled
 * maxima, by the Illinois method on the crossing d1 = d2 (where the nearer block changes: a kink) and
 * golden-section / parabolic steps on the smooth part. The scale search aims at eps (1 - 1e-4) and
 * stops once the deviation is in [LSM_CORNER_ACCEPT, 1] of that, or the trims reach 98 % of their
 * limits; the estimate is good to ~1e-5 relative (checked against dense sampling in the tests).
 *
 * Planes. Two lines are smoothed in their own plane (spanned by the two directions, any 3-D
 * orientation). With an arc, the corner plane is the arc's (G17/G18/G19 or general); the other block
 * must lie in it (line direction normal to the arc's normal, arcs with parallel normals), and arcs
 * must not be helical; otherwise LSM_E_NONPLANAR. Blocks that move A B C are not blended (LSM_E_ROTARY).
 *
 * Limits on the trims: at most max_trim (default LSM_CORNER_DEFAULT_TRIM_FRACTION = 0.49 of each
 * block, so that the corner at the block's other end has the other half), and on an arc at most
 * LSM_CORNER_MAX_ARC_TRIM_RAD of its turning.
 *
 * Outcomes: LSM_OK with the transition; LSM_E_COLLINEAR when there is nothing to smooth (tangents
 * and curvatures already equal: join the blocks directly; not a fault); LSM_E_REVERSAL for an exact
 * reversal (delta = pi: stop); LSM_E_ZERO_LENGTH, LSM_E_NAN, LSM_E_INF, LSM_E_TOLERANCE (eps <= 0),
 * LSM_E_GAP (block 2 does not start at block 1's end), LSM_E_NONPLANAR, LSM_E_ROTARY, LSM_E_ARG (a
 * block that is neither a line nor an arc), LSM_E_CORNER_NO_SOLUTION (no transition within the trim
 * limits: stop at the corner).
 *
 * Cost (instructions on a Cortex-M4F, float build, -Os, QEMU mps2-an386 -icount; see docs/clothoid.md and
 * python -m lissom_hil.bench_clothoid --qemu): two lines, closed form (one atan2, a ~10-term series, no
 * iteration): ~1 500. Corners with arcs: 14 000-18 000 for a typical single scale (2 Newton iterations
 * of ~1 800 each, the deviation search ~10 000); over random corners the mean is ~20 000-22 000 and the
 * largest seen ~43 000 (a few scales when the trims or a fold limit the size). Stack: ~1 KB (float).
 * Units: mm, rad, 1/mm, 1/mm^2.
 */
#ifndef LSM_CORNER_H
#define LSM_CORNER_H

#include "geom.h"

/* Compile-time settings (LSM_CORNER_GAP_TOL_MM, LSM_CORNER_MAX_ARC_TRIM_RAD, LSM_CORNER_ACCEPT,
 * LSM_CORNER_DEFAULT_TRIM_FRACTION, LSM_CORNER_ANGLE_EPS_RAD): lsm_config.h. */

typedef struct lsm_corner_params {
    lsm_real tolerance_mm; /* eps > 0: largest deviation (see above) */
    lsm_real max_trim1_mm; /* most cut from the end of block 1; <= 0: LSM_CORNER_DEFAULT_TRIM_FRACTION of it */
    lsm_real max_trim2_mm; /* most cut from the start of block 2; <= 0: the same fraction of block 2 */
} lsm_corner_params;

typedef struct lsm_corner_result {
    lsm_geom trans[2];              /* clothoids A and B; A starts at p1, B ends at p2 */
    lsm_real trim1_mm;              /* arc length removed from the end of block 1 */
    lsm_real trim2_mm;              /* arc length removed from the start of block 2 */
    lsm_real p1_mm[3];              /* new end of block 1 */
    lsm_real p2_mm[3];              /* new start of block 2 */
    lsm_real deviation_mm;          /* max(vertex_dev_mm, path_dev_mm) <= tolerance */
    lsm_real vertex_dev_mm;         /* distance from the corner point to the transition */
    lsm_real path_dev_mm;           /* largest distance of the transition from the programmed path */
    lsm_real kappa_max_per_mm;      /* largest |kappa| on the transition (eq 7) */
    lsm_real sharpness_max_per_mm2; /* largest |c| on the transition (eq 8) */
    lsm_real delta_rad;             /* deflection angle at the corner, in [0, pi) */
    lsm_real gap_mm;                /* end of B vs p2 (solver residual) */
    lsm_real gap_rad;               /* end tangent of B vs block 2's tangent at p2 */
    uint16_t iterations;            /* Newton iterations, all scales */
    uint8_t scales;                 /* scales L tried */
    uint8_t limited;                /* 1: the trim limits, not the tolerance, set the size */
    uint8_t closed_form;            /* 1: line-line closed form */
} lsm_corner_result;

/* Smooth the corner between b1 (ending at the corner) and b2 (starting there). p may not be NULL
 * (tolerance is required). Nothing is modified; apply the trims with lsm_corner_apply. */
lsm_status lsm_corner_smooth(const lsm_geom *b1, const lsm_geom *b2, const lsm_corner_params *p,
                             lsm_corner_result *out);

/* Trim b1's end and b2's start as the result says. Errors: LSM_E_NULL, LSM_E_RANGE. */
lsm_status lsm_corner_apply(lsm_geom *b1, lsm_geom *b2, const lsm_corner_result *r);

#endif /* LSM_CORNER_H */
