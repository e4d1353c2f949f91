/*
 * test_sim_drive.c: the simulated servo drive (host_sim/drive.c).
 *
 * - parameter validation names the bad field with a distinct status;
 * - closed-loop step response of the default linear and rotary axes: bounded overshoot, settling,
 *   steady-state error ~0 (also with encoder quantisation: within one count), current within its limit;
 * - the step response against the analytic one: without Coulomb friction the drive is linear, and the closed
 *   form of its transfer function (two-mass plant, current lag, P or PI velocity loop, position loop) gives
 *   the response sample by sample. The simulation stays within 0.3 % of the step (0.74 % on a loop tuned to
 *   overshoot 27 %), and 8x shorter servo periods bring it ~8x closer (the gap is the discretisation);
 *   a 10 % error in kv shows as 5 %;
 * - constant-velocity following error equals v/kv without feed-forward (type-1 loop with an
 *   integrating velocity loop) and almost vanishes with full velocity feed-forward;
 * - a current-limited move: the current never exceeds the limit and the axis still settles (anti-windup);
 * - along a smooth move (no friction), velocity feed-forward cuts the largest following error by more than
 *   20x and acceleration feed-forward again, to within twice the spring's quasi-static deflection
 *   m_l a / k; the step-test helper flags an unstable tuning (15 Hz resonance);
 * - the resonance: an open-loop current pulse excites the two-mass mode; its frequency, measured from
 *   the upward zero crossings of the spring deflection x_motor - x_load, matches the analytic damped
 *   frequency of the two-mass model within 0.5 % without friction (and the logarithmic decrement
 *   gives zeta_r within 10 %), within 3 % while the load slides with the default friction; a second
 *   estimate from the DFT peak of the load acceleration agrees within 3 %. When friction holds the
 *   load, the motor rings at sqrt(k / m_motor) instead (checked within 1 %);
 * - determinism (two runs are bit-identical) and input checks.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"

#define PI 3.14159265358979323846

static void test_validate(void **state)
{
    (void)state;
    sim_drive_params p;
    const char *bad = "x";
    for (int rot = 0; rot < 2; rot++) {
        sim_drive_params_default(&p, rot != 0);
        assert_int_equal(sim_drive_validate(&p, 1e-3, &bad), LSM_OK);
        assert_null(bad);
        assert_int_equal(sim_drive_validate(&p, 6e-3, &bad), LSM_OK);
    }
    sim_drive_params_default(&p, false);
    struct {
        double *field;
        double value;
        lsm_status code;
        const char *name;
    } cases[] = {
        {&p.kv_1_s, 0.0, LSM_E_LIMIT, "kv_1_s"},
        {&p.kv_1_s, -1.0, LSM_E_LIMIT, "kv_1_s"},
        {&p.load_mass_kg, NAN, LSM_E_NAN, "load_mass_kg"},
        {&p.motor_mass_kg, INFINITY, LSM_E_INF, "motor_mass_kg"},
        {&p.stiffness_N_m, 0.0, LSM_E_LIMIT, "stiffness_N_m"},
        {&p.current_max_A, 0.0, LSM_E_LIMIT, "current_max_A"},
        {&p.current_tau_s, 0.0, LSM_E_LIMIT, "current_tau_s"},
        {&p.force_const_N_A, -3.0, LSM_E_LIMIT, "force_const_N_A"},
        {&p.vel_kp_A_s_m, 0.0, LSM_E_LIMIT, "vel_kp_A_s_m"},
        {&p.vel_ti_s, -0.01, LSM_E_ARG, "vel_ti_s"},
        {&p.damping_N_s_m, -1.0, LSM_E_ARG, "damping_N_s_m"},
        {&p.coulomb_N, -1.0, LSM_E_ARG, "coulomb_N"},
        {&p.viscous_N_s_m, -1.0, LSM_E_ARG, "viscous_N_s_m"},
        {&p.vff_gain, 2.0, LSM_E_ARG, "vff_gain"},
        {&p.aff_gain, -0.5, LSM_E_ARG, "aff_gain"},
        {&p.aff_gain, 1.6, LSM_E_ARG, "aff_gain"},
        {&p.encoder_counts_per_mm, -1.0, LSM_E_ARG, "encoder_counts_per_mm"},
        {&p.servo_period_s, 0.0, LSM_E_CYCLE, "servo_period_s"},
        {&p.servo_period_s, 1e-3, LSM_E_ARG, "servo_period_s"}, /* 1 kHz cannot resolve 100 Hz + 0.25 ms */
        {&p.stiffness_N_m, 1e10, LSM_E_ARG, "servo_period_s"},  /* a 4 kHz resonance needs a finer step */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        sim_drive_params_default(&p, false);
        *cases[i].field = cases[i].value;
        lsm_status st = sim_drive_validate(&p, 1e-3, &bad);
        if (st != cases[i].code || !bad || strcmp(bad, cases[i].name) != 0)
            print_error("case %zu: got %d %s\n", i, (int)st, bad ? bad : "(null)");
        assert_int_equal(st, cases[i].code);
        assert_non_null(bad);
        assert_string_equal(bad, cases[i].name);
        sim_drive d;
        assert_int_equal(sim_drive_init(&d, &p, 1e-3, 0.0), cases[i].code);
    }
    sim_drive_params_default(&p, false);
    assert_int_equal(sim_drive_validate(&p, 0.0, &bad), LSM_E_CYCLE);
    assert_string_equal(bad, "cycle_s");
    assert_int_equal(sim_drive_validate(&p, 30e-6, &bad), LSM_E_ARG); /* cycle shorter than the servo period */
    assert_int_equal(sim_drive_validate(&p, NAN, &bad), LSM_E_NAN);
    assert_int_equal(sim_drive_validate(NULL, 1e-3, &bad), LSM_E_NULL);
    sim_drive d;
    assert_int_equal(sim_drive_init(&d, &p, 1e-3, NAN), LSM_E_NAN);
    assert_int_equal(sim_drive_init(NULL, &p, 1e-3, 0), LSM_E_NULL);
    assert_int_equal(sim_drive_init(&d, &p, 1e-3, 5.0), LSM_OK);
    double act;
    assert_int_equal(sim_drive_step(&d, NAN, 0, &act), LSM_E_NAN);
    assert_int_equal(sim_drive_step(&d, 0, INFINITY, &act), LSM_E_INF);
    assert_int_equal(sim_drive_step(&d, 5.0, 0, NULL), LSM_E_NULL);
    assert_int_equal(sim_drive_step_current(&d, NAN, &act), LSM_E_NAN);
    /* substeps: 1 ms / 62.5 us = 16 */
    assert_int_equal(d.n_sub, 16);
    assert_true(fabs(d.dt_s - 62.5e-6) < 1e-15);
    assert_int_equal(sim_drive_init(&d, &p, 6e-3, 0.0), LSM_OK);
    assert_int_equal(d.n_sub, 96);
}

