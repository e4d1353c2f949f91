/* geom.c: lines, arcs and clothoids as path elements (see geom.h). */
#include "geom.h"

#include "clothoid.h"
#include "lsm_math.h"

#if LSM_REAL_IS_FLOAT
#define GEOM_ORTHO_TOL LSM_R(1e-5)
#else
#define GEOM_ORTHO_TOL LSM_R(1e-6)
#endif

static lsm_status geom_check(const lsm_real *v, int n)
{
    for (int i = 0; i < n; i++) {
        int r = lsm_check_finite(v[i]);
        if (r != 0)
            return (lsm_status)r;
    }
    return LSM_OK;
}

static bool geom_orthonormal(const lsm_real e1[3], const lsm_real e2[3])
{
    return lsm_fabs(lsm_dot3(e1, e1) - LSM_R(1.0)) <= GEOM_ORTHO_TOL &&
           lsm_fabs(lsm_dot3(e2, e2) - LSM_R(1.0)) <= GEOM_ORTHO_TOL && lsm_fabs(lsm_dot3(e1, e2)) <= GEOM_ORTHO_TOL;
}

LSM_NOINLINE static bool geom_plane_basis(lsm_geom_plane plane, lsm_real e1[3], lsm_real e2[3])
{
    for (int i = 0; i < 3; i++)
        e1[i] = e2[i] = LSM_R(0.0);
    switch (plane) {
    case LSM_GEOM_PLANE_XY: e1[0] = e2[1] = LSM_R(1.0); return true;
    case LSM_GEOM_PLANE_ZX: e1[2] = e2[0] = LSM_R(1.0); return true;
    case LSM_GEOM_PLANE_YZ: e1[1] = e2[2] = LSM_R(1.0); return true;
    case LSM_GEOM_PLANE_GENERAL: break;
    }
    return false;
}

lsm_status lsm_geom_line_init(lsm_geom *g, const lsm_real p0[LSM_MAX_AXES], const lsm_real p1[LSM_MAX_AXES])
{
    if (g == NULL || p0 == NULL || p1 == NULL)
        return LSM_E_NULL;
    lsm_status st = geom_check(p0, LSM_MAX_AXES);
    if (st == LSM_OK)
        st = geom_check(p1, LSM_MAX_AXES);
    if (st != LSM_OK)
        return st;
    lsm_real d[LSM_MAX_AXES];
    lsm_real xyz = LSM_R(0.0), all = LSM_R(0.0);
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        d[i] = p1[i] - p0[i];
        if (lsm_check_finite(d[i]))
            return LSM_E_RANGE;
        if (i < 3)
            xyz += d[i] * d[i];
        all += d[i] * d[i];
    }
    const bool rot = !(xyz > LSM_R(0.0));
    const lsm_real len = lsm_sqrt(rot ? all : xyz);
    if (!(len > LSM_R(0.0)))
        return LSM_E_ZERO_LENGTH;
    if (lsm_check_finite(len))
        return LSM_E_RANGE;
    g->kind = LSM_GEOM_LINE;
    g->plane = 0;
    g->rotary_only = rot ? 1u : 0u;
    g->reserved = 0;
    g->len = len;
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        g->u.line.p0[i] = p0[i];
        g->u.line.dir[i] = d[i] / len;
    }
    return LSM_OK;
}

static lsm_real geom_wrap_2pi(lsm_real a) /* to [0, 2 pi) */
{
    const lsm_real two_pi = (lsm_real)(2.0 * LSM_PI);
    a -= two_pi * lsm_floor(a / two_pi);
    if (a >= two_pi)
        a -= two_pi;
    return a;
}

/* May the centre move by t along the chord (rounded I J K, geom.h)? The points of the arc then move by about
 * |t| sin(half the sweep) <= |t| chord / (2 r) (minor arcs): the float build bounds that by the tolerance (a float
 * centre of a large radius is off by ulp(r), so t reaches millimetres while the path moves by a fraction of a
 * micrometre); the double build bounds t itself. */
static bool geom_shift_ok(lsm_real t, lsm_real chord, lsm_real r)
{
#if LSM_REAL_IS_FLOAT
    const lsm_real f = chord < LSM_R(2.0) * r ? chord / (LSM_R(2.0) * r) : LSM_R(1.0);
    return lsm_fabs(t) * f <= (lsm_real)LSM_GEOM_ARC_TOL_MM && lsm_fabs(t) <= LSM_R(0.5) * r;
#else
    (void)chord;
    (void)r;
    return lsm_fabs(t) <= (lsm_real)LSM_GEOM_ARC_TOL_MM;
#endif
}

