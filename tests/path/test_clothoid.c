/*
 * test_clothoid.c: Fresnel integrals, clothoid evaluation, incremental stepping and the section-IV fit
 * (firmware/path/clothoid.h).
 *
 *   test_clothoid [seed] [count]      (default: seed 1, count 3000 random integrals and fits; 10x passes too)
 *
 * References are independent of the code under test: Fresnel values computed with mpmath at 30
 * digits, and the clothoid integral by composite Gauss-Legendre quadrature in long double (nodes
 * computed here by Newton on the Legendre polynomial), on pieces that turn at most 0.2 rad.
 * Tolerances (stated per type): double 1e-13 relative for Fresnel, integrals within
 * 2e-13 (|s| + Phi |I|) where Phi is the turning bound (the phase itself carries Phi * eps of rounding);
 * float 2e-6 relative resp. 4e-6 (|s| + Phi |I|).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "lsm_test_rng.h"

#include "clothoid.h"

#define IS_F LSM_REAL_IS_FLOAT
#define FRESNEL_REL (IS_F ? 2e-6 : 1e-13)
#define INT_TOL (IS_F ? 4e-6 : 2e-13)
#define PI 3.14159265358979323846

static unsigned long g_seed = 1;
static long g_count = 3000;
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

/* ---- reference quadrature ---- */

#include "lsm_test_quad.h" /* gl_init, g_x, g_w: the reference quadrature */

/* int_a^b e^{i(th0 + k0 t + c t^2/2)} dt in long double (one Gauss-Legendre panel: b - a must be small) */
static void ref_panel(double th0, double k0, double c, long double a, long double b, long double *X, long double *Y)
{
    const long double h = b - a;
    long double sx = 0, sy = 0;
    for (int i = 0; i < GL_N; i++) {
        const long double t = a + h * (g_x[i] + 1) / 2;
        const long double th = th0 + t * (k0 + 0.5L * c * t);
        sx += g_w[i] * cosl(th);
        sy += g_w[i] * sinl(th);
    }
    *X = sx * h / 2;
    *Y = sy * h / 2;
}

static void ref_integral(double th0, double k0, double c, double s, double *X, double *Y)
{
    const double phi = fabs(k0 * s) + fabs(c) * s * s; /* >= turning over [0, s] */
    long m = (long)ceil(phi / 0.2);
    if (m < 1)
        m = 1;
    const long double h = (long double)s / m;
    long double sx = 0, sy = 0;
    for (long j = 0; j < m; j++) {
        const long double a = h * j;
        for (int i = 0; i < GL_N; i++) {
            const long double t = a + h * (g_x[i] + 1) / 2;
            const long double th = th0 + t * (k0 + 0.5L * c * t);
            sx += g_w[i] * cosl(th);
            sy += g_w[i] * sinl(th);
        }
    }
    *X = (double)(sx * h / 2);
    *Y = (double)(sy * h / 2);
}

/* ---- Fresnel ---- */

static void test_fresnel_reference(void **state)
{
    (void)state;
    /* mpmath 1.3, mp.dps = 30: fresnelc(x), fresnels(x) (normalised, int_0^x cos(pi t^2 / 2)) */
    static const double ref[][3] = {
        {0.001, 0.00099999999999975325989, 5.2359877559820659249e-10},
        {0.3, 0.29940097605204721038, 0.014116998006576585807},
        {1, 0.77989340037682282947, 0.43825914739035476608},
        {1.5, 0.44526117603982153506, 0.69750496008209301308},
        {1.6, 0.36546168344048770958, 0.63888768350938090306},
        {1.7, 0.32382687600390025374, 0.54919594032156850105},
        {2.5, 0.45741300964177704525, 0.61918175581959293611},
        {4, 0.49842603303817761553, 0.42051575424692842445},
        {10, 0.49989869420551572361, 0.4681699785848822404},
        {1000, 0.49999999989867881636, 0.49968169011381630608},
    };
    for (size_t i = 0; i < sizeof ref / sizeof ref[0]; i++) {
        lsm_real c, s;
        lsm_clothoid_fresnel((lsm_real)ref[i][0], &c, &s);
        /* float: the argument itself is rounded; compare with the derivative's share of that */
        const double x = (double)(lsm_real)ref[i][0];
        const double dx = x - ref[i][0];
        const double cr = ref[i][1] + dx * cos(PI * x * x / 2), sr = ref[i][2] + dx * sin(PI * x * x / 2);
        if (fabs(c - cr) > FRESNEL_REL * fabs(cr) || fabs(s - sr) > FRESNEL_REL * fabs(sr)) {
            print_error("x = %g: C %.17g vs %.17g, S %.17g vs %.17g\n", ref[i][0], (double)c, cr, (double)s, sr);
            fail();
        }
        lsm_real cn, sn;
        lsm_clothoid_fresnel((lsm_real)-ref[i][0], &cn, &sn);
        assert_true(cn == -c && sn == -s); /* odd */
    }
    lsm_real c0, s0;
    lsm_clothoid_fresnel(0, &c0, &s0);
    assert_true(c0 == 0 && s0 == 0);
}

