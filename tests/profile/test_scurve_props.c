/*
 * test_scurve_props.c: seeded randomized properties of velocity changes, moves and the per-cycle evaluator.
 *
 *   test_scurve_props [seed] [count] [moves]   (default: seed 1, count 20000 velocity changes and sizings, moves
 *                                               count/8; the soak passes moves apart)
 *
 * Rule `strict` must hold, to a relative 1e-9 in double (2e-5 in float):
 *   |J| <= Jmax, |A| <= Amax, |snap| <= DJmax (sampled and analytic), v within [min, max] of the feeds and
 *   never above v_max, the velocity change / the move ends exactly (V(tp) = F; s(T) = D, final setpoint = D),
 *   the per-cycle evaluator (stepgen) matches the closed form at every cycle, and a move is reported
 *   infeasible only when the direct ramp v0 -> v1 alone is longer than D.
 * The strict sizing (and lsm_scurve_sizer) returns exactly what a scan of its whole candidate window returns.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include "lsm_test_rng.h"
#include <stdio.h>
#include <stdlib.h>

#include "lsm_math.h"
#include "move.h"
#include "stepgen.h"

#define REL_TOL (LSM_REAL_IS_FLOAT ? 2e-5 : 1e-9)
#define PI 3.14159265358979323846

static unsigned long g_seed = 1;
static long g_count = 20000;
static long g_moves = -1; /* moves to draw; -1: g_count / 8 */

static uint64_t rng_state;
static double urand(void)
{
    return test_urand(&rng_state);
}
static double logu(double lo, double hi)
{
    return test_logu(&rng_state, lo, hi);
}

static const double k_cycles[5] = {0.00025, 0.0005, 0.001, 0.002, 0.004};

#define CHECK(cond, ...)                                     \
    do {                                                     \
        if (!(cond)) {                                       \
            print_error("case %ld (seed %lu): ", c, g_seed); \
            print_error(__VA_ARGS__);                        \
            print_error("\n");                               \
            fail();                                          \
        }                                                    \
    } while (0)

static void test_velocity_changes(void **state)
{
    (void)state;
    rng_state = 0x9E3779B97F4A7C15ull ^ (uint64_t)g_seed;
    for (long c = 0; c < g_count; c++) {
        const double A = logu(10, 20000), J = logu(100, 2e6), DJ = logu(1e3, 1e9);
        const double dt = k_cycles[(int)(urand() * 5) % 5];
        const double v0 = urand() < 0.2 ? 0 : logu(0.01, 500), v1 = urand() < 0.2 ? 0 : logu(0.01, 500);
        lsm_scurve_limits lim = {(lsm_real)A, (lsm_real)J, (lsm_real)DJ};
        lsm_scurve sc;
        lsm_scurve_info inf;
        lsm_status st =
            lsm_scurve_plan(&sc, &lim, (lsm_real)dt, (lsm_real)v0, (lsm_real)v1, LSM_SCURVE_RULE_STRICT, &inf);
        if (st == LSM_E_TOO_LONG)
            continue; /* more than 2^28 cycles: legitimately refused */
        CHECK(st == LSM_OK, "plan failed %d", (int)st);
        const double jp = fabs((double)sc.jp_mm_s3);
        const double t1 = sc.iv.n1_cycles * dt, t2 = sc.iv.n2_cycles * dt;
        const double vlo = fmin((lsm_real)v0, (lsm_real)v1), vhi = fmax((lsm_real)v0, (lsm_real)v1);
        if (vhi == vlo)
            continue;
        CHECK(jp <= J * (1 + REL_TOL), "J_P %.17g > %.17g", jp, J);
        CHECK(jp * (t1 + t2) <= A * (1 + REL_TOL), "A_P %.17g > %.17g", jp * (t1 + t2), A);
        CHECK(jp * PI / (2 * t1) <= DJ * (1 + REL_TOL), "snap %.17g > %.17g", jp * PI / (2 * t1), DJ);
        /* sampled: each cycle and each quarter cycle; snap by central differences (they underestimate a sine peak) */
        const uint32_t n = lsm_scurve_total_cycles(&sc.iv);
        const uint32_t stride = n > 100 ? n / 100 : 1;
        for (uint32_t k = 0; k <= n; k += stride) {
            for (int q = 0; q < 4; q++) {
                const double t = (k + q / 4.0) * dt;
                lsm_kin kin;
                lsm_scurve_eval_cycle(&sc, k, (lsm_real)(q / 4.0), &kin);
                CHECK(fabs(kin.j_mm_s3) <= J * (1 + REL_TOL), "|J| %.17g > %.17g at t %g", (double)kin.j_mm_s3, J, t);
                CHECK(fabs(kin.a_mm_s2) <= A * (1 + REL_TOL), "|A| %.17g > %.17g at t %g", (double)kin.a_mm_s2, A, t);
                CHECK(kin.v_mm_s >= vlo - REL_TOL * vhi && kin.v_mm_s <= vhi * (1 + REL_TOL),
                      "V %.17g outside [%g, %g]", (double)kin.v_mm_s, vlo, vhi);
            }
            if (!LSM_REAL_IS_FLOAT && k < n) {
                const double t = (k + 0.5) * dt, h = dt * 1e-3;
                lsm_kin a, b;
                (void)t;
                lsm_scurve_eval_cycle(&sc, k, (lsm_real)(0.5 - 1e-3), &a);
                lsm_scurve_eval_cycle(&sc, k, (lsm_real)(0.5 + 1e-3), &b);
                const double snap = fabs(b.j_mm_s3 - a.j_mm_s3) / (2 * h);
                CHECK(snap <= DJ * (1 + 1e-6), "sampled snap %.17g > %.17g", snap, DJ);
            }
        }
        lsm_kin e;
        lsm_scurve_eval_cycle(&sc, n, 0, &e);
        CHECK(fabs(e.v_mm_s - (lsm_real)v1) <= REL_TOL * vhi, "end V %.17g != %.17g", (double)e.v_mm_s, v1);
        CHECK(fabs(e.a_mm_s2) <= REL_TOL * A && fabs(e.j_mm_s3) <= REL_TOL * J, "end A %.9g / J %.9g not zero (n %u)",
              (double)e.a_mm_s2, (double)e.j_mm_s3, n);
    }
}

