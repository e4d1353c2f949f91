/*
 * test_plan_bounds.c: the per-block budget check of a ramp's sub-interval (plan_ramp.c, lsm_pl_block_ratios) is
 * sound: wherever it says a span holds (ra >= 1 and rj >= 1), every axis's continuous acceleration and jerk hold at
 * every point of the block and of the span's box of speeds, accelerations and jerks. Built twice (double, float).
 *
 *   test_plan_bounds [seed] [count]      (default: seed 1, count 400 programs)
 *
 * Each program appends random lines (corners blended within a random tolerance: clothoid pairs in tilted planes)
 * and arcs (G17/18/19, some helical) on a random machine (unequal X Y Z limits, path limits on some) and takes the
 * arcs and clothoids from the planner's own blocks (their real coefficients and caps). For each, random spans
 * (v in [vlo, vhi] below the cap, a and j in signed ranges, of one sign or across 0) are checked; the truth is
 * Beudaert eqs 2-3 on the exact derivatives of the block's geometry, evaluated in double,
 *     q_i'' = q_ss,i v² + q_s,i a,   q_i''' = q_sss,i v³ + 3 q_ss,i v a + q_s,i j,
 * sampled at the box's corners and at random points, at 33 points along the block. The test also counts the spans
 * that hold only by the Frenet-frame bounds of the clothoids (the magnitude budgets of the coefficients fail there),
 * and requires some: the cancellations of c v³ and 3 kappa v a, which the trident's tips use, are exercised.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "lsm_test_rng.h"
#include "planner.h"
#include "planner_int.h"
#include "lsm_test_path.h"

/* The check holds within this relative slack of the limits (the rounding of the test's own evaluation). */
#if LSM_REAL_IS_FLOAT
#define SLACK 2e-5
#else
#define SLACK 1e-9
#endif
#define CAP 64
#define SPANS_PER_BLOCK 40
#define POINTS_ALONG 33
#define BOX_SAMPLES 24

static unsigned long g_seed = 1;
static long g_count = 400;

/* The box of a sub-interval: v, a and j (signed) each in its range. */
typedef struct kspan {
    lsm_real vlo, vhi, alo, ahi, jlo, jhi;
} kspan;

typedef struct stats {
    long blocks, spans, held, held_by_frame;
} stats;

/* Exact q_s, q_ss, q_sss of an arc or clothoid at s (double). */
static void derivs(const lsm_geom *g, double s, double q1[3], double q2[3], double q3[3])
{
    if (g->kind == LSM_GEOM_ARC) {
        const lsm_geom_arc *a = &g->u.arc;
        const double w = (double)a->sweep_rad / (double)g->len, R = (double)a->radius_mm;
        const double ph = (double)a->phi0_rad + w * s, sp = sin(ph), cp = cos(ph);
        double n[3];
        n[0] = (double)a->e1[1] * (double)a->e2[2] - (double)a->e1[2] * (double)a->e2[1];
        n[1] = (double)a->e1[2] * (double)a->e2[0] - (double)a->e1[0] * (double)a->e2[2];
        n[2] = (double)a->e1[0] * (double)a->e2[1] - (double)a->e1[1] * (double)a->e2[0];
        const double ax = (double)a->axial_mm / (double)g->len;
        for (int i = 0; i < 3; i++) {
            const double e1 = (double)a->e1[i], e2 = (double)a->e2[i];
            q1[i] = R * w * (-sp * e1 + cp * e2) + n[i] * ax;
            q2[i] = -R * w * w * (cp * e1 + sp * e2);
            q3[i] = R * w * w * w * (sp * e1 - cp * e2);
        }
        return;
    }
    const lsm_geom_clothoid *c = &g->u.clo;
    const double k0 = (double)c->kappa0_per_mm, cc = (double)c->c_per_mm2;
    const double th = (double)c->theta0_rad + k0 * s + 0.5 * cc * s * s, k = k0 + cc * s;
    const double st = sin(th), ct = cos(th);
    for (int i = 0; i < 3; i++) {
        const double e1 = (double)c->e1[i], e2 = (double)c->e2[i];
        const double T = ct * e1 + st * e2, N = -st * e1 + ct * e2;
        q1[i] = T;
        q2[i] = k * N;
        q3[i] = cc * N - k * k * T;
    }
}

/* The magnitude budgets alone (the check before the Frenet-frame bounds): do a and j hold over the span? */
static int magnitude_holds(const lsm_pblock *b, const kspan *k)
{
    coef c;
    coef_get(b, &c);
    const double v = (double)k->vhi;
    const double am = fmax(fabs((double)k->alo), fabs((double)k->ahi));
    const double jm = fmax(fabs((double)k->jlo), fabs((double)k->jhi));
    const double acc = (double)c.ba * v * v + (double)c.aa * am;
    const double jerk = (double)c.gj * v * v * v + 3.0 * (double)c.bj * v * am + (double)c.aj * jm;
    return acc <= 1.0 && jerk <= 1.0;
}

