/*
 * clothoid.h: planar clothoid segments (Euler spirals), Fresnel integrals, incremental stepping,
 * and the clothoid-to-line fit of Shahzadeh et al. section IV (lsm_clothoid_*).
 *
 * Model (paper eqs 1, 2, 11, 12). A segment starts at (x0, y0) with tangent angle theta0 and
 * curvature kappa0; its curvature changes linearly with arc length s at the sharpness c:
 *     kappa(s) = kappa0 + c s                                     (1)
 *     theta(s) = theta0 + kappa0 s + c s^2 / 2                    (2)
 *     x(s) = x0 + int_0^s cos theta(t) dt,  y(s) = y0 + int_0^s sin theta(t) dt   (11, 12)
 * Lines (kappa0 = c = 0) and circular arcs (c = 0) are special cases. Signs: theta counter-clockwise
 * from +x, kappa > 0 turns left. The centripetal jerk on a clothoid is c v^3 (eq 6), so the feed
 * limits are f1 = sqrt(a_max / kappa_max) (eq 7) and f2 = cbrt(j_max / c_max) (eq 8).
 * Units: mm, rad, 1/mm (curvature), 1/mm^2 (sharpness).
 *
 * Evaluation (lsm_clothoid_integral). With Phi = |kappa0| s + |c| s^2 / 2 (a bound on the turning):
 *  - c == 0: closed form s sinc(kappa0 s / 2) e^{i(theta0 + kappa0 s / 2)} (no cancellation);
 *  - Phi <= LSM_CLOTHOID_SERIES_PHASE_RAD: the segment is cut into pieces that turn at most 1 rad;
 *    on each, e^{i psi(u)} with psi(u) = a u + b u^2 / 2 is summed as a Taylor series whose
 *    coefficients follow from psi' (g_{n+1} = i (a g_n + b g_{n-1}) / (n + 1)); the rotation from
 *    piece to piece is the series' own end value, so only the first piece needs sin/cos;
 *  - otherwise the square is completed and the integral is a difference of Fresnel integrals,
 *    arranged so that the large constant phase theta0 - kappa0^2 / (2c) cancels analytically (in
 *    double the phases that remain are carried with fma error terms and reduced modulo 2 pi).
 * Normalised Fresnel integrals C(x) = int_0^x cos(pi t^2 / 2), S(x) likewise with sin: power series
 * for |x| <= 1.6, continued fraction of erfc((1 - i) sqrt(pi) x / 2) (modified Lentz) above, with
 * the phase pi x^2 / 2 reduced exactly (split of x). Double: about 1e-15 relative (measured against
 * mpmath, tests/py/test_fresnel.py); float: the same code, terminated at float epsilon.
 *
 * Incremental stepping (lsm_clothoid_step): the state (x, y, tangent as a unit vector, kappa) is
 * advanced by ds with the local Taylor series of e^{i psi(u)}, psi(u) = kappa ds u + c ds^2 u^2 / 2, with
 * no trigonometry and no re-integration from 0. The usual step is small (per-cycle steps turn |kappa ds|
 * < 0.15 rad in the contour program): for |psi'(1/2)| <= LSM_CLOTHOID_FAST_PHI_RAD and |c ds^2| <=
 * LSM_CLOTHOID_FAST_B_RAD the series is a fixed polynomial about the step's midpoint (no loop, no test per
 * term, no division; lsm_clothoid_local_fast), truncated below eps/16 by a bound on the region. Larger
 * steps are cut into 2-4 such sub-steps (float), or take the general series (lsm_clothoid_local, summed to
 * eps) on sub-steps that turn at most 1 rad. The sums of position and arc length are compensated (Kahan: in
 * float, s += ds alone would lose 1e-2 mm over 1e4 steps of 0.01 mm), the tangent is renormalised every
 * step (one Newton step, 1.5 - |t|^2 / 2) and every `anchor_every` steps the state is re-anchored on an
 * evaluation from the segment's start: in small-step pieces (float, up to 64 pieces: |kappa0| s + |c| s^2
 * up to 25.6 rad), else the exact evaluation. The start state (lsm_clothoid_stepper_init) is evaluated the same
 * way: just after the segment's start, one small step. The end of the segment is landed on exactly (the
 * state of lsm_clothoid_eval, bit for bit). Error: the truncation is below eps/16, so what is left is
 * rounding: mainly the direction of the tangent, which random-walks by about eps per step, so that the
 * position drifts by roughly (distance since the anchor) * sqrt(steps) * eps (measured in
 * tests/path/test_clothoid.c and reported in docs/clothoid.md). Cost on a Cortex-M4F (float, -Os, instructions):
 * ~155 per step whatever |kappa ds| up to 0.4 rad (about 350 at 0.5 rad), ~170 with re-anchoring every 64
 * steps; starting at a block's entry (lsm_clothoid_init + lsm_clothoid_stepper_init) ~340; a direct
 * evaluation ~1 050.
 *
 * Fit (paper section IV, eqs 13-16): from a start state, find (c, s) so that the end point lies on
 * the line A x + B y + C = 0 and the clothoid meets it at a right angle. Eq 16 (tan theta * m = -1)
 * is singular for horizontal and vertical lines, so the line is used in point-normal form,
 * n . (P(s) - Q) = 0, and the angle condition is theta(s) = direction of the normal that points
 * across the line (the branch within +-pi of theta0). Newton on (c, s) with a damped step, started
 * from a bracket of the reduced one-variable problem (c eliminated with the angle condition) found
 * by a geometric scan of s.
 * Domain: a finite start state and a line (normal not zero); the scan looks for the first crossing with
 * length from dist / 4 to 4096 dist (dist: the start's distance to the line) and turning |kappa0| s +
 * |c| s^2 / 2 up to LSM_CLOTHOID_FIT_MAX_PHASE_RAD. Outside it (no crossing there) the fit refuses with
 * LSM_E_FIT_NO_SOLUTION. Inside it the fit converges: where Newton stalls (near a fold, where the Jacobian
 * of (c, s) is nearly singular; 1 fit in ~12 500 of the randomized test did), the reduced residual is solved
 * in the scan's bracket by regula falsi (Illinois) with bisection safeguards, which narrows any bracket
 * to rounding within LSM_CLOTHOID_FIT_BRACKET_MAX_ITER steps.
 */
