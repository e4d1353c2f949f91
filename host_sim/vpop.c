/* vpop.c: VPOp-style reference planner (see vpop.h). */
#include "vpop.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct vctx {
    const sim_vpop_path *p;
    const sim_vpop_limits *lim;
    double dt;
    double h;          /* grid step of the search (mm) */
    sim_vpop_stats *st;
} vctx;

/* History of the last three steps: s and positions. */
typedef struct hist {
    double s[3];                 /* s_j, s_j-1, s_j-2 */
    double q[3][SIM_VPOP_AXES];
} hist;

static void eval(const vctx *c, double s, double q[SIM_VPOP_AXES])
{
    memset(q, 0, sizeof(double) * SIM_VPOP_AXES);
    c->p->eval(c->p->ctx, s, q);
    c->st->evals++;
}

/* Largest violation of the step's bounds at s (<= 0: feasible). */
static double viol(const vctx *c, const double lo[SIM_VPOP_AXES], const double hi[SIM_VPOP_AXES], double s)
{
    double q[SIM_VPOP_AXES];
    eval(c, s, q);
    double w = -INFINITY;
    for (int i = 0; i < SIM_VPOP_AXES; i++) {
        if (!(c->lim->axis_mask & (1u << i)))
            continue;
        const double a = q[i] - hi[i], b = lo[i] - q[i];
        if (a > w)
            w = a;
        if (b > w)
            w = b;
    }
    return w;
}

/*
 * The feasible s for the next step after history h: *smin, *smax. want: 1 = s_max only, 2 = s_min only, 3 = both.
 * Returns 0 if the set is empty.
 */
static int next_set(const vctx *c, const hist *h, int want, double *smin, double *smax)
{
    const sim_vpop_limits *L = c->lim;
    const double dt = c->dt;
    double lo[SIM_VPOP_AXES], hi[SIM_VPOP_AXES];
    for (int i = 0; i < SIM_VPOP_AXES; i++) {
        const double q0 = h->q[0][i], q1 = h->q[1][i], q2 = h->q[2][i];
        double l = q0 - L->v[i] * dt, u = q0 + L->v[i] * dt;
        const double pa = 2 * q0 - q1, pj = 3 * q0 - 3 * q1 + q2;
        l = fmax(l, pa - L->a[i] * dt * dt);
        u = fmin(u, pa + L->a[i] * dt * dt);
        l = fmax(l, pj - L->j[i] * dt * dt * dt);
        u = fmin(u, pj + L->j[i] * dt * dt * dt);
        lo[i] = l;
        hi[i] = u;
        if ((L->axis_mask & (1u << i)) && l > u)
            return 0;
    }
    const double s0 = h->s[0];
    double top = c->p->length;
    if (c->p->feed) {
        const double f = c->p->feed(c->p->ctx, s0);
        if (s0 + f * dt < top)
            top = s0 + f * dt;
    }
    if (!(top > s0)) {
        if (viol(c, lo, hi, s0) <= 0) {
            *smin = *smax = s0;
            return 1;
        }
        return 0;
    }
    /* the search grid: step h (finer than the jerk window), over [s0, top]; the scans start near the zero-jerk
     * prediction s* = 3 s0 - 3 s1 + s2 and fall back to the whole range */
    const double step = c->h;
    const double pred = 3 * h->s[0] - 3 * h->s[1] + h->s[2];
    const double W = 64 * step;
    if (want & 1) { /* s_max: from above down to the first feasible point, then refined upwards */
        double x = fmin(top, pred + W);
        if (x < s0)
            x = s0;
        int found = 0;
        if (viol(c, lo, hi, x) <= 0) {
            found = 1; /* feasible at the start: walk up */
            while (x < top) {
                const double y = fmin(top, x + step);
                if (viol(c, lo, hi, y) > 0)
                    break;
                x = y;
            }
        } else {
            for (double y = x - step;; y -= step) {
                if (y < s0)
                    y = s0;
                if (viol(c, lo, hi, y) <= 0) {
                    x = y;
                    found = 1;
                    break;
                }
                if (y <= s0)
                    break;
            }
            if (!found) { /* nothing below the start: the part above it */
                for (double y = fmin(top, pred + W) + step; y <= top + 0.5 * step; y += step) {
                    if (viol(c, lo, hi, fmin(y, top)) <= 0) {
                        x = fmin(y, top);
                        found = 1;
                        while (x < top) {
                            const double z = fmin(top, x + step);
                            if (viol(c, lo, hi, z) > 0)
                                break;
                            x = z;
                        }
                        break;
                    }
                }
            }
        }
        if (!found)
            return 0;
        if (x >= top) {
            *smax = top;
        } else {
            double a = x, b = fmin(top, x + step);
            for (int it = 0; it < 60 && b - a > 1e-13 * (1 + fabs(b)); it++) {
                const double m = 0.5 * (a + b);
                if (viol(c, lo, hi, m) <= 0)
                    a = m;
                else
                    b = m;
            }
            *smax = a;
        }
    }
    if (want & 2) { /* s_min: from below up to the first feasible point, then refined downwards */
        double x = fmax(s0, pred - W);
        if (x > top)
            x = top;
        int found = 0;
        if (viol(c, lo, hi, x) <= 0) {
            found = 1;
            while (x > s0) {
                const double y = fmax(s0, x - step);
                if (viol(c, lo, hi, y) > 0)
                    break;
                x = y;
            }
        } else {
            for (double y = x + step;; y += step) {
                if (y > top)
                    y = top;
                if (viol(c, lo, hi, y) <= 0) {
                    x = y;
                    found = 1;
                    break;
                }
                if (y >= top)
                    break;
            }
            if (!found) {
                for (double y = fmax(s0, pred - W) - step; y >= s0 - 0.5 * step; y -= step) {
                    if (viol(c, lo, hi, fmax(y, s0)) <= 0) {
                        x = fmax(y, s0);
                        found = 1;
                        while (x > s0) {
                            const double z = fmax(s0, x - step);
                            if (viol(c, lo, hi, z) > 0)
                                break;
                            x = z;
                        }
                        break;
                    }
                }
            }
        }
        if (!found)
            return 0;
        if (x <= s0) {
            *smin = s0;
        } else {
            double a = fmax(s0, x - step), b = x;
            for (int it = 0; it < 60 && b - a > 1e-13 * (1 + fabs(b)); it++) {
                const double m = 0.5 * (a + b);
                if (viol(c, lo, hi, m) <= 0)
                    b = m;
                else
                    a = m;
            }
            *smin = b;
        }
    }
    return 1;
}

