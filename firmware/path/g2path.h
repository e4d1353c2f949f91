/*
 * g2path.h: G2-continuous approximation of a planar contour of lines and arcs by a chain of
 * clothoids, Shahzadeh et al. section V (lsm_g2path_*).
 *
 * Method (section V). The contour is split into N segments by N + 1 points p_0 .. p_N (each element
 * gets a share of N in proportion to its length, at least one, split at equal arc length). At every
 * inner point p_j the bisector of the angle p_{j-1} p_j p_{j+1} is drawn; it passes through p_j and
 * its normal is u2 - u1 (u1, u2 the unit vectors from p_j to its neighbours), which stays well
 * defined for collinear points. Starting at p_0 with the contour's tangent and curvature, clothoid j
 * is fitted from the end state of clothoid j - 1 to bisector j, meeting it at a right angle
 * (clothoid.h, paper section IV, eqs 13-16); the last one ends on the normal of the contour at p_N.
 * Each clothoid starts with the curvature the previous one ended with, so the chain is G2.
 *
 * Report: the largest distance of the chain from the contour (dev_mm), the largest distance from the
 * polygon p_0 .. p_N (dev_chord_mm: the measure that reproduces the 0.94 mm of the paper's
 * 6-segment example, see docs/clothoid.md), kappa_max and c_max, and the feed limits
 * f1 = sqrt(a_max / kappa_max) (eq 7) and f2 = cbrt(j_max / c_max) (eq 8), in mm/s.
 * Deviations are sampled (16 points per clothoid) and refined by a golden-section search.
 * Observed scaling (paper Fig. 7): doubling N divides dev_mm by about 4 and c_max tends to double.
 *
 * The clothoids are written to caller storage, in plane coordinates: G17 (x, y) = (X, Y),
 * G18 (x, y) = (Z, X), G19 (x, y) = (Y, Z); normal_mm is the contour's constant third coordinate.
 * Units: mm, rad, 1/mm, 1/mm^2, mm/s, mm/s^2, mm/s^3.
 */
#ifndef LSM_G2PATH_H
#define LSM_G2PATH_H

#include "clothoid.h"
#include "geom.h"

typedef struct lsm_g2path_report {
    int n_segments;
    lsm_real dev_mm;                /* largest distance of the chain from the contour */
    lsm_real dev_chord_mm;          /* largest distance from the polygon through the split points */
    lsm_real kappa_max_per_mm;      /* largest |kappa| of the chain */
    lsm_real sharpness_max_per_mm2; /* largest |c| of the chain */
    lsm_real feed_acc_mm_s;         /* eq 7 (LSM_REAL_MAX if kappa_max = 0) */
    lsm_real feed_jerk_mm_s;        /* eq 8 (LSM_REAL_MAX if c_max = 0) */
    lsm_real end_gap_mm;            /* distance of the chain's end from the contour's end */
    lsm_real normal_mm;             /* the contour's coordinate along the plane normal */
    int iterations_max;             /* most Newton iterations of one fit */
    int builds;                     /* paths built (lsm_g2path_auto) */
} lsm_g2path_report;

/* Build the chain with n_segments clothoids into out[0 .. n_segments-1] (cap entries available).
 * The contour: n_elems lines and arcs in the plane (G17/G18/G19), each starting where the previous
 * one ends. a_max_mm_s2, j_max_mm_s3 > 0 give the feed limits. Errors: LSM_E_NULL, LSM_E_NAN,
 * LSM_E_INF, LSM_E_LIMIT, LSM_E_ARG (kind, plane, n_elems < 1, n_segments < n_elems), LSM_E_FULL
 * (cap < n_segments), LSM_E_NONPLANAR, LSM_E_ROTARY, LSM_E_GAP, LSM_E_REVERSAL (a cusp), and the
 * fit's errors (LSM_E_FIT_*, LSM_E_NOT_CONVERGED). */
lsm_status lsm_g2path_build(const lsm_geom *contour, int n_elems, lsm_geom_plane plane, int n_segments,
                            lsm_real a_max_mm_s2, lsm_real j_max_mm_s3, lsm_clothoid *out, int cap,
                            lsm_g2path_report *rep);

/* Choose N automatically: the smallest N found (doubling, then bisection) with dev_mm <= tol_mm,
 * built into out. Errors: as lsm_g2path_build, plus LSM_E_TOLERANCE (tol <= 0) and
 * LSM_E_TOL_UNREACHED (not reached with N = cap; out then holds that path). */
lsm_status lsm_g2path_auto(const lsm_geom *contour, int n_elems, lsm_geom_plane plane, lsm_real tol_mm,
                           lsm_real a_max_mm_s2, lsm_real j_max_mm_s3, lsm_clothoid *out, int cap,
                           lsm_g2path_report *rep);

#endif /* LSM_G2PATH_H */
