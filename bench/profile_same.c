/*
 * profile_same.c: compares the interval sizing and move planning of this tree (lsm_*) with those of a reference
 * revision (ref_lsm_*, the same sources of an older commit with their symbols renamed) on a large seeded random
 * set, bit for bit. Built and run by scripts/profile_same.sh REF [COUNT [SEED]]; a check for refactors of the
 * planner's speed, not a test of the plans themselves (tests/profile does that).
 *
 * Families (each COUNT cases; limits log-uniform, cycles 0.1-4 ms and random ones):
 *   strict    lsm_scurve_strict_intervals over wide limits and velocity changes (and lsm_scurve_plan, both rules)
 *   r2r       1-axis moves from rest to rest (the ranges of bench/ruckig_vs_move.cpp, snap loose or binding)
 *   feeds     1-axis moves with start and end feeds (the ranges of tests/profile/test_scurve_props.c)
 *   short     1-axis moves with feeds whose distance is within a few ramps of the direct ramp's (the fallback)
 *   sync      2-6 axes from rest, some still (test_scurve_props.c's random_request)
 *   paper     1-3 axes, the paper's rounding rule
 * Prints the number of differences per family and the first four of each (argv[3]: how many); exits 1 if any
 * differ.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "move.h"

bool ref_lsm_scurve_strict_intervals(const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real dv_mm_s,
                                     lsm_scurve_intervals *iv);
lsm_status ref_lsm_scurve_plan(lsm_scurve *out, const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real v0_mm_s,
                               lsm_real v1_mm_s, lsm_scurve_rule rule, lsm_scurve_info *info);
lsm_status ref_lsm_move_plan(lsm_move *mv, const lsm_move_request *req);

static uint64_t g_rng;
static double u01(void)
{
    g_rng ^= g_rng << 13;
    g_rng ^= g_rng >> 7;
    g_rng ^= g_rng << 17;
    return (double)(g_rng >> 11) / 9007199254740992.0;
}
static double logu(double lo, double hi)
{
    return lo * exp(log(hi / lo) * u01());
}
static double pick_cycle(void)
{
    static const double k[6] = {0.0001, 0.00025, 0.0005, 0.001, 0.002, 0.004};
    return u01() < 0.2 ? logu(1e-5, 0.05) : k[(int)(u01() * 6) % 6];
}

static long g_shown, g_show_max = 4; /* argv[3]: how many differences to print per family */
/* differing moves by their total cycles against the reference's: same, fewer, more; and status changes */
static long g_same_cycles, g_fewer_cycles, g_more_cycles, g_status_changed;
/* differing single-axis moves whose ramps are those of a fully converged bisection of the peak: this tree's, the
 * reference's, neither's */
static long g_bis_new, g_bis_ref, g_bis_none;

static bool iv_same(const lsm_scurve_intervals *a, const lsm_scurve_intervals *b)
{
    return a->n1_cycles == b->n1_cycles && a->n2_cycles == b->n2_cycles && a->n4_cycles == b->n4_cycles;
}

/* The ramps of the largest peak whose quantised ramps travel at most D: bisection to adjacent feeds. */
static void bisect_ramps(const lsm_move_request *r, lsm_scurve_intervals *acc, lsm_scurve_intervals *dec)
{
    const lsm_axis_limits *L = &r->lim[0];
    const lsm_scurve_limits sl = {L->a_max_mm_s2, L->j_max_mm_s3, L->snap_max_mm_s4};
    const lsm_real v0 = r->v0_mm_s[0], v1 = r->v1_mm_s[0], dt = r->cycle_s,
                   D = (lsm_real)fabs((double)r->distance_mm[0]);
    lsm_real lo = v0 > v1 ? v0 : v1, hi = L->v_max_mm_s;
    for (int i = -1; i < 400; i++) {
        const lsm_real mid = i < 0 ? hi : lo + (hi - lo) / 2;
        if (i >= 0 && !(mid > lo && mid < hi))
            break;
        lsm_scurve_strict_intervals(&sl, dt, (lsm_real)fabs((double)(mid - v0)), acc);
        lsm_scurve_strict_intervals(&sl, dt, (lsm_real)fabs((double)(mid - v1)), dec);
        const lsm_real d = ((v0 + mid) * (lsm_real)lsm_scurve_total_cycles(acc) +
                            (mid + v1) * (lsm_real)lsm_scurve_total_cycles(dec)) *
                           dt / 2;
        if (d <= D)
            lo = mid;
        else
            hi = mid;
        if (i < 0 && lo == hi)
            break;
    }
    lsm_scurve_strict_intervals(&sl, dt, (lsm_real)fabs((double)(lo - v0)), acc);
    lsm_scurve_strict_intervals(&sl, dt, (lsm_real)fabs((double)(lo - v1)), dec);
}
static void show(const char *fam, long c, const char *what)
{
    if (g_shown++ < g_show_max)
        printf("  %s case %ld: %s\n", fam, c, what);
}

