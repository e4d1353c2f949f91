/* clothoid.c: planar clothoids, Fresnel integrals, stepping and the section-IV fit (see clothoid.h). */
#include "clothoid.h"

#include "lsm_math.h"

#if LSM_REAL_IS_FLOAT
#define CL_SPLIT 4097.0f /* 2^12 + 1: splits a float into two halves whose squares are exact */
#define CL_TINY 1.0e-30f
#define CL_HUGE_X 1.0e4f /* above: x F(x) = i / (pi x) to float precision */
#else
#define CL_SPLIT 134217729.0 /* 2^27 + 1 */
#define CL_TINY 1.0e-300
#define CL_HUGE_X 1.0e8
#endif

#define CL_PI ((lsm_real)LSM_PI)
#define CL_SERIES_X LSM_R(1.6) /* Fresnel: power series below, continued fraction above */

/* 1 / (n + 1) for n = 0 .. LSM_CLOTHOID_MAX_TERMS + 3 (avoids divisions in the series loops). */
#define CL_INV(n) ((lsm_real)(1.0 / (n)))
static const lsm_real k_inv[] = {CL_INV(1),  CL_INV(2),  CL_INV(3),  CL_INV(4),  CL_INV(5),  CL_INV(6),  CL_INV(7),
                                 CL_INV(8),  CL_INV(9),  CL_INV(10), CL_INV(11), CL_INV(12), CL_INV(13), CL_INV(14),
                                 CL_INV(15), CL_INV(16), CL_INV(17), CL_INV(18), CL_INV(19), CL_INV(20), CL_INV(21),
                                 CL_INV(22), CL_INV(23), CL_INV(24), CL_INV(25), CL_INV(26), CL_INV(27), CL_INV(28),
                                 CL_INV(29), CL_INV(30), CL_INV(31), CL_INV(32), CL_INV(33), CL_INV(34), CL_INV(35),
                                 CL_INV(36), CL_INV(37), CL_INV(38), CL_INV(39), CL_INV(40), CL_INV(41), CL_INV(42),
                                 CL_INV(43), CL_INV(44)};
_Static_assert(sizeof k_inv / sizeof k_inv[0] >= LSM_CLOTHOID_MAX_TERMS + 4, "k_inv too short");

static inline lsm_real cl_abs1(lsm_real r, lsm_real i)
{
    return lsm_fabs(r) + lsm_fabs(i);
}

/* Complex 1 / (br + i bi) without overflow (Smith). */
static void cl_cinv(lsm_real br, lsm_real bi, lsm_real *rr, lsm_real *ri)
{
    if (lsm_fabs(br) >= lsm_fabs(bi)) {
        lsm_real q = bi / br, d = br + bi * q;
        *rr = LSM_R(1.0) / d;
        *ri = -q / d;
    } else {
        lsm_real q = br / bi, d = br * q + bi;
        *rr = q / d;
        *ri = LSM_R(-1.0) / d;
    }
}

/* ---------------------------------------------------------------- Taylor kernel */

/* Stopping tolerance for a piece with psi(u) = a u + b u^2/2: the imaginary parts are about
 * (|a| + |b|)/8 in size for small arguments, so the tail must be below eps times that. */
static inline lsm_real cl_series_tol(lsm_real a, lsm_real b)
{
    lsm_real m = LSM_R(0.125) * (lsm_fabs(a) + lsm_fabs(b));
    return LSM_REAL_EPS * LSM_R(0.25) * (m < LSM_R(1.0) ? m : LSM_R(1.0));
}

void lsm_clothoid_series_eval(lsm_real a, lsm_real b, int nmom, bool rel, lsm_clothoid_series *o)
{
    const lsm_real tol = rel ? cl_series_tol(a, b) : LSM_R(0.5) * LSM_REAL_EPS;
    const lsm_real grow = lsm_fabs(a) + lsm_fabs(b);
    /* g_{n-1} = (pr, pi), g_n = (gr, gi); sums in locals */
    lsm_real pr = LSM_R(1.0), pi = LSM_R(0.0), gr = LSM_R(0.0), gi = a;
    lsm_real er = LSM_R(1.0), ei = a;
    lsm_real m0r = LSM_R(1.0), m0i = LSM_R(0.5) * a;
    lsm_real m1r = LSM_R(0.5), m1i = a * k_inv[2];
    lsm_real m2r = k_inv[2], m2i = LSM_R(0.25) * a;
    int n = 1;
    while (n + 1 < LSM_CLOTHOID_MAX_TERMS) {
        const lsm_real inv = k_inv[n]; /* 1 / (n + 1) */
        const lsm_real tr = a * gr + b * pr, ti = a * gi + b * pi;
        const lsm_real nr = -ti * inv, ni = tr * inv; /* g_{n+1} = i (a g_n + b g_{n-1}) / (n+1) */
        n++;
        pr = gr;
        pi = gi;
        gr = nr;
        gi = ni;
        er += nr;
        ei += ni;
        const lsm_real i0 = k_inv[n]; /* 1 / (n + 1) */
        m0r += nr * i0;
        m0i += ni * i0;
        if (nmom > 1) {
            const lsm_real i1 = k_inv[n + 1], i2 = k_inv[n + 2];
            m1r += nr * i1;
            m1i += ni * i1;
            m2r += nr * i2;
            m2i += ni * i2;
        }
        if ((lsm_real)(n + 1) > grow && cl_abs1(gr, gi) + cl_abs1(pr, pi) <= tol)
            break;
    }
    o->n = n + 1;
    o->er = er;
    o->ei = ei;
    o->mr[0] = m0r;
    o->mi[0] = m0i;
    o->mr[1] = nmom > 1 ? m1r : LSM_R(0.0);
    o->mi[1] = nmom > 1 ? m1i : LSM_R(0.0);
    o->mr[2] = nmom > 2 ? m2r : LSM_R(0.0);
    o->mi[2] = nmom > 2 ? m2i : LSM_R(0.0);
}

#if defined(__GNUC__)
#define CL_INLINE static inline __attribute__((always_inline))
#define CL_NOINLINE static __attribute__((noinline))
#else
#define CL_INLINE static inline
#define CL_NOINLINE static
#endif

/* Piecewise series over [0, s] (s > 0): moments int_0^s t^j e^{i theta(t)} dt, j < nmom, in absolute
 * orientation; each piece turns at most 1 rad. Returns the number of pieces. Inlined into two functions: the
 * position only (nmom = 1: lsm_clothoid_integral, the stepper's anchor) and the moments of the fit's Jacobian, so
 * that an image without the fit does not carry the higher moments' code. */
