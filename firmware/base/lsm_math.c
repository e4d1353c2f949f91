/*
 * lsm_math.c: deterministic single-precision sin, cos, cbrt and atan2 (lsm_math_*), built from + - * / only.
 *
 * Why: the float build must give bit-identical results on the host and on the Cortex-M4F (the image's setpoint
 * checksum is compared with the host's), but glibc and newlib round sinf/cosf/cbrtf differently on some inputs.
 * IEEE-754 makes + - * / and sqrt exact-rounded everywhere, and GCC in ISO C mode does not contract a*b+c into a
 * fused multiply-add, so these functions give the same bits on every target.
 * Method: Cody-Waite reduction by pi/2 with a three-part constant (exact for |x| < 2^15 pi/2), then the
 * classic Cephes minimax polynomials on [-pi/4, pi/4]; cbrt by an exponent-halving first guess and three
 * Newton steps; atan by the Cephes reduction to |t| <= tan(pi/8) and a degree-9 odd polynomial.
 * Accuracy (tests/base/test_lsm_math.c, against double libm): about 1-2 ulp over the ranges used by the core.
 * The double build keeps the C library (lsm_math.h). sin and cos are one kernel, lsm_math_sincos_pairf (both from one
 * reduction; lsm_math_sinf, lsm_math_cosf and lsm_math_sincosf are its halves): one copy in the image (flash), and
 * declared const in lsm_math.h, so that lsm_sin(x) and lsm_cos(x) of the same x in one function are one call.
 */
#include "lsm_math.h"

#include <string.h>

/* Out of line here, one copy for the whole core (a static function in each object that used it before: flash). */
void lsm_cross3(const lsm_real a[3], const lsm_real b[3], lsm_real o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

/* Inputs beyond this are passed through as they were before (NaN, inf and the largest finite floats): one test
 * |x| <= LSM_MATH_BIG_F (false for NaN) instead of three comparisons. */
#define LSM_MATH_BIG_F 3.0e38f
#if defined(__GNUC__)
#define LM_FABSF(x) __builtin_fabsf(x) /* one VABS on the Cortex-M4F */
#else
#define LM_FABSF(x) fabsf(x)
#endif
#define PIO2_F 1.5707963267948966f
#define PIO4_F 0.7853981633974483f

/* The kernels of lsm_math_sinf and lsm_math_cosf: Cody-Waite reduction by pi/2 (pi/2 in three parts, the first
 * two with trailing zero bits) and the Cephes polynomials on [-pi/4, pi/4]. */
static float lsm_math_sin_polyf(float r)
{
    const float z = r * r;
    return ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * r + r;
}

static float lsm_math_cos_polyf(float r)
{
    const float z = r * r;
    return ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z - 0.5f * z + 1.0f;
}

/* x = k pi/2 + r with |r| <= pi/4 (about); returns r and the quadrant k mod 4. */
static float lsm_math_reduce_pio2f(float x, unsigned *quadrant)
{
    const float kf = x * 0.636619772367581f;
    const float k = kf >= 0 ? (float)(int32_t)(kf + 0.5f) : -(float)(int32_t)(0.5f - kf);
    *quadrant = (unsigned)(int32_t)k & 3u;
    return ((x - k * 1.5703125f) - k * 4.837512969970703e-4f) - k * 7.549790126404332e-8f;
}

lsm_math_sc lsm_math_sincos_pairf(float x)
{
    lsm_math_sc o;
    if (!(LM_FABSF(x) <= LSM_MATH_BIG_F)) {
        o.s = o.c = x - x; /* NaN for NaN and inf (0 for the finite rest above LSM_MATH_BIG_F) */
        return o;
    }
    unsigned q;
    const float r = lsm_math_reduce_pio2f(x, &q);
    const float sp = lsm_math_sin_polyf(r), cp = lsm_math_cos_polyf(r);
    float sv = sp, cv = cp; /* quadrant 0 */
    if (q & 1u) {           /* 1: (cp, -sp); 3: (-cp, sp) */
        sv = cp;
        cv = -sp;
    }
    if (q & 2u) { /* 2: (-sp, -cp) */
        sv = -sv;
        cv = -cv;
    }
    o.s = sv;
    o.c = cv;
    return o;
}

/* The public single functions: the pair's halves (one kernel in the image instead of three). */
float lsm_math_sinf(float x)
{
    return lsm_math_sincos_pairf(x).s;
}

float lsm_math_cosf(float x)
{
    return lsm_math_sincos_pairf(x).c;
}

void lsm_math_sincosf(float x, float *s_out, float *c_out)
{
    const lsm_math_sc o = lsm_math_sincos_pairf(x);
    *s_out = o.s;
    *c_out = o.c;
}

float lsm_math_cbrtf(float x)
{
    if (x == 0 || !(LM_FABSF(x) <= LSM_MATH_BIG_F))
        return x;
    const float a = x < 0 ? -x : x;
    uint32_t bits;
    memcpy(&bits, &a, sizeof bits);
    bits = bits / 3u + 709921077u; /* a third of the exponent (and mantissa): within a few % of a^(1/3) */
    float y;
    memcpy(&y, &bits, sizeof y);
    for (int i = 0; i < 3; i++)
        y = y - (y * y * y - a) / (3.0f * y * y);
    return x < 0 ? -y : y;
}

static float atan_pos(float a) /* a >= 0 */
{
    float base = 0;
    if (a > 2.414213562373095f) {
        base = PIO2_F;
        a = -1.0f / a;
    } else if (a > 0.4142135623730950f) {
        base = PIO4_F;
        a = (a - 1.0f) / (a + 1.0f);
    }
    const float z = a * a;
    return base +
           ((((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * a +
            a);
}

float lsm_math_atan2f(float y, float x)
{
    if (x != x || y != y)
        return x + y;
    if (x == 0) {
        if (y == 0)
            return 0; /* as atan2(+0, +0); the core never relies on the signed-zero cases */
        return y > 0 ? PIO2_F : -PIO2_F;
    }
    const float ay = y < 0 ? -y : y, ax = x < 0 ? -x : x;
    float t;
    if (ax >= ay)
        t = atan_pos(ay / ax);
    else
        t = PIO2_F - atan_pos(ax / ay);
    if (x < 0)
        t = 2 * PIO2_F - t;
    return y < 0 ? -t : t;
}

LSM_NOINLINE int lsm_check_finite(lsm_real x)
{
    if (x - x == LSM_R(0.0)) /* x - x is 0 for every finite x, NaN for NaN and +-inf: one test, no constant */
        return 0;
    return x != x ? -2 /* LSM_E_NAN */ : -3 /* LSM_E_INF */;
}
