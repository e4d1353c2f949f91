/*
 * lissom-sim bench-clothoid: host timing of the clothoid code (a benchmark, not a test).
 *   lissom-sim bench-clothoid [--corners N] [--seed S] [--repeat R] [--steps N] [--corners-out FILE] [--json]
 *
 * - ns per corner smoothed (firmware/path/corner.h), over N seeded random corners (a quarter each of
 *   line-line in 3-D, line-arc, arc-line and arc-arc in G17; deflection 1..179 deg, radii 2..200 mm,
 *   tolerance 0.002..0.2 mm), each smoothed R times; also per kind;
 * - ns per incremental clothoid step (lsm_clothoid_step, 0.05 mm steps) and, for comparison, ns per
 *   direct evaluation at an arbitrary s (lsm_clothoid_eval);
 * - --corners-out FILE: one CSV row per smoothed corner with the transition's end states in its own
 *   plane (x0,y0,theta0,x1,y1,theta1), so that hil/lissom_hil/bench_clothoid.py can time pyclothoids'
 *   G1 fit (Clothoid.G1Hermite) on the same corners.
 * Timing: clock_gettime(CLOCK_MONOTONIC) around whole loops; the figures depend on the host.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "clothoid.h"
#include "commands.h"
#include "corner.h"

typedef struct {
    lsm_geom b1, b2;
    lsm_corner_params p;
    int kind; /* 0 line-line, 1 line-arc, 2 arc-line, 3 arc-arc */
} bc_corner;

static uint64_t g_rng;
static double bc_rand(void) /* xorshift64*, uniform in [0, 1) */
{
    g_rng ^= g_rng >> 12;
    g_rng ^= g_rng << 25;
    g_rng ^= g_rng >> 27;
    return (double)((g_rng * 2685821657736338717ull) >> 11) * (1.0 / 9007199254740992.0);
}
static double bc_uni(double a, double b)
{
    return a + (b - a) * bc_rand();
}

/* An arc in G17 that starts (or ends) at V with unit tangent t there, radius r, turning `turn` rad
 * (signed: > 0 counter-clockwise). */
static lsm_status bc_arc(lsm_geom *g, const double V[3], const double t[2], double r, double turn, int ends_at_v)
{
    const double s = turn > 0 ? 1.0 : -1.0;
    /* centre: left of the tangent for counter-clockwise */
    const double c[3] = {V[0] - s * t[1] * r, V[1] + s * t[0] * r, V[2]};
    const double a0 = atan2(V[1] - c[1], V[0] - c[0]);
    const double a1 = ends_at_v ? a0 - turn : a0 + turn;
    const lsm_real o[3] = {(lsm_real)(c[0] + r * cos(a1)), (lsm_real)(c[1] + r * sin(a1)), (lsm_real)V[2]};
    const lsm_real v[3] = {(lsm_real)V[0], (lsm_real)V[1], (lsm_real)V[2]};
    const lsm_real cr[3] = {(lsm_real)c[0], (lsm_real)c[1], (lsm_real)c[2]};
    return ends_at_v ? lsm_geom_arc_init(g, o, v, cr, LSM_GEOM_PLANE_XY, turn > 0 ? 1 : -1, 0)
                     : lsm_geom_arc_init(g, v, o, cr, LSM_GEOM_PLANE_XY, turn > 0 ? 1 : -1, 0);
}

