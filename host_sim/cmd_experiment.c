/*
 * lissom-sim experiment kombarov: the point-to-point experiment of Kombarov et al. §5.2, on the simulated
 * servo drive (host_sim/drive.h) instead of the paper's Estun axis.
 *
 *   lissom-sim experiment kombarov [--distance MM] [--vff GAIN] [--aff GAIN] [--out DIR] --json
 *
 * Three profiles with the paper's limits (A 1.57 m/s², J 16 m/s³, feed 13.2 m/min = 220 mm/s), each driven
 * through the same drive, setpoint per 1 ms cycle:
 *   trapezoid  Table 1 Test 1: DJ 25132 m/s⁴, so T1 is one cycle: trapezoidal acceleration, constant jerk
 *   sin2       Table 1 Test 2: DJ 560 m/s⁴, the sin² profile with smoothly limited jerk
 *   cjerk      a Ruckig-like time-optimal constant-jerk profile with the same v, a, j (not cycle-quantised)
 * The first two are planned by the firmware (move.h + stepgen.h). Reported per profile: duration, the max and
 * RMS following error (setpoint - load position) over the motion plus 0.3 s of settling, and the ratios of
 * the trapezoid's and the constant-jerk profile's errors to the sin² one's (the paper measured 2x).
 * --vff and --aff set the drive's velocity and acceleration feed-forward gains (default 1 and 1: a tuned CNC
 * axis; without feed-forward the following error is dominated by v / kv, the same for every profile). --out writes DIR/kombarov.csv (t and, per profile,
 * setpoint and following error).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "drive.h"
#include "move.h"
#include "stepgen.h"

#define CYCLE_S 0.001
#define SETTLE_S 0.3
#define MAX_CYCLES 20000

/* ---- a time-optimal rest-to-rest constant-jerk profile (7 segments, continuous time) ---- */
typedef struct cjerk {
    double t[7];  /* segment durations */
    double j[7];  /* jerk per segment */
    double D;
} cjerk;

static double cj_accel_time(double vp, double A, double J)
{
    return vp >= A * A / J ? vp / A + A / J : 2 * sqrt(vp / J);
}

static void cj_plan(cjerk *c, double D, double V, double A, double J)
{
    double vp = V;
    if (vp * cj_accel_time(vp, A, J) > D) { /* two ramps (each vp * ta / 2) longer than D: lower the peak */
        double lo = 0, hi = V;
        for (int i = 0; i < 200; i++) {
            const double mid = (lo + hi) / 2;
            if (mid * cj_accel_time(mid, A, J) > D)
                hi = mid;
            else
                lo = mid;
        }
        vp = lo;
    }
    const double ta = cj_accel_time(vp, A, J);
    const double tj = vp >= A * A / J ? A / J : ta / 2;
    const double tca = ta - 2 * tj;
    const double tc = (D - vp * ta) / vp;
    const double t[7] = {tj, tca, tj, tc > 0 ? tc : 0, tj, tca, tj};
    const double j[7] = {J, 0, -J, 0, -J, 0, J};
    memcpy(c->t, t, sizeof t);
    memcpy(c->j, j, sizeof j);
    c->D = D;
}

static double cj_duration(const cjerk *c)
{
    double T = 0;
    for (int i = 0; i < 7; i++)
        T += c->t[i];
    return T;
}

static void cj_eval(const cjerk *c, double t, double *s, double *v, double *acc)
{
    double p = 0, vv = 0, a = 0;
    for (int i = 0; i < 7; i++) {
        const double h = t < c->t[i] ? t : c->t[i];
        const double jk = c->j[i];
        p += vv * h + a * h * h / 2 + jk * h * h * h / 6;
        vv += a * h + jk * h * h / 2;
        a += jk * h;
        t -= h;
        if (t <= 0)
            break;
    }
    *s = p;
    *v = vv;
    *acc = a;
}

/* ---- the experiment ---- */
typedef struct result {
    const char *name;
    double duration_s, max_fe_mm, rms_fe_mm;
    uint32_t n;
    double set[MAX_CYCLES], fe[MAX_CYCLES];
} result;