#if LSM_REAL_IS_FLOAT
/* Float: end and start are the same point in the plane, to the rounding of their coordinates (a full circle). Not
 * 16 eps r, as in double: at R 6e4 that is 0.1 mm, and a programmed chord of 0.1 mm would turn a full circle. */
static bool geom_same_point(const lsm_real start[3], const lsm_real end[3], const lsm_real e1[3], const lsm_real e2[3])
{
    const lsm_real su = lsm_dot3(start, e1), sv = lsm_dot3(start, e2), eu = lsm_dot3(end, e1), ev = lsm_dot3(end, e2);
    const lsm_real sc = lsm_fabs(su) + lsm_fabs(sv) + lsm_fabs(eu) + lsm_fabs(ev);
    return lsm_fabs(eu - su) + lsm_fabs(ev - sv) <= LSM_R(4.0) * LSM_REAL_EPS * sc;
}

/* Float: the circle through start and end whose centre is the point of the chord's bisector nearest the
 * programmed centre, from the chord d = end - start and the programmed centre's offsets along d and across it,
 *     h = (u1 dv - v1 du) / |d|   (its distance from the chord, > 0 on the left of d),
 *     r = |d/2 + h n|,  phi0 = angle of the start seen from that centre,  sweep = 2 atan2(|d| / 2, dir h),
 * with n the left normal of d. Every quantity is a product of the chord's size and the radius: no r1² - r2², no
 * difference of two end angles, which in float carry ulp(r) / |d| of noise (a 0.2 mm centre shift and a 5e-4 rad
 * turn of the arc at R 400 over a 0.05 mm chord). The caller has excluded end == start (a full circle,
 * geom_same_point). False (and nothing set) when the centre would move too far (geom_shift_ok): the programmed centre
 * is kept. */
static bool geom_arc_bisector(const lsm_real start[3], const lsm_real end[3], const lsm_real e1[3],
                              const lsm_real e2[3], lsm_real u1, lsm_real v1, lsm_real r1, int dir, lsm_real *r,
                              lsm_real *phi0, lsm_real *sweep)
{
    const lsm_real d[3] = {end[0] - start[0], end[1] - start[1], end[2] - start[2]};
    const lsm_real du = lsm_dot3(d, e1), dv = lsm_dot3(d, e2);
    const lsm_real c = lsm_sqrt(du * du + dv * dv);
    const lsm_real h = (u1 * dv - v1 * du) / c;
    const lsm_real t = -((u1 + LSM_R(0.5) * du) * du + (v1 + LSM_R(0.5) * dv) * dv) / c; /* the move along d */
    if (!geom_shift_ok(t, c, r1))
        return false;
    const lsm_real cu = LSM_R(0.5) * du - h * dv / c, cv = LSM_R(0.5) * dv + h * du / c; /* centre - start */
    *r = lsm_sqrt(cu * cu + cv * cv);
    *phi0 = lsm_atan2(-cv, -cu);
    *sweep = LSM_R(2.0) * lsm_atan2(LSM_R(0.5) * c, dir > 0 ? h : -h);
    return true;
}
#endif

static void geom_arc_len(lsm_geom *g)
{
    const lsm_real a = g->u.arc.radius_mm * g->u.arc.sweep_rad, b = g->u.arc.axial_mm;
    g->len = lsm_sqrt(a * a + b * b);
}

