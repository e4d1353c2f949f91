/*
 * test_move_complete.c: lsm_move_plan (move.h) is complete on short single-axis moves between feeds: whenever a
 * whole-cycle plan exists (ramp v0 -> vc, cruise at vc, ramp vc -> v1, every interval whole cycles, each ramp's
 * J_P corrected by eq 34 so that the distance and the end feed are met exactly, every limit held), it plans one.
 *
 * The feasibility is decided independently by brute force over the two ramps' interval totals Ta, Td (cycles):
 *   - the capacity C(T) of a total: the largest velocity change any intervals (n1 >= 1, n2, n4) of total
 *     4 n1 + 2 n2 + n4 = T make within the limits, from this file's own closed form
 *       C(T) = max over n1, n2 of min(J, A / s, 2 t1 DJ / pi) s (T dt - t1 - s),   t1 = n1 dt, s = (n1 + n2) dt
 *     (eq 34's denominator is s (2 t1 + t2 + t4) = s (T dt - t1 - s); the jerk cap is eqs 10, 16, 22);
 *   - for each pair (Ta, Td) the cruise feed of nc cruise cycles is vc = (2 D / dt - v0 Ta - v1 Td) / (Ta + Td + 2 nc)
 *     (eq (1) of move.h in cycles), decreasing in nc; the pair works if some nc >= 0 puts vc in
 *     [v0 - C(Ta), v0 + C(Ta)] n [v1 - C(Td), v1 + C(Td)] n (0, v_max].
 *   The domain: Ta <= TA and Td <= TD, the totals that make any velocity change from v0 (to v1) to a feed in
 *   [0, v_max]; every nc. A witness must hold with a relative margin MARGIN (capacities shrunk, v_max lowered, vc
 *   kept above MARGIN v_max), so that a verdict never rests on the last ulps; the witness's intervals are checked
 *   with the public lsm_scurve_fits (the checker's own closed form against scurve.c).
 * Moves: one axis, v0, v1 > 0, D too short for a cruise at v_max (below the two ramps via v_max), often close to
 * the direct ramp v0 -> v1 (where quantisation leaves the fewest exact shapes), some below it (a descent through a
 * feed below v1 can still land). Limits and cycles as test_scurve_props; ramps to v_max of at most MAX_TOTAL cycles
 * (the brute force is cubic in that).
 * For every feasible move: LSM_OK, both ramps within the limits (analytic peaks), vc in (0, v_max], the end exact.
 * It also reports how many plans take longer than the brute force's shortest (not asserted: the planner's shape is
 * the largest peak's, which is not always the shortest whole-cycle one).
 *   test_move_complete [seed] [count]   (default seed 1, 600 moves)
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>

#include "lsm_test_rng.h"
#include "move.h"

#define PI 3.14159265358979323846
#define REL_TOL (LSM_REAL_IS_FLOAT ? 2e-5 : 1e-9)
/* A witness holds with this relative margin (float: the planner's own rounding of vc and of the capacities). */
#define MARGIN (LSM_REAL_IS_FLOAT ? 1e-4 : 1e-9)
/* Largest ramp total considered (cycles): the capacity table is cubic in it. */
#define MAX_TOTAL 160

static unsigned long long g_seed = 1; /* argv[1] */
static long g_count = 600;            /* argv[2] */

static const double k_cycles[5] = {0.00025, 0.0005, 0.001, 0.002, 0.004};

typedef struct cap_table {
    double cap[MAX_TOTAL + 1];                /* C(T), mm/s */
    lsm_scurve_intervals best[MAX_TOTAL + 1]; /* intervals reaching it */
} cap_table;

