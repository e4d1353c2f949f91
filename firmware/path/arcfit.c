/* arcfit.c: arcs and lines through runs of polyline points (see arcfit.h). */
#include "arcfit.h"

#include "lsm_math.h"

#define R0 LSM_R(0.0)
#define R1 LSM_R(1.0)
#define PI_R ((lsm_real)LSM_PI)

/* Tuning of the fit. */
#define AF_LINE_PREFER LSM_R(0.25) /* a line within tol / 4 is taken without trying an arc (fewer curvature steps) */
/* Relative slack of "the points follow each other" (rounding): the last point's position along the chord,
 * (qe - p0).u with u = (qe - p0) / L, comes out up to a few eps above L. 1e-9 is far above that in double but below
 * float's eps (1.2e-7): float runs whose last point came out an ulp beyond L were no line at all, so a straight pair
 * of 0.2 mm chords on a flat ellipse became a lone segment with two tiny corners (a dip to 49 mm/s, and a low node
 * that cost a re-plan per appended arc while it was in the buffer). */
#if LSM_REAL_IS_FLOAT
#define AF_ORDER_SLACK LSM_R(1e-6) /* 8 eps of float */
#else
#define AF_ORDER_SLACK LSM_R(1e-9)
#endif
#define AF_ANGLE_SLACK_RAD LSM_R(1e-9)    /* a point this far before the arc's start still counts as at its start */
#define AF_FLAT_EPS LSM_R(2048.0)         /* an arc's evaluation error R eps times this must stay below tol (float) */
#define AF_MIN_RADIUS_TOLS LSM_R(4.0)     /* radius at least 4 tol: a smaller circle is not worth an arc at this tol */
#define AF_CHAIN_MIN_POINTS LSM_R(16.0)   /* a chain's plane is measured from at least this many points */
#define AF_CHAIN_MIN_SPREAD_MM LSM_R(0.5) /* whose spread across the plane is at least this (both ways) */
#if LSM_REAL_IS_FLOAT
#define AF_CONTAINS_TOL LSM_R(1e-6) /* the chord's own plane holds a line when |n . d| is below this (rounding) */
#else
#define AF_CONTAINS_TOL LSM_R(1e-10)
#endif
#define AF_DRIFT_SHARE LSM_R(0.5) /* in a given plane, points at most tol / 2 off it: a line there still fits after */

static void sub3(const lsm_real a[3], const lsm_real b[3], lsm_real o[3])
{
    o[0] = a[0] - b[0];
    o[1] = a[1] - b[1];
    o[2] = a[2] - b[2];
}

/* Line p0 -> end (q[n-1], or its projection into a given plane): largest distance of the points (segments are
 * within the larger of their ends' distances; the last point's distance is its offset from `end`). */
static bool fit_line(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, const lsm_real end[3], lsm_real *err)
{
    lsm_real d[3];
    sub3(end, p0, d);
    const lsm_real L = lsm_sqrt(lsm_dot3(d, d));
    if (!(L > R0))
        return false;
    const lsm_real u[3] = {d[0] / L, d[1] / L, d[2] / L};
    lsm_real e = R0, tprev = R0;
    for (int i = 0; i < n; i++) {
        lsm_real r[3];
        sub3(q[i].p, p0, r);
        const lsm_real t = lsm_dot3(r, u);
        if (t < tprev) /* the points must follow each other along the line */
            return false;
        tprev = t;
        const lsm_real x[3] = {r[0] - t * u[0], r[1] - t * u[1], r[2] - t * u[2]};
        e = lsm_max2(e, lsm_sqrt(lsm_dot3(x, x)));
    }
    if (tprev > L * (R1 + AF_ORDER_SLACK))
        return false;
    *err = e;
    return true;
}

/* The line p0 -> qe as the fit, if it fits within tol. */
LSM_NOINLINE static bool af_take_line(bool line_ok, lsm_real lerr, lsm_real tol, const lsm_real *a6, const lsm_real *b6,
                                      lsm_geom *g, lsm_arcfit_result *res)
{
    if (!(line_ok && lerr <= tol && lsm_geom_line_init(g, a6, b6) == LSM_OK))
        return false;
    res->kind = LSM_ARCFIT_LINE;
    res->err_mm = lerr;
    return true;
}

typedef enum { AF_PLANE_OK, AF_PLANE_NONE, AF_PLANE_ON_CHORD } af_plane_kind;