/* One random move request: 1..6 axes; single-axis moves get random feeds. */
static void random_request(lsm_move_request *r)
{
    r->n_axes = (uint8_t)(1 + (int)(urand() * 6) % 6);
    r->cycle_s = (lsm_real)k_cycles[(int)(urand() * 5) % 5];
    r->rule = LSM_SCURVE_RULE_STRICT;
    for (unsigned i = 0; i < r->n_axes; i++) {
        r->lim[i].v_max_mm_s = (lsm_real)logu(5, 2000);
        r->lim[i].a_max_mm_s2 = (lsm_real)logu(50, 20000);
        r->lim[i].j_max_mm_s3 = (lsm_real)logu(500, 2e6);
        r->lim[i].snap_max_mm_s4 = (lsm_real)logu(1e4, 1e9);
        const double d = urand() < 0.1 ? 0 : logu(1e-3, 1000);
        r->distance_mm[i] = (lsm_real)(urand() < 0.5 ? -d : d);
        r->v0_mm_s[i] = r->v1_mm_s[i] = 0;
    }
    if (r->distance_mm[0] == 0)
        r->distance_mm[0] = (lsm_real)logu(1e-3, 1000);
    if (r->n_axes == 1 && urand() < 0.6) {
        r->v0_mm_s[0] = urand() < 0.3 ? 0 : (lsm_real)(urand() * r->lim[0].v_max_mm_s);
        r->v1_mm_s[0] = urand() < 0.3 ? 0 : (lsm_real)(urand() * r->lim[0].v_max_mm_s);
    }
}

static double ax_dir(double d)
{
    return d < 0 ? -1 : 1;
}

