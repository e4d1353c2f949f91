/*
 * lissom-sim bench: host benchmark of the S-curve engine (a benchmark, not a test: numbers vary with the
 * machine; instruction counts on the Cortex-M4F come from scripts/arm_bench.sh).
 *   lissom-sim bench [--json] [--seconds S]
 * Reports ns per velocity-change plan (strict rule), per move plan (1 and 3 axes) and per cycle of the
 * per-cycle evaluator (1, 3 and 6 axes), with the real type in use.
 */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "commands.h"
#include "move.h"
#include "stepgen.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t rng = 88172645463325252ull;
static double u01(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static volatile double g_sink;

static double bench_scurve(double budget)
{
    const lsm_scurve_limits lim = {1570, 16000, 560000};
    long n = 0;
    double t0 = now_s(), t;
    do {
        for (int i = 0; i < 1000; i++, n++) {
            lsm_scurve sc;
            lsm_scurve_plan(&sc, &lim, (lsm_real)0.001, 0, (lsm_real)(1 + 300 * u01()), LSM_SCURVE_RULE_STRICT, NULL);
            g_sink += (double)sc.jp_mm_s3;
        }
        t = now_s() - t0;
    } while (t < budget);
    return 1e9 * t / (double)n;
}

static void request(lsm_move_request *r, unsigned axes)
{
    memset(r, 0, sizeof *r);
    r->n_axes = (uint8_t)axes;
    r->cycle_s = (lsm_real)0.001;
    for (unsigned i = 0; i < axes; i++) {
        r->distance_mm[i] = (lsm_real)(1 + 200 * u01());
        r->lim[i] = (lsm_axis_limits){200, 1570, 16000, 560000};
    }
}

static double bench_move(unsigned axes, double budget)
{
    long n = 0;
    double t0 = now_s(), t;
    do {
        for (int i = 0; i < 100; i++, n++) {
            lsm_move_request r;
            request(&r, axes);
            lsm_move mv;
            lsm_move_plan(&mv, &r);
            g_sink += (double)mv.axis[0].vc_mm_s;
        }
        t = now_s() - t0;
    } while (t < budget);
    return 1e9 * t / (double)n;
}

static double bench_cycle(unsigned axes, double budget)
{
    lsm_move_request r;
    request(&r, axes);
    for (unsigned i = 0; i < axes; i++)
        r.distance_mm[i] = (lsm_real)(300 + 10 * i);
    lsm_move mv;
    lsm_move_plan(&mv, &r);
    long n = 0;
    lsm_real pos[LSM_MAX_AXES];
    double t0 = now_s(), t;
    do {
        lsm_stepgen g;
        lsm_stepgen_init(&g, &mv, NULL);
        while (lsm_stepgen_next(&g, pos))
            n++;
        n++;
        g_sink += (double)pos[0];
        t = now_s() - t0;
    } while (t < budget);
    return 1e9 * t / (double)n;
}

int cmd_bench(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    double budget = 0.3;
    if (cli_num(&a, "seconds", &budget) < 0)
        return 2;
    const bool json = cli_flag(&a, "json");
    if (cli_check_unused(&a, "bench"))
        return 2;
    const double r[] = {bench_scurve(budget),   bench_move(1, budget),  bench_move(3, budget),
                        bench_cycle(1, budget), bench_cycle(3, budget), bench_cycle(6, budget)};
    const char *k[] = {"ns_per_scurve_plan", "ns_per_move_plan_1axis", "ns_per_move_plan_3axes",
                       "ns_per_cycle_1axis", "ns_per_cycle_3axes",     "ns_per_cycle_6axes"};
    if (json) {
        printf("{\"real\":\"%s\"", LSM_REAL_IS_FLOAT ? "float" : "double");
        for (int i = 0; i < 6; i++)
            printf(",\"%s\":%.1f", k[i], r[i]);
        printf("}\n");
    } else {
        printf("host benchmark (%s):\n", LSM_REAL_IS_FLOAT ? "float" : "double");
        for (int i = 0; i < 6; i++)
            printf("  %-24s %10.1f ns\n", k[i], r[i]);
    }
    return 0;
}
