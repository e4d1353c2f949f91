/*
 * drive.c: simulated cascaded servo with a two-mass plant (see drive.h for the model).
 */
#include "drive.h"

#include <math.h>
#include <stddef.h>

#define TWO_PI 6.28318530717958647692

void sim_drive_params_default(sim_drive_params *p, bool rotary)
{
    if (!p)
        return;
    *p = (sim_drive_params){0};
    p->rotary = rotary;
    p->kv_1_s = 40.0;
    p->vff_gain = 0.0;
    p->vel_ti_s = 0.015;
    p->current_tau_s = 0.25e-3;
    p->servo_period_s = 62.5e-6;
    p->encoder_counts_per_mm = 0.0;
    if (!rotary) {
        /* 0.4 kW servo, Kt 0.6 N m/A, J 0.8e-4 kg m^2 (rotor + screw), 20 mm lead */
        p->force_const_N_A = 190.0;
        p->current_max_A = 8.0;
        p->motor_mass_kg = 15.0;
        p->load_mass_kg = 45.0;
        p->stiffness_N_m = 4.4e6; /* resonance ~100 Hz, anti-resonance ~50 Hz */
        p->damping_N_s_m = 700.0; /* zeta ~0.05 */
        p->viscous_N_s_m = 200.0;
        p->coulomb_N = 30.0;
        p->vel_kp_A_s_m = 80.0; /* velocity loop crossover ~40 Hz */
    } else {
        /* servo through a 50:1 gear: Kt 0.6 N m/A, J_rotor 1e-4 kg m^2; table 0.5 kg m^2 */
        p->force_const_N_A = 30.0;
        p->current_max_A = 6.0;
        p->motor_mass_kg = 0.25;
        p->load_mass_kg = 0.5;
        p->stiffness_N_m = 4.2e4; /* N m/rad, resonance ~80 Hz */
        p->damping_N_s_m = 8.4;
        p->viscous_N_s_m = 1.0;
        p->coulomb_N = 5.0;
        p->vel_kp_A_s_m = 6.3;
    }
}

void sim_drive_modes_analytic(const sim_drive_params *p, sim_drive_modes *m)
{
    if (!p || !m)
        return;
    const double mm = p->motor_mass_kg, ml = p->load_mass_kg, k = p->stiffness_N_m, c = p->damping_N_s_m;
    const double mu = mm * ml / (mm + ml);
    const double wr = sqrt(k / mu);
    m->f_res_hz = wr / TWO_PI;
    m->zeta_res = c / (2.0 * sqrt(k * mu));
    m->f_res_damped_hz = m->zeta_res < 1.0 ? m->f_res_hz * sqrt(1.0 - m->zeta_res * m->zeta_res) : 0.0;
    m->f_antires_hz = sqrt(k / ml) / TWO_PI;
}

static lsm_status check_value(double x, bool positive, bool allow_zero, lsm_status neg_code)
{
    if (isnan(x))
        return LSM_E_NAN;
    if (isinf(x))
        return LSM_E_INF;
    if (positive && (x < 0 || (!allow_zero && x == 0)))
        return neg_code;
    return LSM_OK;
}

lsm_status sim_drive_validate(const sim_drive_params *p, double cycle_s, const char **bad_field)
{
    const char *dummy;
    if (!bad_field)
        bad_field = &dummy;
    *bad_field = NULL;
    if (!p)
        return LSM_E_NULL;
    struct {
        const char *name;
        double v;
        bool allow_zero;
        lsm_status code;
    } f[] = {
        {"kv_1_s", p->kv_1_s, false, LSM_E_LIMIT},
        {"vff_gain", p->vff_gain, true, LSM_E_ARG},
        {"aff_gain", p->aff_gain, true, LSM_E_ARG},
        {"vel_kp_A_s_m", p->vel_kp_A_s_m, false, LSM_E_LIMIT},
        {"vel_ti_s", p->vel_ti_s, true, LSM_E_ARG},
        {"current_tau_s", p->current_tau_s, false, LSM_E_LIMIT},
        {"current_max_A", p->current_max_A, false, LSM_E_LIMIT},
        {"force_const_N_A", p->force_const_N_A, false, LSM_E_LIMIT},
        {"motor_mass_kg", p->motor_mass_kg, false, LSM_E_LIMIT},
        {"load_mass_kg", p->load_mass_kg, false, LSM_E_LIMIT},
        {"stiffness_N_m", p->stiffness_N_m, false, LSM_E_LIMIT},
        {"damping_N_s_m", p->damping_N_s_m, true, LSM_E_ARG},
        {"viscous_N_s_m", p->viscous_N_s_m, true, LSM_E_ARG},
        {"coulomb_N", p->coulomb_N, true, LSM_E_ARG},
        {"servo_period_s", p->servo_period_s, false, LSM_E_CYCLE},
        {"encoder_counts_per_mm", p->encoder_counts_per_mm, true, LSM_E_ARG},
    };
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) {
        lsm_status st = check_value(f[i].v, true, f[i].allow_zero, f[i].code);
        if (st != LSM_OK) {
            *bad_field = f[i].name;
            return st;
        }
    }
    if (p->servo_period_s < SIM_DRIVE_MIN_SERVO_PERIOD_S) {
        *bad_field = "servo_period_s";
        return LSM_E_ARG;
    }
    if (p->vff_gain > 1.5) {
        *bad_field = "vff_gain";
        return LSM_E_ARG;
    }
    if (p->aff_gain > 1.5) {
        *bad_field = "aff_gain";
        return LSM_E_ARG;
    }
    lsm_status st = check_value(cycle_s, true, false, LSM_E_CYCLE);
    if (st != LSM_OK) {
        *bad_field = "cycle_s";
        return st;
    }
    /* the explicit integration and the sampled loops need a short enough servo period */
    sim_drive_modes m;
    sim_drive_modes_analytic(p, &m);
    const double dt = p->servo_period_s;
    if (dt * TWO_PI * m.f_res_hz > 0.5 || dt > p->current_tau_s || dt > cycle_s) {
        *bad_field = "servo_period_s";
        return LSM_E_ARG;
    }
    return LSM_OK;
}

