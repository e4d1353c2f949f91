/*
 * lissom-sim demo: the main job of the Quick start. Plans one point-to-point move with the firmware's sin²
 * S-curve (Kombarov Table 1 Test 2 limits, in mm), runs the per-cycle evaluator over it, and writes
 *   OUT/scurve.csv   one row per cycle: t,j,a,v,s (s, mm/s^3, mm/s^2, mm/s, mm)
 *   OUT/scurve.png   J, A, V and S against time (plotted by the Python module lissom_hil.plot)
 * and prints a summary: duration, peaks against the limits, end error.
 *   lissom-sim demo [--out DIR] [--distance MM] [--no-plot]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "move.h"
#include "stepgen.h"

/* `python -m lissom_hil.plot KIND CSV --out PNG` */
int sim_plot(const char *kind, const char *csv, const char *png)
{
    char args[9400];
    snprintf(args, sizeof args, "%s '%s' --out '%s'", kind, csv, png);
    return cli_plot(args);
}

int cmd_demo(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    const char *out = cli_opt(&a, "out");
    double dist = 100;
    if (cli_num(&a, "distance", &dist) < 0)
        return 2;
    const bool no_plot = cli_flag(&a, "no-plot");
    if (cli_check_unused(&a, "demo"))
        return 2;
    if (!out)
        out = "out/demo";
    if (cli_check_range("distance", dist, -CLI_DISTANCE_MAX, CLI_DISTANCE_MAX) || cli_check_out_dir("out", out))
        return 2;
    /* Kombarov Table 1, Test 2 (A 1.57 m/s², J 16 m/s³, DJ 560 m/s⁴, feed 13.2 m/min), in mm */
    lsm_move_request req;
    memset(&req, 0, sizeof req);
    req.n_axes = 1;
    req.cycle_s = (lsm_real)0.001;
    req.rule = LSM_SCURVE_RULE_STRICT;
    req.distance_mm[0] = (lsm_real)dist;
    req.lim[0] = (lsm_axis_limits){220, 1570, 16000, 560000};
    lsm_move mv;
    lsm_status st = lsm_move_plan(&mv, &req);
    if (st != LSM_OK) {
        fprintf(stderr, "error: demo move: %s (%d)\n", lsm_status_str(st), (int)st);
        return 1;
    }
    char csv[4200], png[4200];
    snprintf(png, sizeof png, "%s/scurve.png", out);
    FILE *f = cli_open_out(out, "scurve.csv", csv, sizeof csv);
    if (!f)
        return 1;
    fprintf(f, "t,j,a,v,s\n");
    lsm_stepgen g;
    lsm_stepgen_init(&g, &mv, NULL);
    const uint32_t n = lsm_move_total_cycles(&mv);
    double pj = 0, pa = 0, pv = 0, max_gen_dev = 0;
    lsm_real pos = 0;
    fprintf(f, "0,0,0,0,0\n");
    for (uint32_t k = 1; k <= n; k++) {
        lsm_stepgen_next(&g, &pos); /* the setpoint the firmware emits */
        lsm_kin kin;                /* J, A, V from the closed form at the same cycle */
        lsm_move_eval_cycle(&mv, 0, k, 0, &kin);
        max_gen_dev = fmax(max_gen_dev, fabs((double)pos - (double)kin.s_mm));
        pj = fmax(pj, fabs((double)kin.j_mm_s3));
        pa = fmax(pa, fabs((double)kin.a_mm_s2));
        pv = fmax(pv, fabs((double)kin.v_mm_s));
        fprintf(f, "%.6f,%.9g,%.9g,%.9g,%.12g\n", k * 0.001, (double)kin.j_mm_s3, (double)kin.a_mm_s2,
                (double)kin.v_mm_s, (double)pos);
    }
    fclose(f);
    const double tp = 4.0 * mv.acc.n1_cycles * 0.001;
    printf("Lissom demo: %.1f mm point-to-point move, sin² S-curve (Kombarov Table 1, Test 2 limits)\n", dist);
    printf("  cycles: %u (%.3f s); ramps n1=%u n2=%u n4=%u, cruise %u cycles\n", n, n * 0.001, mv.acc.n1_cycles,
           mv.acc.n2_cycles, mv.acc.n4_cycles, mv.cruise_cycles);
    printf("  peak jerk %.1f / 16000 mm/s^3, accel %.2f / 1570 mm/s^2, feed %.3f / 220 mm/s\n", pj, pa, pv);
    printf("  peak snap %.0f / 560000 mm/s^4 (J_P pi / (2 dt1), dt1 = %.3f s)\n",
           fabs((double)mv.axis[0].jp_acc_mm_s3) * LSM_PI / (2 * tp / 4), tp / 4);
    printf("  end: setpoint %.12g mm (target %.12g), closed-form end error %.2e mm, evaluator vs closed form %.2e mm\n",
           (double)pos, dist, (double)lsm_move_end_error_mm(&mv, 0), max_gen_dev);
    printf("  wrote %s\n", csv);
    if (!no_plot) {
        if (sim_plot("scurve", csv, png) != 0) {
            fprintf(stderr, "error: plotting failed (is the venv set up? scripts/deps.sh)\n");
            return 1;
        }
        printf("  wrote %s\n", png);
    }
    return 0;
}