static void push(const vctx *c, hist *h, double s)
{
    h->s[2] = h->s[1];
    h->s[1] = h->s[0];
    h->s[0] = s;
    memcpy(h->q[2], h->q[1], sizeof h->q[1]);
    memcpy(h->q[1], h->q[0], sizeof h->q[0]);
    eval(c, s, h->q[0]);
}

/* History ending at index k of S (S[-1] = S[-2] = S[-3] = 0: at rest before the start). */
static void hist_at(const vctx *c, const double *S, long k, hist *h)
{
    for (int m = 0; m < 3; m++) {
        const double s = (k - m) >= 0 ? S[k - m] : 0.0;
        h->s[m] = s;
        eval(c, s, h->q[m]);
    }
}

/* From the history at index k-1, take s_min from step k on: does the speed reach 0 (without an empty set)? */
static int brake_ok(const vctx *c, const double *S, long k)
{
    hist h;
    hist_at(c, S, k - 1, &h);
    c->st->tests++;
    for (long n = 0; n < 100000; n++) {
        double smin, smax;
        if (!next_set(c, &h, 2, &smin, &smax))
            return 0;
        const double ds = smin - h.s[0];
        push(c, &h, smin);
        if (ds <= 1e-12 * (1 + fabs(smin)))
            return 1;
    }
    return 0;
}