/* Continuity across the series / continued-fraction switch and the derivative dC/dx = cos(pi x^2/2). */
static void test_fresnel_derivative(void **state)
{
    (void)state;
    const double h = IS_F ? 1e-2 : 1e-4;
    for (double x = 0.2; x < 6.0; x += 0.0731) {
        lsm_real c1, s1, c2, s2;
        lsm_clothoid_fresnel((lsm_real)(x - h), &c1, &s1);
        lsm_clothoid_fresnel((lsm_real)(x + h), &c2, &s2);
        const double dc = (c2 - c1) / (2 * h), ds = (s2 - s1) / (2 * h);
        /* central difference error ~ h^2 f''' / 6 with |f'''| <= (pi x)^2 + pi */
        const double tol = h * h * (PI * PI * x * x + PI) / 3 + (IS_F ? 4e-5 : 1e-10);
        if (fabs(dc - cos(PI * x * x / 2)) > tol || fabs(ds - sin(PI * x * x / 2)) > tol) {
            print_error("x = %g: dC %.12g vs %.12g, dS %.12g vs %.12g\n", x, dc, cos(PI * x * x / 2), ds,
                        sin(PI * x * x / 2));
            fail();
        }
    }
}

/* ---- general integral ---- */

static void check_integral(double th0, double k0, double c, double s, long n)
{
    lsm_real X, Y;
    lsm_clothoid_integral((lsm_real)th0, (lsm_real)k0, (lsm_real)c, (lsm_real)s, &X, &Y);
    /* reference on the parameters as the real type holds them */
    double rX, rY;
    ref_integral((double)(lsm_real)th0, (double)(lsm_real)k0, (double)(lsm_real)c, (double)(lsm_real)s, &rX, &rY);
    const double phi = fabs(k0 * s) + 0.5 * fabs(c) * s * s;
    const double tol = INT_TOL * (fabs(s) + phi * hypot(rX, rY));
    if (!(fabs(X - rX) <= tol && fabs(Y - rY) <= tol)) {
        print_error("case %ld (seed %lu): th0 %.17g k0 %.17g c %.17g s %.17g (Phi %.3g): X %.17g vs %.17g, "
                    "Y %.17g vs %.17g, tol %.3g\n",
                    n, g_seed, th0, k0, c, s, phi, (double)X, rX, (double)Y, rY, tol);
        fail();
    }
}

static void test_integral_cases(void **state)
{
    (void)state;
    /* the three regimes: circle closed form, piecewise series, Fresnel form (c > 0 and c < 0,
     * vertex inside or outside), and s < 0 */
    const double k[][4] = {
        {0, 0, 0, 5},      {0.3, 0.2, 0, 7},       {1, -3, 0, 40},         {0, 0, PI, 1},
        {0, 0, PI, 4.4},   {0.5, 0.1, 0.02, 10},   {2, -0.5, 0.3, -4},     {0, 0, 1, 100},
        {0, 0, -1, 100},   {0.3, 17, 0.237, 16.4}, {0.3, -5, 0.5, 30},     {1, 4, -0.5, 30},
        {0, 1, 1e-9, 100}, {0, 0, 1e-3, 300},      {-2, 0.01, 2e-5, 1500}, {0, 0.5, -0.01, 100},
    };
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++)
        check_integral(k[i][0], k[i][1], k[i][2], k[i][3], (long)i);
}

static void test_integral_random(void **state)
{
    (void)state;
    g_rng = 0x243F6A8885A308D3ull ^ (uint64_t)g_seed;
    for (long n = 0; n < g_count; n++) {
        const double th0 = uni(-4, 4);
        const double k0 = (urand() < 0.2 ? 0 : 1) * (urand() < 0.5 ? -1 : 1) * logu(1e-4, 5);
        const double c = (urand() < 0.15 ? 0 : 1) * (urand() < 0.5 ? -1 : 1) * logu(1e-6, 5);
        double s = (urand() < 0.1 ? -1 : 1) * logu(1e-3, 60);
        /* keep the reference affordable: at most ~2000 rad of turning */
        while (fabs(k0 * s) + fabs(c) * s * s > 2000)
            s *= 0.5;
        check_integral(th0, k0, c, s, n);
    }
}