/* Independent search for an exact whole-cycle single-axis profile (ramp, cruise, ramp) within the limits. */
static bool brute_force_exact(const lsm_move_request *r)
{
    const lsm_axis_limits *L = &r->lim[0];
    const lsm_scurve_limits sl = {L->a_max_mm_s2, L->j_max_mm_s3, L->snap_max_mm_s4};
    const double D = fabs((double)r->distance_mm[0]), v0 = r->v0_mm_s[0], v1 = r->v1_mm_s[0], dt = r->cycle_s;
    static const uint32_t ext[5] = {0, 1, 4, 16, 64};
    for (int a = 0; a <= 60; a++) {
        for (int b = 0; b <= 60; b++) {
            lsm_scurve_intervals ia0, id0;
            lsm_scurve_strict_intervals(&sl, r->cycle_s, (lsm_real)(L->v_max_mm_s * a / 60.0), &ia0);
            lsm_scurve_strict_intervals(&sl, r->cycle_s, (lsm_real)(L->v_max_mm_s * b / 60.0), &id0);
            for (int ka = 0; ka < 5; ka++) {
                for (int kd = 0; kd < 5; kd++) {
                    lsm_scurve_intervals ia = ia0, id = id0;
                    if ((ext[ka] && !ia.n1_cycles) || (ext[kd] && !id.n1_cycles))
                        continue;
                    ia.n4_cycles += ext[ka];
                    id.n4_cycles += ext[kd];
                    const double ta = lsm_scurve_total_cycles(&ia) * dt, td = lsm_scurve_total_cycles(&id) * dt;
                    const double num = D - v0 * ta / 2 - v1 * td / 2;
                    for (int nc = 0; nc <= 400 && num > 0; nc++) {
                        const double den = ta / 2 + nc * dt + td / 2, vc = num / den;
                        if (den > 0 && vc <= L->v_max_mm_s &&
                            lsm_scurve_fits(&sl, r->cycle_s, &ia, (lsm_real)(vc - v0)) &&
                            lsm_scurve_fits(&sl, r->cycle_s, &id, (lsm_real)(vc - v1)))
                            return true;
                    }
                }
            }
        }
    }
    return false;
}

/* One axis of a move, evaluated as lsm_move_eval_cycle does (the phase that holds cycle k + frac, advanced from its
 * start state), with every phase's start state computed once (lsm_move_phase_starts) instead of at each call. The
 * chains of phase ends are the same, so the result is the same bit for bit: test_moves compares the two on a sample
 * of cycles. The dense limit checks use this one, so that a sample of a long move costs one phase advance. */
typedef struct axis_eval {
    lsm_phase ph[LSM_MOVE_PHASES];
    lsm_kin st[LSM_MOVE_PHASES];
} axis_eval;

static void axis_eval_init(axis_eval *e, const lsm_move *mv, unsigned axis)
{
    lsm_move_phases(mv, axis, e->ph);
    lsm_move_phase_starts(mv, axis, e->st);
}

static void axis_eval_cycle(const axis_eval *e, const lsm_move *mv, unsigned axis, uint32_t k, lsm_real frac,
                            lsm_kin *out)
{
    const lsm_move_axis *ax = &mv->axis[axis];
    if (k >= lsm_move_total_cycles(mv)) { /* the terminal state */
        lsm_move_eval_cycle(mv, axis, k, frac, out);
        return;
    }
    uint32_t m = k;
    unsigned p = 0;
    for (; p < LSM_MOVE_PHASES; p++) {
        if (e->ph[p].n_cycles == 0)
            continue;
        if (m < e->ph[p].n_cycles || (m == e->ph[p].n_cycles && frac == 0))
            break;
        m -= e->ph[p].n_cycles;
    }
    assert_true(p < LSM_MOVE_PHASES);
    lsm_phase_advance(&e->ph[p], mv->cycle_s, &e->st[p], ((lsm_real)m + frac) * mv->cycle_s, out);
    if (p == 7) /* the cruise: the planned feed (move.c, eval_phase) */
        out->v_mm_s = ax->vc_mm_s;
    out->s_mm *= ax->dir;
    out->v_mm_s *= ax->dir;
    out->a_mm_s2 *= ax->dir;
    out->j_mm_s3 *= ax->dir;
}

/* Every COMPARE_EVERY-th sample is also evaluated by lsm_move_eval_cycle and must be the same bit for bit. */
#define COMPARE_EVERY 61

static bool same_kin(const lsm_kin *a, const lsm_kin *b)
{
    return a->s_mm == b->s_mm && a->v_mm_s == b->v_mm_s && a->a_mm_s2 == b->a_mm_s2 && a->j_mm_s3 == b->j_mm_s3;
}