CL_INLINE int cl_pieces_body(lsm_real th0, lsm_real k0, lsm_real c, lsm_real s, int nmom, lsm_real mr[3],
                             lsm_real mi[3], lsm_real rot[2])
{
    lsm_real ph = lsm_fabs(k0) * s + lsm_fabs(c) * s * s;
    int m = 1;
    if (ph > LSM_R(1.0))
        m = (int)lsm_ceil(ph);
    const lsm_real h = s / (lsm_real)m;
    lsm_real rr, ri;
    lsm_sincos(th0, &ri, &rr);
    for (int j = 0; j < 3; j++)
        mr[j] = mi[j] = LSM_R(0.0);
    lsm_clothoid_series se;
    for (int p = 0; p < m; p++) {
        const lsm_real tj = h * (lsm_real)p;
        const lsm_real kj = k0 + c * tj;
        lsm_clothoid_series_eval(kj * h, c * h * h, nmom, true, &se);
        /* local moments (w = t - tj): P0 = h M0, P1 = h^2 M1, P2 = h^3 M2 */
        lsm_real p0r = h * se.mr[0], p0i = h * se.mi[0];
        mr[0] += rr * p0r - ri * p0i;
        mi[0] += rr * p0i + ri * p0r;
        if (nmom > 1) {
            lsm_real p1r = h * h * se.mr[1], p1i = h * h * se.mi[1];
            lsm_real q1r = tj * p0r + p1r, q1i = tj * p0i + p1i;
            mr[1] += rr * q1r - ri * q1i;
            mi[1] += rr * q1i + ri * q1r;
            if (nmom > 2) {
                lsm_real p2r = h * h * h * se.mr[2], p2i = h * h * h * se.mi[2];
                lsm_real q2r = tj * tj * p0r + LSM_R(2.0) * tj * p1r + p2r;
                lsm_real q2i = tj * tj * p0i + LSM_R(2.0) * tj * p1i + p2i;
                mr[2] += rr * q2r - ri * q2i;
                mi[2] += rr * q2i + ri * q2r;
            }
        }
        lsm_real nr = rr * se.er - ri * se.ei;
        ri = rr * se.ei + ri * se.er;
        rr = nr;
    }
    if (rot != NULL) { /* e^{i theta(s)}: the unit tangent at s */
        rot[0] = rr;
        rot[1] = ri;
    }
    return m;
}

/* The position int_0^s e^{i theta(t)} dt (cl_pieces_body with nmom = 1) and, if rot != NULL, e^{i theta(s)}. */
CL_NOINLINE void cl_pieces_pos(lsm_real th0, lsm_real k0, lsm_real c, lsm_real s, lsm_real *dx, lsm_real *dy,
                               lsm_real rot[2])
{
    lsm_real mr[3], mi[3];
    (void)cl_pieces_body(th0, k0, c, s, 1, mr, mi, rot);
    *dx = mr[0];
    *dy = mi[0];
}

/* The moments j < nmom (the fit). */
CL_NOINLINE void cl_pieces(lsm_real th0, lsm_real k0, lsm_real c, lsm_real s, int nmom, lsm_real mr[3], lsm_real mi[3])
{
    (void)cl_pieces_body(th0, k0, c, s, nmom, mr, mi, NULL);
}

/* ---------------------------------------------------------------- Fresnel integrals */

void lsm_clothoid_unit_fresnel(lsm_real z, lsm_real *x, lsm_real *y)
{
    lsm_real tr = LSM_R(1.0), ti = LSM_R(0.0);
    lsm_real sr = LSM_R(1.0), si = LSM_R(0.0);
    for (int k = 0; k < 60; k++) {
        const lsm_real f = z / (lsm_real)(k + 1);
        const lsm_real nr = -ti * f, ni = tr * f;
        tr = nr;
        ti = ni;
        const lsm_real d = LSM_R(1.0) / (lsm_real)(2 * k + 3);
        sr += tr * d;
        si += ti * d;
        const lsm_real smallest = lsm_fabs(si) < lsm_fabs(sr) ? lsm_fabs(si) : lsm_fabs(sr);
        if (cl_abs1(tr, ti) * d <= LSM_R(0.25) * LSM_REAL_EPS * smallest)
            break;
    }
    *x = sr;
    *y = si;
}

/* E(x) = C(x) + i S(x) for 0 <= x <= ~1.6: x * sum (i z)^k / (k! (2k + 1)), z = pi x^2 / 2. */
static void cl_fresnel_series(lsm_real x, lsm_real *c, lsm_real *s)
{
    lsm_real sr, si;
    lsm_clothoid_unit_fresnel(CL_PI * LSM_R(0.5) * x * x, &sr, &si);
    *c = x * sr;
    *s = x * si;
}

/* x F(x) = g(x) + i f(x) for x > 1.6, where E(x) = (1 + i)/2 - x F(x) e^{i pi x^2 / 2} and
 * F = 1 / (w + 1 - 1*2 / (w + 5 - 3*4 / (w + 9 - ...))), w = -i pi x^2 (the even continued fraction of
 * erfc((1 - i) sqrt(pi) x / 2)), evaluated with the modified Lentz method. */
static void cl_fresnel_aux(lsm_real x, lsm_real *gr, lsm_real *gi)
{
    if (x > CL_HUGE_X) {
        *gr = LSM_R(1.0) / (CL_PI * CL_PI * x * x * x);
        *gi = LSM_R(1.0) / (CL_PI * x);
        return;
    }
    const lsm_real wi = -CL_PI * x * x;
    lsm_real fr = LSM_R(1.0), fi = wi;         /* f = b0 */
    lsm_real cr = fr, ci = fi;                 /* C */
    lsm_real dr = LSM_R(0.0), di = LSM_R(0.0); /* D */
    for (int n = 1; n < 500; n++) {
        const lsm_real a = -(lsm_real)((2 * n - 1) * (2 * n));
        const lsm_real br = (lsm_real)(4 * n + 1), bi = wi;
        /* D = 1 / (b + a D) */
        lsm_real tr = br + a * dr, ti = bi + a * di;
        if (cl_abs1(tr, ti) < CL_TINY)
            tr = CL_TINY;
        cl_cinv(tr, ti, &dr, &di);
        /* C = b + a / C */
        lsm_real ir, ii;
        cl_cinv(cr, ci, &ir, &ii);
        cr = br + a * ir;
        ci = bi + a * ii;
        if (cl_abs1(cr, ci) < CL_TINY)
            cr = CL_TINY;
        const lsm_real er = cr * dr - ci * di, ei = cr * di + ci * dr;
        const lsm_real nr = fr * er - fi * ei;
        fi = fr * ei + fi * er;
        fr = nr;
        if (cl_abs1(er - LSM_R(1.0), ei) <= LSM_REAL_EPS)
            break;
    }
    lsm_real Fr, Fi;
    cl_cinv(fr, fi, &Fr, &Fi);
    *gr = x * Fr;
    *gi = x * Fi;
}

/* cos and sin of pi x^2 / 2, with x^2 reduced modulo 4 without rounding the large part. */
static void cl_phase_x2(lsm_real x, lsm_real *co, lsm_real *si)
{
    const lsm_real t = x * CL_SPLIT;
    const lsm_real xh = t - (t - x);
    const lsm_real xl = x - xh;
    lsm_real h2 = xh * xh; /* exact */
    h2 -= LSM_R(4.0) * lsm_floor(h2 * LSM_R(0.25));
    lsm_real m2 = LSM_R(2.0) * xh * xl;
    m2 -= LSM_R(4.0) * lsm_floor(m2 * LSM_R(0.25));
    lsm_real r = h2 + m2 + xl * xl; /* x^2 mod 4, in [0, 12) */
    r -= LSM_R(4.0) * lsm_floor(r * LSM_R(0.25));
    if (r > LSM_R(2.0))
        r -= LSM_R(4.0);
    const lsm_real ang = CL_PI * LSM_R(0.5) * r;
    lsm_sincos(ang, si, co);
}

void lsm_clothoid_fresnel(lsm_real x, lsm_real *c, lsm_real *s)
{
    const lsm_real ax = lsm_fabs(x);
    lsm_real cc, ss;
    if (ax == LSM_R(0.0)) {
        cc = ss = LSM_R(0.0);
    } else if (ax <= CL_SERIES_X) {
        cl_fresnel_series(ax, &cc, &ss);
    } else {
        lsm_real gr, gi, co, si;
        cl_fresnel_aux(ax, &gr, &gi);
        cl_phase_x2(ax, &co, &si);
        cc = LSM_R(0.5) - (gr * co - gi * si);
        ss = LSM_R(0.5) - (gr * si + gi * co);
    }
    if (x < LSM_R(0.0)) {
        cc = -cc;
        ss = -ss;
    }
    *c = cc;
    *s = ss;
}