/* Unit vector of v; false if it has no length. */
static bool unit3(const lsm_real v[3], lsm_real o[3])
{
    const lsm_real l = lsm_sqrt(lsm_dot3(v, v));
    if (!(l > R0))
        return false;
    for (int i = 0; i < 3; i++)
        o[i] = v[i] / l;
    return true;
}

/* A frame (eu, ev) of the plane with unit normal n (the same for the same n). */
static void af_frame(const lsm_real n[3], lsm_real eu[3], lsm_real ev[3])
{
    const int k = lsm_fabs(n[0]) <= lsm_fabs(n[1]) && lsm_fabs(n[0]) <= lsm_fabs(n[2]) ? 0
                  : lsm_fabs(n[1]) <= lsm_fabs(n[2])                                   ? 1
                                                                                       : 2;
    const lsm_real ek[3] = {k == 0 ? R1 : R0, k == 1 ? R1 : R0, k == 2 ? R1 : R0};
    lsm_real a[3];
    lsm_cross3(n, ek, a);
    if (!unit3(a, eu))
        eu[0] = R1, eu[1] = eu[2] = R0;
    lsm_cross3(n, eu, ev);
}

/* The chord direction u (unit; on entry the chord's) projected into the plane with unit normal nh. */
static bool af_into_plane(const lsm_real nh[3], lsm_real u[3])
{
    const lsm_real un = lsm_dot3(u, nh);
    lsm_real w[3];
    for (int i = 0; i < 3; i++)
        w[i] = u[i] - un * nh[i];
    return unit3(w, u);
}

/* The plane of the chord (direction u) and the points' offsets from it. */
static af_plane_kind af_plane_free(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real L, const lsm_real u[3],
                                   lsm_real nh[3])
{
    /* the sum of the points' offsets from the chord (an arc's all point the same way): it averages the rounding of
     * the points, where the farthest point alone tilts the plane by about rounding / sagitta (a G-code file rounded
     * to 0.1 um, 6 mm runs on R 40: 2e-4 rad, which the arcs after it inherit, so that a ring in a tilted plane left
     * the tolerance within a quarter turn) */
    lsm_real w[3] = {R0, R0, R0};
    for (int i = 0; i < n - 1; i++) {
        lsm_real r[3];
        sub3(q[i].p, p0, r);
        const lsm_real t = lsm_dot3(r, u);
        for (int j = 0; j < 3; j++)
            w[j] += r[j] - t * u[j];
    }
    lsm_cross3(u, w, nh);
    const lsm_real nl = lsm_sqrt(lsm_dot3(nh, nh));
    if (!(nl > LSM_REAL_EPS * L * L)) /* all on the chord */
        return AF_PLANE_ON_CHORD;
    for (int i = 0; i < 3; i++)
        nh[i] /= nl;
    return AF_PLANE_OK;
}

/* The arc's plane: the one given (pc; the chord direction u is projected into it), or the chord's with the points'
 * offsets from it. Writes the unit normal nh and the in-plane chord direction u (unit; on entry the chord's). */
LSM_NOINLINE static af_plane_kind af_plane(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real L,
                                           const lsm_arcfit_plane *pc, lsm_real u[3], lsm_real nh[3])
{
    if (pc != NULL && pc->kind == LSM_ARCFIT_PLANE_NORMAL) {
        /* the chord must lie in that plane (it joins the previous arc's end to a point on its plane) */
        if (!unit3(pc->v, nh))
            return AF_PLANE_NONE;
        return af_into_plane(nh, u) ? AF_PLANE_OK : AF_PLANE_NONE;
    }
    const af_plane_kind kf = af_plane_free(p0, q, n, L, u, nh);
    if (pc == NULL || pc->kind != LSM_ARCFIT_PLANE_CONTAINS)
        return kf;
    lsm_real d[3];
    if (!unit3(pc->v, d))
        return AF_PLANE_NONE;
    if (kf != AF_PLANE_OK)
        return kf;
    const lsm_real nd = lsm_dot3(nh, d);
    if (lsm_fabs(nd) <= AF_CONTAINS_TOL)
        return AF_PLANE_OK; /* the chord's own plane holds the line (a planar program) */
    /* turned the least to hold it (a chord of the same curve, rounded, is off its plane by about rounding / chord) */
    lsm_real w[3];
    for (int i = 0; i < 3; i++)
        w[i] = nh[i] - nd * d[i];
    if (!unit3(w, nh))
        return AF_PLANE_NONE;
    return af_into_plane(nh, u) ? AF_PLANE_OK : AF_PLANE_NONE;
}

/* Curvature by least squares over the points, sagitta model y(t) = k t (L - t) / 2 (robust to the rounding of the
 * points, unlike a circle through three of them); (u, v) the chord's frame in the plane. */
