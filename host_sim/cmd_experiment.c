/*
 * lissom-sim experiment kombarov: the point-to-point experiment of Kombarov et al. §5.2, on the simulated
 * servo drive (host_sim/drive.h) instead of the paper's Estun axis.
 *
 *   lissom-sim experiment kombarov [--distance MM] [--machine FILE [--axis X]] [--vff GAIN] [--aff GAIN]
 *       [--no-ff] [--feedback load|motor] [--resonance-hz HZ] [--damping ZETA] [--vel-bw-hz HZ] [--kv 1/S]
 *       [--coulomb N] [--band MM] [--settle-window S] [--sweep] [--out DIR] [--json]
 *
 * Three profiles with the paper's limits (A 1.57 m/s², J 16 m/s³, feed 13.2 m/min = 220 mm/s), each driven
 * through the same drive, setpoint per 1 ms cycle:
 *   trapezoid  Table 1 Test 1: DJ 25132 m/s⁴, so T1 is one cycle: trapezoidal acceleration, constant jerk
 *   sin2       Table 1 Test 2: DJ 560 m/s⁴, the sin² profile with smoothly limited jerk
 *   cjerk      a Ruckig-like time-optimal constant-jerk profile with the same v, a, j (not cycle-quantised)
 * The first two are planned by the firmware (move.h + stepgen.h).
 *
 * The following error is setpoint - load position (the true load position, not the quantised reading), whatever
 * position the loop is closed on. Reported per profile:
 *   duration, max_following_error, rms_following_error   over the motion plus the settle window (0.3 s)
 *   motion_max/rms_following_error                       while the setpoint moves (tracking lag)
 *   residual_max/rms_error                               from the end of the cycle whose setpoint is the target
 *                                                        to the end of the window (positioning error, vibration)
 *   settle_time                                          from that moment until |error| stays within --band
 *                                                        (null: still outside at the end of the window)
 *   max_motor_following_error                            setpoint - motor position (a rotary encoder's view)
 *   max_deflection, max_dynamic_deflection               spring deflection x_motor - x_load over the motion,
 *                                                        and its part beyond the quasi-static value
 *                                                        (m_l a + b v + F_c tanh(v / v_eps)) / k of the setpoint
 *   spectral_residual_resonance/antiresonance            max of |A(w)| / w over f / 1.25 .. 1.25 f around the
 *                                                        resonance and the anti-resonance, A the Fourier transform
 *                                                        of the setpoint acceleration: the free vibration that an
 *                                                        undamped oscillator at w is left with by the move (a rigid
 *                                                        servo, no loop)
 *   current_limited                                      the drive's current limit was hit
 *   limits                                               the profile's v, a, j and snap limits (snap null for cjerk)
 * and the trapezoid / sin² ratios of these (ratio_*; the paper measured 2x on the servo error), and cjerk / sin² of
 * the max, RMS and residual error (ratio_max_cjerk, ratio_rms_cjerk, ratio_residual_max_cjerk). Every key is listed
 * with its unit in docs/host_sim.md.
 *
 * The drive is sim_drive_params_default (linear) with vff = aff = 1, or the axis of a machine file (--machine,
 * --axis, default X; its own feed-forward gains and encoder). On top of it:
 *   --vff, --aff, --no-ff   feed-forward gains (--no-ff: both 0)
 *   --feedback load|motor   the position the loop is closed on (motor: semi-closed loop, no linear scale)
 *   --resonance-hz HZ       stiffness set for this undamped two-mass resonance (masses kept; the damping
 *                           ratio is kept unless --damping is given)
 *   --damping ZETA          damping ratio of the resonance, 0 <= ZETA < 1
 *   --vel-bw-hz HZ          velocity loop retuned: vel_kp = 2 pi HZ (m_m + m_l) / kf, vel_ti = 0.6 / HZ (the
 *                           default drive has 40 Hz and 15 ms); without --kv, kv is scaled with the bandwidth
 *   --kv 1/S                position loop gain
 *   --coulomb N             Coulomb friction on the load
 * A drive that passes sim_drive_validate but does not settle in a 2 s closed-loop step test (the machine loader's
 * check) is rejected with exit 1. --sweep takes comma-separated lists for --resonance-hz (default
 * 10,15,20,30,50,75,100,150), --damping (default 0.01,0.02,0.05,0.1), --vel-bw-hz and --kv (default: the drive's)
 * and runs every combination, also those whose step test fails ("step_test_settled": false); without --sweep
 * each takes one value. --band (default 0.001 mm) is the settling band, --settle-window (default 0.3 s, 0.01 to
 * 10 s) the time simulated after the motion. --out writes DIR/kombarov.csv (t and, per profile, setpoint and
 * following error; not with --sweep). Exit 2 for bad options.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "drive.h"
#include "machine.h"
#include "move.h"
#include "stepgen.h"

#define CYCLE_S 0.001
/* Kombarov et al. 2019, Table 1 (Test 1 and Test 2 differ only in the snap limit DJ_max) */
#define K_V_MAX_MM_S 220.0            /* feed change 13.2 m/min */
#define K_A_MAX_MM_S2 1570.0          /* 1.57 m/s^2 */
#define K_J_MAX_MM_S3 16000.0         /* 16 m/s^3 */
#define K_SNAP_TEST1_MM_S4 25132000.0 /* 25132 m/s^4: T1 = pi J / (2 DJ) = 1 ms, one cycle: constant jerk */
#define K_SNAP_TEST2_MM_S4 560000.0   /* 560 m/s^4: T1 = 45 ms, the sin^2 profile */
#define MAX_CYCLES 20000
#define MAX_LIST 16
#define TWO_PI 6.28318530717958647692
#define DNAN ((double)NAN)

