/* corner.c: G2 corner smoothing with a clothoid pair (see corner.h). */
#include "corner.h"

#include "clothoid.h"
#include "lsm_math.h"

#if LSM_REAL_IS_FLOAT
#define CN_PLANAR_TOL LSM_R(1e-5) /* |line direction . arc normal| accepted as "in the plane" */
#define CN_KAPPA_REL LSM_R(1e-5)  /* curvatures equal to this relative amount: no jump */
#define CN_TTOL LSM_R(1e-6)       /* searches along the transition stop at this fraction of L */
#else
#define CN_PLANAR_TOL LSM_R(1e-9)
#define CN_KAPPA_REL LSM_R(1e-9)
#define CN_TTOL LSM_R(1e-7)
#endif
/* Aim at eps (1 - CN_MARGIN): the deviation found by the searches below is good to about 1e-5
 * relative (bracket ends CN_TTOL L apart, a golden section of CN_GOLDEN steps with a parabolic polish),
 * so the margin keeps the true deviation below eps. */
#define CN_MARGIN LSM_R(1e-4)
#define CN_MAX_NEWTON 14
#define CN_MAX_SCALES 14
#define CN_SAMPLES 4 /* samples per clothoid for the deviation */
#define CN_GOLDEN 4  /* golden-section steps of a smooth bracket before the parabolic ones */
#define CN_ACCEPT ((lsm_real)LSM_CORNER_ACCEPT)

/* Out of line where GCC's -Os inlining copies a function into each of its callers although one shared copy is
 * smaller (measured per function on the Cortex-M4F build: the flash of the core counts every byte). */
#if defined(__GNUC__)
#define CN_NOINLINE __attribute__((noinline))
#else
#define CN_NOINLINE
#endif

/* One block near the corner, in the corner frame: curvature k, available length, and what the
 * distance function needs (for an arc: |k|, the unit vector towards the centre, and the angular range as the
 * tangents at both ends). */
typedef struct {
    lsm_real k, len, dmax;
    lsm_real bx, by;     /* the block's point at the corner (V1 or V2) */
    lsm_real tx, ty;     /* its tangent there */
    lsm_real ak, ux, uy; /* arc: |k|, unit vector from the corner point towards the centre */
    lsm_real fx, fy;     /* the block's far end point */
    lsm_real ftx, fty;   /* its tangent there */
    bool full;           /* arc covers the full circle */
    bool wide;           /* arc turns pi or more */
    bool is_arc;
} cn_block;

typedef struct {
    cn_block b[2];
    lsm_real delta;
    /* current solution */
    lsm_real L, d1, d2, km;
    lsm_real ca, cb;                /* sharpness of A and B (set with the samples) */
    lsm_real ths, cs, ss, p1x, p1y; /* start of A: angle, its cos/sin, position */
    lsm_real rx, ry;                /* residual end(B) - block2(d2) */
    lsm_clothoid_series A, B;
    int its;
    /* states at the deviation samples t_j = j h, h = L / CN_SAMPLES, j = 0 .. 2 CN_SAMPLES */
    lsm_real h;
    lsm_real sx[2 * CN_SAMPLES + 1], sy[2 * CN_SAMPLES + 1], stx[2 * CN_SAMPLES + 1], sty[2 * CN_SAMPLES + 1];
} cn_ctx;

/* Point at arc length s along a curve through the origin with angle 0 and curvature k, and the
 * cos/sin of its angle k s. */
static void cn_circ(lsm_real k, lsm_real s, lsm_real *x, lsm_real *y, lsm_real *co, lsm_real *si)
{
    if (k == LSM_R(0.0)) {
        *x = s;
        *y = LSM_R(0.0);
        *co = LSM_R(1.0);
        *si = LSM_R(0.0);
        return;
    }
    const lsm_real h = LSM_R(0.5) * k * s;
    lsm_real sh, ch;
    lsm_sincos(h, &sh, &ch);
    const lsm_real sinc = h == LSM_R(0.0) ? LSM_R(1.0) : sh / h;
    *x = s * sinc * ch;
    *y = s * sinc * sh;
    *co = ch * ch - sh * sh;
    *si = LSM_R(2.0) * sh * ch;
}

/* Point of block i at distance d from the corner (backwards on block 0, forwards on block 1). */
static void cn_block_point(const cn_block *b, lsm_real sd, lsm_real *x, lsm_real *y, lsm_real *co, lsm_real *si)
{
    lsm_real lx, ly, lc, ls;
    cn_circ(b->k, sd, &lx, &ly, &lc, &ls);
    *x = b->bx + b->tx * lx - b->ty * ly;
    *y = b->by + b->ty * lx + b->tx * ly;
    *co = b->tx * lc - b->ty * ls;
    *si = b->ty * lc + b->tx * ls;
}

/* Residual R = end(B) - block2(d2) and, if jac, dR/d(d1, d2) (columns j1, j2). */
static void cn_residual(cn_ctx *c, lsm_real L, lsm_real d1, lsm_real d2, bool jac, lsm_real j[4])
{
    const cn_block *b1 = &c->b[0], *b2 = &c->b[1];
    lsm_real p1x, p1y, cs, ss, p2x, p2y, ce, se;
    cn_block_point(b1, -d1, &p1x, &p1y, &cs, &ss);
    cn_block_point(b2, d2, &p2x, &p2y, &ce, &se);
    const lsm_real ths = -b1->k * d1;
    const lsm_real the = c->delta + b2->k * d2;
    const lsm_real km = (the - ths) / L - LSM_R(0.5) * (b1->k + b2->k);
    const int nm = jac ? 3 : 1;
    lsm_clothoid_series_eval(b1->k * L, (km - b1->k) * L, nm, false, &c->A);
    lsm_clothoid_series_eval(km * L, (b2->k - km) * L, nm, false, &c->B);
    const lsm_clothoid_series *A = &c->A, *B = &c->B;
    /* S = L (MA0 + EA MB0), in the frame of the start of A */
    const lsm_real sr = L * (A->mr[0] + A->er * B->mr[0] - A->ei * B->mi[0]);
    const lsm_real si = L * (A->mi[0] + A->er * B->mi[0] + A->ei * B->mr[0]);
    c->rx = p1x + cs * sr - ss * si - p2x;
    c->ry = p1y + ss * sr + cs * si - p2y;
    c->L = L;
    c->d1 = d1;
    c->d2 = d2;
    c->km = km;
    c->ths = ths;
    c->cs = cs;
    c->ss = ss;
    c->p1x = p1x;
    c->p1y = p1y;
    if (!jac)
        return;
    /* dS/dkm = i L^2 [MA2/2 + EA (MB0/2 + MB1 - MB2/2)] */
    const lsm_real qr = LSM_R(0.5) * B->mr[0] + B->mr[1] - LSM_R(0.5) * B->mr[2];
    const lsm_real qi = LSM_R(0.5) * B->mi[0] + B->mi[1] - LSM_R(0.5) * B->mi[2];
    const lsm_real tr = LSM_R(0.5) * A->mr[2] + A->er * qr - A->ei * qi;
    const lsm_real ti = LSM_R(0.5) * A->mi[2] + A->er * qi + A->ei * qr;
    const lsm_real dsr = -L * L * ti, dsi = L * L * tr;
    /* rotate S and dS/dkm by the start angle */
    const lsm_real Sr = cs * sr - ss * si, Si = ss * sr + cs * si;
    const lsm_real Dr = cs * dsr - ss * dsi, Di = ss * dsr + cs * dsi;
    /* dR/dd1 = -e^{i ths} - i k1 (rot S) + (rot dS) k1 / L */
    const lsm_real f1 = b1->k / L, f2 = b2->k / L;
    j[0] = -cs + b1->k * Si + Dr * f1;
    j[1] = -ss - b1->k * Sr + Di * f1;
    /* dR/dd2 = (rot dS) k2 / L - e^{i the} */
    j[2] = Dr * f2 - ce;
    j[3] = Di * f2 - se;
}

