/*
 * test_arcfit.c: arcs and lines through polyline runs (arcfit.h), double and float builds.
 *
 *   test_arcfit [seed] [count]   (default: seed 1, 400 runs per randomized case)
 *
 * - golden: the float ellipse run of test_planner_scale_float 17 60000 whose straight pair of 0.2 mm chords was no
 *   line (the last point's position along the chord came out an ulp beyond the chord's length, and the order slack
 *   was 1e-9, below float's eps): it became a lone segment with two tiny corners (a dip to 49 mm/s and a re-plan per
 *   appended arc while that node was in the buffer: the cost-flatness failure);
 * - random straight runs (2 to 8 points, 0.2 mm chords, any direction, coordinates to +-60 mm rounded to 0.1 um):
 *   always a line within the tolerance;
 * - random arcs (any plane, R 5 .. 200, 0.1 .. 0.3 mm chords, rounded to 0.1 um): the fit succeeds where its
 *   sagitta model is accurate, and the element it returns and the polyline are within the error bound it reports
 *   of each other (sampled both ways);
 * - the plane of a chain of arcs measured over its points (lsm_arcfit_chain) recovers a rounded ring's plane from a
 *   chain plane tilted by 1e-4 .. 3e-4 rad (random rings, a quarter turn);
 * - a given plane: lines projected into it, arcs refused beyond drift_mm (the line then closes the chain), line-only
 *   kinds, and after a line an arc whose plane holds it.
 * - every fitted element starts on p0 exactly (the random arcs, and golden: a fuzzed program's arc of R 480 from the
 *   origin, whose float start was C + r e1, 3e-5 mm off p0: a setpoint jump of 4e6 mm/s³ at the first cycle).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "arcfit.h"
#include "lsm_test_rng.h"

static unsigned long long g_seed = 1, g_count = 400;

#define TOL 0.01 /* the planner's fit tolerance with its defaults (fit_share 0.5 of G64 P0.02) */

/* ---------------------------------------------------------------------------------------------------------- */
/* distances                                                                                                   */

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* Distance from x to the segment a-b. */
static double seg_dist(const double x[3], const double a[3], const double b[3])
{
    double d[3], r[3], dd = 0, t = 0;
    for (int k = 0; k < 3; k++) {
        d[k] = b[k] - a[k];
        r[k] = x[k] - a[k];
        dd += d[k] * d[k];
        t += r[k] * d[k];
    }
    t = dd > 0 ? fmin(1.0, fmax(0.0, t / dd)) : 0.0;
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = a[k] + t * d[k];
    return dist3(x, c);
}

/* The polyline p0, q[0..n-1] as doubles. */
static void poly(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, double (*P)[3])
{
    for (int k = 0; k < 3; k++)
        P[0][k] = (double)p0[k];
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            P[i + 1][k] = (double)q[i].p[k];
}

#define SAMPLES 4000

/* Largest distance of the element from the polyline, and of the polyline (vertices and segment midpoints) from the
 * element, sampling the element at SAMPLES + 1 points (a sampling error of (len / SAMPLES)² / 8R is added to the
 * second by the caller's slack). */
static void both_ways(const lsm_geom *g, const double (*P)[3], int np, double *el_to_poly, double *poly_to_el)
{
    static double S[SAMPLES + 1][3];
    *el_to_poly = 0;
    for (int i = 0; i <= SAMPLES; i++) {
        lsm_real pos[LSM_MAX_AXES] = {0};
        assert_int_equal(lsm_geom_eval(g, g->len * (lsm_real)i / (lsm_real)SAMPLES, pos, NULL, NULL), LSM_OK);
        for (int k = 0; k < 3; k++)
            S[i][k] = (double)pos[k];
        double dmin = INFINITY;
        for (int j = 0; j + 1 < np; j++)
            dmin = fmin(dmin, seg_dist(S[i], P[j], P[j + 1]));
        *el_to_poly = fmax(*el_to_poly, dmin);
    }
    *poly_to_el = 0;
    for (int j = 0; j < 2 * np - 1; j++) {
        double x[3];
        for (int k = 0; k < 3; k++)
            x[k] = j % 2 == 0 ? P[j / 2][k] : 0.5 * (P[j / 2][k] + P[j / 2 + 1][k]);
        double dmin = INFINITY;
        for (int i = 0; i < SAMPLES; i++)
            dmin = fmin(dmin, seg_dist(x, S[i], S[i + 1]));
        *poly_to_el = fmax(*poly_to_el, dmin);
    }
}

