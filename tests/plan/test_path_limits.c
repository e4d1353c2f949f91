/*
 * test_path_limits.c: every axis limit and the exact end, through G-code and the planner API, on random machines
 * and programs; built twice (double, and float: the Cortex-M4F's numerics) and run at the same counts in both.
 *
 *   test_path_limits [seed] [count]      (default: seed 1, count 300 programs per scenario)
 *
 * Programs (G-code text, parsed by lsm_gcode and streamed into the planner while the interpolator runs):
 *   - lines, G2/G3 arcs with R (R up to 1e5 mm, chords down to 0.05 mm) and with I J K, G17/18/19, helices;
 *   - long coordinates: the whole program offset by 100 .. 1000 mm on each axis;
 *   - G61 and G64 P (corner blending), feeds from slow to beyond the axis limits;
 * on machines with a random cycle (0.5 .. 4 ms) and random, unequal axis limits (Z often far slower).
 * Checked from the setpoints alone:
 *   - per axis, the backward differences |d^n q| / dt^n (n = 1, 2, 3; at rest before and after, Beudaert eq 6)
 *     within the limits, up to the noise bound below;
 *   - the last setpoint is the programmed end: in double bit for bit, in float the programmed end rounded to float
 *     (the parser's position, i.e. the end as the firmware receives it);
 *   - the run ends, and no piece needed the planner's fallback.
 * Golden case (issue 14): `G1 X13.5 Y12.5 F1200` / `G3 X11 Y10 R10000` on a 2 ms machine (XYZ v 1000, a 20000,
 * j 1e6, snap 1e9), and `G1 Y2 F10` / `G3 Y0 R1000`: within the limits, exact ends.
 *
 * Noise bound. A setpoint is the planned motion x(t_k) plus its evaluation error e_k. The interpolator evaluates
 * every element from an exact point near the cursor (a block start, an arc anchor) plus a displacement computed
 * to a relative error of a few eps, so |e_k| <= E = LSM_PATH_NOISE_ULP ulp(M), where M is the largest |coordinate|
 * in the window of samples (every axis: the path parameter's rounding reaches every axis the path moves) and the
 * length of the longest block run so far (the path parameter and the piece's travel are of that size), and ulp is
 * that of lsm_real. An n-th backward difference of the setpoints then differs from that of x by at most 2^n E, so
 *     |d^n q| / dt^n <= limit_n (1 + 1e-6) + 2^n E / dt^n              (n = 1 velocity, 2 acceleration, 3 jerk)
 * with E = 2 ulp (measured worst: reported at the end of each scenario in ulp). In double it is ~1e-13 of the
 * limits; in float it is the only slack, a few ulp of the cycle's differences, nothing else.
 */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "gcode.h"
#include "interp.h"
#include "lsm_test_rng.h"
#include "planner.h"

/* E of the noise bound above, in ulp of lsm_real. */
#define LSM_PATH_NOISE_ULP 2.0

static unsigned long g_seed = 1;
static long g_count = 300;

/* ---------------------------------------------------------------------------------------------------------- */
/* machines                                                                                                    */

typedef struct machine {
    double cycle_s;
    double v[3], a[3], j[3], snap[3];
    double blend_tol_mm;
} machine;

static void machine_cfg(const machine *m, lsm_planner_config *cfg)
{
    lsm_planner_default_config(cfg);
    cfg->cycle_s = (lsm_real)m->cycle_s;
    cfg->axis_mask = 0x07;
    for (int i = 0; i < 3; i++) {
        cfg->axis[i].v_max = (lsm_real)m->v[i];
        cfg->axis[i].a_max = (lsm_real)m->a[i];
        cfg->axis[i].j_max = (lsm_real)m->j[i];
        cfg->axis[i].snap_max = (lsm_real)m->snap[i];
    }
}

