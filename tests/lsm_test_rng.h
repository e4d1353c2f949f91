/*
 * lsm_test_rng.h: the deterministic random numbers of the randomized tests (xorshift64*, the same sequence on
 * every platform), so that a failing [seed] reproduces anywhere. Header-only, for tests.
 */
#ifndef LSM_TEST_RNG_H
#define LSM_TEST_RNG_H

#include <math.h>
#include <stdint.h>

/* Uniform in [0, 1). */
static inline double test_urand(uint64_t *st)
{
    *st ^= *st >> 12;
    *st ^= *st << 25;
    *st ^= *st >> 27;
    return (double)((*st * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

/* Log-uniform in [lo, hi). */
static inline double test_logu(uint64_t *st, double lo, double hi)
{
    return lo * pow(hi / lo, test_urand(st));
}

#endif
