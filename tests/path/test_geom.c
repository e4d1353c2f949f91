/* test_geom.c: lsm_geom arcs from rounded CAM centres (the end lands exactly on the programmed point). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <math.h>

#include <cmocka.h>

#include "geom.h"
#include "lsm_test_geom.h"
#include "lsm_test_rng.h"

/* Distance from the arc's end (eval at len) to the programmed end, and the centre's shift. */
static double end_miss(const lsm_geom *g, const lsm_real end[3])
{
    lsm_real p[LSM_MAX_AXES] = {0};
    assert_int_equal(lsm_geom_eval(g, g->len, p, NULL, NULL), LSM_OK);
    double d2 = 0;
    for (int i = 0; i < 3; i++)
        d2 += ((double)p[i] - end[i]) * ((double)p[i] - end[i]);
    return sqrt(d2);
}

static void test_rounded_centre_quarter(void **state)
{
    (void)state;
    /* quarter circle R 10 about the origin, end radius 10.00002 (I J rounded) */
    const lsm_real s[3] = {10, 0, 0}, e[3] = {0, LSM_R(10.00002), 0}, c[3] = {0, 0, 0};
    lsm_geom g;
    assert_int_equal(lsm_geom_arc_init(&g, s, e, c, LSM_GEOM_PLANE_XY, 1, 0), LSM_OK);
    const double tol = LSM_REAL_IS_FLOAT ? 4e-5 : 1e-12;
    assert_true(end_miss(&g, e) <= tol);
    /* the start is still the start (phi0, radius) */
    lsm_real p[LSM_MAX_AXES] = {0};
    assert_int_equal(lsm_geom_eval(&g, 0, p, NULL, NULL), LSM_OK);
    assert_true(fabs((double)p[0] - 10) <= tol && fabs((double)p[1]) <= tol);
    /* the centre moved along the chord by (r2² - r1²) / (2 chord) = about 1.414e-5 */
    double gc[3];
    test_arc_centre(&g, gc);
    const double shift = hypot(gc[0], gc[1]);
    assert_true(shift > 1.2e-5 && shift < 1.6e-5);
}

static unsigned long long g_seed = 0, g_count = 20000; /* test_geom [seed] [count] */

static void test_rounded_centre_random(void **state)
{
    (void)state;
    uint64_t rng = 0x9e3779b97f4a7c15ull ^ (uint64_t)g_seed;
    const double tol_rel = LSM_REAL_IS_FLOAT ? 3e-6 : 1e-13;
    for (unsigned long long k = 0; k < g_count; k++) {
        const double R = test_logu(&rng, 0.1, 200), a0 = 6.283 * test_urand(&rng);
        const double sw = 0.05 + 6.0 * test_urand(&rng), dir = test_urand(&rng) < 0.5 ? 1 : -1;
        const double cx = 400 * test_urand(&rng) - 200, cy = 400 * test_urand(&rng) - 200;
        const double q = 1e-4; /* CAM rounding of every coordinate (4 decimals) */
        lsm_real s[3] = {(lsm_real)(round((cx + R * cos(a0)) / q) * q), (lsm_real)(round((cy + R * sin(a0)) / q) * q),
                         0};
        lsm_real e[3] = {(lsm_real)(round((cx + R * cos(a0 + dir * sw)) / q) * q),
                         (lsm_real)(round((cy + R * sin(a0 + dir * sw)) / q) * q), 0};
        lsm_real c[3] = {(lsm_real)(round(cx / q) * q), (lsm_real)(round(cy / q) * q), 0};
        lsm_geom g;
        const lsm_status st = lsm_geom_arc_init(&g, s, e, c, LSM_GEOM_PLANE_XY, (int)dir, 0);
        if (st != LSM_OK) { /* only a radius too small to hold the rounding may be refused */
            if (st != LSM_E_ARC_GEOMETRY)
                fail_msg("arc %llu (seed %llu): status %d", k, g_seed, (int)st);
            continue;
        }
        const double chord = hypot((double)e[0] - s[0], (double)e[1] - s[1]);
        const double dr =
            fabs(hypot((double)e[0] - c[0], (double)e[1] - c[1]) - hypot((double)s[0] - c[0], (double)s[1] - c[1]));
        const double shift = dr * (2 * R) / (2 * (chord > 0 ? chord : 1e-300));
        const double miss = end_miss(&g, e);
        /* corrected: exact to rounding; kept: off by at most the radius mismatch */
        const double allowed = (shift <= 0.9 * LSM_GEOM_ARC_TOL_MM ? 0 : dr) + tol_rel * (R + 300);
        if (!(miss <= allowed))
            fail_msg("arc %llu (seed %llu): end missed by %.3g mm > %.3g (R %.6g, shift %.3g)", k, g_seed, miss,
                     allowed, R, shift);
    }
}

/* lsm_geom_moves_rotary: a line with an A, B or C component (also a rotary-only one), never an arc. */
static void test_moves_rotary(void **state)
{
    (void)state;
    const lsm_real p0[LSM_MAX_AXES] = {0, 0, 0, 0, 0, 0};
    lsm_geom g;
    for (int ax = 0; ax < LSM_MAX_AXES; ax++) {
        lsm_real p1[LSM_MAX_AXES] = {0, 0, 0, 0, 0, 0};
        p1[ax] = LSM_R(2.0);
        assert_int_equal(lsm_geom_line_init(&g, p0, p1), LSM_OK);
        assert_int_equal(lsm_geom_moves_rotary(&g), ax >= 3);
        p1[0] = LSM_R(1.0); /* with a linear move too */
        assert_int_equal(lsm_geom_line_init(&g, p0, p1), LSM_OK);
        assert_int_equal(lsm_geom_moves_rotary(&g), ax >= 3);
    }
    const lsm_real s[3] = {10, 0, 0}, e[3] = {0, 10, 0}, c[3] = {0, 0, 0};
    assert_int_equal(lsm_geom_arc_init(&g, s, e, c, LSM_GEOM_PLANE_XY, 1, 0), LSM_OK);
    assert_false(lsm_geom_moves_rotary(&g));
}

int main(int argc, char **argv)
{
    g_seed = test_arg_u(argc, argv, 1, g_seed);
    g_count = test_arg_u(argc, argv, 2, g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rounded_centre_quarter),
        cmocka_unit_test(test_rounded_centre_random),
        cmocka_unit_test(test_moves_rotary),
    };
    return test_seed_finish(argv[0], g_seed, g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
