/* fixstep.c: integers only (no float, no libm): see fixstep.h. */
#include "fixstep.h"

#include <stddef.h>

/* Wrapping multiply: exact modulo 2^64 (the final position fits, so the sum is exact). */
static inline int64_t wmul(int64_t a, int64_t b)
{
    return (int64_t)((uint64_t)a * (uint64_t)b);
}

/* (a * s) >> 30 for a in Q32 (any int64) and s in Q30 (|s| <= 2^30), without 128-bit arithmetic. */
static inline int64_t mul_q30(int64_t a, int32_t s)
{
    const int64_t hi = a >> 32;                         /* signed high word */
    const int64_t lo = (int64_t)(uint32_t)a;            /* unsigned low word, < 2^32 */
    return wmul(hi * 4, s) + ((lo * (int64_t)s) >> 30); /* hi*s*2^32/2^30 + lo*s/2^30 */
}

/* (a * b) >> 20 with a 128-bit intermediate built from 32x32 -> 64 products (b >= 0, b < 2^63). */
static int64_t mul_shr20(int64_t a, uint64_t b)
{
    const bool neg = a < 0;
    const uint64_t ua = neg ? (uint64_t)0 - (uint64_t)a : (uint64_t)a;
    const uint64_t a0 = ua & 0xFFFFFFFFu, a1 = ua >> 32, b0 = b & 0xFFFFFFFFu, b1 = b >> 32;
    const uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    const uint64_t mid = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
    const uint64_t lo = (p00 & 0xFFFFFFFFu) | (mid << 32);
    const uint64_t hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
    const uint64_t r = (lo >> 20) | (hi << 44);
    return neg ? -(int64_t)r : (int64_t)r;
}

static inline int32_t rot_q30(int64_t x)
{
    return (int32_t)((x + (1 << 29)) >> 30);
}

static void enter(lsm_fixstep *g, unsigned p)
{
    for (; p < LSM_FIX_PHASES && g->prog->phase[p].n_cycles == 0; p++) {
    }
    g->phase = (uint8_t)p;
    g->m = 0;
    g->c_q30 = 1 << 30;
    g->s_q30 = 0;
}

lsm_status lsm_fixstep_init(lsm_fixstep *g, const lsm_fixprog *prog)
{
    if (g == NULL || prog == NULL)
        return LSM_E_NULL;
    if (prog->n_axes < 1 || prog->n_axes > LSM_MAX_AXES)
        return LSM_E_ARG;
    g->prog = prog;
    g->k = 0;
    enter(g, 0);
    return LSM_OK;
}

bool lsm_fixstep_next(lsm_fixstep *g, int64_t *pos_counts)
{
    const lsm_fixprog *pr = g->prog;
    const unsigned na = pr->n_axes;
    if (g->k + 1 >= pr->total_cycles || g->phase >= LSM_FIX_PHASES) {
        for (unsigned i = 0; i < na; i++)
            pos_counts[i] = pr->target_counts[i];
        if (g->k < pr->total_cycles)
            g->k++;
        return false;
    }
    const lsm_fix_phase *ph = &pr->phase[g->phase];
    g->m++;
    g->k++;
    const int64_t m = (int64_t)g->m;
    const int64_t m2 = m * m, m3 = m2 * m;
    if (ph->shape != 1) {
        if (g->m == ph->n_cycles) {
            g->c_q30 = -(1 << 30); /* phi = pi exactly */
            g->s_q30 = 0;
        } else {
            const int64_t c = g->c_q30, s = g->s_q30;
            g->c_q30 = rot_q30(c * ph->cd_q30 - s * ph->sd_q30);
            g->s_q30 = rot_q30(s * ph->cd_q30 + c * ph->sd_q30);
        }
    }
    const lsm_fix_axis_phase *ap = pr->ax[g->phase];
    for (unsigned i = 0; i < na; i++) {
        const lsm_fix_axis_phase *a = &ap[i];
        int64_t p = a->p0_q32 + wmul(a->v0_q32, m) + wmul(a->a0h_q32, m2) + mul_shr20(a->j3_q52, (uint64_t)m3);
        if (ph->shape == 0)
            p += -wmul(a->jk8_q32, m) + mul_q30(a->jk16_q32, g->s_q30);
        else if (ph->shape == 2)
            p += wmul(a->jk8_q32, m) - mul_q30(a->jk16_q32, g->s_q30);
        pos_counts[i] = (p + ((int64_t)1 << 31)) >> 32; /* round to the nearest count */
    }
    if (g->m == ph->n_cycles)
        enter(g, g->phase + 1u);
    return true;
}
