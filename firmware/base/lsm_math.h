/*
 * lsm_math.h: the math functions of the core, bound to the real type chosen in lsm_config.h, and input checks.
 * Double: the C library. Float: sqrtf/floorf/ceilf/fabsf from the C library (exact-rounded or exact on every
 * target) and our own sin, cos, cbrt and atan2 (lsm_math.c), built from + - * / only, so that the float build
 * gives bit-identical results on the host and on the Cortex-M4F.
 */
#ifndef LSM_MATH_H
#define LSM_MATH_H

#include <math.h>

#include "lsm_config.h"

/* A function kept out of line: where GCC's -Os inlining (through link-time optimisation too) copies a function into
 * each of its callers although one shared copy is smaller (measured on the Cortex-M4F image, docs/cortex_m.md "Core
 * flash, out of line"; only background code, never the control cycle's). */
#if defined(__GNUC__)
#define LSM_NOINLINE __attribute__((noinline))
#else
#define LSM_NOINLINE
#endif

/* fabs and sqrt as compiler builtins where available: one VABS/VSQRT on the Cortex-M4F instead of a library
 * call of 10-20 instructions when the library names are not expanded inline. */
#if LSM_REAL_IS_FLOAT
#if defined(__GNUC__)
#define lsm_sqrt(x) __builtin_sqrtf(x)
#define lsm_fabs(x) __builtin_fabsf(x)
#else
#define lsm_sqrt sqrtf
#define lsm_fabs fabsf
#endif
#define lsm_cbrt lsm_math_cbrtf
#define lsm_floor floorf
#define lsm_ceil ceilf
#define lsm_sin(x) (lsm_math_sincos_pairf(x).s)
#define lsm_cos(x) (lsm_math_sincos_pairf(x).c)
#define lsm_atan2 lsm_math_atan2f
#define LSM_REAL_EPS 1.1920929e-7f
#define LSM_REAL_MAX 3.4028235e38f
#else
#if defined(__GNUC__)
#define lsm_sqrt(x) __builtin_sqrt(x)
#define lsm_fabs(x) __builtin_fabs(x)
#else
#define lsm_sqrt sqrt
#define lsm_fabs fabs
#endif
#define lsm_cbrt cbrt
#define lsm_floor floor
#define lsm_ceil ceil
#define lsm_sin sin
#define lsm_cos cos
#define lsm_atan2 atan2
#define LSM_REAL_EPS 2.220446049250313e-16
#define LSM_REAL_MAX 1.7976931348623157e308
#endif

/* sin and cos of x from one reduction (lsm_math.c): the kernel of every float sin and cos of the core. Const (no side
 * effects, the result depends on x only): GCC merges lsm_sin(x) and lsm_cos(x) of the same x into one call. A pair
 * of floats is returned in registers (s0, s1 on the Cortex-M4F). */
typedef struct lsm_math_sc {
    float s, c;
} lsm_math_sc;
#if defined(__GNUC__)
__attribute__((const))
#endif
lsm_math_sc
lsm_math_sincos_pairf(float x);

/* Deterministic single-precision functions (lsm_math.c); about 1-2 ulp. sin and cos are the halves of
 * lsm_math_sincos_pairf (the same bits). */
float lsm_math_sinf(float x);
float lsm_math_cosf(float x);
float lsm_math_cbrtf(float x);
float lsm_math_atan2f(float y, float x);

/* 0 if x is finite, else LSM_E_NAN / LSM_E_INF (as int, to keep this header free of status.h); lsm_math.c, out of line:
 * one copy for the core. */
int lsm_check_finite(lsm_real x);

/* a . b of 3-vectors (inline: it sits in the arc fit's per-point loops). */
static inline lsm_real lsm_dot3(const lsm_real a[3], const lsm_real b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* a x b of 3-vectors (lsm_math.c: one copy for the core instead of one per object). */
void lsm_cross3(const lsm_real a[3], const lsm_real b[3], lsm_real o[3]);

/* sin and cos of x at once through pointers (lsm_math_sincos_pairf's halves). */
void lsm_math_sincosf(float x, float *s_out, float *c_out);

/* sin and cos of x at once (float: one argument reduction for both). */
static inline void lsm_sincos(lsm_real x, lsm_real *s, lsm_real *c)
{
#if LSM_REAL_IS_FLOAT
    lsm_math_sincosf(x, s, c);
#else
    *s = sin(x);
    *c = cos(x);
#endif
}

static inline lsm_real lsm_min2(lsm_real a, lsm_real b)
{
    return a < b ? a : b;
}
static inline lsm_real lsm_max2(lsm_real a, lsm_real b)
{
    return a > b ? a : b;
}

#endif /* LSM_MATH_H */