static void bc_make(bc_corner *k, int kind)
{
    const double V[3] = {bc_uni(-50, 50), bc_uni(-50, 50), kind == 0 ? bc_uni(-20, 20) : 3.0};
    const double a1 = bc_uni(-LSM_PI, LSM_PI);
    const double delta = bc_uni(1.0, 179.0) * LSM_PI / 180.0 * (bc_rand() < 0.5 ? -1 : 1);
    const double t1[2] = {cos(a1), sin(a1)}, t2[2] = {cos(a1 + delta), sin(a1 + delta)};
    const double l1 = bc_uni(2, 40), l2 = bc_uni(2, 40);
    k->kind = kind;
    k->p.tolerance_mm = exp(bc_uni(log(0.002), log(0.2)));
    k->p.max_trim1_mm = k->p.max_trim2_mm = 0.0;
    if (kind == 0) {
        /* 3-D: tilt the second direction out of the plane */
        const double tz = bc_uni(-0.5, 0.5);
        const lsm_real p0[6] = {(lsm_real)(V[0] - l1 * t1[0]),
                                (lsm_real)(V[1] - l1 * t1[1]),
                                (lsm_real)(V[2] - l1 * bc_uni(-0.5, 0.5)),
                                0,
                                0,
                                0};
        const lsm_real pv[6] = {(lsm_real)V[0], (lsm_real)V[1], (lsm_real)V[2], 0, 0, 0};
        const lsm_real p2[6] =
            {(lsm_real)(V[0] + l2 * t2[0]), (lsm_real)(V[1] + l2 * t2[1]), (lsm_real)(V[2] + l2 * tz), 0, 0, 0};
        lsm_geom_line_init(&k->b1, p0, pv);
        lsm_geom_line_init(&k->b2, pv, p2);
        return;
    }
    const double r1 = exp(bc_uni(log(2.0), log(200.0))), r2 = exp(bc_uni(log(2.0), log(200.0)));
    const double turn1 = (bc_rand() < 0.5 ? -1 : 1) * fmin(l1 / r1, 2.0);
    const double turn2 = (bc_rand() < 0.5 ? -1 : 1) * fmin(l2 / r2, 2.0);
    if (kind == 2 || kind == 3)
        bc_arc(&k->b1, V, t1, r1, turn1, 1);
    else
        lsm_geom_line_init(&k->b1,
                           (lsm_real[6]){(lsm_real)(V[0] - l1 * t1[0]), (lsm_real)(V[1] - l1 * t1[1]), (lsm_real)V[2],
                                         0, 0, 0},
                           (lsm_real[6]){(lsm_real)V[0], (lsm_real)V[1], (lsm_real)V[2], 0, 0, 0});
    if (kind == 1 || kind == 3)
        bc_arc(&k->b2, V, t2, r2, turn2, 0);
    else
        lsm_geom_line_init(&k->b2, (lsm_real[6]){(lsm_real)V[0], (lsm_real)V[1], (lsm_real)V[2], 0, 0, 0},
                           (lsm_real[6]){(lsm_real)(V[0] + l2 * t2[0]), (lsm_real)(V[1] + l2 * t2[1]), (lsm_real)V[2],
                                         0, 0, 0});
}

static double bc_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static volatile double g_sink;