static double rnd4(double x)
{
    return round(x * 1e4) / 1e4; /* a G-code file's 0.1 um */
}

/* ---------------------------------------------------------------------------------------------------------- */
/* cases                                                                                                       */

/* The float ellipse's straight pair (test_planner_scale_float 17 60000, seq 51425-51426), after a fitted arc whose
 * plane was handed on: a line within tol / 4 (before the fix: no fit at all in the float build). */
static void test_float_straight_pair(void **state)
{
    (void)state;
    const lsm_real p0[3] = {LSM_R(-9.2979002), LSM_R(22.6646004), LSM_R(-4.5896001)};
    lsm_arcfit_pt q[2] = {{{LSM_R(-9.4898996), LSM_R(22.6089001), LSM_R(-4.5896001)}, 1},
                          {{LSM_R(-9.6816998), LSM_R(22.5522995), LSM_R(-4.5896001)}, 2}};
    const lsm_arcfit_plane nz = {{0, 0, 1}, 0, LSM_ARCFIT_PLANE_NORMAL};
    for (int with_plane = 0; with_plane < 2; with_plane++) {
        lsm_geom g;
        lsm_arcfit_result r;
        const bool ok = lsm_arcfit_fit(p0, q, 2, (lsm_real)TOL, with_plane ? &nz : NULL, &g, &r);
        if (!ok || r.kind != LSM_ARCFIT_LINE)
            print_message("FAILED straight pair (plane %d): ok %d kind %d\n", with_plane, ok, (int)r.kind);
        assert_true(ok);
        assert_int_equal(r.kind, LSM_ARCFIT_LINE);
        assert_true((double)r.err_mm <= TOL / 4);
    }
}

/* Starts exactly on p0: position at s = 0 (fuzz_gcode_path_float finding crash-1237252c, machine aniso, G64 P1.01:
 * `G1 X10.0341 Y0.0922 F2500` / `G1 X10.1033 Y0.2790` / `G1 X30.4475 Y1.2092` from the origin, fitted within
 * fit_share 0.5 of 1.01 mm as one arc of R 480; its float start was (-2.4e-7, 3.05e-5)). */
static void assert_starts_on(const lsm_geom *g, const lsm_real p0[3], const char *what)
{
    lsm_real pos[LSM_MAX_AXES] = {0};
    assert_int_equal(lsm_geom_eval(g, LSM_R(0.0), pos, NULL, NULL), LSM_OK);
    for (int k = 0; k < 3; k++)
        if (pos[k] != p0[k]) {
            print_message("FAILED %s: start axis %d %.17g != p0 %.17g (seed %llu)\n", what, k, (double)pos[k],
                          (double)p0[k], g_seed);
            fail();
        }
}

static void test_arc_starts_on_p0(void **state)
{
    (void)state;
    const lsm_real p0[3] = {0, 0, 0};
    const lsm_arcfit_pt q[3] = {{{LSM_R(10.0341), LSM_R(0.0922), 0}, 1},
                                {{LSM_R(10.1033), LSM_R(0.2790), 0}, 2},
                                {{LSM_R(30.4475), LSM_R(1.2092), 0}, 3}};
    lsm_geom g;
    lsm_arcfit_result r;
    assert_true(lsm_arcfit_fit(p0, q, 3, LSM_R(0.505), NULL, &g, &r));
    assert_int_equal(r.kind, LSM_ARCFIT_ARC);
    assert_true((double)r.radius_mm > 100.0); /* a large radius: float ulp(r) is far above ulp of the start */
    assert_starts_on(&g, p0, "golden R 480 arc");
}

