/*
 * test_corner.c: path elements (firmware/path/geom.h) and G2 corner smoothing (firmware/path/corner.h).
 *
 *   test_corner [seed] [count]      (default: seed 1, count 600 random corners)
 *
 * Random corners: line-line in 3-D, line-arc, arc-line and arc-arc in G17, G18 or G19, deflection
 * from 0 (tangent joints with a curvature jump only) to 179.5 deg, radii 0.5..500 mm, block lengths
 * 0.5..100 mm, tolerance 0.001..0.5 mm. For every corner, independently of the code under test
 * (positions by long-double Gauss-Legendre quadrature of the returned clothoids, exact distances to
 * the programmed line segments and arcs):
 *   - G2: position, unit tangent and curvature vector agree at the three joints (block 1 -> A,
 *     A -> B, B -> block 2, after trimming): curvature jump < 1e-9 of kappa_max in double (1e-4 float),
 *     positions within 1e-9 of the corner's size (+1e-10 mm) in double (1e-4 of the size plus 8 ulps of
 *     the largest coordinate, centre or radius involved, in float);
 *   - deviation (max of the distance from the corner point to the transition and of the largest
 *     distance of the transition from the programmed path) <= eps (1 + 1e-9) in double
 *     (1 + 1e-4, plus 4 ulps as above, in float), and the reported deviation matches it (5e-5 resp.
 *     1e-3 of eps, plus those ulps);
 *   - not wasteful: when the size is not limited by the trims, deviation >= LSM_CORNER_ACCEPT eps (0.9);
 *   - trims within their limits; kappa_max, c_max as the clothoids say.
 * Plus: the line-line closed form against its formula, the scaling with eps, every bad-input code.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "lsm_test_geom.h"
#include "lsm_test_rng.h"
#include <string.h>

#include "corner.h"

#define IS_F LSM_REAL_IS_FLOAT
#define PI 3.14159265358979323846

static unsigned long g_seed = 1;
static long g_count = 600;
static uint64_t g_rng;

/* the shared generator (lsm_test_rng.h) on this test's state */
static double urand(void)
{
    return test_urand(&g_rng);
}
static double uni(double a, double b)
{
    return test_uni(&g_rng, a, b);
}
static double logu(double a, double b)
{
    return exp(uni(log(a), log(b)));
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void cross(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}
static double norm(const double a[3])
{
    return sqrt(dot(a, a));
}
static double dist3(const double a[3], const double b[3])
{
    const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return norm(d);
}

/* ---- Gauss-Legendre reference for clothoid positions ---- */

#include "lsm_test_quad.h" /* gl_init, g_x, g_w: the reference quadrature */

typedef struct {
    double o[3], e1[3], e2[3], th0, k0, c, L;
} ref_clo;

static void ref_from_geom(const lsm_geom *g, ref_clo *r)
{
    assert_int_equal(g->kind, LSM_GEOM_CLOTHOID);
    for (int i = 0; i < 3; i++) {
        r->o[i] = g->u.clo.origin_mm[i];
        r->e1[i] = g->u.clo.e1[i];
        r->e2[i] = g->u.clo.e2[i];
    }
    r->th0 = g->u.clo.theta0_rad;
    r->k0 = g->u.clo.kappa0_per_mm;
    r->c = g->u.clo.c_per_mm2;
    r->L = g->len;
}

/* in-plane displacement over [a, b], split in panels turning <= 0.1 rad */
static void ref_disp(const ref_clo *r, long double a, long double b, long double *X, long double *Y)
{
    const double kmax = fabs(r->k0) + fabs(r->c) * (double)(b > a ? b : a);
    long m = (long)ceil((double)(b - a) * kmax / 0.1);
    if (m < 1)
        m = 1;
    const long double h = (b - a) / m;
    long double sx = 0, sy = 0;
    for (long j = 0; j < m; j++)
        for (int i = 0; i < GL_N; i++) {
            const long double t = a + h * j + h * (g_x[i] + 1) / 2;
            const long double th = r->th0 + t * (r->k0 + 0.5L * r->c * t);
            sx += g_w[i] * cosl(th);
            sy += g_w[i] * sinl(th);
        }
    *X = sx * h / 2;
    *Y = sy * h / 2;
}

static void ref_point(const ref_clo *r, long double X, long double Y, double p[3])
{
    for (int i = 0; i < 3; i++)
        p[i] = (double)(r->o[i] + r->e1[i] * X + r->e2[i] * Y);
}

/* ---- exact distance to a programmed block ---- */

static double dist_block(const lsm_geom *g, const double p[3])
{
    if (g->kind == LSM_GEOM_LINE) {
        double a[3], d[3];
        for (int i = 0; i < 3; i++) {
            a[i] = g->u.line.p0[i];
            d[i] = g->u.line.dir[i];
        }
        const double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
        double t = dot(w, d);
        t = t < 0 ? 0 : (t > g->len ? g->len : t);
        const double q[3] = {a[0] + d[0] * t, a[1] + d[1] * t, a[2] + d[2] * t};
        return dist3(p, q);
    }
    const lsm_geom_arc *a = &g->u.arc;
    double e1[3], e2[3], n[3], c[3];
    test_arc_centre(g, c);
    for (int i = 0; i < 3; i++) {
        e1[i] = a->e1[i];
        e2[i] = a->e2[i];
    }
    cross(e1, e2, n);
    const double w[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    const double u = dot(w, e1), v = dot(w, e2), h = dot(w, n);
    double rel = a->sweep_rad > 0 ? atan2(v, u) - a->phi0_rad : a->phi0_rad - atan2(v, u);
    rel -= 2 * PI * floor(rel / (2 * PI));
    if (fabs(a->sweep_rad) >= 2 * PI || rel <= fabs(a->sweep_rad))
        return hypot(hypot(u, v) - a->radius_mm, h);
    lsm_real q0[LSM_MAX_AXES], q1[LSM_MAX_AXES];
    lsm_geom_eval(g, 0, q0, NULL, NULL);
    lsm_geom_eval(g, g->len, q1, NULL, NULL);
    const double d0[3] = {q0[0], q0[1], q0[2]}, d1[3] = {q1[0], q1[1], q1[2]};
    const double x0 = dist3(p, d0), x1 = dist3(p, d1);
    return x0 < x1 ? x0 : x1;
}

/* ---- corner construction ---- */

typedef struct {
    lsm_geom b1, b2;
    double eps;
    int kind;
    double delta_deg;
} corner_case;

static const lsm_geom_plane k_planes[3] = {LSM_GEOM_PLANE_XY, LSM_GEOM_PLANE_ZX, LSM_GEOM_PLANE_YZ};

static void plane_basis(lsm_geom_plane pl, double e1[3], double e2[3])
{
    memset(e1, 0, 3 * sizeof(double));
    memset(e2, 0, 3 * sizeof(double));
    if (pl == LSM_GEOM_PLANE_XY) {
        e1[0] = 1;
        e2[1] = 1;
    } else if (pl == LSM_GEOM_PLANE_ZX) {
        e1[2] = 1;
        e2[0] = 1;
    } else {
        e1[1] = 1;
        e2[2] = 1;
    }
}

/* Arc through V with unit in-plane tangent t there (ending at V if at_end), radius r, turning turn. */
static lsm_status make_arc(lsm_geom *g, lsm_geom_plane pl, const double V[3], const double t[3], double r, double turn,
                           int at_end)
{
    double e1[3], e2[3], n[3], nt[3];
    plane_basis(pl, e1, e2);
    cross(e1, e2, n);
    cross(n, t, nt); /* left of the tangent */
    const double s = turn > 0 ? 1 : -1;
    double c[3], o[3];
    for (int i = 0; i < 3; i++)
        c[i] = V[i] + s * r * nt[i];
    const double rv[3] = {V[0] - c[0], V[1] - c[1], V[2] - c[2]};
    const double a0 = atan2(dot(rv, e2), dot(rv, e1));
    const double a1 = at_end ? a0 - turn : a0 + turn;
    for (int i = 0; i < 3; i++)
        o[i] = c[i] + r * (cos(a1) * e1[i] + sin(a1) * e2[i]);
    lsm_real lc[3], lv[3], lo[3];
    for (int i = 0; i < 3; i++) {
        lc[i] = (lsm_real)c[i];
        lv[i] = (lsm_real)V[i];
        lo[i] = (lsm_real)o[i];
    }
    return at_end ? lsm_geom_arc_init(g, lo, lv, lc, pl, turn > 0 ? 1 : -1, 0)
                  : lsm_geom_arc_init(g, lv, lo, lc, pl, turn > 0 ? 1 : -1, 0);
}

static lsm_status make_line(lsm_geom *g, const double a[3], const double b[3])
{
    lsm_real p[LSM_MAX_AXES] = {0}, q[LSM_MAX_AXES] = {0};
    for (int i = 0; i < 3; i++) {
        p[i] = (lsm_real)a[i];
        q[i] = (lsm_real)b[i];
    }
    return lsm_geom_line_init(g, p, q);
}

static void random_corner(corner_case *k)
{
    const int kind = (int)(urand() * 4) % 4; /* 0 line-line, 1 line-arc, 2 arc-line, 3 arc-arc */
    const lsm_geom_plane pl = k_planes[(int)(urand() * 3) % 3];
    double V[3] = {uni(-100, 100), uni(-100, 100), uni(-100, 100)};
    double e1[3], e2[3], n[3];
    plane_basis(pl, e1, e2);
    cross(e1, e2, n);
    /* deflection: tangent joints (arcs only), small, moderate, near reversal */
    double delta;
    const double u = urand();
    if (kind != 0 && u < 0.15)
        delta = 0;
    else if (u < 0.3)
        delta = logu(1e-3, 1.0) * PI / 180;
    else if (u < 0.85)
        delta = uni(1, 170) * PI / 180;
    else
        delta = uni(170, 179.5) * PI / 180;
    if (urand() < 0.5)
        delta = -delta;
    const double a1 = uni(-PI, PI);
    double t1[3], t2[3];
    if (kind == 0) {
        /* any 3-D directions */
        double w[3] = {uni(-1, 1), uni(-1, 1), uni(-1, 1)};
        double r0[3] = {uni(-1, 1), uni(-1, 1), uni(-1, 1)};
        const double nr = norm(r0);
        for (int i = 0; i < 3; i++)
            t1[i] = r0[i] / nr;
        const double p = dot(w, t1);
        for (int i = 0; i < 3; i++)
            w[i] -= p * t1[i];
        const double nw = norm(w);
        for (int i = 0; i < 3; i++)
            t2[i] = cos(delta) * t1[i] + sin(delta) * w[i] / nw;
    } else {
        for (int i = 0; i < 3; i++) {
            t1[i] = cos(a1) * e1[i] + sin(a1) * e2[i];
            t2[i] = cos(a1 + delta) * e1[i] + sin(a1 + delta) * e2[i];
        }
    }
    const double l1 = logu(0.5, 100), l2 = logu(0.5, 100);
    const double r1 = logu(0.5, 500), r2 = logu(0.5, 500);
    double tr1 = (urand() < 0.5 ? -1 : 1) * fmin(l1 / r1, 3.0), tr2 = (urand() < 0.5 ? -1 : 1) * fmin(l2 / r2, 3.0);
    if (kind == 3 && delta == 0 && fabs(r1 - r2) < 1e-6 * r1 && tr1 * tr2 > 0)
        tr2 = -tr2; /* same circle: nothing to smooth; make it an S */
    lsm_status s1, s2;
    if (kind == 2 || kind == 3)
        s1 = make_arc(&k->b1, pl, V, t1, r1, tr1, 1);
    else {
        const double a[3] = {V[0] - l1 * t1[0], V[1] - l1 * t1[1], V[2] - l1 * t1[2]};
        s1 = make_line(&k->b1, a, V);
    }
    if (kind == 1 || kind == 3)
        s2 = make_arc(&k->b2, pl, V, t2, r2, tr2, 0);
    else {
        const double b[3] = {V[0] + l2 * t2[0], V[1] + l2 * t2[1], V[2] + l2 * t2[2]};
        s2 = make_line(&k->b2, V, b);
    }
    assert_int_equal(s1, LSM_OK);
    assert_int_equal(s2, LSM_OK);
    k->kind = kind;
    k->eps = logu(1e-3, 0.5);
    k->delta_deg = delta * 180 / PI;
}

/* ---- checking one smoothed corner ---- */

typedef struct {
    double dev, vd, pd;
    double joint_gap, joint_tan, joint_curv;
} corner_check;

static void joint(const lsm_geom *a, const lsm_geom *b, double kscale, corner_check *cc)
{
    lsm_real pa[LSM_MAX_AXES], pb[LSM_MAX_AXES], ta[3], tb[3], ca[3], cb[3];
    lsm_geom_eval(a, a->len, pa, ta, ca);
    lsm_geom_eval(b, 0, pb, tb, cb);
    double g = 0, t = 0, c = 0;
    for (int i = 0; i < 3; i++) {
        g += (pa[i] - pb[i]) * (pa[i] - pb[i]);
        t += (ta[i] - tb[i]) * (ta[i] - tb[i]);
        c += (ca[i] - cb[i]) * (ca[i] - cb[i]);
    }
    g = sqrt(g);
    t = sqrt(t);
    c = sqrt(c) / kscale;
    if (g > cc->joint_gap)
        cc->joint_gap = g;
    if (t > cc->joint_tan)
        cc->joint_tan = t;
    if (c > cc->joint_curv)
        cc->joint_curv = c;
}

#define NS 400

typedef struct {
    const ref_clo *r[2];
    long double X[2][NS + 1], Y[2][NS + 1];
    const lsm_geom *b1, *b2;
    double V[3];
} dev_ctx;

static void dev_point(const dev_ctx *d, int w, double t, double p[3])
{
    const ref_clo *r = d->r[w];
    const double h = r->L / NS;
    int j = (int)(t / h);
    if (j > NS)
        j = NS;
    if (j < 0)
        j = 0;
    long double X = d->X[w][j], Y = d->Y[w][j];
    if (t > j * h) {
        long double dx, dy;
        ref_disp(r, (long double)j * h, t, &dx, &dy);
        X += dx;
        Y += dy;
    }
    ref_point(r, X, Y, p);
}

/* t: arc length along the whole transition (A then B) */
static double dev_f(const dev_ctx *d, int which, double t)
{
    double p[3];
    const double la = d->r[0]->L;
    if (t <= la)
        dev_point(d, 0, t, p);
    else
        dev_point(d, 1, t - la, p);
    if (which == 0)
        return -dist3(p, d->V);
    const double a = dist_block(d->b1, p), b = dist_block(d->b2, p);
    return a < b ? a : b;
}

static void check_deviation(const lsm_geom *b1, const lsm_geom *b2, const lsm_corner_result *r, corner_check *cc)
{
    ref_clo ra, rb;
    ref_from_geom(&r->trans[0], &ra);
    ref_from_geom(&r->trans[1], &rb);
    static dev_ctx d;
    d.r[0] = &ra;
    d.r[1] = &rb;
    d.b1 = b1;
    d.b2 = b2;
    lsm_real v[LSM_MAX_AXES];
    lsm_geom_eval(b1, b1->len, v, NULL, NULL);
    for (int i = 0; i < 3; i++)
        d.V[i] = v[i];
    for (int w = 0; w < 2; w++) {
        const ref_clo *rc = d.r[w];
        const long double h = (long double)rc->L / NS;
        d.X[w][0] = d.Y[w][0] = 0;
        for (int j = 1; j <= NS; j++) {
            long double dx, dy;
            ref_disp(rc, h * (j - 1), h * j, &dx, &dy);
            d.X[w][j] = d.X[w][j - 1] + dx;
            d.Y[w][j] = d.Y[w][j - 1] + dy;
        }
    }
    /* A's end (by quadrature) must be B's origin */
    double pa[3];
    ref_point(&ra, d.X[0][NS], d.Y[0][NS], pa);
    const double gab = dist3(pa, rb.o);
    if (gab > cc->joint_gap)
        cc->joint_gap = gab;
    double res[2];
    const double T = ra.L + rb.L;
    for (int which = 0; which < 2; which++) {
        double best = -1e300, bt = 0;
        for (int j = 0; j <= 2 * NS; j++) {
            const double t = T * j / (2 * NS);
            const double f = dev_f(&d, which, t);
            if (f > best) {
                best = f;
                bt = t;
            }
        }
        const double h = T / (2 * NS);
        double a = bt - h < 0 ? 0 : bt - h, b = bt + h > T ? T : bt + h;
        const double g = 0.6180339887498949;
        for (int k = 0; k < 50; k++) {
            const double x1 = b - g * (b - a), x2 = a + g * (b - a);
            const double f1 = dev_f(&d, which, x1), f2 = dev_f(&d, which, x2);
            if (f1 > best)
                best = f1;
            if (f2 > best)
                best = f2;
            if (f1 >= f2)
                b = x2;
            else
                a = x1;
        }
        res[which] = best;
    }
    cc->vd = -res[0];
    cc->pd = res[1];
    cc->dev = cc->vd > cc->pd ? cc->vd : cc->pd;
}

static void check_corner(const corner_case *k, const lsm_corner_result *r, long n, corner_check *cc)
{
    memset(cc, 0, sizeof *cc);
    /* trims applied to copies */
    lsm_geom t1 = k->b1, t2 = k->b2;
    assert_int_equal(lsm_corner_apply(&t1, &t2, r), LSM_OK);
    const double kscale = r->kappa_max_per_mm > 0 ? r->kappa_max_per_mm : 1.0;
    joint(&t1, &r->trans[0], kscale, cc);
    joint(&r->trans[0], &r->trans[1], kscale, cc);
    joint(&r->trans[1], &t2, kscale, cc);
    check_deviation(&k->b1, &k->b2, r, cc);
    const double size = r->trim1_mm + r->trim2_mm + r->trans[0].len;
    /* float: positions carry the rounding of the numbers they are computed from (coordinates, arc
     * centres and radii up to ~1000 mm here); allow a few ulps of the largest */
    double mag = 0;
    const lsm_geom *bb[2] = {&k->b1, &k->b2};
    for (int i = 0; i < 2; i++) {
        const lsm_geom *g = bb[i];
        double gc[3] = {0, 0, 0};
        if (g->kind == LSM_GEOM_ARC)
            test_arc_centre(g, gc);
        const double m = g->kind == LSM_GEOM_ARC
                             ? fabs(gc[0]) + fabs(gc[1]) + fabs(gc[2]) + g->u.arc.radius_mm
                             : fabs(g->u.line.p0[0]) + fabs(g->u.line.p0[1]) + fabs(g->u.line.p0[2]) + g->len;
        if (m > mag)
            mag = m;
    }
    const double ulp = IS_F ? mag * 1.1920929e-7 : 0.0;
    const double gtol = IS_F ? 1e-4 * size + 8 * ulp : 1e-9 * size + 1e-10;
    const double ctol = IS_F ? 1e-4 : 1e-9;
    const double dtol = IS_F ? k->eps * 1e-4 + 4 * ulp : k->eps * 1e-9;
    /* the corner aims at eps (1 - 1e-4) and reports its deviation to about 1e-5 of eps */
    bool ok = cc->joint_gap <= gtol && cc->joint_tan <= (IS_F ? 1e-4 : 1e-9) && cc->joint_curv <= ctol &&
              cc->dev <= k->eps + dtol;
    /* the reported deviation is the real one */
    ok = ok && fabs(r->deviation_mm - cc->dev) <= (IS_F ? 1e-3 : 5e-5) * k->eps + 4 * ulp;
    /* the tolerance is used unless the trims limit the size */
    ok = ok && (r->limited || cc->dev >= LSM_CORNER_ACCEPT * k->eps * (1 - 2e-4) - 4 * ulp);
    /* trims within their limits */
    const double f = LSM_CORNER_DEFAULT_TRIM_FRACTION * (1 + 1e-6);
    ok = ok && r->trim1_mm > 0 && r->trim2_mm > 0 && r->trim1_mm <= f * k->b1.len && r->trim2_mm <= f * k->b2.len;
    /* kappa_max and c_max as the clothoids say */
    const lsm_geom_clothoid *A = &r->trans[0].u.clo, *B = &r->trans[1].u.clo;
    const double L = r->trans[0].len;
    const double km = fmax(fmax(fabs(A->kappa0_per_mm), fabs(A->kappa0_per_mm + A->c_per_mm2 * L)),
                           fabs(B->kappa0_per_mm + B->c_per_mm2 * L));
    ok = ok && fabs(km - r->kappa_max_per_mm) <= 1e-6 * km &&
         fabs(fmax(fabs(A->c_per_mm2), fabs(B->c_per_mm2)) - r->sharpness_max_per_mm2) <=
             1e-6 * r->sharpness_max_per_mm2;
    if (!ok) {
        print_error("corner %ld (seed %lu) kind %d delta %.6g deg eps %.6g: gap %.3g (tol %.3g) tan %.3g curv %.3g "
                    "dev %.9g (vertex %.9g path %.9g) reported %.9g limited %d trims %.6g/%.6g of %.6g/%.6g "
                    "kmax %.6g/%.6g\n",
                    n, g_seed, k->kind, k->delta_deg, k->eps, cc->joint_gap, gtol, cc->joint_tan, cc->joint_curv,
                    cc->dev, cc->vd, cc->pd, (double)r->deviation_mm, r->limited, (double)r->trim1_mm,
                    (double)r->trim2_mm, (double)k->b1.len, (double)k->b2.len, km, (double)r->kappa_max_per_mm);
        const lsm_geom *blk[2] = {&k->b1, &k->b2};
        for (int i = 0; i < 2; i++) {
            const lsm_geom *g = blk[i];
            double gc[3] = {0, 0, 0};
            if (g->kind == LSM_GEOM_ARC)
                test_arc_centre(g, gc);
            if (g->kind == LSM_GEOM_ARC)
                print_error("  b%d arc c %.17g %.17g %.17g e1 %.17g %.17g %.17g e2 %.17g %.17g %.17g r %.17g phi0 "
                            "%.17g "
                            "sweep %.17g\n",
                            i + 1, gc[0], gc[1], gc[2], (double)g->u.arc.e1[0], (double)g->u.arc.e1[1],
                            (double)g->u.arc.e1[2], (double)g->u.arc.e2[0], (double)g->u.arc.e2[1],
                            (double)g->u.arc.e2[2], (double)g->u.arc.radius_mm, (double)g->u.arc.phi0_rad,
                            (double)g->u.arc.sweep_rad);
            else
                print_error("  b%d line p0 %.17g %.17g %.17g dir %.17g %.17g %.17g len %.17g\n", i + 1,
                            (double)g->u.line.p0[0], (double)g->u.line.p0[1], (double)g->u.line.p0[2],
                            (double)g->u.line.dir[0], (double)g->u.line.dir[1], (double)g->u.line.dir[2],
                            (double)g->len);
        }
        for (int i = 0; i < 2; i++) {
            const lsm_geom_clothoid *q = &r->trans[i].u.clo;
            print_error("  T%d o %.17g %.17g %.17g e1 %.17g %.17g %.17g e2 %.17g %.17g %.17g th0 %.17g k0 %.17g c "
                        "%.17g "
                        "L %.17g\n",
                        i, (double)q->origin_mm[0], (double)q->origin_mm[1], (double)q->origin_mm[2], (double)q->e1[0],
                        (double)q->e1[1], (double)q->e1[2], (double)q->e2[0], (double)q->e2[1], (double)q->e2[2],
                        (double)q->theta0_rad, (double)q->kappa0_per_mm, (double)q->c_per_mm2, (double)r->trans[i].len);
        }
        fail();
    }
}

static void test_random_corners(void **state)
{
    (void)state;
    g_rng = 0xA4093822299F31D0ull ^ (uint64_t)g_seed;
    long ok = 0, limited = 0, its = 0, scales = 0, no_solution = 0, per_kind[4] = {0};
    double worst_curv = 0, worst_dev = 0;
    for (long n = 0; n < g_count; n++) {
        corner_case k;
        random_corner(&k);
        const lsm_corner_params p = {(lsm_real)k.eps, 0, 0};
        lsm_corner_result r;
        const lsm_status st = lsm_corner_smooth(&k.b1, &k.b2, &p, &r);
        /* float: a short line at coordinates ~100 mm has a direction good to ~ulp / length ~ 1e-5 rad,
         * so a deflection that small may come out as none */
        if (IS_F && st == LSM_E_COLLINEAR && fabs(k.delta_deg) < 0.05)
            continue;
        if (st == LSM_E_CORNER_NO_SOLUTION) {
            no_solution++;
            print_message("corner %ld: no solution (kind %d, delta %.4g deg, eps %.4g)\n", n, k.kind, k.delta_deg,
                          k.eps);
            continue;
        }
        if (st != LSM_OK) {
            print_error("corner %ld (seed %lu) kind %d delta %.6g: status %d (%s)\n", n, g_seed, k.kind, k.delta_deg,
                        (int)st, lsm_status_str(st));
            fail();
        }
        corner_check cc;
        check_corner(&k, &r, n, &cc);
        ok++;
        per_kind[k.kind]++;
        limited += r.limited;
        its += r.iterations;
        scales += r.scales;
        if (cc.joint_curv > worst_curv)
            worst_curv = cc.joint_curv;
        if (cc.dev / k.eps > worst_dev)
            worst_dev = cc.dev / k.eps;
    }
    print_message("corners: %ld ok (line-line %ld, line-arc %ld, arc-line %ld, arc-arc %ld), %ld trim-limited, "
                  "%ld without solution; worst deviation %.9f eps, worst curvature jump %.2g of kappa_max; "
                  "Newton iterations %.2f and scales %.2f per corner\n",
                  ok, per_kind[0], per_kind[1], per_kind[2], per_kind[3], limited, no_solution, worst_dev, worst_curv,
                  (double)its / (double)ok, (double)scales / (double)ok);
    /* no-solution outcomes are allowed only as rare exceptions (documented: stop at the corner) */
    assert_true(no_solution * 100 <= g_count);
}

/* ---- closed form and scaling ---- */

static void unit_xy(double delta, double *X, double *Y)
{
    ref_clo r = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0, 0, delta, 1};
    long double x, y;
    ref_disp(&r, 0, 1, &x, &y);
    *X = (double)x;
    *Y = (double)y;
}

static lsm_status smooth_lines(const double a[3], const double v[3], const double b[3], double eps,
                               lsm_corner_result *r)
{
    lsm_geom g1, g2;
    assert_int_equal(make_line(&g1, a, v), LSM_OK);
    assert_int_equal(make_line(&g2, v, b), LSM_OK);
    const lsm_corner_params p = {(lsm_real)eps, 0, 0};
    return lsm_corner_smooth(&g1, &g2, &p, r);
}

static void test_line_line_closed_form(void **state)
{
    (void)state;
    for (double deg = 10; deg < 180; deg += 20) {
        const double d = deg * PI / 180, eps = 0.02;
        const double a[3] = {-50, 0, 0}, v[3] = {0, 0, 0}, b[3] = {50 * cos(d), 50 * sin(d), 0};
        lsm_corner_result r;
        assert_int_equal(smooth_lines(a, v, b, eps, &r), LSM_OK);
        double X, Y;
        unit_xy(d, &X, &Y);
        /* vertex distance L Y / cos(d/2) = eps (the firmware aims 1e-4 inside) */
        const double aim = eps * (1 - 1e-4);
        const double L = aim * cos(d / 2) / Y;
        const double rt = IS_F ? 2e-5 : 1e-12;
        assert_true(r.closed_form && !r.limited);
        assert_true(fabs(r.trans[0].len - L) <= rt * L && fabs(r.trans[1].len - L) <= rt * L);
        assert_true(fabs(r.trim1_mm - L * (X + Y * tan(d / 2))) <= rt * r.trim1_mm);
        assert_true(fabs(r.trim2_mm - r.trim1_mm) <= rt * r.trim1_mm);
        assert_true(fabs(r.kappa_max_per_mm - d / L) <= rt * d / L);
        assert_true(fabs(r.sharpness_max_per_mm2 - d / (L * L)) <= 2 * rt * d / (L * L));
        assert_true(fabs(r.deviation_mm - aim) <= rt * eps && fabs(r.path_dev_mm - L * Y) <= rt * eps);
    }
}

static void test_scaling(void **state)
{
    (void)state;
    /* line-line: everything scales with eps: trims and L as eps, kappa_max as 1/eps, c_max as 1/eps^2 */
    const double a[3] = {-40, 3, 1}, v[3] = {0, 0, 0}, b[3] = {10, 30, -5};
    lsm_corner_result r1, r2;
    assert_int_equal(smooth_lines(a, v, b, 0.02, &r1), LSM_OK);
    assert_int_equal(smooth_lines(a, v, b, 0.01, &r2), LSM_OK);
    const double rt = IS_F ? 1e-5 : 1e-12;
    assert_true(fabs(r1.trim1_mm / r2.trim1_mm - 2) <= rt);
    assert_true(fabs(r2.kappa_max_per_mm / r1.kappa_max_per_mm - 2) <= rt);
    assert_true(fabs(r2.sharpness_max_per_mm2 / r1.sharpness_max_per_mm2 - 4) <= 2 * rt);
    /* a tangent line-arc joint (curvature jump only): the deviation grows as L^2, so halving eps
     * shrinks L by sqrt(2) and raises c_max = dkappa / L by sqrt(2); kappa_max stays 1 / R (the pair
     * without overshoot: kappa 0 -> -0.077/R -> 1/R, see corner.c) */
    lsm_geom g1, g2;
    const double p0[3] = {-30, 0, 0}, pv[3] = {0, 0, 0}, t[3] = {1, 0, 0};
    assert_int_equal(make_line(&g1, p0, pv), LSM_OK);
    assert_int_equal(make_arc(&g2, LSM_GEOM_PLANE_XY, pv, t, 20, 1.2, 0), LSM_OK);
    double prevL = 0, prevc = 0;
    for (double eps = 0.004; eps > 0.0004; eps /= 2) {
        const lsm_corner_params p = {(lsm_real)eps, 0, 0};
        lsm_corner_result r;
        assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_OK);
        const double L = r.trans[0].len;
        if (prevL > 0) {
            /* the search stops within [LSM_CORNER_ACCEPT, 1] eps = [0.9, 1] eps and the deviation goes as
             * L^2, so each ratio is sqrt(2) within a factor sqrt(1/0.9) either way */
            const double f = sqrt(1.0 / LSM_CORNER_ACCEPT) * 1.001;
            assert_true(prevL / L < sqrt(2.0) * f && prevL / L > sqrt(2.0) / f);
            assert_true(r.sharpness_max_per_mm2 / prevc < sqrt(2.0) * f &&
                        r.sharpness_max_per_mm2 / prevc > sqrt(2.0) / f);
        }
        if (fabs(r.kappa_max_per_mm * 20 - 1.0) >= (IS_F ? 1e-5 : 1e-12)) {
            print_error("eps %g: kappa_max * R = %.6g, L %.6g, trims %.6g %.6g dev %.6g limited %d\n", eps,
                        (double)(r.kappa_max_per_mm * 20), L, (double)r.trim1_mm, (double)r.trim2_mm,
                        (double)r.deviation_mm, r.limited);
            fail();
        }
        prevL = L;
        prevc = r.sharpness_max_per_mm2;
    }
}

