/*
 * lsm_test_path.h: random path items for the planner's randomized tests. Header-only; needs lsm_test_rng.h and
 * planner.h included before it.
 *
 * test_append_random_arc: one arc from p in a random plane (XY, ZX or YZ), radius log-uniform in [r_lo, r_hi] mm,
 * sweep uniform in [0.2, sw_hi] rad either way, one in five a helix (up to +-2 mm along the plane's normal). On
 * LSM_OK, p becomes the arc's end (as the planner stored it, rounded to lsm_real). A refused arc leaves p as it was.
 *
 * test_random_machine: X Y Z with unequal limits (v 50-1000 mm/s, a 500-2e4 mm/s², j 2e3-1e6 mm/s³, snap 1e6-1e9
 * mm/s⁴, each log-uniform), a cycle uniform in [0.5 ms, cycle_hi_s]; path a and j limits on three machines in ten.
 *
 * test_random_planner: program `prog` of a run with seed `seed` (its own stream, st, mixed with `salt`): a random
 * machine as above and an empty planner on it, starting at the origin.
 */
#ifndef LSM_TEST_PATH_H
#define LSM_TEST_PATH_H

#include <math.h>
#include <string.h>

static inline lsm_status test_append_random_arc(lsm_planner *pl, uint64_t *st, double p[3], double r_lo, double r_hi,
                                                double sw_hi, const lsm_planner_move *mv)
{
    static const lsm_geom_plane planes[3] = {LSM_GEOM_PLANE_XY, LSM_GEOM_PLANE_ZX, LSM_GEOM_PLANE_YZ};
    static const int axes[3][3] = {{0, 1, 2}, {2, 0, 1}, {1, 2, 0}}; /* e1, e2, n of each plane */
    const int pi = (int)(test_urand(st) * 3) % 3;
    const double r = test_logu(st, r_lo, r_hi), ph = test_uni(st, 0, 6.283185307179586);
    const double sw = test_uni(st, 0.2, sw_hi), dir = test_urand(st) < 0.5 ? 1.0 : -1.0;
    double c[3] = {p[0], p[1], p[2]}, e[3] = {p[0], p[1], p[2]};
    const int *ax = axes[pi];
    c[ax[0]] = p[ax[0]] - r * cos(ph);
    c[ax[1]] = p[ax[1]] - r * sin(ph);
    e[ax[0]] = c[ax[0]] + r * cos(ph + dir * sw);
    e[ax[1]] = c[ax[1]] + r * sin(ph + dir * sw);
    if (test_urand(st) < 0.2)
        e[ax[2]] += test_uni(st, -2, 2); /* a helix */
    const lsm_real el[3] = {(lsm_real)e[0], (lsm_real)e[1], (lsm_real)e[2]};
    const lsm_real cl[3] = {(lsm_real)c[0], (lsm_real)c[1], (lsm_real)c[2]};
    const lsm_status s = lsm_planner_append_arc(pl, el, cl, planes[pi], (int)dir, 0, mv);
    if (s == LSM_OK)
        memcpy(p, e, sizeof e);
    return s;
}

/* Appends the line from p (updated to its end on success) along the unit direction d over len mm. */
static inline lsm_status test_append_line(lsm_planner *pl, double p[3], const double d[3], double len,
                                          const lsm_planner_move *mv)
{
    lsm_real e[LSM_MAX_AXES] = {0};
    for (int i = 0; i < 3; i++)
        e[i] = (lsm_real)(p[i] + len * d[i]);
    const lsm_status s = lsm_planner_append_line(pl, e, mv);
    if (s == LSM_OK)
        for (int i = 0; i < 3; i++)
            p[i] = (double)e[i];
    return s;
}

/* Appends one random line, arc or short dense polyline (0.1-0.5 mm chords of a curve) from p (updated to its end),
 * at a random feed and tolerance (the feeds make the caps vary from block to block). */
static inline void test_append_random_item(lsm_planner *pl, uint64_t *st, double p[3])
{
    const lsm_planner_move mv = {(lsm_real)test_logu(st, 5, 300), (lsm_real)test_logu(st, 2e-3, 0.1), 0, 0};
    const double u = test_urand(st);
    if (u < 0.3) {
        (void)test_append_random_arc(pl, st, p, 0.1, 30, 4.0, &mv); /* (refused when it does not fit) */
        return;
    }
    double h = test_uni(st, 0, 6.283185307179586);
    if (u < 0.65) {
        const double d[3] = {cos(h), sin(h), test_urand(st) < 0.5 ? 0.0 : test_uni(st, -0.5, 0.5)};
        const double n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double dn[3] = {d[0] / n, d[1] / n, d[2] / n};
        (void)test_append_line(pl, p, dn, test_logu(st, 0.05, 20), &mv);
        return;
    }
    const double turn = test_uni(st, -0.08, 0.08); /* a curve of chords */
    for (int k = 0; k < 8; k++) {
        h += turn;
        const double d[3] = {cos(h), sin(h), 0};
        (void)test_append_line(pl, p, d, test_uni(st, 0.1, 0.5), &mv);
    }
}

static inline void test_random_machine(uint64_t *st, lsm_planner_config *cfg, double cycle_hi_s)
{
    lsm_planner_default_config(cfg);
    cfg->cycle_s = (lsm_real)test_uni(st, 0.0005, cycle_hi_s);
    cfg->axis_mask = 0x7;
    for (int i = 0; i < 3; i++) {
        cfg->axis[i].v_max = (lsm_real)test_logu(st, 50, 1000);
        cfg->axis[i].a_max = (lsm_real)test_logu(st, 500, 20000);
        cfg->axis[i].j_max = (lsm_real)test_logu(st, 2000, 1e6);
        cfg->axis[i].snap_max = (lsm_real)test_logu(st, 1e6, 1e9);
    }
    if (test_urand(st) < 0.3) {
        cfg->path_a_max_mm_s2 = (lsm_real)test_logu(st, 300, 20000);
        cfg->path_j_max_mm_s3 = (lsm_real)test_logu(st, 1000, 1e6);
    }
}

static inline lsm_status test_random_planner(lsm_planner *pl, lsm_pblock *store, uint32_t cap, uint64_t *st,
                                             unsigned long seed, long prog, uint64_t salt, double cycle_hi_s)
{
    *st = (uint64_t)seed * 0x9E3779B97F4A7C15ull + (uint64_t)prog * 0xD1B54A32D192ED69ull + salt;
    lsm_planner_config cfg;
    test_random_machine(st, &cfg, cycle_hi_s);
    const lsm_real start[LSM_MAX_AXES] = {0};
    return lsm_planner_init(pl, &cfg, store, cap, start);
}

#endif