typedef struct {
    double overshoot;   /* fraction of the step */
    double settle_s;    /* last time the error was outside 1 % of the step */
    double final_err;   /* at the end */
    double max_current; /* |i| */
    bool limited;
} step_stats;

static step_stats step_response(const sim_drive_params *p, double step, double seconds)
{
    sim_drive d;
    const double cycle = 1e-3;
    assert_int_equal(sim_drive_init(&d, p, cycle, 0.0), LSM_OK);
    step_stats s = {0};
    const int n = (int)(seconds / cycle + 0.5);
    double act = 0, peak = 0;
    for (int k = 0; k < n; k++) {
        assert_int_equal(sim_drive_step(&d, step, 0, &act), LSM_OK);
        sim_drive_state st;
        sim_drive_get_state(&d, &st);
        assert_true(fabs(st.following_error - (step - act)) < 1e-12 * fabs(step));
        if (act > peak)
            peak = act;
        if (fabs(st.current_A) > s.max_current)
            s.max_current = fabs(st.current_A);
        s.limited |= st.current_limited;
        if (fabs(step - act) > 0.01 * step)
            s.settle_s = (k + 1) * cycle;
    }
    s.overshoot = (peak - step) / step;
    s.final_err = step - act;
    return s;
}

static void test_step_response(void **state)
{
    (void)state;
    sim_drive_params p;
    /* linear axis, 1 mm step: no current limit involved */
    sim_drive_params_default(&p, false);
    step_stats s = step_response(&p, 1.0, 3.0);
    printf("linear 1 mm step: overshoot %.3f %%, settled (1 %%) after %.3f s, error at 3 s %.2e mm, i_max %.2f A\n",
           100 * s.overshoot, s.settle_s, s.final_err, s.max_current);
    assert_true(s.overshoot >= 0 && s.overshoot < 0.05);
    assert_true(s.settle_s < 0.25);
    assert_true(fabs(s.final_err) < 1e-4); /* 0.1 um */
    assert_false(s.limited);
    assert_true(s.max_current <= p.current_max_A);
    /* rotary axis, 0.01 rad */
    sim_drive_params_default(&p, true);
    s = step_response(&p, 0.01, 3.0);
    printf("rotary 0.01 rad step: overshoot %.3f %%, settled after %.3f s, error %.2e rad\n", 100 * s.overshoot,
           s.settle_s, s.final_err);
    assert_true(s.overshoot >= 0 && s.overshoot < 0.05);
    assert_true(s.settle_s < 0.25);
    assert_true(fabs(s.final_err) < 1e-6);
    /* with a 1000 counts/mm encoder the axis stops within one count */
    sim_drive_params_default(&p, false);
    p.encoder_counts_per_mm = 1000;
    s = step_response(&p, 1.0, 3.0);
    assert_true(fabs(s.final_err) <= 1e-3);
    assert_true(s.overshoot < 0.05);
    /* without friction the integrator is not needed for zero error, and there is no hunting */
    sim_drive_params_default(&p, false);
    p.coulomb_N = 0;
    s = step_response(&p, 1.0, 2.0);
    assert_true(fabs(s.final_err) < 1e-6);
}

