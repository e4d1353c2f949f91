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
 * the plane of the chord and the points' summed offsets from it (or a given plane); its curvature k is the least-squares
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
    lsm_real end_mm[3]; /* lines: the end (q[n-1], or its projection into the given plane) */
    uint8_t drifted;    /* a line in the given plane because the points left it by more than drift_mm (no arc) */
} lsm_arcfit_result;

/* What the fitted element must keep to (the block before the run: corner.h blends planar joints only). */
typedef enum lsm_arcfit_plane_kind {
    LSM_ARCFIT_PLANE_NORMAL = 1,  /* after a fitted arc: an arc lies in the plane through p0 with normal v, and a line
                                  * too (it ends on q[n-1] projected into the plane) */
    LSM_ARCFIT_LINE_FREE = 2,     /* a line only */
    LSM_ARCFIT_LINE_IN = 3,       /* a line only, in the plane through p0 with normal v (projected as above) */
    LSM_ARCFIT_PLANE_CONTAINS = 4 /* after a line of direction v: an arc lies in a plane through p0 that contains v
                                   * (the chord's own turned the least to hold v; the arc then ends on q[n-1]'s
                                   * projection); lines are free */
} lsm_arcfit_plane_kind;

typedef struct lsm_arcfit_plane {
    lsm_real v[3];     /* the normal, or the line's direction (need not be unit) */
    lsm_real drift_mm; /* NORMAL: an arc only while every point is within this of the plane (<= tol; 0: tol / 2) */
    uint8_t kind;      /* lsm_arcfit_plane_kind */
} lsm_arcfit_plane;

/*
 * Fits p0, q[0 .. n-1] (n >= 1) within tol_mm. `plane` (may be NULL: any plane): the plane the element keeps to (see
 * lsm_arcfit_plane_kind). In a given plane, the element ends on q[n-1] projected into it (off q[n-1] by its offset
 * from the plane, within tol), and an arc is taken only while every point is within drift_mm of that plane, so
 * that a line in the plane still fits after it: a run that leaves the plane of a chain of arcs (a tilted ring whose
 * first plane came from rounded points) ends the chain with such a line. A line is preferred when it fits within
 * tol/4. On success writes the element to g (it starts exactly on
 * p0 and ends at q[n-1] within rounding, or on its projection) and returns true. Background (the planner's appends).
 */
bool lsm_arcfit_fit(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real tol_mm, const lsm_arcfit_plane *plane,
                    lsm_geom *g, lsm_arcfit_result *res);

/*
 * The plane of a chain of fitted arcs, measured. Consecutive fitted arcs share one plane (corner.h blends planar
 * joints only), taken from the first run's rounded points: a ring in a tilted plane, rounded to 0.1 um, gets it to
 * about 5e-5 rad (6 mm runs on R 40), so its points leave it by up to 2 R times that within a turn. The offsets z of
 * the chain's points from its plane (through `origin`, unit normal n) are fitted by least squares, z = a u + b v + c
 * ((u, v) a frame of the plane): n - a e_u - b e_v is the plane the points keep to (the rounding averages out over
 * the chain: ~1e-6 rad after a quarter turn of R 15-40). The planner changes to it through lines (plan_fit.c).
 * Memory: 12 lsm_real. Background.
 */
typedef struct lsm_arcfit_chain {
    lsm_real origin[3];
    lsm_real s[9]; /* sums of uu, uv, vv, u, v, 1, zu, zv, z */
} lsm_arcfit_chain;

/* Starts a chain at origin (the start of its first arc). */
void lsm_arcfit_chain_reset(lsm_arcfit_chain *c, const lsm_real origin[3]);
/* Adds the points q[0 .. n-1] of a run emitted in the chain's plane (unit normal nrm). */
void lsm_arcfit_chain_add(lsm_arcfit_chain *c, const lsm_real nrm[3], const lsm_arcfit_pt *q, int n);
/* The measured plane's unit normal (the chain's plane has unit normal nrm). False when the points do not determine it
 * (fewer than 16, or spread less than 0.5 mm across the plane either way). */
bool lsm_arcfit_chain_plane(const lsm_arcfit_chain *c, const lsm_real nrm[3], lsm_real out[3]);

#endif /* LSM_ARCFIT_H */