static void fill_caps(cap_table *t, double A, double J, double DJ, double dt)
{
    for (uint32_t T = 0; T <= MAX_TOTAL; T++) {
        t->cap[T] = 0;
        t->best[T] = (lsm_scurve_intervals){0, 0, 0};
        for (uint32_t n1 = 1; 4 * n1 <= T; n1++) {
            for (uint32_t n2 = 0; 4 * n1 + 2 * n2 <= T; n2++) {
                const double t1 = n1 * dt, s = (n1 + n2) * dt;
                double jx = fmin(J, 2 * t1 * DJ / PI);
                jx = fmin(jx, A / s);
                const double c = jx * s * (T * dt - t1 - s);
                if (c > t->cap[T]) {
                    t->cap[T] = c;
                    t->best[T] = (lsm_scurve_intervals){n1, n2, T - 4 * n1 - 2 * n2};
                }
            }
        }
    }
}

/* The smallest total whose capacity reaches dv (MAX_TOTAL + 1 if none). */
static uint32_t min_total(const cap_table *t, double dv)
{
    if (dv <= 0)
        return 0;
    for (uint32_t T = 0; T <= MAX_TOTAL; T++)
        if (t->cap[T] >= dv)
            return T;
    return MAX_TOTAL + 1;
}

typedef struct witness {
    bool found;
    uint32_t ta, td, nc;
    double vc;
} witness;

/* The shortest plan (Ta + Td + nc) of the domain, with the margin. */
static witness brute_force(const cap_table *t, double D, double v0, double v1, double vmax, double dt, uint32_t TA,
                           uint32_t TD)
{
    witness w = {false, 0, 0, 0, 0};
    const double d2 = 2 * D / dt;
    uint32_t best = UINT32_MAX;
    for (uint32_t ta = 4; ta <= TA; ta++) {
        const double ca = t->cap[ta] * (1 - MARGIN);
        for (uint32_t td = 4; td <= TD; td++) {
            const double cd = t->cap[td] * (1 - MARGIN);
            const double lo = fmax(fmax(v0 - ca, v1 - cd), MARGIN * vmax);
            const double hi = fmin(fmin(v0 + ca, v1 + cd), vmax * (1 - MARGIN));
            const double num = d2 - v0 * ta - v1 * td;
            if (lo > hi || !(num > 0))
                continue;
            /* vc = num / (ta + td + 2 nc) in [lo, hi] */
            const double nlo = fmax(ceil((num / hi - ta - td) / 2), 0);
            const double nhi = floor((num / lo - ta - td) / 2);
            for (double nc = nlo; nc <= nhi && nc < nlo + 3; nc++) { /* the edge's rounding: check the few first */
                const double vc = num / (ta + td + 2 * nc);
                if (!(vc >= lo && vc <= hi))
                    continue;
                if (ta + td + (uint32_t)nc < best) {
                    best = ta + td + (uint32_t)nc;
                    w = (witness){true, ta, td, (uint32_t)nc, vc};
                }
                break;
            }
        }
    }
    return w;
}

typedef struct short_move {
    lsm_move_request r;
    double D, v0, v1, vmax, dt;
    double direct; /* the direct ramp's distance (shortest total) */
    uint32_t TA, TD;
} short_move;

