/*
 * test_planner_append.c: what one append does (the cost figures of docs/cortex_m.md, "Planner, per appended block"),
 * double and float builds.
 *
 *   test_planner_append [seed] [count]   (default: seed 1, 12 programs)
 *
 *   - test_one_block_per_append: an append pushes at most one block with its corner smoothing and backward pass
 *     (planner.c, "one block per append"): an arc whose append emits the pending G1 run is held for the next call
 *     (its slots reserved: lsm_planner_free, lsm_planner_count), which pushes it first and holds its own block if
 *     it has one; lsm_planner_flush pushes it. A G1 right after a programmed arc is not held for arc fitting (no
 *     fitted arc may follow a programmed one, plan_fit.c run_may_start); a G1 after a line is. (Before: the arc's
 *     append emitted the G1 held before it too, two corners and two backward passes in one call, the worst append
 *     of the M4 dense benchmark.)
 *   - test_nodes_certified (randomized): programs of the M4 dense benchmark's kinds (dense polylines, zigzags, half
 *     circles joined by lines at 0.3 rad corners, random feeds and tolerances) streamed into a 64-block buffer as a
 *     controller would (append while 3 slots are free, one prepare and one step per cycle). After every append,
 *     every node's W passes its own test against the node after it (lsm_pl_arrival_ok: one verified ramp from W
 *     reaches the next node's W, or a cruise at W goes through), so the W search (plan_nodes.c node_w: guesses with
 *     closing tests, then bisection) only ever keeps certified speeds; at most one corner per append when no run
 *     was pending (a pending run that is not fitted is emitted a segment and a corner per point); the count of
 *     blocks includes the held one; the run ends exactly on its last point with no fallback piece and no piece
 *     planned in the cycle.
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

#include "interp.h"
#include "lsm_test_rng.h"
#include "planner.h"
#include "planner_int.h"

#define CAP 64u
static lsm_pblock g_blk[CAP];
static lsm_planner g_pl;
static lsm_interp g_ip;
static unsigned long long g_seed = 1, g_count = 12;

static void init_planner(void)
{
    lsm_planner_config cfg;
    lsm_planner_default_config(&cfg);
    const lsm_real start[LSM_MAX_AXES] = {0};
    assert_int_equal(lsm_planner_init(&g_pl, &cfg, g_blk, CAP, start), LSM_OK);
    assert_int_equal(lsm_interp_init(&g_ip, &g_pl), LSM_OK);
}

static lsm_planner_move move_of(double feed, double tol)
{
    lsm_planner_move mv;
    memset(&mv, 0, sizeof mv);
    mv.feed_mm_s = (lsm_real)feed;
    mv.tol_mm = (lsm_real)tol;
    return mv;
}

static lsm_status line_to(double x, double y, const lsm_planner_move *mv)
{
    lsm_real end[LSM_MAX_AXES] = {0};
    end[0] = (lsm_real)x;
    end[1] = (lsm_real)y;
    return lsm_planner_append_line(&g_pl, end, mv);
}

static lsm_status arc_to(double x, double y, double cx, double cy, int dir, const lsm_planner_move *mv)
{
    const lsm_real end[3] = {(lsm_real)x, (lsm_real)y, 0};
    const lsm_real c[3] = {(lsm_real)cx, (lsm_real)cy, 0};
    return lsm_planner_append_arc(&g_pl, end, c, LSM_GEOM_PLANE_XY, dir, 0u, mv);
}

static void test_one_block_per_append(void **state)
{
    (void)state;
    init_planner();
    const lsm_planner_move mv = move_of(100.0, 0.02);
    assert_int_equal(line_to(10.0, 0.0, &mv), LSM_OK);
    assert_int_equal(g_pl.fit_n, 1u); /* a line after the start: held for arc fitting */
    assert_int_equal(g_pl.tail, 0u);
    /* a left half circle R 2 from (10, 0): the held line is emitted (pushed), so the arc is held */
    assert_int_equal(arc_to(10.0, 4.0, 10.0, 2.0, 1, &mv), LSM_OK);
    assert_int_equal(g_pl.fit_n, 0u);
    assert_int_equal(g_pl.tail, 1u);
    assert_int_equal(g_pl.held, 1u);
    assert_int_equal(lsm_planner_count(&g_pl), 2u);
    assert_int_equal(lsm_planner_free(&g_pl), CAP - 1u - 3u); /* the held arc's slots are reserved */
    /* a 3 mm line 0.3 rad off the arc's end tangent (-X): the call pushes the arc (its corner) and holds the line
     * (a G1 after a programmed arc is not held for fitting: no fitted arc may follow a programmed one) */
    const double h = 3.14159265358979 + 0.3;
    const double x1 = 10.0 + 3.0 * cos(h), y1 = 4.0 + 3.0 * sin(h);
    uint32_t corners = g_pl.stats.corners;
    assert_int_equal(line_to(x1, y1, &mv), LSM_OK);
    assert_int_equal(g_pl.fit_n, 0u);
    assert_int_equal(g_pl.held, 1u);
    assert_true(g_pl.stats.corners <= corners + 1u);
    assert_true(fabs((double)g_pl.tail_pos[0] - 10.0) < 1e-4 && fabs((double)g_pl.tail_pos[1] - 4.0) < 1e-4);
    /* the next half circle (right, G2): pushes the held line with its corner, holds itself */
    const double nx = -sin(h), ny = cos(h); /* left of the heading; a right turn goes the other way */
    const double x2 = x1 - 4.0 * nx, y2 = y1 - 4.0 * ny;
    corners = g_pl.stats.corners;
    assert_int_equal(arc_to(x2, y2, x1 - 2.0 * nx, y1 - 2.0 * ny, -1, &mv), LSM_OK);
    assert_int_equal(g_pl.stats.corners, corners + 1u);
    assert_int_equal(g_pl.held, 1u);
    assert_true(g_pl.tail_pos[0] == (lsm_real)x1 && g_pl.tail_pos[1] == (lsm_real)y1);
    /* a paused stream flushes: the held arc is pushed */
    corners = g_pl.stats.corners;
    assert_int_equal(lsm_planner_flush(&g_pl), LSM_OK);
    assert_int_equal(g_pl.held, 0u);
    assert_int_equal(g_pl.stats.corners, corners + 1u);
    assert_int_equal(lsm_planner_count(&g_pl), g_pl.tail - g_pl.head);
    /* a line after it is pushed at once (nothing else pushed in that call) */
    const uint32_t tail3 = g_pl.tail;
    assert_int_equal(line_to(x2 - 3.0 * cos(h), y2 - 3.0 * sin(h), &mv), LSM_OK);
    assert_int_equal(g_pl.held, 0u);
    assert_int_equal(g_pl.fit_n, 0u);
    assert_true(g_pl.tail > tail3);
    /* a line after a line is held for fitting */
    const uint32_t tail4 = g_pl.tail;
    assert_int_equal(line_to(x2 - 6.0 * cos(h + 0.2), y2 - 6.0 * sin(h + 0.2), &mv), LSM_OK);
    assert_int_equal(g_pl.fit_n, 1u);
    assert_int_equal(g_pl.tail, tail4);
}

