/*
 * test_g2path.c: the section-V G2 path construction (firmware/path/g2path.h).
 *
 *   test_g2path [seed] [count]      (default: seed 1, count 40 random contours)
 *
 * - Paper reproduction (../shared/papers/NOTES.md): the contour "line 15.5 mm, 90 deg arc R 10 mm,
 *   line 15.5 mm" with 7 points gives 0.945 mm (distance from the polygon through the points; 1.023 mm
 *   from the contour itself), c_max 0.00817, feed limits 2364 / 1275 mm/min (a_max 50 mm/s^2,
 *   j_max 500 mm/s^3); 96 segments give 0.0040 mm and c_max 0.1046.
 * - Scaling (paper Fig. 7): each doubling of N divides the deviation by 3.7..4.3 and multiplies c_max
 *   by 1.55..2.1, the factor approaching 2.
 * - G2: every clothoid starts where, in the direction and with the curvature the previous one ended
 *   (end states recomputed independently by Gauss-Legendre quadrature); each meets its bisector at a
 *   right angle; the same contour in G18 gives the same numbers.
 * - Automatic N: the N found meets the tolerance and N - 1 does not.
 * - Random smooth-ish contours (lines and tangent or kinked arcs) build without error, G2.
 * - Bad input: every error code.
 * Tolerances: double as stated; float 1e-3 relative on the paper figures, 1e-4 on G2 joints.
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
#include <string.h>

#include "g2path.h"

#define IS_F LSM_REAL_IS_FLOAT
#define PI 3.14159265358979323846
#define CAP 1600

static unsigned long g_seed = 1;
static long g_count = 40;
static uint64_t g_rng;
static lsm_clothoid g_out[CAP];

/* the shared generator (lsm_test_rng.h) on this test's state */
static double urand(void)
{
    return test_urand(&g_rng);
}
static double uni(double a, double b)
{
    return test_uni(&g_rng, a, b);
}

/* ---- independent end state of a clothoid (Gauss-Legendre, 12 nodes, panels turning <= 0.1 rad) ---- */
#include "lsm_test_quad.h" /* gl_init, g_x, g_w: the reference quadrature */

static void ref_end(const lsm_clothoid *c, double *x, double *y, double *th, double *k)
{
    const double L = c->len_mm;
    const double kmax = fabs(c->kappa0_per_mm) + fabs(c->c_per_mm2) * L;
    long m = (long)ceil(L * kmax / 0.1);
    if (m < 1)
        m = 1;
    const long double h = (long double)L / m;
    long double sx = 0, sy = 0;
    for (long j = 0; j < m; j++)
        for (int i = 0; i < GL_N; i++) {
            const long double t = h * j + h * (g_x[i] + 1) / 2;
            const long double a = c->theta0_rad + t * (c->kappa0_per_mm + 0.5L * c->c_per_mm2 * t);
            sx += g_w[i] * cosl(a);
            sy += g_w[i] * sinl(a);
        }
    *x = c->x0_mm + (double)(sx * h / 2);
    *y = c->y0_mm + (double)(sy * h / 2);
    *th = c->theta0_rad + L * (c->kappa0_per_mm + 0.5 * c->c_per_mm2 * L);
    *k = c->kappa0_per_mm + c->c_per_mm2 * L;
}

/* ---- contours ---- */

static lsm_status line(lsm_geom *g, double x0, double y0, double x1, double y1)
{
    const lsm_real a[LSM_MAX_AXES] = {(lsm_real)x0, (lsm_real)y0, 0, 0, 0, 0};
    const lsm_real b[LSM_MAX_AXES] = {(lsm_real)x1, (lsm_real)y1, 0, 0, 0, 0};
    return lsm_geom_line_init(g, a, b);
}

/* The paper's Fig. 4 contour as reconstructed in NOTES.md, in G17 (XY) or G18 (ZX: x -> Z, y -> X). */
static void paper_contour(lsm_geom c[3], lsm_geom_plane pl)
{
    if (pl == LSM_GEOM_PLANE_XY) {
        assert_int_equal(line(&c[0], 0, 0, 15.5, 0), LSM_OK);
        const lsm_real s[3] = {15.5, 0, 0}, e[3] = {25.5, 10, 0}, ce[3] = {15.5, 10, 0};
        assert_int_equal(lsm_geom_arc_init(&c[1], s, e, ce, LSM_GEOM_PLANE_XY, 1, 0), LSM_OK);
        assert_int_equal(line(&c[2], 25.5, 10, 25.5, 25.5), LSM_OK);
    } else {
        /* plane coordinates (u, v) = (Z, X), normal Y = 7 */
        const lsm_real a0[6] = {0, 7, 0, 0, 0, 0}, a1[6] = {0, 7, 15.5, 0, 0, 0};
        assert_int_equal(lsm_geom_line_init(&c[0], a0, a1), LSM_OK);
        const lsm_real s[3] = {0, 7, 15.5}, e[3] = {10, 7, 25.5}, ce[3] = {10, 7, 15.5};
        assert_int_equal(lsm_geom_arc_init(&c[1], s, e, ce, LSM_GEOM_PLANE_ZX, 1, 0), LSM_OK);
        const lsm_real b0[6] = {10, 7, 25.5, 0, 0, 0}, b1[6] = {25.5, 7, 25.5, 0, 0, 0};
        assert_int_equal(lsm_geom_line_init(&c[2], b0, b1), LSM_OK);
    }
}

