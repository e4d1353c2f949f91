/*
 * geom.h: the primitive path elements of the planner (lsm_geom_*): lines in up to six axes, circular
 * and helical arcs, and planar clothoids placed in 3-D.
 *
 * Every element is parametrised by its arc length s in [0, len] and answers position, unit tangent
 * and curvature vector (dT/ds, its norm is the curvature kappa) at s.
 *  - Line: p(s) = p0 + dir s over all LSM_MAX_AXES axes (X Y Z mm, A B C rad). len is the XYZ length
 *    (mm) and dir is a unit vector in XYZ; A B C move in proportion (rad per mm). A line that moves
 *    only A B C is "rotary only": len is then the ABC length in rad.
 *  - Arc (G2/G3 or any plane): centre c, orthonormal plane basis (e1, e2) with normal n = e1 x e2,
 *    radius r, start angle phi0 (from e1 towards e2), signed sweep (> 0: counter-clockwise about n)
 *    and a helical component `axial` along n over the whole arc:
 *        phi(s) = phi0 + sweep s / len,  p(s) = c + r (cos phi e1 + sin phi e2) + n axial s / len,
 *        len = sqrt((r sweep)^2 + axial^2),  kappa = r sweep^2 / len^2 (= 1/r when axial = 0).
 *    G17: (e1, e2) = (X, Y); G18: (Z, X); G19: (Y, Z), as in RS274/NGC; G3 is counter-clockwise.
 *    Float build: the arc keeps its start point p0 (exactly the programmed start) instead of its centre, and
 *    is evaluated from it by the chord to phi (no cancellation, whatever the radius):
 *        p(s) = p0 + 2 r sin(dphi/2) (-sin(phi0 + dphi/2) e1 + cos(phi0 + dphi/2) e2) + n axial s / len,
 *        dphi = sweep s / len,
 *    and its sweep comes from the chord d and the cross product X = (p0 - c) x d in the plane,
 *    sweep = 2 atan2(|d|²/2, +-X) (no difference of two angles). A float centre is off by ulp(r) (5e-4 mm at
 *    R = 1e4) and c + r u(phi) carries that much noise into every setpoint; from p0 the error is a few ulp of
 *    the coordinates and of the chord. The double build keeps the centre (ulp(r) is 2e-12 mm at R = 1e4), and
 *    with it its results bit for bit. lsm_geom_arc_centre gives the centre in both builds.
 *  - Clothoid: a planar clothoid (clothoid.h, paper eqs 1, 2, 11, 12) drawn in the plane through
 *    `origin` spanned by (e1, e2): p(s) = origin + e1 X(s) + e2 Y(s), with X + iY =
 *    int_0^s e^{i(theta0 + kappa0 t + c t^2/2)} dt; kappa(s) = kappa0 + c s (signed about n).
 * Arcs and clothoids do not move A B C: their evaluation leaves pos[3..] as the caller set them (the
 * planner keeps the rotary position of the block start there).
 *
 * Size: float build (Cortex-M4F) sizeof(lsm_geom) <= 64 bytes (checked below), double 128 bytes.
 * Units: mm, rad, 1/mm.
 */
#ifndef LSM_GEOM_H
#define LSM_GEOM_H

#include "lsm_config.h"
#include "status.h"

/* Compile-time settings (LSM_GEOM_ARC_TOL_MM): lsm_config.h. */

typedef enum lsm_geom_kind { LSM_GEOM_LINE = 1, LSM_GEOM_ARC = 2, LSM_GEOM_CLOTHOID = 3 } lsm_geom_kind;

typedef enum lsm_geom_plane {
    LSM_GEOM_PLANE_GENERAL = 0, /* any orthonormal (e1, e2) */
    LSM_GEOM_PLANE_XY = 17,     /* G17: e1 = X, e2 = Y, n = Z */
    LSM_GEOM_PLANE_ZX = 18,     /* G18: e1 = Z, e2 = X, n = Y */
    LSM_GEOM_PLANE_YZ = 19      /* G19: e1 = Y, e2 = Z, n = X */
} lsm_geom_plane;

typedef struct lsm_geom_line {
    lsm_real p0[LSM_MAX_AXES];  /* start: X Y Z mm, A B C rad */
    lsm_real dir[LSM_MAX_AXES]; /* d(axis)/ds */
} lsm_geom_line;

typedef struct lsm_geom_arc {
    /* the start point (exactly the programmed start of a G2/G3): the arc is evaluated by its chord from there, so
     * its rounding is that of the coordinates, not of the radius (a centre 1e5 mm away adds ulp(1e5) of noise) */
    lsm_real start_mm[3];
    lsm_real e1[3], e2[3]; /* orthonormal plane basis */
    lsm_real radius_mm;
    lsm_real phi0_rad;  /* start angle */
    lsm_real sweep_rad; /* signed swept angle (may exceed 2 pi with full turns) */
    lsm_real axial_mm;  /* helix: displacement along n over the arc */
} lsm_geom_arc;