/* ---- the step response against the analytic response of the linear loop ----
 *
 * Without Coulomb friction the drive is linear: the two-mass plant (motor m_m, load m_l, spring k, damper c,
 * viscous friction b on the load), the current loop a first-order lag tau, the velocity loop a PI
 * C(s) = kp (1 + 1/(Ti s)) on the motor velocity (or P only, Ti = 0), the position loop kv on the load. With
 * Q = c s + k, P_l = m_l s^2 + (b + c) s + k and R = (m_m s^2 + Q) P_l - Q^2, its transfer function is
 *
 *   X_l / X_set = N(s) / D(s),  PI:     N = kf kp kv (Ti s + 1) Q,  D = Ti s (tau s + 1) R + kf kp (Ti s + 1)(kv Q + s P_l)
 *                               P only: N = kf kp kv Q,             D = (tau s + 1) R + kf kp (kv Q + s P_l)
 *
 * (the load equation gives X_m = X_l P_l / Q, the motor equation kf I = X_l R / Q). With the roots s_i of D (all
 * simple), the unit-step response is h(t) = 1 + sum_i c_i e^(s_i t), c_i = N(s_i) / (s_i D'(s_i)), and its
 * integral H(t) = t + sum_i c_i (e^(s_i t) - 1) / s_i. The drive ramps a new setpoint over one cycle T, so the
 * analytic position at the end of cycle k after a step X0 is X0 (H(kT) - H(kT - T)) / T. What the simulation
 * adds is only the discretisation: loops sampled at 16 kHz with the current command held, RK4. */
#include <complex.h>

#define LL_MAX 8
typedef struct {
    int n;                         /* degree of D */
    double d[LL_MAX], num[LL_MAX]; /* coefficients, ascending powers */
    int n_num;
    double complex root[LL_MAX], c[LL_MAX];
} lin_loop;

/* out = a * b; degrees na, nb; returns the degree of the product */
static int poly_mul(const double *a, int na, const double *b, int nb, double *out)
{
    double tmp[LL_MAX] = {0};
    assert_true(na + nb < LL_MAX);
    for (int i = 0; i <= na; i++)
        for (int j = 0; j <= nb; j++)
            tmp[i + j] += a[i] * b[j];
    memcpy(out, tmp, sizeof tmp);
    return na + nb;
}

/* out = a + f b */
static int poly_add(const double *a, int na, double f, const double *b, int nb, double *out)
{
    const int n = na > nb ? na : nb;
    for (int i = 0; i <= n; i++)
        out[i] = (i <= na ? a[i] : 0) + f * (i <= nb ? b[i] : 0);
    return n;
}

static double complex poly_eval(const double *a, int n, double complex s)
{
    double complex v = 0;
    for (int i = n; i >= 0; i--)
        v = v * s + a[i];
    return v;
}

static double complex poly_deriv_eval(const double *a, int n, double complex s)
{
    double complex v = 0;
    for (int i = n; i >= 1; i--)
        v = v * s + (double)i * a[i];
    return v;
}