int cmd_bench_clothoid(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    double nc = 2000, seed = 1, rep = 20, nsteps = 200000;
    if (cli_num(&a, "corners", &nc) < 0 || cli_num(&a, "seed", &seed) < 0 || cli_num(&a, "repeat", &rep) < 0 ||
        cli_num(&a, "steps", &nsteps) < 0)
        return 2;
    const char *out_path = cli_opt(&a, "corners-out");
    const bool json = cli_flag(&a, "json");
    if (cli_check_unused(&a, "bench-clothoid"))
        return 2;
    if (!(nc >= 4 && nc <= 1e6 && rep >= 1 && rep <= 1e4 && nsteps >= 1 && nsteps <= 1e9)) {
        fprintf(stderr, "error: bench-clothoid: --corners 4..1e6, --repeat 1..1e4, --steps 1..1e9\n");
        return 2;
    }
    const int n = (int)nc, R = (int)rep;
    g_rng = (uint64_t)seed * 0x9E3779B97F4A7C15ull + 1u;
    bc_corner *k = calloc((size_t)n, sizeof *k);
    lsm_corner_result *res = calloc((size_t)n, sizeof *res);
    lsm_status *st = calloc((size_t)n, sizeof *st);
    if (!k || !res || !st) {
        fprintf(stderr, "error: bench-clothoid: out of memory\n");
        return 1;
    }
    for (int i = 0; i < n; i++)
        bc_make(&k[i], i % 4);
    double t_kind[4] = {0, 0, 0, 0};
    int n_kind[4] = {0, 0, 0, 0}, failed = 0, it_max = 0, sc_max = 0;
    long iters = 0, scales = 0;
    for (int kind = 0; kind < 4; kind++) {
        const double t0 = bc_now_ns();
        for (int r = 0; r < R; r++)
            for (int i = kind; i < n; i += 4)
                st[i] = lsm_corner_smooth(&k[i].b1, &k[i].b2, &k[i].p, &res[i]);
        t_kind[kind] = bc_now_ns() - t0;
        for (int i = kind; i < n; i += 4) {
            n_kind[kind]++;
            failed += st[i] != LSM_OK;
            if (st[i] == LSM_OK && kind > 0) {
                iters += res[i].iterations;
                scales += res[i].scales;
                if (res[i].iterations > it_max)
                    it_max = res[i].iterations;
                if (res[i].scales > sc_max)
                    sc_max = res[i].scales;
            }
        }
    }
    double t_all = 0;
    for (int kind = 0; kind < 4; kind++)
        t_all += t_kind[kind];

    /* stepping vs direct evaluation */
    lsm_clothoid cl;
    lsm_clothoid_init(&cl, 0, 0, 0.3, 0.02, 0.004, 1e9);
    lsm_clothoid_stepper sp;
    lsm_clothoid_stepper_init(&sp, &cl, 0, 1000);
    lsm_clothoid_state s;
    const long ns_ = (long)nsteps;
    double t0 = bc_now_ns();
    for (long i = 0; i < ns_; i++) {
        lsm_clothoid_step(&sp, 0.05, &s);
        if (sp.s_mm > 200.0) /* keep the curvature moderate: restart */
            lsm_clothoid_stepper_init(&sp, &cl, 0, 1000);
    }
    const double t_step = (bc_now_ns() - t0) / (double)ns_;
    g_sink = s.x_mm;
    const long ne = ns_ / 10 > 0 ? ns_ / 10 : 1;
    t0 = bc_now_ns();
    for (long i = 0; i < ne; i++) {
        lsm_clothoid_eval(&cl, 0.05 * (double)(i % 4000), &s);
        g_sink += s.x_mm;
    }
    const double t_eval = (bc_now_ns() - t0) / (double)ne;

    if (out_path) {
        FILE *f = fopen(out_path, "w");
        if (!f) {
            fprintf(stderr, "error: bench-clothoid: cannot write '%s'\n", out_path);
            return 1;
        }
        fprintf(f, "kind,x0,y0,theta0,x1,y1,theta1\n");
        for (int i = 0; i < n; i++) {
            if (st[i] != LSM_OK)
                continue;
            const lsm_geom_clothoid *A = &res[i].trans[0].u.clo, *B = &res[i].trans[1].u.clo;
            const double L = res[i].trans[1].len;
            lsm_real pe[LSM_MAX_AXES];
            lsm_geom_eval(&res[i].trans[1], (lsm_real)L, pe, NULL, NULL);
            double x1 = 0, y1 = 0;
            for (int d = 0; d < 3; d++) {
                x1 += (pe[d] - A->origin_mm[d]) * A->e1[d];
                y1 += (pe[d] - A->origin_mm[d]) * A->e2[d];
            }
            const double th1 = B->theta0_rad + L * (B->kappa0_per_mm + 0.5 * B->c_per_mm2 * L);
            fprintf(f, "%d,0,0,%.17g,%.17g,%.17g,%.17g\n", k[i].kind, A->theta0_rad, x1, y1, th1);
        }
        fclose(f);
    }
    const char *names[4] = {"line_line", "line_arc", "arc_line", "arc_arc"};
    if (json) {
        printf("{\"corners\": %d, \"repeat\": %d, \"failed\": %d, \"ns_per_corner\": %.1f", n, R, failed,
               t_all / ((double)n * R));
        for (int kind = 0; kind < 4; kind++)
            printf(", \"ns_per_corner_%s\": %.1f", names[kind], t_kind[kind] / ((double)n_kind[kind] * R));
        printf(", \"newton_iterations_per_arc_corner\": %.2f, \"newton_iterations_max\": %d",
               (double)iters / (double)(n_kind[1] + n_kind[2] + n_kind[3]), it_max);
        printf(", \"scales_per_arc_corner\": %.2f, \"scales_max\": %d",
               (double)scales / (double)(n_kind[1] + n_kind[2] + n_kind[3]), sc_max);
        printf(", \"ns_per_step\": %.2f, \"ns_per_eval\": %.2f, \"steps\": %ld}\n", t_step, t_eval, ns_);
    } else {
        printf("corners: %d x %d, failed %d: %.0f ns per corner\n", n, R, failed, t_all / ((double)n * R));
        for (int kind = 0; kind < 4; kind++)
            printf("  %-10s %8.0f ns\n", names[kind], t_kind[kind] / ((double)n_kind[kind] * R));
        printf("clothoid step %.1f ns, direct eval %.1f ns\n", t_step, t_eval);
    }
    free(k);
    free(res);
    free(st);
    return 0;
}