typedef struct lsm_geom_clothoid {
    lsm_real origin_mm[3];
    lsm_real e1[3], e2[3];
    lsm_real theta0_rad;
    lsm_real kappa0_per_mm;
    lsm_real c_per_mm2;
} lsm_geom_clothoid;

typedef struct lsm_geom {
    lsm_real len;        /* arc length: mm (rad for a rotary-only line) */
    uint8_t kind;        /* lsm_geom_kind */
    uint8_t plane;       /* lsm_geom_plane of an arc or clothoid, 0 for lines */
    uint8_t rotary_only; /* line that moves only A B C */
    uint8_t reserved;
    union {
        lsm_geom_line line;
        lsm_geom_arc arc;
        lsm_geom_clothoid clo;
    } u;
} lsm_geom;

#if LSM_REAL_IS_FLOAT
_Static_assert(sizeof(lsm_geom) <= 64, "lsm_geom must fit in 64 bytes in the float build");
#endif

/* Line from p0 to p1 (LSM_MAX_AXES values each). Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF,
 * LSM_E_ZERO_LENGTH (p0 == p1 on every axis). */
lsm_status lsm_geom_line_init(lsm_geom *g, const lsm_real p0[LSM_MAX_AXES], const lsm_real p1[LSM_MAX_AXES]);

/* Arc in G17/G18/G19 from start, end and centre (X Y Z, mm), direction dir = +1 (G3, counter-
 * clockwise) or -1 (G2), plus `turns` extra full turns; end == start (in the plane) is a full
 * circle. The centre's coordinate along the normal is ignored (the start's is used); the end's
 * normal coordinate gives the helix. When the end is a little off the start's circle (rounded I J K),
 * the centre is moved onto the chord's perpendicular bisector (the point nearest the programmed centre)
 * if that moves it by at most LSM_GEOM_ARC_TOL_MM, so the arc passes through both programmed points.
 * Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF, LSM_E_ARG (plane or
 * dir), LSM_E_ARC_GEOMETRY (zero radius, |r_start - r_end| > LSM_GEOM_ARC_TOL_MM). */
lsm_status lsm_geom_arc_init(lsm_geom *g, const lsm_real start[3], const lsm_real end[3], const lsm_real centre[3],
                             lsm_geom_plane plane, int dir, uint32_t turns);

/* Arc from its parameters (general plane). Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF,
 * LSM_E_ARC_GEOMETRY (radius <= 0, basis not orthonormal within 1e-6), LSM_E_ZERO_LENGTH (sweep 0). */
lsm_status lsm_geom_arc_init_general(lsm_geom *g, const lsm_real centre[3], const lsm_real e1[3], const lsm_real e2[3],
                                     lsm_real radius_mm, lsm_real phi0_rad, lsm_real sweep_rad, lsm_real axial_mm);

/* Clothoid placed in the plane (origin, e1, e2). Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF,
 * LSM_E_ARG (basis not orthonormal within 1e-6), LSM_E_ZERO_LENGTH (len <= 0). */
lsm_status lsm_geom_clothoid_init(lsm_geom *g, const lsm_real origin[3], const lsm_real e1[3], const lsm_real e2[3],
                                  lsm_real theta0_rad, lsm_real kappa0_per_mm, lsm_real c_per_mm2, lsm_real len_mm);

/* Position, unit tangent (XYZ) and curvature vector dT/ds at s (clamped to [0, len]). Any of pos,
 * tan, curv may be NULL. pos holds LSM_MAX_AXES values; arcs and clothoids write only pos[0..2].
 * A rotary-only line reports a zero tangent. Errors: LSM_E_NULL (g), LSM_E_NAN (s). */
lsm_status lsm_geom_eval(const lsm_geom *g, lsm_real s, lsm_real pos[LSM_MAX_AXES], lsm_real tan[3], lsm_real curv[3]);

/* The centre of an arc (its coordinate along n is the start point's): stored in the double build, derived from
 * the start point in the float build (to about r ulp(phi0) there). */
void lsm_geom_arc_centre(const lsm_geom *g, lsm_real c[3]);

/* Curvature magnitude at s (1/mm). */
lsm_real lsm_geom_kappa(const lsm_geom *g, lsm_real s);
/* Length (mm; rad for rotary-only lines). */
lsm_real lsm_geom_length(const lsm_geom *g);
/* Unit tangents at the start and the end. */
void lsm_geom_start_tangent(const lsm_geom *g, lsm_real t[3]);
void lsm_geom_end_tangent(const lsm_geom *g, lsm_real t[3]);
/* The plane normal of an arc or clothoid (e1 x e2); false for a line. */
bool lsm_geom_normal(const lsm_geom *g, lsm_real n[3]);
/* A line that moves a rotary axis (A, B or C: dir[3..5] not 0); false for arcs and clothoids. Background. */
bool lsm_geom_moves_rotary(const lsm_geom *g);

/* Remove d from the start / the end (0 <= d < len). Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF,
 * LSM_E_RANGE (d < 0 or d >= len). */
lsm_status lsm_geom_trim_start(lsm_geom *g, lsm_real d);
lsm_status lsm_geom_trim_end(lsm_geom *g, lsm_real d);

#endif /* LSM_GEOM_H */