/* ---- a time-optimal rest-to-rest constant-jerk profile (7 segments, continuous time) ---- */
typedef struct cjerk {
    double t[7]; /* segment durations */
    double j[7]; /* jerk per segment */
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

/* ---- the profiles (independent of the drive) ---- */
typedef struct profile {
    const char *name;
    double duration_s;
    uint32_t n; /* motion cycles; set[n - 1] is the target */
    double set[MAX_CYCLES], vel[MAX_CYCLES], acc[MAX_CYCLES];
} profile;

static int lissom_profile(profile *pr, double D, double snap)
{
    lsm_move_request req;
    memset(&req, 0, sizeof req);
    req.n_axes = 1;
    req.cycle_s = CYCLE_S;
    req.distance_mm[0] = D;
    req.lim[0] = (lsm_axis_limits){K_V_MAX_MM_S, K_A_MAX_MM_S2, K_J_MAX_MM_S3, snap};
    lsm_move mv;
    if (lsm_move_plan(&mv, &req) != LSM_OK)
        return -1;
    const uint32_t n = lsm_move_total_cycles(&mv);
    if (n == 0 || n >= MAX_CYCLES)
        return -1;
    lsm_stepgen g;
    lsm_stepgen_init(&g, &mv, NULL);
    for (uint32_t k = 1; k <= n; k++) {
        lsm_real p;
        lsm_stepgen_next(&g, &p);
        lsm_kin kin;
        lsm_move_eval_cycle(&mv, 0, k, 0, &kin);
        pr->set[k - 1] = p;
        pr->vel[k - 1] = kin.v_mm_s;
        pr->acc[k - 1] = kin.a_mm_s2;
    }
    pr->n = n;
    pr->duration_s = n * CYCLE_S;
    return 0;
}

static int cjerk_profile(profile *pr, double D)
{
    cjerk c;
    cj_plan(&c, D, K_V_MAX_MM_S, K_A_MAX_MM_S2, K_J_MAX_MM_S3);
    const double T = cj_duration(&c);
    const uint32_t n = (uint32_t)ceil(T / CYCLE_S - 1e-9);
    if (n == 0 || n >= MAX_CYCLES)
        return -1;
    for (uint32_t k = 1; k <= n; k++) {
        double s, v, acc;
        cj_eval(&c, k < n ? k * CYCLE_S : T, &s, &v, &acc);
        pr->set[k - 1] = k < n ? s : D;
        pr->vel[k - 1] = k < n ? v : 0;
        pr->acc[k - 1] = k < n ? acc : 0;
    }
    pr->n = n;
    pr->duration_s = T;
    return 0;
}

/* |A(w)| / w [mm] for the setpoint as the drive sees it (linear between cycles, so its acceleration is a train
 * of velocity steps at the cycle boundaries): the residual amplitude of an undamped oscillator at w. */
static double spectral_at(const profile *pr, double f_hz)
{
    const double w = TWO_PI * f_hz;
    double re = 0, im = 0, s_prev = 0, v_prev = 0;
    for (uint32_t k = 0; k <= pr->n; k++) {
        const double s = k < pr->n ? pr->set[k] : pr->set[pr->n - 1];
        const double v = (s - s_prev) / CYCLE_S; /* velocity over cycle k (ends at t = (k + 1) dt) */
        const double dv = v - v_prev, t = k * CYCLE_S;
        re += dv * cos(w * t);
        im -= dv * sin(w * t);
        s_prev = s;
        v_prev = v;
    }
    return hypot(re, im) / w;
}

/* The largest spectral residual over f / 1.25 .. 1.25 f (41 points, log-spaced): the closed loop shifts the mode,
 * and one frequency alone can fall on a zero of a profile's spectrum. */
static double spectral_residual(const profile *pr, double f_hz)
{
    double mx = 0;
    for (int i = 0; i <= 40; i++)
        mx = fmax(mx, spectral_at(pr, f_hz * pow(1.25, (i - 20) / 20.0)));
    return mx;
}

/* ---- one drive run ---- */
typedef struct result {
    double max_fe, rms_fe;         /* motion + window (the original keys) */
    double motion_max, motion_rms; /* while the setpoint moves */
    double resid_max, resid_rms;   /* from the cycle that reached the target to the end of the window */
    double settle_s;               /* DNAN: not within the band at the end of the window */
    double motor_max;              /* max |set - x_motor| */
    double defl_max, defl_dyn_max; /* spring deflection over the motion, and beyond quasi-static */
    double spec_res, spec_antires; /* spectral residual [mm] */
    bool limited;                  /* the current limit was hit */
    uint32_t n;
    double fe[MAX_CYCLES];
} result;

typedef struct config {
    double D, band, window_s;
    sim_drive_params dp;
} config;

static int run_drive(result *r, const config *cfg, const profile *pr)
{
    const sim_drive_params *p = &cfg->dp;
    sim_drive d;
    if (sim_drive_init(&d, p, CYCLE_S, 0) != LSM_OK)
        return -1;
    const uint32_t nm = pr->n, n = nm + (uint32_t)lround(cfg->window_s / CYCLE_S);
    if (n > MAX_CYCLES)
        return -1;
    *r = (result){0};
    double sum2 = 0, msum2 = 0, rsum2 = 0;
    long last_out = -1;
    for (uint32_t k = 0; k < n; k++) {
        const bool moving = k < nm;
        const double sp = moving ? pr->set[k] : pr->set[nm - 1];
        const double vf = moving ? pr->vel[k] : 0, af = moving ? pr->acc[k] : 0;
        double act;
        sim_drive_step_ff(&d, sp, vf, af, &act);
        sim_drive_state st;
        sim_drive_get_state(&d, &st);
        const double fe = sp - act, afe = fabs(fe);
        r->limited = r->limited || st.current_limited;
        r->fe[k] = fe;
        sum2 += fe * fe;
        r->max_fe = fmax(r->max_fe, afe);
        r->motor_max = fmax(r->motor_max, fabs(sp - st.motor_pos));
        if (moving) {
            msum2 += fe * fe;
            r->motion_max = fmax(r->motion_max, afe);
            const double defl = st.motor_pos - st.load_pos; /* mm */
            const double v = vf * 1e-3, a = af * 1e-3;
            const double qs = (p->load_mass_kg * a + p->viscous_N_s_m * v + p->coulomb_N * tanh(v / d.v_eps_m_s)) /
                              p->stiffness_N_m * 1e3;
            r->defl_max = fmax(r->defl_max, fabs(defl));
            r->defl_dyn_max = fmax(r->defl_dyn_max, fabs(defl - qs));
        }
        if (k + 1 >= nm) { /* the end of the cycle whose setpoint is the target, and after */
            rsum2 += fe * fe;
            r->resid_max = fmax(r->resid_max, afe);
            if (afe > cfg->band)
                last_out = (long)k;
        }
    }
    r->n = n;
    r->rms_fe = sqrt(sum2 / n);
    r->motion_rms = sqrt(msum2 / nm);
    r->resid_rms = sqrt(rsum2 / (n - nm + 1));
    if (last_out == (long)n - 1)
        r->settle_s = DNAN;
    else
        r->settle_s = last_out < 0 ? 0.0 : (double)(last_out - (long)(nm - 1) + 1) * CYCLE_S;
    sim_drive_modes md;
    sim_drive_modes_analytic(p, &md);
    r->spec_res = spectral_residual(pr, md.f_res_hz);
    r->spec_antires = spectral_residual(pr, md.f_antires_hz);
    return 0;
}

/* ---- drive set-up ---- */
static double vel_bw_hz(const sim_drive_params *p)
{
    return p->vel_kp_A_s_m * p->force_const_N_A / (TWO_PI * (p->motor_mass_kg + p->load_mass_kg));
}

static void apply(sim_drive_params *p, double f_res, double zeta, double bw, double kv)
{
    const double mu = p->motor_mass_kg * p->load_mass_kg / (p->motor_mass_kg + p->load_mass_kg);
    if (!isnan(zeta) || !isnan(f_res)) {
        sim_drive_modes md;
        sim_drive_modes_analytic(p, &md);
        const double z = isnan(zeta) ? md.zeta_res : zeta;
        if (!isnan(f_res))
            p->stiffness_N_m = pow(TWO_PI * f_res, 2) * mu;
        p->damping_N_s_m = 2.0 * z * sqrt(p->stiffness_N_m * mu);
    }
    if (!isnan(bw)) {
        if (isnan(kv))
            p->kv_1_s *= bw / vel_bw_hz(p); /* keep the drive's kv / velocity bandwidth ratio */
        p->vel_kp_A_s_m = TWO_PI * bw * (p->motor_mass_kg + p->load_mass_kg) / p->force_const_N_A;
        p->vel_ti_s = 0.6 / bw;
    }
    if (!isnan(kv))
        p->kv_1_s = kv;
}

/* 0 stable, 1 the step test does not settle, -1 invalid (message printed) */
static int check_drive(const sim_drive_params *p)
{
    const char *bad = NULL;
    if (sim_drive_validate(p, CYCLE_S, &bad) != LSM_OK) {
        fprintf(stderr, "error: drive parameter %s out of range\n", bad ? bad : "?");
        return -1;
    }
    sim_drive_step_stats ss;
    const double step = p->encoder_counts_per_mm > 0 ? fmax(1.0, 100.0 / p->encoder_counts_per_mm) : 1.0;
    if (sim_drive_step_test(p, CYCLE_S, step, 2.0, &ss) != LSM_OK || !ss.settled)
        return 1;
    return 0;
}

static double ratio(double a, double b)
{
    return (isfinite(a) && isfinite(b) && b > 0) ? a / b : DNAN;
}

static void print_drive_json(const sim_drive_params *p)
{
    sim_drive_modes md;
    sim_drive_modes_analytic(p, &md);
    printf("{\"feedback\":\"%s\",\"resonance_hz\":", p->motor_feedback ? "motor" : "load");
    json_num(stdout, md.f_res_hz);
    printf(",\"antiresonance_hz\":");
    json_num(stdout, md.f_antires_hz);
    printf(",\"damping\":");
    json_num(stdout, md.zeta_res);
    printf(",\"vel_bw_hz\":");
    json_num(stdout, vel_bw_hz(p));
    printf(",\"vel_ti_s\":");
    json_num(stdout, p->vel_ti_s);
    printf(",\"kv_1_s\":");
    json_num(stdout, p->kv_1_s);
    printf(",\"vff_gain\":");
    json_num(stdout, p->vff_gain);
    printf(",\"aff_gain\":");
    json_num(stdout, p->aff_gain);
    printf(",\"encoder_counts_per_mm\":");
    json_num(stdout, p->encoder_counts_per_mm);
    printf("}");
}

static const char *const k_names[3] = {"trapezoid", "sin2", "cjerk"};

static void print_profiles_json(const profile *pr, const result *r)
{
    printf("{");
    for (int i = 0; i < 3; i++) {
        const result *x = &r[i];
        printf("%s\"%s\":{\"duration\":%.9g,\"max_following_error\":%.9g,\"rms_following_error\":%.9g", i ? "," : "",
               k_names[i], pr[i].duration_s, x->max_fe, x->rms_fe);
        printf(",\"limits\":{\"v_max_mm_s\":%.9g,\"a_max_mm_s2\":%.9g,\"j_max_mm_s3\":%.9g,\"snap_max_mm_s4\":",
               K_V_MAX_MM_S, K_A_MAX_MM_S2, K_J_MAX_MM_S3);
        json_num(stdout, i == 0 ? K_SNAP_TEST1_MM_S4 : i == 1 ? K_SNAP_TEST2_MM_S4 : DNAN); /* cjerk: none (null) */
        printf("}");
        const struct {
            const char *k;
            double v;
        } f[] = {{"motion_max_following_error", x->motion_max},
                 {"motion_rms_following_error", x->motion_rms},
                 {"residual_max_error", x->resid_max},
                 {"residual_rms_error", x->resid_rms},
                 {"settle_time", x->settle_s},
                 {"max_motor_following_error", x->motor_max},
                 {"max_deflection", x->defl_max},
                 {"max_dynamic_deflection", x->defl_dyn_max},
                 {"spectral_residual_resonance", x->spec_res},
                 {"spectral_residual_antiresonance", x->spec_antires}};
        for (size_t j = 0; j < sizeof f / sizeof f[0]; j++) {
            printf(",\"%s\":", f[j].k);
            json_num(stdout, f[j].v);
        }
        printf(",\"current_limited\":%s}", x->limited ? "true" : "false");
    }
    printf("}");
}

static void print_ratios_json(const result *r)
{
    const result *t = &r[0], *s = &r[1], *c = &r[2];
    const struct {
        const char *k;
        double v;
    } f[] = {{"ratio_motion_max", ratio(t->motion_max, s->motion_max)},
             {"ratio_motion_rms", ratio(t->motion_rms, s->motion_rms)},
             {"ratio_residual_max", ratio(t->resid_max, s->resid_max)},
             {"ratio_residual_rms", ratio(t->resid_rms, s->resid_rms)},
             {"ratio_settle", ratio(t->settle_s, s->settle_s)},
             {"ratio_spectral_resonance", ratio(t->spec_res, s->spec_res)},
             {"ratio_spectral_antiresonance", ratio(t->spec_antires, s->spec_antires)},
             {"ratio_residual_max_cjerk", ratio(c->resid_max, s->resid_max)}};
    for (size_t j = 0; j < sizeof f / sizeof f[0]; j++) {
        printf(",\"%s\":", f[j].k);
        json_num(stdout, f[j].v);
    }
}

static profile g_prof[3];
static result g_res[3];

static int run_all(const config *cfg)
{
    for (int i = 0; i < 3; i++)
        if (run_drive(&g_res[i], cfg, &g_prof[i]))
            return -1;
    return 0;
}

static void fmt_us(char *buf, size_t n, double mm)
{
    if (isfinite(mm))
        snprintf(buf, n, "%.3f", 1e3 * mm);
    else
        snprintf(buf, n, "-");
}

static void fmt_ratio(char *buf, size_t n, double x)
{
    if (isfinite(x))
        snprintf(buf, n, "%.2f", x);
    else
        snprintf(buf, n, "-");
}

/* one option as a list; outside a sweep it must have one value. Returns the count (0 absent), -1 error. */
static int list_opt(cli_args *a, const char *name, double *out, bool sweep)
{
    const int n = cli_num_list(a, name, out, MAX_LIST);
    if (n > 1 && !sweep) {
        fprintf(stderr, "error: --%s takes one value (a list needs --sweep)\n", name);
        return -1;
    }
    return n;
}

static bool check_list(const char *name, const double *v, int n, double lo, double hi, bool lo_open, bool hi_open)
{
    for (int i = 0; i < n; i++) {
        const double x = v[i];
        if (!isfinite(x) || (lo_open ? x <= lo : x < lo) || (hi_open ? x >= hi : x > hi)) {
            fprintf(stderr, "error: --%s must be in %c%g, %g%c (got %g)\n", name, lo_open ? '(' : '[', lo, hi,
                    hi_open ? ')' : ']', x);
            return false;
        }
    }
    return true;
}

static void write_csv(FILE *f)
{
    fprintf(f, "t,trapezoid_set,trapezoid_fe,sin2_set,sin2_fe,cjerk_set,cjerk_fe\n");
    uint32_t n = 0;
    for (int i = 0; i < 3; i++)
        n = g_res[i].n > n ? g_res[i].n : n;
    for (uint32_t k = 0; k < n; k++) {
        fprintf(f, "%.4f", (k + 1) * CYCLE_S);
        for (int i = 0; i < 3; i++) {
            const result *r = &g_res[i];
            const profile *pr = &g_prof[i];
            const uint32_t kk = k < pr->n ? k : pr->n - 1;
            fprintf(f, ",%.9g,%.9g", pr->set[kk], k < r->n ? r->fe[k] : 0.0);
        }
        fprintf(f, "\n");
    }
}

/* Defaults of the options. */
#define EXP_DEFAULT_DISTANCE_MM 100.0 /* the paper's move */
#define EXP_DEFAULT_BAND_MM 0.001     /* settled: within 1 um of the target */
#define EXP_DEFAULT_WINDOW_S 0.3      /* the settle window after the setpoint reached the target */

/* The command's options. */
typedef struct {
    double D, vff, aff, band, window, coulomb;
    bool sweep, no_ff, json;
    double fr[MAX_LIST], zr[MAX_LIST], bw[MAX_LIST], kv[MAX_LIST];
    int nf, nz, nb, nk;
    const char *feedback, *machine, *axis, *out;
} exp_opts;

/* Reads the options (0, or exit code 2 after a message). */
static int exp_read(int argc, char **argv, exp_opts *o)
{
    cli_args a;
    cli_init(&a, argc, argv);
    o->D = EXP_DEFAULT_DISTANCE_MM;
    o->vff = o->aff = o->coulomb = DNAN;
    o->band = EXP_DEFAULT_BAND_MM;
    o->window = EXP_DEFAULT_WINDOW_S;
    if (cli_num(&a, "distance", &o->D) < 0 || cli_num(&a, "vff", &o->vff) < 0 || cli_num(&a, "aff", &o->aff) < 0 ||
        cli_num(&a, "band", &o->band) < 0 || cli_num(&a, "settle-window", &o->window) < 0 ||
        cli_num(&a, "coulomb", &o->coulomb) < 0)
        return 2;
    o->sweep = cli_flag(&a, "sweep");
    o->no_ff = cli_flag(&a, "no-ff");
    o->nf = list_opt(&a, "resonance-hz", o->fr, o->sweep);
    o->nz = list_opt(&a, "damping", o->zr, o->sweep);
    o->nb = list_opt(&a, "vel-bw-hz", o->bw, o->sweep);
    o->nk = list_opt(&a, "kv", o->kv, o->sweep);
    if (o->nf < 0 || o->nz < 0 || o->nb < 0 || o->nk < 0)
        return 2;
    o->feedback = cli_opt(&a, "feedback");
    o->machine = cli_opt(&a, "machine");
    o->axis = cli_opt(&a, "axis");
    o->out = cli_opt(&a, "out");
    o->json = cli_flag(&a, "json");
    if (cli_check_unused(&a, "experiment kombarov"))
        return 2;
    if (o->out && cli_check_out_dir("out", o->out))
        return 2;
    return 0;
}

/* Checks the options' values and combinations (true, or false after a message). */
static bool exp_check(const exp_opts *o)
{
    const char *err = NULL;
    if (!(o->D > 0 && o->D <= 1000))
        err = "--distance must be in (0, 1000] mm";
    else if (!(o->band > 0 && isfinite(o->band)))
        err = "--band must be a positive number of mm";
    else if (!(o->window >= 0.01 && o->window <= 10))
        err = "--settle-window must be in [0.01, 10] s";
    else if (!isnan(o->coulomb) && !(o->coulomb >= 0 && o->coulomb <= 1e4))
        err = "--coulomb must be in [0, 10000] N";
    else if (o->no_ff && (!isnan(o->vff) || !isnan(o->aff)))
        err = "--no-ff and --vff/--aff exclude each other";
    if (err) {
        fprintf(stderr, "error: %s\n", err);
        return false;
    }
    if (o->feedback && strcmp(o->feedback, "load") != 0 && strcmp(o->feedback, "motor") != 0) {
        fprintf(stderr, "error: --feedback must be load or motor (got %s)\n", o->feedback);
        return false;
    }
    if (o->axis && !o->machine) {
        fprintf(stderr, "error: --axis needs --machine\n");
        return false;
    }
    if (o->sweep && o->out) {
        fprintf(stderr, "error: --out writes one run; it cannot be combined with --sweep\n");
        return false;
    }
    return check_list("resonance-hz", o->fr, o->nf, 0, 2000, true, false) &&
           check_list("damping", o->zr, o->nz, 0, 1, false, true) &&
           check_list("vel-bw-hz", o->bw, o->nb, 0, 1000, true, false) &&
           check_list("kv", o->kv, o->nk, 0, 1000, true, false);
}

/* The drive: a machine file's axis, or the default drive with full feed-forward; then the options on top. */
static int exp_drive(const exp_opts *o, config *cfg)
{
    if (o->machine) {
        static sim_machine m;
        char err[512];
        if (sim_machine_load_file(o->machine, &m, err, sizeof err) != SIM_MACHINE_OK) {
            fprintf(stderr, "error: %s\n", err);
            return 2;
        }
        const char name = o->axis ? o->axis[0] : 'X';
        const sim_machine_axis *ax = (o->axis && strlen(o->axis) != 1) ? NULL : sim_machine_axis_by_name(&m, name);
        if (!ax) {
            fprintf(stderr, "error: --axis: machine %s has no axis %s\n", m.name, o->axis ? o->axis : "X");
            return 2;
        }
        if (ax->rotary) {
            fprintf(stderr, "error: --axis: the experiment needs a linear axis (%c is rotary)\n", ax->name);
            return 2;
        }
        cfg->dp = ax->drive;
    } else {
        sim_drive_params_default(&cfg->dp, false);
        cfg->dp.vff_gain = 1;
        cfg->dp.aff_gain = 1;
    }
    if (!isnan(o->coulomb))
        cfg->dp.coulomb_N = o->coulomb;
    if (o->feedback)
        cfg->dp.motor_feedback = strcmp(o->feedback, "motor") == 0;
    if (o->no_ff)
        cfg->dp.vff_gain = cfg->dp.aff_gain = 0;
    if (!isnan(o->vff))
        cfg->dp.vff_gain = o->vff;
    if (!isnan(o->aff))
        cfg->dp.aff_gain = o->aff;
    return 0;
}

/* The three profiles of the move (0, or an exit code after a message). */
static int exp_profiles(const exp_opts *o)
{
    if (lissom_profile(&g_prof[0], o->D, K_SNAP_TEST1_MM_S4) || lissom_profile(&g_prof[1], o->D, K_SNAP_TEST2_MM_S4) ||
        cjerk_profile(&g_prof[2], o->D)) {
        fprintf(stderr, "error: experiment failed (move too long?)\n");
        return 1;
    }
    for (int i = 0; i < 3; i++)
        g_prof[i].name = k_names[i];
    if (g_prof[0].n + o->window / CYCLE_S + 1 > MAX_CYCLES || g_prof[1].n + o->window / CYCLE_S + 1 > MAX_CYCLES) {
        fprintf(stderr, "error: move plus settle window longer than %d cycles\n", MAX_CYCLES);
        return 2;
    }
    return 0;
}

static void exp_single_json(const exp_opts *o, const config *cfg)
{
    const result *t = &g_res[0], *s = &g_res[1], *cj = &g_res[2];
    printf("{\"distance_mm\":%.9g,\"vff_gain\":%.9g,\"aff_gain\":%.9g,\"band_mm\":%.9g,\"settle_window_s\":%.9g,"
           "\"drive\":",
           o->D, cfg->dp.vff_gain, cfg->dp.aff_gain, o->band, o->window);
    print_drive_json(&cfg->dp);
    printf(",\"profiles\":");
    print_profiles_json(g_prof, g_res);
    const double top[4] = {ratio(t->max_fe, s->max_fe), ratio(t->rms_fe, s->rms_fe), ratio(cj->max_fe, s->max_fe),
                           ratio(cj->rms_fe, s->rms_fe)};
    static const char *const top_k[4] = {"ratio_max", "ratio_rms", "ratio_max_cjerk", "ratio_rms_cjerk"};
    for (int i = 0; i < 4; i++) {
        printf(",\"%s\":", top_k[i]);
        json_num(stdout, top[i]);
    }
    print_ratios_json(g_res);
    printf("}\n");
}

static void exp_single_text(const exp_opts *o, const config *cfg)
{
    const result *t = &g_res[0], *s = &g_res[1], *cj = &g_res[2];
    sim_drive_modes md;
    sim_drive_modes_analytic(&cfg->dp, &md);
    printf("Kombarov §5.2 on the simulated drive: %.1f mm, %g mm/s, %g mm/s2, %g mm/s3, vff %.2f, aff %.2f\n", o->D,
           K_V_MAX_MM_S, K_A_MAX_MM_S2, K_J_MAX_MM_S3, cfg->dp.vff_gain, cfg->dp.aff_gain);
    printf("  trapezoid = Table 1 Test 1 (snap %g mm/s4), sin2 = Test 2 (snap %g mm/s4), cjerk = Ruckig-like "
           "time-optimal constant jerk\n",
           K_SNAP_TEST1_MM_S4, K_SNAP_TEST2_MM_S4);
    printf("  position loop on the %s\n", cfg->dp.motor_feedback ? "motor (semi-closed)" : "load (linear scale)");
    printf("  drive: resonance %.1f Hz (zeta %.3f), anti-resonance %.1f Hz, velocity loop %.1f Hz, kv %g /s\n",
           md.f_res_hz, md.zeta_res, md.f_antires_hz, vel_bw_hz(&cfg->dp), cfg->dp.kv_1_s);
    printf("  error = setpoint - load position; residual = after the setpoint reached the target; band %g um\n",
           1e3 * o->band);
    printf("  %-10s %8s %11s %11s %11s %11s %9s\n", "profile", "time s", "max FE um", "RMS FE um", "resid um",
           "spectral um", "settle ms");
    for (int i = 0; i < 3; i++) {
        const result *r = &g_res[i];
        char st[32];
        if (isfinite(r->settle_s))
            snprintf(st, sizeof st, "%.0f", 1e3 * r->settle_s);
        else
            snprintf(st, sizeof st, ">%.0f", 1e3 * o->window);
        printf("  %-10s %8.4f %11.3f %11.3f %11.3f %11.4f %9s\n", k_names[i], g_prof[i].duration_s, 1e3 * r->max_fe,
               1e3 * r->rms_fe, 1e3 * r->resid_max, 1e3 * r->spec_res, st);
    }
    char b1[32], b2[32], b3[32];
    fmt_ratio(b1, sizeof b1, ratio(t->resid_max, s->resid_max));
    fmt_ratio(b2, sizeof b2, ratio(t->settle_s, s->settle_s));
    fmt_ratio(b3, sizeof b3, ratio(cj->resid_max, s->resid_max));
    printf("  trapezoid / sin2: max %.2fx, RMS %.2fx, residual %sx, settle %sx\n", t->max_fe / s->max_fe,
           t->rms_fe / s->rms_fe, b1, b2);
    printf("  cjerk / sin2:     max %.2fx, RMS %.2fx, residual %sx\n", cj->max_fe / s->max_fe, cj->rms_fe / s->rms_fe,
           b3);
}

/* One run on one drive: the summary, and the setpoints and errors to --out. */
static int exp_single(const exp_opts *o, config *cfg)
{
    apply(&cfg->dp, o->nf ? o->fr[0] : DNAN, o->nz ? o->zr[0] : DNAN, o->nb ? o->bw[0] : DNAN, o->nk ? o->kv[0] : DNAN);
    const int c = check_drive(&cfg->dp);
    if (c < 0)
        return 2;
    if (c > 0) {
        sim_drive_modes md;
        sim_drive_modes_analytic(&cfg->dp, &md);
        fprintf(stderr,
                "error: the drive does not settle in a closed-loop step test (resonance %.1f Hz, velocity "
                "loop %.1f Hz, kv %g /s): lower --vel-bw-hz or --kv, or raise --resonance-hz\n",
                md.f_res_hz, vel_bw_hz(&cfg->dp), cfg->dp.kv_1_s);
        return 1;
    }
    if (run_all(cfg)) {
        fprintf(stderr, "error: experiment failed\n");
        return 1;
    }
    if (o->json)
        exp_single_json(o, cfg);
    else
        exp_single_text(o, cfg);
    if (o->out) {
        char path[4200];
        FILE *f = cli_open_out(o->out, "kombarov.csv", path, sizeof path);
        if (!f)
            return 1;
        write_csv(f);
        fclose(f);
    }
    return 0;
}

/* One row of the sweep (the drive c, after the runs). */
static void exp_sweep_row(const exp_opts *o, const config *c, double f_r, double zeta, bool stable, int row)
{
    const result *t = &g_res[0], *s = &g_res[1];
    if (o->json) {
        printf("%s{\"drive\":", row ? "," : "");
        print_drive_json(&c->dp);
        printf(",\"step_test_settled\":%s", stable ? "true" : "false");
        printf(",\"profiles\":");
        print_profiles_json(g_prof, g_res);
        printf(",\"ratio_max\":");
        json_num(stdout, ratio(t->max_fe, s->max_fe));
        printf(",\"ratio_rms\":");
        json_num(stdout, ratio(t->rms_fe, s->rms_fe));
        printf(",\"ratio_max_cjerk\":");
        json_num(stdout, ratio(g_res[2].max_fe, s->max_fe));
        printf(",\"ratio_rms_cjerk\":");
        json_num(stdout, ratio(g_res[2].rms_fe, s->rms_fe));
        print_ratios_json(g_res);
        printf("}");
        return;
    }
    char r[5][32], u[2][32];
    fmt_ratio(r[0], 32, ratio(t->max_fe, s->max_fe));
    fmt_ratio(r[1], 32, ratio(t->rms_fe, s->rms_fe));
    fmt_ratio(r[2], 32, ratio(t->resid_max, s->resid_max));
    fmt_ratio(r[3], 32, ratio(t->settle_s, s->settle_s));
    fmt_ratio(r[4], 32, ratio(t->spec_res, s->spec_res));
    fmt_us(u[0], 32, t->resid_max);
    fmt_us(u[1], 32, s->resid_max);
    printf("  %6.1f %5.3f %6.1f %5.1f | %8.3f %8.3f | %7s %7s %7s %7s %7s | %8s %8s%s%s\n", f_r, zeta,
           vel_bw_hz(&c->dp), c->dp.kv_1_s, 1e3 * t->max_fe, 1e3 * s->max_fe, r[0], r[1], r[2], r[3], r[4], u[0], u[1],
           (t->limited || s->limited) ? " current limit" : "", stable ? "" : " step test fails");
}

/* The sweep over resonance, damping, velocity loop and kv (defaults: a grid of resonances and dampings). */
static int exp_sweep(exp_opts *o, const config *cfg)
{
    static const double k_fr[] = {10, 15, 20, 30, 50, 75, 100, 150}, k_zr[] = {0.01, 0.02, 0.05, 0.1};
    if (o->nf == 0) {
        o->nf = (int)(sizeof k_fr / sizeof k_fr[0]);
        memcpy(o->fr, k_fr, sizeof k_fr);
    }
    if (o->nz == 0) {
        o->nz = (int)(sizeof k_zr / sizeof k_zr[0]);
        memcpy(o->zr, k_zr, sizeof k_zr);
    }
    if (o->nb == 0) {
        o->nb = 1;
        o->bw[0] = DNAN;
    }
    if (o->nk == 0) {
        o->nk = 1;
        o->kv[0] = DNAN;
    }
    if (o->json) {
        printf("{\"distance_mm\":%.9g,\"band_mm\":%.9g,\"settle_window_s\":%.9g,\"sweep\":[", o->D, o->band, o->window);
    } else {
        printf("Kombarov §5.2 sweep: %.1f mm, vff %.2f, aff %.2f, position loop on the %s; ratios trapezoid / sin2; "
               "error = setpoint - load\n",
               o->D, cfg->dp.vff_gain, cfg->dp.aff_gain, cfg->dp.motor_feedback ? "motor" : "load");
        printf("  %6s %5s %6s %5s | %8s %8s | %7s %7s %7s %7s %7s | %8s %8s\n", "f_r Hz", "zeta", "vel Hz", "kv",
               "max um", "sin2 um", "max", "RMS", "resid", "settle", "spect", "trap res", "sin2 res");
    }
    int row = 0;
    for (int ib = 0; ib < o->nb; ib++)
        for (int ik = 0; ik < o->nk; ik++)
            for (int iz = 0; iz < o->nz; iz++)
                for (int i_f = 0; i_f < o->nf; i_f++) {
                    config c = *cfg;
                    apply(&c.dp, o->fr[i_f], o->zr[iz], o->bw[ib], o->kv[ik]);
                    const int chk = check_drive(&c.dp);
                    if (chk < 0)
                        return 2;
                    if (run_all(&c)) {
                        fprintf(stderr, "error: experiment failed\n");
                        return 1;
                    }
                    exp_sweep_row(o, &c, o->fr[i_f], o->zr[iz], chk == 0, row);
                    row++;
                }
    if (o->json)
        printf("]}\n");
    return 0;
}

int cmd_experiment(int argc, char **argv)
{
    if (argc < 1 || strcmp(argv[0], "kombarov") != 0) {
        fprintf(stderr, "error: usage: lissom-sim experiment kombarov [--distance MM] [--machine FILE [--axis X]] "
                        "[--vff GAIN] [--aff GAIN] [--no-ff] [--feedback load|motor] [--resonance-hz HZ] [--damping "
                        "ZETA] [--vel-bw-hz HZ] [--coulomb N] "
                        "[--kv 1/S] [--band MM] [--settle-window S] [--sweep] [--out DIR] [--json]\n");
        return 2;
    }
    static exp_opts o;
    if (exp_read(argc - 1, argv + 1, &o) != 0 || !exp_check(&o))
        return 2;
    config cfg = {.D = o.D, .band = o.band, .window_s = o.window};
    int rc = exp_drive(&o, &cfg);
    if (rc == 0)
        rc = exp_profiles(&o);
    if (rc != 0)
        return rc;
    return o.sweep ? exp_sweep(&o, &cfg) : exp_single(&o, &cfg);
}