static void machine_rand(machine *m, uint64_t *rs)
{
    static const double cycles[4] = {0.0005, 0.001, 0.002, 0.004};
    m->cycle_s = cycles[(int)(test_urand(rs) * 4)];
    for (int i = 0; i < 3; i++) {
        m->v[i] = test_logu(rs, 30, 1000);
        m->a[i] = test_logu(rs, 300, 20000);
        m->j[i] = test_logu(rs, 1e4, 1e6);
        m->snap[i] = m->j[i] * test_logu(rs, 100, 1000);
    }
    if (test_urand(rs) < 0.4) { /* a slow Z */
        m->v[2] = test_logu(rs, 10, 100);
        m->a[2] = test_logu(rs, 100, 1000);
        m->j[2] = test_logu(rs, 1e3, 1e4);
        m->snap[2] = m->j[2] * 300;
    }
    m->blend_tol_mm = test_logu(rs, 0.002, 0.1);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* programs                                                                                                    */

#define PROG_MAX 16384

typedef struct text {
    char s[PROG_MAX];
    size_t n;
} text;

static void put(text *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    const int k = vsnprintf(t->s + t->n, PROG_MAX - t->n, fmt, ap);
    va_end(ap);
    if (k > 0 && t->n + (size_t)k < PROG_MAX)
        t->n += (size_t)k;
}

static double urand(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * test_urand(s);
}

/* A random program from `at` (the parser's start, mm). kind 0: anything; 1: large-radius arcs (R form, short
 * chords); 2: long coordinates (offsets 100 .. 1000 mm). */
static void gen(text *t, uint64_t *rs, int kind, double at[3])
{
    t->n = 0;
    const double off = kind == 2 ? test_logu(rs, 100, 1000) : (test_urand(rs) < 0.2 ? test_logu(rs, 1, 100) : 0);
    double p[3];
    for (int i = 0; i < 3; i++) {
        at[i] = (test_urand(rs) < 0.5 ? -1 : 1) * off * urand(rs, 0.5, 1.0);
        p[i] = at[i];
    }
    put(t, "G21 G90 G17\n");
    put(t, test_urand(rs) < 0.25 ? "G61\n" : "G64 P%.4f\n", test_logu(rs, 0.001, 0.05));
    const int n = 2 + (int)(test_urand(rs) * 10);
    int plane = 17;
    for (int k = 0; k < n; k++) {
        const double feed = test_logu(rs, 200, 60000); /* mm/min */
        const int what = kind == 1 ? (test_urand(rs) < 0.7 ? 2 : 0) : (int)(test_urand(rs) * 4);
        if (test_urand(rs) < 0.15) {
            plane = 17 + (int)(test_urand(rs) * 3);
            put(t, "G%d\n", plane);
        }
        const int u = plane == 17 ? 0 : plane == 18 ? 2 : 1, v = plane == 17 ? 1 : plane == 18 ? 0 : 2, w = 3 - u - v;
        if (what <= 1) { /* a line */
            const double len = test_logu(rs, 0.01, 60);
            double d[3] = {urand(rs, -1, 1), urand(rs, -1, 1), test_urand(rs) < 0.5 ? 0 : urand(rs, -1, 1)};
            const double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + 1e-12;
            double q[3];
            for (int i = 0; i < 3; i++)
                q[i] = round((p[i] + d[i] / dl * len) * 1e4) / 1e4;
            put(t, "G1 X%.4f Y%.4f Z%.4f F%.1f\n", q[0], q[1], q[2], feed);
            memcpy(p, q, sizeof p);
        } else if (what == 2) { /* an arc with R: large radii, short chords */
            const double R = kind == 1 ? test_logu(rs, 10, 1e5) : test_logu(rs, 0.5, 1e4);
            const double chord = fmin(test_logu(rs, 0.05, 50), 1.9 * R);
            const double a = urand(rs, 0, 2 * LSM_PI);
            double q[3];
            memcpy(q, p, sizeof q);
            q[u] = round((p[u] + chord * cos(a)) * 1e4) / 1e4;
            q[v] = round((p[v] + chord * sin(a)) * 1e4) / 1e4;
            if (test_urand(rs) < 0.15)
                q[w] = round((p[w] + urand(rs, -2, 2)) * 1e4) / 1e4;
            if (q[u] == p[u] && q[v] == p[v])
                continue;
            put(t, "G%d X%.4f Y%.4f Z%.4f R%.4f F%.1f\n", test_urand(rs) < 0.5 ? 2 : 3, q[0], q[1], q[2], R, feed);
            memcpy(p, q, sizeof p);
        } else { /* an arc with I J K: centre at a random point, sweep up to almost a full turn */
            const double R = test_logu(rs, 0.3, 300);
            const double a0 = urand(rs, 0, 2 * LSM_PI), sw = urand(rs, 0.05, 6.0);
            const int dir = test_urand(rs) < 0.5 ? 1 : -1;
            const double cu = p[u] - R * cos(a0), cv = p[v] - R * sin(a0);
            double q[3];
            memcpy(q, p, sizeof q);
            q[u] = round((cu + R * cos(a0 + dir * sw)) * 1e4) / 1e4;
            q[v] = round((cv + R * sin(a0 + dir * sw)) * 1e4) / 1e4;
            if (test_urand(rs) < 0.15)
                q[w] = round((p[w] + urand(rs, -2, 2)) * 1e4) / 1e4;
            const double off_c[3] = {0, 0, 0};
            (void)off_c;
            const char *ln = plane == 17 ? "IJ" : plane == 18 ? "KI" : "JK";
            put(t, "G%d X%.4f Y%.4f Z%.4f %c%.4f %c%.4f F%.1f\n", dir > 0 ? 3 : 2, q[0], q[1], q[2], ln[0],
                round((cu - p[u]) * 1e4) / 1e4, ln[1], round((cv - p[v]) * 1e4) / 1e4, feed);
            memcpy(p, q, sizeof p);
        }
    }
    put(t, "M2\n");
}

/* ---------------------------------------------------------------------------------------------------------- */
/* running                                                                                                     */

typedef struct blk_in {
    lsm_gcode_block b;
    double tol_mm;
} blk_in;

typedef struct trace { /* interpolator state per cycle (TEST_TRACE: printed around the first failure) */
    uint32_t blk, serial;
    uint8_t kind, phase;
    double off, tau, v;
} trace;

typedef struct run_res {
    trace *tr;
    double *q; /* 3 per cycle */
    long n;
    int done;
    int parse_err;  /* the parser or the planner refused the program (skipped) */
    double end[3];  /* the parser's final position */
    double max_len; /* longest block appended */
    uint32_t fallbacks;
} run_res;

static lsm_status append_one(lsm_planner *pl, const blk_in *q)
{
    const lsm_gcode_block *b = &q->b;
    lsm_planner_move mv;
    memset(&mv, 0, sizeof mv);
    mv.rapid = b->type == LSM_GCODE_BLOCK_RAPID;
    mv.feed_mm_s = b->feed_mm_s;
    mv.tol_mm = (lsm_real)q->tol_mm;
    mv.seq = b->line;
    if (b->type == LSM_GCODE_BLOCK_ARC)
        return lsm_planner_append_arc(pl, b->end, b->centre, (lsm_geom_plane)b->plane, b->dir, b->turns, &mv);
    return lsm_planner_append_line(pl, b->end, &mv);
}

static int parse(const text *t, const machine *m, const double at[3], blk_in **out, long *n_out, double end[3])
{
    lsm_gcode g;
    lsm_gcode_options go;
    lsm_gcode_default_options(&go);
    go.axis_mask = 0x07;
    assert_int_equal(lsm_gcode_init(&g, &go), LSM_OK);
    lsm_real p0[LSM_GCODE_N_AXES] = {(lsm_real)at[0], (lsm_real)at[1], (lsm_real)at[2], 0, 0, 0};
    assert_int_equal(lsm_gcode_set_position(&g, p0), LSM_OK);
    long n = 0, cap = 64;
    blk_in *v = malloc((size_t)cap * sizeof *v);
    size_t i = 0;
    while (i < t->n) {
        size_t e = i;
        while (e < t->n && t->s[e] != '\n')
            e++;
        static lsm_gcode_result res;
        const lsm_status st = lsm_gcode_parse_line(&g, t->s + i, e - i, &res);
        i = e + 1;
        if (st != LSM_OK) {
            free(v);
            return -1;
        }
        for (int k = 0; k < res.n_blocks; k++) {
            if (n == cap) {
                cap *= 2;
                v = realloc(v, (size_t)cap * sizeof *v);
            }
            v[n].b = res.blocks[k];
            v[n].tol_mm = res.modal.blend == LSM_GCODE_EXACT_STOP ? 0
                          : res.modal.blend_tol_mm > 0            ? (double)res.modal.blend_tol_mm
                                                                  : m->blend_tol_mm;
            n++;
        }
    }
    const lsm_real *pe = lsm_gcode_position(&g);
    for (int k = 0; k < 3; k++)
        end[k] = (double)pe[k];
    *out = v;
    *n_out = n;
    return 0;
}

static void run(const text *t, const machine *m, const double at[3], uint32_t capacity, run_res *r)
{
    memset(r, 0, sizeof *r);
    blk_in *v = NULL;
    long nb = 0;
    if (parse(t, m, at, &v, &nb, r->end) != 0) {
        r->parse_err = 1;
        return;
    }
    lsm_planner_config cfg;
    machine_cfg(m, &cfg);
    lsm_pblock *store = calloc(capacity, sizeof *store);
    static lsm_planner pl;
    lsm_real st[LSM_MAX_AXES] = {(lsm_real)at[0], (lsm_real)at[1], (lsm_real)at[2], 0, 0, 0};
    assert_int_equal(lsm_planner_init(&pl, &cfg, store, capacity, st), LSM_OK);
    static lsm_interp ip;
    assert_int_equal(lsm_interp_init(&ip, &pl), LSM_OK);
    long cap = 1 << 14;
    r->q = malloc((size_t)cap * 3 * sizeof(double));
    long next = 0;
    int fin = 0;
    const long max_cycles = (long)(3000.0 / m->cycle_s);
    for (long k = 0; k < max_cycles; k++) {
        while (!fin && next < nb) {
            const lsm_status s = append_one(&pl, &v[next]);
            if (s == LSM_E_FULL)
                break;
            if (s == LSM_E_ARC_GEOMETRY || s == LSM_E_RANGE) { /* an arc the planner refuses: skip the program */
                r->parse_err = 1;
                goto out;
            }
            if (s != LSM_OK && s != LSM_E_ZERO_LENGTH)
                fail_msg("append %ld: %s", next, lsm_status_str(s));
            next++;
        }
        for (uint32_t id = pl.head; id != pl.tail; id++) /* released blocks (a posted release) read as NULL */
            if (lsm_planner_block(&pl, id) != NULL)
                r->max_len = fmax(r->max_len, (double)lsm_planner_block(&pl, id)->g.len);
        if (getenv("TEST_GAPS"))
            for (uint32_t id = pl.head; id + 1u != pl.tail && id != pl.tail; id++) {
                if (lsm_planner_block(&pl, id) == NULL)
                    continue;
                const lsm_geom *g0 = &lsm_planner_block(&pl, id)->g, *g1 = &lsm_planner_block(&pl, id + 1u)->g;
                lsm_real e[LSM_MAX_AXES] = {0}, b0[LSM_MAX_AXES] = {0};
                lsm_geom_eval(g0, g0->len, e, NULL, NULL);
                lsm_geom_eval(g1, 0, b0, NULL, NULL);
                const double gap =
                    fmax(fmax(fabs((double)e[0] - b0[0]), fabs((double)e[1] - b0[1])), fabs((double)e[2] - b0[2]));
                if (gap > 1e-5)
                    print_message("gap %u->%u kind %d->%d: %.3g (len %g %g)\n", id, id + 1, g0->kind, g1->kind, gap,
                                  (double)g0->len, (double)g1->len);
            }
        if (!fin && next == nb && lsm_planner_finish(&pl) == LSM_OK)
            fin = 1;
        lsm_real pos[LSM_MAX_AXES];
        (void)lsm_interp_prepare(&ip);
        const lsm_interp_state s = lsm_interp_step(&ip, pos);
        if (r->n == cap) {
            cap *= 2;
            r->q = realloc(r->q, (size_t)cap * 3 * sizeof(double));
        }
        for (int i = 0; i < 3; i++)
            r->q[3 * r->n + i] = (double)pos[i];
        if (getenv("TEST_TRACE")) {
            if (r->n == 0)
                r->tr = malloc((size_t)cap * sizeof *r->tr);
            else if ((r->n & (r->n - 1)) == 0 && r->n >= (1 << 14))
                r->tr = realloc(r->tr, (size_t)cap * sizeof *r->tr);
            const lsm_pblock *b = lsm_planner_block(&pl, ip.blk);
            r->tr[r->n] = (trace){ip.blk,         ip.serial,        b ? b->g.kind : 0, ip.phase, (double)ip.off_mm,
                                  (double)ip.tau, (double)ip.v_mm_s};
        }
        r->n++;
        if (s == LSM_INTERP_DONE) {
            r->done = 1;
            break;
        }
    }
out:
    if (!r->done && r->tr && r->n > 3)
        for (long i = r->n - 3; i < r->n; i++)
            print_message("  not done %ld: %.9f %.9f %.9f blk %u kind %u piece %u phase %u off %.9g tau %.9g v %.6g "
                          "state %d head %u tail %u len %.9g\n",
                          i, r->q[3 * i], r->q[3 * i + 1], r->q[3 * i + 2], r->tr[i].blk, r->tr[i].kind,
                          r->tr[i].serial, r->tr[i].phase, r->tr[i].off, r->tr[i].tau, r->tr[i].v, ip.state, pl.head,
                          pl.tail,
                          lsm_planner_block(&pl, ip.blk) ? (double)lsm_planner_block(&pl, ip.blk)->g.len : -1.0);
    free(store);
    free(v);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* checking                                                                                                    */

static double ulp_of(double x)
{
    x = fabs(x);
    if (LSM_REAL_IS_FLOAT) {
        const float f = (float)x;
        return (double)(nextafterf(f, INFINITY) - f);
    }
    return nextafter(x, INFINITY) - x;
}

typedef struct worst {
    double ratio; /* largest |d^n q| / (limit + bound) */
    double ulps;  /* largest excess over the limit, in ulp / dt^n units: (|d^n q| - limit dt^n) / ulp */
} worst;

/* Returns 0 if every axis holds its limits within the noise bound; else prints the worst sample. */
static int check_limits(const run_res *r, const machine *m, const char *what, long c, worst *w)
{
    const double dt = m->cycle_s;
    int bad = 0;
    for (int a = 0; a < 3; a++) {
        const double lim[4] = {0, m->v[a], m->a[a], m->j[a]};
        double h[4] = {0, 0, 0, 0}; /* q_k, q_k-1, q_k-2, q_k-3 */
        for (int i = 0; i < 4; i++)
            h[i] = r->q[a];
        double mag[4] = {0, 0, 0, 0};
        for (int i = 0; i < 4; i++)
            mag[i] = fmax(fmax(fabs(r->q[0]), fabs(r->q[1])), fabs(r->q[2]));
        for (long k = 0; k < r->n + 3; k++) {
            const long kk = k < r->n ? k : r->n - 1;
            for (int i = 3; i > 0; i--) {
                h[i] = h[i - 1];
                mag[i] = mag[i - 1];
            }
            h[0] = r->q[3 * kk + a];
            mag[0] = fmax(fmax(fabs(r->q[3 * kk]), fabs(r->q[3 * kk + 1])), fabs(r->q[3 * kk + 2]));
            const double M = fmax(fmax(fmax(mag[0], mag[1]), fmax(mag[2], mag[3])), r->max_len);
            const double E = LSM_PATH_NOISE_ULP * ulp_of(M);
            const double d[4] = {0, h[0] - h[1], h[0] - 2 * h[1] + h[2], h[0] - 3 * h[1] + 3 * h[2] - h[3]};
            for (int o = 1; o <= 3; o++) {
                const double dtn = pow(dt, o), bound = lim[o] * (1 + 1e-6) * dtn + ldexp(E, o);
                const double x = fabs(d[o]);
                w->ratio = fmax(w->ratio, x / bound);
                w->ulps = fmax(w->ulps, (x - lim[o] * (1 + 1e-6) * dtn) / ulp_of(M));
                if (x > bound && !bad) {
                    bad = 1;
                    print_message("%s %ld (seed %lu): axis %d order %d at cycle %ld: %.6g > limit %.6g + noise %.3g "
                                  "(%.2f ulp of %.4g over the limit)\n",
                                  what, c, g_seed, a, o, k, x / dtn, lim[o], ldexp(E, o) / dtn,
                                  (x - lim[o] * dtn) / ulp_of(M), M);
                    for (long i = kk - 6; r->tr && i <= kk + 2 && i < r->n; i++)
                        if (i >= 0)
                            print_message("  %ld: %.9f %.9f %.9f blk %u kind %u piece %u phase %u off %.9g tau %.9g v "
                                          "%.6g\n",
                                          i, r->q[3 * i], r->q[3 * i + 1], r->q[3 * i + 2], r->tr[i].blk, r->tr[i].kind,
                                          r->tr[i].serial, r->tr[i].phase, r->tr[i].off, r->tr[i].tau, r->tr[i].v);
                }
            }
        }
    }
    return bad;
}

static int check_end(const run_res *r, const char *what, long c)
{
    for (int i = 0; i < 3; i++) {
        const double last = r->q[3 * (r->n - 1) + i], want = r->end[i];
        if (last != want) {
            print_message("%s %ld (seed %lu): end axis %d %.17g != %.17g (%.3g ulp)\n", what, c, g_seed, i, last, want,
                          (last - want) / ulp_of(want));
            return 1;
        }
    }
    return 0;
}

static void dump(const text *t, const machine *m, const double at[3], uint32_t capacity)
{
    print_message("start %.17g %.17g %.17g, capacity %u\n", at[0], at[1], at[2], capacity);
    print_message("machine: cycle %g s, v %g %g %g, a %g %g %g, j %g %g %g, snap %g %g %g\n", m->cycle_s, m->v[0],
                  m->v[1], m->v[2], m->a[0], m->a[1], m->a[2], m->j[0], m->j[1], m->j[2], m->snap[0], m->snap[1],
                  m->snap[2]);
    print_message("program:\n%.*s", (int)t->n, t->s);
}

static uint64_t rng(int salt)
{
    return 0x9E3779B97F4A7C15ull ^ ((uint64_t)g_seed * 0x100000001B3ull) ^ (uint64_t)salt * 0xD1B54A32D192ED03ull;
}

static void scenario(int kind, const char *name)
{
    uint64_t rs = rng(kind + 1);
    static text t;
    long ok = 0, skipped = 0, failed = 0;
    worst w = {0, 0};
    for (long c = 0; c < g_count; c++) {
        machine m;
        machine_rand(&m, &rs);
        double at[3];
        gen(&t, &rs, kind, at);
        const uint32_t capacity = 16 + (uint32_t)(test_urand(&rs) * 112);
        run_res r;
        run(&t, &m, at, capacity, &r);
        if (r.parse_err) {
            skipped++;
            free(r.q);
            continue;
        }
        int bad = 0;
        if (!r.done) {
            print_message("%s %ld (seed %lu): did not finish\n", name, c, g_seed);
            bad = 1;
        }
        if (!bad)
            bad = check_limits(&r, &m, name, c, &w) | check_end(&r, name, c);
        if (r.fallbacks) {
            print_message("%s %ld (seed %lu): %u fallback pieces\n", name, c, g_seed, r.fallbacks);
            bad = 1;
        }
        if (bad) {
            dump(&t, &m, at, capacity);
            failed++;
        } else {
            ok++;
        }
        free(r.q);
        free(r.tr);
    }
    print_message("%s: %ld programs within the limits with exact ends, %ld refused by the parser/planner, %ld failed; "
                  "worst |d^n q| / (limit + noise bound) %.4f, worst excess over the limit %.2f ulp\n",
                  name, ok, skipped, failed, w.ratio, w.ulps);
    if (failed)
        fail_msg("%s: %ld of %ld programs failed (seed %lu)", name, failed, g_count, g_seed);
    assert_true(ok > g_count / 2);
}

static void test_mixed(void **state)
{
    (void)state;
    scenario(0, "mixed");
}

static void test_large_radius(void **state)
{
    (void)state;
    scenario(1, "large radius");
}

static void test_long_coordinates(void **state)
{
    (void)state;
    scenario(2, "long coordinates");
}

/* The golden cases of issue 14. */
static void golden(const char *prog, const machine *m, const double at[3], const char *what)
{
    static text t;
    t.n = 0;
    put(&t, "%s", prog);
    run_res r;
    run(&t, m, at, 64, &r);
    assert_false(r.parse_err);
    assert_true(r.done);
    worst w = {0, 0};
    const int bad = check_limits(&r, m, what, 0, &w) | check_end(&r, what, 0);
    print_message("%s: %ld cycles, end %.17g %.17g %.17g, worst ratio %.4f\n", what, r.n, r.q[3 * (r.n - 1)],
                  r.q[3 * (r.n - 1) + 1], r.q[3 * (r.n - 1) + 2], w.ratio);
    if (bad)
        fail_msg("%s", what);
    assert_int_equal(r.fallbacks, 0);
    free(r.q);
    free(r.tr);
}

static void test_golden(void **state)
{
    (void)state;
    machine m = {0.002, {1000, 1000, 1000}, {20000, 20000, 20000}, {1e6, 1e6, 1e6}, {1e9, 1e9, 1e9}, 0.02};
    const double z[3] = {0, 0, 0};
    golden("G1 X13.5 Y12.5 F1200\nG3 X11 Y10 R10000\nM2\n", &m, z, "R 10000, 2 ms");
    golden("G1 Y2 F10\nG3 Y0 R1000\nM2\n", &m, z, "R 1000 back to 0, 2 ms");
    /* router.json's limits and cycle */
    machine router = {0.001, {250, 250, 100}, {3000, 3000, 1500}, {60000, 60000, 30000}, {1.18e7, 1.18e7, 5.9e6}, 0.02};
    golden("G1 X13.5 Y12.5 F1200\nG3 X11 Y10 R10000\nM2\n", &router, z, "R 10000, router");
    golden("G1 Y2 F10\nG3 Y0 R1000\nM2\n", &router, z, "R 1000 back to 0, router");
    /* large radius 190 of seed 3 (double): Z jerk 1945.36 > 1942.45 on the R 96160 arc, from the double build's
     * centre form c + r u(phi), whose rounding (ulp(r)) is noise on every setpoint; arcs are evaluated from their
     * start point and anchors now, in both builds (geom.h, interp.h) */
    machine slow_z = {0.0005,
                      {155.747, 95.4639, 73.6592},
                      {12495.2, 380.07, 188.778},
                      {36904.5, 573636, 1942.45},
                      {4.66142e+06, 2.84026e+08, 582734},
                      0.02};
    const double at190[3] = {-63.653514288769024, 41.772048908517569, -39.322184881422274};
    golden("G21 G90 G17\nG64 P0.0183\nG18\nG3 X-63.5901 Y41.7720 Z-37.0194 R5503.3462 F3843.4\n"
           "G2 X-63.4535 Y41.7720 Z-36.9941 R44.9284 F1648.0\nG1 X-64.3146 Y44.0535 Z-40.7079 F267.0\n"
           "G3 X-63.4129 Y44.0535 Z-40.1086 R10.3014 F6307.9\nG1 X-63.4170 Y44.0318 Z-40.1184 F978.6\n"
           "G2 X-63.4146 Y44.0318 Z-40.2440 R11831.9602 F26775.7\nG2 X-63.4722 Y44.0318 Z-41.6539 R308.5003 F646.2\n"
           "G3 X-63.1209 Y44.0318 Z-41.0913 R96159.6909 F40446.3\nG1 X-63.0777 Y43.9190 Z-41.0913 F35677.6\n"
           "G3 X-63.1991 Y43.9190 Z-41.1601 R24.4002 F233.7\nM2\n",
           &slow_z, at190, "large radius 190 of seed 3, slow Z, 0.5 ms");
}

int main(int argc, char **argv)
{
    g_seed = (unsigned long)test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    print_message("seed %lu, count %ld (%s)\n", g_seed, g_count, LSM_REAL_IS_FLOAT ? "float" : "double");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_golden),
        cmocka_unit_test(test_mixed),
        cmocka_unit_test(test_large_radius),
        cmocka_unit_test(test_long_coordinates),
    };
    return cmocka_run_group_tests_name(LSM_REAL_IS_FLOAT ? "path_limits_float" : "path_limits", tests, NULL, NULL);
}