static void test_eval(void **state)
{
    (void)state;
    lsm_clothoid cl;
    assert_int_equal(lsm_clothoid_init(&cl, 1, 2, 0.5, 0.1, -0.02, 10), LSM_OK);
    lsm_clothoid_state s;
    assert_int_equal(lsm_clothoid_eval(&cl, 0, &s), LSM_OK);
    assert_true(s.x_mm == 1 && s.y_mm == 2 && s.theta_rad == (lsm_real)0.5 && s.kappa_per_mm == (lsm_real)0.1);
    assert_int_equal(lsm_clothoid_eval(&cl, 7.5, &s), LSM_OK);
    const double th = 0.5 + 0.1 * 7.5 - 0.01 * 7.5 * 7.5, k = 0.1 - 0.02 * 7.5;
    assert_true(fabs(s.theta_rad - th) < (IS_F ? 1e-6 : 1e-15) && fabs(s.kappa_per_mm - k) < (IS_F ? 1e-7 : 1e-16));
    double rx, ry;
    ref_integral(0.5, 0.1, -0.02, 7.5, &rx, &ry);
    assert_true(fabs(s.x_mm - 1 - rx) < (IS_F ? 1e-5 : 1e-13) && fabs(s.y_mm - 2 - ry) < (IS_F ? 1e-5 : 1e-13));
    /* bad input */
    lsm_real nanv = (lsm_real)NAN, infv = (lsm_real)INFINITY;
    assert_int_equal(lsm_clothoid_eval(&cl, nanv, &s), LSM_E_NAN);
    assert_int_equal(lsm_clothoid_eval(&cl, infv, &s), LSM_E_INF);
    assert_int_equal(lsm_clothoid_eval(NULL, 1, &s), LSM_E_NULL);
    assert_int_equal(lsm_clothoid_init(&cl, nanv, 0, 0, 0, 0, 1), LSM_E_NAN);
    assert_int_equal(lsm_clothoid_init(&cl, 0, 0, 0, infv, 0, 1), LSM_E_INF);
    assert_int_equal(lsm_clothoid_init(&cl, 0, 0, 0, 0, 0, -1), LSM_E_RANGE);
    assert_int_equal(lsm_clothoid_init(NULL, 0, 0, 0, 0, 0, 1), LSM_E_NULL);
    /* a result beyond the real type */
    assert_int_equal(lsm_clothoid_init(&cl, 0, 0, 0, 0, IS_F ? 1e30 : 1e300, 1), LSM_OK);
    assert_int_equal(lsm_clothoid_eval(&cl, IS_F ? 1e10 : 1e10, &s), LSM_E_RANGE);
}

/* ---- stepping ---- */

/* Largest distance between the stepped position and a long-double reference accumulated panel by
 * panel over the same steps. */
static double step_drift(const lsm_clothoid *cl, double ds, uint32_t anchor, long *nsteps)
{
    lsm_clothoid_stepper st;
    assert_int_equal(lsm_clothoid_stepper_init(&st, cl, 0, anchor), LSM_OK);
    lsm_clothoid_state a, b;
    double worst = 0;
    long n = 0;
    long double rx = cl->x0_mm, ry = cl->y0_mm, rs = 0;
    while (st.s_mm < cl->len_mm) {
        assert_int_equal(lsm_clothoid_step(&st, (lsm_real)ds, &a), LSM_OK);
        n++;
        const long double s1 = st.s_mm;
        for (long double t = rs; t < s1;) { /* panels of at most 0.05 mm */
            const long double t1 = t + 0.05L < s1 ? t + 0.05L : s1;
            long double px, py;
            ref_panel(cl->theta0_rad, cl->kappa0_per_mm, cl->c_per_mm2, t, t1, &px, &py);
            rx += px;
            ry += py;
            t = t1;
        }
        rs = s1;
        const double e = hypot(a.x_mm - (double)rx, a.y_mm - (double)ry);
        if (e > worst)
            worst = e;
        assert_int_equal(lsm_clothoid_eval(cl, st.s_mm, &b), LSM_OK);
        assert_true(fabs(a.kappa_per_mm - b.kappa_per_mm) <= (IS_F ? 1e-5 : 1e-12) * (1 + fabs(b.kappa_per_mm)));
    }
    /* the end state is landed on exactly */
    assert_true(st.s_mm == cl->len_mm);
    assert_int_equal(lsm_clothoid_eval(cl, cl->len_mm, &b), LSM_OK);
    assert_true(a.x_mm == b.x_mm && a.y_mm == b.y_mm);
    *nsteps = n;
    return worst;
}

static void test_stepper(void **state)
{
    (void)state;
    lsm_clothoid cl;
    /* 100 mm clothoid turning about 3.5 rad, 1e4 steps of 0.01 mm */
    assert_int_equal(lsm_clothoid_init(&cl, 3, -2, 0.7, -0.01, 0.0009, 100), LSM_OK);
    long n;
    const double free_run = step_drift(&cl, 0.01, 0, &n);
    const double anchored = step_drift(&cl, 0.01, 256, &n);
    print_message("stepper: %ld steps of 0.01 mm over 100 mm: max drift %.3g mm without re-anchoring, %.3g mm "
                  "anchored every 256 steps\n",
                  n, free_run, anchored);
    /* rounding only (clothoid.h): the tangent's direction random-walks by ~eps per step, so the drift is
     * about (distance since the anchor) * sqrt(steps) * eps, plus a few ulps of the coordinates (~100 mm)
     * from the anchoring evaluation itself */
    const double eps = IS_F ? 1.1920929e-7 : 2.220446049250313e-16;
    assert_true(free_run < 2 * 100.0 * sqrt(1e4) * eps + 8 * eps * 100);
    assert_true(anchored < 2 * 2.56 * sqrt(256.0) * eps + 8 * eps * 100);
    /* large steps (each turning > 1 rad) are split internally */
    assert_int_equal(lsm_clothoid_init(&cl, 0, 0, 0, 0.5, 0.2, 12), LSM_OK);
    const double big = step_drift(&cl, 3.0, 0, &n);
    assert_true(big < (IS_F ? 1e-4 : 1e-12));
    /* bad input */
    lsm_clothoid_stepper st;
    assert_int_equal(lsm_clothoid_stepper_init(&st, &cl, 0, 0), LSM_OK);
    assert_int_equal(lsm_clothoid_step(&st, -1, NULL), LSM_E_NEG_FEED);
    assert_int_equal(lsm_clothoid_step(&st, (lsm_real)NAN, NULL), LSM_E_NAN);
    assert_int_equal(lsm_clothoid_stepper_init(&st, &cl, 13, 0), LSM_E_RANGE);
    assert_int_equal(lsm_clothoid_stepper_init(&st, &cl, -1, 0), LSM_E_RANGE);
}