static void lin_loop_build(lin_loop *L, const sim_drive_params *p)
{
    const double mm = p->motor_mass_kg, ml = p->load_mass_kg, k = p->stiffness_N_m, c = p->damping_N_s_m;
    const double b = p->viscous_N_s_m, kf = p->force_const_N_A, kp = p->vel_kp_A_s_m, kv = p->kv_1_s;
    const double tau = p->current_tau_s, Ti = p->vel_ti_s;
    const double Q[2] = {k, c}, Pl[3] = {k, b + c, ml}, mQ[3] = {k, c, mm}, lag[2] = {1, tau}, s1[2] = {0, 1};
    double R[LL_MAX], t1[LL_MAX], t2[LL_MAX], pos[LL_MAX];
    int nR = poly_mul(mQ, 2, Pl, 2, R); /* (m_m s^2 + Q) P_l */
    int nt = poly_mul(Q, 1, Q, 1, t1);
    nR = poly_add(R, nR, -1, t1, nt, R);  /* - Q^2 */
    int np = poly_mul(s1, 1, Pl, 2, t1);  /* s P_l */
    np = poly_add(t1, np, kv, Q, 1, pos); /* kv Q + s P_l */
    memset(L, 0, sizeof *L);
    if (Ti > 0) {
        const double tis[2] = {0, Ti}, pi[2] = {1, Ti};
        int n1 = poly_mul(tis, 1, lag, 1, t1);
        n1 = poly_mul(t1, n1, R, nR, t1);      /* Ti s (tau s + 1) R */
        int n2 = poly_mul(pi, 1, pos, np, t2); /* (Ti s + 1)(kv Q + s P_l) */
        L->n = poly_add(t1, n1, kf * kp, t2, n2, L->d);
        L->n_num = poly_mul(pi, 1, Q, 1, L->num);
    } else {
        int n1 = poly_mul(lag, 1, R, nR, t1);
        L->n = poly_add(t1, n1, kf * kp, pos, np, L->d);
        L->n_num = 1;
        memcpy(L->num, Q, sizeof Q);
    }
    for (int i = 0; i <= L->n_num; i++)
        L->num[i] *= kf * kp * kv;
    /* roots of D: Durand-Kerner on the monic polynomial, from points on a circle of the roots' scale */
    double mon[LL_MAX];
    for (int i = 0; i <= L->n; i++)
        mon[i] = L->d[i] / L->d[L->n];
    double scale = 0;
    for (int i = 0; i < L->n; i++)
        scale = fmax(scale, pow(fabs(mon[i]), 1.0 / (L->n - i)));
    const double complex z = 0.4 + 0.9 * I;
    for (int i = 0; i < L->n; i++)
        L->root[i] = scale * cpow(z, i);
    for (int it = 0; it < 5000; it++) {
        double move = 0;
        for (int i = 0; i < L->n; i++) {
            double complex den = 1;
            for (int j = 0; j < L->n; j++)
                if (j != i)
                    den *= L->root[i] - L->root[j];
            const double complex step = poly_eval(mon, L->n, L->root[i]) / den;
            L->root[i] -= step;
            move = fmax(move, cabs(step) / cabs(L->root[i]));
        }
        if (move < 1e-14)
            break;
    }
    for (int i = 0; i < L->n; i++) {
        const double complex r = L->root[i];
        /* a root (Newton's residual tiny against the root) of a stable loop */
        assert_true(cabs(poly_eval(L->d, L->n, r) / poly_deriv_eval(L->d, L->n, r)) < 1e-9 * cabs(r));
        assert_true(creal(r) < 0);
        L->c[i] = poly_eval(L->num, L->n_num, r) / (r * poly_deriv_eval(L->d, L->n, r));
    }
}

/* Integral of the unit-step response, H(t). */
static double lin_loop_H(const lin_loop *L, double t)
{
    double complex h = t;
    for (int i = 0; i < L->n; i++)
        h += L->c[i] * (cexp(L->root[i] * t) - 1) / L->root[i];
    return creal(h);
}

/* Largest |drive - reference| over `seconds` after a step of `step` (and the two responses' overshoots). */
static double step_vs_analytic(const sim_drive_params *p, double step, double seconds, double *ov_drive, double *ov_ref)
{
    lin_loop L;
    lin_loop_build(&L, p);
    /* h(0) = 0: the residues sum to -1 (the model's own consistency) */
    double complex sum = 0;
    for (int i = 0; i < L.n; i++)
        sum += L.c[i];
    assert_true(cabs(sum + 1) < 1e-9);
    sim_drive d;
    const double T = 1e-3;
    assert_int_equal(sim_drive_init(&d, p, T, 0.0), LSM_OK);
    const int n = (int)(seconds / T + 0.5);
    double worst = 0, peak_d = 0, peak_r = 0;
    for (int k = 1; k <= n; k++) {
        double act;
        assert_int_equal(sim_drive_step(&d, step, 0, &act), LSM_OK);
        sim_drive_state st;
        sim_drive_get_state(&d, &st);
        assert_false(st.current_limited); /* the loop stays linear */
        const double ref = step * (lin_loop_H(&L, k * T) - lin_loop_H(&L, (k - 1) * T)) / T;
        worst = fmax(worst, fabs(act - ref));
        peak_d = fmax(peak_d, act);
        peak_r = fmax(peak_r, ref);
    }
    *ov_drive = (peak_d - step) / step;
    *ov_ref = (peak_r - step) / step;
    return worst;
}