/* First guess of the trims at scale L: the symmetric line-line trim plus the asymmetry of the
 * small-slope model, in which the y equation reads dk z^2/2 + delta z - dk L^2/6 = 0 for
 * z = d2 - d1/2 - d2/2 (dk = k2 - k1); its root that vanishes with dk is taken in a stable form.
 * (Starting at z = 0 would be singular for tangent joints: z = 0 is the vertex of that quadratic.) */
static void cn_guess(const cn_ctx *c, lsm_real L, lsm_real ratio, lsm_real *d1, lsm_real *d2)
{
    const lsm_real dk = c->b[1].k - c->b[0].k;
    const lsm_real q = c->delta * c->delta + dk * dk * L * L * (LSM_R(1.0) / LSM_R(3.0));
    const lsm_real den = LSM_R(3.0) * (c->delta + lsm_sqrt(q));
    lsm_real z = den > LSM_R(0.0) ? dk * L * L / den : LSM_R(0.0);
    const lsm_real base = ratio * L;
    if (z > LSM_R(0.9) * base)
        z = LSM_R(0.9) * base;
    if (z < LSM_R(-0.9) * base)
        z = LSM_R(-0.9) * base;
    *d1 = base - z;
    *d2 = base + z;
}

/* Damped Newton on (d1, d2) at scale L from the guess in *d1, *d2. */
static bool cn_solve(cn_ctx *c, lsm_real L, lsm_real *d1, lsm_real *d2)
{
    lsm_real x1 = *d1, x2 = *d2, J[4];
    for (int it = 0; it < CN_MAX_NEWTON; it++) {
        cn_residual(c, L, x1, x2, true, J);
        const lsm_real r0 = lsm_fabs(c->rx) + lsm_fabs(c->ry);
        if (r0 != r0)
            return false;
        if (r0 <= LSM_R(16.0) * LSM_REAL_EPS * (x1 + x2 + L)) {
            *d1 = x1;
            *d2 = x2;
            return true;
        }
        const lsm_real det = J[0] * J[3] - J[2] * J[1];
        if (!(lsm_fabs(det) > LSM_R(0.0)))
            return false;
        const lsm_real s1 = (-c->rx * J[3] + c->ry * J[2]) / det;
        const lsm_real s2 = (-c->ry * J[0] + c->rx * J[1]) / det;
        lsm_real lam = LSM_R(1.0);
        bool ok = false;
        c->its++;
        for (int h = 0; h < 8; h++, lam *= LSM_R(0.5)) {
            const lsm_real n1 = x1 + lam * s1, n2 = x2 + lam * s2;
            if (!(n1 > LSM_R(0.0)) || !(n2 > LSM_R(0.0)))
                continue;
            if (h == 0) { /* full step: accept unless it makes things much worse */
                x1 = n1;
                x2 = n2;
                ok = true;
                break;
            }
            cn_residual(c, L, n1, n2, false, NULL);
            if (lsm_fabs(c->rx) + lsm_fabs(c->ry) < r0) {
                x1 = n1;
                x2 = n2;
                ok = true;
                break;
            }
        }
        if (!ok)
            return false;
    }
    return false;
}

/* Distance from (x, y) to block b in the corner frame. sgn = -1: block 1 (extends backwards from
 * its corner point), +1: block 2. */
static lsm_real cn_dist(const cn_block *b, lsm_real sgn, lsm_real x, lsm_real y)
{
    const lsm_real px = x - b->bx, py = y - b->by;
    if (!b->is_arc) {
        const lsm_real along = (px * b->tx + py * b->ty) * sgn; /* >= 0 on the block side */
        if (along < LSM_R(0.0))
            return lsm_sqrt(px * px + py * py);
        if (along > b->len) {
            const lsm_real ex = px - sgn * b->tx * b->len, ey = py - sgn * b->ty * b->len;
            return lsm_sqrt(ex * ex + ey * ey);
        }
        return lsm_fabs(px * b->ty - py * b->tx);
    }
    /* within the arc's angular range: on the block's side of the radial lines through both ends,
     * tested with the tangents there (local and well conditioned, unlike angles about a far centre) */
    const bool hb = (px * b->tx + py * b->ty) * sgn >= LSM_R(0.0);
    const bool he = ((x - b->fx) * b->ftx + (y - b->fy) * b->fty) * sgn <= LSM_R(0.0);
    if (b->full || (b->wide ? (hb || he) : (hb && he))) {
        /* |rho - r| without cancelling two large numbers (r = 1/|k| can be far larger than the
         * distance): with w = P - B and u the unit vector from B to the centre,
         * |rho - r| = | |k| |w|^2 - 2 w.u | / ( | |k| w - u | + 1 ) */
        const lsm_real wu = px * b->ux + py * b->uy;
        const lsm_real ex = b->ak * px - b->ux, ey = b->ak * py - b->uy;
        return lsm_fabs(b->ak * (px * px + py * py) - LSM_R(2.0) * wu) / (lsm_sqrt(ex * ex + ey * ey) + LSM_R(1.0));
    }
    /* outside the arc's angular range: the nearer end point */
    const lsm_real d0 = lsm_sqrt(px * px + py * py);
    const lsm_real d1 = lsm_sqrt((x - b->fx) * (x - b->fx) + (y - b->fy) * (y - b->fy));
    return d0 < d1 ? d0 : d1;
}

/* Advance a state (x, y, unit tangent, curvature k) by w along a clothoid of sharpness c (the steps
 * here are a sixth of a clothoid at most, so the local series needs a few terms). */
static void cn_sub(lsm_real x, lsm_real y, lsm_real tx, lsm_real ty, lsm_real k, lsm_real c, lsm_real w, lsm_real *ox,
                   lsm_real *oy, lsm_real *otx, lsm_real *oty)
{
    lsm_real er, ei, mr, mi;
    lsm_clothoid_local(k * w, c * w * w, &er, &ei, &mr, &mi);
    *ox = x + w * (tx * mr - ty * mi);
    *oy = y + w * (tx * mi + ty * mr);
    if (otx != NULL) {
        *otx = tx * er - ty * ei;
        *oty = tx * ei + ty * er;
    }
}

/* Sharpness on the interval of samples that starts at sample j. */
static lsm_real cn_sharp(const cn_ctx *c, int j)
{
    return j < CN_SAMPLES ? c->ca : c->cb;
}

