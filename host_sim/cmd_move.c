/*
 * lissom-sim move: a synchronised point-to-point move (firmware/profile/move.h).
 *   lissom-sim move --distance D1[,D2,...] --vmax .. --amax .. --jmax .. --snap-max .. --cycle T
 *                   [--v0 ..] [--v1 ..] [--rule paper|strict] [--samples FILE.csv] --json
 * Each of --vmax/--amax/--jmax/--snap-max/--v0/--v1 takes one value for all axes or one per axis.
 * JSON: {"n_cycles","duration","axes":[{"jp","end_error",...}]}; end_error is where the closed form itself
 * lands (s(T) - D, mm) before the terminal state takes over, so it measures the plan's exactness.
 * --samples writes one row per cycle: t, then the position of each axis (p0, p1, ...).
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "move.h"

int cli_rule(cli_args *a, lsm_scurve_rule *rule);

/* Reads an option that is one value for all n axes or one per axis. Returns 0 ok, 1 absent, -1 error. */
static int per_axis(cli_args *a, const char *name, double *out, int n)
{
    double v[LSM_MAX_AXES];
    int k = cli_num_list(a, name, v, LSM_MAX_AXES);
    if (k < 0)
        return -1;
    if (k == 0)
        return 1;
    if (k != 1 && k != n) {
        fprintf(stderr, "error: --%s needs 1 or %d values, got %d\n", name, n, k);
        return -1;
    }
    for (int i = 0; i < n; i++)
        out[i] = v[k == 1 ? 0 : i];
    return 0;
}