/* Every node's W passes its own test against the node after it (the backward pass's certificate). */
static void check_nodes(unsigned prog, uint32_t item)
{
    for (uint32_t id = g_pl.head; id != g_pl.tail; id++) {
        const lsm_pblock *b = blk(&g_pl, id);
        if (!(b->flags & LSM_PB_NODE) || (b->flags & LSM_PB_STOP))
            continue;
        if (!lsm_pl_arrival_ok(&g_pl, id, b->w_mm_s)) {
            print_error("program %u item %u: node %u (W %.9g) fails its own test\n", prog, item, id, (double)b->w_mm_s);
            fail();
        }
    }
}

/* The M4 dense benchmark's kinds of item, with random feeds, tolerances and sizes. */
typedef struct gen {
    double p[2], h;
    uint32_t k, n;
    int kind, left; /* 0 dense polyline, 1 zigzag, 2 half circles and lines */
    double feed, tol, r, seg;
} gen;

static bool gen_next(gen *g, uint64_t *rs, bool *arc, double end[2], double c[2], int *dir)
{
    if (g->k >= g->n)
        return false;
    if (g->k % 24u == 0u) {
        g->kind = (int)(test_urand(rs) * 3.0);
        g->feed = test_uni(rs, 20.0, 200.0);
        g->tol = test_logu(rs, 0.005, 0.05);
        g->r = test_uni(rs, 1.0, 5.0);
        g->seg = test_uni(rs, 0.1, 0.5);
    }
    *arc = false;
    const uint32_t j = g->k++;
    if (g->kind == 0) {
        const double s = g->seg * (0.5 + test_urand(rs));
        g->h += s / 20.0;
        g->p[0] += s * cos(g->h);
        g->p[1] += s * sin(g->h);
    } else if (g->kind == 1) {
        const double h = g->h + ((j & 1u) ? 0.4 : -0.4);
        g->p[0] += 1.5 * cos(h);
        g->p[1] += 1.5 * sin(h);
    } else if ((j & 1u) == 0u) {
        const double sg = g->left ? 1.0 : -1.0;
        const double nx = -sin(g->h) * sg, ny = cos(g->h) * sg;
        *arc = true;
        *dir = g->left ? 1 : -1;
        c[0] = g->p[0] + g->r * nx;
        c[1] = g->p[1] + g->r * ny;
        g->p[0] += 2.0 * g->r * nx;
        g->p[1] += 2.0 * g->r * ny;
        g->h += 3.14159265358979;
        g->left = !g->left;
    } else {
        g->h += 0.3;
        g->p[0] += 3.0 * cos(g->h);
        g->p[1] += 3.0 * sin(g->h);
    }
    end[0] = g->p[0];
    end[1] = g->p[1];
    return true;
}