/* G2 along the chain and the right angle at each bisector (the line normal is recomputed from the
 * returned states, so this checks the chain, not the fit's own residual). */
static void check_chain(int n, double *worst_gap, double *worst_k)
{
    double wg = 0, wk = 0;
    for (int j = 0; j + 1 < n; j++) {
        double x, y, th, k;
        ref_end(&g_out[j], &x, &y, &th, &k);
        const lsm_clothoid *nx = &g_out[j + 1];
        const double gap = hypot(x - nx->x0_mm, y - nx->y0_mm);
        const double dth = fabs(remainder(th - nx->theta0_rad, 2 * PI));
        const double dk = fabs(k - nx->kappa0_per_mm);
        if (gap > wg)
            wg = gap;
        if (dk / (fabs(k) + 1e-3) > wk)
            wk = dk / (fabs(k) + 1e-3);
        assert_true(dth < (IS_F ? 1e-4 : 1e-12));
    }
    *worst_gap = wg;
    *worst_k = wk;
}

static void test_paper_reproduction(void **state)
{
    (void)state;
    lsm_geom c[3];
    paper_contour(c, LSM_GEOM_PLANE_XY);
    lsm_g2path_report r;
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, 6, 50, 500, g_out, CAP, &r), LSM_OK);
    print_message("6 segments: deviation from the polygon %.4f mm, from the contour %.4f mm, c_max %.5f, kappa_max "
                  "%.5f, feed limits %.1f / %.1f mm/min\n",
                  (double)r.dev_chord_mm, (double)r.dev_mm, (double)r.sharpness_max_per_mm2, (double)r.kappa_max_per_mm,
                  60 * (double)r.feed_jerk_mm_s, 60 * (double)r.feed_acc_mm_s);
    const double rt = IS_F ? 1e-3 : 5e-4; /* NOTES.md gives 3-4 digits */
    assert_true(fabs(r.dev_chord_mm - 0.945) < rt * 0.945 + 0.0005);
    assert_true(fabs(r.sharpness_max_per_mm2 - 0.00817) < 0.000005 + rt * 0.00817);
    assert_true(fabs(60 * r.feed_jerk_mm_s - 2364) < 1.0);
    assert_true(fabs(60 * r.feed_acc_mm_s - 1275) < 1.0);
    assert_true(r.dev_mm > r.dev_chord_mm); /* the contour bulges out of the polygon at mid-arc */
    /* the paper's Fig. 5 is symmetric: c of clothoid j equals -c of clothoid 5 - j */
    for (int j = 0; j < 3; j++)
        assert_true(fabs(g_out[j].c_per_mm2 + g_out[5 - j].c_per_mm2) < (IS_F ? 1e-6 : 1e-12));
    assert_true(fabs(g_out[0].c_per_mm2) < (IS_F ? 1e-7 : 1e-14)); /* the first piece is straight */
    assert_true(r.end_gap_mm < (IS_F ? 1e-4 : 1e-10));

    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, 96, 50, 500, g_out, CAP, &r), LSM_OK);
    print_message("96 segments: deviation %.5f mm (polygon %.5f), c_max %.4f\n", (double)r.dev_mm,
                  (double)r.dev_chord_mm, (double)r.sharpness_max_per_mm2);
    assert_true(fabs(r.dev_mm - 0.0040) < 0.00005);
    assert_true(fabs(r.sharpness_max_per_mm2 - 0.1046) < 0.0005);
    double wg, wk;
    check_chain(96, &wg, &wk);
    assert_true(wg < (IS_F ? 1e-4 : 1e-10) && wk < (IS_F ? 1e-4 : 1e-9));

    /* the same in G18 */
    lsm_geom d[3];
    paper_contour(d, LSM_GEOM_PLANE_ZX);
    lsm_g2path_report r2;
    assert_int_equal(lsm_g2path_build(d, 3, LSM_GEOM_PLANE_ZX, 96, 50, 500, g_out, CAP, &r2), LSM_OK);
    assert_true(fabs(r2.dev_mm - r.dev_mm) < (IS_F ? 1e-5 : 1e-12) && fabs(r2.normal_mm - 7) < 1e-6);
    assert_true(fabs(r2.sharpness_max_per_mm2 - r.sharpness_max_per_mm2) < (IS_F ? 1e-4 : 1e-12));
}