/* Random straight runs: always a line. */
static void test_straight_runs_random(void **state)
{
    (void)state;
    uint64_t rs = g_seed * 0x9E3779B97F4A7C15ull + 11u;
    for (unsigned long long c = 0; c < g_count; c++) {
        const int n = 2 + (int)(test_urand(&rs) * 7.0);
        const double th = test_uni(&rs, 0, 6.283185307179586), ph = test_uni(&rs, -1.5707963, 1.5707963);
        const double z_share = test_urand(&rs) < 0.5 ? 0.0 : 1.0; /* half of them in a plane z = const */
        const double u[3] = {cos(th) * cos(ph * z_share), sin(th) * cos(ph * z_share), sin(ph * z_share)};
        double a[3];
        for (int k = 0; k < 3; k++)
            a[k] = test_uni(&rs, -60, 60);
        lsm_real p0[3];
        lsm_arcfit_pt q[8];
        for (int k = 0; k < 3; k++)
            p0[k] = (lsm_real)rnd4(a[k]);
        for (int i = 0; i < n; i++) {
            for (int k = 0; k < 3; k++)
                q[i].p[k] = (lsm_real)rnd4(a[k] + 0.2 * (i + 1) * u[k]);
            q[i].seq = (uint32_t)i;
        }
        lsm_geom g;
        lsm_arcfit_result r;
        const bool ok = lsm_arcfit_fit(p0, q, n, (lsm_real)TOL, NULL, &g, &r);
        if (!ok || r.kind != LSM_ARCFIT_LINE)
            print_message("FAILED straight run %llu (seed %llu): %d points, ok %d kind %d\n", c, g_seed, n, ok,
                          (int)r.kind);
        assert_true(ok);
        assert_int_equal(r.kind, LSM_ARCFIT_LINE);
    }
}