static void test_moves(void **state)
{
    (void)state;
    rng_state = 0xD1B54A32D192ED03ull ^ (uint64_t)g_seed;
    const long count = g_moves >= 0 ? g_moves : g_count / 8 > 0 ? g_count / 8 : 1;
    long infeasible = 0, planned = 0, quantised_out = 0, compared = 0;
    for (long c = 0; c < count; c++) {
        lsm_move_request r = {0};
        random_request(&r);
        lsm_move mv;
        lsm_status st = lsm_move_plan(&mv, &r);
        if (st == LSM_E_TOO_LONG)
            continue;
        if (st == LSM_E_INFEASIBLE) {
            /* only when the direct ramp v0 -> v1 is longer than the distance */
            lsm_scurve_limits sl = {r.lim[0].a_max_mm_s2, r.lim[0].j_max_mm_s3, r.lim[0].snap_max_mm_s4};
            lsm_scurve sc;
            CHECK(r.n_axes == 1, "multi-axis move from rest reported infeasible");
            CHECK(lsm_scurve_plan(&sc, &sl, r.cycle_s, r.v0_mm_s[0], r.v1_mm_s[0], LSM_SCURVE_RULE_STRICT, NULL) ==
                      LSM_OK,
                  "direct ramp");
            /* Either the direct ramp alone is longer than D, or no whole-cycle profile of this family lands on
             * D within the limits. The second is checked independently by brute force: ramp intervals from a
             * dense grid of targets, each also stretched at T4, and every cruise length up to 400 cycles. */
            const double direct = lsm_scurve_distance_mm(&sc), D = fabs((double)r.distance_mm[0]);
            if (direct <= D * (1 - 1e-6)) {
                CHECK(!brute_force_exact(&r),
                      "refused, but a whole-cycle profile exists: lissom-sim move --distance %.17g "
                      "--v0 %.17g --v1 %.17g --vmax %.17g --amax %.17g --jmax %.17g --snap-max %.17g --cycle %.17g",
                      (double)r.distance_mm[0], (double)r.v0_mm_s[0], (double)r.v1_mm_s[0], (double)r.lim[0].v_max_mm_s,
                      (double)r.lim[0].a_max_mm_s2, (double)r.lim[0].j_max_mm_s3, (double)r.lim[0].snap_max_mm_s4,
                      (double)r.cycle_s);
                quantised_out++;
            }
            infeasible++;
            continue;
        }
        CHECK(st == LSM_OK, "move plan failed %d", (int)st);
        planned++;
        const uint32_t n = lsm_move_total_cycles(&mv);
        const double dt = r.cycle_s;
        lsm_stepgen g;
        assert_int_equal(lsm_stepgen_init(&g, &mv, NULL), LSM_OK);
        const uint32_t stride = n > 3000 ? n / 3000 : 1;
        lsm_real pos[LSM_MAX_AXES];
        double max_gen_err = 0;
        axis_eval ev[LSM_MAX_AXES];
        for (unsigned i = 0; i < r.n_axes; i++)
            axis_eval_init(&ev[i], &mv, i);
        unsigned long sample = 0;
        for (uint32_t k = 1; k <= n; k++) {
            const bool more = lsm_stepgen_next(&g, pos);
            CHECK(more == (k < n), "stepgen ended at %u of %u", k, n);
            if (k % stride && k + 2 < n)
                continue; /* compare on a stride (and the last cycles); the generator itself runs every cycle */
            for (unsigned i = 0; i < r.n_axes; i++) {
                const lsm_axis_limits *L = &r.lim[i];
                lsm_kin kin;
                axis_eval_cycle(&ev[i], &mv, i, k, 0, &kin);
                if (sample++ % COMPARE_EVERY == 0) {
                    lsm_kin ref;
                    lsm_move_eval_cycle(&mv, i, k, 0, &ref);
                    CHECK(same_kin(&kin, &ref), "cached evaluation differs from lsm_move_eval_cycle at k %u axis %u", k,
                          i);
                    compared++;
                }
                const double scale = fabs((double)r.distance_mm[i]) + L->v_max_mm_s * dt;
                const double err = fabs((double)pos[i] - (double)kin.s_mm);
                if (err > max_gen_err)
                    max_gen_err = err;
                CHECK(err <= (LSM_REAL_IS_FLOAT ? 1e-5 : 1e-9) * scale,
                      "stepgen %.17g vs closed form %.17g at k %u axis %u", (double)pos[i], (double)kin.s_mm, k, i);
                for (int q = 0; q < 2; q++) {
                    axis_eval_cycle(&ev[i], &mv, i, k - 1, (lsm_real)(q ? 0.5 : 0.0), &kin);
                    CHECK(fabs(kin.v_mm_s) <= L->v_max_mm_s * (1 + REL_TOL), "axis %u v %.17g > %.17g", i,
                          (double)kin.v_mm_s, (double)L->v_max_mm_s);
                    CHECK(fabs(kin.a_mm_s2) <= L->a_max_mm_s2 * (1 + REL_TOL), "axis %u a %.17g > %.17g", i,
                          (double)kin.a_mm_s2, (double)L->a_max_mm_s2);
                    CHECK(fabs(kin.j_mm_s3) <= L->j_max_mm_s3 * (1 + REL_TOL), "axis %u j %.17g > %.17g", i,
                          (double)kin.j_mm_s3, (double)L->j_max_mm_s3);
                    CHECK(r.v0_mm_s[i] > 0 || r.v1_mm_s[i] > 0 ||
                              kin.v_mm_s * ax_dir(r.distance_mm[i]) >= -REL_TOL * L->v_max_mm_s,
                          "axis %u moves backwards (v %.9g at cycle %u+%d of %u; vmax %.6g vc %.6g D %.6g dt %g)", i,
                          (double)kin.v_mm_s, k - 1, q, n, (double)L->v_max_mm_s, (double)mv.axis[i].vc_mm_s,
                          (double)r.distance_mm[i], dt);
                }
            }
        }
        for (unsigned i = 0; i < r.n_axes; i++) {
            const lsm_axis_limits *L = &r.lim[i];
            const lsm_move_axis *ax = &mv.axis[i];
            /* analytic peaks of both ramps */
            const lsm_scurve_intervals *ivs[2] = {&mv.acc, &mv.dec};
            const double jps[2] = {fabs((double)ax->jp_acc_mm_s3), fabs((double)ax->jp_dec_mm_s3)};
            for (int h = 0; h < 2; h++) {
                if (ivs[h]->n1_cycles == 0)
                    continue;
                const double t1 = ivs[h]->n1_cycles * dt, t2 = ivs[h]->n2_cycles * dt;
                CHECK(jps[h] <= L->j_max_mm_s3 * (1 + REL_TOL), "axis %u ramp %d J_P", i, h);
                CHECK(jps[h] * (t1 + t2) <= L->a_max_mm_s2 * (1 + REL_TOL), "axis %u ramp %d A_P", i, h);
                CHECK(jps[h] * PI / (2 * t1) <= L->snap_max_mm_s4 * (1 + REL_TOL), "axis %u ramp %d snap", i, h);
            }
            CHECK(ax->vc_mm_s <= L->v_max_mm_s * (1 + REL_TOL), "axis %u vc above v_max", i);
            /* exact end: the closed form lands on D, and the last setpoint is D itself */
            const double D = r.distance_mm[i];
            CHECK(fabs((double)lsm_move_end_error_mm(&mv, i)) <= (LSM_REAL_IS_FLOAT ? 1e-5 : 1e-9) * (fabs(D) + 1),
                  "axis %u end error %.3g", i, (double)lsm_move_end_error_mm(&mv, i));
            CHECK(pos[i] == r.distance_mm[i], "axis %u final setpoint %.17g != %.17g", i, (double)pos[i], D);
            lsm_kin kin;
            lsm_move_eval_cycle(&mv, i, n, 0, &kin);
            CHECK(kin.s_mm == r.distance_mm[i] && kin.a_mm_s2 == 0 && kin.j_mm_s3 == 0, "terminal state");
        }
        /* synchronisation: from rest, the axes stay proportional (a straight line) */
        if (r.n_axes > 1) {
            lsm_kin k0;
            lsm_move_eval_cycle(&mv, 0, n / 3, 0, &k0);
            for (unsigned i = 1; i < r.n_axes; i++) {
                lsm_kin ki;
                lsm_move_eval_cycle(&mv, i, n / 3, 0, &ki);
                const double want = (double)k0.s_mm * r.distance_mm[i] / r.distance_mm[0];
                CHECK(fabs((double)ki.s_mm - want) <=
                          (LSM_REAL_IS_FLOAT ? 1e-4 : 1e-9) * (fabs((double)r.distance_mm[i]) + 1),
                      "axis %u off the line: %.17g vs %.17g", i, (double)ki.s_mm, want);
            }
        }
    }
    print_message("moves: %ld planned, %ld infeasible: %ld with v0/v1 too high for D, %ld with no exact whole-cycle "
                  "profile (confirmed by brute force); %ld samples compared with lsm_move_eval_cycle\n",
                  planned, infeasible, infeasible - quantised_out, quantised_out, compared);
    assert_true(planned == 0 || compared > 0);
    assert_true(count == 0 || planned > count / 2);
    assert_true(quantised_out * 100 <= planned); /* rare: under 1 % */
}

