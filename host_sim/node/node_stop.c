#include "node_stop.h"

#include <math.h>
#include <string.h>

#include "lsm_math.h"

#define PI_D 3.14159265358979323846

double node_stop_ramp_time(double da, double J, double S, double *jp, double *t1, double *t2)
{
    double p = 0, r = 0, c = 0;
    if (da > 0) {
        const double knee = PI_D * J * J / (2 * S);
        if (da >= knee) {
            p = J;
            r = PI_D * J / (2 * S);
            c = da / J - r;
            if (c < 0)
                c = 0;
        } else {
            r = sqrt(PI_D * da / (2 * S));
            p = 2 * S * r / PI_D;
            c = 0;
        }
    }
    if (jp != NULL)
        *jp = p;
    if (t1 != NULL)
        *t1 = r;
    if (t2 != NULL)
        *t2 = c;
    return 2 * r + c;
}

/* End velocity (travel frame) without a plateau, for the intermediate acceleration a1. */
static double end_velocity(double v, double a, double a1, const node_stop_limits *l)
{
    const double ta = node_stop_ramp_time(fabs(a - a1), l->jerk, l->snap, NULL, NULL, NULL);
    const double tc = node_stop_ramp_time(fabs(a1), l->jerk, l->snap, NULL, NULL, NULL);
    return v + (a + a1) * ta / 2 + a1 * tc / 2;
}

static void add_phase(node_stop *s, lsm_phase_shape shape, double dur, double jerk)
{
    if (!(dur > 0))
        return;
    s->shape[s->n_phases] = shape;
    s->dur[s->n_phases] = dur;
    s->jerk[s->n_phases] = jerk;
    s->n_phases++;
}

static void add_ramp(node_stop *s, double from, double to)
{
    double jp, t1, t2;
    (void)node_stop_ramp_time(fabs(to - from), s->lim.jerk, s->lim.snap, &jp, &t1, &t2);
    if (!(t1 > 0))
        return;
    const double sg = to > from ? 1.0 : -1.0;
    add_phase(s, LSM_PHASE_RISE, t1, sg * jp);
    add_phase(s, LSM_PHASE_CONST, t2, sg * jp);
    add_phase(s, LSM_PHASE_FALL, t1, sg * jp);
}

/* State after tau seconds of phase i, from its start state (travel frame). */
static void advance(const node_stop *s, unsigned i, double tau, lsm_kin *out)
{
    lsm_real u[4];
    lsm_phase_unit(s->shape[i], s->dur[i], tau, u);
    const lsm_kin k = s->start[i];
    const double jk = s->jerk[i];
    out->j_mm_s3 = jk * u[0];
    out->a_mm_s2 = k.a_mm_s2 + jk * u[1];
    out->v_mm_s = k.v_mm_s + k.a_mm_s2 * tau + jk * u[2];
    out->s_mm = k.s_mm + k.v_mm_s * tau + k.a_mm_s2 * tau * tau / 2 + jk * u[3];
}

lsm_status node_stop_plan(node_stop *s, double p, double v, double a, const node_stop_limits *lim)
{
    if (s == NULL || lim == NULL)
        return LSM_E_NULL;
    const double in[6] = {p, v, a, lim->decel, lim->jerk, lim->snap};
    for (int i = 0; i < 6; i++) {
        int st = lsm_check_finite(in[i]);
        if (st != 0)
            return (lsm_status)st;
    }
    if (!(lim->decel > 0) || !(lim->jerk > 0) || !(lim->snap > 0))
        return LSM_E_LIMIT;
    memset(s, 0, sizeof *s);
    s->lim = *lim;
    s->origin = p;
    s->dir = 1;
    if (v == 0 && a == 0)
        return LSM_OK; /* at rest: nothing to do */
    s->dir = v > 0 ? 1.0 : v < 0 ? -1.0 : (a > 0 ? 1.0 : -1.0);
    const double vt = s->dir * v, at = s->dir * a, D = lim->decel;

    double a1, tb = 0;
    const double f0 = end_velocity(vt, at, 0, lim);
    if (f0 <= 0) {
        a1 = 0; /* braking harder than the limits can undo: ramp a to 0, a second stage follows */
    } else {
        const double fd = end_velocity(vt, at, -D, lim);
        if (fd >= 0) {
            a1 = -D;
            tb = fd / D;
        } else {
            double lo = -D, hi = 0; /* f(lo) < 0 < f(hi) */
            for (int it = 0; it < 2000 && hi - lo > 4e-16 * (fabs(lo) + fabs(hi)); it++) {
                const double mid = (lo + hi) / 2;
                if (end_velocity(vt, at, mid, lim) > 0)
                    hi = mid;
                else
                    lo = mid;
            }
            a1 = (lo + hi) / 2;
        }
    }
    add_ramp(s, at, a1);
    add_phase(s, LSM_PHASE_CONST, tb, 0);
    add_ramp(s, a1, 0);
    s->start[0].s_mm = 0;
    s->start[0].v_mm_s = vt;
    s->start[0].a_mm_s2 = at;
    s->start[0].j_mm_s3 = 0;
    s->t_end = 0;
    for (unsigned i = 0; i < s->n_phases; i++) {
        advance(s, i, s->dur[i], &s->start[i + 1]);
        s->t_end += s->dur[i];
    }
    /* the end is rest by construction (up to rounding); a negative end velocity is the overshoot stage */
    s->start[s->n_phases].a_mm_s2 = 0;
    s->start[s->n_phases].j_mm_s3 = 0;
    s->active = true;
    return LSM_OK;
}

void node_stop_eval(const node_stop *s, double t, lsm_kin *out)
{
    lsm_kin k;
    unsigned i = 0;
    double t0 = 0;
    while (i < s->n_phases && t > t0 + s->dur[i]) {
        t0 += s->dur[i];
        i++;
    }
    if (i >= s->n_phases)
        k = s->start[s->n_phases];
    else
        advance(s, i, t - t0, &k);
    out->s_mm = s->origin + s->dir * k.s_mm;
    out->v_mm_s = s->dir * k.v_mm_s;
    out->a_mm_s2 = s->dir * k.a_mm_s2;
    out->j_mm_s3 = s->dir * k.j_mm_s3;
}

bool node_stop_step(node_stop *s, double dt, lsm_kin *out)
{
    if (!s->active) {
        out->s_mm = s->origin;
        out->v_mm_s = out->a_mm_s2 = out->j_mm_s3 = 0;
        return false;
    }
    s->t += dt;
    if (s->t < s->t_end) {
        node_stop_eval(s, s->t, out);
        return true;
    }
    const lsm_kin e = s->start[s->n_phases];
    const double p_end = s->origin + s->dir * e.s_mm;
    const double v_end = s->dir * e.v_mm_s;
    const double scale = fabs(s->start[0].v_mm_s) + fabs(s->start[0].a_mm_s2) * s->t_end + 1e-12;
    if (fabs(v_end) > 1e-9 * scale) {
        /* overshoot stage done: stop again from (p_end, v_end, 0) with the rest of this cycle */
        const double rest = s->t - s->t_end;
        node_stop_limits lim = s->lim;
        if (node_stop_plan(s, p_end, v_end, 0, &lim) == LSM_OK && s->active) {
            s->t = rest;
            if (s->t < s->t_end) {
                node_stop_eval(s, s->t, out);
                return true;
            }
            return node_stop_step(s, 0, out);
        }
    }
    s->active = false;
    s->origin = p_end;
    out->s_mm = p_end;
    out->v_mm_s = out->a_mm_s2 = out->j_mm_s3 = 0;
    return false;
}