static long family_strict(long count)
{
    long diff = 0;
    for (long c = 0; c < count; c++) {
        const lsm_scurve_limits lim = {(lsm_real)logu(1, 1e6), (lsm_real)logu(10, 1e8), (lsm_real)logu(10, 1e11)};
        const lsm_real dt = (lsm_real)pick_cycle();
        const lsm_real dv = (lsm_real)(u01() < 0.05 ? 0 : logu(1e-6, 1e4));
        lsm_scurve_intervals a, b;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        const bool ra = lsm_scurve_strict_intervals(&lim, dt, dv, &a);
        const bool rb = ref_lsm_scurve_strict_intervals(&lim, dt, dv, &b);
        if (ra != rb || (ra && memcmp(&a, &b, sizeof a))) {
            char s[200];
            snprintf(s, sizeof s, "A %.17g J %.17g DJ %.17g dt %.17g dv %.17g: (%u %u %u) vs ref (%u %u %u)",
                     (double)lim.a_max_mm_s2, (double)lim.j_max_mm_s3, (double)lim.snap_max_mm_s4, (double)dt,
                     (double)dv, a.n1_cycles, a.n2_cycles, a.n4_cycles, b.n1_cycles, b.n2_cycles, b.n4_cycles);
            show("strict", c, s);
            diff++;
            continue;
        }
        const lsm_real v0 = (lsm_real)(u01() < 0.3 ? 0 : logu(0.01, 1000));
        for (int rule = 0; rule < 2; rule++) {
            lsm_scurve sa, sb;
            lsm_scurve_info ia, ib;
            memset(&sa, 0, sizeof sa);
            memset(&sb, 0, sizeof sb);
            memset(&ia, 0, sizeof ia);
            memset(&ib, 0, sizeof ib);
            const lsm_status qa = lsm_scurve_plan(&sa, &lim, dt, v0, v0 + dv, (lsm_scurve_rule)rule, &ia);
            const lsm_status qb = ref_lsm_scurve_plan(&sb, &lim, dt, v0, v0 + dv, (lsm_scurve_rule)rule, &ib);
            if (qa != qb || memcmp(&sa, &sb, sizeof sa) || memcmp(&ia, &ib, sizeof ia)) {
                show("strict", c, rule ? "lsm_scurve_plan (paper rule)" : "lsm_scurve_plan (strict rule)");
                diff++;
                break;
            }
        }
    }
    return diff;
}

static void axis_limits(lsm_axis_limits *L, bool bench_ranges)
{
    L->v_max_mm_s = (lsm_real)logu(5, 2000);
    L->a_max_mm_s2 = (lsm_real)logu(50, 20000);
    L->j_max_mm_s3 = (lsm_real)logu(500, 2e6);
    if (bench_ranges) {
        const double dj_free = LSM_PI * (double)L->j_max_mm_s3 * (double)L->j_max_mm_s3 / (2 * (double)L->a_max_mm_s2);
        L->snap_max_mm_s4 = (lsm_real)(u01() < 0.5 ? dj_free * logu(1e-3, 0.3) : dj_free * logu(3, 100));
    } else {
        L->snap_max_mm_s4 = (lsm_real)logu(1e4, 1e9);
    }
}

static bool same_move(const lsm_move_request *r, const char *fam, long c)
{
    lsm_move a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    const lsm_status sa = lsm_move_plan(&a, r);
    const lsm_status sb = ref_lsm_move_plan(&b, r);
    if (sa == sb && (sa != LSM_OK || !memcmp(&a, &b, sizeof a)))
        return true;
    if (sa != sb) {
        g_status_changed++;
    } else {
        const uint32_t na = lsm_move_total_cycles(&a), nb = lsm_move_total_cycles(&b);
        if (na == nb)
            g_same_cycles++;
        else if (na < nb)
            g_fewer_cycles++;
        else
            g_more_cycles++;
        if (r->n_axes == 1 && r->rule == LSM_SCURVE_RULE_STRICT) {
            lsm_scurve_intervals acc, dec;
            bisect_ramps(r, &acc, &dec);
            if (iv_same(&a.acc, &acc) && iv_same(&a.dec, &dec))
                g_bis_new++;
            else if (iv_same(&b.acc, &acc) && iv_same(&b.dec, &dec))
                g_bis_ref++;
            else
                g_bis_none++;
        }
    }
    char s[400];
    snprintf(s, sizeof s,
             "status %d vs ref %d; acc (%u %u %u) vs (%u %u %u), dec (%u %u %u) vs (%u %u %u), nc %u vs %u; "
             "axis 0: D %.17g v0 %.17g v1 %.17g vmax %.17g a %.17g j %.17g snap %.17g dt %.17g",
             (int)sa, (int)sb, a.acc.n1_cycles, a.acc.n2_cycles, a.acc.n4_cycles, b.acc.n1_cycles, b.acc.n2_cycles,
             b.acc.n4_cycles, a.dec.n1_cycles, a.dec.n2_cycles, a.dec.n4_cycles, b.dec.n1_cycles, b.dec.n2_cycles,
             b.dec.n4_cycles, a.cruise_cycles, b.cruise_cycles, (double)r->distance_mm[0], (double)r->v0_mm_s[0],
             (double)r->v1_mm_s[0], (double)r->lim[0].v_max_mm_s, (double)r->lim[0].a_max_mm_s2,
             (double)r->lim[0].j_max_mm_s3, (double)r->lim[0].snap_max_mm_s4, (double)r->cycle_s);
    show(fam, c, s);
    return false;
}