/* ---------------------------------------------------------------- general integral */

/* For c > 0 and an endpoint with scaled curvature u = kappa / sqrt(pi c) and angle th: the part of
 * e^{i theta_v} E(u) = e^{i theta_v} A + B (see lsm_clothoid_integral). */
static void cl_fresnel_end(lsm_real u, lsm_real th, lsm_real *ar, lsm_real *ai, lsm_real *br, lsm_real *bi)
{
    const lsm_real au = lsm_fabs(u);
    const lsm_real sg = u < LSM_R(0.0) ? LSM_R(-1.0) : LSM_R(1.0);
    if (au <= CL_SERIES_X) {
        lsm_real cc, ss;
        if (au == LSM_R(0.0)) {
            cc = ss = LSM_R(0.0);
        } else {
            cl_fresnel_series(au, &cc, &ss);
        }
        *ar = sg * cc;
        *ai = sg * ss;
        *br = *bi = LSM_R(0.0);
    } else {
        lsm_real gr, gi;
        cl_fresnel_aux(au, &gr, &gi);
        lsm_real co, si;
        lsm_sincos(th, &si, &co);
        *ar = sg * LSM_R(0.5);
        *ai = sg * LSM_R(0.5);
        *br = -sg * (gr * co - gi * si);
        *bi = -sg * (gr * si + gi * co);
    }
}

#if LSM_REAL_IS_FLOAT
static lsm_real cl_phase(lsm_real th0, lsm_real k0, lsm_real c, lsm_real s)
{
    return th0 + s * (k0 + LSM_R(0.5) * c * s);
}
static lsm_real cl_vertex_phase(lsm_real th0, lsm_real k0, lsm_real c)
{
    return th0 - k0 * k0 / (LSM_R(2.0) * c);
}
#else
/* Large phases (the Fresnel form is used when the clothoid turns more than 32 rad, up to ~1e8 rad
 * for the Fresnel integrals at x ~ 1e4): the products are carried with their rounding errors (fma)
 * and reduced modulo 2 pi with a two-part 2 pi, so that cos and sin see an angle good to ~eps. */
#define CL_2PI_HI 6.283185307179586
#define CL_2PI_LO 2.4492935982947064e-16
static double cl_mod2pi(double hi, double lo)
{
    const double n = floor(hi / CL_2PI_HI + 0.5);
    return (fma(-n, CL_2PI_HI, hi) - n * CL_2PI_LO) + lo;
}
/* theta0 + k0 s + c s^2 / 2, reduced */
static double cl_phase(double th0, double k0, double c, double s)
{
    const double a = k0 * s, ae = fma(k0, s, -a);
    const double p = s * s, pe = fma(s, s, -p);
    const double hc = 0.5 * c;
    const double b = hc * p, be = fma(hc, p, -b) + hc * pe;
    return th0 + cl_mod2pi(a, ae) + cl_mod2pi(b, be);
}
/* theta0 - k0^2 / (2c), reduced */
static double cl_vertex_phase(double th0, double k0, double c)
{
    const double q = k0 * k0, qe = fma(k0, k0, -q);
    const double d = 2.0 * c;
    const double v = q / d, ve = (fma(-v, d, q) + qe) / d;
    return th0 - cl_mod2pi(v, ve);
}
#endif

/* c > 0, s > 0. I = sqrt(pi/c) e^{i theta_v} [E(u1) - E(u0)], theta(t) = theta_v + pi u(t)^2 / 2. */
static void cl_integral_fresnel(lsm_real th0, lsm_real k0, lsm_real c, lsm_real s, lsm_real *dx, lsm_real *dy)
{
    const lsm_real sq = lsm_sqrt(CL_PI * c);
    const lsm_real k1 = k0 + c * s;
    const lsm_real th1 = cl_phase(th0, k0, c, s);
    const lsm_real u0 = k0 / sq, u1 = k1 / sq;
    lsm_real a0r, a0i, b0r, b0i, a1r, a1i, b1r, b1i;
    cl_fresnel_end(u0, th0, &a0r, &a0i, &b0r, &b0i);
    cl_fresnel_end(u1, th1, &a1r, &a1i, &b1r, &b1i);
    lsm_real rr = b1r - b0r, ri = b1i - b0i;
    const lsm_real dar = a1r - a0r, dai = a1i - a0i;
    if (dar != LSM_R(0.0) || dai != LSM_R(0.0)) {
        const lsm_real thv = cl_vertex_phase(th0, k0, c);
        lsm_real co, si;
        lsm_sincos(thv, &si, &co);
        rr += co * dar - si * dai;
        ri += co * dai + si * dar;
    }
    const lsm_real f = CL_PI / sq; /* sqrt(pi / c) */
    *dx = f * rr;
    *dy = f * ri;
}

/* s > 0, c != 0: lsm_clothoid_integral uses the piecewise series (else the Fresnel form). */
static inline bool cl_series_regime(lsm_real k0, lsm_real c, lsm_real s)
{
    const lsm_real phi = lsm_fabs(k0) * s + LSM_R(0.5) * lsm_fabs(c) * s * s;
    return phi <= (lsm_real)LSM_CLOTHOID_SERIES_PHASE_RAD;
}

void lsm_clothoid_integral(lsm_real theta0_rad, lsm_real kappa0_per_mm, lsm_real c_per_mm2, lsm_real s_mm,
                           lsm_real *dx_mm, lsm_real *dy_mm)
{
    const lsm_real th0 = theta0_rad, k0 = kappa0_per_mm, c = c_per_mm2, s = s_mm;
    lsm_real *const dx = dx_mm, *const dy = dy_mm;
    if (s == LSM_R(0.0)) {
        *dx = *dy = LSM_R(0.0);
        return;
    }
    if (s < LSM_R(0.0)) {
        lsm_real x, y;
        lsm_clothoid_integral(th0, -k0, c, -s, &x, &y);
        *dx = -x;
        *dy = -y;
        return;
    }
    if (c == LSM_R(0.0)) {
        const lsm_real h = LSM_R(0.5) * k0 * s;
        const lsm_real sinc = h == LSM_R(0.0) ? LSM_R(1.0) : lsm_sin(h) / h;
        lsm_real co, si;
        lsm_sincos(th0 + h, &si, &co);
        *dx = s * sinc * co;
        *dy = s * sinc * si;
        return;
    }
    if (cl_series_regime(k0, c, s)) {
        cl_pieces_pos(th0, k0, c, s, dx, dy, NULL);
        return;
    }
    if (c > LSM_R(0.0)) {
        cl_integral_fresnel(th0, k0, c, s, dx, dy);
    } else {
        lsm_real x, y;
        cl_integral_fresnel(-th0, -k0, -c, s, &x, &y);
        *dx = x;
        *dy = -y;
    }
}

/* ---------------------------------------------------------------- segments */

static lsm_status cl_check(lsm_real v)
{
    return (lsm_status)lsm_check_finite(v);
}

/* Validation of the six parameters of a segment: one test for the common case (x - x is 0 for every finite x and
 * NaN otherwise, so the sum is 0 only if all six are finite), the checks one by one to report the first bad one. */