int cmd_move(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    double dist[LSM_MAX_AXES];
    int n = cli_num_list(&a, "distance", dist, LSM_MAX_AXES);
    if (n <= 0) {
        if (n == 0)
            fprintf(stderr, "error: missing required option --distance\n");
        return 2;
    }
    double vmax[LSM_MAX_AXES], amax[LSM_MAX_AXES], jmax[LSM_MAX_AXES], snap[LSM_MAX_AXES];
    double v0[LSM_MAX_AXES] = {0}, v1[LSM_MAX_AXES] = {0}, cycle;
    const char *req_names[4] = {"vmax", "amax", "jmax", "snap-max"};
    double *req_vals[4] = {vmax, amax, jmax, snap};
    for (int k = 0; k < 4; k++) {
        int r = per_axis(&a, req_names[k], req_vals[k], n);
        if (r == 1)
            fprintf(stderr, "error: missing required option --%s\n", req_names[k]);
        if (r != 0)
            return 2;
    }
    if (per_axis(&a, "v0", v0, n) < 0 || per_axis(&a, "v1", v1, n) < 0 || cli_num_req(&a, "cycle", &cycle))
        return 2;
    lsm_move_request req;
    memset(&req, 0, sizeof req);
    if (cli_rule(&a, &req.rule))
        return 2;
    const char *samples = cli_opt(&a, "samples");
    const bool json = cli_flag(&a, "json");
    if (cli_check_unused(&a, "move"))
        return 2;
    for (int i = 0; i < n; i++) {
        if (cli_check_range("distance", dist[i], -CLI_DISTANCE_MAX, CLI_DISTANCE_MAX) ||
            cli_check_range("vmax", vmax[i], CLI_LIMIT_MIN, CLI_VEL_MAX) ||
            cli_check_range("amax", amax[i], CLI_LIMIT_MIN, CLI_ACC_MAX) ||
            cli_check_range("jmax", jmax[i], CLI_LIMIT_MIN, CLI_JERK_MAX) ||
            cli_check_range("snap-max", snap[i], CLI_LIMIT_MIN, CLI_SNAP_MAX) ||
            cli_check_range("v0", v0[i], -CLI_VEL_MAX, CLI_VEL_MAX) ||
            cli_check_range("v1", v1[i], -CLI_VEL_MAX, CLI_VEL_MAX))
            return 2;
    }
    if (cli_check_cycle("cycle", cycle) || (samples && cli_check_out_file("samples", samples)))
        return 2;

    req.n_axes = (uint8_t)n;
    req.cycle_s = (lsm_real)cycle;
    for (int i = 0; i < n; i++) {
        req.distance_mm[i] = (lsm_real)dist[i];
        req.v0_mm_s[i] = (lsm_real)v0[i];
        req.v1_mm_s[i] = (lsm_real)v1[i];
        req.lim[i] = (lsm_axis_limits){(lsm_real)vmax[i], (lsm_real)amax[i], (lsm_real)jmax[i], (lsm_real)snap[i]};
    }
    lsm_move mv;
    lsm_status st = lsm_move_plan(&mv, &req);
    if (st != LSM_OK) {
        fprintf(stderr, "error: move: %s (%d)\n", lsm_status_str(st), (int)st);
        return 1;
    }
    const uint32_t total = lsm_move_total_cycles(&mv);
    if (samples && cli_check_sample_rows("samples", (double)total + 1, cycle))
        return 2;
    if (json) {
        printf("{\"n_cycles\":%u,\"duration\":", total);
        json_num(stdout, lsm_move_duration_s(&mv));
        printf(",\"slowest_axis\":%u,\"acc\":{\"n1\":%u,\"n2\":%u,\"n4\":%u},\"cruise_cycles\":%u,"
               "\"dec\":{\"n1\":%u,\"n2\":%u,\"n4\":%u},\"axes\":[",
               mv.slowest_axis, mv.acc.n1_cycles, mv.acc.n2_cycles, mv.acc.n4_cycles, mv.cruise_cycles,
               mv.dec.n1_cycles, mv.dec.n2_cycles, mv.dec.n4_cycles);
        for (int i = 0; i < n; i++) {
            const lsm_move_axis *ax = &mv.axis[i];
            const double jp = ax->jp_acc_mm_s3 < 0 ? -ax->jp_acc_mm_s3 : ax->jp_acc_mm_s3;
            printf("%s{\"jp\":", i ? "," : "");
            json_num(stdout, jp);
            printf(",\"jp_acc\":");
            json_num(stdout, ax->dir * ax->jp_acc_mm_s3);
            printf(",\"jp_dec\":");
            json_num(stdout, ax->dir * ax->jp_dec_mm_s3);
            printf(",\"vc\":");
            json_num(stdout, ax->dir * ax->vc_mm_s);
            printf(",\"distance\":");
            json_num(stdout, ax->distance_mm);
            printf(",\"end_error\":");
            json_num(stdout, lsm_move_end_error_mm(&mv, (unsigned)i));
            printf("}");
        }
        printf("]}\n");
    } else {
        printf("move: %u cycles, %.6g s, slowest axis %u\n", total, (double)lsm_move_duration_s(&mv), mv.slowest_axis);
        for (int i = 0; i < n; i++)
            printf("  axis %d: vc %.6g mm/s, jp_acc %.6g, jp_dec %.6g mm/s^3, end error %.3g mm\n", i,
                   (double)mv.axis[i].vc_mm_s, (double)mv.axis[i].jp_acc_mm_s3, (double)mv.axis[i].jp_dec_mm_s3,
                   (double)lsm_move_end_error_mm(&mv, (unsigned)i));
    }
    if (samples) {
        FILE *out = fopen(samples, "w");
        if (!out) {
            fprintf(stderr, "error: cannot write %s\n", samples);
            return 1;
        }
        fprintf(out, "t");
        for (int i = 0; i < n; i++)
            fprintf(out, ",p%d", i);
        fprintf(out, "\n");
        for (uint32_t k = 0; k <= total; k++) {
            fprintf(out, "%.9g", k * cycle);
            for (int i = 0; i < n; i++) {
                lsm_kin kin;
                lsm_move_eval(&mv, (unsigned)i, (lsm_real)(k * cycle), &kin);
                fprintf(out, ",%.17g", (double)kin.s_mm);
            }
            fprintf(out, "\n");
        }
        fclose(out);
    }
    return 0;
}
