/*
 * test_lsm_math.c: the deterministic single-precision sin, cos, cbrt and atan2 (lsm_math.c) against double libm.
 * Error bound: 3 ulp of the result, or 2^-24 absolute near a zero of sin/cos (where ulp shrinks) over
 * |x| <= 1000 rad, and the special values. Both builds test the same float functions.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>

#include "lsm_math.h"
#include "lsm_test_rng.h"

static double ulp_err(float got, double want)
{
    const double u = fmax(fabs(want), FLT_MIN) * FLT_EPSILON; /* one ulp at want's binade, roughly */
    return fabs((double)got - want) / u;
}

static void test_sin_cos(void **state)
{
    (void)state;
    uint64_t st = 7;
    double worst_s = 0, worst_c = 0;
    for (int i = 0; i < 400000; i++) {
        const float x = (float)((test_urand(&st) * 2 - 1) * (i < 200000 ? 4.0 : 1000.0));
        const double s = sin((double)x), c = cos((double)x);
        const float gs = lsm_math_sinf(x), gc = lsm_math_cosf(x);
        const double es = fabs(s) > 1e-3 ? ulp_err(gs, s) : fabs((double)gs - s) / FLT_EPSILON;
        const double ec = fabs(c) > 1e-3 ? ulp_err(gc, c) : fabs((double)gc - c) / FLT_EPSILON;
        worst_s = fmax(worst_s, es);
        worst_c = fmax(worst_c, ec);
    }
    print_message("sin worst %.2f ulp, cos worst %.2f ulp\n", worst_s, worst_c);
    assert_true(worst_s <= 3 && worst_c <= 3);
    assert_true(lsm_math_sinf(0) == 0 && lsm_math_cosf(0) == 1);
    assert_true(isnan(lsm_math_sinf(NAN)) && isnan(lsm_math_cosf(INFINITY)));
}

/* lsm_math_sincosf: the same bits as lsm_math_sinf and lsm_math_cosf, in every quadrant and for NaN and inf. */
static void test_sincos_same_bits(void **state)
{
    (void)state;
    uint64_t st = 9;
    for (int i = 0; i < 200000; i++) {
        const float x = (float)((test_urand(&st) * 2 - 1) * (i < 100000 ? 8.0 : 1000.0));
        float s, c;
        lsm_math_sincosf(x, &s, &c);
        if (s != lsm_math_sinf(x) || c != lsm_math_cosf(x))
            fail_msg("x %.9g: sincos (%.9g, %.9g), sin %.9g, cos %.9g", (double)x, (double)s, (double)c,
                     (double)lsm_math_sinf(x), (double)lsm_math_cosf(x));
    }
    float s, c;
    lsm_math_sincosf(NAN, &s, &c);
    assert_true(isnan(s) && isnan(c));
    lsm_math_sincosf(-INFINITY, &s, &c);
    assert_true(isnan(s) && isnan(c));
}

static void test_cbrt(void **state)
{
    (void)state;
    uint64_t st = 11;
    double worst = 0;
    for (int i = 0; i < 400000; i++) {
        const float x = (float)((test_urand(&st) < 0.5 ? -1 : 1) * test_logu(&st, 1e-30, 1e30));
        worst = fmax(worst, ulp_err(lsm_math_cbrtf(x), cbrt((double)x)));
    }
    print_message("cbrt worst %.2f ulp\n", worst);
    assert_true(worst <= 3);
    assert_true(lsm_math_cbrtf(0) == 0 && lsm_math_cbrtf(27) == 3 && lsm_math_cbrtf(-8) == -2);
}

static void test_atan2(void **state)
{
    (void)state;
    uint64_t st = 13;
    double worst = 0;
    for (int i = 0; i < 400000; i++) {
        const float y = (float)((test_urand(&st) * 2 - 1) * test_logu(&st, 1e-6, 1e6));
        const float x = (float)((test_urand(&st) * 2 - 1) * test_logu(&st, 1e-6, 1e6));
        const double want = atan2((double)y, (double)x);
        worst = fmax(worst, fabs(want) > 1e-3 ? ulp_err(lsm_math_atan2f(y, x), want)
                                              : fabs((double)lsm_math_atan2f(y, x) - want) / FLT_EPSILON);
    }
    print_message("atan2 worst %.2f ulp\n", worst);
    assert_true(worst <= 3);
    assert_true(lsm_math_atan2f(0, 1) == 0 && lsm_math_atan2f(1, 0) > 1.5707f && lsm_math_atan2f(-1, 0) < -1.5707f);
    assert_true(fabs((double)lsm_math_atan2f(0, -1) - 3.14159265358979323846) < 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sin_cos),
        cmocka_unit_test(test_sincos_same_bits),
        cmocka_unit_test(test_cbrt),
        cmocka_unit_test(test_atan2),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