static void run_program(unsigned prog, uint64_t *rs)
{
    init_planner();
    gen g;
    memset(&g, 0, sizeof g);
    g.n = 240u;
    g.h = test_uni(rs, 0.0, 6.283185307179586);
    bool arc = false, have, finished = false;
    double end[2] = {0, 0}, c[2] = {0, 0};
    int dir = 1;
    have = gen_next(&g, rs, &arc, end, c, &dir);
    uint32_t item = 0;
    lsm_real pos[LSM_MAX_AXES];
    lsm_interp_state st = LSM_INTERP_IDLE;
    for (uint32_t cyc = 0; cyc < 400000u; cyc++) {
        while (have && lsm_planner_free(&g_pl) >= 3u) {
            const lsm_planner_move mv = move_of(g.feed, g.tol);
            const uint32_t corners0 = g_pl.stats.corners, fit0 = g_pl.fit_n;
            const lsm_status s = arc ? arc_to(end[0], end[1], c[0], c[1], dir, &mv) : line_to(end[0], end[1], &mv);
            if (s == LSM_E_FULL)
                break;
            assert_int_equal(s, LSM_OK);
            if (fit0 == 0u && g_pl.stats.corners > corners0 + 1u) {
                print_error("program %u item %u: %u corners in one append without a pending run\n", prog, item,
                            g_pl.stats.corners - corners0);
                fail();
            }
            check_nodes(prog, item);
            assert_int_equal(lsm_planner_count(&g_pl), g_pl.tail - g_pl.head + g_pl.held);
            item++;
            have = gen_next(&g, rs, &arc, end, c, &dir);
        }
        if (!have && !finished) {
            assert_int_equal(lsm_planner_finish(&g_pl), LSM_OK);
            finished = true;
            check_nodes(prog, item);
        }
        (void)lsm_interp_prepare(&g_ip);
        st = lsm_interp_step(&g_ip, pos);
        if (st == LSM_INTERP_DONE && finished)
            break;
    }
    if (st != LSM_INTERP_DONE) {
        print_error("program %u did not finish\n", prog);
        fail();
    }
    assert_true(pos[0] == (lsm_real)end[0] && pos[1] == (lsm_real)end[1]);
    assert_int_equal(g_pl.stats.plan_fallbacks, 0u);
    assert_int_equal(g_ip.tick_plans, 0u);
}

static void test_nodes_certified(void **state)
{
    (void)state;
    uint64_t rs = g_seed * 0x9E3779B97F4A7C15ull + 11u;
    for (unsigned p = 0; p < (unsigned)g_count; p++)
        run_program(p, &rs);
}

int main(int argc, char **argv)
{
    g_seed = test_arg_u(argc, argv, 1, 1);
    g_count = test_arg_u(argc, argv, 2, 12);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_block_per_append),
        cmocka_unit_test(test_nodes_certified),
    };
    return test_seed_finish(argv[0], g_seed, g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