static bool af_curvature(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real L, const lsm_real u[3],
                         const lsm_real v[3], lsm_real *k)
{
    lsm_real sgy = R0, sgg = R0;
    for (int i = 0; i < n - 1; i++) {
        lsm_real r[3];
        sub3(q[i].p, p0, r);
        const lsm_real t = lsm_dot3(r, u), y = lsm_dot3(r, v);
        const lsm_real gg = t * (L - t) / LSM_R(2.0);
        sgy += y * gg;
        sgg += gg * gg;
    }
    if (!(sgg > R0))
        return false;
    *k = sgy / sgg;
    return true;
}

/* The candidate circle (centre C, frame e1 = (p0 - C) / r, e2 = nh x e1, sense sg): every point's distance to it
 * and every segment's bound, with the points' angles along the arc increasing within [0, pi]. On success the error
 * bound and the arc's end angle. */
static bool af_check_arc(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real tol, lsm_real hmax,
                         const lsm_real C[3], const lsm_real e1[3], const lsm_real e2[3], const lsm_real nh[3],
                         lsm_real r, lsm_real sg, lsm_real *err_out, lsm_real *th_end, bool *drifted)
{
    /* (the start is on the circle by construction: (r, 0) in the plane) */
    lsm_real err = R0, eprev = R0, th_prev = R0, xp = r, yp = R0, hp = R0;
    const lsm_real *xprev = p0;
    for (int i = 0; i < n; i++) {
        lsm_real rel[3];
        sub3(q[i].p, C, rel);
        const lsm_real x1 = lsm_dot3(rel, e1), y1 = lsm_dot3(rel, e2), h = lsm_dot3(rel, nh);
        lsm_real th = lsm_atan2(sg * y1, x1);
        if (th < -AF_ANGLE_SLACK_RAD)
            th += LSM_R(2.0) * PI_R;
        if (th < th_prev || th > PI_R)
            return false;
        if (lsm_fabs(h) > hmax) {
            *drifted = true; /* (off the given plane) */
            return false;
        }
        const lsm_real rho = lsm_sqrt(x1 * x1 + y1 * y1), rho_p = lsm_sqrt(xp * xp + yp * yp);
        const lsm_real e = lsm_sqrt((rho - r) * (rho - r) + h * h);
        /* the segment from the previous point (chord h): in the plane, its points are no farther from the centre
         * than its farther end and no nearer than its nearest point (the foot of the perpendicular from the centre,
         * |a x b| / |b - a|, if it falls inside, else the nearer end); along the normal, between its ends' offsets.
         * That bound is taken with the sagitta estimate max(e_i, e_i+1) + h²/8r the fits were tuned with, which
         * alone is no bound: points inside the circle by e put the chord up to about e h²/8r² farther (tight arcs:
         * 1e-3 mm at r 0.1); the larger of the two keeps every fit the estimate accepted and was a bound for. */
        const lsm_real dx = x1 - xp, dy = y1 - yp, dd = dx * dx + dy * dy, tf = -(xp * dx + yp * dy);
        const bool foot_in = dd > R0 && tf > R0 && tf < dd;
        const lsm_real near = foot_in ? lsm_fabs(xp * y1 - yp * x1) / lsm_sqrt(dd) : lsm_min2(rho, rho_p);
        const lsm_real radial = lsm_max2(R0, lsm_max2(r - near, lsm_max2(rho, rho_p) - r));
        const lsm_real axial = lsm_max2(lsm_fabs(h), lsm_fabs(hp));
        lsm_real c[3];
        sub3(q[i].p, xprev, c);
        const lsm_real sagitta = lsm_max2(e, eprev) + lsm_dot3(c, c) / (LSM_R(8.0) * r);
        const lsm_real seg = lsm_max2(sagitta, lsm_sqrt(radial * radial + axial * axial));
        err = lsm_max2(err, lsm_max2(e, seg));
        if (err > tol)
            return false;
        th_prev = th;
        eprev = e;
        xprev = q[i].p;
        xp = x1;
        yp = y1;
        hp = h;
    }
    *err_out = err;
    *th_end = th_prev;
    return true;
}

/* The arc through p0 and qe with curvature k (radius R) in the plane nh, minor arc bulging to +v when k > 0, if every
 * point and segment is within tol. */