/* ---- the small-step kernel and large steps ---- */

/* E = e^{i psi(1)} and M = int_0^1 e^{i psi(u)} du, psi(u) = a u + b u^2 / 2, in long double (16 panels). */
static void ref_local(double a, double b, long double *er, long double *ei, long double *mr, long double *mi)
{
    long double sx = 0, sy = 0;
    for (int j = 0; j < 16; j++) {
        long double px, py;
        ref_panel(0, a, b, j / 16.0L, (j + 1) / 16.0L, &px, &py);
        sx += px;
        sy += py;
    }
    *er = cosl((long double)a + 0.5L * b);
    *ei = sinl((long double)a + 0.5L * b);
    *mr = sx;
    *mi = sy;
}

/* Largest error of lsm_clothoid_local_fast (and of lsm_clothoid_local, for comparison) against the reference, in
 * units of eps, over a grid of (phi = a + b/2, b) spanning [-phi_max, phi_max] x [-b_max, b_max]. */
static double local_fast_err(double phi_max, double b_max, int n, double *err_general)
{
    const double eps = IS_F ? 1.1920929e-7 : 2.220446049250313e-16;
    double worst = 0, worst_g = 0;
    for (int i = -n; i <= n; i++) {
        for (int j = -n; j <= n; j++) {
            const lsm_real b = (lsm_real)(b_max * j / n);
            const lsm_real a = (lsm_real)(phi_max * i / n - 0.5 * b);
            long double er, ei, mr, mi;
            ref_local(a, b, &er, &ei, &mr, &mi);
            lsm_real fer, fei, fmr, fmi, ger, gei, gmr, gmi;
            lsm_clothoid_local_fast(a, b, &fer, &fei, &fmr, &fmi);
            lsm_clothoid_local(a, b, &ger, &gei, &gmr, &gmi);
            const double e =
                (double)fmaxl(fmaxl(fabsl(fer - er), fabsl(fei - ei)), fmaxl(fabsl(fmr - mr), fabsl(fmi - mi)));
            const double g =
                (double)fmaxl(fmaxl(fabsl(ger - er), fabsl(gei - ei)), fmaxl(fabsl(gmr - mr), fabsl(gmi - mi)));
            if (e > worst)
                worst = e;
            if (g > worst_g)
                worst_g = g;
        }
    }
    *err_general = worst_g / eps;
    return worst / eps;
}

static void test_local_fast(void **state)
{
    (void)state;
    const double P = LSM_CLOTHOID_FAST_PHI_RAD, B = LSM_CLOTHOID_FAST_B_RAD;
    double g;
    /* inside the small-step region, corners and edges included (the truncation is largest at the corners): the
     * polynomial is as accurate as the general series, about 1 eps (rounding). Measured: float 1.01 eps (general
     * series 2.00), double 1.15 (1.50). Truncated earlier it fails: sin(phi/2) to x^3 gives 44 eps (float) and 7500
     * (double), G without r^3 5 and 670, without r^2 q 3 and 134 (float, double). */
    const double in = local_fast_err(P, B, 24, &g);
    print_message("local_fast: inside the region (|a + b/2| <= %g, |b| <= %g) max error %.2f eps (general series "
                  "%.2f eps)\n",
                  P, B, in, g);
    assert_true(in <= 1.5);
    assert_true(in <= g + 0.5);
    /* the truncation alone: it is systematic, the rounding is not, so the mean error over many points near a
     * corner of the region (where the truncation is largest) shows it. Measured: at most 0.03 eps (rounding is
     * not quite unbiased either). Without the cos(phi/2) x^6 term or the r q^2 term of G the float means are 1.1
     * and 0.5 eps, without the q^3 term of G the double mean is 0.65 eps (dropping it costs float only 0.06 eps). */
    const double eps = IS_F ? 1.1920929e-7 : 2.220446049250313e-16;
    double worst_mean = 0;
    for (int corner = 0; corner < 4; corner++) {
        long double se[4] = {0, 0, 0, 0};
        const int nn = 4000;
        g_rng = 0x9E3779B97F4A7C15ull + (uint64_t)corner;
        for (int k = 0; k < nn; k++) {
            const lsm_real b = (lsm_real)(((corner & 1) ? -B : B) * uni(0.9, 1.0));
            const lsm_real a = (lsm_real)(((corner & 2) ? -P : P) * uni(0.9, 1.0) - 0.5 * b);
            long double er, ei, mr, mi;
            ref_local(a, b, &er, &ei, &mr, &mi);
            lsm_real fer, fei, fmr, fmi;
            lsm_clothoid_local_fast(a, b, &fer, &fei, &fmr, &fmi);
            se[0] += fer - er;
            se[1] += fei - ei;
            se[2] += fmr - mr;
            se[3] += fmi - mi;
        }
        for (int k = 0; k < 4; k++)
            worst_mean = fmax(worst_mean, fabs((double)(se[k] / nn) / eps));
    }
    print_message("local_fast: largest mean error near a corner of the region %.3f eps\n", worst_mean);
    assert_true(worst_mean <= 0.1);
    /* outside the region it is the general series: the same accuracy up to steps that turn 1 rad */
    const double out = local_fast_err(1.0, 1.0, 10, &g);
    print_message("local_fast: |a + b/2| <= 1, |b| <= 1: max error %.2f eps (general series %.2f eps)\n", out, g);
    assert_true(out <= 4.0);
}