static double g_acc[MAX_CYCLES];

static int run_drive(result *r, const sim_drive_params *dp, const double *set, const double *vel, uint32_t n_motion)
{
    sim_drive d;
    if (sim_drive_init(&d, dp, CYCLE_S, 0) != LSM_OK)
        return -1;
    const uint32_t n = n_motion + (uint32_t)(SETTLE_S / CYCLE_S);
    if (n > MAX_CYCLES)
        return -1;
    double sum2 = 0, mx = 0;
    for (uint32_t k = 0; k < n; k++) {
        const double sp = k < n_motion ? set[k] : set[n_motion - 1];
        const double vf = k < n_motion ? vel[k] : 0;
        const double af = k < n_motion ? g_acc[k] : 0;
        double act;
        sim_drive_step_ff(&d, sp, vf, af, &act);
        const double fe = sp - act;
        r->set[k] = sp;
        r->fe[k] = fe;
        sum2 += fe * fe;
        mx = fmax(mx, fabs(fe));
    }
    r->n = n;
    r->max_fe_mm = mx;
    r->rms_fe_mm = sqrt(sum2 / n);
    return 0;
}

static int lissom_profile(result *r, const sim_drive_params *dp, double D, double snap, double *set, double *vel)
{
    lsm_move_request req;
    memset(&req, 0, sizeof req);
    req.n_axes = 1;
    req.cycle_s = CYCLE_S;
    req.distance_mm[0] = D;
    req.lim[0] = (lsm_axis_limits){220, 1570, 16000, snap};
    lsm_move mv;
    if (lsm_move_plan(&mv, &req) != LSM_OK)
        return -1;
    const uint32_t n = lsm_move_total_cycles(&mv);
    if (n + 1 + SETTLE_S / CYCLE_S > MAX_CYCLES)
        return -1;
    lsm_stepgen g;
    lsm_stepgen_init(&g, &mv, NULL);
    for (uint32_t k = 1; k <= n; k++) {
        lsm_real p;
        lsm_stepgen_next(&g, &p);
        lsm_kin kin;
        lsm_move_eval_cycle(&mv, 0, k, 0, &kin);
        set[k - 1] = p;
        vel[k - 1] = kin.v_mm_s;
        g_acc[k - 1] = kin.a_mm_s2;
    }
    r->duration_s = n * CYCLE_S;
    return run_drive(r, dp, set, vel, n);
}

static int cjerk_profile(result *r, const sim_drive_params *dp, double D, double *set, double *vel)
{
    cjerk c;
    cj_plan(&c, D, 220, 1570, 16000);
    const double T = cj_duration(&c);
    const uint32_t n = (uint32_t)ceil(T / CYCLE_S - 1e-9);
    if (n + 1 + SETTLE_S / CYCLE_S > MAX_CYCLES)
        return -1;
    for (uint32_t k = 1; k <= n; k++) {
        double s, v, acc;
        cj_eval(&c, k < n ? k * CYCLE_S : T, &s, &v, &acc);
        set[k - 1] = k < n ? s : D;
        vel[k - 1] = k < n ? v : 0;
        g_acc[k - 1] = k < n ? acc : 0;
    }
    r->duration_s = T;
    return run_drive(r, dp, set, vel, n);
}

static result g_res[3];
static double g_set[MAX_CYCLES], g_vel[MAX_CYCLES];