/* One value of [lo, hi]: an end, or a random point. */
static double pick(uint64_t *st, double lo, double hi, int which)
{
    if (which == 0)
        return lo;
    if (which == 1)
        return hi;
    return test_uni(st, lo, hi);
}

/* Every axis's a and j (and the path limits) at the span's box points along the block; fails the test if the
 * check said the span holds and a point does not. */
static void check_truth(const lsm_planner *pl, const lsm_pblock *b, const kspan *k, uint64_t *st, long prog)
{
    const lsm_planner_config *cf = &pl->cfg;
    for (int p = 0; p < POINTS_ALONG; p++) {
        const double s = (double)b->g.len * p / (POINTS_ALONG - 1);
        double q1[3], q2[3], q3[3];
        derivs(&b->g, s, q1, q2, q3);
        for (int m = 0; m < BOX_SAMPLES; m++) {
            const double v = pick(st, (double)k->vlo, (double)k->vhi, m < 8 ? (m & 1) : 2);
            const double a = pick(st, (double)k->alo, (double)k->ahi, m < 8 ? ((m >> 1) & 1) : 2);
            const double j = pick(st, (double)k->jlo, (double)k->jhi, m < 8 ? ((m >> 2) & 1) : 2);
            double an2 = 0, jn2 = 0;
            for (int i = 0; i < 3; i++) {
                const double acc = q2[i] * v * v + q1[i] * a;
                const double jerk = q3[i] * v * v * v + 3.0 * q2[i] * v * a + q1[i] * j;
                an2 += acc * acc;
                jn2 += jerk * jerk;
                if (fabs(acc) > (double)cf->axis[i].a_max * (1.0 + SLACK) ||
                    fabs(jerk) > (double)cf->axis[i].j_max * (1.0 + SLACK))
                    fail_msg("program %ld: block kind %d len %.6g: axis %d a %.9g (A %.9g) j %.9g (J %.9g) at s %.6g "
                             "v %.9g a %.9g j %.9g; span v [%.9g, %.9g] a [%.9g, %.9g] j [%.9g, %.9g]",
                             prog, b->g.kind, (double)b->g.len, i, acc, (double)cf->axis[i].a_max, jerk,
                             (double)cf->axis[i].j_max, s, v, a, j, (double)k->vlo, (double)k->vhi, (double)k->alo,
                             (double)k->ahi, (double)k->jlo, (double)k->jhi);
            }
            if (cf->path_a_max_mm_s2 > 0 && sqrt(an2) > (double)cf->path_a_max_mm_s2 * (1.0 + SLACK))
                fail_msg("program %ld: block kind %d: path acceleration %.9g > %.9g (magnitude budgets hold: %d)", prog,
                         b->g.kind, sqrt(an2), (double)cf->path_a_max_mm_s2, magnitude_holds(b, k));
            if (cf->path_j_max_mm_s3 > 0 && sqrt(jn2) > (double)cf->path_j_max_mm_s3 * (1.0 + SLACK))
                fail_msg("program %ld: block kind %d: path jerk %.9g > %.9g at s %.6g v %.9g a %.9g j %.9g (magnitude "
                         "budgets hold: %d, cap %.9g)",
                         prog, b->g.kind, sqrt(jn2), (double)cf->path_j_max_mm_s3, s, v, a, j, magnitude_holds(b, k),
                         (double)b->cap_geo_mm_s);
        }
    }
}

/* A signed range [lo, hi] of magnitude up to mag: of one sign (either) or across 0. */
static void signed_range(uint64_t *st, double mag, lsm_real *lo, lsm_real *hi)
{
    const double x = test_uni(st, 0, mag), y = test_uni(st, 0, mag);
    const double r = test_urand(st);
    double l, h;
    if (r < 0.4) {
        l = fmin(x, y);
        h = fmax(x, y);
    } else if (r < 0.8) {
        l = -fmax(x, y);
        h = -fmin(x, y);
    } else {
        l = -x;
        h = y;
    }
    *lo = (lsm_real)l;
    *hi = (lsm_real)h;
}