/* ---- bad input ---- */

static void test_bad_input(void **state)
{
    (void)state;
    lsm_geom g1, g2, g3;
    const double a[3] = {0, 0, 0}, v[3] = {10, 0, 0}, b[3] = {10, 10, 0};
    assert_int_equal(make_line(&g1, a, v), LSM_OK);
    assert_int_equal(make_line(&g2, v, b), LSM_OK);
    lsm_corner_params p = {0.01, 0, 0};
    lsm_corner_result r;
    assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_OK);
    /* tolerance */
    p.tolerance_mm = 0;
    assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_E_TOLERANCE);
    p.tolerance_mm = -1;
    assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_E_TOLERANCE);
    p.tolerance_mm = (lsm_real)NAN;
    assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_E_NAN);
    p.tolerance_mm = (lsm_real)INFINITY;
    assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_E_INF);
    p.tolerance_mm = 0.01;
    p.max_trim1_mm = (lsm_real)NAN;
    assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_E_NAN);
    p.max_trim1_mm = 0;
    /* collinear and reversal */
    const double c[3] = {20, 0, 0}, back[3] = {0, 0, 0};
    assert_int_equal(make_line(&g3, v, c), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&g1, &g3, &p, &r), LSM_E_COLLINEAR);
    assert_int_equal(make_line(&g3, v, back), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&g1, &g3, &p, &r), LSM_E_REVERSAL);
    /* the same circle continued: collinear; a tangent arc reversing: reversal */
    const double t[3] = {1, 0, 0}, tb[3] = {-1, 0, 0}, o[3] = {10, 0, 0};
    lsm_geom arc1, arc2;
    assert_int_equal(make_arc(&arc1, LSM_GEOM_PLANE_XY, o, t, 5, 0.5, 1), LSM_OK);
    assert_int_equal(make_arc(&arc2, LSM_GEOM_PLANE_XY, o, t, 5, 0.5, 0), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&arc1, &arc2, &p, &r), LSM_E_COLLINEAR);
    assert_int_equal(make_arc(&arc2, LSM_GEOM_PLANE_XY, o, tb, 5, 0.5, 0), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&arc1, &arc2, &p, &r), LSM_E_REVERSAL);
    /* zero length (a block built by hand) and NaN inside a block */
    lsm_geom z = g2;
    z.len = 0;
    assert_int_equal(lsm_corner_smooth(&g1, &z, &p, &r), LSM_E_ZERO_LENGTH);
    z = g2;
    z.u.line.p0[1] = (lsm_real)NAN;
    assert_int_equal(lsm_corner_smooth(&g1, &z, &p, &r), LSM_E_NAN);
    lsm_real zp[LSM_MAX_AXES] = {1, 2, 3, 0, 0, 0};
    assert_int_equal(lsm_geom_line_init(&z, zp, zp), LSM_E_ZERO_LENGTH);
    /* gap, rotary axes, non-planar, helical, kind */
    const double v2[3] = {10, 0.5, 0}, b2[3] = {10, 10, 0};
    assert_int_equal(make_line(&g3, v2, b2), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&g1, &g3, &p, &r), LSM_E_GAP);
    lsm_real ra[LSM_MAX_AXES] = {10, 0, 0, 0, 0, 0}, rb[LSM_MAX_AXES] = {10, 10, 0, 0.5, 0, 0};
    assert_int_equal(lsm_geom_line_init(&g3, ra, rb), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&g1, &g3, &p, &r), LSM_E_ROTARY);
    const double up[3] = {0, 0, -10};
    assert_int_equal(make_line(&g3, up, v), LSM_OK); /* comes down in Z into a G17 arc */
    assert_int_equal(make_arc(&arc2, LSM_GEOM_PLANE_XY, o, t, 5, 0.5, 0), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&g3, &arc2, &p, &r), LSM_E_NONPLANAR);
    const lsm_real hs[3] = {10, 0, 0}, he[3] = {15, 5, 2}, hc[3] = {10, 5, 0};
    assert_int_equal(lsm_geom_arc_init(&arc2, hs, he, hc, LSM_GEOM_PLANE_XY, 1, 0), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&g1, &arc2, &p, &r), LSM_E_NONPLANAR);
    lsm_geom cl;
    const lsm_real co[3] = {10, 0, 0}, e1[3] = {0, 1, 0}, e2[3] = {-1, 0, 0};
    assert_int_equal(lsm_geom_clothoid_init(&cl, co, e1, e2, 0, 0, 0.01, 5), LSM_OK);
    assert_int_equal(lsm_corner_smooth(&g1, &cl, &p, &r), LSM_E_ARG);
    assert_int_equal(lsm_corner_smooth(NULL, &g2, &p, &r), LSM_E_NULL);
    assert_int_equal(lsm_corner_smooth(&g1, &g2, NULL, &r), LSM_E_NULL);
    /* all distinct */
    const lsm_status codes[] = {LSM_E_TOLERANCE,         LSM_E_NAN, LSM_E_INF,    LSM_E_COLLINEAR, LSM_E_REVERSAL,
                                LSM_E_ZERO_LENGTH,       LSM_E_GAP, LSM_E_ROTARY, LSM_E_NONPLANAR, LSM_E_ARG,
                                LSM_E_CORNER_NO_SOLUTION};
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++)
        for (size_t j = i + 1; j < sizeof codes / sizeof codes[0]; j++)
            assert_true(codes[i] != codes[j]);
}