/* One step of ds from s0 against the long-double reference: position error (mm) and tangent error (rad). */
static void one_step_err(const lsm_clothoid *cl, double s0, double ds, double *pos_err, double *tan_err)
{
    lsm_clothoid_stepper st;
    assert_int_equal(lsm_clothoid_stepper_init(&st, cl, (lsm_real)s0, 0), LSM_OK);
    const double x0 = st.x_mm, y0 = st.y_mm, tx0 = st.tx, ty0 = st.ty, sa = st.s_mm;
    assert_int_equal(lsm_clothoid_step(&st, (lsm_real)ds, NULL), LSM_OK);
    /* the step's own error: from the stepper's start state, along the same arc lengths */
    long double px = 0, py = 0;
    const long double s1 = st.s_mm;
    const int np = 64;
    for (int k = 0; k < np; k++) {
        long double qx, qy;
        ref_panel(0, cl->kappa0_per_mm, cl->c_per_mm2, sa + (s1 - sa) * k / np, sa + (s1 - sa) * (k + 1) / np, &qx,
                  &qy);
        px += qx;
        py += qy;
    }
    /* rotate by the start tangent of the reference (angle theta(sa) - theta0) into the stepper's frame */
    const long double th_a = sa * (cl->kappa0_per_mm + 0.5L * cl->c_per_mm2 * sa);
    const long double ca = cosl(th_a), sn = sinl(th_a);
    const long double lx = px * ca + py * sn, ly = -px * sn + py * ca; /* in the frame of the start tangent */
    const long double rx = x0 + lx * tx0 - ly * ty0, ry = y0 + lx * ty0 + ly * tx0;
    *pos_err = hypot((double)(st.x_mm - rx), (double)(st.y_mm - ry));
    const long double dth = (s1 * (cl->kappa0_per_mm + 0.5L * cl->c_per_mm2 * s1)) - th_a;
    const long double etx = tx0 * cosl(dth) - ty0 * sinl(dth), ety = tx0 * sinl(dth) + ty0 * cosl(dth);
    *tan_err = hypot((double)(st.tx - etx), (double)(st.ty - ety));
}

static void test_stepper_large_steps(void **state)
{
    (void)state;
    const double eps = IS_F ? 1.1920929e-7 : 2.220446049250313e-16;
    /* single steps from |kappa ds| = 0.001 to 3 rad with the sharpness up to the edge of the small-step region
     * and beyond (small steps, steps cut into 2-4 polynomial sub-steps, the general series, steps split at 1 rad):
     * each must be as good as rounding allows, whatever path it takes */
    const double kds[] = {0.001, 0.05, 0.2, 0.39, 0.41, 0.6, 0.79, 1.2, 1.59, 1.61, 3.0};
    const double bfac[] = {0, 0.5, 1, -1, 3};
    double worst_pos = 0, worst_tan = 0;
    for (size_t i = 0; i < sizeof kds / sizeof kds[0]; i++) {
        for (size_t j = 0; j < sizeof bfac / sizeof bfac[0]; j++) {
            const double ds = 0.25, k0 = kds[i] / ds;
            const double b = bfac[j] * LSM_CLOTHOID_FAST_B_RAD * (kds[i] < 0.2 ? 0.5 : 1.0);
            const double c = b / (ds * ds);
            lsm_clothoid cl;
            assert_int_equal(lsm_clothoid_init(&cl, 0, 0, 0.3, k0, c, 10 * ds), LSM_OK);
            double pe, te;
            one_step_err(&cl, 0, ds, &pe, &te);
            /* the position moves by ds: a few eps of it; the tangent: a few eps */
            if (!(pe <= 4 * eps * ds && te <= 4 * eps)) {
                print_error("kappa ds %g, c ds^2 %g: position error %.3g mm (%.2f eps ds), tangent %.3g (%.2f eps)\n",
                            kds[i], b, pe, pe / (eps * ds), te, te / eps);
                fail();
            }
            if (pe / (eps * ds) > worst_pos)
                worst_pos = pe / (eps * ds);
            if (te / eps > worst_tan)
                worst_tan = te / eps;
        }
    }
    print_message("large steps: worst single step %.2f eps * ds in position, %.2f eps in the tangent\n", worst_pos,
                  worst_tan);
    /* many large steps: 400 steps of 0.25 mm at kappa about 1.3 /mm (|kappa ds| 0.3 to 0.36), no anchoring, against
     * the long-double reference: rounding only, as in test_stepper */
    lsm_clothoid cl;
    assert_int_equal(lsm_clothoid_init(&cl, 20, -5, -1.0, 1.2, 0.0025, 100), LSM_OK);
    long n;
    const double d = step_drift(&cl, 0.25, 0, &n);
    print_message("large steps: %ld steps of 0.25 mm (|kappa ds| 0.3-0.36): max drift %.3g mm\n", n, d);
    assert_true(d < 2 * 100.0 * sqrt((double)n) * eps + 8 * eps * 100);
}