static void test_scaling(void **state)
{
    (void)state;
    lsm_geom c[3];
    paper_contour(c, LSM_GEOM_PLANE_XY);
    double pd = 0, pc = 0;
    for (int n = 6; n <= 768; n *= 2) {
        lsm_g2path_report r;
        assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, n, 50, 500, g_out, CAP, &r), LSM_OK);
        double wg, wk;
        check_chain(n, &wg, &wk);
        assert_true(wg < (IS_F ? 2e-4 : 1e-10) && wk < (IS_F ? 1e-4 : 1e-9));
        if (pd > 0) {
            const double fd = pd / r.dev_mm, fc = r.sharpness_max_per_mm2 / pc;
            print_message("N %4d: deviation %.6f mm (/%.3f), c_max %.5f (x%.3f), feed limits %.0f / %.0f mm/min\n", n,
                          (double)r.dev_mm, fd, (double)r.sharpness_max_per_mm2, fc, 60 * (double)r.feed_jerk_mm_s,
                          60 * (double)r.feed_acc_mm_s);
            /* float: at N >= 384 the deviation (< 0.3 um) is within the rounding of 25 mm coordinates */
            if (!(IS_F && n >= 384))
                assert_true(fd > 3.7 && fd < 4.3);
            assert_true(fc > 1.55 && fc < 2.1);
            if (n >= 96)
                assert_true(fc > 1.9);
        }
        pd = r.dev_mm;
        pc = r.sharpness_max_per_mm2;
    }
}

static void test_auto(void **state)
{
    (void)state;
    lsm_geom c[3];
    paper_contour(c, LSM_GEOM_PLANE_XY);
    const double tols[] = {0.5, 0.05, 0.01, 0.001};
    for (size_t i = 0; i < sizeof tols / sizeof tols[0]; i++) {
        lsm_g2path_report r, r1;
        assert_int_equal(lsm_g2path_auto(c, 3, LSM_GEOM_PLANE_XY, tols[i], 50, 500, g_out, CAP, &r), LSM_OK);
        print_message("tolerance %.3f mm: N = %d, deviation %.6f mm, c_max %.4f, %d builds\n", tols[i], r.n_segments,
                      (double)r.dev_mm, (double)r.sharpness_max_per_mm2, r.builds);
        assert_true(r.dev_mm <= tols[i]);
        if (r.n_segments > 3) {
            assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, r.n_segments - 1, 50, 500, g_out, CAP, &r1),
                             LSM_OK);
            assert_true(r1.dev_mm > tols[i]);
        }
    }
    /* unreachable within the storage */
    lsm_g2path_report r;
    assert_int_equal(lsm_g2path_auto(c, 3, LSM_GEOM_PLANE_XY, 1e-7, 50, 500, g_out, 40, &r), LSM_E_TOL_UNREACHED);
    assert_true(r.n_segments == 40);
}

static void test_random_contours(void **state)
{
    (void)state;
    g_rng = 0x452821E638D01377ull ^ (uint64_t)g_seed;
    static lsm_geom c[8];
    double worst_g = 0, worst_k = 0;
    for (long n = 0; n < g_count; n++) {
        /* a chain of lines and arcs, each continuing tangentially or turning by up to 40 deg */
        double x = uni(-20, 20), y = uni(-20, 20), a = uni(-PI, PI);
        const int ne = 2 + (int)(urand() * 5);
        for (int i = 0; i < ne; i++) {
            if (urand() < 0.4)
                a += uni(-0.7, 0.7);
            const double len = uni(3, 30);
            if (urand() < 0.5) {
                assert_int_equal(line(&c[i], x, y, x + len * cos(a), y + len * sin(a)), LSM_OK);
                x += len * cos(a);
                y += len * sin(a);
            } else {
                const double r = uni(3, 40), turn = (urand() < 0.5 ? -1 : 1) * fmin(len / r, 2.0);
                const double s = turn > 0 ? 1 : -1;
                const double cx = x - s * sin(a) * r, cy = y + s * cos(a) * r;
                const double a0 = atan2(y - cy, x - cx), a1 = a0 + turn;
                const lsm_real st[3] = {(lsm_real)x, (lsm_real)y, 0};
                const lsm_real en[3] = {(lsm_real)(cx + r * cos(a1)), (lsm_real)(cy + r * sin(a1)), 0};
                const lsm_real ce[3] = {(lsm_real)cx, (lsm_real)cy, 0};
                assert_int_equal(lsm_geom_arc_init(&c[i], st, en, ce, LSM_GEOM_PLANE_XY, turn > 0 ? 1 : -1, 0), LSM_OK);
                lsm_real pe[LSM_MAX_AXES];
                lsm_geom_eval(&c[i], c[i].len, pe, NULL, NULL);
                x = pe[0];
                y = pe[1];
                a += turn;
            }
        }
        const int nseg = ne * (4 + (int)(urand() * 20));
        lsm_g2path_report r;
        const lsm_status st = lsm_g2path_build(c, ne, LSM_GEOM_PLANE_XY, nseg, 1000, 50000, g_out, CAP, &r);
        if (st != LSM_OK) {
            print_error("contour %ld (seed %lu): %d elements, %d segments: %s\n", n, g_seed, ne, nseg,
                        lsm_status_str(st));
            fail();
        }
        double wg, wk;
        check_chain(nseg, &wg, &wk);
        if (wg > worst_g)
            worst_g = wg;
        if (wk > worst_k)
            worst_k = wk;
        assert_true(wg < (IS_F ? 2e-4 : 1e-9) && wk < (IS_F ? 1e-4 : 1e-9));
        assert_true(r.end_gap_mm <= 2 * r.dev_mm + (IS_F ? 1e-4 : 1e-9)); /* on the end normal, near the contour */
    }
    print_message("random contours: worst joint gap %.3g mm, worst curvature jump %.3g (relative)\n", worst_g, worst_k);
}

