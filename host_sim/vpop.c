/* vpop.c: VPOp-style reference planner (see vpop.h). */
#include "vpop.h"

#include "json.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct vctx {
    const sim_vpop_path *p;
    const sim_vpop_limits *lim;
    double dt;
    double h;   /* J_min dt³ / 4 (mm): the jerk window scale (search margins, whole-range scan step) */
    double jt;  /* tangential jerk bound for the stop test: the smallest axis jerk limit */
    double jn;  /* |(J_x, J_y, J_z)| if only linear axes are constrained (s bounds from the chord), else 0 */
    double tol; /* the searches locate the ends of the feasible set to this (mm) */
    sim_vpop_stats *st;
} vctx;

/* History of the last three steps: s and positions. */
typedef struct hist {
    double s[3]; /* s_j, s_j-1, s_j-2 */
    double q[3][SIM_VPOP_AXES];
} hist;

static void eval(const vctx *c, double s, double q[SIM_VPOP_AXES])
{
    memset(q, 0, sizeof(double) * SIM_VPOP_AXES);
    c->p->eval(c->p->ctx, s, q);
    c->st->evals++;
}

/* Positions and dq/ds at s. */
static void eval_d(const vctx *c, double s, double q[SIM_VPOP_AXES], double d[SIM_VPOP_AXES])
{
    memset(q, 0, sizeof(double) * SIM_VPOP_AXES);
    memset(d, 0, sizeof(double) * SIM_VPOP_AXES);
    if (c->p->eval_d) {
        c->p->eval_d(c->p->ctx, s, q, d);
        c->st->evals++;
        return;
    }
    const double e = 1e-6, a = fmax(0.0, s - e), b = fmin(c->p->length, s + e);
    double qa[SIM_VPOP_AXES], qb[SIM_VPOP_AXES];
    eval(c, s, q);
    eval(c, a, qa);
    eval(c, b, qb);
    if (b > a)
        for (int i = 0; i < SIM_VPOP_AXES; i++)
            d[i] = (qb[i] - qa[i]) / (b - a);
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

/* The bounds of one step: lo[i] <= q_i(s) <= hi[i] for every constrained axis, s0 <= s <= top. */
typedef struct stepb {
    double lo[SIM_VPOP_AXES], hi[SIM_VPOP_AXES];
    double s0, top, pred;
    double slo; /* no s below this is feasible (the chord bound; s0 if none) */
} stepb;

/* Returns 0 if an axis's bounds are already empty. */
static int step_bounds(const vctx *c, const hist *h, stepb *b)
{
    const sim_vpop_limits *L = c->lim;
    const double dt = c->dt;
    const double jdt3 = dt * dt * dt;
    int ok = 1;
    for (int i = 0; i < SIM_VPOP_AXES; i++) {
        const double q0 = h->q[0][i], q1 = h->q[1][i], q2 = h->q[2][i];
        double l = q0 - L->v[i] * dt, u = q0 + L->v[i] * dt;
        const double pa = 2 * q0 - q1, pj = 3 * q0 - 3 * q1 + q2;
        l = fmax(l, pa - L->a[i] * dt * dt);
        u = fmin(u, pa + L->a[i] * dt * dt);
        l = fmax(l, pj - L->j[i] * jdt3);
        u = fmin(u, pj + L->j[i] * jdt3);
        b->lo[i] = l;
        b->hi[i] = u;
        if ((L->axis_mask & (1u << i)) && l > u)
            ok = 0;
    }
    b->s0 = h->s[0];
    b->top = c->p->length;
    if (c->p->feed) {
        /* the feed at s0, lowered to the feed where the step would end if that is lower (a step into a slower
         * block is not faster than that block's feed) */
        double f = c->p->feed(c->p->ctx, b->s0);
        for (int it = 0; it < 4 && b->s0 + f * dt < b->top; it++) {
            const double g = c->p->feed(c->p->ctx, b->s0 + f * dt);
            if (!(g < f))
                break;
            f = g;
        }
        if (b->s0 + f * dt < b->top)
            b->top = b->s0 + f * dt;
    }
    if (c->p->next_stop) {
        double sp = c->p->next_stop(c->p->ctx, b->s0);
        if (sp <= b->s0 && h->s[1] == b->s0 && h->s[2] == b->s0) /* at rest on the stop: go on to the next */
            sp = c->p->next_stop(c->p->ctx, nextafter(b->s0, HUGE_VAL));
        if (sp < b->top)
            b->top = fmax(sp, b->s0);
    }
    b->pred = 3 * h->s[0] - 3 * h->s[1] + h->s[2];
    b->slo = b->s0;
    if (c->jn > 0) {
        /* linear axes only (s is their arc length): the chord q(s) - q0 differs from the zero-jerk one
         * 2 q0 - 3 q1 + q2 by at most |J| dt³, and arc >= chord, so s >= s0 + |P| - |J| dt³; and an arc is within
         * 10 % of its chord unless it turns by more than ~1.5 rad in one step, so s <= s0 + 1.1 (|P| + |J| dt³) */
        double p2 = 0;
        for (int i = 0; i < 3; i++) {
            const double d = 2 * h->q[0][i] - 3 * h->q[1][i] + h->q[2][i];
            p2 += d * d;
        }
        const double P = sqrt(p2), jw = c->jn * dt * dt * dt;
        if (P > jw)
            b->slo = fmin(b->top, b->s0 + (P - jw) * (1 - 1e-9));
        const double up = b->s0 + 1.1 * (P + jw) + 8 * c->h;
        if (up < b->top)
            b->top = up;
    }
    return ok;
}

/*
 * The bounds linearised at x (q_i(s) ~ q_i(x) + q_i'(x) (s - x)): the interval [*A, *B] of s they allow. Returns 0
 * if it is empty (or an axis with no slope at x is out of its bounds).
 */
static int lin_set(const vctx *c, const stepb *b, double x, double *A, double *B)
{
    double q[SIM_VPOP_AXES], d[SIM_VPOP_AXES];
    eval_d(c, x, q, d);
    double lo = b->slo, hi = b->top;
    for (int i = 0; i < SIM_VPOP_AXES; i++) {
        if (!(c->lim->axis_mask & (1u << i)))
            continue;
        const double t = d[i];
        if (fabs(t) < 1e-12) {
            if (q[i] < b->lo[i] || q[i] > b->hi[i])
                return 0;
            continue;
        }
        double u1 = x + (b->lo[i] - q[i]) / t, u2 = x + (b->hi[i] - q[i]) / t;
        if (t < 0) {
            const double w = u1;
            u1 = u2;
            u2 = w;
        }
        if (u1 > lo)
            lo = u1;
        if (u2 < hi)
            hi = u2;
    }
    *A = lo;
    *B = hi;
    return lo <= hi;
}

/*
 * Newton on the end of the feasible set (dir +1: s_max, -1: s_min), from the zero-jerk prediction: x <- the end
 * of the linearised set at x. The answer is a point checked against the exact bounds (backing off inwards by
 * tol, 2 tol, 4 tol ... if the converged end is outside by rounding). Returns 0 if it does not converge to a
 * feasible point (the caller falls back to the grid scan).
 */
static int fast_end(const vctx *c, const stepb *b, int dir, double *out)
{
    const double edge = dir > 0 ? b->top : b->slo;
    if (viol(c, b->lo, b->hi, edge) <= 0) {
        *out = edge;
        return 1;
    }
    double x = fmin(b->top, fmax(b->slo, b->pred));
    int conv = 0;
    for (int it = 0; it < 12; it++) {
        double A, B;
        if (!lin_set(c, b, x, &A, &B))
            return 0;
        const double y = dir > 0 ? B : A;
        const double dx = y - x;
        x = y;
        if (fabs(dx) <= c->tol) {
            conv = 1;
            break;
        }
    }
    if (!conv)
        return 0;
    double back = 0;
    for (int k = 0; k < 30; k++) {
        const double y = x - dir * back;
        if (y < b->slo || y > b->top)
            return 0;
        if (viol(c, b->lo, b->hi, y) <= 0) {
            *out = y;
            return 1;
        }
        back = back > 0 ? 2 * back : c->tol;
    }
    return 0;
}

/*
 * Grid scan of [w0, w1] (n intervals) for feasible points; the first and last are refined by bisection against
 * their infeasible neighbours. Returns 0 if no grid point is feasible.
 */
static int scan_window(const vctx *c, const stepb *b, double w0, double w1, int n, int want, double *smin, double *smax)
{
    const double st = (w1 - w0) / n;
    int first = -1, last = -1;
    for (int k = 0; k <= n; k++) {
        const double x = k == n ? w1 : w0 + st * k;
        if (viol(c, b->lo, b->hi, x) <= 0) {
            if (first < 0)
                first = k;
            last = k;
        }
    }
    if (first < 0)
        return 0;
    if (want & 1) {
        double a = last == n ? w1 : w0 + st * last, z = last == n ? w1 : w0 + st * (last + 1);
        if (last == n && w1 < b->top) /* feasible at the window's end: continue upwards */
            for (z = fmin(b->top, a + st); viol(c, b->lo, b->hi, z) <= 0 && z < b->top; z = fmin(b->top, z + st))
                a = z;
        if (z > a && viol(c, b->lo, b->hi, z) <= 0)
            a = z;
        for (int it = 0; it < 80 && z - a > c->tol; it++) {
            const double m = 0.5 * (a + z);
            if (viol(c, b->lo, b->hi, m) <= 0)
                a = m;
            else
                z = m;
        }
        *smax = a;
    }
    if (want & 2) {
        double z = first == 0 ? w0 : w0 + st * first, a = first == 0 ? w0 : w0 + st * (first - 1);
        if (first == 0 && w0 > b->slo)
            for (a = fmax(b->slo, z - st); viol(c, b->lo, b->hi, a) <= 0 && a > b->slo; a = fmax(b->slo, a - st))
                z = a;
        if (a < z && viol(c, b->lo, b->hi, a) <= 0)
            z = a;
        for (int it = 0; it < 80 && z - a > c->tol; it++) {
            const double m = 0.5 * (a + z);
            if (viol(c, b->lo, b->hi, m) <= 0)
                z = m;
            else
                a = m;
        }
        *smin = z;
    }
    return 1;
}

/*
 * When Newton fails: every feasible s has the dominant axis k (largest |dq_k/ds|, monotone over one step) within
 * its bounds, so the set lies in the window where q_k(s) is in [lo_k, hi_k] (its ends found by Newton on q_k
 * alone), widened by a margin; that window is scanned. With no dominant axis, the whole range is scanned on a grid
 * finer than the jerk window.
 */
static int fallback(const vctx *c, const stepb *b, int want, double *smin, double *smax)
{
    c->st->fallbacks++;
    const double x = fmin(b->top, fmax(b->slo, b->pred));
    double q[SIM_VPOP_AXES], d[SIM_VPOP_AXES];
    eval_d(c, x, q, d);
    int k = -1;
    for (int i = 0; i < SIM_VPOP_AXES; i++)
        if ((c->lim->axis_mask & (1u << i)) && (k < 0 || fabs(d[i]) > fabs(d[k])))
            k = i;
    if (k < 0 || fabs(d[k]) < 0.05) {
        const double span = b->top - b->slo;
        const int n = (int)fmin(200000.0, ceil(span / c->h));
        return scan_window(c, b, b->slo, b->top, n < 1 ? 1 : n, want, smin, smax);
    }
    double e[2];
    for (int m = 0; m < 2; m++) {
        const double target = m ? b->hi[k] : b->lo[k];
        double y = x;
        for (int it = 0; it < 8; it++) {
            double qq[SIM_VPOP_AXES], dd[SIM_VPOP_AXES];
            eval_d(c, y, qq, dd);
            if (fabs(dd[k]) < 1e-3)
                break;
            const double ny = fmin(b->top + 1.0, fmax(b->slo - 1.0, y - (qq[k] - target) / dd[k]));
            const double dy = ny - y;
            y = ny;
            if (fabs(dy) <= c->tol)
                break;
        }
        e[m] = y;
    }
    double w0 = fmin(e[0], e[1]), w1 = fmax(e[0], e[1]);
    const double margin = 0.25 * (w1 - w0) + 4 * c->h;
    w0 = fmax(b->slo, w0 - margin);
    w1 = fmin(b->top, w1 + margin);
    if (w1 < w0)
        return 0;
    return scan_window(c, b, w0, w1, 48, want, smin, smax);
}

/* The candidate s after history h passes the continuous check (vpop.h: step_cont; 1 if there is none). */
static int cont_ok(const vctx *c, const hist *h, double s)
{
    if (!c->p->step_cont)
        return 1;
    const double s4[4] = {h->s[2], h->s[1], h->s[0], s};
    c->st->cont_checks++;
    return c->p->step_cont(c->p->ctx, c->lim, c->dt, s4);
}

/* s is a feasible next step after h: within the step's range, the discrete bounds and the continuous check. */
static int step_pass(const vctx *c, const hist *h, const stepb *b, double s)
{
    return s >= b->s0 && s <= b->top && viol(c, b->lo, b->hi, s) <= 0 && cont_ok(c, h, s);
}

#define CONT_GRID 8       /* points tried across the discrete set when its end fails the continuous check */
#define CONT_BISECT 60    /* then bisection (to the search tolerance) between the first that passes and its neighbour */
#define CONT_REL_TOL 1e-5 /* ... or to this share of the step (s - s_j): finer changes nothing measurable */

/* The end of the discrete set [smin, smax] (dir +1: smax, -1: smin) moved inwards to the last point that also passes
 * the continuous check: smax itself if it passes, else the first of CONT_GRID points towards the other end that
 * passes, refined by bisection against its failing neighbour. Returns 0 if none passes (the set counts as empty). */
static int cont_end(const vctx *c, const hist *h, const stepb *b, double smin, double smax, int dir, double *out)
{
    const double from = dir > 0 ? smax : smin, to = dir > 0 ? smin : smax;
    if (step_pass(c, h, b, from)) {
        *out = from;
        return 1;
    }
    double fail = from;
    for (int k = 1; k <= CONT_GRID; k++) {
        const double x = k == CONT_GRID ? to : from + (to - from) * k / CONT_GRID;
        if (!step_pass(c, h, b, x)) {
            fail = x;
            continue;
        }
        double ok = x;
        const double tol = fmax(c->tol, CONT_REL_TOL * fabs(from - b->s0));
        for (int it = 0; it < CONT_BISECT && fabs(fail - ok) > tol; it++) {
            const double m = 0.5 * (ok + fail);
            if (step_pass(c, h, b, m))
                ok = m;
            else
                fail = m;
        }
        *out = ok;
        return 1;
    }
    return 0;
}

/* The ends of the discrete set after h (want as next_set) into *lo, *hi. Returns 0 if it is empty. */
static int discrete_ends(const vctx *c, const stepb *b, int want, double *lo, double *hi)
{
    if (!(b->top > b->slo)) {
        if (!(viol(c, b->lo, b->hi, b->slo) <= 0))
            return 0;
        *lo = *hi = b->slo;
        return 1;
    }
    int ok = 1;
    if (want & 1)
        ok = fast_end(c, b, 1, hi);
    if (ok && (want & 2))
        ok = fast_end(c, b, -1, lo);
    return ok || fallback(c, b, want, lo, hi);
}

/* The feasible s for the next step after history h: *smin, *smax (want: 1 = s_max only, 2 = s_min only, 3 =
 * both). The linearised search; if it fails, the dominant-axis window scan. With cont and a continuous check
 * (vpop.h: step_cont), the wanted ends of the discrete set are then moved inwards to the last points that pass it
 * (cont_end; the other end is found when it is needed). Returns 0 if the set is empty. */
static int next_set_c(const vctx *c, const hist *h, int want, int cont, double *smin, double *smax)
{
    stepb b;
    if (!step_bounds(c, h, &b))
        return 0;
    double lo = 0, hi = 0;
    if (!discrete_ends(c, &b, want, &lo, &hi))
        return 0;
    if (cont && c->p->step_cont) {
        int have = want;
        if ((want & 1) && !step_pass(c, h, &b, hi)) {
            if (!(have & 2) && !discrete_ends(c, &b, 2, &lo, &hi))
                return 0;
            have |= 2;
            if (!cont_end(c, h, &b, lo, hi, 1, &hi))
                return 0;
        }
        if ((want & 2) && !step_pass(c, h, &b, lo)) {
            if (!(have & 1) && !discrete_ends(c, &b, 1, &lo, &hi))
                return 0;
            if (!cont_end(c, h, &b, lo, hi, -1, &lo))
                return 0;
        }
    }
    if (want & 1)
        *smax = hi;
    if (want & 2)
        *smin = lo;
    return 1;
}

static int next_set(const vctx *c, const hist *h, int want, double *smin, double *smax)
{
    return next_set_c(c, h, want, 1, smin, smax);
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

/* Brakes from history h with the point beta of the way from s_min to s_max at every step; 1 if it comes to rest
 * (two steps without motion) without an empty set. */
static int brake_step(const vctx *c, const hist *h, double beta, double *sel);

static int brake_seq(const vctx *c, hist h, double beta)
{
    int still = 0;
    for (long n = 0; n < 20000; n++) {
        double sel;
        if (!brake_step(c, &h, beta, &sel))
            return 0;
        const double ds = sel - h.s[0];
        push(c, &h, sel);
        still = ds <= 1e-12 * (1 + fabs(sel)) ? still + 1 : 0;
        if (still >= 2)
            return 1;
    }
    return 0;
}

/*
 * From the history at index k-1, brake from step k on: does the machine come to rest without an empty set? The
 * paper's test takes s_min at every step; that bang braking stops with the deceleration still in the history, a
 * dead end when the next set is empty (it is, e.g., on the trident's tips), so softer sequences are tried too.
 */
/* Braking sequences tried, in order: beta < 0 is the time-optimal stop of a jerk-limited point on the tangent (as
 * hard as possible while the speed still covers the deceleration's release, v >= a² / (2 J)), with J the jerk of a
 * straight line in the local direction (-1) or the smallest axis jerk limit (-2, gentler); beta >= 0 takes the
 * point beta of the way from s_min to the constant-speed step. The first that comes to rest certifies the step.
 * Which sequences are tried changes the result (by a few %: VPOp is a heuristic, not the optimum). */
#define N_BETAS 4
static const double k_betas[N_BETAS] = {-1.0, -2.0, 0.5, 0.25};

/* Returns 1 + the index of the braking sequence that works, or 0. */
static int brake_ok(const vctx *c, const double *S, long k)
{
    hist h;
    hist_at(c, S, k - 1, &h);
    c->st->tests++;
    for (int i = 0; i < N_BETAS; i++)
        if (brake_seq(c, h, k_betas[i]))
            return i + 1;
    return 0;
}

/* With a continuous check, a braking sequence's choice *sel between smin and smax (both pass it) may fail it: then
 * it becomes the last point from smin towards it that passes (bisection). Returns 1. */
static int cont_sel(const vctx *c, const hist *h, double smin, double *sel)
{
    if (!c->p->step_cont || *sel <= smin || cont_ok(c, h, *sel))
        return 1;
    double ok = smin, fail = *sel;
    const double tol = fmax(c->tol, CONT_REL_TOL * fabs(fail - h->s[0]));
    for (int it = 0; it < CONT_BISECT && fail - ok > tol; it++) {
        const double m = 0.5 * (ok + fail);
        if (cont_ok(c, h, m))
            ok = m;
        else
            fail = m;
    }
    *sel = ok;
    return 1;
}

/* The choice of the braking sequence beta after history h, on the discrete set (cont 0) or on the set whose ends pass
 * the continuous check (cont 1, moved towards s_min until it passes). */
static int brake_choice(const vctx *c, const hist *h, double beta, int cont, double *sel);

/* One step of the braking sequence beta from history h (the choice brake_seq makes). With a continuous check, the
 * choice is first made on the discrete set and kept if it passes; else it is made again with cont (brake_choice). */
static int brake_step(const vctx *c, const hist *h, double beta, double *sel)
{
    if (c->p->step_cont && brake_choice(c, h, beta, 0, sel) && cont_ok(c, h, *sel))
        return 1;
    return brake_choice(c, h, beta, 1, sel);
}

static int brake_choice(const vctx *c, const hist *h, double beta, int cont, double *sel)
{
    double smin, smax;
    if (!next_set_c(c, h, 3, cont, &smin, &smax))
        return 0;
    const double dt = c->dt, v = (h->s[0] - h->s[1]) / dt;
    if (beta >= 0) {
        const double cap = h->s[0] + v * dt; /* not faster than the last step */
        *sel = smin + beta * (fmin(smax, fmax(cap, smin)) - smin);
        return !cont || cont_sel(c, h, smin, sel);
    }
    /* the smallest s whose (v', a') can still stop cleanly: v' >= a'² / (2 J) when a' < 0, with J the tangential
     * jerk a straight line in the local direction allows, min_i J_i / |dq_i/ds| */
    double J = HUGE_VAL;
    if (beta < -1.5) {
        J = c->jt;
    } else {
        double q[SIM_VPOP_AXES], d[SIM_VPOP_AXES];
        eval_d(c, h->s[0], q, d);
        for (int i = 0; i < SIM_VPOP_AXES; i++)
            if ((c->lim->axis_mask & (1u << i)) && fabs(d[i]) > 1e-9)
                J = fmin(J, c->lim->j[i] / fabs(d[i]));
        if (!(J < HUGE_VAL))
            J = c->jt;
    }
    double lo = smin, hi = smax;
    const double s = lo;
    const double v1 = (s - h->s[0]) / dt, a1 = (v1 - v) / dt;
    if (!(a1 < 0 && v1 < a1 * a1 / (2 * J))) {
        *sel = s;
        return 1;
    }
    for (int it = 0; it < 50 && hi - lo > 1e-13 * (1 + fabs(hi)); it++) {
        const double m = 0.5 * (lo + hi);
        const double vm = (m - h->s[0]) / dt, am = (vm - v) / dt;
        if (am < 0 && vm < am * am / (2 * J))
            lo = m;
        else
            hi = m;
    }
    *sel = hi;
    return !cont || cont_sel(c, h, smin, sel);
}

/* Is s feasible as the next step after h, and does some braking sequence come to rest from there? */
static int step_ok(const vctx *c, const hist *h, double s)
{
    stepb b;
    if (!step_bounds(c, h, &b) || !step_pass(c, h, &b, s))
        return 0;
    hist g = *h;
    push(c, &g, s);
    for (int i = 0; i < N_BETAS; i++)
        if (brake_seq(c, g, k_betas[i]))
            return 1;
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
    vctx c = {p, lim, dt, 0, 0, 0, 0, st};
    double jmin = INFINITY;
    for (int i = 0; i < SIM_VPOP_AXES; i++)
        if ((lim->axis_mask & (1u << i)) && lim->j[i] < jmin)
            jmin = lim->j[i];
    c.h = jmin * dt * dt * dt / 4;
    c.jt = jmin;
    if (!(lim->axis_mask & 0x38))
        c.jn = sqrt(lim->j[0] * lim->j[0] * !!(lim->axis_mask & 1) + lim->j[1] * lim->j[1] * !!(lim->axis_mask & 2) +
                    lim->j[2] * lim->j[2] * !!(lim->axis_mask & 4));
    c.tol = fmax(1e-7 * jmin * dt * dt * dt, 1e-14 * (1 + p->length));
    size_t cap = 4096;
    double *S = calloc(cap, sizeof *S);
    if (!S)
        return -1;
    long n = 0;          /* S[0 .. n-1] planned */
    long last_brake = 0; /* the dichotomy searches from here */
    int cert_beta = 1;   /* the braking sequence certified at last_brake (at rest at the start: any) */
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
        /* empty: the latest step k in [last_brake, n-1] from which braking all the way works (dichotomy); if
         * there is none, go on with the braking certified at last_brake (this always progresses) */
        st->backtracks++;
        if (st->backtracks == 1)
            st->first_fail = n + 1;
        if (getenv("VPOP_DEBUG"))
            fprintf(stderr, "backtrack %zu at n %ld s %.9f %.9f %.9f last_brake %ld evals %zu\n", st->backtracks, n,
                    S[n - 1], n > 1 ? S[n - 2] : 0, n > 2 ? S[n - 3] : 0, last_brake, st->evals);
        long k = last_brake;
        int cert = brake_ok(&c, S, last_brake);
        if (cert) {
            long lo = last_brake, hi = n - 1;
            while (hi > lo) {
                const long mid = (lo + hi + 1) / 2;
                if (st->backtracks == 1 && st->n_first_tests < 32)
                    st->first_tests[st->n_first_tests++] = mid + 1;
                const int r = brake_ok(&c, S, mid);
                if (r) {
                    lo = mid;
                    cert = r;
                } else {
                    hi = mid - 1;
                }
            }
            k = lo;
        } else {
            cert = cert_beta;
        }
        hist_at(&c, S, k - 1, &h);
        double sel;
        if (!brake_step(&c, &h, k_betas[cert - 1], &sel)) {
            free(S);
            return -1;
        }
        /* The switching step: the braking sequence's first step is certified; lim->refine_iters > 0 bisects for
         * the largest step in [that, s_max] from which some braking sequence still comes to rest (a later, faster
         * switch). Always done (60 iterations) when the braking step makes (almost) no progress: typically at
         * rest, where braking stays while s_max leads to a dead end (one jerk-limited step from rest reaches L or
         * a stop, and nothing can follow it); from rest a small enough step always certifies. */
        const int iters = sel - h.s[0] <= 1e-3 * c.h ? 60 : lim->refine_iters;
        if (iters > 0) {
            double lo = sel, hi = lo, a, b;
            if (next_set(&c, &h, 1, &a, &b))
                hi = b;
            for (int it = 0; it < iters && hi - lo > c.tol; it++) {
                const double m = 0.5 * (lo + hi);
                if (step_ok(&c, &h, m))
                    lo = m;
                else
                    hi = m;
            }
            sel = lo;
        }
        if (st->backtracks == 1)
            st->first_brake = k + 1;
        n = k;
        S[n++] = sel;
        push(&c, &h, sel);
        last_brake = n;
        cert_beta = cert;
    }
    if (!(n >= 3 && S[n - 1] >= L && S[n - 2] >= L && S[n - 3] >= L)) { /* max_steps reached before rest on L */
        free(S);
        return -1;
    }
    /* drop the repeated rest samples at the end but one */
    while (n >= 2 && S[n - 2] >= L)
        n--;
    st->steps = (size_t)n;
    if (getenv("VPOP_DEBUG"))
        fprintf(stderr,
                "vpop: %zu steps, %zu evals, %zu backtracks, %zu brake tests, %zu fallbacks, %zu continuous checks\n",
                st->steps, st->evals, st->backtracks, st->tests, st->fallbacks, st->cont_checks);
    *s_out = S;
    *n_out = (size_t)n;
    return 0;
}

void sim_vpop_measure(const sim_vpop_path *p, const double *S, size_t n, double dt, double v[SIM_VPOP_AXES],
                      double a[SIM_VPOP_AXES], double j[SIM_VPOP_AXES])
{
    double q[4][SIM_VPOP_AXES]; /* q[0] newest */
    memset(q, 0, sizeof q);
    p->eval(p->ctx, 0.0, q[1]);
    memcpy(q[2], q[1], sizeof q[1]);
    memcpy(q[3], q[1], sizeof q[1]);
    for (int i = 0; i < SIM_VPOP_AXES; i++)
        v[i] = a[i] = j[i] = 0;
    for (size_t k = 0; n > 0 && k < n + 3; k++) {
        memset(q[0], 0, sizeof q[0]);
        p->eval(p->ctx, S[k < n ? k : n - 1], q[0]);
        for (int i = 0; i < SIM_VPOP_AXES; i++) {
            v[i] = fmax(v[i], fabs(q[0][i] - q[1][i]) / dt);
            a[i] = fmax(a[i], fabs(q[0][i] - 2 * q[1][i] + q[2][i]) / (dt * dt));
            j[i] = fmax(j[i], fabs(q[0][i] - 3 * q[1][i] + 3 * q[2][i] - q[3][i]) / (dt * dt * dt));
        }
        memmove(q[1], q[0], 3 * sizeof q[0]);
    }
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
    b->tab_v = malloc((size_t)(n_tab + 1) * sizeof(double));
    if (!b->tab_u || !b->tab_s || !b->tab_v) {
        sim_bspline_free(b);
        return -1;
    }
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
    for (int i = 0; i <= n_tab; i++)
        b->tab_v[i] = speed_u(b, b->tab_u[i]);
    return 0;
}

void sim_bspline_free(sim_bspline *b)
{
    free(b->tab_u);
    free(b->tab_s);
    free(b->tab_v);
    b->tab_u = b->tab_s = b->tab_v = NULL;
}

void sim_bspline_eval_sd(void *ctx, double s, double q[SIM_VPOP_AXES], double dq[SIM_VPOP_AXES])
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
    /* cubic Hermite of u(s) on the interval, du/ds = 1 / |C'(u)| at its ends: a C1 parametrisation (any smooth
     * parametrisation serves: the setpoints are points of the curve, s is only the search variable) */
    const double s0 = b->tab_s[lo], s1 = b->tab_s[hi], u0 = b->tab_u[lo], u1 = b->tab_u[hi];
    const double hs = s1 - s0;
    double u = u0;
    if (hs > 0) {
        const double t = (s - s0) / hs;
        const double d0 = hs / b->tab_v[lo], d1 = hs / b->tab_v[hi];
        const double t2 = t * t, t3 = t2 * t;
        u = (2 * t3 - 3 * t2 + 1) * u0 + (t3 - 2 * t2 + t) * d0 + (-2 * t3 + 3 * t2) * u1 + (t3 - t2) * d1;
    }
    double xy[2], d[2];
    deboor(b, u < 0 ? 0 : u > 1 ? 1 : u, xy, dq ? d : NULL);
    q[0] = xy[0];
    q[1] = xy[1];
    if (dq) {
        const double n = sqrt(d[0] * d[0] + d[1] * d[1]);
        dq[0] = n > 0 ? d[0] / n : 0;
        dq[1] = n > 0 ? d[1] / n : 0;
    }
}

