/* g2path.c: section-V G2 path construction (see g2path.h). */
#include "g2path.h"

#include "lsm_math.h"

#if LSM_REAL_IS_FLOAT
#define GP_PLANAR_TOL LSM_R(1e-5)
#else
#define GP_PLANAR_TOL LSM_R(1e-9)
#endif
#define GP_SAMPLES 16
#define GP_GOLDEN 24

typedef struct {
    lsm_real e1[3], e2[3], n[3];
} gp_plane;

/* An element (or a polygon side) in plane coordinates, for distances. */
typedef struct {
    bool arc, full;
    lsm_real ax, ay, bx, by; /* end points */
    lsm_real cx, cy, r;      /* arc */
    lsm_real mx, my, cw;     /* arc: mid radial direction, cos(half sweep) */
} gp_elem2d;

/* Split point walker. */
typedef struct {
    const lsm_geom *c;
    int n_elems, n;
    lsm_real total, cum; /* total length; length before element e */
    int e, m, ne, b_prev;
} gp_walk;

static lsm_real dot3(const lsm_real a[3], const lsm_real b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static bool gp_plane_make(lsm_geom_plane plane, gp_plane *pl)
{
    for (int i = 0; i < 3; i++)
        pl->e1[i] = pl->e2[i] = pl->n[i] = LSM_R(0.0);
    switch (plane) {
    case LSM_GEOM_PLANE_XY: pl->e1[0] = pl->e2[1] = pl->n[2] = LSM_R(1.0); return true;
    case LSM_GEOM_PLANE_ZX: pl->e1[2] = pl->e2[0] = pl->n[1] = LSM_R(1.0); return true;
    case LSM_GEOM_PLANE_YZ: pl->e1[1] = pl->e2[2] = pl->n[0] = LSM_R(1.0); return true;
    case LSM_GEOM_PLANE_GENERAL: break;
    }
    return false;
}

static void gp_proj(const gp_plane *pl, const lsm_real p[3], lsm_real *x, lsm_real *y)
{
    *x = dot3(p, pl->e1);
    *y = dot3(p, pl->e2);
}

static void gp_point(const gp_plane *pl, const lsm_geom *g, lsm_real s, lsm_real *x, lsm_real *y)
{
    lsm_real p[LSM_MAX_AXES];
    lsm_geom_eval(g, s, p, NULL, NULL);
    gp_proj(pl, p, x, y);
}

static void gp_elem_make(const gp_plane *pl, const lsm_geom *g, gp_elem2d *e)
{
    gp_point(pl, g, LSM_R(0.0), &e->ax, &e->ay);
    gp_point(pl, g, g->len, &e->bx, &e->by);
    e->arc = g->kind == LSM_GEOM_ARC;
    e->full = false;
    if (!e->arc)
        return;
    const lsm_geom_arc *a = &g->u.arc;
    lsm_real centre[3];
    lsm_geom_arc_centre(g, centre);
    gp_proj(pl, centre, &e->cx, &e->cy);
    e->r = a->radius_mm;
    lsm_real mx, my;
    gp_point(pl, g, LSM_R(0.5) * g->len, &mx, &my);
    mx -= e->cx;
    my -= e->cy;
    const lsm_real mn = lsm_sqrt(mx * mx + my * my);
    e->mx = mx / mn;
    e->my = my / mn;
    const lsm_real half = LSM_R(0.5) * lsm_fabs(a->sweep_rad);
    e->full = half >= (lsm_real)LSM_PI;
    e->cw = lsm_cos(half);
}

static void gp_seg_make(lsm_real ax, lsm_real ay, lsm_real bx, lsm_real by, gp_elem2d *e)
{
    e->arc = e->full = false;
    e->ax = ax;
    e->ay = ay;
    e->bx = bx;
    e->by = by;
}

static lsm_real gp_dist(const gp_elem2d *e, lsm_real x, lsm_real y)
{
    if (e->arc) {
        const lsm_real qx = x - e->cx, qy = y - e->cy;
        const lsm_real rho = lsm_sqrt(qx * qx + qy * qy);
        if (e->full || qx * e->mx + qy * e->my >= e->cw * rho)
            return lsm_fabs(rho - e->r);
    } else {
        const lsm_real dx = e->bx - e->ax, dy = e->by - e->ay;
        const lsm_real l2 = dx * dx + dy * dy;
        if (l2 > LSM_R(0.0)) {
            lsm_real t = ((x - e->ax) * dx + (y - e->ay) * dy) / l2;
            if (t >= LSM_R(0.0) && t <= LSM_R(1.0)) {
                const lsm_real px = e->ax + t * dx - x, py = e->ay + t * dy - y;
                return lsm_sqrt(px * px + py * py);
            }
        }
    }
    const lsm_real d0 = lsm_sqrt((x - e->ax) * (x - e->ax) + (y - e->ay) * (y - e->ay));
    const lsm_real d1 = lsm_sqrt((x - e->bx) * (x - e->bx) + (y - e->by) * (y - e->by));
    return d0 < d1 ? d0 : d1;
}

/* ---------------------------------------------------------------- split points */

static void gp_walk_bound(gp_walk *w)
{
    /* b_e = round(N cum_e / total), kept so that every element gets >= 1 segment */
    const lsm_real cum_e = w->cum + w->c[w->e].len;
    int b = (int)lsm_floor((lsm_real)w->n * cum_e / w->total + LSM_R(0.5));
    if (w->e == w->n_elems - 1)
        b = w->n;
    const int lo = w->b_prev + 1, hi = w->n - (w->n_elems - 1 - w->e);
    if (b < lo)
        b = lo;
    if (b > hi)
        b = hi;
    w->ne = b - w->b_prev;
}

static void gp_walk_init(gp_walk *w, const lsm_geom *c, int n_elems, int n, lsm_real total)
{
    w->c = c;
    w->n_elems = n_elems;
    w->n = n;
    w->total = total;
    w->cum = LSM_R(0.0);
    w->e = 0;
    w->m = 0;
    w->b_prev = 0;
    gp_walk_bound(w);
}

/* Current split point, and the element its following piece belongs to. */
static void gp_walk_point(const gp_walk *w, const gp_plane *pl, lsm_real *x, lsm_real *y)
{
    const lsm_geom *g = &w->c[w->e];
    const lsm_real s = w->m == w->ne ? g->len : g->len * (lsm_real)w->m / (lsm_real)w->ne;
    gp_point(pl, g, s, x, y);
}

static void gp_walk_next(gp_walk *w)
{
    w->m++;
    if (w->m == w->ne && w->e < w->n_elems - 1) {
        w->b_prev += w->ne;
        w->cum += w->c[w->e].len;
        w->e++;
        w->m = 0;
        gp_walk_bound(w);
    }
}

/* ---------------------------------------------------------------- deviation of one clothoid */

typedef struct {
    const lsm_clothoid *cl;
    const gp_elem2d *el;
    int n_el;
} gp_devctx;

static lsm_real gp_devf(const gp_devctx *d, lsm_real t)
{
    lsm_clothoid_state s;
    lsm_clothoid_eval(d->cl, t, &s);
    lsm_real best = LSM_REAL_MAX;
    for (int i = 0; i < d->n_el; i++) {
        const lsm_real v = gp_dist(&d->el[i], s.x_mm, s.y_mm);
        if (v < best)
            best = v;
    }
    return best;
}

static lsm_real gp_maxdev(const gp_devctx *d)
{
    const lsm_real L = d->cl->len_mm;
    const lsm_real h = L / (lsm_real)GP_SAMPLES;
    lsm_real best = LSM_R(-1.0);
    int arg = 0;
    for (int i = 0; i <= GP_SAMPLES; i++) {
        const lsm_real v = gp_devf(d, h * (lsm_real)i);
        if (v > best) {
            best = v;
            arg = i;
        }
    }
    const lsm_real g = LSM_R(0.6180339887498949);
    lsm_real a = h * (lsm_real)(arg > 0 ? arg - 1 : 0), b = h * (lsm_real)(arg < GP_SAMPLES ? arg + 1 : GP_SAMPLES);
    lsm_real x1 = b - g * (b - a), x2 = a + g * (b - a);
    lsm_real f1 = gp_devf(d, x1), f2 = gp_devf(d, x2);
    for (int i = 0; i < GP_GOLDEN; i++) {
        if (f1 >= f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = gp_devf(d, x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = gp_devf(d, x2);
        }
        if (f1 > best)
            best = f1;
        if (f2 > best)
            best = f2;
    }
    return best;
}

/* ---------------------------------------------------------------- build */

static lsm_status gp_validate(const lsm_geom *contour, int n_elems, const gp_plane *pl, lsm_real *total,
                              lsm_real *normal)
{
    lsm_real t = LSM_R(0.0);
    lsm_real p0[LSM_MAX_AXES];
    lsm_geom_eval(&contour[0], LSM_R(0.0), p0, NULL, NULL);
    *normal = dot3(p0, pl->n);
    for (int i = 0; i < n_elems; i++) {
        const lsm_geom *g = &contour[i];
        if (g->kind != LSM_GEOM_LINE && g->kind != LSM_GEOM_ARC)
            return LSM_E_ARG;
        int fr = lsm_check_finite(g->len);
        if (fr != 0)
            return (lsm_status)fr;
        if (!(g->len > LSM_R(0.0)))
            return LSM_E_ZERO_LENGTH;
        if (g->kind == LSM_GEOM_LINE) {
            for (int k = 0; k < 2 * LSM_MAX_AXES; k++) {
                fr = lsm_check_finite(k < LSM_MAX_AXES ? g->u.line.p0[k] : g->u.line.dir[k - LSM_MAX_AXES]);
                if (fr != 0)
                    return (lsm_status)fr;
            }
            if (g->rotary_only || g->u.line.dir[3] != LSM_R(0.0) || g->u.line.dir[4] != LSM_R(0.0) ||
                g->u.line.dir[5] != LSM_R(0.0))
                return LSM_E_ROTARY;
            if (lsm_fabs(dot3(g->u.line.dir, pl->n)) > GP_PLANAR_TOL)
                return LSM_E_NONPLANAR;
        } else {
            lsm_real na[3];
            lsm_geom_normal(g, na);
            const lsm_real c = dot3(na, pl->n);
            if (lsm_fabs(lsm_fabs(c) - LSM_R(1.0)) > GP_PLANAR_TOL ||
                lsm_fabs(g->u.arc.axial_mm) > GP_PLANAR_TOL * g->len)
                return LSM_E_NONPLANAR;
        }
        lsm_real ps[LSM_MAX_AXES];
        lsm_geom_eval(g, LSM_R(0.0), ps, NULL, NULL);
        if (lsm_fabs(dot3(ps, pl->n) - *normal) > (lsm_real)LSM_G2PATH_GAP_TOL_MM)
            return LSM_E_NONPLANAR;
        if (i > 0) {
            lsm_real pe[LSM_MAX_AXES];
            lsm_geom_eval(&contour[i - 1], contour[i - 1].len, pe, NULL, NULL);
            lsm_real d2 = LSM_R(0.0);
            for (int k = 0; k < 3; k++)
                d2 += (pe[k] - ps[k]) * (pe[k] - ps[k]);
            if (lsm_sqrt(d2) > (lsm_real)LSM_G2PATH_GAP_TOL_MM)
                return LSM_E_GAP;
        }
        t += g->len;
    }
    *total = t;
    return LSM_OK;
}

static lsm_status gp_build(const lsm_geom *contour, int n_elems, const gp_plane *pl, lsm_real total, int n,
                           lsm_real a_max, lsm_real j_max, lsm_clothoid *out, lsm_g2path_report *rep)
{
    /* start state: the contour's start, tangent angle and signed curvature in the plane */
    lsm_real p[LSM_MAX_AXES], t[3], cv[3];
    lsm_geom_eval(&contour[0], LSM_R(0.0), p, t, cv);
    lsm_clothoid_state st;
    gp_proj(pl, p, &st.x_mm, &st.y_mm);
    st.theta_rad = lsm_atan2(dot3(t, pl->e2), dot3(t, pl->e1));
    {
        /* kappa = (t x curv) . n */
        const lsm_real cz = (t[1] * cv[2] - t[2] * cv[1]) * pl->n[0] + (t[2] * cv[0] - t[0] * cv[2]) * pl->n[1] +
                            (t[0] * cv[1] - t[1] * cv[0]) * pl->n[2];
        st.kappa_per_mm = cz;
    }
    gp_walk w;
    gp_walk_init(&w, contour, n_elems, n, total);
    /* rolling window of split points q[0] = p_{j-2}, q[1] = p_{j-1}, q[2] = p_j, q[3] = p_{j+1} */
    lsm_real qx[4], qy[4];
    int qe[4]; /* element of the piece that starts at the point */
    qx[1] = st.x_mm;
    qy[1] = st.y_mm;
    qx[0] = qx[1];
    qy[0] = qy[1];
    qe[1] = qe[0] = 0;
    gp_walk_point(&w, pl, &qx[1], &qy[1]);
    qe[1] = w.e;
    gp_walk_next(&w);
    gp_walk_point(&w, pl, &qx[2], &qy[2]);
    qe[2] = w.e;
    lsm_real kmax = lsm_fabs(st.kappa_per_mm), cmax = LSM_R(0.0), dev = LSM_R(0.0), devc = LSM_R(0.0);
    int itmax = 0;
    for (int j = 1; j <= n; j++) {
        lsm_real nx, ny;
        if (j < n) {
            gp_walk_next(&w);
            gp_walk_point(&w, pl, &qx[3], &qy[3]);
            qe[3] = w.e;
            lsm_real u1x = qx[1] - qx[2], u1y = qy[1] - qy[2], u2x = qx[3] - qx[2], u2y = qy[3] - qy[2];
            const lsm_real l1 = lsm_sqrt(u1x * u1x + u1y * u1y), l2 = lsm_sqrt(u2x * u2x + u2y * u2y);
            if (!(l1 > LSM_R(0.0)) || !(l2 > LSM_R(0.0)))
                return LSM_E_ZERO_LENGTH;
            nx = u2x / l2 - u1x / l1;
            ny = u2y / l2 - u1y / l1;
            if (!(lsm_sqrt(nx * nx + ny * ny) > LSM_R(1e-6)))
                return LSM_E_REVERSAL;
        } else {
            lsm_real te[3];
            lsm_geom_end_tangent(&contour[n_elems - 1], te);
            nx = dot3(te, pl->e1);
            ny = dot3(te, pl->e2);
            qx[3] = qx[2];
            qy[3] = qy[2];
            qe[3] = qe[2];
        }
        lsm_clothoid_fit_result fr;
        lsm_status s = lsm_clothoid_fit_pn(&st, qx[2], qy[2], nx, ny, &fr);
        if (s != LSM_OK)
            return s;
        if (fr.iterations > itmax)
            itmax = fr.iterations;
        lsm_clothoid *cl = &out[j - 1];
        s = lsm_clothoid_init(cl, st.x_mm, st.y_mm, st.theta_rad, st.kappa_per_mm, fr.c_per_mm2, fr.s_mm);
        if (s != LSM_OK)
            return s;
        if (lsm_fabs(fr.end.kappa_per_mm) > kmax)
            kmax = lsm_fabs(fr.end.kappa_per_mm);
        if (lsm_fabs(fr.c_per_mm2) > cmax)
            cmax = lsm_fabs(fr.c_per_mm2);
        if (fr.s_mm > LSM_R(0.0)) {
            /* distance from the contour: the element of this piece and its neighbours */
            gp_elem2d el[3];
            int ne = 0;
            const int e = qe[1];
            for (int k = e - 1; k <= e + 1; k++)
                if (k >= 0 && k < n_elems)
                    gp_elem_make(pl, &contour[k], &el[ne++]);
            gp_devctx dc = {cl, el, ne};
            lsm_real d = gp_maxdev(&dc);
            if (d > dev)
                dev = d;
            /* distance from the polygon: the piece and its neighbours */
            ne = 0;
            if (j > 1)
                gp_seg_make(qx[0], qy[0], qx[1], qy[1], &el[ne++]);
            gp_seg_make(qx[1], qy[1], qx[2], qy[2], &el[ne++]);
            if (j < n)
                gp_seg_make(qx[2], qy[2], qx[3], qy[3], &el[ne++]);
            dc.n_el = ne;
            d = gp_maxdev(&dc);
            if (d > devc)
                devc = d;
        }
        st = fr.end;
        for (int k = 0; k < 3; k++) {
            qx[k] = qx[k + 1];
            qy[k] = qy[k + 1];
            qe[k] = qe[k + 1];
        }
    }
    lsm_real pe[LSM_MAX_AXES], ex, ey;
    lsm_geom_eval(&contour[n_elems - 1], contour[n_elems - 1].len, pe, NULL, NULL);
    gp_proj(pl, pe, &ex, &ey);
    rep->n_segments = n;
    rep->dev_mm = dev;
    rep->dev_chord_mm = devc;
    rep->kappa_max_per_mm = kmax;
    rep->sharpness_max_per_mm2 = cmax;
    rep->feed_acc_mm_s = kmax > LSM_R(0.0) ? lsm_sqrt(a_max / kmax) : LSM_REAL_MAX;
    rep->feed_jerk_mm_s = cmax > LSM_R(0.0) ? lsm_cbrt(j_max / cmax) : LSM_REAL_MAX;
    rep->end_gap_mm = lsm_sqrt((st.x_mm - ex) * (st.x_mm - ex) + (st.y_mm - ey) * (st.y_mm - ey));
    rep->iterations_max = itmax;
    return LSM_OK;
}

static lsm_status gp_prepare(const lsm_geom *contour, int n_elems, lsm_geom_plane plane, lsm_real a_max, lsm_real j_max,
                             const lsm_clothoid *out, const lsm_g2path_report *rep, gp_plane *pl, lsm_real *total,
                             lsm_real *normal)
{
    if (contour == NULL || out == NULL || rep == NULL)
        return LSM_E_NULL;
    int fr = lsm_check_finite(a_max);
    if (fr == 0)
        fr = lsm_check_finite(j_max);
    if (fr != 0)
        return (lsm_status)fr;
    if (!(a_max > LSM_R(0.0)) || !(j_max > LSM_R(0.0)))
        return LSM_E_LIMIT;
    if (n_elems < 1 || !gp_plane_make(plane, pl))
        return LSM_E_ARG;
    return gp_validate(contour, n_elems, pl, total, normal);
}

lsm_status lsm_g2path_build(const lsm_geom *contour, int n_elems, lsm_geom_plane plane, int n_segments,
                            lsm_real a_max_mm_s2, lsm_real j_max_mm_s3, lsm_clothoid *out, int cap,
                            lsm_g2path_report *rep)
{
    gp_plane pl;
    lsm_real total, normal;
    lsm_status st = gp_prepare(contour, n_elems, plane, a_max_mm_s2, j_max_mm_s3, out, rep, &pl, &total, &normal);
    if (st != LSM_OK)
        return st;
    if (n_segments < n_elems)
        return LSM_E_ARG;
    if (cap < n_segments)
        return LSM_E_FULL;
    rep->normal_mm = normal;
    rep->builds = 1;
    return gp_build(contour, n_elems, &pl, total, n_segments, a_max_mm_s2, j_max_mm_s3, out, rep);
}

lsm_status lsm_g2path_auto(const lsm_geom *contour, int n_elems, lsm_geom_plane plane, lsm_real tol_mm,
                           lsm_real a_max_mm_s2, lsm_real j_max_mm_s3, lsm_clothoid *out, int cap,
                           lsm_g2path_report *rep)
{
    gp_plane pl;
    lsm_real total, normal;
    lsm_status st = gp_prepare(contour, n_elems, plane, a_max_mm_s2, j_max_mm_s3, out, rep, &pl, &total, &normal);
    if (st != LSM_OK)
        return st;
    int fr = lsm_check_finite(tol_mm);
    if (fr != 0)
        return (lsm_status)fr;
    if (!(tol_mm > LSM_R(0.0)))
        return LSM_E_TOLERANCE;
    if (cap < n_elems)
        return LSM_E_FULL;
    int builds = 0;
    /* bracket: lo fails (or is below the minimum), hi meets the tolerance */
    int lo = n_elems - 1, hi = -1;
    int n = n_elems * 2 < cap ? n_elems * 2 : cap;
    lsm_g2path_report r;
    while (hi < 0) {
        st = gp_build(contour, n_elems, &pl, total, n, a_max_mm_s2, j_max_mm_s3, out, &r);
        builds++;
        if (st != LSM_OK)
            return st;
        if (r.dev_mm <= tol_mm) {
            hi = n;
            break;
        }
        lo = n;
        if (n >= cap)
            break;
        /* deviation ~ 1 / N^2: jump near the answer, at least doubling while far away */
        lsm_real est = (lsm_real)n * lsm_sqrt(r.dev_mm / tol_mm) * LSM_R(1.05);
        int nn = est > (lsm_real)cap ? cap : (int)lsm_ceil(est);
        if (nn <= n)
            nn = n + 1;
        n = nn;
    }
    if (hi < 0) {
        *rep = r;
        rep->normal_mm = normal;
        rep->builds = builds;
        return LSM_E_TOL_UNREACHED;
    }
    while (hi - lo > 1) {
        const int mid = lo + (hi - lo) / 2;
        st = gp_build(contour, n_elems, &pl, total, mid, a_max_mm_s2, j_max_mm_s3, out, &r);
        builds++;
        if (st != LSM_OK)
            return st;
        if (r.dev_mm <= tol_mm)
            hi = mid;
        else
            lo = mid;
    }
    st = gp_build(contour, n_elems, &pl, total, hi, a_max_mm_s2, j_max_mm_s3, out, rep);
    builds++;
    rep->normal_mm = normal;
    rep->builds = builds;
    return st;
}