/* The sample states of the current solution, stepped from the start of A. */
CN_NOINLINE static void cn_sample_states(cn_ctx *c)
{
    c->h = c->L / (lsm_real)CN_SAMPLES;
    c->ca = (c->km - c->b[0].k) / c->L;
    c->cb = (c->b[1].k - c->km) / c->L;
    c->sx[0] = c->p1x;
    c->sy[0] = c->p1y;
    c->stx[0] = c->cs;
    c->sty[0] = c->ss;
    for (int j = 0; j < 2 * CN_SAMPLES; j++) {
        const lsm_real k =
            j < CN_SAMPLES ? c->b[0].k + c->ca * c->h * (lsm_real)j : c->km + c->cb * c->h * (lsm_real)(j - CN_SAMPLES);
        cn_sub(c->sx[j], c->sy[j], c->stx[j], c->sty[j], k, cn_sharp(c, j), c->h, &c->sx[j + 1], &c->sy[j + 1],
               &c->stx[j + 1], &c->sty[j + 1]);
    }
}

/* Curvature of the transition at t. */
static lsm_real cn_kappa(const cn_ctx *c, lsm_real t)
{
    if (t <= c->L)
        return c->b[0].k + c->ca * t;
    return c->km + c->cb * (t - c->L);
}

/* Point of the transition at t in [0, 2L] and, if tx != NULL, its unit tangent: a short step from the
 * nearest sample before t. */
static void cn_trans_point(const cn_ctx *c, lsm_real t, lsm_real *x, lsm_real *y, lsm_real *tx, lsm_real *ty)
{
    int j = (int)(t * (lsm_real)CN_SAMPLES / c->L);
    if (j < 0)
        j = 0;
    if (j > 2 * CN_SAMPLES - 1)
        j = 2 * CN_SAMPLES - 1;
    const lsm_real tj = c->h * (lsm_real)j;
    cn_sub(c->sx[j], c->sy[j], c->stx[j], c->sty[j], cn_kappa(c, tj), cn_sharp(c, j), t - tj, x, y, tx, ty);
}

/* Distance of the transition point at t from the programmed path; *side: nearer block (0 or 1). */
static lsm_real cn_pathdist(const cn_ctx *c, lsm_real t, int *side, lsm_real *diff)
{
    lsm_real x, y;
    cn_trans_point(c, t, &x, &y, NULL, NULL);
    const lsm_real a = cn_dist(&c->b[0], LSM_R(-1.0), x, y);
    const lsm_real b = cn_dist(&c->b[1], LSM_R(1.0), x, y);
    if (side)
        *side = a <= b ? 0 : 1;
    if (diff)
        *diff = a - b;
    return a < b ? a : b;
}

/* Smallest distance from the corner point (the frame origin) to the transition: safeguarded Newton
 * on g(t) = (P - V) . T = 0 in [lo, hi], g' = 1 + (P - V) . kappa N, from the best sample t0. */
static lsm_real cn_vertex(const cn_ctx *c, lsm_real lo, lsm_real hi, lsm_real t0, lsm_real best2)
{
    lsm_real t = t0;
    for (int i = 0; i < 8; i++) {
        lsm_real x, y, tx, ty;
        cn_trans_point(c, t, &x, &y, &tx, &ty);
        const lsm_real d2 = x * x + y * y;
        if (d2 < best2)
            best2 = d2;
        const lsm_real g = x * tx + y * ty;
        if (g > LSM_R(0.0))
            hi = t;
        else
            lo = t;
        const lsm_real gp = LSM_R(1.0) + cn_kappa(c, t) * (-x * ty + y * tx);
        lsm_real tn = gp > LSM_R(0.0) ? t - g / gp : LSM_R(0.5) * (lo + hi);
        if (!(tn > lo && tn < hi))
            tn = LSM_R(0.5) * (lo + hi);
        if (lsm_fabs(tn - t) <= LSM_R(1e-5) * c->L) { /* the distance is then good to ~1e-10 */
            t = tn;
            break;
        }
        t = tn;
    }
    lsm_real x, y;
    cn_trans_point(c, t, &x, &y, NULL, NULL);
    const lsm_real d2 = x * x + y * y;
    return lsm_sqrt(d2 < best2 ? d2 : best2);
}

/* The crossing d1 = d2 between a and b (where the nearer block changes), by the Illinois method.
 * fa, fb: d1 - d2 at a, b (opposite signs). Returns the end of the final bracket on b's side when
 * keep_b, else on a's side; the largest path distance met is folded into *best. */
static lsm_real cn_crossing(const cn_ctx *c, lsm_real a, lsm_real fa, lsm_real b, lsm_real fb, bool keep_b,
                            lsm_real *best)
{
    int keep = 0;
    for (int i = 0; i < 24 && b - a > CN_TTOL * c->L; i++) {
        lsm_real m = (a * fb - b * fa) / (fb - fa);
        if (!(m > a && m < b))
            m = LSM_R(0.5) * (a + b);
        lsm_real fm;
        const lsm_real v = cn_pathdist(c, m, NULL, &fm);
        if (v > *best)
            *best = v;
        /* d1 = d2 to 1e-5 of the distance: the kink's value is known well enough */
        if (lsm_fabs(fm) <= LSM_R(1e-5) * v)
            return m;
        if ((fm > LSM_R(0.0)) == (fa > LSM_R(0.0))) {
            a = m;
            fa = fm;
            if (keep == -1)
                fb *= LSM_R(0.5);
            keep = -1;
        } else {
            b = m;
            fb = fm;
            if (keep == 1)
                fa *= LSM_R(0.5);
            keep = 1;
        }
    }
    return keep_b ? b : a;
}

/* Largest path distance in [lo, hi] around the sample tm. Where the nearer block changes between lo
 * and tm or between tm and hi, the crossing (a kink of min(d1, d2), often the maximum) is found first
 * and becomes the end of the bracket; on the remaining smooth bracket, successive parabolic
 * interpolation. */