static lsm_status cl_check_seg(lsm_real x0, lsm_real y0, lsm_real th0, lsm_real k0, lsm_real c, lsm_real len)
{
    const lsm_real z = ((x0 - x0) + (y0 - y0)) + ((th0 - th0) + (k0 - k0)) + ((c - c) + (len - len));
    if (!(z == LSM_R(0.0))) {
        const lsm_real v[6] = {x0, y0, th0, k0, c, len};
        for (int i = 0; i < 6; i++) {
            lsm_status st = cl_check(v[i]);
            if (st != LSM_OK)
                return st;
        }
    }
    return len < LSM_R(0.0) ? LSM_E_RANGE : LSM_OK;
}

lsm_status lsm_clothoid_init(lsm_clothoid *cl, lsm_real x0_mm, lsm_real y0_mm, lsm_real theta0_rad,
                             lsm_real kappa0_per_mm, lsm_real c_per_mm2, lsm_real len_mm)
{
    if (cl == NULL)
        return LSM_E_NULL;
    lsm_status st = cl_check_seg(x0_mm, y0_mm, theta0_rad, kappa0_per_mm, c_per_mm2, len_mm);
    if (st != LSM_OK)
        return st;
    cl->x0_mm = x0_mm;
    cl->y0_mm = y0_mm;
    cl->theta0_rad = theta0_rad;
    cl->kappa0_per_mm = kappa0_per_mm;
    cl->c_per_mm2 = c_per_mm2;
    cl->len_mm = len_mm;
    return LSM_OK;
}

static inline lsm_real cl_theta(const lsm_clothoid *cl, lsm_real s)
{
    return cl->theta0_rad + s * (cl->kappa0_per_mm + LSM_R(0.5) * cl->c_per_mm2 * s);
}

static void cl_state(const lsm_clothoid *cl, lsm_real s, lsm_clothoid_state *out)
{
    lsm_real dx, dy;
    lsm_clothoid_integral(cl->theta0_rad, cl->kappa0_per_mm, cl->c_per_mm2, s, &dx, &dy);
    out->x_mm = cl->x0_mm + dx;
    out->y_mm = cl->y0_mm + dy;
    out->theta_rad = cl_theta(cl, s);
    out->kappa_per_mm = cl->kappa0_per_mm + cl->c_per_mm2 * s;
}

lsm_status lsm_clothoid_eval(const lsm_clothoid *cl, lsm_real s_mm, lsm_clothoid_state *out)
{
    if (cl == NULL || out == NULL)
        return LSM_E_NULL;
    lsm_status st = cl_check(s_mm);
    if (st != LSM_OK)
        return st;
    cl_state(cl, s_mm, out);
    if (lsm_check_finite(out->x_mm) || lsm_check_finite(out->y_mm) || lsm_check_finite(out->theta_rad) ||
        lsm_check_finite(out->kappa_per_mm))
        return LSM_E_RANGE;
    return LSM_OK;
}

/* ---------------------------------------------------------------- stepping */

/* Functions of the stepper's usual path, inlined into the one function that runs it, cl_step_poly (GCC does not
 * inline functions used more than once at -Os); elsewhere they are called through the plain functions below them. */
#if defined(__GNUC__)
#define CL_HOT static inline __attribute__((always_inline))
#else
#define CL_HOT static inline
#endif

/* E = e^{i psi(1)} and M = int_0^1 e^{i psi(u)} du for psi(u) = a u + b u^2 / 2 (lsm_clothoid_local). A
 * homogeneous aggregate of four reals: returned in registers (s0-s3 on the Cortex-M4F). */
typedef struct cl_em {
    lsm_real er, ei, mr, mi;
} cl_em;

/* The small-step polynomial (lsm_clothoid_local_fast; valid for |a + b/2| <= LSM_CLOTHOID_FAST_PHI_RAD and
 * |b| <= LSM_CLOTHOID_FAST_B_RAD). Expanded about the midpoint u = 1/2, where psi(u) = phi/2 - r + phi v +
 * 2 r v^2 (v = u - 1/2 in [-1/2, 1/2], phi = a + b/2 = psi'(1/2), r = b/4):
 *   E = H^2 with H = e^{i phi/2},   M = H G,   G = int_{-1/2}^{1/2} e^{i (phi v + r (4 v^2 - 1))} dv,
 *   G = sum_{k,m} (-i r)^k (-q)^m / ((2m)! (2m+1)(2m+3)...(2m+2k+1)),   q = phi^2 / 4
 * (the odd powers of v integrate to 0, and v^2 <= 1/4: the terms fall like q^m and r^k, not phi^n and b^k).
 * Kept: sin(phi/2) to x^5 and cos(phi/2) to x^6; G to q^3, r^2 q and r^3. The largest dropped terms are
 * x^7/5040 (in E), q^4/362880, r^4/945, r^3 q/1890 and r^2 q^2/7560: at the corners of the region the truncation
 * error is 5.1e-9 in float (eps/23) and 4.9e-18 in double (eps/45), against mpmath (docs/clothoid.md). */
#define CL_1_OVER(n) (LSM_R(1.0) / LSM_R(n))
CL_HOT cl_em cl_local_poly_hot(lsm_real a, lsm_real b)
{
    const lsm_real x = LSM_R(0.5) * (a + LSM_R(0.5) * b); /* phi / 2 */
    const lsm_real q = x * x;
    const lsm_real r = LSM_R(0.25) * b, r2 = r * r;
    /* H = e^{i x} */
    const lsm_real hs = x + x * q * (q * CL_1_OVER(120.0) - CL_1_OVER(6.0));
    const lsm_real hc = LSM_R(1.0) + q * (q * (CL_1_OVER(24.0) - q * CL_1_OVER(720.0)) - LSM_R(0.5));
    /* G */
    const lsm_real gr = LSM_R(1.0) - (q * (CL_1_OVER(6.0) - q * (CL_1_OVER(120.0) - q * CL_1_OVER(5040.0))) +
                                      r2 * (CL_1_OVER(15.0) - q * CL_1_OVER(210.0)));
    const lsm_real gi = -r * (CL_1_OVER(3.0) - q * (CL_1_OVER(30.0) - q * CL_1_OVER(840.0)) - r2 * CL_1_OVER(105.0));
    cl_em o;
    o.er = (hc - hs) * (hc + hs);
    o.ei = LSM_R(2.0) * hc * hs;
    o.mr = hc * gr - hs * gi;
    o.mi = hc * gi + hs * gr;
    return o;
}

CL_HOT bool cl_local_is_small(lsm_real a, lsm_real b)
{
    return lsm_fabs(a + LSM_R(0.5) * b) <= (lsm_real)LSM_CLOTHOID_FAST_PHI_RAD &&
           lsm_fabs(b) <= (lsm_real)LSM_CLOTHOID_FAST_B_RAD;
}

static cl_em cl_local_any(lsm_real a, lsm_real b)
{
    cl_em o;
    if (cl_local_is_small(a, b))
        return cl_local_poly_hot(a, b);
    lsm_clothoid_local(a, b, &o.er, &o.ei, &o.mr, &o.mi);
    return o;
}

void lsm_clothoid_local_fast(lsm_real a, lsm_real b, lsm_real *er, lsm_real *ei, lsm_real *mr, lsm_real *mi)
{
    const cl_em o = cl_local_any(a, b);
    *er = o.er;
    *ei = o.ei;
    *mr = o.mr;
    *mi = o.mi;
}

/* Applies a sub-step of length h with (E, M) to the state: position += h T M (compensated), T = T E (renormalised
 * with one Newton step towards |T| = 1). */
