/*
 * lissom-sim bench-planner: the real-time planner (lissom) against the VPOp-style offline reference (vpop.h) on
 * the example programs, on identical geometry (both run through sim_run_program(): G-code, arc fitting, G2 corner
 * smoothing; VPOp then plans the planner's geometry). A benchmark, not a test.
 *
 *   lissom-sim bench-planner [--json] [--root DIR] [--only NAME] [--out DIR]
 *
 * For every case: duration of each planner, their ratio (lissom / vpop), for each the largest axis velocity,
 * acceleration and jerk as a ratio to the axis limit (backward differences, Beudaert eq 6), host ns per appended
 * block (lissom planner) and per cycle (lissom interpolator; for vpop the planning time per setpoint), and vpop's
 * total planning time, lissom's background piece planning per piece (lsm_interp_prepare), and the continuous axis
 * jerk that vpop's motion asks between its samples (largest and 99th percentile over the samples, as a ratio to the
 * limit: VPOp holds the limit at the samples only, the real-time planner everywhere; pathrun.h). Cases: the trident polyline on the Beudaert Table 1 machine, the circle of 0.1 mm chords,
 * the pocket and the 3-D surface on the router, and the trident on the B-spline itself (vpop only: Beudaert
 * section 3.1, programmed feed and control points from host_sim/examples/trident_bspline.json), with the switching
 * step refined (SIM_VPOP_REFINE, as `run --planner vpop`) and, as trident-bspline-0, without (the paper's rule).
 * DIR (default: the repository of this executable, else the current directory) holds host_sim/examples and
 * host_sim/machines. --only runs one case (trident, circle, pocket, surface, trident-bspline, trident-bspline-0).
 * --out DIR writes the B-spline trident's setpoints (DIR/trident_bspline.csv, trident_bspline_0.csv: t, s, X, Y,
 * feed_mm_s = the backward difference of s).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "machine.h"
#include "pathrun.h"
#include "vpop.h"

typedef struct bp_case {
    const char *name, *program, *machine;
} bp_case;

static const bp_case k_cases[] = {
    {"trident", "host_sim/examples/trident.ngc", "host_sim/machines/beudaert_table1.json"},
    {"circle", "host_sim/examples/circle_chords.ngc", "host_sim/machines/router.json"},
    {"pocket", "host_sim/examples/pocket.ngc", "host_sim/machines/router.json"},
    {"surface", "host_sim/examples/surface_finish.ngc", "host_sim/machines/router.json"},
};

typedef struct bp_row {
    const char *name;
    int has_lissom;
    double dur[2];              /* lissom, vpop (s) */
    double rv[2], ra[2], rj[2]; /* largest axis v/a/j over its limit */
    double ns_block, ns_cycle;  /* lissom planner / interpolator */
    double vpop_ns_cycle, vpop_s;
    double ns_piece;         /* lissom: background piece planning (lsm_interp_prepare) per piece */
    double isj_max, isj_p99; /* vpop: continuous axis jerk its motion asks between samples / J (pathrun.h) */
    double dur_c;            /* vpop-cont (pathrun.h), the continuous-limit reference: duration (-1 n/a) */
    double cr_c[3];          /* its largest axis v/a/j over the limits on its continuous motion (vp_cont_verify) */
    double cj_vpop;          /* plain VPOp's continuous jerk / J by the same measure (-1 n/a) */
    double cs_s;             /* the reference's planning time on the host (s) */
} bp_row;

static double bp_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void bp_ratios(const sim_machine *m, const double *v, const double *a, const double *j, double *rv, double *ra,
                      double *rj)
{
    *rv = *ra = *rj = 0;
    for (int i = 0; i < m->n_axes; i++) {
        const sim_machine_axis *x = &m->axes[i];
        const int k = x->index;
        *rv = fmax(*rv, v[k] / x->v_max_u_s);
        *ra = fmax(*ra, a[k] / x->a_max_u_s2);
        *rj = fmax(*rj, j[k] / x->j_max_u_s3);
    }
}