static void test_step_response_analytic(void **state)
{
    (void)state;
    /* the default axis without Coulomb friction, with a P or PI velocity loop, and a stiff position loop (kv 120
     * /s against the 40 Hz velocity loop) whose response overshoots and rings */
    static const struct {
        const char *name;
        bool p_only;
        double kv_1_s, max_dev; /* tolerance: fraction of the step at 62.5 us */
    } cases[] = {{"P velocity loop", true, 40, 0.004},
                 {"PI velocity loop", false, 40, 0.004},
                 {"PI velocity loop, kv 120", false, 120, 0.01}};
    sim_drive_params p;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double dev[2], ov_d[2], ov_r[2];
        for (int fine = 0; fine < 2; fine++) {
            sim_drive_params_default(&p, false);
            p.coulomb_N = 0;
            p.kv_1_s = cases[c].kv_1_s;
            if (cases[c].p_only)
                p.vel_ti_s = 0;
            if (fine)
                p.servo_period_s /= 8;
            dev[fine] = step_vs_analytic(&p, 1.0, 0.6, &ov_d[fine], &ov_r[fine]);
            printf("linear 1 mm step, %s, no Coulomb friction, servo period %.2f us: largest difference from the "
                   "analytic response %.4f %% of the step; overshoot %.3f %% (analytic %.3f %%)\n",
                   cases[c].name, 1e6 * p.servo_period_s, 100 * dev[fine], 100 * ov_d[fine], 100 * ov_r[fine]);
        }
        assert_true(dev[0] < cases[c].max_dev);
        /* the difference is the discretisation: 8x finer loops, about 8x closer (first order in the period) */
        assert_true(dev[1] < dev[0] / 6);
        assert_true(fabs(ov_d[1] - ov_r[1]) < 0.001);
    }
    /* the comparison is sensitive: the same reference against a drive whose position gain is 10 % off */
    sim_drive_params_default(&p, false);
    p.coulomb_N = 0;
    lin_loop L;
    lin_loop_build(&L, &p);
    sim_drive_params q = p;
    q.kv_1_s *= 1.1;
    sim_drive d;
    assert_int_equal(sim_drive_init(&d, &q, 1e-3, 0.0), LSM_OK);
    double worst = 0;
    for (int k = 1; k <= 600; k++) {
        double act;
        assert_int_equal(sim_drive_step(&d, 1.0, 0, &act), LSM_OK);
        worst = fmax(worst, fabs(act - (lin_loop_H(&L, k * 1e-3) - lin_loop_H(&L, (k - 1) * 1e-3)) / 1e-3));
    }
    printf("  against a drive with kv 10 %% higher: %.3f %% of the step\n", 100 * worst);
    assert_true(worst > 0.01);
}

static void test_current_limit(void **state)
{
    (void)state;
    sim_drive_params p;
    sim_drive_params_default(&p, false);
    /* a 50 mm step asks for far more than 8 A */
    step_stats s = step_response(&p, 50.0, 3.0);
    printf("linear 50 mm step: overshoot %.3f %%, settled after %.3f s, i_max %.3f A (limit %.1f)\n", 100 * s.overshoot,
           s.settle_s, s.max_current, p.current_max_A);
    assert_true(s.limited);
    assert_true(s.max_current <= p.current_max_A * (1 + 1e-12));
    assert_true(s.max_current > 0.99 * p.current_max_A);
    assert_true(s.overshoot < 0.02); /* no integrator wind-up */
    assert_true(s.settle_s < 0.5);
    assert_true(fabs(s.final_err) < 1e-3);
}

static void test_ramp_following_error(void **state)
{
    (void)state;
    sim_drive_params p;
    sim_drive_params_default(&p, false);
    const double v = 100.0, cycle = 1e-3; /* mm/s */
    for (int ff = 0; ff < 2; ff++) {
        p.vff_gain = ff ? 1.0 : 0.0;
        sim_drive d;
        assert_int_equal(sim_drive_init(&d, &p, cycle, 0.0), LSM_OK);
        double act = 0, err = 0;
        for (int k = 1; k <= 2000; k++) {
            double set = v * k * cycle;
            assert_int_equal(sim_drive_step(&d, set, v, &act), LSM_OK);
            err = set - act;
        }
        printf("ramp %.0f mm/s, vff %.0f: following error %.5f mm (v/kv = %.5f mm)\n", v, p.vff_gain, err,
               v / p.kv_1_s);
        if (ff == 0)
            assert_true(fabs(err - v / p.kv_1_s) < 0.01 * v / p.kv_1_s);
        else
            assert_true(fabs(err) < 0.02 * v / p.kv_1_s);
    }
}

/* Where the position loop is closed: on a ramp at 100 mm/s with velocity feed-forward and only viscous friction
 * on the load, the spring carries b v, so the load trails the motor by b v / k. The loop removes the error of the
 * position it measures: with load feedback set - load -> 0 (and set - motor -> -b v / k), with motor feedback
 * (semi-closed loop) set - motor -> 0 and set - load -> b v / k. Both on top of the lead of one servo substep,
 * -v dt_s, that the loop has on a ramp (the setpoint of the substep is compared before the substep is integrated). */