static lsm_real cn_path_max(const cn_ctx *c, lsm_real lo, lsm_real tm, lsm_real hi, lsm_real best)
{
    int sl, sm, sh;
    lsm_real dl, dm, dh;
    lsm_real fl = cn_pathdist(c, lo, &sl, &dl);
    (void)cn_pathdist(c, tm, &sm, &dm);
    lsm_real fh = cn_pathdist(c, hi, &sh, &dh);
    if (sl != sm) {
        lo = cn_crossing(c, lo, dl, tm, dm, true, &best);
        fl = cn_pathdist(c, lo, NULL, NULL);
    }
    if (sh != sm) {
        hi = cn_crossing(c, tm, dm, hi, dh, false, &best);
        fh = cn_pathdist(c, hi, NULL, NULL);
    }
    if (fl > best)
        best = fl;
    if (fh > best)
        best = fh;
    if (!(lo < hi))
        return best;
    /* the smooth part: a few golden-section steps (robust when the maximum sits at a bracket end,
     * next to a crossing), then successive parabolic steps through the best point and its neighbours */
    (void)tm;
    const lsm_real g = LSM_R(0.6180339887498949);
    lsm_real a = lo, b = hi;
    lsm_real x1 = b - g * (b - a), x2 = a + g * (b - a);
    lsm_real f1 = cn_pathdist(c, x1, NULL, NULL), f2 = cn_pathdist(c, x2, NULL, NULL);
    for (int i = 0; i < CN_GOLDEN; i++) {
        if (f1 >= f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = cn_pathdist(c, x1, NULL, NULL);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = cn_pathdist(c, x2, NULL, NULL);
        }
    }
    if (f1 > best)
        best = f1;
    if (f2 > best)
        best = f2;
    /* bracket (xa, xb, xc) with the larger of f1, f2 in the middle */
    lsm_real xa, xb, xc, fa, fb, fc;
    if (f1 >= f2) {
        xa = a;
        xb = x1;
        xc = x2;
        fa = cn_pathdist(c, xa, NULL, NULL);
        fb = f1;
        fc = f2;
    } else {
        xa = x1;
        xb = x2;
        xc = b;
        fa = f1;
        fb = f2;
        fc = cn_pathdist(c, xc, NULL, NULL);
    }
    for (int i = 0; i < 3; i++) {
        const lsm_real p = (xb - xa) * (fb - fc), q = (xb - xc) * (fb - fa);
        if (!(lsm_fabs(p - q) > LSM_R(0.0)))
            break;
        const lsm_real x = xb - LSM_R(0.5) * ((xb - xa) * p - (xb - xc) * q) / (p - q);
        if (!(x > xa && x < xc) || lsm_fabs(x - xb) <= CN_TTOL * c->L)
            break;
        const lsm_real fx = cn_pathdist(c, x, NULL, NULL);
        if (fx > best)
            best = fx;
        if (x < xb) {
            if (fx >= fb) {
                xc = xb;
                fc = fb;
                xb = x;
                fb = fx;
            } else {
                xa = x;
                fa = fx;
            }
        } else {
            if (fx >= fb) {
                xa = xb;
                fa = fb;
                xb = x;
                fb = fx;
            } else {
                xc = x;
                fc = fx;
            }
        }
    }
    return best;
}

/* Vertex and path deviation of the current solution. The path distance is refined around every
 * sampled local maximum within 3 % of the largest sample (two at most). */
CN_NOINLINE static void cn_measure(cn_ctx *c, lsm_real *vd, lsm_real *pd)
{
    const int n = 2 * CN_SAMPLES;
    cn_sample_states(c);
    const lsm_real h = c->h;
    lsm_real f[2 * CN_SAMPLES + 1];
    lsm_real bv = LSM_REAL_MAX, bp = LSM_R(-1.0);
    int av = 0;
    for (int i = 0; i <= n; i++) {
        const lsm_real x = c->sx[i], y = c->sy[i];
        const lsm_real d2 = x * x + y * y;
        if (d2 < bv) {
            bv = d2;
            av = i;
        }
        const lsm_real a = cn_dist(&c->b[0], LSM_R(-1.0), x, y);
        const lsm_real b = cn_dist(&c->b[1], LSM_R(1.0), x, y);
        f[i] = a < b ? a : b;
        if (f[i] > bp)
            bp = f[i];
    }
    const int v0 = av > 0 ? av - 1 : 0, v1 = av < n ? av + 1 : n;
    *vd = cn_vertex(c, h * (lsm_real)v0, h * (lsm_real)v1, h * (lsm_real)av, bv);
    /* the two largest local maxima of the samples */
    int m1 = -1, m2 = -1;
    for (int i = 0; i <= n; i++) {
        if ((i > 0 && f[i] < f[i - 1]) || (i < n && f[i] < f[i + 1]))
            continue;
        if (m1 < 0 || f[i] > f[m1]) {
            m2 = m1;
            m1 = i;
        } else if (m2 < 0 || f[i] > f[m2]) {
            m2 = i;
        }
    }
    lsm_real best = bp;
    for (int k = 0; k < 2; k++) {
        const int i = k == 0 ? m1 : m2;
        if (i < 0 || (k == 1 && f[i] < LSM_R(0.97) * bp))
            continue;
        const int p0 = i > 0 ? i - 1 : 0, p1 = i < n ? i + 1 : n;
        best = cn_path_max(c, h * (lsm_real)p0, h * (lsm_real)i, h * (lsm_real)p1, best);
    }
    *pd = best;
}

/* Sets up block i of the corner frame (called twice: out of line, -124 B). */
CN_NOINLINE static void cn_setup_block(cn_block *b, const lsm_geom *g, lsm_real k, lsm_real len, lsm_real dmax,
                                       lsm_real bx, lsm_real by, lsm_real tx, lsm_real ty, lsm_real sgn)
{
    b->k = k;
    b->len = len;
    b->dmax = dmax;
    b->bx = bx;
    b->by = by;
    b->tx = tx;
    b->ty = ty;
    b->is_arc = g->kind == LSM_GEOM_ARC;
    b->full = false;
    b->wide = false;
    cn_block_point(b, sgn * len, &b->fx, &b->fy, &b->ftx, &b->fty);
    if (!b->is_arc)
        return;
    /* centre: left of the tangent for k > 0 */
    b->ak = lsm_fabs(k);
    b->ux = k > LSM_R(0.0) ? -ty : ty;
    b->uy = k > LSM_R(0.0) ? tx : -tx;
    const lsm_real turn = lsm_fabs(k) * len;
    b->full = turn >= (lsm_real)(2.0 * LSM_PI);
    b->wide = turn >= (lsm_real)LSM_PI;
}

static lsm_status cn_check_block(const lsm_geom *g)
{
    if (g->kind != LSM_GEOM_LINE && g->kind != LSM_GEOM_ARC)
        return LSM_E_ARG;
    const lsm_real *v = g->kind == LSM_GEOM_LINE ? g->u.line.p0 : (const lsm_real *)&g->u.arc; /* 13 reals */
    const int n = g->kind == LSM_GEOM_LINE ? 2 * LSM_MAX_AXES : 13;
    /* 0 * x is NaN for NaN and +-inf, 0 otherwise: one test for all, then classify if needed */
    lsm_real z = LSM_R(0.0);
    for (int i = 0; i < n; i++)
        z += LSM_R(0.0) * v[i];
    if (z != z) {
        for (int i = 0; i < n; i++) {
            int r = lsm_check_finite(v[i]);
            if (r != 0)
                return (lsm_status)r;
        }
    }
    int r = lsm_check_finite(g->len);
    if (r != 0)
        return (lsm_status)r;
    if (!(g->len > LSM_R(0.0)))
        return LSM_E_ZERO_LENGTH;
    return LSM_OK;
}

/* X + iY = int_0^1 e^{i d u^2/2} du = sum_m (i d/2)^m / (m! (2m + 1)), 0 <= d <= pi: the half of the
 * symmetric pair of unit length (the series of the Fresnel integrals, lsm_clothoid_unit_fresnel at z = d/2). Its
 * stop (a term below eps/4 of min(|X|, |Y|)) is the one written here before, eps/4 of Y: 0 <= Y < X for d in
 * [0, pi]; for the tiny negative d of a tangent joint, the terms it leaves out are below half an ulp of Y. */
static void cn_unit_pair(lsm_real d, lsm_real *X, lsm_real *Y)
{
    lsm_clothoid_unit_fresnel(LSM_R(0.5) * d, X, Y);
}

/* Fills a clothoid element without the validation of lsm_geom_clothoid_init (the corner's numbers
 * are finite by construction and its basis orthonormal). */
