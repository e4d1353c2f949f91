/*
 * lsm_test_quad.h: the reference quadrature of the path tests: Gauss-Legendre with GL_N nodes in long double
 * (nodes g_x and weights g_w on [-1, 1], found by Newton on the Legendre polynomial; gl_init() fills them).
 * Each test file that includes it gets its own copy of the tables.
 */
#ifndef LSM_TEST_QUAD_H
#define LSM_TEST_QUAD_H

#include <math.h>

#define GL_N 12
static long double g_x[GL_N], g_w[GL_N];

static inline void gl_init(void)
{
    for (int i = 0; i < GL_N; i++) {
        long double x = cosl(3.14159265358979323846264L * (i + 0.75L) / (GL_N + 0.5L));
        long double dp = 0;
        for (int it = 0; it < 100; it++) {
            long double p0 = 1, p1 = x;
            for (int k = 2; k <= GL_N; k++) {
                long double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = GL_N * (x * p1 - p0) / (x * x - 1);
            long double dx = p1 / dp;
            x -= dx;
            if (fabsl(dx) < 1e-19L)
                break;
        }
        g_x[i] = x;
        g_w[i] = 2 / ((1 - x * x) * dp * dp);
    }
}

#endif