/* A random short move between feeds whose ramps fit the table (rejection sampling). */
static void random_short_move(uint64_t *rng, cap_table *t, short_move *m)
{
    for (;;) {
        lsm_move_request *r = &m->r;
        *r = (lsm_move_request){0};
        r->n_axes = 1;
        r->cycle_s = (lsm_real)k_cycles[(int)(test_urand(rng) * 5) % 5];
        r->rule = LSM_SCURVE_RULE_STRICT;
        lsm_axis_limits *L = &r->lim[0];
        L->v_max_mm_s = (lsm_real)test_logu(rng, 5, 2000);
        L->a_max_mm_s2 = (lsm_real)test_logu(rng, 50, 20000);
        L->j_max_mm_s3 = (lsm_real)test_logu(rng, 500, 2e6);
        L->snap_max_mm_s4 = (lsm_real)test_logu(rng, 1e4, 1e9);
        r->v0_mm_s[0] = (lsm_real)(test_uni(rng, 0.01, 1) * (double)L->v_max_mm_s);
        r->v1_mm_s[0] = (lsm_real)(test_uni(rng, 0.01, 1) * (double)L->v_max_mm_s);
        const lsm_scurve_limits sl = {L->a_max_mm_s2, L->j_max_mm_s3, L->snap_max_mm_s4};
        lsm_scurve_intervals iv;
        /* cheap rejection first: the public sizing's ramp to v_max is within a few cycles of the shortest */
        if (!lsm_scurve_strict_intervals(&sl, r->cycle_s, L->v_max_mm_s, &iv) ||
            lsm_scurve_total_cycles(&iv) > MAX_TOTAL - 8)
            continue;
        m->dt = r->cycle_s;
        m->vmax = L->v_max_mm_s;
        m->v0 = r->v0_mm_s[0];
        m->v1 = r->v1_mm_s[0];
        fill_caps(t, L->a_max_mm_s2, L->j_max_mm_s3, L->snap_max_mm_s4, m->dt);
        m->TA = min_total(t, fmax(m->v0, m->vmax - m->v0));
        m->TD = min_total(t, fmax(m->v1, m->vmax - m->v1));
        if (m->TA > MAX_TOTAL || m->TD > MAX_TOTAL)
            continue;
        /* the distances of the direct ramp and of the two ramps via v_max (shortest totals) */
        const double direct = (m->v0 + m->v1) * min_total(t, fabs(m->v1 - m->v0)) * m->dt / 2;
        const double via_vmax =
            ((m->v0 + m->vmax) * min_total(t, m->vmax - m->v0) + (m->vmax + m->v1) * min_total(t, m->vmax - m->v1)) *
            m->dt / 2;
        if (!(via_vmax > direct))
            continue;
        const double u = test_urand(rng), pick = test_urand(rng);
        double D;
        if (pick < 0.15)
            D = direct * (0.5 + 0.5 * u); /* below the direct ramp */
        else if (pick < 0.6)
            D = direct + (via_vmax - direct) * u * u * u; /* close above it */
        else
            D = direct + (via_vmax - direct) * u;
        if (!(D > 0))
            continue;
        r->distance_mm[0] = (lsm_real)(test_urand(rng) < 0.5 ? -D : D);
        m->D = fabs((double)r->distance_mm[0]);
        m->direct = direct;
        return;
    }
}

static bool ramp_within(const lsm_scurve_intervals *iv, double jp, const lsm_axis_limits *L, double dt)
{
    if (iv->n1_cycles == 0)
        return jp == 0;
    const double t1 = iv->n1_cycles * dt, t2 = iv->n2_cycles * dt;
    return fabs(jp) <= L->j_max_mm_s3 * (1 + REL_TOL) && fabs(jp) * (t1 + t2) <= L->a_max_mm_s2 * (1 + REL_TOL) &&
           fabs(jp) * PI / (2 * t1) <= L->snap_max_mm_s4 * (1 + REL_TOL);
}

static void print_move(long c, const short_move *m)
{
    print_error("case %ld (seed %llu): lissom-sim move --distance %.17g --v0 %.17g --v1 %.17g --vmax %.17g --amax "
                "%.17g "
                "--jmax %.17g --snap-max %.17g --cycle %.17g\n",
                c, g_seed, (double)m->r.distance_mm[0], m->v0, m->v1, m->vmax, (double)m->r.lim[0].a_max_mm_s2,
                (double)m->r.lim[0].j_max_mm_s3, (double)m->r.lim[0].snap_max_mm_s4, m->dt);
}