/* Starting anywhere (and re-anchoring: the same evaluation from the segment's start) is as accurate as the exact
 * evaluation: the short starts of block entry (one small step), starts that need many small pieces, and starts
 * beyond that (the exact evaluation). */
static void test_stepper_start(void **state)
{
    (void)state;
    const double eps = IS_F ? 1.1920929e-7 : 2.220446049250313e-16;
    const double segs[][6] = {
        /* x0, y0, theta0, kappa0, c, len */
        {3, -2, 0.7, -0.01, 0.0009, 100}, /* turns 3.5 rad */
        {-40, 25, 2.5, 0.6, -0.35, 0.3},  /* a corner blend */
        {0, 0, -1.0, 31.7, -471, 0.0677}, /* a tight one */
        {10, 10, 0.2, 0.05, 2.0, 12},     /* turns 150 rad: beyond the pieces, the exact evaluation */
    };
    const double frac[] = {0, 1e-4, 0.003, 0.05, 0.2, 0.5, 0.9, 1};
    double worst_pos = 0, worst_tan = 0;
    for (size_t i = 0; i < sizeof segs / sizeof segs[0]; i++) {
        lsm_clothoid cl;
        assert_int_equal(lsm_clothoid_init(&cl, segs[i][0], segs[i][1], segs[i][2], segs[i][3], segs[i][4], segs[i][5]),
                         LSM_OK);
        for (size_t j = 0; j < sizeof frac / sizeof frac[0]; j++) {
            const lsm_real s0 = (lsm_real)(frac[j] * cl.len_mm);
            lsm_clothoid_stepper st;
            assert_int_equal(lsm_clothoid_stepper_init(&st, &cl, s0, 0), LSM_OK);
            double rx, ry;
            ref_integral(cl.theta0_rad, cl.kappa0_per_mm, cl.c_per_mm2, s0, &rx, &ry);
            const long double th = cl.theta0_rad + s0 * (cl.kappa0_per_mm + 0.5L * cl.c_per_mm2 * s0);
            const double phi = fabs(cl.kappa0_per_mm * s0) + 0.5 * fabs(cl.c_per_mm2) * s0 * s0;
            /* a few eps of the coordinates, and of the rounding of the angle (eps per radian); measured: 1.4 eps
             * (double) and 0.9 (float) of |x0| + |y0| + s0, the tangent 1.4 eps (1 + phi) */
            const double scale = fabs(cl.x0_mm) + fabs(cl.y0_mm) + s0;
            const double pe = hypot(st.x_mm - cl.x0_mm - rx, st.y_mm - cl.y0_mm - ry);
            const double te = hypot((double)(st.tx - cosl(th)), (double)(st.ty - sinl(th)));
            if (!(pe <= 4 * eps * (scale + phi * hypot(rx, ry)) && te <= 4 * eps * (1 + phi))) {
                print_error("segment %zu, s0 %.9g: position error %.3g mm, tangent %.3g\n", i, (double)s0, pe, te);
                fail();
            }
            if (scale > 0 && pe / (eps * scale) > worst_pos)
                worst_pos = pe / (eps * scale);
            if (te / eps > worst_tan)
                worst_tan = te / eps;
            if (s0 == cl.len_mm) { /* the end state exactly */
                lsm_clothoid_state b;
                assert_int_equal(lsm_clothoid_eval(&cl, s0, &b), LSM_OK);
                assert_true(st.x_mm == b.x_mm && st.y_mm == b.y_mm);
            }
        }
    }
    print_message("stepper start: worst %.2f eps * (|x0| + |y0| + s0) in position, %.2f eps in the tangent\n",
                  worst_pos, worst_tan);
}

/* ---- fit ---- */