lsm_status lsm_geom_arc_init(lsm_geom *g, const lsm_real start[3], const lsm_real end[3], const lsm_real centre[3],
                             lsm_geom_plane plane, int dir, uint32_t turns)
{
    if (g == NULL || start == NULL || end == NULL || centre == NULL)
        return LSM_E_NULL;
    lsm_status st = geom_check(start, 3);
    if (st == LSM_OK)
        st = geom_check(end, 3);
    if (st == LSM_OK)
        st = geom_check(centre, 3);
    if (st != LSM_OK)
        return st;
    lsm_real e1[3], e2[3], n[3];
    if (!geom_plane_basis(plane, e1, e2) || (dir != 1 && dir != -1))
        return LSM_E_ARG;
    lsm_cross3(e1, e2, n);
    lsm_real ds[3], de[3];
    for (int i = 0; i < 3; i++) {
        ds[i] = start[i] - centre[i];
        de[i] = end[i] - centre[i];
    }
    lsm_real u1 = lsm_dot3(ds, e1), v1 = lsm_dot3(ds, e2), u2 = lsm_dot3(de, e1), v2 = lsm_dot3(de, e2);
    lsm_real r1 = lsm_sqrt(u1 * u1 + v1 * v1), r2 = lsm_sqrt(u2 * u2 + v2 * v2);
    if (!(r1 > LSM_R(0.0)) || !(r2 > LSM_R(0.0)) || lsm_check_finite(r1) || lsm_check_finite(r2))
        return LSM_E_ARC_GEOMETRY;
    if (lsm_fabs(r1 - r2) > (lsm_real)LSM_GEOM_ARC_TOL_MM)
        return LSM_E_ARC_GEOMETRY;
    lsm_real phi0, sweep;
#if LSM_REAL_IS_FLOAT
    /* Float: the bisector's circle from the programmed centre (u1, v1, r1) where it applies; the shift and the two end
     * angles below only where it does not (a full circle, or a centre that would move too far) */
    const bool same = geom_same_point(start, end, e1, e2);
    if (same || !geom_arc_bisector(start, end, e1, e2, u1, v1, r1, dir, &r1, &phi0, &sweep))
#endif
    {
        /* Rounded I J K (CAM output) leave the end a little off the start's circle. Move the centre onto the
         * perpendicular bisector of the chord, to its point nearest the programmed centre: shift t along the chord
         * direction d, t = (r2² - r1²) / (2 |chord|); then both points lie on the circle and the arc ends exactly on
         * the programmed end. Only while that shift stays within the radius tolerance (a nearly closed arc with
         * a short chord keeps the programmed centre, and its end is off by at most |r1 - r2|). */
        const lsm_real du = u2 - u1, dv = v2 - v1;
        const lsm_real chord = lsm_sqrt(du * du + dv * dv);
        if (r1 != r2 && chord > LSM_R(16.0) * LSM_REAL_EPS * r1) {
            const lsm_real t = (r2 - r1) * (r2 + r1) / (LSM_R(2.0) * chord);
            if (geom_shift_ok(t, chord, r1)) {
                const lsm_real su = t * du / chord, sv = t * dv / chord;
                u1 -= su, v1 -= sv, u2 -= su, v2 -= sv;
                r1 = lsm_sqrt(u1 * u1 + v1 * v1); /* the radius kept (the end's, r2, is equal up to rounding) */
            }
        }
        phi0 = lsm_atan2(v1, u1);
        const lsm_real phi1 = lsm_atan2(v2, u2);
        sweep = geom_wrap_2pi(dir > 0 ? phi1 - phi0 : phi0 - phi1);
    }
    /* end == start (to rounding) is a full circle */
#if LSM_REAL_IS_FLOAT
    if (sweep == LSM_R(0.0) || same)
        sweep = (lsm_real)(2.0 * LSM_PI);
#else
    const lsm_real cu = u2 - u1, cv = v2 - v1;
    if (sweep == LSM_R(0.0) || lsm_sqrt(cu * cu + cv * cv) <= LSM_R(16.0) * LSM_REAL_EPS * r1)
        sweep = (lsm_real)(2.0 * LSM_PI);
#endif
    sweep += (lsm_real)(2.0 * LSM_PI) * (lsm_real)turns;
    g->kind = LSM_GEOM_ARC;
    g->plane = (uint8_t)plane;
    g->rotary_only = 0;
    g->reserved = 0;
    for (int i = 0; i < 3; i++) {
        g->u.arc.start_mm[i] = start[i];
        g->u.arc.e1[i] = e1[i];
        g->u.arc.e2[i] = e2[i];
    }
    g->u.arc.radius_mm = r1;
    g->u.arc.phi0_rad = phi0;
    g->u.arc.sweep_rad = dir > 0 ? sweep : -sweep;
    lsm_real dse[3] = {end[0] - start[0], end[1] - start[1], end[2] - start[2]};
    g->u.arc.axial_mm = lsm_dot3(dse, n);
    geom_arc_len(g);
    if (lsm_check_finite(g->len))
        return LSM_E_RANGE;
    return LSM_OK;
}