#ifndef LSM_CLOTHOID_H
#define LSM_CLOTHOID_H

#include "lsm_config.h"
#include "status.h"

/* Compile-time settings (LSM_CLOTHOID_SERIES_PHASE_RAD, LSM_CLOTHOID_MAX_TERMS): lsm_config.h. */
/* The small-step region of lsm_clothoid_local_fast (and of the stepper's usual step): |a + b/2| (the turning of
 * the step at its midpoint) and |b| (twice the turning that the sharpness adds), rad. Inside, a fixed polynomial is
 * accurate to better than eps/16 (float: 5.1e-9 at the corners, double: 4.9e-18; clothoid.c, docs/clothoid.md),
 * so the double region is smaller. Not meant to be overridden: the bounds belong to the polynomial. */
#if LSM_REAL_IS_FLOAT
#define LSM_CLOTHOID_FAST_PHI_RAD 0.4
#define LSM_CLOTHOID_FAST_B_RAD 0.16
#else
#define LSM_CLOTHOID_FAST_PHI_RAD 0.02
#define LSM_CLOTHOID_FAST_B_RAD 0.001
#endif
/* Compile-time settings (LSM_CLOTHOID_FIT_MAX_ITER, LSM_CLOTHOID_FIT_MAX_PHASE_RAD,
 * LSM_CLOTHOID_FIT_BRACKET_MAX_ITER): lsm_config.h. */

/* A planar clothoid segment. */
typedef struct lsm_clothoid {
    lsm_real x0_mm, y0_mm;  /* start point */
    lsm_real theta0_rad;    /* start tangent angle */
    lsm_real kappa0_per_mm; /* start curvature (signed) */
    lsm_real c_per_mm2;     /* sharpness dkappa/ds */
    lsm_real len_mm;        /* length L >= 0 */
} lsm_clothoid;