/* Random arcs in any plane: fitted, within the bound they report (both ways). */
static void test_arcs_random(void **state)
{
    (void)state;
    uint64_t rs = g_seed * 0x2545F4914F6CDD1Dull + 5u;
    /* float: an arc's evaluation error is about R eps (arcfit.h): keep the radii where float fits arcs */
    const double rmax = LSM_REAL_IS_FLOAT ? 30.0 : 200.0;
    int arcs = 0;
    for (unsigned long long c = 0; c < g_count; c++) {
        const double R = test_logu(&rs, 5.0, rmax), h = test_uni(&rs, 0.1, 0.3);
        const int n = 4 + (int)(test_urand(&rs) * (LSM_ARCFIT_MAX - 4));
        double e1[3], e2[3], ctr[3];
        const double th = test_uni(&rs, 0, 6.283185307179586), ph = test_uni(&rs, -1.5, 1.5);
        const double nrm[3] = {cos(th) * cos(ph), sin(th) * cos(ph), sin(ph)};
        const double t0[3] = {-sin(th), cos(th), 0};
        for (int k = 0; k < 3; k++)
            e1[k] = t0[k];
        e2[0] = nrm[1] * e1[2] - nrm[2] * e1[1];
        e2[1] = nrm[2] * e1[0] - nrm[0] * e1[2];
        e2[2] = nrm[0] * e1[1] - nrm[1] * e1[0];
        for (int k = 0; k < 3; k++)
            ctr[k] = test_uni(&rs, -30, 30);
        const double phi0 = test_uni(&rs, 0, 6.283185307179586), dphi = 2.0 * asin(h / (2.0 * R));
        const double sg = test_urand(&rs) < 0.5 ? 1.0 : -1.0;
        if (n * dphi > 3.0)
            continue; /* arcs span at most pi */
        lsm_real p0[3];
        lsm_arcfit_pt q[LSM_ARCFIT_MAX];
        for (int i = 0; i <= n; i++) {
            const double ph_i = phi0 + sg * dphi * i;
            for (int k = 0; k < 3; k++) {
                const double x = rnd4(ctr[k] + R * (cos(ph_i) * e1[k] + sin(ph_i) * e2[k]));
                if (i == 0)
                    p0[k] = (lsm_real)x;
                else
                    q[i - 1].p[k] = (lsm_real)x;
            }
            if (i > 0)
                q[i - 1].seq = (uint32_t)i;
        }
        lsm_geom g;
        lsm_arcfit_result r;
        const bool ok = lsm_arcfit_fit(p0, q, n, (lsm_real)TOL, NULL, &g, &r);
        /* the curvature comes from a parabola (sagitta model), off the circle by about L^4 / (128 R^3): where that
         * is well inside the tolerance the fit must succeed; elsewhere the run just ends earlier in the planner */
        const double L = 2.0 * R * sin(0.5 * n * dphi);
        if (!ok && L * L * L * L / (128.0 * R * R * R) < TOL / 10)
            print_message("FAILED arc %llu (seed %llu): R %.3f, %d chords of %.3f mm: no fit\n", c, g_seed, R, n, h);
        assert_true(ok || L * L * L * L / (128.0 * R * R * R) >= TOL / 10);
        if (!ok)
            continue;
        arcs += r.kind == LSM_ARCFIT_ARC;
        assert_starts_on(&g, p0, "random arc");
        double P[LSM_ARCFIT_MAX + 1][3];
        poly(p0, q, n, P);
        double a, b;
        both_ways(&g, (const double(*)[3])P, n + 1, &a, &b);
        /* slack: the sampling of the element (chord sagitta of a sample step), and the element's own evaluation
         * error (float: about R eps, and the coordinates' ulp) */
        const double step = (double)g.len / SAMPLES;
        const double slack = step * step / (8.0 * R) + (LSM_REAL_IS_FLOAT ? 2048.0 * 1.2e-7 * (R + 60.0) : 1e-9);
        if (!(a <= (double)r.err_mm + slack && b <= (double)r.err_mm + slack && (double)r.err_mm <= TOL))
            print_message("FAILED arc %llu (seed %llu): R %.3f, %d chords: err %.3g, element-polyline %.3g, "
                          "polyline-element %.3g (excess %.3g, %.3g)\n",
                          c, g_seed, R, n, (double)r.err_mm, a, b, a - (double)r.err_mm, b - (double)r.err_mm);
        assert_true((double)r.err_mm <= TOL);
        assert_true(a <= (double)r.err_mm + slack);
        assert_true(b <= (double)r.err_mm + slack);
    }
    print_message("arcs_random: %d of %llu fitted as arcs\n", arcs, g_count);
}

/* The angle between a unit vector and a unit normal, |a x b| (acos of the dot product cannot resolve float normals:
 * 6e-8 of rounding in the dot product is 3.5e-4 rad). */