/* A point, a frame (e1, e2) and four scalars: all finite and within range (geom_check). */
static lsm_status geom_check_frame(const lsm_real p[3], const lsm_real e1[3], const lsm_real e2[3],
                                   const lsm_real sc[4])
{
    lsm_status st = geom_check(p, 3);
    if (st == LSM_OK)
        st = geom_check(e1, 3);
    if (st == LSM_OK)
        st = geom_check(e2, 3);
    if (st == LSM_OK)
        st = geom_check(sc, 4);
    return st;
}

lsm_status lsm_geom_arc_init_general(lsm_geom *g, const lsm_real centre[3], const lsm_real e1[3], const lsm_real e2[3],
                                     lsm_real radius_mm, lsm_real phi0_rad, lsm_real sweep_rad, lsm_real axial_mm)
{
    if (g == NULL || centre == NULL || e1 == NULL || e2 == NULL)
        return LSM_E_NULL;
    const lsm_real sc[4] = {radius_mm, phi0_rad, sweep_rad, axial_mm};
    const lsm_status st = geom_check_frame(centre, e1, e2, sc);
    if (st != LSM_OK)
        return st;
    if (!(radius_mm > LSM_R(0.0)) || !geom_orthonormal(e1, e2))
        return LSM_E_ARC_GEOMETRY;
    if (sweep_rad == LSM_R(0.0))
        return LSM_E_ZERO_LENGTH;
    g->kind = LSM_GEOM_ARC;
    g->plane = LSM_GEOM_PLANE_GENERAL;
    g->rotary_only = 0;
    g->reserved = 0;
    lsm_real sp, cp;
    lsm_sincos(phi0_rad, &sp, &cp);
    for (int i = 0; i < 3; i++) {
        g->u.arc.start_mm[i] = centre[i] + radius_mm * (cp * e1[i] + sp * e2[i]);
        g->u.arc.e1[i] = e1[i];
        g->u.arc.e2[i] = e2[i];
    }
    g->u.arc.radius_mm = radius_mm;
    g->u.arc.phi0_rad = phi0_rad;
    g->u.arc.sweep_rad = sweep_rad;
    g->u.arc.axial_mm = axial_mm;
    geom_arc_len(g);
    if (lsm_check_finite(g->len))
        return LSM_E_RANGE;
    return LSM_OK;
}

lsm_status lsm_geom_clothoid_init(lsm_geom *g, const lsm_real origin[3], const lsm_real e1[3], const lsm_real e2[3],
                                  lsm_real theta0_rad, lsm_real kappa0_per_mm, lsm_real c_per_mm2, lsm_real len_mm)
{
    if (g == NULL || origin == NULL || e1 == NULL || e2 == NULL)
        return LSM_E_NULL;
    const lsm_real sc[4] = {theta0_rad, kappa0_per_mm, c_per_mm2, len_mm};
    const lsm_status st = geom_check_frame(origin, e1, e2, sc);
    if (st != LSM_OK)
        return st;
    if (!geom_orthonormal(e1, e2))
        return LSM_E_ARG;
    if (!(len_mm > LSM_R(0.0)))
        return LSM_E_ZERO_LENGTH;
    g->kind = LSM_GEOM_CLOTHOID;
    g->plane = LSM_GEOM_PLANE_GENERAL;
    g->rotary_only = 0;
    g->reserved = 0;
    for (int i = 0; i < 3; i++) {
        g->u.clo.origin_mm[i] = origin[i];
        g->u.clo.e1[i] = e1[i];
        g->u.clo.e2[i] = e2[i];
    }
    g->u.clo.theta0_rad = theta0_rad;
    g->u.clo.kappa0_per_mm = kappa0_per_mm;
    g->u.clo.c_per_mm2 = c_per_mm2;
    g->len = len_mm;
    return LSM_OK;
}

static void geom_arc_normal(const lsm_geom_arc *a, lsm_real n[3])
{
    lsm_cross3(a->e1, a->e2, n);
}

/* The in-plane chord from the start to the angle phi0 + dphi: 2 r sin(dphi/2) (-sin(phi0 + dphi/2) e1 +
 * cos(phi0 + dphi/2) e2), to a few ulp of its length. */