CL_HOT void cl_apply_hot(lsm_clothoid_stepper *st, lsm_real h, cl_em em)
{
    const lsm_real tx = st->tx, ty = st->ty;
    /* compensated sums: the increments are small against the coordinates */
    const lsm_real ix = h * (tx * em.mr - ty * em.mi) - st->cx_mm, iy = h * (tx * em.mi + ty * em.mr) - st->cy_mm;
    const lsm_real x = st->x_mm, y = st->y_mm;
    const lsm_real nxp = x + ix, nyp = y + iy;
    st->cx_mm = (nxp - x) - ix;
    st->cy_mm = (nyp - y) - iy;
    st->x_mm = nxp;
    st->y_mm = nyp;
    const lsm_real nx = tx * em.er - ty * em.ei, ny = tx * em.ei + ty * em.er;
    const lsm_real f = LSM_R(1.5) - LSM_R(0.5) * (nx * nx + ny * ny); /* one Newton step towards |t| = 1 */
    st->tx = nx * f;
    st->ty = ny * f;
}

static void cl_apply(lsm_clothoid_stepper *st, lsm_real h, cl_em em)
{
    cl_apply_hot(st, h, em);
}

/* A small sub-step (cl_local_is_small): the polynomial and the update, the one copy of the polynomial in the image
 * (out of line: the usual step of lsm_clothoid_step calls it too). */
CL_NOINLINE void cl_step_poly(lsm_clothoid_stepper *st, lsm_real h, lsm_real a, lsm_real b)
{
    cl_apply_hot(st, h, cl_local_poly_hot(a, b));
}

/* Any sub-step of length h (a = k h, b = c h^2): the polynomial where small, else the general series. */
static void cl_step_one(lsm_clothoid_stepper *st, lsm_real h, lsm_real a, lsm_real b)
{
    if (cl_local_is_small(a, b)) {
        cl_step_poly(st, h, a, b);
        return;
    }
    cl_em o;
    lsm_clothoid_local(a, b, &o.er, &o.ei, &o.mr, &o.mi);
    cl_apply(st, h, o);
}

/* Exact state at st->s_mm: x and y as lsm_clothoid_eval computes them (bit for bit, so that the end of the segment
 * is landed on exactly), the tangent from the same series (its end rotation) where that is used, else from the
 * angle. */
static void cl_anchor(lsm_clothoid_stepper *st)
{
    const lsm_clothoid *cl = &st->seg;
    const lsm_real s = st->s_mm;
    lsm_real dx, dy, rot[2];
    if (s > LSM_R(0.0) && cl->c_per_mm2 != LSM_R(0.0) && cl_series_regime(cl->kappa0_per_mm, cl->c_per_mm2, s)) {
        cl_pieces_pos(cl->theta0_rad, cl->kappa0_per_mm, cl->c_per_mm2, s, &dx, &dy, rot);
    } else {
        lsm_clothoid_integral(cl->theta0_rad, cl->kappa0_per_mm, cl->c_per_mm2, s, &dx, &dy);
        lsm_sincos(cl_theta(cl, s), &rot[1], &rot[0]);
    }
    st->x_mm = cl->x0_mm + dx;
    st->y_mm = cl->y0_mm + dy;
    st->tx = rot[0];
    st->ty = rot[1];
    st->kappa_per_mm = cl->kappa0_per_mm + cl->c_per_mm2 * s;
    st->cx_mm = st->cy_mm = LSM_R(0.0);
    st->since_anchor = 0;
}

/* Most polynomial pieces of an anchor from the segment's start; beyond, the exact evaluation. Float: an anchor
 * from m pieces costs about 100 m instructions, the exact evaluation about 850 per radian of turning, and the
 * polynomial needs m ~ 2.5 pieces per radian. Double: only a start within one small step (the region is small). */
#if LSM_REAL_IS_FLOAT
#define CL_ANCHOR_POLY_MAX 64
#else
#define CL_ANCHOR_POLY_MAX 1
#endif

/* The state at st->s_mm (< len) evaluated from the start of the segment, in m equal pieces that are small steps:
 * piece j has phi_j = h (k0 + c h (j + 1/2)), so |phi_j| <= (|k0| s + |c| s^2) / m, and b_j = c s^2 / m^2. As
 * accurate as the exact evaluation (each piece to a couple of eps), not bit for bit the same. False (nothing
 * changed) if it would take more than CL_ANCHOR_POLY_MAX pieces. */
static bool cl_anchor_poly(lsm_clothoid_stepper *st)
{
    const lsm_clothoid *cl = &st->seg;
    const lsm_real s = st->s_mm, k0 = cl->kappa0_per_mm, c = cl->c_per_mm2;
    const lsm_real bb = lsm_fabs(c) * s * s, ph = lsm_fabs(k0) * s + bb;
    int m = 1;
    if (!(ph <= (lsm_real)LSM_CLOTHOID_FAST_PHI_RAD && bb <= (lsm_real)LSM_CLOTHOID_FAST_B_RAD)) {
        const lsm_real mp = ph * (LSM_R(1.0) / (lsm_real)LSM_CLOTHOID_FAST_PHI_RAD);
        const lsm_real mb = lsm_sqrt(bb * (LSM_R(1.0) / (lsm_real)LSM_CLOTHOID_FAST_B_RAD));
        const lsm_real mm = lsm_ceil(mp > mb ? mp : mb);
        if (!(mm <= (lsm_real)CL_ANCHOR_POLY_MAX))
            return false;
        m = (int)mm;
    }
    lsm_sincos(cl->theta0_rad, &st->ty, &st->tx);
    st->x_mm = cl->x0_mm;
    st->y_mm = cl->y0_mm;
    st->cx_mm = st->cy_mm = LSM_R(0.0);
    if (m == 1) { /* the usual block entry: s is short */
        if (s > LSM_R(0.0))
            cl_step_one(st, s, k0 * s, c * s * s); /* small: |a + b/2| <= ph, |b| = bb, also rounded */
    } else {
        const lsm_real h = s / (lsm_real)m, b = c * h * h;
        for (int j = 0; j < m; j++)
            cl_step_one(st, h, (k0 + c * (h * (lsm_real)j)) * h, b); /* checks the region again */
    }
    st->kappa_per_mm = k0 + c * s;
    st->since_anchor = 0;
    return true;
}

lsm_status lsm_clothoid_stepper_init(lsm_clothoid_stepper *st, const lsm_clothoid *seg, lsm_real s0_mm,
                                     uint32_t anchor_every)
{
    if (st == NULL || seg == NULL)
        return LSM_E_NULL;
    lsm_status r =
        cl_check_seg(seg->x0_mm, seg->y0_mm, seg->theta0_rad, seg->kappa0_per_mm, seg->c_per_mm2, seg->len_mm);
    if (r != LSM_OK)
        return r;
    r = cl_check(s0_mm);
    if (r != LSM_OK)
        return r;
    if (s0_mm < LSM_R(0.0) || s0_mm > seg->len_mm)
        return LSM_E_RANGE;
    st->seg = *seg;
    st->s_mm = s0_mm;
    st->cs_mm = LSM_R(0.0);
    st->anchor_every = anchor_every;
    /* from the segment's start in small steps (the usual start, just after the beginning, is one of them); at the
     * end (exactly the end state) or beyond CL_ANCHOR_POLY_MAX pieces, the exact evaluation */
    if (!(s0_mm < seg->len_mm && cl_anchor_poly(st)))
        cl_anchor(st);
    return LSM_OK;
}