/*
 * Reference of the strict sizing: the whole 5 x 6 window around the continuous guide, every candidate with its
 * smallest n4, the first of the shortest (ties: the larger eq-34 denominator), as scurve.c scanned it before its
 * scan learned to skip candidates by lower bounds. The sizing (and the sizer) must return exactly this.
 */
static bool ref_within(const lsm_scurve_limits *lim, lsm_real t1, lsm_real t2, lsm_real den, lsm_real dv)
{
    const lsm_real jp = dv / den;
    return jp <= lim->j_max_mm_s3 && jp * (t1 + t2) <= lim->a_max_mm_s2 &&
           jp * (lsm_real)PI <= 2 * t1 * lim->snap_max_mm_s4;
}

static bool ref_min_n4(const lsm_scurve_limits *lim, lsm_real dt, lsm_real dv, uint32_t n1, uint32_t n2, uint32_t *n4)
{
    const lsm_real t1 = (lsm_real)n1 * dt, t2 = (lsm_real)n2 * dt, s12 = t1 + t2, den0 = s12 * (2 * t1 + t2);
    lsm_real cap = lim->j_max_mm_s3;
    cap = cap < lim->a_max_mm_s2 / (t1 + t2) ? cap : lim->a_max_mm_s2 / (t1 + t2);
    const lsm_real cs = 2 * t1 * lim->snap_max_mm_s4 / (lsm_real)PI;
    cap = cap < cs ? cap : cs;
    const lsm_real need = dv / cap;
    lsm_real k = 0;
    if (need > den0) {
        k = lsm_ceil((need - den0) / (s12 * dt));
        if (!(k < (lsm_real)0x10000000u))
            return false;
    }
    uint32_t n = (uint32_t)k;
    for (int g = 0; g < 4 && !ref_within(lim, t1, t2, s12 * (2 * t1 + t2 + (lsm_real)n * dt), dv); g++)
        n++;
    *n4 = n;
    return true;
}