static void cn_fill_clothoid(lsm_geom *g, const lsm_real o[3], const lsm_real e1[3], const lsm_real e2[3], lsm_real th0,
                             lsm_real k0, lsm_real c, lsm_real len)
{
    g->kind = LSM_GEOM_CLOTHOID;
    g->plane = LSM_GEOM_PLANE_GENERAL;
    g->rotary_only = 0;
    g->reserved = 0;
    g->len = len;
    for (int i = 0; i < 3; i++) {
        g->u.clo.origin_mm[i] = o[i];
        g->u.clo.e1[i] = e1[i];
        g->u.clo.e2[i] = e2[i];
    }
    g->u.clo.theta0_rad = th0;
    g->u.clo.kappa0_per_mm = k0;
    g->u.clo.c_per_mm2 = c;
}

/* Fills the clothoid pair of the general solution into out. */
static lsm_status cn_emit(const cn_ctx *c, const lsm_real ex[3], const lsm_real ey[3], const lsm_geom *b1,
                          const lsm_geom *b2, lsm_real gap_in, lsm_corner_result *out)
{
    const cn_block *k1 = &c->b[0], *k2 = &c->b[1];
    const lsm_real L = c->L;
    lsm_real pa[LSM_MAX_AXES], pb[LSM_MAX_AXES], pm[3];
    lsm_status st = lsm_geom_eval(b1, b1->len - c->d1, pa, NULL, NULL);
    if (st == LSM_OK)
        st = lsm_geom_eval(b2, c->d2, pb, NULL, NULL);
    if (st != LSM_OK)
        return st;
    /* junction M = P1 + e^{i ths} L MA0 (in the frame) */
    const lsm_real mx = L * c->A.mr[0], my = L * c->A.mi[0];
    const lsm_real jx = c->cs * mx - c->ss * my, jy = c->ss * mx + c->cs * my;
    for (int i = 0; i < 3; i++) {
        out->p1_mm[i] = pa[i];
        out->p2_mm[i] = pb[i];
        pm[i] = pa[i] + ex[i] * jx + ey[i] * jy;
    }
    const lsm_real thm = c->ths + LSM_R(0.5) * (k1->k + c->km) * L;
    cn_fill_clothoid(&out->trans[0], pa, ex, ey, c->ths, k1->k, (c->km - k1->k) / L, L);
    cn_fill_clothoid(&out->trans[1], pm, ex, ey, thm, c->km, (k2->k - c->km) / L, L);
    out->trim1_mm = c->d1;
    out->trim2_mm = c->d2;
    lsm_real km = lsm_fabs(c->km);
    if (lsm_fabs(k1->k) > km)
        km = lsm_fabs(k1->k);
    if (lsm_fabs(k2->k) > km)
        km = lsm_fabs(k2->k);
    out->kappa_max_per_mm = km;
    const lsm_real ca = lsm_fabs(c->km - k1->k) / L, cb = lsm_fabs(k2->k - c->km) / L;
    out->sharpness_max_per_mm2 = ca > cb ? ca : cb;
    /* residuals: end of B against block 2 at d2: the solver's residual plus the input's gap */
    const lsm_real the_b = thm + LSM_R(0.5) * (c->km + k2->k) * L;
    out->gap_mm = lsm_sqrt(c->rx * c->rx + c->ry * c->ry) + gap_in;
    out->gap_rad = lsm_fabs(the_b - (c->delta + k2->k * c->d2));
    return LSM_OK;
}

/* Tuning of the corner search (lsm_corner_smooth). */
#define CN_TRIM_MAX_SHARE LSM_R(0.999) /* a trim leaves at least 0.1 % of its block (no zero-length rest) */
#define CN_PATH_DEV_COEF LSM_R(0.0235) /* path distance of a curvature jump, about 0.0235 |dk| L^2 (docs/clothoid.md) */
#define CN_TRIM_BACKOFF LSM_R(0.99)    /* a scale whose trims hit their limits: retry 1 % inside them */
#define CN_TRIM_NEAR LSM_R(0.98)       /* trims within 2 % of their limits: the scale cannot grow much more */
#define CN_BRACKET_CLOSED LSM_R(1.02)  /* scale bracket closed to 2 %: the accepted scale is as good as it gets */
#define CN_MIN_SCALE_STEP LSM_R(1e-9)  /* a next scale below 1e-9 of the last: the search has collapsed */

/* The corner in its plane: end of block 1 (v1, t1), start of block 2 (v2, t2) and the gap g between them, the
 * frame (ex = t1, ey = n x ex; ey flipped so that the turn is a left turn), the blocks' signed in-plane curvatures
 * k, block 2's start tangent in the frame (t2x, t2y) and the turning delta. */
typedef struct {
    const lsm_geom *bb[2];
    lsm_real v1[LSM_MAX_AXES], v2[LSM_MAX_AXES], t1[3], t2[3], g[3], gap; /* gap = |g| */
    lsm_real n[3], ex[3], ey[3];
    lsm_real k[2];
    lsm_real t2x, t2y, delta;
    bool arc1, arc2;
} cn_corner;

/* Input checks: tolerance, trim limits, the blocks themselves, no rotary axes and no helices. */
static lsm_status cn_check_input(const lsm_geom *b1, const lsm_geom *b2, const lsm_corner_params *p)
{
    int fr = lsm_check_finite(p->tolerance_mm);
    if (fr != 0)
        return (lsm_status)fr;
    if (!(p->tolerance_mm > LSM_R(0.0)))
        return LSM_E_TOLERANCE;
    if (p->max_trim1_mm != p->max_trim1_mm || p->max_trim2_mm != p->max_trim2_mm)
        return LSM_E_NAN;
    lsm_status st = cn_check_block(b1);
    if (st == LSM_OK)
        st = cn_check_block(b2);
    if (st != LSM_OK)
        return st;
    const lsm_geom *bb[2] = {b1, b2};
    for (int i = 0; i < 2; i++) {
        if (bb[i]->kind == LSM_GEOM_LINE) {
            if (bb[i]->rotary_only || lsm_geom_moves_rotary(bb[i]))
                return LSM_E_ROTARY;
        } else if (lsm_fabs(bb[i]->u.arc.axial_mm) > CN_PLANAR_TOL * bb[i]->len) {
            return LSM_E_NONPLANAR;
        }
    }
    return LSM_OK;
}

/* The corner's plane normal n: an arc's normal (the other block must lie in its plane), or t1 x t2 for two
 * lines. */