void lsm_clothoid_local(lsm_real a, lsm_real b, lsm_real *er_out, lsm_real *ei_out, lsm_real *mr_out, lsm_real *mi_out)
{
    const lsm_real tol = LSM_R(0.5) * LSM_REAL_EPS;
    const lsm_real grow = lsm_fabs(a) + lsm_fabs(b);
    /* g_0 = 1, g_1 = i a; E = sum g_n, M = sum g_n / (n + 1) */
    lsm_real pr = LSM_R(1.0), pi = LSM_R(0.0), gr = LSM_R(0.0), gi = a;
    lsm_real er = LSM_R(1.0), ei = a, mr = LSM_R(1.0), mi = LSM_R(0.5) * a;
    for (int n = 1; n + 1 < LSM_CLOTHOID_MAX_TERMS; n++) {
        const lsm_real tr = a * gr + b * pr, ti = a * gi + b * pi;
        const lsm_real inv = k_inv[n];
        const lsm_real nr = -ti * inv, ni = tr * inv;
        pr = gr;
        pi = gi;
        gr = nr;
        gi = ni;
        er += nr;
        ei += ni;
        mr += nr * k_inv[n + 1];
        mi += ni * k_inv[n + 1];
        if ((lsm_real)(n + 2) > grow && cl_abs1(gr, gi) + cl_abs1(pr, pi) <= tol)
            break;
    }
    *er_out = er;
    *ei_out = ei;
    *mr_out = mr;
    *mi_out = mi;
}

/* Most sub-steps a step outside the small-step region is cut into for the polynomial; beyond, the general series.
 * Float only: there two or three polynomial sub-steps cost less than one general series (350 against 440
 * instructions at |kappa ds| = 0.5); the double region is so small that the sub-steps would be many, each adding
 * its rounding (the host build does not need the speed). */
#if LSM_REAL_IS_FLOAT
#define CL_POLY_SPLIT_MAX 4
#else
#define CL_POLY_SPLIT_MAX 1
#endif

/* A step outside the small-step region (ph = |a| + |b|). Cut into m <= CL_POLY_SPLIT_MAX equal sub-steps if each
 * is then small: sub-step j has phi_j = h (k + c h (j + 1/2)), so |phi_j| <= ph / m, and b_j = b / m^2. Otherwise
 * the general series, on sub-steps that turn at most about 1 rad. */
static void cl_step_general(lsm_clothoid_stepper *st, lsm_real ds, lsm_real a, lsm_real b)
{
    const lsm_real ph = lsm_fabs(a) + lsm_fabs(b), ab = lsm_fabs(b);
    int m = 0;
    for (int k = 2; k <= CL_POLY_SPLIT_MAX; k++) {
        const lsm_real kr = (lsm_real)k;
        if (ph <= kr * (lsm_real)LSM_CLOTHOID_FAST_PHI_RAD && ab <= kr * kr * (lsm_real)LSM_CLOTHOID_FAST_B_RAD) {
            m = k;
            break;
        }
    }
    if (m == 0) {
        if (ph <= LSM_R(1.0)) {
            cl_step_one(st, ds, a, b);
            return;
        }
        m = (int)lsm_ceil(ph);
    }
    const lsm_real c = st->seg.c_per_mm2;
    const lsm_real h = ds / (lsm_real)m;
    for (int i = 0; i < m; i++) {
        cl_step_one(st, h, st->kappa_per_mm * h, c * h * h); /* checks the region again */
        st->kappa_per_mm += c * h;                           /* reset from the arc length after the step */
    }
}

lsm_status lsm_clothoid_step(lsm_clothoid_stepper *st, lsm_real ds_mm, lsm_clothoid_state *out)
{
    if (st == NULL)
        return LSM_E_NULL;
    if (!(ds_mm >= LSM_R(0.0) && ds_mm <= LSM_REAL_MAX)) { /* NaN, infinite or negative */
        lsm_status r = cl_check(ds_mm);
        return r != LSM_OK ? r : LSM_E_NEG_FEED;
    }
    const lsm_real left = st->seg.len_mm - st->s_mm;
    bool at_end = false;
    if (ds_mm >= left) {
        ds_mm = left;
        at_end = true;
    }
    if (ds_mm > LSM_R(0.0)) {
        const lsm_real c = st->seg.c_per_mm2;
        const lsm_real a = st->kappa_per_mm * ds_mm, b = c * ds_mm * ds_mm;
        if (cl_local_is_small(a, b)) /* the usual step: a fixed polynomial */
            cl_step_poly(st, ds_mm, a, b);
        else
            cl_step_general(st, ds_mm, a, b);
        const lsm_real is = ds_mm - st->cs_mm, ns = st->s_mm + is;
        st->cs_mm = (ns - st->s_mm) - is;
        st->s_mm = ns;
        if (ns >= st->seg.len_mm)
            at_end = true;
        st->kappa_per_mm = st->seg.kappa0_per_mm + c * ns;
        st->since_anchor++;
    }
    if (at_end) {
        st->s_mm = st->seg.len_mm;
        cl_anchor(st); /* land exactly on the end state */
    } else if (st->anchor_every != 0 && st->since_anchor >= st->anchor_every) {
        if (!cl_anchor_poly(st))
            cl_anchor(st);
    }
    if (out != NULL) {
        out->x_mm = st->x_mm;
        out->y_mm = st->y_mm;
        out->theta_rad = cl_theta(&st->seg, st->s_mm);
        out->kappa_per_mm = st->kappa_per_mm;
    }
    return LSM_OK;
}

/* ---------------------------------------------------------------- fit (section IV) */

typedef struct {
    lsm_real x0, y0, th0, k0; /* start */
    lsm_real nx, ny;          /* unit normal of the line */
    lsm_real d0;              /* signed distance of the start from the line */
    lsm_real delta;           /* required turning: theta(s) - theta0 */
    int evals;
} cl_fit;

/* Residuals F1 = n.(P(s) - Q) (mm), F2 = theta(s) - theta_target (rad) and, if J, the Jacobian
 * d(F1, F2)/d(c, s). Returns false if (c, s) is outside the domain searched. */
static bool cl_fit_eval(cl_fit *f, lsm_real c, lsm_real s, lsm_real *F1, lsm_real *F2, lsm_real J[4])
{
    const lsm_real phi = lsm_fabs(f->k0) * s + LSM_R(0.5) * lsm_fabs(c) * s * s;
    if (!(s > LSM_R(0.0)) || !(phi <= (lsm_real)LSM_CLOTHOID_FIT_MAX_PHASE_RAD))
        return false;
    lsm_real mr[3], mi[3];
    cl_pieces(f->th0, f->k0, c, s, J ? 3 : 1, mr, mi);
    f->evals++;
    *F1 = f->d0 + f->nx * mr[0] + f->ny * mi[0];
    *F2 = s * (f->k0 + LSM_R(0.5) * c * s) - f->delta;
    if (J) {
        const lsm_real th = f->th0 + s * (f->k0 + LSM_R(0.5) * c * s);
        /* dP/dc = int (t^2 / 2) i e^{i theta} dt = (i M2) / 2 */
        J[0] = LSM_R(0.5) * (-f->nx * mi[2] + f->ny * mr[2]); /* dF1/dc */
        lsm_real co, si;
        lsm_sincos(th, &si, &co);
        J[1] = f->nx * co + f->ny * si; /* dF1/ds */
        J[2] = LSM_R(0.5) * s * s;      /* dF2/dc */
        J[3] = f->k0 + c * s;           /* dF2/ds */
    }
    return true;
}

static lsm_real cl_wrap_pi(lsm_real a)
{
    const lsm_real two_pi = LSM_R(2.0) * CL_PI;
    a -= two_pi * lsm_floor(a / two_pi + LSM_R(0.5));
    return a; /* in [-pi, pi) */
}