static void test_motor_feedback(void **state)
{
    (void)state;
    const double v = 100.0, cycle = 1e-3;
    for (int mf = 0; mf < 2; mf++) {
        sim_drive_params p;
        sim_drive_params_default(&p, false);
        p.coulomb_N = 0;
        p.vff_gain = 1.0;
        p.motor_feedback = mf;
        sim_drive d;
        assert_int_equal(sim_drive_init(&d, &p, cycle, 0.0), LSM_OK);
        double act = 0, set = 0;
        for (int k = 1; k <= 3000; k++) {
            set = v * k * cycle;
            assert_int_equal(sim_drive_step(&d, set, v, &act), LSM_OK);
        }
        sim_drive_state st;
        sim_drive_get_state(&d, &st);
        const double defl = p.viscous_N_s_m * v / p.stiffness_N_m; /* mm: N s/m * mm/s / (N/m) */
        printf("ramp %.0f mm/s, %s feedback: set - load %.6f mm, set - motor %.6f mm (b v / k = %.6f mm)\n", v,
               mf ? "motor" : "load", set - st.load_pos, set - st.motor_pos, defl);
        const double lead = -v * d.dt_s;
        const double load_err = set - st.load_pos - lead, motor_err = set - st.motor_pos - lead;
        if (mf) {
            assert_true(fabs(motor_err) < 0.02 * defl);
            assert_true(fabs(load_err - defl) < 0.02 * defl);
        } else {
            assert_true(fabs(load_err) < 0.02 * defl);
            assert_true(fabs(motor_err + defl) < 0.02 * defl);
        }
    }
}

/* Feed-forward: along a smooth move (velocity 100 sin^2(pi t / 0.3 s) mm/s) the largest following error
 * falls with velocity feed-forward and again with acceleration feed-forward added. */
static void test_feed_forward(void **state)
{
    (void)state;
    const double cycle = 1e-3, T = 0.3, V = 100.0;
    double emax[3];
    for (int c = 0; c < 3; c++) {
        sim_drive_params p;
        sim_drive_params_default(&p, false);
        p.coulomb_N = 0; /* friction is not fed forward: leave it out to compare with the model */
        p.viscous_N_s_m = 0;
        p.vff_gain = c >= 1 ? 1.0 : 0.0;
        p.aff_gain = c >= 2 ? 1.0 : 0.0;
        sim_drive d;
        assert_int_equal(sim_drive_init(&d, &p, cycle, 0.0), LSM_OK);
        emax[c] = 0;
        for (int k = 1; k <= 600; k++) {
            double t = k * cycle, x, v, a;
            if (t < T) {
                x = V * (t / 2 - T / (4 * PI) * sin(2 * PI * t / T));
                v = V * pow(sin(PI * t / T), 2);
                a = V * PI / T * sin(2 * PI * t / T);
            } else {
                x = V * T / 2;
                v = a = 0;
            }
            double act;
            assert_int_equal(sim_drive_step_ff(&d, x, v, a, &act), LSM_OK);
            if (fabs(x - act) > emax[c])
                emax[c] = fabs(x - act);
        }
    }
    printf("smooth 15 mm move: max following error %.4f mm (no FF), %.4f mm (velocity FF), %.4f mm (velocity + "
           "acceleration FF)\n",
           emax[0], emax[1], emax[2]);
    /* with both feed-forwards what is left is of the order of the spring's quasi-static deflection
     * m_l a / k (the rigid-body feed-forward ignores the compliance), 10.7 um here */
    sim_drive_params q;
    sim_drive_params_default(&q, false);
    const double defl = q.load_mass_kg * (V * PI / T * 1e-3) / q.stiffness_N_m * 1e3; /* mm */
    printf("  spring deflection m_l a_max / k = %.4f mm\n", defl);
    assert_true(emax[0] > 0.9 * V / q.kv_1_s); /* about v_max / kv without feed-forward */
    assert_true(emax[1] < 0.05 * emax[0]);
    assert_true(emax[2] < 0.6 * emax[1]);
    assert_true(emax[2] < 2.0 * defl);
}

static void test_step_test_api(void **state)
{
    (void)state;
    sim_drive_params p;
    sim_drive_params_default(&p, false);
    sim_drive_step_stats s;
    assert_int_equal(sim_drive_step_test(&p, 1e-3, 1.0, 2.0, &s), LSM_OK);
    assert_true(s.settled);
    assert_true(s.overshoot < 0.05 && s.settle_s < 0.25 && fabs(s.final_error) < 1e-3);
    assert_int_equal(sim_drive_step_test(&p, 1e-3, 0.0, 2.0, &s), LSM_E_ARG);
    assert_int_equal(sim_drive_step_test(&p, 1e-3, 1.0, 2.0, NULL), LSM_E_NULL);
    /* a 15 Hz resonance under a 40 Hz velocity loop: valid numbers, unstable loop */
    const double mu = p.motor_mass_kg * p.load_mass_kg / (p.motor_mass_kg + p.load_mass_kg);
    p.stiffness_N_m = pow(2 * PI * 15.0, 2) * mu;
    p.damping_N_s_m = 2 * 0.03 * sqrt(p.stiffness_N_m * mu);
    assert_int_equal(sim_drive_validate(&p, 1e-3, NULL), LSM_OK);
    assert_int_equal(sim_drive_step_test(&p, 1e-3, 1.0, 2.0, &s), LSM_OK);
    printf("15 Hz resonance under the default gains: settled %d, error in the last 0.5 s up to %.3g mm\n",
           (int)s.settled, s.max_error);
    assert_false(s.settled);
}