static uint32_t ref_count(lsm_real x)
{
    if (!(x > 0))
        return 0;
    return x < (lsm_real)0x10000000u ? (uint32_t)x : 0x10000000u;
}

static bool ref_strict_intervals(const lsm_scurve_limits *lim, lsm_real dt, lsm_real dv, lsm_scurve_intervals *iv)
{
    iv->n1_cycles = iv->n2_cycles = iv->n4_cycles = 0;
    const lsm_real P = (lsm_real)PI, A = lim->a_max_mm_s2, J = lim->j_max_mm_s3, DJ = lim->snap_max_mm_s4;
    lsm_real t1c = P * J / (2 * DJ);
    const lsm_real t1a = lsm_sqrt(P * A / (2 * DJ));
    t1c = t1c < t1a ? t1c : t1a;
    const lsm_real xf = P * dv / (4 * DJ);
    const lsm_real t1f = lsm_cbrt(xf);
    t1c = t1c < t1f ? t1c : t1f;
    const lsm_real jc = 2 * t1c * DJ / P, t2a = A / jc - t1c;
    const lsm_real r = t1c * t1c / 4 + dv / jc;
    const lsm_real t2f = lsm_sqrt(r) - 3 * t1c / 2;
    lsm_real t2c = t2a < t2f ? t2a : t2f;
    t2c = t2c > 0 ? t2c : 0;
    const lsm_real y1 = t1c / dt + (lsm_real)0.5, y2 = t2c / dt + (lsm_real)0.5;
    const uint32_t c1 = ref_count(lsm_floor(y1)), c2 = ref_count(lsm_floor(y2));
    if (c1 >= 0x10000000u || c2 >= 0x10000000u)
        return false;
    const uint32_t n1_lo = c1 > 3 ? c1 - 2 : 1, n1_hi = c1 + 2, n2_lo = c2 > 2 ? c2 - 2 : 0, n2_hi = c2 + 2;
    uint32_t best_total = 0xFFFFFFFFu;
    lsm_real best_den = 0;
    bool found = false;
    for (uint32_t n1 = n1_lo; n1 <= n1_hi; n1++) {
        for (uint32_t k = 0; k <= n2_hi - n2_lo + 1; k++) {
            if (k > n2_hi - n2_lo && n2_lo == 0)
                break;
            const uint32_t n2 = k > n2_hi - n2_lo ? 0 : n2_lo + k;
            uint32_t n4;
            if (!ref_min_n4(lim, dt, dv, n1, n2, &n4))
                continue;
            const uint64_t total = 4ull * n1 + 2ull * n2 + n4;
            if (total >= 0x10000000u)
                continue;
            const lsm_scurve_intervals cand = {n1, n2, n4};
            const lsm_real den = lsm_scurve_jerk_den(&cand, dt);
            if (total < best_total || (total == best_total && den > best_den)) {
                best_total = (uint32_t)total;
                best_den = den;
                *iv = cand;
                found = true;
            }
        }
    }
    return found;
}