int cmd_experiment(int argc, char **argv)
{
    if (argc < 1 || strcmp(argv[0], "kombarov") != 0) {
        fprintf(stderr, "error: usage: lissom-sim experiment kombarov [--distance MM] [--vff GAIN] [--out DIR] --json\n");
        return 2;
    }
    cli_args a;
    cli_init(&a, argc - 1, argv + 1);
    double D = 100, vff = 1, aff = 1;
    if (cli_num(&a, "distance", &D) < 0 || cli_num(&a, "vff", &vff) < 0 || cli_num(&a, "aff", &aff) < 0)
        return 2;
    const char *out = cli_opt(&a, "out");
    const bool json = cli_flag(&a, "json");
    if (cli_check_unused(&a, "experiment kombarov"))
        return 2;
    if (!(D > 0 && D <= 1000)) {
        fprintf(stderr, "error: --distance must be in (0, 1000] mm\n");
        return 2;
    }
    sim_drive_params dp;
    sim_drive_params_default(&dp, false);
    dp.vff_gain = vff;
    dp.aff_gain = aff;
    const char *bad = NULL;
    if (sim_drive_validate(&dp, CYCLE_S, &bad) != LSM_OK) {
        fprintf(stderr, "error: drive parameter %s out of range\n", bad ? bad : "?");
        return 2;
    }
    g_res[0].name = "trapezoid";
    g_res[1].name = "sin2";
    g_res[2].name = "cjerk";
    if (lissom_profile(&g_res[0], &dp, D, 25132000, g_set, g_vel) || lissom_profile(&g_res[1], &dp, D, 560000, g_set, g_vel) ||
        cjerk_profile(&g_res[2], &dp, D, g_set, g_vel)) {
        fprintf(stderr, "error: experiment failed (move too long?)\n");
        return 1;
    }
    const result *t = &g_res[0], *s = &g_res[1], *c = &g_res[2];
    if (json) {
        printf("{\"distance_mm\":%.9g,\"vff_gain\":%.9g,\"aff_gain\":%.9g,\"profiles\":{", D, vff, aff);
        for (int i = 0; i < 3; i++)
            printf("%s\"%s\":{\"duration\":%.9g,\"max_following_error\":%.9g,\"rms_following_error\":%.9g}",
                   i ? "," : "", g_res[i].name, g_res[i].duration_s, g_res[i].max_fe_mm, g_res[i].rms_fe_mm);
        printf("},\"ratio_max\":%.9g,\"ratio_rms\":%.9g,\"ratio_max_cjerk\":%.9g,\"ratio_rms_cjerk\":%.9g}\n",
               t->max_fe_mm / s->max_fe_mm, t->rms_fe_mm / s->rms_fe_mm, c->max_fe_mm / s->max_fe_mm,
               c->rms_fe_mm / s->rms_fe_mm);
    } else {
        printf("Kombarov §5.2 on the simulated drive: %.1f mm, 220 mm/s, vff %.2f, aff %.2f\n", D, vff, aff);
        printf("  %-10s %9s %14s %14s\n", "profile", "time s", "max FE um", "RMS FE um");
        for (int i = 0; i < 3; i++)
            printf("  %-10s %9.4f %14.3f %14.3f\n", g_res[i].name, g_res[i].duration_s, 1e3 * g_res[i].max_fe_mm,
                   1e3 * g_res[i].rms_fe_mm);
        printf("  trapezoid / sin2: max %.2fx, RMS %.2fx; constant-jerk / sin2: max %.2fx, RMS %.2fx\n",
               t->max_fe_mm / s->max_fe_mm, t->rms_fe_mm / s->rms_fe_mm, c->max_fe_mm / s->max_fe_mm,
               c->rms_fe_mm / s->rms_fe_mm);
    }
    if (out) {
        char path[4200];
        FILE *f = cli_open_out(out, "kombarov.csv", path, sizeof path);
        if (!f)
            return 1;
        fprintf(f, "t,trapezoid_set,trapezoid_fe,sin2_set,sin2_fe,cjerk_set,cjerk_fe\n");
        uint32_t n = 0;
        for (int i = 0; i < 3; i++)
            n = g_res[i].n > n ? g_res[i].n : n;
        for (uint32_t k = 0; k < n; k++) {
            fprintf(f, "%.4f", (k + 1) * CYCLE_S);
            for (int i = 0; i < 3; i++) {
                const result *r = &g_res[i];
                const uint32_t kk = k < r->n ? k : r->n - 1;
                fprintf(f, ",%.9g,%.9g", r->set[kk], k < r->n ? r->fe[kk] : 0.0);
            }
            fprintf(f, "\n");
        }
        fclose(f);
    }
    return 0;
}