static void geom_arc_chord(const lsm_geom_arc *a, lsm_real dphi, lsm_real c[3])
{
    const lsm_real h = LSM_R(0.5) * dphi;
    lsm_real sh, ch, sm, cm;
    lsm_sincos(h, &sh, &ch);
    lsm_sincos(a->phi0_rad + h, &sm, &cm);
    const lsm_real k = LSM_R(2.0) * a->radius_mm * sh;
    for (int i = 0; i < 3; i++)
        c[i] = k * (cm * a->e2[i] - sm * a->e1[i]);
    (void)ch;
}

void lsm_geom_arc_centre(const lsm_geom *g, lsm_real c[3])
{
    const lsm_geom_arc *a = &g->u.arc;
    lsm_real sp, cp;
    lsm_sincos(a->phi0_rad, &sp, &cp);
    for (int i = 0; i < 3; i++)
        c[i] = a->start_mm[i] - a->radius_mm * (cp * a->e1[i] + sp * a->e2[i]);
}

lsm_status lsm_geom_eval(const lsm_geom *g, lsm_real s, lsm_real pos[LSM_MAX_AXES], lsm_real tan[3], lsm_real curv[3])
{
    if (g == NULL)
        return LSM_E_NULL;
    if (s != s)
        return LSM_E_NAN;
    if (s < LSM_R(0.0))
        s = LSM_R(0.0);
    if (s > g->len)
        s = g->len;
    switch ((lsm_geom_kind)g->kind) {
    case LSM_GEOM_LINE: {
        const lsm_geom_line *l = &g->u.line;
        if (pos)
            for (int i = 0; i < LSM_MAX_AXES; i++)
                pos[i] = l->p0[i] + l->dir[i] * s;
        for (int i = 0; i < 3; i++) {
            if (tan)
                tan[i] = g->rotary_only ? LSM_R(0.0) : l->dir[i];
            if (curv)
                curv[i] = LSM_R(0.0);
        }
        return LSM_OK;
    }
    case LSM_GEOM_ARC: {
        const lsm_geom_arc *a = &g->u.arc;
        const lsm_real f = s / g->len;
        const lsm_real phi = a->phi0_rad + a->sweep_rad * f;
        lsm_real co = LSM_R(0.0), si = LSM_R(0.0);
        if (tan || curv) /* (the position comes from the chord) */
            lsm_sincos(phi, &si, &co);
        lsm_real n[3];
        geom_arc_normal(a, n);
        const lsm_real w = a->sweep_rad / g->len; /* dphi/ds */
        lsm_real chord[3] = {LSM_R(0.0), LSM_R(0.0), LSM_R(0.0)};
        if (pos)
            geom_arc_chord(a, a->sweep_rad * f, chord);
        for (int i = 0; i < 3; i++) {
            const lsm_real radial = co * a->e1[i] + si * a->e2[i];
            if (pos)
                pos[i] = a->start_mm[i] + chord[i] + n[i] * a->axial_mm * f;
            if (tan)
                tan[i] = w * a->radius_mm * (-si * a->e1[i] + co * a->e2[i]) + n[i] * a->axial_mm / g->len;
            if (curv)
                curv[i] = -w * w * a->radius_mm * radial;
        }
        return LSM_OK;
    }
    case LSM_GEOM_CLOTHOID: {
        const lsm_geom_clothoid *c = &g->u.clo;
        lsm_real X = LSM_R(0.0), Y = LSM_R(0.0);
        if (pos)
            lsm_clothoid_integral(c->theta0_rad, c->kappa0_per_mm, c->c_per_mm2, s, &X, &Y);
        const lsm_real th = c->theta0_rad + s * (c->kappa0_per_mm + LSM_R(0.5) * c->c_per_mm2 * s);
        const lsm_real k = c->kappa0_per_mm + c->c_per_mm2 * s;
        lsm_real co, si;
        lsm_sincos(th, &si, &co);
        for (int i = 0; i < 3; i++) {
            if (pos)
                pos[i] = c->origin_mm[i] + c->e1[i] * X + c->e2[i] * Y;
            if (tan)
                tan[i] = co * c->e1[i] + si * c->e2[i];
            if (curv)
                curv[i] = k * (-si * c->e1[i] + co * c->e2[i]);
        }
        return LSM_OK;
    }
    }
    return LSM_E_ARG;
}

