/*
 * pp_check.h: the per-cycle limit checks of a PP axis's demand (tests/motion/test_pp_midramp.c,
 * tests/motion/test_pp_props.c). Header-only, for tests. Feed every cycle's demand state (s, v, a, j) in order;
 * the first call only records.
 *
 *   own state      |v| <= V, |a| <= A, |j| <= J; |v_k - v_k-1| <= A dt and |a_k - a_k-1| <= J dt (no jump);
 *                  with a snap limit S (profile type 1; 0: none, type 0): |j_k - j_k-1| <= S dt;
 *   backward       of the positions, order n = 1..4 (v, a, j, snap; order 4 only with S): |D_n p / dt^n| <= L_n.
 *   differences    The n-th backward difference over dt^n is the mean of the n-th derivative over the last n cycles
 *                  weighted by a B-spline (a kernel >= 0 of integral 1), so a demand within its limits never
 *                  exceeds them. The float build checks order 1 only (PP_CHECK_DIFF_ORDER): the rounding of float
 *                  positions, 2^n ulp(|p|) / dt^n, is above the limits from order 2 on at 1 ms.
 * Noise bounds, no tolerance: the own state PP_NOISE_ULPS ulps of the real type relative to each limit's scale (the
 * closed-form states carry a few roundings of quantities of that size); a difference of order n: float_noise.h's
 * bound, 2^n K u / dt^n, u the ulp unit of the largest |position| seen (each position is within K u of the exact
 * curve; K = FLOAT_NOISE_POS_ULPS, derived and measured there, the same bound as the path fuzz targets').
 * The same bounds hold for every cycle, in a planned move or not, in both builds: in a move's cruise the velocity of
 * the demand is the planned cruise feed, which the ramps' evaluated ends meet within a few ulps (firmware/profile/
 * move.c, eval_phase), and the rounding of the float positions of the two ramp ends stays in the positions (within
 * the first difference's noise), not in a step of the velocity.
 */
#ifndef PP_CHECK_H
#define PP_CHECK_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "float_noise.h"
#include "lsm_config.h"
#include "scurve.h"

#define PP_NOISE_ULPS 8.0
#define PP_POS_ULPS FLOAT_NOISE_POS_ULPS /* K of float_noise.h (the name the motion tests' comments use) */
#if LSM_REAL_IS_FLOAT
#define PP_ULP_REL ((double)FLT_EPSILON)
#define PP_CHECK_DIFF_ORDER 1
#else
#define PP_ULP_REL DBL_EPSILON
#define PP_CHECK_DIFF_ORDER 4
#endif

typedef struct pp_checker {
    double dt, V, A, J, S; /* S = 0: no snap check (profile type 0) */
    double p[5];           /* the last positions, p[0] the newest */
    unsigned np;           /* positions held (<= 5) */
    lsm_kin prev;
    double pmax;
    unsigned long n;  /* cycles checked */
    double worst[10]; /* worst ratio to the allowed value: v a j snap dv da, then D1 .. D4 */
    bool bad;
    char msg[320];
} pp_checker;

static inline void pp_check_init(pp_checker *c, double dt, double V, double A, double J, double S)
{
    memset(c, 0, sizeof *c);
    c->dt = dt;
    c->V = V;
    c->A = A;
    c->J = J;
    c->S = S;
}

/* The limits change (a new set-point with other limits): the checker keeps its history. */
static inline void pp_check_limits(pp_checker *c, double V, double A, double J, double S)
{
    c->V = V;
    c->A = A;
    c->J = J;
    c->S = S;
}

static inline void pp_check_note(pp_checker *c, int slot, double x, double allowed, const char *what)
{
    const double r = fabs(x) / allowed;
    if (r > c->worst[slot])
        c->worst[slot] = r;
    if (r > 1 && !c->bad) {
        c->bad = true;
        snprintf(c->msg, sizeof c->msg,
                 "cycle %lu: %s %.9g exceeds %.9g (ratio %.9g); state s %.12g v %.9g a %.9g j %.9g", c->n, what, x,
                 allowed, r, c->p[0], (double)c->prev.v_mm_s, (double)c->prev.a_mm_s2, (double)c->prev.j_mm_s3);
    }
}

/* The backward differences of order 1..PP_CHECK_DIFF_ORDER of the positions held. */
static inline void pp_check_diffs(pp_checker *c)
{
    const double L[4] = {c->V, c->A, c->J, c->S};
    static const char *names[4] = {"D1 p/dt (v)", "D2 p/dt^2 (a)", "D3 p/dt^3 (j)", "D4 p/dt^4 (snap)"};
    double d[5];
    for (unsigned i = 0; i < c->np; i++)
        d[i] = c->p[i];
    double dtn = 1;
    for (unsigned n = 1; n <= (unsigned)PP_CHECK_DIFF_ORDER && n < c->np; n++) {
        for (unsigned i = 0; i + n < c->np; i++)
            d[i] = d[i] - d[i + 1]; /* order n at d[0..np-n) */
        dtn *= c->dt;
        if (n == 4 && !(c->S > 0))
            break;
        const double noise = float_noise_diff(c->pmax, (int)n, c->dt);
        pp_check_note(c, 5 + (int)n, d[0] / dtn, L[n - 1] + noise, names[n - 1]);
    }
}

static inline void pp_check_kin(pp_checker *c, const lsm_kin *k)
{
    const double nz = PP_NOISE_ULPS * PP_ULP_REL;
    for (unsigned i = 4; i > 0; i--)
        c->p[i] = c->p[i - 1];
    c->p[0] = (double)k->s_mm;
    if (c->np < 5u)
        c->np++;
    if (fabs(c->p[0]) > c->pmax)
        c->pmax = fabs(c->p[0]);
    if (c->n > 0) {
        const lsm_kin *p = &c->prev;
        pp_check_note(c, 0, k->v_mm_s, c->V * (1 + nz), "v");
        pp_check_note(c, 1, k->a_mm_s2, c->A * (1 + nz), "a");
        pp_check_note(c, 2, k->j_mm_s3, c->J * (1 + nz), "j");
        if (c->S > 0)
            pp_check_note(c, 3, k->j_mm_s3 - p->j_mm_s3, c->S * c->dt + nz * c->J, "dj/dt (snap) dt");
        pp_check_note(c, 4, k->v_mm_s - p->v_mm_s, c->A * c->dt + nz * c->V, "dv");
        pp_check_note(c, 5, k->a_mm_s2 - p->a_mm_s2, c->J * c->dt + nz * c->A, "da");
        pp_check_diffs(c);
    }
    c->prev = *k;
    c->n++;
}

#endif