int sim_vpop_plan(const sim_vpop_path *p, const sim_vpop_limits *lim, double dt, size_t max_steps, double **s_out,
                  size_t *n_out, sim_vpop_stats *st)
{
    sim_vpop_stats dummy;
    if (!st)
        st = &dummy;
    memset(st, 0, sizeof *st);
    *s_out = NULL;
    *n_out = 0;
    vctx c = {p, lim, dt, 0, st};
    double jmin = INFINITY;
    for (int i = 0; i < SIM_VPOP_AXES; i++)
        if ((lim->axis_mask & (1u << i)) && lim->j[i] < jmin)
            jmin = lim->j[i];
    c.h = jmin * dt * dt * dt / 4;
    size_t cap = 4096;
    double *S = calloc(cap, sizeof *S);
    if (!S)
        return -1;
    long n = 0;            /* S[0 .. n-1] planned */
    long last_brake = 0;   /* the dichotomy searches from here */
    hist h;
    hist_at(&c, S, -1, &h);
    const double L = p->length;
    while ((size_t)n < max_steps) {
        if (n >= 3 && S[n - 1] >= L && S[n - 2] >= L && S[n - 3] >= L)
            break; /* at rest on the end */
        double smin, smax;
        if (next_set(&c, &h, 1, &smin, &smax)) {
            if ((size_t)n == cap) {
                cap *= 2;
                double *ns = realloc(S, cap * sizeof *S);
                if (!ns) {
                    free(S);
                    return -1;
                }
                S = ns;
            }
            S[n++] = smax;
            push(&c, &h, smax);
            continue;
        }
        /* empty: the latest step k in [last_brake, n-1] from which braking all the way works */
        st->backtracks++;
        if (getenv("VPOP_DEBUG"))
            fprintf(stderr, "backtrack %zu at n %ld s %.6f last_brake %ld evals %zu\n", st->backtracks, n, S[n - 1],
                    last_brake, st->evals);
        long lo = last_brake, hi = n - 1;
        while (lo > 0 && !brake_ok(&c, S, lo))
            lo = lo / 2;
        if (lo == 0 && !brake_ok(&c, S, 0)) {
            free(S);
            return -1;
        }
        while (hi > lo) {
            const long mid = (lo + hi + 1) / 2;
            if (brake_ok(&c, S, mid))
                lo = mid;
            else
                hi = mid - 1;
        }
        /* s_min at step lo, then s_max again */
        hist_at(&c, S, lo - 1, &h);
        double a, b;
        if (!next_set(&c, &h, 2, &a, &b)) {
            free(S);
            return -1;
        }
        n = lo;
        S[n++] = a;
        push(&c, &h, a);
        last_brake = n;
    }
    /* drop the repeated rest samples at the end but one */
    while (n >= 2 && S[n - 2] >= L)
        n--;
    st->steps = (size_t)n;
    *s_out = S;
    *n_out = (size_t)n;
    return 0;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* B-spline helper                                                                                             */

static int span_of(const sim_bspline *b, double u)
{
    const int n = b->n_ctrl - 1, p = b->degree;
    if (u >= b->knots[n + 1])
        return n;
    int lo = p, hi = n + 1;
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (u < b->knots[mid])
            hi = mid;
        else
            lo = mid;
    }
    return lo;
}

/* de Boor: point and first derivative */
static void deboor(const sim_bspline *b, double u, double xy[2], double d[2])
{
    const int p = b->degree, k = span_of(b, u);
    double P[8][2];
    for (int j = 0; j <= p; j++) {
        P[j][0] = b->ctrl[k - p + j][0];
        P[j][1] = b->ctrl[k - p + j][1];
    }
    double Q[8][2]; /* derivative control points (degree p-1) */
    for (int j = 0; j < p; j++) {
        const int i = k - p + j + 1;
        const double den = b->knots[i + p] - b->knots[i];
        const double f = den > 0 ? p / den : 0;
        Q[j][0] = f * (P[j + 1][0] - P[j][0]);
        Q[j][1] = f * (P[j + 1][1] - P[j][1]);
    }
    for (int r = 1; r <= p; r++)
        for (int j = p; j >= r; j--) {
            const int i = k - p + j;
            const double den = b->knots[i + p - r + 1] - b->knots[i];
            const double a = den > 0 ? (u - b->knots[i]) / den : 0;
            P[j][0] = (1 - a) * P[j - 1][0] + a * P[j][0];
            P[j][1] = (1 - a) * P[j - 1][1] + a * P[j][1];
        }
    xy[0] = P[p][0];
    xy[1] = P[p][1];
    if (d) {
        for (int r = 1; r <= p - 1; r++)
            for (int j = p - 1; j >= r; j--) {
                const int i = k - p + 1 + j;
                const double den = b->knots[i + p - 1 - r + 1] - b->knots[i];
                const double a = den > 0 ? (u - b->knots[i]) / den : 0;
                Q[j][0] = (1 - a) * Q[j - 1][0] + a * Q[j][0];
                Q[j][1] = (1 - a) * Q[j - 1][1] + a * Q[j][1];
            }
        d[0] = Q[p - 1][0];
        d[1] = Q[p - 1][1];
    }
}

