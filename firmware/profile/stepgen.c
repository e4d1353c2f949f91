#include "stepgen.h"

#include "lsm_math.h"

#define PI_R ((lsm_real)LSM_PI)

static void phase_of(const lsm_move *mv, unsigned p, uint32_t *n, uint8_t *shape)
{
    /* the 15 phases: 7 of the first ramp, the cruise, 7 of the second ramp (move.h) */
    static const uint8_t shapes[7] = {LSM_PHASE_RISE, LSM_PHASE_CONST, LSM_PHASE_FALL, LSM_PHASE_CONST,
                                      LSM_PHASE_RISE, LSM_PHASE_CONST, LSM_PHASE_FALL};
    if (p == 7) {
        *n = mv->cruise_cycles;
        *shape = LSM_PHASE_CONST;
        return;
    }
    const lsm_scurve_intervals *iv = p < 7 ? &mv->acc : &mv->dec;
    const unsigned q = p < 7 ? p : p - 8;
    *shape = shapes[q];
    *n = (q == 1 || q == 5) ? iv->n2_cycles : (q == 3 ? iv->n4_cycles : iv->n1_cycles);
}

static lsm_real jerk_of(const lsm_move_axis *ax, unsigned p)
{
    if (p == 7 || p == 3 || p == 11)
        return 0;
    if (p < 7)
        return p < 3 ? ax->jp_acc_mm_s3 : -ax->jp_acc_mm_s3;
    return p < 11 ? ax->jp_dec_mm_s3 : -ax->jp_dec_mm_s3;
}

/* Enters phase p (skipping empty phases); returns false past the last phase. */
static bool enter_phase(lsm_stepgen *g, unsigned p)
{
    for (; p < LSM_MOVE_PHASES; p++) {
        uint32_t n;
        uint8_t shape;
        phase_of(g->mv, p, &n, &shape);
        if (n == 0)
            continue;
        g->phase = (uint8_t)p;
        g->m = 0;
        g->c = 1;
        g->s = 0;
        if (shape != LSM_PHASE_CONST) {
            const lsm_real T = (lsm_real)n * g->mv->cycle_s;
            const lsm_real w = PI_R / (2 * T);
            g->k8 = 1 / (8 * w * w);
            g->k16 = 1 / (16 * w * w * w);
        }
        for (unsigned i = 0; i < g->mv->n_axes; i++) {
            g->jerk[i] = jerk_of(&g->mv->axis[i], p);
            g->start[i].s_mm = g->st_s[p][i];
            g->start[i].v_mm_s = g->st_v[p][i];
            g->start[i].a_mm_s2 = g->st_a[p][i];
        }
        return true;
    }
    g->phase = LSM_MOVE_PHASES;
    return false;
}

lsm_status lsm_stepgen_init(lsm_stepgen *g, const lsm_move *mv, const lsm_real *start_mm)
{
    if (g == NULL || mv == NULL)
        return LSM_E_NULL;
    g->mv = mv;
    g->k = 0;
    g->total = lsm_move_total_cycles(mv);
    g->cd_acc = g->cd_dec = 1;
    g->sd_acc = g->sd_dec = 0;
    if (mv->acc.n1_cycles) {
        g->cd_acc = lsm_cos(PI_R / (lsm_real)mv->acc.n1_cycles);
        g->sd_acc = lsm_sin(PI_R / (lsm_real)mv->acc.n1_cycles);
    }
    if (mv->dec.n1_cycles) {
        g->cd_dec = lsm_cos(PI_R / (lsm_real)mv->dec.n1_cycles);
        g->sd_dec = lsm_sin(PI_R / (lsm_real)mv->dec.n1_cycles);
    }
    for (unsigned i = 0; i < mv->n_axes; i++) {
        g->origin_mm[i] = start_mm ? start_mm[i] : 0;
        lsm_kin st[LSM_MOVE_PHASES];
        lsm_move_phase_starts(mv, i, st);
        for (unsigned p = 0; p < LSM_MOVE_PHASES; p++) {
            g->st_s[p][i] = st[p].s_mm;
            g->st_v[p][i] = st[p].v_mm_s;
            g->st_a[p][i] = st[p].a_mm_s2;
        }
    }
    enter_phase(g, 0);
    return LSM_OK;
}

bool lsm_stepgen_next(lsm_stepgen *g, lsm_real *pos_mm)
{
    const lsm_move *mv = g->mv;
    const unsigned na = mv->n_axes;
    if (g->k + 1 >= g->total) {
        /* the last cycle (and any call after it): the exact terminal state */
        for (unsigned i = 0; i < na; i++)
            pos_mm[i] = g->origin_mm[i] + mv->axis[i].distance_mm;
        if (g->k < g->total)
            g->k++;
        return false;
    }
    uint32_t n;
    uint8_t shape;
    phase_of(mv, g->phase, &n, &shape);
    g->m++;
    g->k++;
    const lsm_real dt = mv->cycle_s;
    const lsm_real tau = (lsm_real)g->m * dt;
    const bool end = g->m == n;
    lsm_real bs; /* unit-jerk position basis of the shape */
    if (shape == LSM_PHASE_CONST) {
        bs = tau * tau * tau / 6;
    } else {
        const bool first = g->phase < 7;
        const lsm_real cd = first ? g->cd_acc : g->cd_dec, sd = first ? g->sd_acc : g->sd_dec;
        if (end) {
            g->c = -1; /* phi = pi exactly */
            g->s = 0;
        } else {
            const lsm_real c = g->c * cd - g->s * sd;
            g->s = g->s * cd + g->c * sd;
            g->c = c;
        }
        const lsm_real sg = shape == LSM_PHASE_RISE ? 1 : -1;
        bs = tau * tau * tau / 12 - sg * tau * g->k8 + sg * g->s * g->k16;
    }
    for (unsigned i = 0; i < na; i++) {
        const lsm_kin *st = &g->start[i];
        const lsm_real s = st->s_mm + tau * (st->v_mm_s + tau * st->a_mm_s2 / 2) + g->jerk[i] * bs;
        pos_mm[i] = g->origin_mm[i] + mv->axis[i].dir * s;
    }
    if (end)
        enter_phase(g, g->phase + 1u);
    return true;
}