lsm_status sim_drive_init(sim_drive *d, const sim_drive_params *p, double cycle_s, double pos)
{
    if (!d || !p)
        return LSM_E_NULL;
    lsm_status st = sim_drive_validate(p, cycle_s, NULL);
    if (st != LSM_OK)
        return st;
    st = check_value(pos, false, true, LSM_OK);
    if (st != LSM_OK)
        return st;
    *d = (sim_drive){0};
    d->p = *p;
    d->cycle_s = cycle_s;
    double n = ceil(cycle_s / p->servo_period_s - 1e-9);
    d->n_sub = n < 1 ? 1u : (uint32_t)n;
    d->dt_s = cycle_s / (double)d->n_sub;
    d->unit_m = p->rotary ? 1.0 : 1e-3;
    d->v_eps_m_s = fmax(1e-4, 2.0 * p->coulomb_N * d->dt_s / p->load_mass_kg);
    const double x = pos * d->unit_m;
    d->x_m = x;
    d->x_l = x;
    d->set_prev_m = x;
    d->set_m = x;
    return LSM_OK;
}

/* state derivative: y = (x_m, v_m, x_l, v_l, i) */
static void deriv(const sim_drive *d, const double y[5], double i_cmd, double dy[5])
{
    const sim_drive_params *p = &d->p;
    const double spring = p->stiffness_N_m * (y[0] - y[2]) + p->damping_N_s_m * (y[1] - y[3]);
    const double fric = p->viscous_N_s_m * y[3] + p->coulomb_N * tanh(y[3] / d->v_eps_m_s);
    dy[0] = y[1];
    dy[1] = (p->force_const_N_A * y[4] - spring) / p->motor_mass_kg;
    dy[2] = y[3];
    dy[3] = (spring - fric) / p->load_mass_kg;
    dy[4] = (i_cmd - y[4]) / p->current_tau_s;
}

static void integrate(sim_drive *d, double i_cmd, double h)
{
    double y[5] = {d->x_m, d->v_m, d->x_l, d->v_l, d->i_A}, k1[5], k2[5], k3[5], k4[5], t[5];
    deriv(d, y, i_cmd, k1);
    for (int j = 0; j < 5; j++)
        t[j] = y[j] + 0.5 * h * k1[j];
    deriv(d, t, i_cmd, k2);
    for (int j = 0; j < 5; j++)
        t[j] = y[j] + 0.5 * h * k2[j];
    deriv(d, t, i_cmd, k3);
    for (int j = 0; j < 5; j++)
        t[j] = y[j] + h * k3[j];
    deriv(d, t, i_cmd, k4);
    for (int j = 0; j < 5; j++)
        y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    d->x_m = y[0];
    d->v_m = y[1];
    d->x_l = y[2];
    d->v_l = y[3];
    d->i_A = y[4];
}

static double clamp_current(const sim_drive *d, double i, bool *limited)
{
    const double lim = d->p.current_max_A;
    if (i > lim) {
        *limited = true;
        return lim;
    }
    if (i < -lim) {
        *limited = true;
        return -lim;
    }
    return i;
}

static double measured_pos(const sim_drive *d)
{
    const double x = d->p.motor_feedback ? d->x_m : d->x_l;
    const double cpu = d->p.encoder_counts_per_mm; /* counts per API unit */
    if (cpu <= 0)
        return x;
    const double units = x / d->unit_m;
    return floor(units * cpu + 0.5) / cpu * d->unit_m;
}

lsm_status sim_drive_step(sim_drive *d, double setpoint, double vel_ff, double *actual)
{
    return sim_drive_step_ff(d, setpoint, vel_ff, 0.0, actual);
}