void sim_bspline_point(const sim_bspline *b, double u, double xy[2])
{
    deboor(b, u, xy, NULL);
}

static double speed_u(const sim_bspline *b, double u)
{
    double xy[2], d[2];
    deboor(b, u, xy, d);
    return sqrt(d[0] * d[0] + d[1] * d[1]);
}

int sim_bspline_init(sim_bspline *b, int degree, int n_ctrl, const double *knots, const double (*ctrl)[2],
                     double feed_mm_s, int n_tab)
{
    memset(b, 0, sizeof *b);
    if (degree < 1 || degree > 7 || n_ctrl < degree + 1 || n_ctrl > 16 || n_tab < 16)
        return -1;
    b->degree = degree;
    b->n_ctrl = n_ctrl;
    for (int i = 0; i < n_ctrl + degree + 1; i++)
        b->knots[i] = knots[i];
    for (int i = 0; i < n_ctrl; i++) {
        b->ctrl[i][0] = ctrl[i][0];
        b->ctrl[i][1] = ctrl[i][1];
    }
    b->feed = feed_mm_s;
    b->n_tab = n_tab;
    b->tab_u = malloc((size_t)(n_tab + 1) * sizeof(double));
    b->tab_s = malloc((size_t)(n_tab + 1) * sizeof(double));
    if (!b->tab_u || !b->tab_s)
        return -1;
    /* 5-point Gauss-Legendre per interval */
    static const double gx[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
    static const double gw[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                 0.2369268850561891};
    double s = 0;
    b->tab_u[0] = 0;
    b->tab_s[0] = 0;
    for (int i = 0; i < n_tab; i++) {
        const double u0 = (double)i / n_tab, u1 = (double)(i + 1) / n_tab;
        double acc = 0;
        for (int g = 0; g < 5; g++)
            acc += gw[g] * speed_u(b, 0.5 * (u0 + u1) + 0.5 * (u1 - u0) * gx[g]);
        s += acc * 0.5 * (u1 - u0);
        b->tab_u[i + 1] = u1;
        b->tab_s[i + 1] = s;
    }
    b->length = s;
    return 0;
}

void sim_bspline_free(sim_bspline *b)
{
    free(b->tab_u);
    free(b->tab_s);
    b->tab_u = b->tab_s = NULL;
}

void sim_bspline_eval_s(void *ctx, double s, double q[SIM_VPOP_AXES])
{
    const sim_bspline *b = ctx;
    if (s <= 0)
        s = 0;
    if (s >= b->length)
        s = b->length;
    int lo = 0, hi = b->n_tab;
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (b->tab_s[mid] <= s)
            lo = mid;
        else
            hi = mid;
    }
    /* cubic Hermite of u(s) on the interval, du/ds = 1 / |C'(u)| at its ends: a smooth parametrisation */
    const double s0 = b->tab_s[lo], s1 = b->tab_s[hi], u0 = b->tab_u[lo], u1 = b->tab_u[hi];
    const double hs = s1 - s0;
    double u = u0;
    if (hs > 0) {
        const double t = (s - s0) / hs;
        const double d0 = hs / speed_u(b, u0), d1 = hs / speed_u(b, u1);
        const double t2 = t * t, t3 = t2 * t;
        u = (2 * t3 - 3 * t2 + 1) * u0 + (t3 - 2 * t2 + t) * d0 + (-2 * t3 + 3 * t2) * u1 + (t3 - t2) * d1;
    }
    double xy[2];
    deboor(b, u < 0 ? 0 : u > 1 ? 1 : u, xy, NULL);
    q[0] = xy[0];
    q[1] = xy[1];
}

double sim_bspline_feed(void *ctx, double s)
{
    (void)s;
    return ((const sim_bspline *)ctx)->feed;
}