/* Open-loop current pulse of `amp_A` for `steps` servo periods; records the spring deflection and
 * the load acceleration at every servo period. */
static void excite(const sim_drive_params *p, double amp_A, int steps, double *defl, double *acc, int n)
{
    sim_drive d;
    const double cycle = p->servo_period_s; /* one substep per call: fine sampling */
    assert_int_equal(sim_drive_init(&d, p, cycle, 0.0), LSM_OK);
    double act;
    for (int k = 0; k < n; k++) {
        assert_int_equal(sim_drive_step_current(&d, k < steps ? amp_A : 0.0, &act), LSM_OK);
        sim_drive_state s;
        sim_drive_get_state(&d, &s);
        defl[k] = s.motor_pos - s.load_pos;
        acc[k] = s.load_acc;
    }
}

/* Frequency from the upward zero crossings (linear interpolation) in x[k0 .. k1), whole periods only
 * so that a small offset of the oscillation does not bias it. */
static double zero_crossings(const double *x, int k0, int k1, double dt)
{
    double first = -1, last = -1;
    int periods = -1;
    for (int k = k0; k + 1 < k1; k++) {
        if (x[k] < 0 && x[k + 1] >= 0) {
            double t = (k + x[k] / (x[k] - x[k + 1])) * dt;
            if (first < 0)
                first = t;
            last = t;
            periods++;
        }
    }
    assert_true(periods >= 5);
    return periods / (last - first);
}

/* Damping ratio from the logarithmic decrement of the positive peaks in x[k0 .. k1). */
static double log_decrement_zeta(const double *x, int k0, int k1)
{
    double peaks[64];
    int np = 0;
    for (int k = k0 + 1; k + 1 < k1 && np < 64; k++)
        if (x[k] > 0 && x[k] >= x[k - 1] && x[k] > x[k + 1])
            peaks[np++] = x[k];
    assert_true(np >= 6);
    double delta = log(peaks[0] / peaks[5]) / 5.0;
    return delta / sqrt(4 * PI * PI + delta * delta);
}

/* Peak of a direct DFT magnitude of x[k0 .. k1) over [f_lo, f_hi] on a 0.1 Hz grid. */
static double dft_peak(const double *x, int k0, int k1, double dt, double f_lo, double f_hi)
{
    double best_f = 0, best = -1;
    for (double f = f_lo; f <= f_hi; f += 0.1) {
        double re = 0, im = 0;
        for (int k = k0; k < k1; k++) {
            re += x[k] * cos(2 * PI * f * k * dt);
            im -= x[k] * sin(2 * PI * f * k * dt);
        }
        double m = re * re + im * im;
        if (m > best) {
            best = m;
            best_f = f;
        }
    }
    return best_f;
}