lsm_status sim_drive_step_ff(sim_drive *d, double setpoint, double vel_ff, double acc_ff, double *actual)
{
    if (!d || !actual)
        return LSM_E_NULL;
    if (isnan(setpoint) || isnan(vel_ff) || isnan(acc_ff))
        return LSM_E_NAN;
    if (isinf(setpoint) || isinf(vel_ff) || isinf(acc_ff))
        return LSM_E_INF;
    const sim_drive_params *p = &d->p;
    const double set_end = setpoint * d->unit_m;
    const double vff = p->vff_gain * vel_ff * d->unit_m;
    const double iff = p->aff_gain * (p->motor_mass_kg + p->load_mass_kg) * acc_ff * d->unit_m / p->force_const_N_A;
    const double start = d->set_m;
    d->set_prev_m = start;
    d->limited = false;
    for (uint32_t k = 1; k <= d->n_sub; k++) {
        const double x_set = start + (set_end - start) * ((double)k / (double)d->n_sub);
        const double v_cmd = p->kv_1_s * (x_set - measured_pos(d)) + vff;
        const double e = v_cmd - d->v_m;
        double integ = d->integ_m_s;
        if (p->vel_ti_s > 0)
            integ += e * d->dt_s / p->vel_ti_s;
        bool lim = false;
        double i_cmd = clamp_current(d, p->vel_kp_A_s_m * (e + integ) + iff, &lim);
        /* anti-windup: keep the integrator unless the clamp is pushing against it */
        if (!lim || (integ - d->integ_m_s) * i_cmd < 0)
            d->integ_m_s = integ;
        if (lim) {
            d->limited = true;
            i_cmd = clamp_current(d, p->vel_kp_A_s_m * (e + d->integ_m_s) + iff, &lim);
        }
        d->i_cmd_A = i_cmd;
        integrate(d, i_cmd, d->dt_s);
    }
    d->set_m = set_end;
    d->cycles++;
    *actual = d->x_l / d->unit_m;
    return LSM_OK;
}

lsm_status sim_drive_step_current(sim_drive *d, double i_cmd_A, double *actual)
{
    if (!d || !actual)
        return LSM_E_NULL;
    if (isnan(i_cmd_A))
        return LSM_E_NAN;
    if (isinf(i_cmd_A))
        return LSM_E_INF;
    bool lim = false;
    const double i_cmd = clamp_current(d, i_cmd_A, &lim);
    d->limited = lim;
    d->i_cmd_A = i_cmd;
    for (uint32_t k = 0; k < d->n_sub; k++)
        integrate(d, i_cmd, d->dt_s);
    /* in current mode the position loop follows the load, so that switching back is bumpless */
    d->set_prev_m = d->set_m;
    d->set_m = d->p.motor_feedback ? d->x_m : d->x_l;
    d->integ_m_s = 0;
    d->cycles++;
    *actual = d->x_l / d->unit_m;
    return LSM_OK;
}

void sim_drive_get_state(const sim_drive *d, sim_drive_state *s)
{
    if (!d || !s)
        return;
    const double u = d->unit_m;
    double y[5] = {d->x_m, d->v_m, d->x_l, d->v_l, d->i_A}, dy[5];
    deriv(d, y, d->i_cmd_A, dy);
    s->load_pos = d->x_l / u;
    s->load_vel = d->v_l / u;
    s->load_acc = dy[3] / u;
    s->motor_pos = d->x_m / u;
    s->motor_vel = d->v_m / u;
    s->setpoint = d->set_m / u;
    s->following_error = (d->set_m - d->x_l) / u;
    s->current_A = d->i_A;
    s->current_cmd_A = d->i_cmd_A;
    s->current_limited = d->limited;
}

lsm_status sim_drive_step_test(const sim_drive_params *p, double cycle_s, double step, double duration_s,
                               sim_drive_step_stats *out)
{
    if (!out)
        return LSM_E_NULL;
    if (!(step != 0) || !isfinite(step) || !(duration_s > 0) || !isfinite(duration_s))
        return LSM_E_ARG;
    sim_drive d;
    lsm_status st = sim_drive_init(&d, p, cycle_s, 0.0);
    if (st != LSM_OK)
        return st;
    *out = (sim_drive_step_stats){0};
    const long n = (long)ceil(duration_s / cycle_s);
    const double tol = 0.02 * fabs(step);
    double peak = 0, act = 0;
    for (long k = 0; k < n; k++) {
        sim_drive_step(&d, step, 0.0, &act);
        if (!isfinite(act)) {
            out->max_error = INFINITY;
            out->final_error = INFINITY;
            out->settle_s = duration_s;
            return LSM_OK; /* diverged: settled stays false */
        }
        const double e = fabs(step - act);
        if ((step > 0 ? act : -act) > peak)
            peak = step > 0 ? act : -act;
        if (e > tol)
            out->settle_s = (double)(k + 1) * cycle_s;
        if (k >= 3 * n / 4 && e > out->max_error)
            out->max_error = e;
    }
    out->overshoot = (peak - fabs(step)) / fabs(step);
    out->final_error = step - act;
    out->settled = out->max_error <= tol;
    return LSM_OK;
}