static void check_block_spans(const lsm_planner *pl, uint32_t id, uint64_t *st, long prog, stats *sx)
{
    const lsm_pblock *b = lsm_planner_block(pl, id);
    sx->blocks++;
    const double cap = fmin((double)cap_of(pl, id), 1e4); /* (the feed too: check_span compares with it) */
    double amax = 0, jmax = 0;
    for (int i = 0; i < 3; i++) {
        amax = fmax(amax, (double)pl->cfg.axis[i].a_max);
        jmax = fmax(jmax, (double)pl->cfg.axis[i].j_max);
    }
    for (int n = 0; n < SPANS_PER_BLOCK; n++) {
        kspan k;
        const double vhi = cap * test_uni(st, 0.05, 1.0);
        k.vhi = (lsm_real)vhi;
        k.vlo = (lsm_real)(vhi * (test_urand(st) < 0.3 ? 1.0 : test_uni(st, 0.3, 1.0)));
        signed_range(st, test_logu(st, amax * 1e-3, amax * 2.0), &k.alo, &k.ahi);
        signed_range(st, test_logu(st, jmax * 1e-3, jmax * 2.0), &k.jlo, &k.jhi);
        const lsm_kin lo = {0, k.vlo, k.alo, k.jlo}, hi = {0, k.vhi, k.ahi, k.jhi};
        lsm_real ra, rj;
        lsm_pl_block_ratios(pl, id, &lo, &hi, &ra, &rj);
        sx->spans++;
        if (!(ra >= 1 && rj >= 1))
            continue;
        sx->held++;
        if (!magnitude_holds(b, &k))
            sx->held_by_frame++;
        check_truth(pl, b, &k, st, prog);
    }
}

/* Appends one random line or arc from p (updated to its end). */
static lsm_status append_one(lsm_planner *pl, uint64_t *st, double p[3])
{
    lsm_planner_move mv = {(lsm_real)test_logu(st, 5, 500), (lsm_real)test_logu(st, 1e-3, 0.2), 0, 0};
    if (test_urand(st) < 0.35)
        return test_append_random_arc(pl, st, p, 0.05, 30, 5.5, &mv);
    const double len = test_logu(st, 0.05, 20);
    double d[3] = {test_uni(st, -1, 1), test_uni(st, -1, 1), test_uni(st, -1, 1)};
    if (test_urand(st) < 0.5)
        d[2] = 0; /* planar corners too */
    const double n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(n > 1e-3))
        return LSM_E_ZERO_LENGTH;
    lsm_real e[LSM_MAX_AXES] = {0};
    for (int i = 0; i < 3; i++)
        e[i] = (lsm_real)(p[i] + len * d[i] / n);
    const lsm_status s = lsm_planner_append_line(pl, e, &mv);
    if (s == LSM_OK)
        for (int i = 0; i < 3; i++)
            p[i] = (double)e[i];
    return s;
}

/* The coefficients of a curved block bound its geometric derivatives per axis at every point (exact, double): alpha_a
 * |q_s,i| / A_i, beta_a |q_ss,i| / A_i, gamma_j |q_sss,i| / J_i (and with path limits the path's |q_ss|, |q_sss|).
 * gamma_j of a clothoid is the better of the magnitudes |c| |N_i| + kappa² |T_i| and the direction bound of
 * q_sss = c N - kappa² T (plan_block.c, clothoid_psi); this checks the latter where it is the tighter. */
static void check_coef_bounds(const lsm_planner *pl, uint32_t id, long prog, long *tighter)
{
    const lsm_pblock *b = lsm_planner_block(pl, id);
    const lsm_planner_config *cf = &pl->cfg;
    coef c;
    coef_get(b, &c);
    for (int p = 0; p < 4 * POINTS_ALONG; p++) {
        const double s = (double)b->g.len * p / (4 * POINTS_ALONG - 1);
        double q1[3], q2[3], q3[3];
        derivs(&b->g, s, q1, q2, q3);
        double n2 = 0, n3 = 0;
        for (int i = 0; i < 3; i++) {
            const double A = (double)cf->axis[i].a_max, J = (double)cf->axis[i].j_max;
            if (fabs(q1[i]) / A > (double)c.aa * (1.0 + SLACK) || fabs(q2[i]) / A > (double)c.ba * (1.0 + SLACK) ||
                fabs(q3[i]) / J > (double)c.gj * (1.0 + SLACK))
                fail_msg("program %ld: block kind %d len %.6g: axis %d |q_s| %.9g |q_ss| %.9g |q_sss| %.9g at s %.6g "
                         "above the coefficients (alpha_a %.9g beta_a %.9g gamma_j %.9g)",
                         prog, b->g.kind, (double)b->g.len, i, fabs(q1[i]), fabs(q2[i]), fabs(q3[i]), s,
                         (double)c.aa * A, (double)c.ba * A, (double)c.gj * J);
            n2 += q2[i] * q2[i];
            n3 += q3[i] * q3[i];
        }
        if (cf->path_j_max_mm_s3 > 0 && sqrt(n3) / (double)cf->path_j_max_mm_s3 > (double)c.gj * (1.0 + SLACK))
            fail_msg("program %ld: path |q_sss| %.9g above gamma_j", prog, sqrt(n3));
        if (cf->path_a_max_mm_s2 > 0 && sqrt(n2) / (double)cf->path_a_max_mm_s2 > (double)c.ba * (1.0 + SLACK))
            fail_msg("program %ld: path |q_ss| %.9g above beta_a", prog, sqrt(n2));
    }
    if (b->g.kind != LSM_GEOM_CLOTHOID)
        return;
    /* the magnitudes' bound |c| max|N_i| + kappa_max² max|T_i| (sampled: at most the bound itself) */
    const lsm_geom_clothoid *cl = &b->g.u.clo;
    const double k0 = (double)cl->kappa0_per_mm, cc = (double)cl->c_per_mm2, k1 = k0 + cc * (double)b->g.len;
    const double k = fmax(fabs(k0), fabs(k1));
    double mT[3] = {0, 0, 0}, mN[3] = {0, 0, 0};
    for (int p = 0; p < 4 * POINTS_ALONG; p++) {
        const double s = (double)b->g.len * p / (4 * POINTS_ALONG - 1);
        const double th = (double)cl->theta0_rad + s * (k0 + 0.5 * cc * s);
        for (int i = 0; i < 3; i++) {
            mT[i] = fmax(mT[i], fabs(cos(th) * (double)cl->e1[i] + sin(th) * (double)cl->e2[i]));
            mN[i] = fmax(mN[i], fabs(-sin(th) * (double)cl->e1[i] + cos(th) * (double)cl->e2[i]));
        }
    }
    double mag = 0;
    for (int i = 0; i < 3; i++)
        mag = fmax(mag, (fabs(cc) * mN[i] + k * k * mT[i]) / (double)cf->axis[i].j_max);
    if ((double)c.gj < 0.95 * mag)
        (*tighter)++;
}