static void check_fit(const lsm_clothoid_state *s0, double A, double B, double C, const lsm_clothoid_fit_result *r,
                      long n)
{
    /* recompute the end independently */
    double X, Y;
    ref_integral(s0->theta_rad, s0->kappa_per_mm, r->c_per_mm2, r->s_mm, &X, &Y);
    const double x = s0->x_mm + X, y = s0->y_mm + Y;
    const double h = hypot(A, B);
    const double dist = fabs(A * x + B * y + C) / h;
    const double th = s0->theta_rad + r->s_mm * (s0->kappa_per_mm + 0.5 * r->c_per_mm2 * r->s_mm);
    const double cross = (cos(th) * B - sin(th) * A) / h; /* tangent x normal */
    const double scale = fabs(A * s0->x_mm + B * s0->y_mm + C) / h + r->s_mm;
    const double tol = IS_F ? 2e-5 : 1e-10;
    if (!(dist <= tol * scale && fabs(cross) <= tol * 10 && r->s_mm > 0 && r->iterations <= LSM_CLOTHOID_FIT_MAX_ITER &&
          r->bracket_steps <= LSM_CLOTHOID_FIT_BRACKET_MAX_ITER)) {
        print_error("fit %ld (seed %lu): dist %.3g (scale %.3g), cross %.3g, s %.6g, c %.6g, it %d, bracket %d\n", n,
                    g_seed, dist, scale, cross, (double)r->s_mm, (double)r->c_per_mm2, r->iterations, r->bracket_steps);
        fail();
    }
    assert_true(fabs(r->end.x_mm - x) <= tol * scale && fabs(r->end.y_mm - y) <= tol * scale);
    assert_true(fabs(r->end.kappa_per_mm - (s0->kappa_per_mm + r->c_per_mm2 * r->s_mm)) <=
                (IS_F ? 1e-5 : 1e-12) * (1 + fabs(r->end.kappa_per_mm)));
}

static void test_fit_lines(void **state)
{
    (void)state;
    /* vertical, horizontal and oblique lines in general form */
    const double lines[][3] = {{1, 0, -10}, {0, 1, -10}, {0, -2, 20}, {-3, 0, 30}, {1, 1, -10}, {1, -0.2, -3}};
    const lsm_clothoid_state starts[] = {{0, 0, 0, 0}, {0, 0, 0.3, 0.05}, {0, 0, -0.4, -0.02}, {1, 1, 1.2, 0.1}};
    long n = 0;
    for (size_t i = 0; i < sizeof lines / sizeof lines[0]; i++) {
        for (size_t j = 0; j < sizeof starts / sizeof starts[0]; j++, n++) {
            lsm_clothoid_fit_result r;
            lsm_status st = lsm_clothoid_fit_line(&starts[j], lines[i][0], lines[i][1], lines[i][2], &r);
            if (st == LSM_E_FIT_NO_SOLUTION)
                continue; /* heading away and curling: none on the principal branch */
            if (st != LSM_OK) {
                print_error("line %zu start %zu: status %d\n", i, j, (int)st);
                fail();
            }
            check_fit(&starts[j], lines[i][0], lines[i][1], lines[i][2], &r, n);
        }
    }
    /* a start aimed at the line always has a solution: the vertical line x = 10 from the origin */
    const lsm_clothoid_state s0 = {0, 0, 0.5, 0};
    lsm_clothoid_fit_result r;
    assert_int_equal(lsm_clothoid_fit_line(&s0, 1, 0, -10, &r), LSM_OK);
    check_fit(&s0, 1, 0, -10, &r, -1);
    assert_true(r.c_per_mm2 < 0); /* turns right, back to the normal (+x) */
}

static void test_fit_random(void **state)
{
    (void)state;
    g_rng = 0x13198A2E03707344ull ^ (uint64_t)g_seed;
    long solved = 0, aimed = 0, aimed_solved = 0, it_total = 0, it_max = 0, fallbacks = 0, bracket_max = 0;
    for (long n = 0; n < g_count; n++) {
        lsm_clothoid_state s0 = {(lsm_real)uni(-50, 50), (lsm_real)uni(-50, 50), (lsm_real)uni(-PI, PI),
                                 (lsm_real)((urand() < 0.3 ? 0 : 1) * uni(-0.1, 0.1))};
        const double dist = logu(0.5, 50), phi = uni(-PI, PI);
        const double nx = cos(phi), ny = sin(phi);
        const double qx = s0.x_mm + dist * nx, qy = s0.y_mm + dist * ny; /* foot of the start on the line */
        double A = nx, B = ny;
        if (urand() < 0.15) { /* exactly vertical or horizontal */
            if (fabs(nx) > fabs(ny)) {
                A = nx > 0 ? 1 : -1;
                B = 0;
            } else {
                A = 0;
                B = ny > 0 ? 1 : -1;
            }
        }
        const double scale = logu(0.01, 100);
        A *= scale;
        B *= scale;
        const double C = -(A * qx + B * qy);
        lsm_clothoid_fit_result r;
        lsm_status st = lsm_clothoid_fit_line(&s0, (lsm_real)A, (lsm_real)B, (lsm_real)C, &r);
        /* "aimed": heading within 60 deg of the line's normal towards it, gentle curvature */
        const double dn = cos(s0.theta_rad) * (A * (qx - s0.x_mm) + B * (qy - s0.y_mm) >= 0 ? A : -A) +
                          sin(s0.theta_rad) * (A * (qx - s0.x_mm) + B * (qy - s0.y_mm) >= 0 ? B : -B);
        const bool is_aimed = dn / hypot(A, B) > 0.5 && fabs(s0.kappa_per_mm) * dist < 0.5;
        aimed += is_aimed;
        if (st == LSM_OK) {
            solved++;
            aimed_solved += is_aimed;
            check_fit(&s0, A, B, C, &r, n);
            it_total += r.iterations;
            if (r.iterations > it_max)
                it_max = r.iterations;
            fallbacks += r.bracket_steps > 0;
            if (r.bracket_steps > bracket_max)
                bracket_max = r.bracket_steps;
        } else if (st != LSM_E_FIT_NO_SOLUTION) {
            print_error("fit %ld (seed %lu): status %d (%s)\n", n, g_seed, (int)st, lsm_status_str(st));
            fail();
        } else if (is_aimed) {
            print_error("fit %ld (seed %lu): aimed start without solution\n", n, g_seed);
            fail();
        }
    }
    print_message("fit: %ld of %ld solved (%ld of %ld aimed), Newton iterations mean %.2f max %ld, %ld bracketed "
                  "(steps max %ld)\n",
                  solved, g_count, aimed_solved, aimed, solved ? (double)it_total / solved : 0.0, it_max, fallbacks,
                  bracket_max);
    assert_true(aimed_solved == aimed);
}

