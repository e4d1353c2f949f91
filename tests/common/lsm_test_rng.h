/*
 * lsm_test_rng.h: the deterministic random numbers of the randomized tests (xorshift64*, the same sequence on
 * every platform), so that a failing [seed] reproduces anywhere. Header-only, for tests.
 */
#ifndef LSM_TEST_RNG_H
#define LSM_TEST_RNG_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

/* Uniform in [0, 1). */
static inline double test_urand(uint64_t *st)
{
    *st ^= *st >> 12;
    *st ^= *st << 25;
    *st ^= *st >> 27;
    return (double)((*st * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

/* Uniform in [lo, hi). */
static inline double test_uni(uint64_t *st, double lo, double hi)
{
    return lo + (hi - lo) * test_urand(st);
}

/* Log-uniform in [lo, hi). */
static inline double test_logu(uint64_t *st, double lo, double hi)
{
    return lo * pow(hi / lo, test_urand(st));
}

/* The randomized tests' command line, `test_x [seed] [count]`: each argument optional, a whole decimal number
 * (or 0x hex); anything else ends the test with status 2 and a message, so a mistyped soak never silently runs
 * the default. Returns the argument, or dflt when it is absent. */
static inline unsigned long long test_arg_u(int argc, char **argv, int k, unsigned long long dflt)
{
    if (argc <= k)
        return dflt;
    char *end = NULL;
    const unsigned long long v = strtoull(argv[k], &end, 0);
    if (end == argv[k] || *end != '\0' || argv[k][0] == '-') {
        fprintf(stderr, "%s: argument %d must be a non-negative whole number, not \"%s\" (usage: [seed] [count])\n",
                argv[0], k, argv[k]);
        exit(2);
    }
    return v;
}

/* The end of a randomized test's main: passes rc (cmocka_run_group_tests' result) through and, when a test
 * failed, prints the seed and count and the command that replays the run (the failing case's own message names
 * its index). */
static inline int test_seed_finish(const char *prog, unsigned long long seed, unsigned long long count, int rc)
{
    if (rc != 0)
        fprintf(stderr, "%s: %d failed with seed %llu, count %llu; replay: %s %llu %llu\n", prog, rc, seed, count, prog,
                seed, count);
    return rc;
}

#endif