static lsm_status cn_corner_normal(cn_corner *cc)
{
    lsm_real w[3];
    lsm_cross3(cc->t1, cc->t2, w);
    const lsm_real sw = lsm_sqrt(lsm_dot3(w, w));
    if (cc->arc1 || cc->arc2) {
        lsm_geom_normal(cc->arc1 ? cc->bb[0] : cc->bb[1], cc->n);
        if (cc->arc1 && cc->arc2) {
            lsm_real n2[3], x[3];
            lsm_geom_normal(cc->bb[1], n2);
            lsm_cross3(cc->n, n2, x);
            if (lsm_sqrt(lsm_dot3(x, x)) > CN_PLANAR_TOL)
                return LSM_E_NONPLANAR;
        } else {
            const lsm_real *tl = cc->arc1 ? cc->t2 : cc->t1;
            if (lsm_fabs(lsm_dot3(tl, cc->n)) > CN_PLANAR_TOL)
                return LSM_E_NONPLANAR;
        }
        if (lsm_fabs(lsm_dot3(cc->g, cc->n)) > (lsm_real)LSM_CORNER_GAP_TOL_MM)
            return LSM_E_GAP;
    } else {
        if (!(sw > LSM_R(0.0)))
            return lsm_dot3(cc->t1, cc->t2) > LSM_R(0.0) ? LSM_E_COLLINEAR : LSM_E_REVERSAL;
        for (int i = 0; i < 3; i++)
            cc->n[i] = w[i] / sw;
    }
    return LSM_OK;
}

/* The frame, the signed in-plane curvatures about n, the orientation and the turning delta. */
static lsm_status cn_corner_orient(cn_corner *cc)
{
    for (int i = 0; i < 3; i++)
        cc->ex[i] = cc->t1[i];
    lsm_cross3(cc->n, cc->ex, cc->ey);
    for (int i = 0; i < 2; i++) {
        cc->k[i] = LSM_R(0.0);
        if (cc->bb[i]->kind == LSM_GEOM_ARC) {
            lsm_real na[3];
            lsm_geom_normal(cc->bb[i], na);
            const lsm_real sgn = (cc->bb[i]->u.arc.sweep_rad > LSM_R(0.0)) == (lsm_dot3(na, cc->n) > LSM_R(0.0))
                                     ? LSM_R(1.0)
                                     : LSM_R(-1.0);
            cc->k[i] = sgn / cc->bb[i]->u.arc.radius_mm;
        }
    }
    cc->t2x = lsm_dot3(cc->t2, cc->ex);
    cc->t2y = lsm_dot3(cc->t2, cc->ey);
    /* orientation: make the turn a left turn (delta >= 0). A tangent joint (|delta| within the angle
     * epsilon) is oriented so that k2 <= k1 instead: the Newton start then picks the pair whose
     * curvature stays within [min, max] of k1, k2 in size (no overshoot; for a line and an arc of
     * radius R, kappa goes 0 -> -0.077/R -> 1/R rather than 0 -> 1.077/R -> 1/R, same deviation and
     * c_max), and the choice does not depend on the rounding of delta's sign. */
    const bool tangent = lsm_fabs(cc->t2y) <= (lsm_real)LSM_CORNER_ANGLE_EPS_RAD && cc->t2x > LSM_R(0.0);
    if (tangent ? cc->k[1] > cc->k[0] : cc->t2y < LSM_R(0.0)) {
        for (int i = 0; i < 3; i++)
            cc->ey[i] = -cc->ey[i];
        cc->t2y = -cc->t2y;
        cc->k[0] = -cc->k[0];
        cc->k[1] = -cc->k[1];
    }
    cc->delta = lsm_atan2(cc->t2y, cc->t2x); /* in [-aeps, pi] */
    const lsm_real aeps = (lsm_real)LSM_CORNER_ANGLE_EPS_RAD;
    const lsm_real kscale = lsm_fabs(cc->k[0]) > lsm_fabs(cc->k[1]) ? lsm_fabs(cc->k[0]) : lsm_fabs(cc->k[1]);
    if (lsm_fabs(cc->delta) <= aeps && lsm_fabs(cc->k[1] - cc->k[0]) <= CN_KAPPA_REL * kscale)
        return LSM_E_COLLINEAR;
    if ((lsm_real)LSM_PI - cc->delta <= aeps)
        return LSM_E_REVERSAL;
    return LSM_OK;
}

/* The corner's geometry (cn_corner) from the two blocks: joint, gap, plane, frame, curvatures, turning. */
static lsm_status cn_corner_setup(const lsm_geom *b1, const lsm_geom *b2, cn_corner *cc)
{
    cc->bb[0] = b1;
    cc->bb[1] = b2;
    lsm_geom_eval(b1, b1->len, cc->v1, cc->t1, NULL);
    lsm_geom_eval(b2, LSM_R(0.0), cc->v2, cc->t2, NULL);
    for (int i = 0; i < 3; i++)
        cc->g[i] = cc->v2[i] - cc->v1[i];
    cc->gap = lsm_sqrt(lsm_dot3(cc->g, cc->g));
    if (cc->gap > (lsm_real)LSM_CORNER_GAP_TOL_MM)
        return LSM_E_GAP;
    cc->arc1 = b1->kind == LSM_GEOM_ARC;
    cc->arc2 = b2->kind == LSM_GEOM_ARC;
    lsm_status st = cn_corner_normal(cc);
    if (st != LSM_OK)
        return st;
    return cn_corner_orient(cc);
}

/* The longest trim of each block: the caller's limit (or the default share of the block), below the whole block,
 * and on an arc at most LSM_CORNER_MAX_ARC_TRIM_RAD of turning. */
static void cn_trim_limits(const cn_corner *cc, const lsm_corner_params *p, lsm_real dmax[2])
{
    const lsm_real mt[2] = {p->max_trim1_mm, p->max_trim2_mm};
    for (int i = 0; i < 2; i++) {
        const lsm_geom *b = cc->bb[i];
        dmax[i] = mt[i] > LSM_R(0.0) ? mt[i] : (lsm_real)LSM_CORNER_DEFAULT_TRIM_FRACTION * b->len;
        if (dmax[i] > CN_TRIM_MAX_SHARE * b->len)
            dmax[i] = CN_TRIM_MAX_SHARE * b->len;
        if (cc->k[i] != LSM_R(0.0) && lsm_fabs(cc->k[i]) * dmax[i] > (lsm_real)LSM_CORNER_MAX_ARC_TRIM_RAD)
            dmax[i] = (lsm_real)LSM_CORNER_MAX_ARC_TRIM_RAD / lsm_fabs(cc->k[i]);
    }
}

/* Two lines: the symmetric pair in closed form, X + iY = int_0^1 e^{i delta u^2/2} du, half-length L from the
 * target deviation (or the trim limits), hc = cos(delta / 2), ratio = trim per unit half-length. */
static lsm_status cn_line_line(const cn_corner *cc, const lsm_real dmax[2], lsm_real target, lsm_real X, lsm_real Y,
                               lsm_real hc, lsm_real ratio, lsm_corner_result *out)
{
    const lsm_real delta = cc->delta;
    lsm_real L = target * hc / Y;
    const lsm_real dm = dmax[0] < dmax[1] ? dmax[0] : dmax[1];
    if (L * ratio > dm) {
        L = dm / ratio;
        out->limited = 1;
    }
    const lsm_real d = L * ratio;
    const lsm_real c = delta / (L * L);
    lsm_real pa[3], pm[3];
    for (int i = 0; i < 3; i++) {
        pa[i] = cc->v1[i] - cc->t1[i] * d;
        pm[i] = pa[i] + L * (X * cc->ex[i] + Y * cc->ey[i]);
        out->p1_mm[i] = pa[i];
        out->p2_mm[i] = cc->v2[i] + cc->t2[i] * d;
    }
    if (!(L > LSM_R(0.0)) || lsm_check_finite(c) != 0)
        return LSM_E_CORNER_NO_SOLUTION; /* L underflowed or c overflowed */
    cn_fill_clothoid(&out->trans[0], pa, cc->ex, cc->ey, LSM_R(0.0), LSM_R(0.0), c, L);
    cn_fill_clothoid(&out->trans[1], pm, cc->ex, cc->ey, LSM_R(0.5) * delta, delta / L, -c, L);
    out->trim1_mm = d;
    out->trim2_mm = d;
    out->vertex_dev_mm = L * Y / hc;
    out->path_dev_mm = L * Y;
    out->deviation_mm = out->vertex_dev_mm;
    out->kappa_max_per_mm = delta / L;
    out->sharpness_max_per_mm2 = c;
    /* B ends on block 2 by symmetry (rounding only); what is left is the input's own gap */
    out->gap_mm = cc->gap;
    out->gap_rad = LSM_R(0.0);
    out->closed_form = 1;
    out->scales = 1;
    return LSM_OK;
}