static int bp_program(const char *root, const bp_case *c, bp_row *row)
{
    char pp[1200], mp[1200], err[256];
    snprintf(pp, sizeof pp, "%s/%s", root, c->program);
    snprintf(mp, sizeof mp, "%s/%s", root, c->machine);
    sim_machine m;
    if (sim_machine_load_file(mp, &m, err, sizeof err) != SIM_MACHINE_OK) {
        fprintf(stderr, "error: %s\n", err);
        return -1;
    }
    size_t len = 0;
    char *text = sim_read_file(pp, &len);
    if (!text) {
        fprintf(stderr, "error: cannot read %s\n", pp);
        return -1;
    }
    memset(row, 0, sizeof *row);
    row->name = c->name;
    row->has_lissom = 1;
    row->dur_c = row->cj_vpop = -1;
    for (int k = 0; k < 3; k++) {
        sim_run_opts o;
        memset(&o, 0, sizeof o);
        o.machine = &m;
        o.text = text;
        o.len = len;
        o.planner = k == 2 ? SIM_RUN_VPOP_CONT : k ? SIM_RUN_VPOP : SIM_RUN_LISSOM;
        sim_run_result r;
        const double t0 = bp_now();
        if (sim_run_program(&o, &r) != 0) {
            fprintf(stderr, "error: %s (%s): %s\n", c->program, sim_run_planner_name(o.planner), r.err);
            sim_run_free(&r);
            free(text);
            return -1;
        }
        const double wall = bp_now() - t0;
        if (k == 2) {
            row->dur_c = r.duration_s;
            memcpy(row->cr_c, r.cont_ratio, sizeof row->cr_c);
            row->cs_s = wall;
            sim_run_free(&r);
            continue;
        }
        row->dur[k] = r.duration_s;
        bp_ratios(&m, r.max_v, r.max_a, r.max_j, &row->rv[k], &row->ra[k], &row->rj[k]);
        if (k == 0) {
            row->ns_block = r.plan_ns_per_block;
            row->ns_cycle = r.interp_ns_per_cycle;
            row->ns_piece = r.prepare_ns_per_piece;
        } else {
            row->vpop_ns_cycle = r.interp_ns_per_cycle;
            row->vpop_s = wall;
            row->isj_max = r.intersample_jerk_max;
            row->isj_p99 = r.intersample_jerk_p99;
            row->cj_vpop = r.cont_ratio[2];
        }
        sim_run_free(&r);
    }
    free(text);
    return 0;
}

static int bp_bspline(const char *root, int refine, const char *out, bp_row *row)
{
    char bp[1200], mp[1200], err[256];
    snprintf(bp, sizeof bp, "%s/host_sim/examples/trident_bspline.json", root);
    snprintf(mp, sizeof mp, "%s/host_sim/machines/beudaert_table1.json", root);
    sim_machine m;
    if (sim_machine_load_file(mp, &m, err, sizeof err) != SIM_MACHINE_OK) {
        fprintf(stderr, "error: %s\n", err);
        return -1;
    }
    sim_bspline b;
    if (sim_bspline_load(bp, &b, 4096, err, sizeof err) != 0) {
        fprintf(stderr, "error: %s\n", err);
        return -1;
    }
    sim_vpop_path p = sim_bspline_path(&b);
    sim_vpop_limits lim;
    memset(&lim, 0, sizeof lim);
    for (int i = 0; i < m.n_axes; i++) { /* the spline is in X Y */
        const int k = m.axes[i].index;
        if (k > 1)
            continue;
        lim.axis_mask |= (uint8_t)(1u << k);
        lim.v[k] = m.axes[i].v_max_u_s;
        lim.a[k] = m.axes[i].a_max_u_s2;
        lim.j[k] = m.axes[i].j_max_u_s3;
    }
    lim.refine_iters = refine;
    double *S = NULL;
    size_t n = 0;
    sim_vpop_stats st;
    const double t0 = bp_now();
    const int rc = sim_vpop_plan(&p, &lim, m.cycle_s, (size_t)(600 / m.cycle_s), &S, &n, &st);
    const double wall = bp_now() - t0;
    if (rc != 0) {
        fprintf(stderr, "error: vpop on the trident B-spline: no motion found\n");
        sim_bspline_free(&b);
        return -1;
    }
    if (out) { /* the setpoints, for plots (the paper's Fig. 5: feed along the path) */
        char path[1400];
        FILE *f = cli_open_out(out, refine ? "trident_bspline.csv" : "trident_bspline_0.csv", path, sizeof path);
        if (!f) {
            free(S);
            sim_bspline_free(&b);
            return -1;
        }
        fprintf(f, "t,s,X,Y,feed_mm_s\n");
        double prev = 0;
        for (size_t k = 0; k < n; k++) {
            double q[SIM_VPOP_AXES] = {0};
            p.eval(p.ctx, S[k], q);
            fprintf(f, "%.6g,%.12g,%.12g,%.12g,%.9g\n", (double)(k + 1) * m.cycle_s, S[k], q[0], q[1],
                    (S[k] - prev) / m.cycle_s);
            prev = S[k];
        }
        fclose(f);
        fprintf(stderr, "wrote %s\n", path);
    }
    double v[SIM_VPOP_AXES], a[SIM_VPOP_AXES], j[SIM_VPOP_AXES];
    sim_vpop_measure(&p, S, n, m.cycle_s, v, a, j);
    memset(row, 0, sizeof *row);
    row->name = refine ? "trident-bspline" : "trident-bspline-0";
    row->dur[1] = (double)n * m.cycle_s;
    sim_machine m2 = m; /* ratios over X and Y only */
    m2.n_axes = 0;
    for (int i = 0; i < m.n_axes; i++)
        if (m.axes[i].index <= 1)
            m2.axes[m2.n_axes++] = m.axes[i];
    bp_ratios(&m2, v, a, j, &row->rv[1], &row->ra[1], &row->rj[1]);
    row->vpop_s = wall;
    row->vpop_ns_cycle = n ? 1e9 * wall / (double)n : 0;
    row->isj_max = row->isj_p99 = -1; /* (not measured on the spline) */
    row->dur_c = row->cj_vpop = -1;
    free(S);
    sim_bspline_free(&b);
    return 0;
}