static void test_resonance(void **state)
{
    (void)state;
    enum { N = 8000 }; /* 0.5 s at 16 kHz */
    static double defl[N], acc[N];
    for (int rot = 0; rot < 2; rot++) {
        sim_drive_params p;
        sim_drive_params_default(&p, rot != 0);
        const double dt = p.servo_period_s;
        sim_drive_modes m;
        sim_drive_modes_analytic(&p, &m);
        const int k0 = (int)(0.015 / dt), k1 = k0 + (int)(0.1 / dt), k2 = k0 + (int)(0.25 / dt);

        /* A: no friction, short pulse. The free two-mass mode: w_r sqrt(1 - zeta_r^2). */
        sim_drive_params q = p;
        q.coulomb_N = 0;
        q.viscous_N_s_m = 0;
        excite(&q, 0.25 * q.current_max_A, 4, defl, acc, N);
        double f = zero_crossings(defl, k0, k1, dt);
        double f_dft = dft_peak(acc, k0, k2, dt, 0.5 * m.f_res_hz, 1.5 * m.f_res_hz);
        double zeta = log_decrement_zeta(defl, k0, k1);
        printf("%s, no friction: resonance %.3f Hz (zero crossings), %.1f Hz (DFT); analytic %.3f Hz damped, "
               "%.3f undamped; zeta %.4f vs %.4f\n",
               rot ? "rotary" : "linear", f, f_dft, m.f_res_damped_hz, m.f_res_hz, zeta, m.zeta_res);
        assert_true(fabs(f - m.f_res_damped_hz) < 0.005 * m.f_res_damped_hz);
        assert_true(fabs(f_dft - m.f_res_damped_hz) < 0.03 * m.f_res_damped_hz);
        assert_true(fabs(zeta - m.zeta_res) < 0.1 * m.zeta_res);

        /* B: default friction, a long full-current pulse: the load keeps sliding through the window,
         * Coulomb friction is then a constant force and the mode is still the free one. (Viscous
         * friction on the load adds damping, so zeta is not compared here.) */
        excite(&p, p.current_max_A, (int)(0.01 / dt), defl, acc, N);
        f = zero_crossings(defl, k0, k1, dt);
        f_dft = dft_peak(acc, k0, k2, dt, 0.5 * m.f_res_hz, 1.5 * m.f_res_hz);
        printf("%s, sliding with friction: resonance %.3f Hz (zero crossings), %.1f Hz (DFT); analytic %.3f Hz\n",
               rot ? "rotary" : "linear", f, f_dft, m.f_res_damped_hz);
        assert_true(fabs(f - m.f_res_damped_hz) < 0.03 * m.f_res_damped_hz);
        assert_true(fabs(f_dft - m.f_res_damped_hz) < 0.03 * m.f_res_damped_hz);

        /* C: default friction, a short pulse: the load sticks within a few ms and the motor rings
         * against a held load, at sqrt(k / m_motor) (damped by c alone), well below w_r. */
        excite(&p, 0.25 * p.current_max_A, 4, defl, acc, N);
        const double zm = p.damping_N_s_m / (2 * sqrt(p.stiffness_N_m * p.motor_mass_kg));
        const double f_locked = sqrt(p.stiffness_N_m / p.motor_mass_kg) / (2 * PI) * sqrt(1 - zm * zm);
        f = zero_crossings(defl, k0, k1, dt);
        printf("%s, stuck load: %.3f Hz measured, sqrt(k/m_m) damped %.3f Hz\n", rot ? "rotary" : "linear", f,
               f_locked);
        assert_true(fabs(f - f_locked) < 0.01 * f_locked);
        assert_true(f < 0.95 * m.f_res_damped_hz);
    }
    /* and the analytic formulas themselves, on hand-computed numbers: m_m = 15, m_l = 45, k = 4.4e6 */
    sim_drive_params p;
    sim_drive_params_default(&p, false);
    sim_drive_modes m;
    sim_drive_modes_analytic(&p, &m);
    const double mu = 15.0 * 45.0 / 60.0; /* 11.25 kg */
    assert_true(fabs(m.f_res_hz - sqrt(4.4e6 / mu) / (2 * PI)) < 1e-9);
    assert_true(fabs(m.f_antires_hz - sqrt(4.4e6 / 45.0) / (2 * PI)) < 1e-9);
    assert_true(fabs(m.zeta_res - 700.0 / (2 * sqrt(4.4e6 * mu))) < 1e-12);
    assert_true(m.f_res_hz > 95 && m.f_res_hz < 105);
}

static void test_deterministic(void **state)
{
    (void)state;
    sim_drive_params p;
    sim_drive_params_default(&p, false);
    p.encoder_counts_per_mm = 500;
    p.vff_gain = 0.8;
    sim_drive a, b;
    assert_int_equal(sim_drive_init(&a, &p, 2e-3, 1.0), LSM_OK);
    assert_int_equal(sim_drive_init(&b, &p, 2e-3, 1.0), LSM_OK);
    for (int k = 0; k < 3000; k++) {
        double t = k * 2e-3, set = 1.0 + 20.0 * sin(3.0 * t), vff = 60.0 * cos(3.0 * t), xa, xb;
        assert_int_equal(sim_drive_step(&a, set, vff, &xa), LSM_OK);
        assert_int_equal(sim_drive_step(&b, set, vff, &xb), LSM_OK);
        assert_memory_equal(&xa, &xb, sizeof xa);
    }
    assert_memory_equal(&a, &b, sizeof a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validate),
        cmocka_unit_test(test_step_response),
        cmocka_unit_test(test_step_response_analytic),
        cmocka_unit_test(test_current_limit),
        cmocka_unit_test(test_ramp_following_error),
        cmocka_unit_test(test_feed_forward),
        cmocka_unit_test(test_motor_feedback),
        cmocka_unit_test(test_step_test_api),
        cmocka_unit_test(test_resonance),
        cmocka_unit_test(test_deterministic),
    };
    return cmocka_run_group_tests_name("sim_drive", tests, NULL, NULL);
}