/* ---- the trims and explicit limits ---- */

static void test_apply_and_limits(void **state)
{
    (void)state;
    lsm_geom g1, g2;
    const double a[3] = {0, 0, 0}, v[3] = {2, 0, 0}, b[3] = {2, 30, 0};
    assert_int_equal(make_line(&g1, a, v), LSM_OK);
    assert_int_equal(make_line(&g2, v, b), LSM_OK);
    /* a large tolerance on a short block: the trims limit the size */
    lsm_corner_params p = {1.0, 0, 0};
    lsm_corner_result r;
    assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_OK);
    assert_true(r.limited && r.deviation_mm < 1.0);
    assert_true(fabs(r.trim1_mm - LSM_CORNER_DEFAULT_TRIM_FRACTION * 2.0) < 1e-5);
    /* an explicit smaller limit */
    p.max_trim1_mm = 0.3;
    p.max_trim2_mm = 0.3;
    assert_int_equal(lsm_corner_smooth(&g1, &g2, &p, &r), LSM_OK);
    assert_true(r.trim1_mm <= 0.3 + 1e-6 && r.trim2_mm <= 0.3 + 1e-6);
    assert_int_equal(lsm_corner_apply(&g1, &g2, &r), LSM_OK);
    lsm_real e[LSM_MAX_AXES], s[LSM_MAX_AXES];
    lsm_geom_eval(&g1, g1.len, e, NULL, NULL);
    lsm_geom_eval(&g2, 0, s, NULL, NULL);
    for (int i = 0; i < 3; i++)
        assert_true(fabs(e[i] - r.p1_mm[i]) < 1e-5 && fabs(s[i] - r.p2_mm[i]) < 1e-5);
    assert_true(fabs(g1.len - (2 - r.trim1_mm)) < 1e-5);
}