/* The repository: <repo>/<build>/bin/lissom-sim -> <repo>, if it has host_sim/examples; else ".". */
static void bp_root(char *out, size_t n)
{
    char exe[1024];
    const ssize_t k = readlink("/proc/self/exe", exe, sizeof exe - 1);
    snprintf(out, n, ".");
    if (k <= 0)
        return;
    exe[k] = '\0';
    for (int up = 0; up < 3; up++) {
        char *sl = strrchr(exe, '/');
        if (!sl)
            return;
        *sl = '\0';
    }
    char probe[1100];
    snprintf(probe, sizeof probe, "%s/host_sim/examples/trident.ngc", exe);
    if (access(probe, R_OK) == 0)
        snprintf(out, n, "%s", exe);
}

int cmd_bench_planner(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    const bool json = cli_flag(&a, "json");
    const char *root_opt = cli_opt(&a, "root");
    const char *only = cli_opt(&a, "only");
    const char *out = cli_opt(&a, "out");
    if (cli_check_unused(&a, "bench-planner") != 0 || (out && cli_check_out_dir("out", out)))
        return 2;
    char root[1024];
    if (root_opt)
        snprintf(root, sizeof root, "%s", root_opt);
    else
        bp_root(root, sizeof root);
    bp_row rows[8];
    int nr = 0;
    const size_t nc = sizeof k_cases / sizeof k_cases[0];
    for (size_t i = 0; i < nc; i++) {
        if (only && strcmp(only, k_cases[i].name) != 0)
            continue;
        if (bp_program(root, &k_cases[i], &rows[nr]) != 0)
            return 1;
        nr++;
    }
    for (int refine = SIM_VPOP_REFINE; refine >= 0; refine -= SIM_VPOP_REFINE) {
        if (only && strcmp(only, refine ? "trident-bspline" : "trident-bspline-0") != 0)
            continue;
        if (bp_bspline(root, refine, out, &rows[nr]) != 0)
            return 1;
        nr++;
    }
    if (nr == 0) {
        fprintf(stderr, "error: --only: unknown case '%s'\n", only);
        return 2;
    }
    if (json) {
        printf("{\n  \"cases\": [");
        for (int i = 0; i < nr; i++) {
            const bp_row *r = &rows[i];
            printf("%s\n    {\"name\": \"%s\"", i ? "," : "", r->name);
            if (r->has_lissom) {
                printf(", \"lissom\": {\"duration\": ");
                json_num(stdout, r->dur[0]);
                printf(", \"max_v_ratio\": ");
                json_num(stdout, r->rv[0]);
                printf(", \"max_a_ratio\": ");
                json_num(stdout, r->ra[0]);
                printf(", \"max_j_ratio\": ");
                json_num(stdout, r->rj[0]);
                printf(", \"ns_per_block\": ");
                json_num(stdout, r->ns_block);
                printf(", \"ns_per_cycle\": ");
                json_num(stdout, r->ns_cycle);
                printf(", \"ns_per_piece\": ");
                json_num(stdout, r->ns_piece);
                printf("}");
            }
            printf(", \"vpop\": {\"duration\": ");
            json_num(stdout, r->dur[1]);
            printf(", \"max_v_ratio\": ");
            json_num(stdout, r->rv[1]);
            printf(", \"max_a_ratio\": ");
            json_num(stdout, r->ra[1]);
            printf(", \"max_j_ratio\": ");
            json_num(stdout, r->rj[1]);
            printf(", \"ns_per_cycle\": ");
            json_num(stdout, r->vpop_ns_cycle);
            printf(", \"planning_s\": ");
            json_num(stdout, r->vpop_s);
            if (r->isj_max >= 0) {
                printf(", \"intersample_jerk_ratio\": {\"max\": ");
                json_num(stdout, r->isj_max);
                printf(", \"p99\": ");
                json_num(stdout, r->isj_p99);
                printf("}");
            }
            printf("}");
            if (r->cj_vpop >= 0) {
                printf(", \"vpop_continuous_jerk_ratio\": ");
                json_num(stdout, r->cj_vpop);
            }
            if (r->dur_c > 0) {
                printf(", \"vpop_cont\": {\"duration\": ");
                json_num(stdout, r->dur_c);
                printf(", \"continuous_ratio\": {\"v\": ");
                json_num(stdout, r->cr_c[0]);
                printf(", \"a\": ");
                json_num(stdout, r->cr_c[1]);
                printf(", \"j\": ");
                json_num(stdout, r->cr_c[2]);
                printf("}, \"planning_s\": ");
                json_num(stdout, r->cs_s);
                printf("}");
            }
            if (r->has_lissom) {
                printf(", \"ratio\": ");
                json_num(stdout, r->dur[0] / r->dur[1]);
                if (r->dur_c > 0) {
                    printf(", \"ratio_cont\": ");
                    json_num(stdout, r->dur[0] / r->dur_c);
                }
            }
            printf("}");
        }
        printf("\n  ]\n}\n");
        return 0;
    }
    printf("%-16s %9s %9s %6s %9s %6s  %-17s  %-17s  %-20s  %8s  %11s  %9s %9s %10s %9s %9s\n", "case", "lissom s",
           "vpop s", "ratio", "vpop-c s", "ratio", "lissom v/a/j", "vpop v/a/j", "vpop-c cont v/a/j", "vpop cj",
           "vpop isj", "ns/block", "ns/cycle", "ns/piece", "vpop s", "cs s");
    for (int i = 0; i < nr; i++) {
        const bp_row *r = &rows[i];
        char isj[32] = "-", cs[16] = "-", cr[16] = "-", ccr[48] = "-", cj[16] = "-", css[16] = "-";
        if (r->isj_max >= 0)
            snprintf(isj, sizeof isj, "%.2f/%.2f", r->isj_max, r->isj_p99);
        if (r->cj_vpop >= 0)
            snprintf(cj, sizeof cj, "%.3f", r->cj_vpop);
        if (r->dur_c > 0) {
            snprintf(cs, sizeof cs, "%.3f", r->dur_c);
            snprintf(cr, sizeof cr, "%.3f", r->dur[0] / r->dur_c);
            snprintf(ccr, sizeof ccr, "%.3f/%.3f/%.6f", r->cr_c[0], r->cr_c[1], r->cr_c[2]);
            snprintf(css, sizeof css, "%.3f", r->cs_s);
        }
        if (r->has_lissom)
            printf("%-16s %9.3f %9.3f %6.3f %9s %6s  %5.3f/%5.3f/%5.3f  %5.3f/%5.3f/%5.3f  %-20s  %8s  %11s  %9.0f "
                   "%9.0f "
                   "%10.0f %9.3f %9s\n",
                   r->name, r->dur[0], r->dur[1], r->dur[0] / r->dur[1], cs, cr, r->rv[0], r->ra[0], r->rj[0], r->rv[1],
                   r->ra[1], r->rj[1], ccr, cj, isj, r->ns_block, r->ns_cycle, r->ns_piece, r->vpop_s, css);
        else
            printf("%-16s %9s %9.3f %6s %9s %6s  %17s  %5.3f/%5.3f/%5.3f  %-20s  %8s  %11s  %9s %9s %10s %9.3f %9s\n",
                   r->name, "-", r->dur[1], "-", "-", "-", "-", r->rv[1], r->ra[1], r->rj[1], "-", "-", isj, "-", "-",
                   "-", r->vpop_s, "-");
    }
    printf(
        "\nvpop isj: the continuous axis jerk VPOp's motion asks between its samples, over the limit (largest / 99th "
        "percentile; it holds the limit at the samples only); lissom holds it everywhere.\n"
        "vpop-c: the continuous-limit reference (run --planner vpop-cont): VPOp whose every step also holds v, a and "
        "j continuously between its samples (Beudaert eq 3 on the exact path derivatives, the motion between samples "
        "being their cubic B-spline); ratio = lissom / vpop-c. `vpop-c cont v/a/j`: the largest axis v/a/j over the "
        "limits on that continuous motion, measured independently (resampled 32 times a cycle, finite differences of "
        "the exact positions); `vpop cj`: plain VPOp's continuous jerk / J by the same measure. `cs s`: the "
        "reference's planning time on the host.\n");
    return 0;
}