/* A planned move keeps every limit and lands exactly; false (with a message) otherwise. */
static bool plan_ok(long c, const short_move *m, const lsm_move *mv)
{
    const lsm_move_axis *ax = &mv->axis[0];
    const lsm_axis_limits *L = &m->r.lim[0];
    const bool ramps =
        ramp_within(&mv->acc, ax->jp_acc_mm_s3, L, m->dt) && ramp_within(&mv->dec, ax->jp_dec_mm_s3, L, m->dt);
    const bool feed = ax->vc_mm_s > 0 && ax->vc_mm_s <= L->v_max_mm_s;
    const double err = fabs((double)lsm_move_end_error_mm(mv, 0));
    const bool exact = err <= (LSM_REAL_IS_FLOAT ? 1e-5 : 1e-9) * (m->D + 1);
    lsm_kin e;
    lsm_move_eval_cycle(mv, 0, lsm_move_total_cycles(mv), 0, &e);
    const double dir = m->r.distance_mm[0] < 0 ? -1 : 1;
    const bool end = e.s_mm == m->r.distance_mm[0] && (double)e.v_mm_s == dir * m->v1 && e.a_mm_s2 == 0;
    if (ramps && feed && exact && end)
        return true;
    print_move(c, m);
    print_error("  planned but ramps within %d, vc %.17g in (0, vmax] %d, end error %.3g, terminal %d\n", ramps,
                (double)ax->vc_mm_s, feed, err, end);
    return false;
}

static void test_feasible_short_moves_plan(void **state)
{
    (void)state;
    uint64_t rng = 0xA0761D6478BD642Full ^ (uint64_t)g_seed;
    static cap_table table;
    long feasible = 0, refused = 0, refused_below = 0, bad = 0, longer = 0, planned_outside = 0;
    uint32_t worst_extra = 0;
    for (long c = 0; c < g_count; c++) {
        short_move m;
        random_short_move(&rng, &table, &m);
        const witness w = brute_force(&table, m.D, m.v0, m.v1, m.vmax, m.dt, m.TA, m.TD);
        lsm_move mv;
        const lsm_status st = lsm_move_plan(&mv, &m.r);
        if (!w.found) {
            if (st == LSM_OK) {
                planned_outside++; /* a plan beyond the domain or within the margin: still within the limits */
                bad += !plan_ok(c, &m, &mv);
            }
            continue;
        }
        feasible++;
        /* the checker's closed form agrees with scurve.c on the witness */
        const lsm_scurve_limits sl = {m.r.lim[0].a_max_mm_s2, m.r.lim[0].j_max_mm_s3, m.r.lim[0].snap_max_mm_s4};
        if (!lsm_scurve_fits(&sl, m.r.cycle_s, &table.best[w.ta], (lsm_real)(w.vc - m.v0)) ||
            !lsm_scurve_fits(&sl, m.r.cycle_s, &table.best[w.td], (lsm_real)(w.vc - m.v1))) {
            print_move(c, &m);
            print_error("  checker: witness (%u, %u, %u) vc %.17g does not fit by lsm_scurve_fits\n", w.ta, w.td, w.nc,
                        w.vc);
            bad++;
            continue;
        }
        if (st != LSM_OK) {
            print_move(c, &m);
            print_error("  refused (%d) but feasible: ramp totals %u, %u, cruise %u cycles, vc %.17g\n", (int)st, w.ta,
                        w.td, w.nc, w.vc);
            refused++;
            refused_below += m.D < m.direct;
            continue;
        }
        bad += !plan_ok(c, &m, &mv);
        const uint32_t n = lsm_move_total_cycles(&mv), wn = w.ta + w.td + w.nc;
        if (n > wn) {
            longer++;
            worst_extra = n - wn > worst_extra ? n - wn : worst_extra;
        }
    }
    print_message("short moves: %ld, %ld feasible, %ld of them refused (%ld with D below the direct ramp's); %ld plans "
                  "with a limit or end wrong; %ld planned outside the brute force's domain; %ld plans longer than the "
                  "shortest (worst +%u cycles)\n",
                  g_count, feasible, refused, refused_below, bad, planned_outside, longer, worst_extra);
    assert_int_equal(refused, 0);
    assert_int_equal(bad, 0);
}

int main(int argc, char **argv)
{
    g_seed = test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_feasible_short_moves_plan),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