lsm_real lsm_geom_kappa(const lsm_geom *g, lsm_real s)
{
    lsm_real cv[3];
    if (lsm_geom_eval(g, s, NULL, NULL, cv) != LSM_OK)
        return LSM_R(0.0);
    return lsm_sqrt(lsm_dot3(cv, cv));
}

lsm_real lsm_geom_length(const lsm_geom *g)
{
    return g ? g->len : LSM_R(0.0);
}

void lsm_geom_start_tangent(const lsm_geom *g, lsm_real t[3])
{
    (void)lsm_geom_eval(g, LSM_R(0.0), NULL, t, NULL);
}

void lsm_geom_end_tangent(const lsm_geom *g, lsm_real t[3])
{
    (void)lsm_geom_eval(g, g->len, NULL, t, NULL);
}

bool lsm_geom_moves_rotary(const lsm_geom *g)
{
    if (g->kind != LSM_GEOM_LINE)
        return false;
    return g->u.line.dir[3] != LSM_R(0.0) || g->u.line.dir[4] != LSM_R(0.0) || g->u.line.dir[5] != LSM_R(0.0);
}

bool lsm_geom_normal(const lsm_geom *g, lsm_real n[3])
{
    if (g->kind == LSM_GEOM_ARC) {
        geom_arc_normal(&g->u.arc, n);
        return true;
    }
    if (g->kind == LSM_GEOM_CLOTHOID) {
        lsm_cross3(g->u.clo.e1, g->u.clo.e2, n);
        return true;
    }
    return false;
}

LSM_NOINLINE static lsm_status geom_trim_check(const lsm_geom *g, lsm_real d)
{
    if (g == NULL)
        return LSM_E_NULL;
    int r = lsm_check_finite(d);
    if (r != 0)
        return (lsm_status)r;
    if (d < LSM_R(0.0) || d >= g->len)
        return LSM_E_RANGE;
    return LSM_OK;
}

lsm_status lsm_geom_trim_start(lsm_geom *g, lsm_real d)
{
    lsm_status st = geom_trim_check(g, d);
    if (st != LSM_OK || d == LSM_R(0.0))
        return st;
    switch ((lsm_geom_kind)g->kind) {
    case LSM_GEOM_LINE:
        for (int i = 0; i < LSM_MAX_AXES; i++)
            g->u.line.p0[i] += g->u.line.dir[i] * d;
        g->len -= d;
        return LSM_OK;
    case LSM_GEOM_ARC: {
        lsm_geom_arc *a = &g->u.arc;
        const lsm_real f = d / g->len;
        lsm_real p[LSM_MAX_AXES] = {0};
        (void)lsm_geom_eval(g, d, p, NULL, NULL); /* the new start */
        for (int i = 0; i < 3; i++)
            a->start_mm[i] = p[i];
        a->phi0_rad += a->sweep_rad * f;
        a->sweep_rad -= a->sweep_rad * f;
        a->axial_mm -= a->axial_mm * f;
        geom_arc_len(g);
        return LSM_OK;
    }
    case LSM_GEOM_CLOTHOID: {
        lsm_geom_clothoid *c = &g->u.clo;
        lsm_real X, Y;
        lsm_clothoid_integral(c->theta0_rad, c->kappa0_per_mm, c->c_per_mm2, d, &X, &Y);
        for (int i = 0; i < 3; i++)
            c->origin_mm[i] += c->e1[i] * X + c->e2[i] * Y;
        c->theta0_rad += d * (c->kappa0_per_mm + LSM_R(0.5) * c->c_per_mm2 * d);
        c->kappa0_per_mm += c->c_per_mm2 * d;
        g->len -= d;
        return LSM_OK;
    }
    }
    return LSM_E_ARG;
}

lsm_status lsm_geom_trim_end(lsm_geom *g, lsm_real d)
{
    lsm_status st = geom_trim_check(g, d);
    if (st != LSM_OK || d == LSM_R(0.0))
        return st;
    if (g->kind == LSM_GEOM_ARC) {
        lsm_geom_arc *a = &g->u.arc;
        const lsm_real f = LSM_R(1.0) - d / g->len;
        a->sweep_rad *= f;
        a->axial_mm *= f;
        geom_arc_len(g);
        return LSM_OK;
    }
    if (g->kind == LSM_GEOM_LINE || g->kind == LSM_GEOM_CLOTHOID) {
        g->len -= d;
        return LSM_OK;
    }
    return LSM_E_ARG;
}
