/*
 * lissom-sim scurve: plans one sin² velocity change (firmware/profile/scurve.h) and prints it as JSON.
 *   lissom-sim scurve --v0 V0 --v1 V1 --amax A --jmax J --snap-max DJ --cycle T [--rule paper|strict]
 *                     [--samples FILE.csv] --json
 * Units are any consistent set (mm, s by convention; the algorithm is dimensionally homogeneous, so the
 * paper's m/s inputs give the paper's m/s outputs).
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "scurve.h"

int cli_rule(cli_args *a, lsm_scurve_rule *rule)
{
    const char *r = cli_opt(a, "rule");
    *rule = LSM_SCURVE_RULE_STRICT;
    if (r == NULL || strcmp(r, "strict") == 0)
        return 0;
    if (strcmp(r, "paper") == 0) {
        *rule = LSM_SCURVE_RULE_PAPER;
        return 0;
    }
    fprintf(stderr, "error: --rule must be 'paper' or 'strict', not '%s'\n", r);
    return -1;
}

int cmd_scurve(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    double v0, v1, amax, jmax, snap, cycle;
    if (cli_num_req(&a, "v0", &v0) || cli_num_req(&a, "v1", &v1) || cli_num_req(&a, "amax", &amax) ||
        cli_num_req(&a, "jmax", &jmax) || cli_num_req(&a, "snap-max", &snap) || cli_num_req(&a, "cycle", &cycle))
        return 2;
    lsm_scurve_rule rule;
    if (cli_rule(&a, &rule))
        return 2;
    const char *samples = cli_opt(&a, "samples");
    const bool json = cli_flag(&a, "json");
    if (cli_check_unused(&a, "scurve"))
        return 2;
    if (cli_check_range("v0", v0, 0, CLI_VEL_MAX) || cli_check_range("v1", v1, 0, CLI_VEL_MAX) ||
        cli_check_range("amax", amax, CLI_LIMIT_MIN, CLI_ACC_MAX) ||
        cli_check_range("jmax", jmax, CLI_LIMIT_MIN, CLI_JERK_MAX) ||
        cli_check_range("snap-max", snap, CLI_LIMIT_MIN, CLI_SNAP_MAX) || cli_check_cycle("cycle", cycle) ||
        (samples && cli_check_out_file("samples", samples)))
        return 2;

    const lsm_scurve_limits lim = {(lsm_real)amax, (lsm_real)jmax, (lsm_real)snap};
    lsm_scurve sc;
    lsm_scurve_info inf;
    lsm_status st = lsm_scurve_plan(&sc, &lim, (lsm_real)cycle, (lsm_real)v0, (lsm_real)v1, rule, &inf);
    if (st != LSM_OK) {
        fprintf(stderr, "error: scurve: %s (%d)\n", lsm_status_str(st), (int)st);
        return 1;
    }
    if (samples && cli_check_sample_rows("samples", (double)lsm_scurve_total_cycles(&sc.iv) + 1, cycle))
        return 2;
    const double dt = cycle;
    const double jp = sc.jp_mm_s3 < 0 ? -sc.jp_mm_s3 : sc.jp_mm_s3;
    struct {
        const char *k;
        double v;
    } f[] = {
        {"dt1", sc.iv.n1_cycles * dt},
        {"dt2", sc.iv.n2_cycles * dt},
        {"dt4", sc.iv.n4_cycles * dt},
        {"tp", lsm_scurve_duration_s(&sc)},
        {"dt1j", inf.dt1j_s},
        {"dt1a", inf.dt1a_s},
        {"dt1f", inf.dt1f_s},
        {"dt2a", inf.dt2a_s},
        {"dt2f", inf.dt2f_s},
        {"dt4f", inf.dt4f_s},
        {"jp_initial", inf.jp_initial_mm_s3},
        {"jp", jp},
        {"ap", inf.ap_mm_s2},
        {"ap_final", inf.ap_final_mm_s2},
        {"snap_final", inf.snap_final_mm_s4},
        {"distance", lsm_scurve_distance_mm(&sc)},
    };
    if (json) {
        printf("{\"rule\":\"%s\",\"n1\":%u,\"n2\":%u,\"n4\":%u", rule == LSM_SCURVE_RULE_PAPER ? "paper" : "strict",
               sc.iv.n1_cycles, sc.iv.n2_cycles, sc.iv.n4_cycles);
        for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) {
            printf(",\"%s\":", f[i].k);
            json_num(stdout, f[i].v);
        }
        printf(",\"direction\":\"%s\"}\n", sc.jp_mm_s3 < 0 ? "down" : "up");
    } else {
        printf("rule %s: n1=%u n2=%u n4=%u\n", rule == LSM_SCURVE_RULE_PAPER ? "paper" : "strict", sc.iv.n1_cycles,
               sc.iv.n2_cycles, sc.iv.n4_cycles);
        for (size_t i = 0; i < sizeof f / sizeof f[0]; i++)
            printf("  %-11s %.6g\n", f[i].k, f[i].v);
    }
    if (samples) {
        FILE *out = fopen(samples, "w");
        if (!out) {
            fprintf(stderr, "error: cannot write %s\n", samples);
            return 1;
        }
        fprintf(out, "t,j,a,v,s\n");
        const uint32_t n = lsm_scurve_total_cycles(&sc.iv);
        for (uint32_t k = 0; k <= n; k++) {
            lsm_kin kin;
            lsm_scurve_eval(&sc, (lsm_real)(k * dt), &kin);
            fprintf(out, "%.9g,%.17g,%.17g,%.17g,%.17g\n", k * dt, kin.j_mm_s3, kin.a_mm_s2, kin.v_mm_s, kin.s_mm);
        }
        fclose(out);
    }
    return 0;
}