/* The search over the scale L of the general case. */
typedef struct {
    lsm_real L, g1, g2;      /* the scale to try next and the Newton start of its trims */
    lsm_real L_ok, L_bad;    /* the largest scale within the tolerance, the smallest beyond it or without solution */
    lsm_real L_prev, D_prev; /* the last measurement */
    lsm_real ma, mb;         /* the model D = ma L + mb L^2 */
    lsm_real best_d1, best_d2, best_vd, best_pd; /* the solution at L_ok */
    int scales;
} cn_search;

/* The scale at which the model D = a L + b L^2 (a > 0, b >= 0) reaches aim: the stable root of b L^2 + a L - aim = 0
 * (only + - * / and sqrt, so that the float build gives the same results on the host and on the Cortex-M4F). */
CN_NOINLINE static lsm_real cn_model_scale(lsm_real a, lsm_real b, lsm_real aim)
{
    if (b > LSM_R(0.0))
        return LSM_R(2.0) * aim / (a + lsm_sqrt(a * a + LSM_R(4.0) * b * aim));
    return aim / a;
}

/* First scale from the model D ~ a L + b L^2, aimed at the middle of the accepted band, within the trim limits. */
static void cn_search_init(cn_search *s, const cn_ctx *ctx, const cn_corner *cc, const lsm_real dmax[2],
                           lsm_real target, lsm_real Y, lsm_real hc, lsm_real ratio)
{
    const lsm_real aim0 = (LSM_R(1.0) + CN_ACCEPT) * LSM_R(0.5) * target;
    const lsm_real a = Y / hc;
    const lsm_real bq = CN_PATH_DEV_COEF * lsm_fabs(cc->k[1] - cc->k[0]);
    lsm_real L = cn_model_scale(a, bq, aim0);
    const lsm_real rg = ratio > LSM_R(1.0) ? ratio : LSM_R(1.0);
    const lsm_real dm = dmax[0] < dmax[1] ? dmax[0] : dmax[1];
    if (L * rg > dm)
        L = dm / rg;
    s->L = L;
    cn_guess(ctx, L, ratio, &s->g1, &s->g2);
    s->L_ok = LSM_R(0.0);
    s->L_bad = LSM_REAL_MAX;
    s->D_prev = LSM_R(0.0);
    s->L_prev = LSM_R(0.0);
    s->best_d1 = s->best_d2 = s->best_vd = s->best_pd = LSM_R(0.0);
    /* the model D = ma L + mb L^2, refitted to the measurements (only + - * / and sqrt, so that the
     * float build gives the same results on the host and on the Cortex-M4F) */
    s->ma = a;
    s->mb = bq;
    s->scales = 0;
}

/* No transition at scale L: a smaller scale (the family folds at large L k), started from the accepted solution
 * scaled if there is one. Returns the next scale. */
static lsm_real cn_search_no_solution(const cn_ctx *ctx, cn_search *s, lsm_real ratio)
{
    const lsm_real L = s->L;
    if (L < s->L_bad)
        s->L_bad = L;
    const lsm_real L_next = s->L_ok > LSM_R(0.0) ? lsm_sqrt(s->L_ok * s->L_bad) : LSM_R(0.5) * L;
    cn_guess(ctx, L_next, ratio, &s->g1, &s->g2);
    if (s->L_ok > LSM_R(0.0)) {
        s->g1 = s->best_d1 * L_next / s->L_ok;
        s->g2 = s->best_d2 * L_next / s->L_ok;
    }
    return L_next;
}

/* Refits the model D = ma L + mb L^2 to the measurement D at L: through both last measurements if that gives
 * non-negative coefficients, else the same shape scaled to match. */
static void cn_search_refit(cn_search *s, lsm_real L, lsm_real D)
{
    if (s->L_prev > LSM_R(0.0) && L != s->L_prev) {
        const lsm_real L_prev = s->L_prev, D_prev = s->D_prev;
        const lsm_real det = L * L_prev * (L_prev - L);
        const lsm_real na = (D * L_prev * L_prev - D_prev * L * L) / det;
        const lsm_real nb = (D_prev * L - D * L_prev) / det;
        if (na >= LSM_R(0.0) && nb >= LSM_R(0.0) && na + nb > LSM_R(0.0)) {
            s->ma = na;
            s->mb = nb;
            return;
        }
    }
    const lsm_real f = D / (s->ma * L + s->mb * L * L);
    s->ma *= f;
    s->mb *= f;
}

/* A transition with trims (d1, d2) within their limits at scale L: measure its deviation D, refit the model, keep
 * it if D is within the target. False when it is accepted (the tolerance is used, or the trims are nearly at their
 * limits); otherwise *L_next is the model's scale for the aim, not past the trim limits. */
static bool cn_search_measure(cn_ctx *ctx, cn_search *s, lsm_real d1, lsm_real d2, lsm_real target, lsm_real *L_next)
{
    const lsm_real L = s->L;
    lsm_real vd, pd;
    cn_measure(ctx, &vd, &pd);
    const lsm_real D = vd > pd ? vd : pd;
    cn_search_refit(s, L, D);
    s->L_prev = L;
    s->D_prev = D;
    /* how close the trims are to their limits (they grow about linearly with L) */
    const lsm_real r1 = d1 / ctx->b[0].dmax, r2 = d2 / ctx->b[1].dmax;
    const lsm_real rho = r1 > r2 ? r1 : r2;
    if (D <= target) {
        s->L_ok = L;
        s->best_d1 = d1;
        s->best_d2 = d2;
        s->best_vd = vd;
        s->best_pd = pd;
        if (D >= CN_ACCEPT * target || rho >= CN_TRIM_NEAR)
            return false; /* the tolerance is used, or the trims are (nearly) at their limits */
    } else if (L < s->L_bad) {
        s->L_bad = L;
    }
    /* secant step in log-log, aiming slightly inside, but not past the trim limits */
    const lsm_real aim = (LSM_R(1.0) + CN_ACCEPT) * LSM_R(0.5) * target;
    lsm_real Ln = cn_model_scale(s->ma, s->mb, aim);
    const lsm_real L_trim = L * CN_TRIM_BACKOFF / rho;
    if (Ln > L_trim)
        Ln = L_trim;
    s->g1 = d1 * Ln / L;
    s->g2 = d2 * Ln / L;
    *L_next = Ln;
    return true;
}