/* Issue 14 item 8: fit 12560 of seed 1 (the random generator's case, as built in double): damped Newton stalls
 * near a fold (40 iterations, merit decreasing by ever smaller steps) and the bracketed fallback solves it. */
static void test_fit_newton_stall(void **state)
{
    (void)state;
    const lsm_clothoid_state s0 = {(lsm_real)2.2955060213834528, (lsm_real)-49.458438263876111,
                                   (lsm_real)-0.25613082619075822, (lsm_real)-0.0033990664679933447};
    const double A = -16.670062181883733, B = 44.804071438268572, C = 2150.4717230458327;
    lsm_clothoid_fit_result r;
    const lsm_status st = lsm_clothoid_fit_line(&s0, (lsm_real)A, (lsm_real)B, (lsm_real)C, &r);
    if (st != LSM_OK) {
        print_error("stalled fit: status %d (%s), it %d, bracket %d\n", (int)st, lsm_status_str(st), r.iterations,
                    r.bracket_steps);
        fail();
    }
    check_fit(&s0, A, B, C, &r, 12560);
    assert_int_equal(r.iterations, LSM_CLOTHOID_FIT_MAX_ITER); /* Newton did stall: the fallback is what is tested */
    assert_true(r.bracket_steps > 0);
}

static void test_fit_bad_input(void **state)
{
    (void)state;
    const lsm_clothoid_state s0 = {0, 0, 0, 0};
    lsm_clothoid_fit_result r;
    assert_int_equal(lsm_clothoid_fit_line(&s0, 0, 0, 1, &r), LSM_E_FIT_LINE);
    assert_int_equal(lsm_clothoid_fit_line(&s0, (lsm_real)NAN, 1, 1, &r), LSM_E_NAN);
    assert_int_equal(lsm_clothoid_fit_line(&s0, 1, (lsm_real)INFINITY, 1, &r), LSM_E_INF);
    const lsm_clothoid_state sn = {0, (lsm_real)NAN, 0, 0};
    assert_int_equal(lsm_clothoid_fit_line(&sn, 1, 0, -1, &r), LSM_E_NAN);
    assert_int_equal(lsm_clothoid_fit_line(NULL, 1, 0, -1, &r), LSM_E_NULL);
    /* start on the line x = 0, heading along it: no clothoid meets it at a right angle */
    const lsm_clothoid_state on = {0, 5, (lsm_real)(PI / 2), 0};
    assert_int_equal(lsm_clothoid_fit_line(&on, 1, 0, 0, &r), LSM_E_FIT_ON_LINE);
    /* on the line and already normal to it: the empty clothoid */
    const lsm_clothoid_state on_n = {0, 5, 0, 0.1};
    assert_int_equal(lsm_clothoid_fit_line(&on_n, 1, 0, 0, &r), LSM_OK);
    assert_true(r.s_mm == 0 && r.iterations == 0);
    /* heading straight away from the line with no curvature: unreachable on the principal branch */
    assert_int_equal(lsm_clothoid_fit_line(&s0, 1, 0, 10, &r), LSM_E_FIT_NO_SOLUTION);
    /* distinct codes */
    assert_true(LSM_E_FIT_LINE != LSM_E_FIT_ON_LINE && LSM_E_FIT_ON_LINE != LSM_E_FIT_NO_SOLUTION &&
                LSM_E_FIT_NO_SOLUTION != LSM_E_NOT_CONVERGED);
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    gl_init();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fresnel_reference),
        cmocka_unit_test(test_fresnel_derivative),
        cmocka_unit_test(test_integral_cases),
        cmocka_unit_test(test_integral_random),
        cmocka_unit_test(test_eval),
        cmocka_unit_test(test_stepper),
        cmocka_unit_test(test_local_fast),
        cmocka_unit_test(test_stepper_large_steps),
        cmocka_unit_test(test_stepper_start),
        cmocka_unit_test(test_fit_lines),
        cmocka_unit_test(test_fit_random),
        cmocka_unit_test(test_fit_newton_stall),
        cmocka_unit_test(test_fit_bad_input),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