/* A point on a clothoid. */
typedef struct lsm_clothoid_state {
    lsm_real x_mm, y_mm;
    lsm_real theta_rad;
    lsm_real kappa_per_mm;
} lsm_clothoid_state;

/* Validates and stores a segment. Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF, LSM_E_RANGE (len < 0). */
lsm_status lsm_clothoid_init(lsm_clothoid *cl, lsm_real x0_mm, lsm_real y0_mm, lsm_real theta0_rad,
                             lsm_real kappa0_per_mm, lsm_real c_per_mm2, lsm_real len_mm);

/* State at arc length s (any finite s, also outside [0, len]: the clothoid extended). Errors:
 * LSM_E_NULL, LSM_E_NAN, LSM_E_INF (s or a result not finite). */
lsm_status lsm_clothoid_eval(const lsm_clothoid *cl, lsm_real s_mm, lsm_clothoid_state *out);

/* The displacement X + iY = int_0^s e^{i(theta0 + kappa0 t + c t^2/2)} dt. No validation: finite
 * inputs give finite results; callers validate. Negative s integrates backwards. */
void lsm_clothoid_integral(lsm_real theta0_rad, lsm_real kappa0_per_mm, lsm_real c_per_mm2, lsm_real s_mm,
                           lsm_real *dx_mm, lsm_real *dy_mm);

/* Normalised Fresnel integrals C(x) = int_0^x cos(pi t^2/2) dt and S(x) (sin); odd in x. */
void lsm_clothoid_fresnel(lsm_real x, lsm_real *c, lsm_real *s);

/* Taylor kernel shared with the corner module. For psi(u) = a u + b u^2/2 on [0, 1], with the
 * coefficients g_n of e^{i psi(u)} = sum g_n u^n (g_0 = 1, g_{n+1} = i (a g_n + b g_{n-1}) / (n + 1)):
 * the end value e^{i psi(1)} and the moments M_j = int_0^1 u^j e^{i psi(u)} du, j < nmom
 * (1 <= nmom <= 3). The piece of a clothoid that starts with curvature k and sharpness c over length h
 * has a = k h, b = c h^2, and int_0^h t^j e^{i psi} dt = h^{j+1} M_j. The sum stops when two
 * consecutive terms are below eps / 2 (rel = false: absolute accuracy, what positions need) or below
 * eps (|a| + |b|) / 32 (rel = true: also the small imaginary parts of short pieces to eps relative;
 * the Fresnel-type evaluation uses this). Meant for |a| + |b|/2 up to ~3 (about 24 terms in double,
 * 14 in float; at most LSM_CLOTHOID_MAX_TERMS). */
typedef struct lsm_clothoid_series {
    int n;                 /* number of terms used */
    lsm_real er, ei;       /* e^{i psi(1)} */
    lsm_real mr[3], mi[3]; /* M_0 .. M_2 (those at and above nmom are 0) */
} lsm_clothoid_series;
void lsm_clothoid_series_eval(lsm_real a, lsm_real b, int nmom, bool rel, lsm_clothoid_series *out);

/* X + iY = int_0^1 e^{i z u^2} du = sum_k (i z)^k / (k! (2k + 1)), for |z| up to ~4 (the Fresnel integrals below 1.6,
 * E(x) = x (X + iY) at z = pi x^2 / 2; the corner module's symmetric pair at z = delta / 2). The sum stops when a
 * term is below eps / 4 of the smaller of |X| and |Y|. */
void lsm_clothoid_unit_fresnel(lsm_real z, lsm_real *x, lsm_real *y);

/* The same kernel without moments beyond M_0, in registers, to absolute epsilon: E = e^{i psi(1)}
 * and M = int_0^1 e^{i psi(u)} du. A step of length w from a point with unit tangent T and curvature
 * k along sharpness c moves by w T M and turns T into T E (a = k w, b = c w^2). Used by the stepper and
 * the corner module; meant for |a| + |b| <= ~1 (a few terms). */
void lsm_clothoid_local(lsm_real a, lsm_real b, lsm_real *er, lsm_real *ei, lsm_real *mr, lsm_real *mi);