/* Keeps the next scale inside the bracket (L_ok, L_bad). False when the search ends: the bracket closed, or the
 * next scale collapsed. (Out of line: -60 B, one call per scale.) */
CN_NOINLINE static bool cn_search_advance(cn_search *s, lsm_real L_next)
{
    const lsm_real L = s->L;
    bool done = false;
    if (s->L_bad < LSM_REAL_MAX && L_next >= s->L_bad)
        L_next = s->L_ok > LSM_R(0.0) ? lsm_sqrt(s->L_ok * s->L_bad) : LSM_R(0.5) * s->L_bad;
    if (s->L_ok > LSM_R(0.0) && L_next <= s->L_ok)
        L_next = s->L_bad < LSM_REAL_MAX ? lsm_sqrt(s->L_ok * s->L_bad) : LSM_R(2.0) * s->L_ok;
    if (s->L_ok > LSM_R(0.0) && s->L_bad < LSM_REAL_MAX && s->L_bad <= s->L_ok * CN_BRACKET_CLOSED)
        done = true; /* bracket closed: L_ok is as good as it gets */
    if (!(L_next > LSM_R(0.0)) || L_next < CN_MIN_SCALE_STEP * L)
        return false;
    s->L = L_next;
    return !done;
}

/* One scale of the search: solve for the trims at s->L, then choose the next scale. False when the search ends. */
static bool cn_search_scale(cn_ctx *ctx, cn_search *s, lsm_real ratio, lsm_real target)
{
    const lsm_real L = s->L;
    lsm_real d1 = s->g1, d2 = s->g2;
    lsm_real L_next;
    if (!cn_solve(ctx, L, &d1, &d2)) {
        L_next = cn_search_no_solution(ctx, s, ratio);
    } else if (d1 > ctx->b[0].dmax || d2 > ctx->b[1].dmax) {
        if (L < s->L_bad)
            s->L_bad = L;
        lsm_real f1 = ctx->b[0].dmax / d1, f2 = ctx->b[1].dmax / d2;
        L_next = L * CN_TRIM_BACKOFF * (f1 < f2 ? f1 : f2);
        s->g1 = d1 * L_next / L;
        s->g2 = d2 * L_next / L;
    } else if (!cn_search_measure(ctx, s, d1, d2, target, &L_next)) {
        return false;
    }
    return cn_search_advance(s, L_next);
}

/* The general case (an arc on either side): the scale search, then the accepted solution written out. */
static lsm_status cn_general(const cn_corner *cc, const lsm_real dmax[2], lsm_real target, lsm_real Y, lsm_real hc,
                             lsm_real ratio, lsm_corner_result *out)
{
    /* frame origin V1 */
    cn_ctx ctx;
    ctx.delta = cc->delta;
    ctx.its = 0;
    cn_setup_block(&ctx.b[0], cc->bb[0], cc->k[0], cc->bb[0]->len, dmax[0], LSM_R(0.0), LSM_R(0.0), LSM_R(1.0),
                   LSM_R(0.0), LSM_R(-1.0));
    /* both blocks meet at V1 in the frame: a gap between them (at most LSM_CORNER_GAP_TOL_MM, in float
     * a few ulps of the coordinates) is left to gap_mm; kept in the frame, a lateral gap would be
     * out of reach of the small transitions of nearly straight corners */
    cn_setup_block(&ctx.b[1], cc->bb[1], cc->k[1], cc->bb[1]->len, dmax[1], LSM_R(0.0), LSM_R(0.0), cc->t2x, cc->t2y,
                   LSM_R(1.0));
    cn_search s;
    cn_search_init(&s, &ctx, cc, dmax, target, Y, hc, ratio);
    while (s.scales < CN_MAX_SCALES) {
        s.scales++;
        if (!cn_search_scale(&ctx, &s, ratio, target))
            break;
    }
    out->iterations = (uint16_t)ctx.its;
    out->scales = (uint8_t)s.scales;
    if (!(s.L_ok > LSM_R(0.0)))
        return ctx.its >= CN_MAX_NEWTON * CN_MAX_SCALES ? LSM_E_NOT_CONVERGED : LSM_E_CORNER_NO_SOLUTION;
    if (ctx.L != s.L_ok || ctx.d1 != s.best_d1 || ctx.d2 != s.best_d2) {
        /* restore the accepted solution (series and residual) */
        lsm_real d1 = s.best_d1, d2 = s.best_d2;
        cn_residual(&ctx, s.L_ok, d1, d2, true, (lsm_real[4]){0});
    }
    /* limited: the tolerance could not be used (trim limits, or no transition at larger scales) */
    out->limited = (s.best_vd > s.best_pd ? s.best_vd : s.best_pd) < CN_ACCEPT * target ? 1 : 0;
    lsm_status st = cn_emit(&ctx, cc->ex, cc->ey, cc->bb[0], cc->bb[1], cc->gap, out);
    if (st != LSM_OK)
        return st;
    out->vertex_dev_mm = s.best_vd;
    out->path_dev_mm = s.best_pd;
    out->deviation_mm = s.best_vd > s.best_pd ? s.best_vd : s.best_pd;
    return LSM_OK;
}

lsm_status lsm_corner_smooth(const lsm_geom *b1, const lsm_geom *b2, const lsm_corner_params *p, lsm_corner_result *out)
{
    if (b1 == NULL || b2 == NULL || p == NULL || out == NULL)
        return LSM_E_NULL;
    lsm_status st = cn_check_input(b1, b2, p);
    if (st != LSM_OK)
        return st;
    cn_corner cc;
    st = cn_corner_setup(b1, b2, &cc);
    if (st != LSM_OK)
        return st;
    lsm_real dmax[2];
    cn_trim_limits(&cc, p, dmax);

    const lsm_real eps = p->tolerance_mm;
    const lsm_real target = eps * (LSM_R(1.0) - CN_MARGIN);
    /* the symmetric line-line pair: X + iY = int_0^1 e^{i delta u^2/2} du */
    lsm_real X, Y;
    cn_unit_pair(cc.delta, &X, &Y);
    lsm_real hc, hs;
    lsm_sincos(LSM_R(0.5) * cc.delta, &hs, &hc);
    const lsm_real ratio = X + Y * hs / hc; /* trim per unit half-length */

    out->delta_rad = cc.delta;
    out->iterations = 0;
    out->scales = 0;
    out->limited = 0;
    out->closed_form = 0;
    if (!cc.arc1 && !cc.arc2)
        return cn_line_line(&cc, dmax, target, X, Y, hc, ratio, out);
    return cn_general(&cc, dmax, target, Y, hc, ratio, out);
}

lsm_status lsm_corner_apply(lsm_geom *b1, lsm_geom *b2, const lsm_corner_result *r)
{
    if (b1 == NULL || b2 == NULL || r == NULL)
        return LSM_E_NULL;
    if (r->trim1_mm >= b1->len || r->trim2_mm >= b2->len)
        return LSM_E_RANGE;
    lsm_status st = lsm_geom_trim_end(b1, r->trim1_mm);
    if (st == LSM_OK)
        st = lsm_geom_trim_start(b2, r->trim2_mm);
    return st;
}