static bool af_arc(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real tol, lsm_real hmax, lsm_real L,
                   lsm_real k, lsm_real R, const lsm_real u[3], const lsm_real v[3], const lsm_real nh[3], lsm_geom *g,
                   lsm_arcfit_result *res, bool *drifted)
{
    const lsm_real yc = (k > R0 ? -R1 : R1) * lsm_sqrt(R * R - L * L / LSM_R(4.0));
    lsm_real C[3], e1[3], e2[3];
    for (int i = 0; i < 3; i++)
        C[i] = p0[i] + LSM_R(0.5) * L * u[i] + yc * v[i];
    for (int i = 0; i < 3; i++)
        e1[i] = p0[i] - C[i];
    const lsm_real e1l = lsm_sqrt(lsm_dot3(e1, e1));
    if (!(e1l > R0))
        return false;
    for (int i = 0; i < 3; i++)
        e1[i] /= e1l; /* exactly unit: the plane normal is passed on from arc to arc */
    lsm_cross3(nh, e1, e2);
    const lsm_real r = R;
    const lsm_real sg = k > R0 ? -R1 : R1; /* bulging to +v: clockwise about nh */
    lsm_real err, th_end;
    if (!af_check_arc(p0, q, n, tol, hmax, C, e1, e2, nh, r, sg, &err, &th_end, drifted))
        return false;
    if (!(th_end > R0))
        return false;
    if (lsm_geom_arc_init_general(g, C, e1, e2, r, R0, sg * th_end, R0) != LSM_OK)
        return false;
    /* The arc starts on p0 exactly (phi0 = 0, e1 points from C to p0): init_general's C + r e1 is off by ulp(r)
     * (3e-5 mm at r 480 in float), a setpoint jump where the element joins what came before. */
    for (int i = 0; i < 3; i++)
        g->u.arc.start_mm[i] = p0[i];
    res->kind = LSM_ARCFIT_ARC;
    res->err_mm = err;
    res->radius_mm = r;
    for (int i = 0; i < 3; i++)
        res->normal[i] = nh[i];
    return true;
}