static void test_coef_bounds(void **state)
{
    (void)state;
    static lsm_pblock store[CAP];
    static lsm_planner pl;
    long blocks = 0, tighter = 0;
    for (long prog = 0; prog < g_count; prog++) {
        uint64_t st;
        assert_int_equal(test_random_planner(&pl, store, CAP, &st, g_seed, prog, 1u, 0.006), LSM_OK);
        double p[3] = {0, 0, 0};
        for (int n = 0; n < 24 && lsm_planner_free(&pl) > 6; n++)
            (void)append_one(&pl, &st, p);
        assert_int_equal(lsm_planner_flush(&pl), LSM_OK);
        for (uint32_t id = pl.head; id != pl.tail; id++) {
            const lsm_pblock *b = lsm_planner_block(&pl, id);
            if (b->g.kind == LSM_GEOM_ARC || b->g.kind == LSM_GEOM_CLOTHOID) {
                blocks++;
                check_coef_bounds(&pl, id, prog, &tighter);
            }
        }
    }
    print_message("curved blocks %ld, clothoids whose gamma_j is below 0.95 of the magnitudes' bound (sampled) %ld\n",
                  blocks, tighter);
    assert_true(blocks > g_count);
    assert_true(tighter * 20 > blocks); /* the direction bound decides on some clothoids (it is exercised) */
}

static void test_block_ratios_sound(void **state)
{
    (void)state;
    stats sx = {0, 0, 0, 0};
    static lsm_pblock store[CAP];
    static lsm_planner pl;
    for (long prog = 0; prog < g_count; prog++) {
        uint64_t st;
        assert_int_equal(test_random_planner(&pl, store, CAP, &st, g_seed, prog, 1u, 0.006), LSM_OK);
        double p[3] = {0, 0, 0};
        for (int n = 0; n < 24 && lsm_planner_free(&pl) > 6; n++)
            (void)append_one(&pl, &st, p); /* (an arc that does not fit is refused: the next one is tried) */
        assert_int_equal(lsm_planner_flush(&pl), LSM_OK);
        for (uint32_t id = pl.head; id != pl.tail; id++) {
            const lsm_pblock *b = lsm_planner_block(&pl, id);
            if (b->g.kind == LSM_GEOM_ARC || b->g.kind == LSM_GEOM_CLOTHOID)
                check_block_spans(&pl, id, &st, prog, &sx);
        }
    }
    print_message("curved blocks %ld, spans %ld, held %ld, held only by the Frenet-frame bounds %ld\n", sx.blocks,
                  sx.spans, sx.held, sx.held_by_frame);
    assert_true(sx.blocks > g_count);             /* arcs and clothoids were made */
    assert_true(sx.held_by_frame * 50 > sx.held); /* and the frame bounds decided more than 2 % of the spans held */
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, 1);
    g_count = (long)test_arg_u(argc, argv, 2, 400);
    print_message("seed %lu, count %ld\n", g_seed, g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_coef_bounds),
        cmocka_unit_test(test_block_ratios_sound),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