static double angle_to(const lsm_real a[3], const double b[3])
{
    const double x[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    return sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
}

/* A ring in a tilted plane (normal nt), rounded to 0.1 um: point i of 0.2 mm chords from phase ph. */
static void ring_pt(const double c[3], const double e1[3], const double e2[3], double R, double ph, long i,
                    lsm_real out[3])
{
    const double a = ph + i * 2.0 * asin(0.1 / R);
    for (int k = 0; k < 3; k++)
        out[k] = (lsm_real)rnd4(c[k] + R * (cos(a) * e1[k] + sin(a) * e2[k]));
}

/* The chain's measured plane: a chain plane tilted by 1e-4 .. 3e-4 rad from a rounded ring's; over a quarter turn of
 * its points, lsm_arcfit_chain_plane recovers the ring's normal to the rounding (~1e-6 rad; the tilt itself, the
 * plane of one run's points, is what left the ring running as segments: test_planner_scale, test_ring3d_seeds). */
static void test_chain_plane_random(void **state)
{
    (void)state;
    uint64_t rs = g_seed * 0x61C8864680B583EBull + 3u;
    const unsigned long long count = g_count / 20 + 1;
    for (unsigned long long c = 0; c < count; c++) {
        const double R = test_uni(&rs, 10, LSM_REAL_IS_FLOAT ? 30 : 60), ph = test_uni(&rs, 0, 6.283185307179586);
        const double th = test_uni(&rs, 0, 6.283185307179586), tl = test_uni(&rs, 0.1, 1.4);
        const double nt[3] = {sin(tl) * cos(th), sin(tl) * sin(th), cos(tl)};
        double e1[3] = {-sin(th), cos(th), 0}, e2[3], ctr[3];
        e2[0] = nt[1] * e1[2] - nt[2] * e1[1];
        e2[1] = nt[2] * e1[0] - nt[0] * e1[2];
        e2[2] = nt[0] * e1[1] - nt[1] * e1[0];
        for (int k = 0; k < 3; k++)
            ctr[k] = test_uni(&rs, -20, 20);
        /* the chain's plane: nt tilted by 1e-4 .. 3e-4 about a random in-plane axis */
        const double tilt = test_uni(&rs, 1e-4, 3e-4), ax = test_uni(&rs, 0, 6.283185307179586);
        lsm_real nc[3];
        double nl = 0;
        for (int k = 0; k < 3; k++) {
            const double v = nt[k] + tilt * (cos(ax) * e1[k] + sin(ax) * e2[k]);
            nl += v * v;
        }
        for (int k = 0; k < 3; k++)
            nc[k] = (lsm_real)((nt[k] + tilt * (cos(ax) * e1[k] + sin(ax) * e2[k])) / sqrt(nl));
        lsm_arcfit_chain ch;
        lsm_real o[3];
        ring_pt(ctr, e1, e2, R, ph, 0, o);
        lsm_arcfit_chain_reset(&ch, o);
        const long quarter = (long)(0.25 * 6.283185307179586 * R / 0.2);
        for (long i = 1; i <= quarter; i++) {
            lsm_arcfit_pt q;
            ring_pt(ctr, e1, e2, R, ph, i, q.p);
            q.seq = (uint32_t)i;
            lsm_arcfit_chain_add(&ch, nc, &q, 1);
        }
        lsm_real nm[3];
        assert_true(lsm_arcfit_chain_plane(&ch, nc, nm));
        const double err = angle_to(nm, nt), err0 = angle_to(nc, nt);
        /* the measured plane keeps the ring within tol / 50 over its diameter (the rounding of the points: ~1e-6 rad
         * at R 15 over a quarter turn) */
        const double bound = TOL / 50.0 / (2.0 * R);
        if (!(err <= bound))
            print_message("FAILED chain plane %llu (seed %llu): R %.2f, chain plane off by %.3g rad, measured %.3g\n",
                          c, g_seed, R, err0, err);
        assert_true(err <= bound);
    }
}

/* In a given plane: a line ends on the last point's projection (its offset is part of the error), an arc is refused
 * once a point leaves the plane by more than drift_mm (a line then closes the chain: `drifted`), and the line-only
 * kinds give lines. */
static void test_given_plane(void **state)
{
    (void)state;
    /* a circle R 40 through p0 in the plane z = 0, the points rising off it (a tilt of 4e-4 rad about X) */
    const lsm_real p0[3] = {40, 0, 0};
    lsm_arcfit_pt q[24];
    for (int i = 0; i < 24; i++) {
        const double a = (i + 1) * 0.005;
        q[i].p[0] = (lsm_real)(40 * cos(a));
        q[i].p[1] = (lsm_real)(40 * sin(a));
        q[i].p[2] = (lsm_real)(40 * sin(a) * 4e-4); /* up to 1.9 um at the last point, 0.64 um at the 8th */
        q[i].seq = (uint32_t)i;
    }
    lsm_arcfit_plane pc = {{0, 0, 1}, (lsm_real)0.004, LSM_ARCFIT_PLANE_NORMAL};
    lsm_geom g;
    lsm_arcfit_result r;
    /* within drift 4 um: an arc in z = 0, ending off the last point by its height */
    assert_true(lsm_arcfit_fit(p0, q, 24, (lsm_real)TOL, &pc, &g, &r));
    assert_int_equal(r.kind, LSM_ARCFIT_ARC);
    assert_int_equal(r.drifted, 0);
    lsm_real e[LSM_MAX_AXES] = {0};
    assert_int_equal(lsm_geom_eval(&g, g.len, e, NULL, NULL), LSM_OK);
    assert_true(fabs((double)e[2] - (double)p0[2]) <= 1e-6);
    /* drift 0.5 um: no arc; the line in the plane closes the chain */
    pc.drift_mm = (lsm_real)0.0005;
    assert_true(lsm_arcfit_fit(p0, q, 8, (lsm_real)TOL, &pc, &g, &r));
    assert_int_equal(r.kind, LSM_ARCFIT_LINE);
    assert_int_equal(r.drifted, 1);
    assert_true(r.end_mm[2] == p0[2]); /* projected: z of p0 */
    assert_true((double)r.err_mm >= (double)q[7].p[2] - 1e-9 && (double)r.err_mm <= TOL);
    assert_true(fabs((double)g.u.line.dir[2]) <= 1e-12);
    /* line only, in the plane or free */
    pc.kind = LSM_ARCFIT_LINE_IN;
    assert_true(lsm_arcfit_fit(p0, q, 8, (lsm_real)TOL, &pc, &g, &r));
    assert_int_equal(r.kind, LSM_ARCFIT_LINE);
    assert_true(r.end_mm[2] == p0[2]);
    pc.kind = LSM_ARCFIT_LINE_FREE;
    assert_true(lsm_arcfit_fit(p0, q, 8, (lsm_real)TOL, &pc, &g, &r));
    assert_int_equal(r.kind, LSM_ARCFIT_LINE);
    assert_true(r.end_mm[0] == q[7].p[0] && r.end_mm[1] == q[7].p[1] && r.end_mm[2] == q[7].p[2]);
    assert_false(lsm_arcfit_fit(p0, q, 24, (lsm_real)TOL, &pc, &g, &r)); /* (no line within tol, and no arc) */
    /* after a line (its direction the chord to the first point, off the points' plane by their rounding-scale
     * rise): an arc whose plane holds that line */
    lsm_arcfit_plane pl = {{q[0].p[0] - p0[0], q[0].p[1] - p0[1], q[0].p[2] - p0[2] + (lsm_real)1e-5},
                           0,
                           LSM_ARCFIT_PLANE_CONTAINS};
    assert_true(lsm_arcfit_fit(p0, q, 24, (lsm_real)TOL, &pl, &g, &r));
    assert_int_equal(r.kind, LSM_ARCFIT_ARC);
    const double dl = sqrt((double)(pl.v[0] * pl.v[0] + pl.v[1] * pl.v[1] + pl.v[2] * pl.v[2]));
    const double dn = ((double)pl.v[0] * r.normal[0] + (double)pl.v[1] * r.normal[1] + (double)pl.v[2] * r.normal[2]);
    assert_true(fabs(dn) / dl <= (LSM_REAL_IS_FLOAT ? 1e-6 : 1e-12));
    assert_true((double)r.err_mm <= TOL);
}

int main(int argc, char **argv)
{
    g_seed = test_arg_u(argc, argv, 1, 1);
    g_count = test_arg_u(argc, argv, 2, 400);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_float_straight_pair), cmocka_unit_test(test_straight_runs_random),
        cmocka_unit_test(test_arcs_random),         cmocka_unit_test(test_chain_plane_random),
        cmocka_unit_test(test_given_plane),         cmocka_unit_test(test_arc_starts_on_p0),
    };
    return test_seed_finish(argv[0], g_seed, g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