/* ---- geometry ---- */

static void fd_check(const lsm_geom *g, double s)
{
    const double h = IS_F ? 1e-2 : 1e-5;
    lsm_real p0[LSM_MAX_AXES], p1[LSM_MAX_AXES], t[3], t0[3], t1[3], c[3];
    lsm_geom_eval(g, (lsm_real)(s - h), p0, t0, NULL);
    lsm_geom_eval(g, (lsm_real)(s + h), p1, t1, NULL);
    lsm_geom_eval(g, (lsm_real)s, NULL, t, c);
    const double tol = IS_F ? 2e-3 : 1e-8;
    double nt = 0;
    for (int i = 0; i < 3; i++) {
        assert_true(fabs((p1[i] - p0[i]) / (2 * h) - t[i]) < tol);
        assert_true(fabs((t1[i] - t0[i]) / (2 * h) - c[i]) < tol * (1 + fabs(c[i])) * 10);
        nt += t[i] * t[i];
    }
    assert_true(fabs(nt - 1) < (IS_F ? 1e-5 : 1e-12));
}

static void test_geom(void **state)
{
    (void)state;
    if (IS_F)
        assert_true(sizeof(lsm_geom) <= 64);
    print_message("sizeof(lsm_geom) = %zu bytes\n", sizeof(lsm_geom));
    /* G18: e1 = Z, e2 = X; G3 is counter-clockwise about +Y: from +Z towards +X */
    lsm_geom g;
    const lsm_real st[3] = {0, 0, 5}, en[3] = {5, 0, 0}, ce[3] = {0, 0, 0};
    assert_int_equal(lsm_geom_arc_init(&g, st, en, ce, LSM_GEOM_PLANE_ZX, 1, 0), LSM_OK);
    assert_true(fabs(g.len - 5 * PI / 2) < 1e-5);
    lsm_real p[LSM_MAX_AXES] = {0, 0, 0, 7, 8, 9}, t[3];
    lsm_geom_eval(&g, g.len, p, t, NULL);
    assert_true(fabs(p[0] - 5) < 1e-5 && fabs(p[1]) < 1e-5 && fabs(p[2]) < 1e-5);
    assert_true(p[3] == 7 && p[4] == 8 && p[5] == 9); /* rotary axes untouched by arcs */
    assert_true(fabs(t[2] + 1) < 1e-5);               /* arriving at +X going towards -Z */
    fd_check(&g, 1.0);
    /* G19 G2 (clockwise about +X) with a helix */
    const lsm_real s2[3] = {0, 3, 0}, e2[3] = {1, -3, 0}, c2[3] = {0, 0, 0};
    assert_int_equal(lsm_geom_arc_init(&g, s2, e2, c2, LSM_GEOM_PLANE_YZ, -1, 1), LSM_OK);
    assert_true(fabs(g.u.arc.sweep_rad + 3 * PI) < 1e-5); /* half a turn plus one full turn */
    lsm_geom_eval(&g, g.len, p, NULL, NULL);
    assert_true(fabs(p[0] - 1) < 1e-5 && fabs(p[1] + 3) < 1e-4 && fabs(p[2]) < 1e-4);
    fd_check(&g, 2.0);
    /* full circle: end == start */
    assert_int_equal(lsm_geom_arc_init(&g, s2, s2, c2, LSM_GEOM_PLANE_XY, 1, 0), LSM_OK);
    assert_true(fabs(g.u.arc.sweep_rad - 2 * PI) < 1e-6);
    /* radius mismatch, zero radius, bad plane/dir */
    const lsm_real bad[3] = {0, 3.5, 0};
    assert_int_equal(lsm_geom_arc_init(&g, s2, bad, c2, LSM_GEOM_PLANE_XY, 1, 0), LSM_E_ARC_GEOMETRY);
    assert_int_equal(lsm_geom_arc_init(&g, c2, s2, c2, LSM_GEOM_PLANE_XY, 1, 0), LSM_E_ARC_GEOMETRY);
    assert_int_equal(lsm_geom_arc_init(&g, s2, e2, c2, LSM_GEOM_PLANE_GENERAL, 1, 0), LSM_E_ARG);
    assert_int_equal(lsm_geom_arc_init(&g, s2, e2, c2, LSM_GEOM_PLANE_XY, 0, 0), LSM_E_ARG);
    /* a six-axis line: path length in XYZ, rotary axes in proportion; a rotary-only line */
    const lsm_real l0[LSM_MAX_AXES] = {0, 0, 0, 0, 0, 0}, l1[LSM_MAX_AXES] = {3, 4, 0, 1, 0, -2};
    assert_int_equal(lsm_geom_line_init(&g, l0, l1), LSM_OK);
    assert_true(fabs(g.len - 5) < 1e-6 && !g.rotary_only);
    lsm_geom_eval(&g, 2.5, p, NULL, NULL);
    assert_true(fabs(p[3] - 0.5) < 1e-6 && fabs(p[5] + 1) < 1e-6);
    const lsm_real r1[LSM_MAX_AXES] = {0, 0, 0, 0.3, 0.4, 0};
    assert_int_equal(lsm_geom_line_init(&g, l0, r1), LSM_OK);
    assert_true(g.rotary_only && fabs(g.len - 0.5) < 1e-6);
    /* clothoid element: consistent with its derivatives, trims keep the geometry */
    const lsm_real o[3] = {1, 2, 3}, b1[3] = {0, (lsm_real)0.6, (lsm_real)0.8}, b2[3] = {1, 0, 0};
    assert_int_equal(lsm_geom_clothoid_init(&g, o, b1, b2, 0.3, 0.05, 0.02, 12), LSM_OK);
    fd_check(&g, 4.0);
    lsm_real q[LSM_MAX_AXES], q2[LSM_MAX_AXES];
    lsm_geom_eval(&g, 7, q, NULL, NULL);
    lsm_geom h = g;
    assert_int_equal(lsm_geom_trim_start(&h, 3), LSM_OK);
    lsm_geom_eval(&h, 4, q2, NULL, NULL);
    for (int i = 0; i < 3; i++)
        assert_true(fabs(q[i] - q2[i]) < (IS_F ? 1e-5 : 1e-12));
    assert_int_equal(lsm_geom_trim_end(&h, 9), LSM_E_RANGE);
    assert_int_equal(lsm_geom_trim_end(&h, -1), LSM_E_RANGE);
    /* arc trims */
    assert_int_equal(lsm_geom_arc_init(&g, st, en, ce, LSM_GEOM_PLANE_ZX, 1, 0), LSM_OK);
    lsm_geom_eval(&g, 3, q, NULL, NULL);
    h = g;
    assert_int_equal(lsm_geom_trim_start(&h, 1), LSM_OK);
    assert_int_equal(lsm_geom_trim_end(&h, 1), LSM_OK);
    lsm_geom_eval(&h, 2, q2, NULL, NULL);
    for (int i = 0; i < 3; i++)
        assert_true(fabs(q[i] - q2[i]) < (IS_F ? 1e-5 : 1e-12));
    assert_true(fabs(h.len - (g.len - 2)) < 1e-5);
    /* non-orthonormal basis */
    const lsm_real nb[3] = {1, 0.1f, 0};
    assert_int_equal(lsm_geom_clothoid_init(&g, o, nb, b2, 0, 0, 0, 1), LSM_E_ARG);
    assert_int_equal(lsm_geom_arc_init_general(&g, o, nb, b2, 1, 0, 1, 0), LSM_E_ARC_GEOMETRY);
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    gl_init();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_geom),
        cmocka_unit_test(test_line_line_closed_form),
        cmocka_unit_test(test_scaling),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_apply_and_limits),
        cmocka_unit_test(test_random_corners),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