/* The same E and M, cheaper for small steps: for |a + b/2| <= LSM_CLOTHOID_FAST_PHI_RAD and
 * |b| <= LSM_CLOTHOID_FAST_B_RAD a fixed polynomial with no loop and no division (about 50 flops; truncation below
 * eps/16, the rest is rounding, a few eps), otherwise lsm_clothoid_local. Equal to lsm_clothoid_local to a few eps,
 * not bit for bit. The stepper uses it. */
void lsm_clothoid_local_fast(lsm_real a, lsm_real b, lsm_real *er, lsm_real *ei, lsm_real *mr, lsm_real *mi);

/* Incremental evaluation for the per-cycle interpolator (see the header comment). */
typedef struct lsm_clothoid_stepper {
    lsm_clothoid seg;
    lsm_real s_mm;         /* arc length reached, in [0, len] */
    lsm_real cs_mm;        /* compensation term of the arc-length sum (Kahan) */
    lsm_real x_mm, y_mm;   /* position */
    lsm_real cx_mm, cy_mm; /* compensation terms of the position sums (Kahan) */
    lsm_real tx, ty;       /* unit tangent (cos theta, sin theta) */
    lsm_real kappa_per_mm; /* curvature */
    uint32_t since_anchor; /* steps since the last exact evaluation */
    uint32_t anchor_every; /* re-anchor every this many steps (0: never) */
} lsm_clothoid_stepper;

/* Start at arc length s0 (0 <= s0 <= len), evaluated from the segment's start (see the header comment; at s0 = len
 * exactly the state of lsm_clothoid_eval). Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF, LSM_E_RANGE. */
lsm_status lsm_clothoid_stepper_init(lsm_clothoid_stepper *st, const lsm_clothoid *seg, lsm_real s0_mm,
                                     uint32_t anchor_every);
/* Advance by ds >= 0 (clamped at the end of the segment); out may be NULL (the interpolator reads st->x_mm and
 * st->y_mm). The angle reported is theta0 + kappa0 s + c s^2/2 (exact); x, y and the tangent vector come from
 * the stepping.
 * Errors: LSM_E_NULL, LSM_E_NAN / LSM_E_INF (ds), LSM_E_NEG_FEED (ds < 0). */
lsm_status lsm_clothoid_step(lsm_clothoid_stepper *st, lsm_real ds_mm, lsm_clothoid_state *out);

/* Fit result. */
typedef struct lsm_clothoid_fit_result {
    lsm_real c_per_mm2;     /* sharpness found */
    lsm_real s_mm;          /* length found (> 0, or 0 if the start already is on the line, normal to it) */
    lsm_clothoid_state end; /* end state (eqs 1, 2, 11, 12) */
    int iterations;         /* Newton iterations on (c, s) */
    int bracket_steps;      /* steps of the bracketed fallback (0 unless Newton stalled) */
    int evaluations;        /* clothoid evaluations, scan included */
    lsm_real residual_mm;   /* distance of the end point from the line */
    lsm_real residual_rad;  /* angle between the end tangent and the line normal */
} lsm_clothoid_fit_result;

/* Fit to the line a x + b y + c = 0 (general form; vertical and horizontal lines are fine).
 * Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF, LSM_E_FIT_LINE (a = b = 0), LSM_E_FIT_ON_LINE (start on the
 * line and not normal to it), LSM_E_FIT_NO_SOLUTION (no crossing found with turning below
 * LSM_CLOTHOID_FIT_MAX_PHASE_RAD and length below 4096 times the start's distance to the line),
 * LSM_E_NOT_CONVERGED (not expected on the domain above: the fallback's cap; kept as a guard). */
lsm_status lsm_clothoid_fit_line(const lsm_clothoid_state *start, lsm_real a, lsm_real b, lsm_real c,
                                 lsm_clothoid_fit_result *out);
/* The same with the line through (qx, qy) with normal (nx, ny) (need not be unit length). */
lsm_status lsm_clothoid_fit_pn(const lsm_clothoid_state *start, lsm_real qx_mm, lsm_real qy_mm, lsm_real nx,
                               lsm_real ny, lsm_clothoid_fit_result *out);

#endif /* LSM_CLOTHOID_H */