void sim_bspline_eval_s(void *ctx, double s, double q[SIM_VPOP_AXES])
{
    sim_bspline_eval_sd(ctx, s, q, NULL);
}

sim_vpop_path sim_bspline_path(sim_bspline *b)
{
    sim_vpop_path p = {b->length, sim_bspline_eval_s, sim_bspline_feed, b, sim_bspline_eval_sd, NULL, NULL};
    return p;
}

static int num_array(const char *text, const sim_json_tok *t, int a, double *out, int max)
{
    if (a < 0 || t[a].type != SIM_JSON_ARRAY || t[a].size > max)
        return -1;
    int n = 0;
    for (int e = a + 1, i = 0; i < t[a].size; i++, e = t[e].next)
        if (sim_json_number(text, &t[e], &out[n++]) != 0)
            return -1;
    return n;
}

int sim_bspline_load(const char *path, sim_bspline *b, int n_tab, char *err, size_t errlen)
{
    memset(b, 0, sizeof *b);
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open", path);
        return -1;
    }
    char text[16384];
    const size_t len = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[len] = '\0';
    sim_json_tok t[512];
    sim_json_error je;
    if (sim_json_parse(text, len, t, 512, &je) < 0) {
        snprintf(err, errlen, "%s:%d:%d: %s", path, je.line, je.column, je.msg);
        return -1;
    }
    double deg = 0, feed = 0, knots[32];
    int kd = sim_json_find(text, t, 0, "degree"), kf = sim_json_find(text, t, 0, "programmed_feed_mm_min");
    int nk = num_array(text, t, sim_json_find(text, t, 0, "knots"), knots, 32);
    int kc = sim_json_find(text, t, 0, "control_points_mm");
    if (kd < 0 || kf < 0 || nk < 0 || kc < 0 || t[kc].type != SIM_JSON_ARRAY || t[kc].size > 16 ||
        sim_json_number(text, &t[kd], &deg) != 0 || sim_json_number(text, &t[kf], &feed) != 0 || !(feed > 0)) {
        snprintf(err, errlen, "%s: needs degree, knots, control_points_mm (at most 16) and programmed_feed_mm_min",
                 path);
        return -1;
    }
    double ctrl[16][2];
    int nc = 0;
    for (int e = kc + 1, i = 0; i < t[kc].size; i++, e = t[e].next) {
        double xy[2];
        if (num_array(text, t, e, xy, 2) != 2) {
            snprintf(err, errlen, "%s: control point %d is not [x, y]", path, i);
            return -1;
        }
        ctrl[nc][0] = xy[0];
        ctrl[nc][1] = xy[1];
        nc++;
    }
    if (deg != floor(deg) || nk != nc + (int)deg + 1) {
        snprintf(err, errlen, "%s: %d knots for %d control points of degree %g (want n + p + 1)", path, nk, nc, deg);
        return -1;
    }
    if (sim_bspline_init(b, (int)deg, nc, knots, (const double(*)[2])ctrl, feed / 60.0, n_tab) != 0) {
        snprintf(err, errlen, "%s: bad B-spline", path);
        return -1;
    }
    return 0;
}

double sim_bspline_feed(void *ctx, double s)
{
    (void)s;
    return ((const sim_bspline *)ctx)->feed;
}