/* Tuning of the fit. */
#define CL_FIT_ZERO_EPS LSM_R(16.0)    /* eps multiples: on the line / along its normal within the rounding of d0 */
#define CL_FIT_SCAN_K_MIN (-4)         /* the scan starts at s = dist / 4: shorter candidates turn too sharply */
#define CL_FIT_SCAN_K_MAX 24           /* ... and ends at s = 2^12 dist, the documented reach (4096 times dist) */
#define CL_FIT_CONV_EPS LSM_R(32.0)    /* eps multiples of the problem's scale: residuals at rounding level */
#define CL_FIT_MAX_HALVINGS 30         /* damping: a Newton step is halved at most this often (2^-30) */
#define CL_FIT_MERIT_FLOOR LSM_R(4.0)  /* eps^2 multiples: a merit at rounding level counts as a decrease */
#define CL_FIT_BISECT_EVERY 3          /* fallback: a bisection when 3 steps did not halve the bracket */
#define CL_FIT_COLLAPSE_EPS LSM_R(4.0) /* fallback: eps multiples of s; a narrower bracket pins the root */

/* Validates the input and sets up the problem: unit normal, signed distance d0 and its rounding bound. */
static lsm_status cl_fit_setup(const lsm_clothoid_state *start, lsm_real qx_mm, lsm_real qy_mm, lsm_real nx,
                               lsm_real ny, cl_fit *f, lsm_real *d_err)
{
    const lsm_real v[8] = {start->x_mm, start->y_mm, start->theta_rad, start->kappa_per_mm, qx_mm, qy_mm, nx, ny};
    for (int i = 0; i < 8; i++) {
        lsm_status st = cl_check(v[i]);
        if (st != LSM_OK)
            return st;
    }
    const lsm_real nn = lsm_sqrt(nx * nx + ny * ny);
    if (!(nn > LSM_R(0.0)) || lsm_check_finite(nn))
        return LSM_E_FIT_LINE;
    f->x0 = start->x_mm;
    f->y0 = start->y_mm;
    f->th0 = start->theta_rad;
    f->k0 = start->kappa_per_mm;
    f->nx = nx / nn;
    f->ny = ny / nn;
    f->evals = 0;
    const lsm_real px = f->x0 - qx_mm, py = f->y0 - qy_mm;
    f->d0 = f->nx * px + f->ny * py;
    *d_err = CL_FIT_ZERO_EPS * LSM_REAL_EPS *
             (lsm_fabs(f->nx * px) + lsm_fabs(f->ny * py) + lsm_fabs(f->nx * qx_mm) + lsm_fabs(f->ny * qy_mm));
    return LSM_OK;
}

/* Start on the line: the only solution is s = 0, if the tangent is already along the normal. */
static lsm_status cl_fit_on_line(const cl_fit *f, const lsm_clothoid_state *start, lsm_clothoid_fit_result *out)
{
    lsm_real co, si;
    lsm_sincos(f->th0, &si, &co);
    const lsm_real cr = f->nx * si - f->ny * co;
    if (!(lsm_fabs(cr) <= CL_FIT_ZERO_EPS * LSM_REAL_EPS))
        return LSM_E_FIT_ON_LINE;
    out->c_per_mm2 = LSM_R(0.0);
    out->s_mm = LSM_R(0.0);
    out->end = *start;
    out->residual_mm = lsm_fabs(f->d0);
    out->residual_rad = lsm_fabs(cr);
    return LSM_OK;
}

/* The sharpness that meets the angle condition at length s (the reduced problem: F2 = 0). */
static inline lsm_real cl_fit_c_of_s(const cl_fit *f, lsm_real s)
{
    return LSM_R(2.0) * (f->delta - f->k0 * s) / (s * s);
}

/* A bracket of the reduced residual F1(c(s), s): s scanned geometrically, s = dist 2^(k/2), for the first
 * sign change. [sa, sb] with ra = F1(sa) on the start's side (sa = 0: ra = d0) and rb on the other or 0. */
static bool cl_fit_scan(cl_fit *f, lsm_real dist, lsm_real *sa, lsm_real *ra, lsm_real *sb, lsm_real *rb)
{
    *sa = LSM_R(0.0);
    *ra = f->d0;
    *sb = LSM_R(0.0);
    *rb = f->d0;
    for (int k = CL_FIT_SCAN_K_MIN; k <= CL_FIT_SCAN_K_MAX; k++) {
        /* s = dist * 2^(k/2) */
        lsm_real s = dist * ((k & 1) ? LSM_R(1.4142135623730951) : LSM_R(1.0));
        int e = k >> 1; /* floor(k / 2) */
        for (int i = 0; i < (e < 0 ? -e : e); i++)
            s = e < 0 ? s * LSM_R(0.5) : s * LSM_R(2.0);
        const lsm_real c = cl_fit_c_of_s(f, s);
        lsm_real F1, F2;
        if (!cl_fit_eval(f, c, s, &F1, &F2, NULL)) {
            if (k > 0)
                return false; /* turning beyond the limit: stop searching */
            continue;
        }
        if ((F1 > LSM_R(0.0)) != (f->d0 > LSM_R(0.0)) || F1 == LSM_R(0.0)) {
            *sb = s;
            *rb = F1;
            return true;
        }
        *sa = s;
        *ra = F1;
    }
    return false;
}

/* Residuals at rounding level, relative to the problem's scale. */
static bool cl_fit_converged(const cl_fit *f, lsm_real dist, lsm_real s, lsm_real F1, lsm_real F2)
{
    const lsm_real tol1 = CL_FIT_CONV_EPS * LSM_REAL_EPS * (dist + s);
    const lsm_real tol2 = CL_FIT_CONV_EPS * LSM_REAL_EPS * (LSM_R(1.0) + lsm_fabs(f->delta) + lsm_fabs(f->k0 * s));
    return lsm_fabs(F1) <= tol1 && lsm_fabs(F2) <= tol2;
}

/* One damped Newton step on (c, s) from the residuals F1, F2 and Jacobian J (determinant det != 0): the full step, halved until the merit
 * (F1 / dist)^2 + F2^2 decreases. False if no halving decreases it. */
static bool cl_fit_newton_step(cl_fit *f, lsm_real dist, const lsm_real J[4], lsm_real det, lsm_real F1, lsm_real F2,
                               lsm_real *c, lsm_real *s)
{
    const lsm_real dc = (-F1 * J[3] + F2 * J[1]) / det;
    const lsm_real dsv = (-F2 * J[0] + F1 * J[2]) / det;
    const lsm_real m0 = (F1 / dist) * (F1 / dist) + F2 * F2;
    lsm_real lam = LSM_R(1.0);
    for (int h = 0; h < CL_FIT_MAX_HALVINGS; h++, lam *= LSM_R(0.5)) {
        const lsm_real cn = *c + lam * dc, sn = *s + lam * dsv;
        lsm_real G1, G2;
        if (!cl_fit_eval(f, cn, sn, &G1, &G2, NULL))
            continue;
        const lsm_real m1 = (G1 / dist) * (G1 / dist) + G2 * G2;
        if (m1 < m0 || m1 <= CL_FIT_MERIT_FLOOR * LSM_REAL_EPS * LSM_REAL_EPS) {
            *c = cn;
            *s = sn;
            return true;
        }
    }
    return false;
}