static void test_sizing_matches_window_scan(void **state)
{
    (void)state;
    rng_state = 0x8CB92BA72F3D8DD7ull ^ (uint64_t)g_seed;
    for (long c = 0; c < g_count; c++) {
        /* wide limits (every regime of eqs 25-37, counts from 1 to millions of cycles) */
        const lsm_scurve_limits lim = {(lsm_real)logu(1, 1e6), (lsm_real)logu(10, 1e8), (lsm_real)logu(10, 1e11)};
        const lsm_real dt = (lsm_real)(urand() < 0.3 ? logu(1e-5, 0.05) : k_cycles[(int)(urand() * 5) % 5]);
        const lsm_real dv = (lsm_real)logu(1e-6, 1e4);
        lsm_scurve_intervals got, want, via;
        const bool ok_got = lsm_scurve_strict_intervals(&lim, dt, dv, &got);
        const bool ok_want = ref_strict_intervals(&lim, dt, dv, &want);
        lsm_scurve_sizer sz;
        lsm_scurve_sizer_init(&sz, &lim, dt);
        const bool ok_via = lsm_scurve_sizer_intervals(&sz, dv, &via);
        CHECK(ok_got == ok_want && ok_via == ok_want, "overflow verdicts differ (%d %d %d)", ok_got, ok_want, ok_via);
        if (!ok_want)
            continue;
        CHECK(got.n1_cycles == want.n1_cycles && got.n2_cycles == want.n2_cycles && got.n4_cycles == want.n4_cycles,
              "sizing (%u %u %u) != window scan (%u %u %u): A %.17g J %.17g DJ %.17g dt %.17g dv %.17g", got.n1_cycles,
              got.n2_cycles, got.n4_cycles, want.n1_cycles, want.n2_cycles, want.n4_cycles, (double)lim.a_max_mm_s2,
              (double)lim.j_max_mm_s3, (double)lim.snap_max_mm_s4, (double)dt, (double)dv);
        CHECK(via.n1_cycles == got.n1_cycles && via.n2_cycles == got.n2_cycles && via.n4_cycles == got.n4_cycles,
              "sizer differs from lsm_scurve_strict_intervals");
    }
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    g_moves = argc > 3 ? (long)test_arg_u(argc, argv, 3, 0) : -1;
    print_message("seed %lu, count %ld, moves %ld\n", g_seed, g_count, g_moves >= 0 ? g_moves : g_count / 8);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_velocity_changes),
        cmocka_unit_test(test_moves),
        cmocka_unit_test(test_sizing_matches_window_scan),
    };
    const int rc = cmocka_run_group_tests(tests, NULL, NULL);
    if (rc != 0 && g_moves >= 0)
        fprintf(stderr, "%s: moves %ld (replay with it as the third argument)\n", argv[0], g_moves);
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, rc);
}
