/*
 * arcfit.h: fitting runs of short G1 segments (CAM polylines) with circular arcs or lines within a tolerance
 * (lsm_arcfit_*), used by the planner's append path.
 *
 * Why. A dense polyline that samples a smooth curve turns by a small angle delta at every vertex. Smoothing every
 * vertex with its own clothoid pair (corner.h) makes the curvature oscillate on the scale of the segments: the
 * sharpness is about delta / (h/2)², so the feed limit cbrt(j / c) (Shahzadeh eq 8) drops far below what the curve
 * itself allows (a circle of 0.1 mm chords at R 10: 25 mm/s with j = 60 m/s³, against 180 mm/s for the circle).
 * Fitting arcs through the points first restores the curve's own curvature; the joints between consecutive arcs
 * (small kinks and curvature steps) are then smoothed by corner.h as usual.
 *
 * Model. A run is a start point p0 (the end of what was already emitted) and points q1 .. qn (ends of
 * consecutive segments). Its candidate arc goes through p0 and qn (kept exactly, so consecutive elements join) in
 * the plane of the chord and the point farthest from it (or a given plane); its curvature k is the least-squares
 * fit of the points' offsets y_i from the chord to the sagitta model y(t) = k t (L - t) / 2, which averages the
 * rounding of the points (a circle through three close points of a G-code file rounded to 0.1 um can be off by
 * 1/mm in curvature). The candidate line goes from p0 to qn. A candidate fits when every point is within tol of it
 * (in-plane radial and out-of-plane distance), the points follow each other along it, and every segment stays
 * within tol: in the plane, a segment's points are no farther from the centre than its farther end and no nearer
 * than its line (|a x b| / |b - a| for ends a, b relative to the centre), and along the normal between its ends'
 * offsets, so its distance to the arc is at most sqrt(radial² + axial²) of those. The error returned is that
 * bound, so the programmed polyline is within `err` of the fitted element everywhere, and vice versa. Arcs span at
 * most pi.
 * Units: mm.
 */
#ifndef LSM_ARCFIT_H
#define LSM_ARCFIT_H

#include "geom.h"

/* Compile-time settings (LSM_ARCFIT_MAX): lsm_config.h. */

typedef struct lsm_arcfit_pt {
    lsm_real p[3];
    uint32_t seq;
} lsm_arcfit_pt;

typedef enum lsm_arcfit_kind { LSM_ARCFIT_NONE = 0, LSM_ARCFIT_LINE = 1, LSM_ARCFIT_ARC = 2 } lsm_arcfit_kind;

typedef struct lsm_arcfit_result {
    lsm_arcfit_kind kind;
    lsm_real err_mm;    /* largest distance between the polyline and the element (bound) */
    lsm_real radius_mm; /* arcs */
    lsm_real normal[3]; /* arcs: unit normal of the plane (the arc runs counter-clockwise about it) */
} lsm_arcfit_result;

/*
 * Fits p0, q[0 .. n-1] (n >= 1) within tol_mm. `plane_n` (may be NULL): if given, an arc must lie in the plane with
 * this unit normal through p0 (continuity with a previous arc: corner.h blends planar joints only). A line is
 * preferred when it fits within tol/4. On success writes the element to g (it starts at p0 and ends at q[n-1]
 * within rounding) and returns true.
 */
bool lsm_arcfit_fit(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real tol_mm, const lsm_real *plane_n,
                    lsm_geom *g, lsm_arcfit_result *res);

#endif /* LSM_ARCFIT_H */