/* Damped Newton on (c, s) from (*c, *s); on success the final residuals in F1, F2. */
static bool cl_fit_newton(cl_fit *f, lsm_real dist, lsm_real *c, lsm_real *s, lsm_real *F1, lsm_real *F2, int *it)
{
    lsm_real J[4];
    *it = 0;
    while (true) {
        if (!cl_fit_eval(f, *c, *s, F1, F2, J))
            return false;
        if (cl_fit_converged(f, dist, *s, *F1, *F2))
            return true;
        if (*it >= LSM_CLOTHOID_FIT_MAX_ITER)
            return false;
        const lsm_real det = J[0] * J[3] - J[1] * J[2];
        if (!(lsm_fabs(det) > LSM_R(0.0)))
            return false;
        const bool ok = cl_fit_newton_step(f, dist, J, det, *F1, *F2, c, s);
        (*it)++;
        if (!ok)
            return false;
    }
}

/* The fallback when Newton stalls (near a fold of the two-variable problem, where its Jacobian is nearly singular
 * and the damping takes ever smaller steps): the reduced residual F1(c(s), s) in the scan's bracket [sa, sb], by
 * regula falsi with the Illinois modification and a bisection whenever CL_FIT_BISECT_EVERY steps did not halve the
 * bracket. The reduced residual is continuous on the bracket and its turning |k0| s + |delta - k0 s| is convex in
 * s, so below the cap at both ends and inside; the bracket at least halves every CL_FIT_BISECT_EVERY steps, so
 * LSM_CLOTHOID_FIT_BRACKET_MAX_ITER steps narrow it to rounding. Ends converged, or with the bracket collapsed to
 * CL_FIT_COLLAPSE_EPS eps of s (the root pinned to rounding: the better end is taken). */
static bool cl_fit_bracket(cl_fit *f, lsm_real dist, lsm_real sa, lsm_real ra, lsm_real sb, lsm_real rb, lsm_real *c,
                           lsm_real *s, lsm_real *F1, lsm_real *F2, int *steps)
{
    lsm_real w_ref = sb - sa;
    int side = 0; /* which end moved last: -1 sa, +1 sb */
    for (*steps = 1; *steps <= LSM_CLOTHOID_FIT_BRACKET_MAX_ITER; (*steps)++) {
        lsm_real sn = (sa * rb - sb * ra) / (rb - ra);
        if (*steps % CL_FIT_BISECT_EVERY == 0) {
            if (sb - sa > LSM_R(0.5) * w_ref)
                sn = LSM_R(0.5) * (sa + sb);
            w_ref = sb - sa;
        }
        if (!(sn > sa && sn < sb))
            sn = LSM_R(0.5) * (sa + sb);
        const lsm_real cn = cl_fit_c_of_s(f, sn);
        lsm_real G1, G2;
        if (!cl_fit_eval(f, cn, sn, &G1, &G2, NULL))
            return false; /* not expected: the bracket lies inside the domain */
        *c = cn;
        *s = sn;
        *F1 = G1;
        *F2 = G2;
        if (G1 == LSM_R(0.0) || cl_fit_converged(f, dist, sn, G1, G2))
            return true;
        if ((G1 > LSM_R(0.0)) == (ra > LSM_R(0.0))) {
            sa = sn;
            ra = G1;
            if (side == -1)
                rb *= LSM_R(0.5);
            side = -1;
        } else {
            sb = sn;
            rb = G1;
            if (side == 1)
                ra *= LSM_R(0.5);
            side = 1;
        }
        if (sb - sa <= CL_FIT_COLLAPSE_EPS * LSM_REAL_EPS * sb && sa > LSM_R(0.0))
            return true; /* the last point lies within the collapsed bracket */
    }
    return false;
}

/* The result at (c, s): the end state from one more evaluation, and the residuals. */
static void cl_fit_emit(const cl_fit *f, lsm_real c, lsm_real s, lsm_real F1, lsm_real F2, lsm_clothoid_fit_result *out)
{
    lsm_real dx, dy;
    cl_pieces_pos(f->th0, f->k0, c, s, &dx, &dy, NULL);
    out->c_per_mm2 = c;
    out->s_mm = s;
    out->end.x_mm = f->x0 + dx;
    out->end.y_mm = f->y0 + dy;
    out->end.theta_rad = f->th0 + s * (f->k0 + LSM_R(0.5) * c * s);
    out->end.kappa_per_mm = f->k0 + c * s;
    out->residual_mm = lsm_fabs(F1);
    out->residual_rad = lsm_fabs(F2);
}

lsm_status lsm_clothoid_fit_pn(const lsm_clothoid_state *start, lsm_real qx_mm, lsm_real qy_mm, lsm_real nx,
                               lsm_real ny, lsm_clothoid_fit_result *out)
{
    if (start == NULL || out == NULL)
        return LSM_E_NULL;
    cl_fit f;
    lsm_real d_err;
    lsm_status st = cl_fit_setup(start, qx_mm, qy_mm, nx, ny, &f, &d_err);
    if (st != LSM_OK)
        return st;
    out->iterations = 0;
    out->evaluations = 0;
    out->bracket_steps = 0;
    if (lsm_fabs(f.d0) <= d_err)
        return cl_fit_on_line(&f, start, out);
    /* end tangent: the normal direction pointing across the line, on the branch within pi of theta0 */
    const lsm_real sg = f.d0 > LSM_R(0.0) ? LSM_R(-1.0) : LSM_R(1.0);
    const lsm_real th_t = lsm_atan2(sg * f.ny, sg * f.nx);
    f.delta = cl_wrap_pi(th_t - f.th0);
    const lsm_real dist = lsm_fabs(f.d0);

    lsm_real sa, ra, sb, rb;
    const bool found = cl_fit_scan(&f, dist, &sa, &ra, &sb, &rb);
    out->evaluations = f.evals;
    if (!found)
        return LSM_E_FIT_NO_SOLUTION;
    /* Newton from the secant point of the bracket */
    lsm_real s = sa + (sb - sa) * ra / (ra - rb);
    if (!(s > LSM_R(0.0)))
        s = LSM_R(0.5) * sb;
    lsm_real c = cl_fit_c_of_s(&f, s);
    lsm_real F1 = LSM_R(0.0), F2 = LSM_R(0.0);
    int it = 0, steps = 0;
    bool conv = cl_fit_newton(&f, dist, &c, &s, &F1, &F2, &it);
    if (!conv)
        conv = cl_fit_bracket(&f, dist, sa, ra, sb, rb, &c, &s, &F1, &F2, &steps);
    out->iterations = it;
    out->bracket_steps = steps;
    out->evaluations = f.evals;
    if (!conv)
        return LSM_E_NOT_CONVERGED;
    cl_fit_emit(&f, c, s, F1, F2, out);
    return LSM_OK;
}

lsm_status lsm_clothoid_fit_line(const lsm_clothoid_state *start, lsm_real a, lsm_real b, lsm_real c,
                                 lsm_clothoid_fit_result *out)
{
    if (start == NULL || out == NULL)
        return LSM_E_NULL;
    const lsm_real v[3] = {a, b, c};
    for (int i = 0; i < 3; i++) {
        lsm_status st = cl_check(v[i]);
        if (st != LSM_OK)
            return st;
    }
    const lsm_real m = lsm_fabs(a) > lsm_fabs(b) ? lsm_fabs(a) : lsm_fabs(b);
    if (!(m > LSM_R(0.0)))
        return LSM_E_FIT_LINE;
    a /= m; /* scale so that a^2 + b^2 cannot overflow */
    b /= m;
    c /= m;
    const lsm_real n2 = a * a + b * b;
    /* the foot of the origin on the line: Q = -c (a, b) / (a^2 + b^2) */
    const lsm_real qx = -c * a / n2, qy = -c * b / n2;
    return lsm_clothoid_fit_pn(start, qx, qy, a, b, out);
}
