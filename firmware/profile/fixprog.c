#include "fixprog.h"

#include "lsm_math.h"

#define TWO32 4294967296.0
#define TWO30 1073741824.0
#define TWO52 4503599627370496.0
#define POS_LIMIT_COUNTS 2147483647.0

/* Rounds x * 2^32 (or 2^52) to int64; false if it does not fit. Done in double where the build has it. */
static bool to_q(double x, double scale, int64_t *out)
{
    const double y = x * scale;
    if (!(y > -9.2e18 && y < 9.2e18))
        return false;
    *out = (int64_t)(y < 0 ? y - 0.5 : y + 0.5);
    return true;
}

static bool to_q32(double x, int64_t *out)
{
    return to_q(x, TWO32, out);
}

lsm_status lsm_fixprog_compile(lsm_fixprog *out, const lsm_move *mv, const lsm_real *counts_per_mm,
                               const int64_t *start_counts)
{
    if (out == NULL || mv == NULL || counts_per_mm == NULL || start_counts == NULL)
        return LSM_E_NULL;
    for (unsigned i = 0; i < mv->n_axes; i++) {
        if (lsm_check_finite(counts_per_mm[i]) != 0 || !(counts_per_mm[i] > 0))
            return LSM_E_LIMIT;
        const double target = (double)start_counts[i] + (double)mv->axis[i].distance_mm * (double)counts_per_mm[i];
        if (!(target > -POS_LIMIT_COUNTS && target < POS_LIMIT_COUNTS) ||
            !((double)start_counts[i] > -POS_LIMIT_COUNTS && (double)start_counts[i] < POS_LIMIT_COUNTS))
            return LSM_E_RANGE;
        out->target_counts[i] = (int64_t)(target < 0 ? target - 0.5 : target + 0.5);
    }
    out->n_axes = mv->n_axes;
    out->total_cycles = lsm_move_total_cycles(mv);
    const double dt = (double)mv->cycle_s;
    lsm_phase ph[LSM_MOVE_PHASES];
    lsm_move_phases(mv, 0, ph);
    for (unsigned p = 0; p < LSM_FIX_PHASES; p++) {
        lsm_fix_phase *f = &out->phase[p];
        f->n_cycles = ph[p].n_cycles;
        f->shape = ph[p].shape;
        f->cd_q30 = 1 << 30;
        f->sd_q30 = 0;
        const bool accelerating = p != 7; /* the cruise has neither jerk nor acceleration */
        if (accelerating && f->n_cycles > LSM_FIX_MAX_RAMP_CYCLES)
            return LSM_E_RANGE;
        const double n1 = (double)f->n_cycles;
        if (f->shape != LSM_PHASE_CONST && f->n_cycles > 0) {
            f->cd_q30 = (int32_t)lrint(cos(LSM_PI / n1) * TWO30);
            f->sd_q30 = (int32_t)lrint(sin(LSM_PI / n1) * TWO30);
        }
        for (unsigned i = 0; i < mv->n_axes; i++) {
            lsm_phase pa[LSM_MOVE_PHASES];
            lsm_move_phases(mv, i, pa);
            lsm_kin st;
            lsm_move_phase_start(mv, i, p, &st);
            const double c = (double)counts_per_mm[i] * (double)mv->axis[i].dir;
            const double J = (double)pa[p].jerk_mm_s3 * c * dt * dt * dt;
            lsm_fix_axis_phase *a = &out->ax[p][i];
            const double p0 = (double)start_counts[i] + (double)st.s_mm * c;
            bool ok = to_q32(p0, &a->p0_q32) && to_q32((double)st.v_mm_s * c * dt, &a->v0_q32) &&
                      to_q32((double)st.a_mm_s2 * c * dt * dt / 2, &a->a0h_q32);
            if (f->shape == LSM_PHASE_CONST) {
                ok = ok && to_q(J / 6, TWO52, &a->j3_q52);
                a->jk8_q32 = a->jk16_q32 = 0;
            } else {
                ok = ok && to_q(J / 12, TWO52, &a->j3_q52) &&
                     to_q32(J * n1 * n1 / (2 * LSM_PI * LSM_PI), &a->jk8_q32) &&
                     to_q32(J * n1 * n1 * n1 / (2 * LSM_PI * LSM_PI * LSM_PI), &a->jk16_q32);
            }
            if (!ok)
                return LSM_E_RANGE;
        }
    }
    return LSM_OK;
}