static void test_bad_input(void **state)
{
    (void)state;
    lsm_geom c[3];
    paper_contour(c, LSM_GEOM_PLANE_XY);
    lsm_g2path_report r;
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, 6, (lsm_real)NAN, 500, g_out, CAP, &r), LSM_E_NAN);
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, 6, 50, (lsm_real)INFINITY, g_out, CAP, &r), LSM_E_INF);
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, 6, 0, 500, g_out, CAP, &r), LSM_E_LIMIT);
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, 6, 50, -1, g_out, CAP, &r), LSM_E_LIMIT);
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, 2, 50, 500, g_out, CAP, &r), LSM_E_ARG);
    assert_int_equal(lsm_g2path_build(c, 0, LSM_GEOM_PLANE_XY, 6, 50, 500, g_out, CAP, &r), LSM_E_ARG);
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_GENERAL, 6, 50, 500, g_out, CAP, &r), LSM_E_ARG);
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_XY, 6, 50, 500, g_out, 5, &r), LSM_E_FULL);
    assert_int_equal(lsm_g2path_build(NULL, 3, LSM_GEOM_PLANE_XY, 6, 50, 500, g_out, CAP, &r), LSM_E_NULL);
    assert_int_equal(lsm_g2path_auto(c, 3, LSM_GEOM_PLANE_XY, 0, 50, 500, g_out, CAP, &r), LSM_E_TOLERANCE);
    assert_int_equal(lsm_g2path_auto(c, 3, LSM_GEOM_PLANE_XY, (lsm_real)NAN, 50, 500, g_out, CAP, &r), LSM_E_NAN);
    /* the contour in the wrong plane, a gap, a cusp, rotary axes */
    assert_int_equal(lsm_g2path_build(c, 3, LSM_GEOM_PLANE_YZ, 6, 50, 500, g_out, CAP, &r), LSM_E_NONPLANAR);
    lsm_geom d[3];
    memcpy(d, c, sizeof d);
    assert_int_equal(line(&d[2], 25.5, 10.1, 25.5, 25.5), LSM_OK);
    assert_int_equal(lsm_g2path_build(d, 3, LSM_GEOM_PLANE_XY, 6, 50, 500, g_out, CAP, &r), LSM_E_GAP);
    assert_int_equal(line(&d[0], 0, 0, 10, 0), LSM_OK);
    assert_int_equal(line(&d[1], 10, 0, 0, 0), LSM_OK);
    assert_int_equal(lsm_g2path_build(d, 2, LSM_GEOM_PLANE_XY, 2, 50, 500, g_out, CAP, &r), LSM_E_REVERSAL);
    const lsm_real ra[6] = {0, 0, 0, 0, 0, 0}, rb[6] = {10, 0, 0, 1, 0, 0};
    assert_int_equal(lsm_geom_line_init(&d[0], ra, rb), LSM_OK);
    assert_int_equal(lsm_g2path_build(d, 1, LSM_GEOM_PLANE_XY, 2, 50, 500, g_out, CAP, &r), LSM_E_ROTARY);
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    gl_init();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_paper_reproduction), cmocka_unit_test(test_scaling),   cmocka_unit_test(test_auto),
        cmocka_unit_test(test_random_contours),    cmocka_unit_test(test_bad_input),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