bool lsm_arcfit_fit(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real tol, const lsm_arcfit_plane *pc,
                    lsm_geom *g, lsm_arcfit_result *res)
{
    res->kind = LSM_ARCFIT_NONE;
    res->err_mm = R0;
    res->radius_mm = R0;
    res->drifted = 0;
    if (n < 1 || !(tol > R0))
        return false;
    const lsm_real *qe = q[n - 1].p;
    /* the line's end: qe, or in a given plane its projection there (corner.h blends an arc and a line only when the
     * line lies in the arc's plane); the offset is part of the line's error */
    lsm_real le[3] = {qe[0], qe[1], qe[2]};
    lsm_real pn[3];
    const bool in_plane = pc != NULL && (pc->kind == LSM_ARCFIT_PLANE_NORMAL || pc->kind == LSM_ARCFIT_LINE_IN);
    const bool line_only = pc != NULL && (pc->kind == LSM_ARCFIT_LINE_FREE || pc->kind == LSM_ARCFIT_LINE_IN);
    if (in_plane) {
        if (!unit3(pc->v, pn))
            return false;
        lsm_real r[3];
        sub3(qe, p0, r);
        const lsm_real z = lsm_dot3(r, pn);
        for (int i = 0; i < 3; i++)
            le[i] = qe[i] - z * pn[i];
    }
    lsm_real a6[LSM_MAX_AXES] = {p0[0], p0[1], p0[2], R0, R0, R0};
    lsm_real b6[LSM_MAX_AXES] = {le[0], le[1], le[2], R0, R0, R0};
    lsm_real lerr = LSM_REAL_MAX;
    const bool line_ok = fit_line(p0, q, n, le, &lerr);
    for (int i = 0; i < 3; i++)
        res->end_mm[i] = le[i];
    if (line_only)
        return af_take_line(line_ok, lerr, tol, a6, b6, g, res);
    if (line_ok && (lerr <= tol * AF_LINE_PREFER || n < 2))
        return af_take_line(line_ok, lerr, tol, a6, b6, g, res);
    if (n < 2)
        return false;
    /* chord p0 -> qe (both kept exactly), its direction u, the plane nh, v across the chord in the plane */
    lsm_real b[3], u[3], nh[3], v[3];
    sub3(qe, p0, b);
    const lsm_real L0 = lsm_sqrt(lsm_dot3(b, b));
    if (!(L0 > R0))
        return false;
    for (int i = 0; i < 3; i++)
        u[i] = b[i] / L0;
    const af_plane_kind pk = af_plane(p0, q, n, L0, pc, u, nh);
    if (pk == AF_PLANE_NONE)
        return false;
    if (pk == AF_PLANE_ON_CHORD)
        return af_take_line(line_ok, lerr, tol, a6, b6, g, res);
    /* in a given plane the chord is qe's projection (the arc ends off qe by its offset from the plane): the points
     * may leave that plane by at most drift_mm (AF_DRIFT_SHARE of the tolerance by default), so that a line in it
     * still fits after the last arc there (which closes the chain: plan_fit.c) */
    const lsm_real hmax = !in_plane ? tol : pc->drift_mm > R0 ? lsm_min2(pc->drift_mm, tol) : AF_DRIFT_SHARE * tol;
    const lsm_real L = L0; /* (the projected chord is shorter by about offset² / L: the check below measures the
                            * points against the circle actually built) */
    lsm_cross3(nh, u, v);  /* (u, v, nh) right-handed; v points across the chord, in the plane */
    lsm_real k;
    if (!af_curvature(p0, q, n, L, u, v, &k))
        return false;
    const lsm_real R = R1 / lsm_fabs(k);
    /* an arc is evaluated with an error of about R eps (lsm_real): a radius so large that this error is not far
     * below the tolerance (float builds) is fitted with a line, or not at all */
    const bool too_flat = R * LSM_REAL_EPS * AF_FLAT_EPS > tol;
    if (!(lsm_fabs(k) > R0) || !(R > AF_MIN_RADIUS_TOLS * tol) || !(L < LSM_R(2.0) * R) || too_flat)
        return af_take_line(line_ok, lerr, tol, a6, b6, g, res);
    bool drifted = false;
    if (af_arc(p0, q, n, tol, hmax, L, k, R, u, v, nh, g, res, &drifted))
        return true;
    /* the points left the given plane: a line in it closes the chain of arcs */
    res->drifted = drifted ? 1u : 0u;
    return drifted && af_take_line(line_ok, lerr, tol, a6, b6, g, res);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* the plane of a chain of arcs, measured                                                                       */

void lsm_arcfit_chain_reset(lsm_arcfit_chain *c, const lsm_real origin[3])
{
    for (int i = 0; i < 3; i++)
        c->origin[i] = origin[i];
    for (int i = 0; i < 9; i++)
        c->s[i] = R0;
}

void lsm_arcfit_chain_add(lsm_arcfit_chain *c, const lsm_real nrm[3], const lsm_arcfit_pt *q, int n)
{
    lsm_real eu[3], ev[3];
    af_frame(nrm, eu, ev);
    for (int i = 0; i < n; i++) {
        lsm_real r[3];
        sub3(q[i].p, c->origin, r);
        const lsm_real u = lsm_dot3(r, eu), v = lsm_dot3(r, ev), z = lsm_dot3(r, nrm);
        const lsm_real add[9] = {u * u, u * v, v * v, u, v, R1, z * u, z * v, z};
        for (int k = 0; k < 9; k++)
            c->s[k] += add[k];
    }
}

/* Determinant of the 3x3 matrix with columns a, b, c. */
static lsm_real det3(const lsm_real a[3], const lsm_real b[3], const lsm_real c[3])
{
    lsm_real x[3];
    lsm_cross3(b, c, x);
    return lsm_dot3(a, x);
}

bool lsm_arcfit_chain_plane(const lsm_arcfit_chain *c, const lsm_real nrm[3], lsm_real out[3])
{
    const lsm_real *s = c->s;
    /* normal equations of z = a u + b v + c over the chain's points (Cramer) */
    const lsm_real m0[3] = {s[0], s[1], s[3]}, m1[3] = {s[1], s[2], s[4]}, m2[3] = {s[3], s[4], s[5]};
    const lsm_real rhs[3] = {s[6], s[7], s[8]};
    const lsm_real det = det3(m0, m1, m2);
    /* the points must spread across the plane: det is N^3 times the product of the variances of u and v (less
     * their covariance), at least AF_CHAIN_MIN_SPREAD_MM^4 */
    const lsm_real sp2 = AF_CHAIN_MIN_SPREAD_MM * AF_CHAIN_MIN_SPREAD_MM;
    if (!(s[5] >= AF_CHAIN_MIN_POINTS) || !(det > s[5] * s[5] * s[5] * sp2 * sp2))
        return false;
    const lsm_real a = det3(rhs, m1, m2) / det, b = det3(m0, rhs, m2) / det;
    lsm_real eu[3], ev[3], nt[3];
    af_frame(nrm, eu, ev);
    for (int i = 0; i < 3; i++)
        nt[i] = nrm[i] - a * eu[i] - b * ev[i];
    return unit3(nt, out);
}