static long family_moves(const char *fam, long count)
{
    long diff = 0;
    for (long c = 0; c < count; c++) {
        lsm_move_request r;
        memset(&r, 0, sizeof r);
        r.rule = LSM_SCURVE_RULE_STRICT;
        r.cycle_s = (lsm_real)pick_cycle();
        if (!strcmp(fam, "r2r")) {
            r.n_axes = 1;
            r.cycle_s = (lsm_real)(u01() < 0.5 ? 0.001 : r.cycle_s);
            axis_limits(&r.lim[0], true);
            r.distance_mm[0] = (lsm_real)(logu(1e-2, 1e3) * (u01() < 0.5 ? -1 : 1));
        } else if (!strcmp(fam, "feeds") || !strcmp(fam, "short")) {
            r.n_axes = 1;
            axis_limits(&r.lim[0], u01() < 0.5);
            const lsm_real vm = r.lim[0].v_max_mm_s;
            r.v0_mm_s[0] = (lsm_real)(u01() < 0.3 ? 0 : u01() * (double)vm);
            r.v1_mm_s[0] = (lsm_real)(u01() < 0.3 ? 0 : u01() * (double)vm);
            double d = logu(1e-3, 1000);
            if (!strcmp(fam, "short")) {
                /* the direct ramp's distance plus up to a few short ramps' travel */
                const lsm_scurve_limits sl = {r.lim[0].a_max_mm_s2, r.lim[0].j_max_mm_s3, r.lim[0].snap_max_mm_s4};
                lsm_scurve sc;
                if (lsm_scurve_plan(&sc, &sl, r.cycle_s, r.v0_mm_s[0], r.v1_mm_s[0], LSM_SCURVE_RULE_STRICT, NULL) !=
                    LSM_OK)
                    continue;
                d = (double)lsm_scurve_distance_mm(&sc) * (1 + logu(1e-6, 0.5));
                if (!(d > 0))
                    d = logu(1e-3, 1);
            }
            r.distance_mm[0] = (lsm_real)(u01() < 0.5 ? -d : d);
        } else {
            const bool paper = !strcmp(fam, "paper");
            r.n_axes = (uint8_t)(paper ? 1 + (int)(u01() * 3) % 3 : 2 + (int)(u01() * 5) % 5);
            r.rule = paper ? LSM_SCURVE_RULE_PAPER : LSM_SCURVE_RULE_STRICT;
            const bool bench = u01() < 0.5;
            for (unsigned i = 0; i < r.n_axes; i++) {
                axis_limits(&r.lim[i], bench);
                const double d = u01() < 0.1 ? 0 : logu(1e-3, 1000);
                r.distance_mm[i] = (lsm_real)(u01() < 0.5 ? -d : d);
            }
            if (r.distance_mm[0] == 0)
                r.distance_mm[0] = (lsm_real)logu(1e-3, 1000);
        }
        if (!same_move(&r, fam, c))
            diff++;
    }
    return diff;
}

int main(int argc, char **argv)
{
    const long count = argc > 1 ? atol(argv[1]) : 100000;
    const unsigned long long seed = argc > 2 ? strtoull(argv[2], NULL, 0) : 1;
    if (argc > 3)
        g_show_max = atol(argv[3]);
    g_rng = 0x9E3779B97F4A7C15ull ^ (seed * 0xD1B54A32D192ED03ull);
    if (!g_rng)
        g_rng = 1;
    long total = 0;
    printf("profile_same (%s), seed %llu, %ld cases per family\n", LSM_REAL_IS_FLOAT ? "float" : "double", seed, count);
    const long d0 = family_strict(count);
    printf("strict: %ld differ\n", d0);
    total += d0;
    static const char *const fams[] = {"r2r", "feeds", "short", "sync", "paper"};
    for (unsigned f = 0; f < sizeof fams / sizeof fams[0]; f++) {
        const long d = family_moves(fams[f], fams[f][0] == 's' && fams[f][1] == 'y' ? count / 4 : count);
        printf("%s: %ld differ (same cycles %ld, fewer %ld, more %ld, status %ld; single axis, the ramps of a "
               "converged "
               "bisection: this tree %ld, reference %ld, neither %ld)\n",
               fams[f], d, g_same_cycles, g_fewer_cycles, g_more_cycles, g_status_changed, g_bis_new, g_bis_ref,
               g_bis_none);
        g_same_cycles = g_fewer_cycles = g_more_cycles = g_status_changed = g_shown = 0;
        g_bis_new = g_bis_ref = g_bis_none = 0;
        total += d;
    }
    printf("total: %ld differ\n", total);
    return total ? 1 : 0;
}
