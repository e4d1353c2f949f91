/* plan_piece.c: the forward step: the piece from the interpolator's point to the next node at the best feed
 * (planner.h, "Look-ahead invariants"), staircases, feed hold, and the check of the commitment horizon. */
#include <string.h>

#include "planner_int.h"

/* Staircases (staircase()): only for a rise above STAIR_MIN_RISE times v0 (plus STAIR_MIN_RISE_ABS mm/s from rest);
 * not when ramp A already starts at once with STAIR_UNSLOWED of its block's limits at rest (nothing slowed it);
 * levels at STAIR_LEVEL_RATIO of the rise, then of that, down to a step of STAIR_MIN_STEP of v0; taken only when it
 * gains more than STAIR_MIN_GAIN_CYCLES cycles (less is within the quantisation of the ramps). */
#define STAIR_MIN_RISE LSM_R(1.2)
#define STAIR_MIN_RISE_ABS LSM_R(1e-6)
#define STAIR_UNSLOWED LSM_R(0.9)
#define STAIR_LEVEL_RATIO LSM_R(0.6)
#define STAIR_MIN_STEP LSM_R(0.02)
#define STAIR_MIN_GAIN_CYCLES LSM_R(2.0)
/* A staircase candidate is skipped before it is planned when even its bound on the gain (stair_may_gain) falls short
 * by more than this slack: half a cycle, plus a relative share of the times for their rounding. */
#define STAIR_PRUNE_SLACK_CYCLES LSM_R(0.5)
#define STAIR_PRUNE_SLACK_REL LSM_R(1e-4)

/* ------------------------------------------------------------------------------------------------------------ */
/* pieces                                                                                                       */

typedef struct plan5 {
    bool step; /* ramp A is one step of a staircase (the interpolator re-plans at its end) */
    lsm_real v0, vc, v1;
    ramp A, B;
    lsm_real xA, xB; /* ramp starts (piece-relative); lead cruise [0, xA], cruise [xA + A.dist, xB],
                         trail cruise [xB + B.dist, D] */
    lsm_real slack;  /* the room feas5 measured between the ramps (a guide for the cruise search, never a result):
                        the cruise length, or, when ramp B did not fit after ramp A, about how much room it lacked
                        (< 0); 0: not measured (something else decided) */
} plan5;

static void no_ramp(ramp *r, lsm_real dt, lsm_real v)
{
    lsm_pl_ramp_plan(r, dt, v, v, R1, R1, R1);
}

/* Ramp A from v0 to vc, placed as early as it verifies at or after X0 (a lead cruise at v0 before it). */
static bool place_A(pctx *pc, lsm_real v0, lsm_real vc, plan5 *p, bool catchup, lsm_real X0)
{
    const lsm_real dt = pc->pl->cfg.cycle_s, D = pc->D;
    p->xA = R0;
    if (vc == v0) {
        no_ramp(&p->A, dt, v0);
        return true;
    }
    if (vc < v0) {
        if (!catchup)
            return false;
        return lsm_pl_fit_decel_now(pc, R0, D, v0, vc, &p->A);
    }
    if (X0 > R0 && !lsm_pl_region_ok(pc, R0, X0, v0))
        return false;
    return lsm_pl_fit_accel(pc, X0, D, v0, vc, false, &p->A, &p->xA);
}

/* Ramp B (vc -> v1) as late as it verifies after ramp A, and the cruise between them. */
static bool place_B(pctx *pc, plan5 *p, bool exact)
{
    const lsm_real dt = pc->pl->cfg.cycle_s, D = pc->D;
    const lsm_real xa_end = p->xA + p->A.dist;
    if (p->vc > p->v1) {
        if (!lsm_pl_fit_decel(pc, xa_end, D, p->vc, p->v1, exact, false, &p->B, &p->xB)) {
            p->slack = lsm_min2(D - p->B.dist - xa_end, R0); /* (its last try; room left: something else failed it) */
            return false;
        }
    } else {
        no_ramp(&p->B, dt, p->vc);
        p->xB = D;
    }
    p->slack = p->xB - xa_end;
    if (p->slack < -LEN_EPS * (R1 + D))
        return false;
    if (p->slack < R0) {
        p->xB = xa_end;
        p->slack = R0;
    }
    return true;
}

/* The whole piece for cruise feed vc: ramp A as early as it verifies, ramp B as late, the cruise between. Ramp A is
 * placed for itself; where a cap below vc follows it (a dip that the lead cruise at v0 could pass, e.g. the corner
 * a piece starts at), ramp A moves after that dip, once (else the whole piece ran at v0). */
static bool feas5_first_A(pctx *pc, lsm_real v0, lsm_real vc, lsm_real v1, bool catchup, plan5 *p)
{
    p->v0 = v0;
    p->vc = vc;
    p->v1 = v1;
    p->slack = R0;
    return vc > R0 && place_A(pc, v0, vc, p, catchup, R0);
}

/* The rest of feas5 once its first ramp A is placed (feas5_first_A). */
static bool feas5_rest(pctx *pc, bool exact, bool catchup, plan5 *p)
{
    const lsm_real v0 = p->v0, vc = p->vc;
    if (!place_B(pc, p, exact))
        return false;
    lsm_real xa_end = p->xA + p->A.dist;
    if (lsm_pl_region_ok(pc, xa_end, p->xB, vc))
        return true;
    p->slack = R0;  /* (a cap, not the room, failed it) */
    lsm_real x_dip; /* (from rest there is no lead cruise: a ramp from v0 = 0 starts where the piece starts) */
    if (catchup || !(v0 > R0) || !(vc > v0) || !lsm_pl_last_below(pc, xa_end, p->xB, vc, &x_dip))
        return false;
    if (!place_A(pc, v0, vc, p, false, x_dip) || !place_B(pc, p, exact))
        return false;
    xa_end = p->xA + p->A.dist;
    if (lsm_pl_region_ok(pc, xa_end, p->xB, vc))
        return true;
    p->slack = R0;
    return false;
}

static bool feas5(pctx *pc, lsm_real v0, lsm_real vc, lsm_real v1, bool exact, bool catchup, plan5 *p)
{
    return feas5_first_A(pc, v0, vc, v1, catchup, p) && feas5_rest(pc, exact, catchup, p);
}

static void put_ramp(lsm_piece *pc, int at, const ramp *r, lsm_real dt)
{
    lsm_phase ph[7];
    lsm_scurve_phases(&r->iv, r->jp, ph);
    for (int i = 0; i < 7; i++) {
        lsm_piece_phase *q = &pc->ph[at + i];
        q->n_cycles = ph[i].n_cycles;
        q->T_s = (lsm_real)ph[i].n_cycles * dt;
        q->shape = ph[i].shape;
        q->jerk_mm_s3 = ph[i].jerk_mm_s3;
    }
}

static void put_cruise(lsm_piece *pc, int at, lsm_real len, lsm_real v)
{
    lsm_piece_phase *q = &pc->ph[at];
    q->n_cycles = 0;
    q->shape = LSM_PHASE_CONST;
    q->jerk_mm_s3 = R0;
    q->len_mm = len > R0 && v > R0 ? len : R0;
    q->T_s = q->len_mm > R0 ? q->len_mm / v : R0;
}

static void fill_piece(const lsm_planner *pl, const pctx *ctx, const plan5 *p, lsm_real end_x, lsm_piece *out)
{
    const lsm_real dt = pl->cfg.cycle_s;
    memset(out, 0, sizeof *out);
    out->blk = ctx->id0;
    out->off_mm = ctx->off0;
    out->v0_mm_s = p->v0;
    out->v1_mm_s = p->v1;
    out->vc_mm_s = p->vc;
    out->end_blk = ctx->id_end;
    out->stop = p->v1 > R0 ? 0u : 1u;
    out->step = p->step ? 1u : 0u;
    const lsm_real xa_end = p->xA + p->A.dist, xb_end = p->xB + p->B.dist;
    put_cruise(out, 0, p->xA, p->v0);
    put_ramp(out, 1, &p->A, dt);
    put_cruise(out, 8, p->xB - xa_end, p->vc);
    put_ramp(out, 9, &p->B, dt);
    put_cruise(out, 16, end_x - xb_end, p->v1);
    /* phase start states and the travel of every ramp phase (exact boundary values, no trigonometry) */
    lsm_kin k = {R0, p->v0, R0, R0};
    lsm_real T = R0;
    for (int i = 0; i < LSM_PIECE_PHASES; i++) {
        lsm_piece_phase *q = &out->ph[i];
        out->st[i] = k;
        out->st[i].j_mm_s3 = R0;
        if (i == 0 || i == 8 || i == 16) { /* cruises run at exactly their feed */
            const lsm_real v = i == 0 ? p->v0 : i == 8 ? p->vc : p->v1;
            if (i > 0) /* up to where the next ramp (or the end) is planned: the phases add up to the piece */
                put_cruise(out, i, (i == 8 ? p->xB : end_x) - k.s_mm, v);
            out->st[i].v_mm_s = v;
            out->st[i].a_mm_s2 = R0;
            k.v_mm_s = v;
            k.a_mm_s2 = R0;
            k.s_mm += q->len_mm;
        } else if (q->n_cycles) {
            const lsm_phase ph = {q->n_cycles, q->shape, q->jerk_mm_s3};
            lsm_kin e;
            lsm_phase_end(&ph, dt, &out->st[i], &e);
            q->len_mm = e.s_mm - out->st[i].s_mm;
            k = e;
        }
        T += q->T_s;
    }
    /* the ramps' ends carry rounding: the cruises start exactly where they are planned */
    out->len_mm = end_x;
    out->T_s = T;
}

/* The node after block `after` (exclusive) and its W; tail: the end of the buffer (W = 0). */
uint32_t lsm_pl_node_after(const lsm_planner *pl, uint32_t after, lsm_real *w)
{
    for (uint32_t id = after + 1u;; id++) {
        if (id == pl->tail) {
            *w = R0;
            return id;
        }
        const lsm_pblock *b = blk(pl, id);
        if (b->flags & LSM_PB_STOP) {
            *w = R0;
            return id;
        }
        if (b->flags & LSM_PB_NODE) {
            *w = b->w_mm_s;
            return id;
        }
    }
}

/* Fallback when no verified piece was found (should not happen; counted): stop as soon as possible with a verified
 * ramp, anywhere ahead; the next piece starts from rest. */
static lsm_status fallback(lsm_planner *pl, pctx *pc, lsm_real v0, lsm_piece *out)
{
    pl->stats.plan_fallbacks++;
    plan5 p;
    memset(&p, 0, sizeof p);
    const lsm_real dt = pl->cfg.cycle_s;
    p.v0 = p.vc = v0;
    p.v1 = R0;
    no_ramp(&p.A, dt, v0);
    no_ramp(&p.B, dt, v0);
    if (v0 > R0) {
        pctx all;
        lsm_pl_pctx_init(&all, pl, pc->id0, pc->off0, pl->tail);
        all.floor = v0;
        if (lsm_pl_fit_decel_now(&all, R0, all.D, v0, R0, &p.B)) {
            fill_piece(pl, &all, &p, p.B.dist, out);
            out->hold = 1; /* ends anywhere */
            return LSM_E_INTERNAL;
        }
    }
    fill_piece(pl, pc, &p, R0, out);
    out->stop = 1;
    out->hold = 1;
    out->T_s = R0;
    return LSM_E_INTERNAL;
}

static bool plan_normal(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, pctx *pcp, plan5 *bestp,
                        uint32_t *reach);

/* Time from the piece start to x (>= the end of ramp A, <= the start of ramp B) along p. */
static lsm_real time_to(const plan5 *p, lsm_real dt, lsm_real x)
{
    const lsm_real xa_end = p->xA + p->A.dist;
    lsm_real t = (lsm_real)lsm_scurve_total_cycles(&p->A.iv) * dt;
    if (p->xA > R0 && p->v0 > R0)
        t += p->xA / p->v0;
    if (x > xa_end && p->vc > R0)
        t += (x - xa_end) / p->vc;
    return t;
}

/* Time of the whole piece p of length D. */
static lsm_real plan_time(const plan5 *p, lsm_real dt, lsm_real D)
{
    lsm_real t = time_to(p, dt, p->xB) + (lsm_real)lsm_scurve_total_cycles(&p->B.iv) * dt;
    const lsm_real xb_end = p->xB + p->B.dist;
    if (D > xb_end && p->v1 > R0)
        t += (D - xb_end) / p->v1;
    return t;
}

/* The piece from the end of a step at vc (sub) with the highest cruise in [vc, vmax] that verifies (bisection), in
 * *q; false if not even a cruise at vc verifies. */
static bool best_after_step(pctx *sub, lsm_real vc, lsm_real vmax, lsm_real v1, bool exact, plan5 *q)
{
    if (feas5(sub, vc, vmax, lsm_min2(v1, vmax), exact, false, q))
        return true;
    plan5 t;
    if (!feas5(sub, vc, vc, lsm_min2(v1, vc), exact, false, q))
        return false;
    lsm_real l = vc, u = vmax;
    for (int it = 0; it < VC_BISECT && u - l > SPEED_RES * u; it++) {
        const lsm_real mid = (l + u) / LSM_R(2.0);
        if (feas5(sub, vc, mid, lsm_min2(v1, mid), exact, false, &t)) {
            *q = t;
            l = mid;
        } else {
            u = mid;
        }
    }
    return true;
}

/* The highest tangential a, j and snap of any verified ramp on the piece: a ramp passes its check only where its
 * peaks are within the budgets of every block it crosses (plan_ramp.c, check_span), and each budget is at most the
 * block's at rest (1 / alpha_a, 1 / alpha_j, 1 / alpha_s: the speed terms only take from it). A block with a
 * coefficient 0 does not bound that quantity: it is then unbounded (0 here). */
typedef struct ramp_tops {
    lsm_real a, j, s; /* 0: unbounded */
} ramp_tops;

static lsm_real top_of(lsm_real coef_max_inv, bool unbounded)
{
    return unbounded || !(coef_max_inv > R0) ? R0 : R1 / coef_max_inv;
}

static void piece_tops(const pctx *pc, ramp_tops *t)
{
    lsm_real aa = LSM_REAL_MAX, aj = LSM_REAL_MAX, as = LSM_REAL_MAX; /* the smallest coefficients */
    for (uint32_t id = pc->id0; id != pc->id_end; id++) {
        coef c;
        coef_get(blk(pc->pl, id), &c);
        aa = lsm_min2(aa, c.aa);
        aj = lsm_min2(aj, c.aj);
        as = lsm_min2(as, c.as);
    }
    t->a = top_of(aa, aa == LSM_REAL_MAX);
    t->j = top_of(aj, aj == LSM_REAL_MAX);
    t->s = top_of(as, as == LSM_REAL_MAX);
}

/* A lower bound of the time of a velocity change by dv that starts and ends with a = j = 0 within the peaks t
 * (a ramp): dv <= a T; dv <= j T² / 4 (|a| <= j min(t, T - t)); dv <= s T³ / 24 (|j| <= s min(t, T - t) and
 * dv = the integral of (T/2 - t) j dt). */
static lsm_real ramp_time_min(lsm_real dv, const ramp_tops *t)
{
    lsm_real T = R0;
    if (!(dv > R0))
        return T;
    if (t->a > R0)
        T = lsm_max2(T, dv / t->a);
    if (t->j > R0)
        T = lsm_max2(T, LSM_R(2.0) * lsm_sqrt(dv / t->j));
    if (t->s > R0)
        T = lsm_max2(T, lsm_cbrt(LSM_R(24.0) * dv / t->s));
    return T;
}

/* The least time a ramp u -> w (u < w <= vmax) loses against travelling its distance at vmax: T (2 vmax - u - w) /
 * (2 vmax), its distance being (u + w) T / 2. */
static lsm_real ramp_loss_min(lsm_real u, lsm_real w, lsm_real vmax, const ramp_tops *t)
{
    return ramp_time_min(w - u, t) * (LSM_R(2.0) * vmax - u - w) / (LSM_R(2.0) * vmax);
}

/* Could a staircase whose gain is at most `bound` beat `need`? The bound holds in exact arithmetic (every speed of
 * a candidate is at most vmax, and a sin² ramp's time is 2 dist / (v_a + v_b) >= dist / vmax); the slack covers
 * the rounding of the times (t: their size) and of the positions (x: the length compared, an exact end within
 * LEN_EPS of it), so that a candidate skipped here would also have been rejected after planning it. */
static bool stair_may_gain(lsm_real bound, lsm_real need, lsm_real dt, lsm_real t, lsm_real x, lsm_real vmax)
{
    const lsm_real slack = STAIR_PRUNE_SLACK_CYCLES * dt + STAIR_PRUNE_SLACK_REL * lsm_fabs(t) +
                           LSM_R(4.0) * LEN_EPS * (R1 + lsm_fabs(x)) / vmax;
    return bound + slack > need;
}

/* One staircase candidate: a first ramp v0 -> vc, then, re-planned from its end, a second one up to best's cruise.
 * Taken into *found when it reaches that cruise (or the end of best's ramp A, xe) sooner than best by more than
 * *gain. With to_end, the second piece is the best one from the end of the first ramp (it need not reach best's
 * cruise) and the two are compared over the whole piece. */
static void try_step(pctx *pc, const ramp_tops *tops, const plan5 *best, lsm_real vc, bool exact, bool to_end,
                     lsm_real *gain, plan5 *found, bool *have)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    const lsm_real v0 = best->v0, vmax = best->vc, xe = best->xA + best->A.dist;
    const lsm_real need = *gain + STAIR_MIN_GAIN_CYCLES * dt; /* the gain to beat */
    /* best's time to where it is compared (xe, or the end of the piece): no candidate can gain more than what best
     * loses there against running at vmax all the way, less what the candidate's own ramps lose at least (the
     * first step v0 -> vc; without to_end also the second ramp vc -> vmax, which ends before xe) */
    const lsm_real t_best = to_end ? plan_time(best, dt, pc->D) : time_to(best, dt, xe);
    const lsm_real x_cmp = to_end ? pc->D : xe;
    const lsm_real loss2 = to_end ? R0 : ramp_loss_min(vc, vmax, vmax, tops);
    const lsm_real loss1 = ramp_loss_min(v0, vc, vmax, tops);
    if (!stair_may_gain(t_best - x_cmp / vmax - loss1 - loss2, need, dt, t_best, x_cmp, vmax))
        return;
    plan5 p, q;
    /* the first step's ramp A alone first: ramp B is planned only when the gain bound with that ramp A may still
     * win, or when a cap below vc after it (lsm_pl_region_ok fails) would make feas5_rest move ramp A after a dip */
    if (!feas5_first_A(pc, v0, vc, lsm_min2(best->v1, vc), false, &p))
        return;
    {
        const lsm_real x1 = p.xA + p.A.dist, t1 = time_to(&p, dt, x1);
        if (!(x1 < best->xB &&
              stair_may_gain(t_best - t1 - (x_cmp - x1) / vmax - loss2, need, dt, t_best + t1, x_cmp, vmax)) &&
            lsm_pl_region_ok(pc, x1, pc->D, vc))
            return;
    }
    if (!feas5_rest(pc, exact, false, &p))
        return;
    const lsm_real x1 = p.xA + p.A.dist;
    if (!(x1 < best->xB))
        return;
    /* with the first step known: the second piece needs at least (x_cmp - x1) / vmax */
    const lsm_real t1 = time_to(&p, dt, x1);
    if (!stair_may_gain(t_best - t1 - (x_cmp - x1) / vmax - loss2, need, dt, t_best + t1, x_cmp, vmax))
        return;
    /* the second ramp, from the end of the first one */
    lsm_pl_seek(pc, x1);
    pctx sub;
    lsm_pl_pctx_init(&sub, pc->pl, pc->cid, x1 - pc->cx, pc->id_end);
    if (!(sub.D > LEN_EPS * (R1 + sub.D)))
        return;
    lsm_real g;
    if (to_end) {
        if (!best_after_step(&sub, vc, vmax, best->v1, exact, &q))
            return;
        g = plan_time(best, dt, pc->D) - (time_to(&p, dt, x1) + plan_time(&q, dt, sub.D));
    } else {
        if (!feas5(&sub, vc, vmax, lsm_min2(best->v1, vmax), exact, false, &q))
            return;
        const lsm_real x2 = x1 + q.xA + q.A.dist;
        const lsm_real X = lsm_max2(x2, xe);
        if (!(X <= best->xB) || !(X - x1 <= q.xB))
            return;
        g = time_to(best, dt, X) - (time_to(&p, dt, x1) + time_to(&q, dt, X - x1));
    }
    if (g > *gain + STAIR_MIN_GAIN_CYCLES * dt) {
        *gain = g;
        *found = p;
        *have = true;
    }
}

/*
 * One sin² ramp from v0 to the highest cruise must fit every block it crosses: where it starts in a slow,
 * curved stretch (out of a valley), that stretch lowers its acceleration and jerk for the whole ramp, or delays
 * its start (a lead cruise at v0). A staircase may be faster: a lower ramp first, then, re-planned at its end
 * (a = 0 there, lsm_piece.step), a second one up to the same cruise. Levels tried: geometric levels from the top,
 * and, where best has a lead cruise at v0, the caps that stretch allows (its suffix minima: a plateau between a
 * slow start and a fast end, which the geometric levels miss when it lies far below the top, ran at v0). For each
 * level the second ramp is planned too (try_step), and the staircase is taken when it reaches the highest cruise
 * (or the end of the first plan's ramp; from a cap level, the end of the piece) sooner than the single ramp.
 */
static void staircase(pctx *pc, plan5 *best)
{
    const lsm_real v0 = best->v0, vmax = best->vc;
    if (!(vmax > v0 * STAIR_MIN_RISE + STAIR_MIN_RISE_ABS) || best->xB < best->xA + best->A.dist)
        return;
    /* a ramp A that starts at once with (nearly) the limits of its first block at rest was not slowed: no lower
     * step can reach the cruise sooner */
    lsm_real na, nj, ns;
    lsm_pl_guess_limits(pc, R0, &na, &nj, &ns);
    if (!(best->xA > R0) && best->A.a_lim >= STAIR_UNSLOWED * na && best->A.j_lim >= STAIR_UNSLOWED * nj)
        return;
    const bool exact = !(best->v1 > R0);
    ramp_tops tops;
    piece_tops(pc, &tops);
    lsm_real gain = R0;
    plan5 found;
    memset(&found, 0, sizeof found);
    bool have = false;
    const lsm_real k = STAIR_LEVEL_RATIO;
    lsm_real dv = (vmax - v0) * k;
    for (int it = 0; it < STAIR_LEVELS; it++, dv *= k) {
        const lsm_real vc = v0 + dv;
        if (!(vc > v0 * (R1 + STAIR_MIN_STEP)))
            break;
        try_step(pc, &tops, best, vc, exact, false, &gain, &found, &have);
    }
    if (best->xA > R0) {
        /* the caps of the lead cruise, from its end back to the start: each new lower minimum is a level */
        const lsm_planner *pl = pc->pl;
        lsm_pl_seek(pc, best->xA);
        lsm_real m = vmax;
        int levels = 0;
        for (uint32_t id = pc->cid; levels < STAIR_LEVELS; id--) {
            const lsm_real c = cap_floor(pl, id, blk(pl, id), pc->floor);
            if (c < m) {
                m = c;
                if (!(m > v0 * (R1 + STAIR_MIN_STEP)))
                    break;
                try_step(pc, &tops, best, m, exact, true, &gain, &found, &have);
                levels++;
            }
            if (id == pc->id0)
                break;
        }
    }
    if (have) {
        found.step = true;
        *best = found;
    }
}

/*
 * The piece memo. The interpolator often asks for a piece it asked for before: it prepares the successor of its
 * piece (from the piece's end), an append changes the plan (pl->gen), it re-plans the rest of its piece from a sample
 * in the cruise (a REPLAN, taken: it ends where the piece did, at the same speed), and then prepares the successor
 * again, from the same point at the same speed (the dense M4 benchmark: 85 of its 392 searches). The search
 * (plan_normal) is a function of its inputs (id0, off0, v0), of the blocks it reads (geometry, feed, cap,
 * coefficients, flags, W), of the override and the configuration, and of where the buffer ends if it meets it:
 * nothing else (the position cursor of each pctx starts afresh, and the search keeps no state between calls). It
 * reads no block at or after `reach` (search_reach). So while no block before reach was written, and neither the
 * override nor the configuration changed, the same call finds the same plan, and the piece built from it
 * (fill_piece, deterministic) is the same bit for bit. Every write to a block goes through lsm_pl_changed (a new
 * block at the tail, the trim of the last block, the backward pass from the first node it changed on: bp_stop + 1, or
 * all of them when it walked the whole buffer), an override change through lsm_pl_changed_all, and
 * lsm_planner_init clears the memo; the head moving on (blocks released) changes no block still held, and a call
 * whose start was released is refused before the memo is asked. Only NORMAL searches are kept (a REPLAN between the
 * two would replace the successor's), but a REPLAN takes a kept piece: the same search, which succeeded.
 * tests/plan/test_plan_memo.c runs random programs with and without the memo and compares every piece and setpoint.
 */
/* The same input bit for bit (+0 and -0 are one value, not one input). */
static bool same_bits(lsm_real a, lsm_real b)
{
#if LSM_REAL_IS_FLOAT
    uint32_t x, y;
#else
    uint64_t x, y;
#endif
    memcpy(&x, &a, sizeof a);
    memcpy(&y, &b, sizeof b);
    return x == y;
}

_Static_assert(sizeof(plan5) == LSM_PLANNER_MEMO_PLAN_BYTES, "lsm_planner_memo.plan holds one plan5");

/* Keeps the plan p the search found for the call (id0, off0, v0), keyed on the call itself. */
static void memo_put(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, const pctx *pc, const plan5 *p,
                     uint32_t reach)
{
    lsm_planner_memo *m = &pl->memo;
    if (m->off)
        return;
    m->id0 = id0;
    m->off0_mm = off0;
    m->v0_mm_s = v0;
    m->reach = reach;
    m->end_blk = pc->id_end;
    m->len_mm = pc->D;
    memcpy(m->plan, p, sizeof *p);
    m->ok = 1;
}

/* The kept plan for (id0, off0, v0) into *p, and what fill_piece reads of its pctx into *pc; false: none. */
static bool memo_get(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, pctx *pc, plan5 *p)
{
    const lsm_planner_memo *m = &pl->memo;
    if (!m->ok || m->off || m->id0 != id0 || !same_bits(m->off0_mm, off0) || !same_bits(m->v0_mm_s, v0))
        return false;
    memcpy(p, m->plan, sizeof *p);
    memset(pc, 0, sizeof *pc);
    pc->id0 = id0;
    pc->off0 = off0;
    pc->id_end = m->end_blk;
    pc->D = m->len_mm;
    pl->stats.pieces_kept++;
    return true;
}

lsm_status lsm_planner_plan_piece(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, lsm_piece_mode mode,
                                  lsm_piece *out)
{
    if (pl == NULL || out == NULL)
        return LSM_E_NULL;
    lsm_planner_apply_requests(pl); /* the tick's requests first (planner.h) */
    if (id_lt(id0, pl->head) || !id_lt(id0, pl->tail))
        return LSM_E_EMPTY;
    const lsm_real dt = pl->cfg.cycle_s;
    plan5 p;
    memset(&p, 0, sizeof p);
    if (mode == LSM_PIECE_HOLD) {
        /* within the path up to the next exact stop (a corner the machine cannot pass at speed) */
        uint32_t id_end = id0 + 1u;
        while (id_end != pl->tail && !(blk(pl, id_end)->flags & LSM_PB_STOP))
            id_end++;
        pctx pc;
        lsm_pl_pctx_init(&pc, pl, id0, off0, id_end);
        p.v0 = p.vc = v0;
        p.v1 = R0;
        no_ramp(&p.A, dt, v0);
        no_ramp(&p.B, dt, v0);
        if (v0 > R0 && !lsm_pl_fit_decel_now(&pc, R0, pc.D, v0, R0, &p.B))
            return LSM_E_INFEASIBLE;
        fill_piece(pl, &pc, &p, p.B.dist, out);
        out->hold = 1;
        pl->stats.pieces++;
        return LSM_OK;
    }
    if (off0 >= blk(pl, id0)->g.len && id0 + 1u == pl->tail)
        return LSM_E_EMPTY;
    pctx pc;
    plan5 best;
    uint32_t reach;
    if (!memo_get(pl, id0, off0, v0, &pc, &best)) {
        if (!plan_normal(pl, id0, off0, v0, &pc, &best, &reach))
            return mode == LSM_PIECE_REPLAN ? LSM_E_INFEASIBLE : fallback(pl, &pc, v0, out);
        if (mode == LSM_PIECE_NORMAL)
            memo_put(pl, id0, off0, v0, &pc, &best, reach);
    }
    fill_piece(pl, &pc, &best, pc.D, out);
    pl->stats.pieces++;
    return LSM_OK;
}

/* Forward search of plan_normal: the tuning numbers. */
/* Nodes tried from the interpolator's point: a node that appeared ahead since the speed was committed cannot trap
 * it (each further one puts the dip of the one before inside the piece, verified pointwise); a few suffice. */
#define NODE_CANDIDATES 5
/* A piece shorter than this many cycles of travel would start and end inside one control cycle, too soon for the
 * next one to be planned in the background: pass 0 plans across such a valley node. */
#define SHORT_PIECE_CYCLES LSM_R(1.5)
/* Override catch-up: cruise targets tried from the cap here down towards v1, each this share of the way closer. */
#define CATCHUP_TRIES 24
#define CATCHUP_SHRINK LSM_R(0.7)
/* Extra bisection steps when a lower cruise below dips is searched (the bracket starts at 0, not at v1). */
#define DIP_EXTRA_BISECT 8
/* Extra bisection steps for the highest cruise while no plan has been found yet (a plan is needed, not a better
 * one: a finer search before giving up to the fallback). */
#define CRUISE_EXTRA_BISECT 20
/* A cruise this many cycles long or more, below (1 - node_drop) of the highest cap of its piece, is re-planned at
 * the end of ramp A (slow_cruise_step). */
#define SLOW_CRUISE_CYCLES LSM_R(50.0)
/* The cruise search aims SECANT_AIM of its resolution below the predicted highest feed (a verified try there leaves
 * the bracket to close), and closes it from below with a try SECANT_CLOSE of the resolution above l. */
#define SECANT_AIM LSM_R(0.5)
#define SECANT_CLOSE LSM_R(0.95)
/* After this many tries in a row on one side of the bracket, the midpoint (the interpolation is not converging). */
#define SECANT_STALL 3

/* The state of one forward search (plan_normal) over its candidate nodes. */
typedef struct search {
    lsm_planner *pl;
    uint32_t id0; /* the start: block, offset, speed (a = 0) */
    lsm_real off0, v0;
    pctx pc;             /* the piece to the candidate node (the last one tried) */
    lsm_real w1;         /* W of the candidate node */
    lsm_real v1;         /* arrival speed at it */
    bool exact;          /* the node is a stop */
    bool catchup;        /* v0 is above the caps right here (override lowered) */
    bool have;           /* best holds a verified plan */
    lsm_real ga, gj, gs; /* budgets at the start (at rest): the distance probes */
    plan5 best, p;       /* the best plan so far, and the one being tried */
    uint32_t far;        /* the farthest candidate node (search_reach) */
} search;

/* Forward step: the highest v1 <= w1 that one ramp from v0 reaches (then cruise). */
static void reach_speed(search *s)
{
    pctx *pc = &s->pc;
    if (!(s->v1 > s->v0) || s->catchup || feas5(pc, s->v0, s->v1, s->v1, false, false, &s->p))
        return;
    lsm_real lo = s->v0, hi = s->v1;
    lsm_real probe = lsm_pl_speed_for_dist(s->v0, pc->D, s->ga, s->gj, s->gs, s->v1);
    for (int it = 0; it < W_BISECT && hi - lo > SPEED_RES * hi; it++) {
        const lsm_real mid = probe_mid(lo, hi, &probe);
        if (feas5(pc, s->v0, mid, mid, false, false, &s->p))
            lo = mid;
        else
            hi = mid;
    }
    s->v1 = lo;
}

/* Arriving below the node's W: at a speed from which the machine can go on (verified like W). */
static void arrival_speed(search *s, uint32_t id_end)
{
    if (s->catchup || !(s->v1 > R0) || !(s->v1 < s->w1) || lsm_pl_arrival_ok(s->pl, id_end, s->v1))
        return;
    lsm_real lo = R0, hi = s->v1;
    for (int it = 0; it < W_BISECT && hi - lo > SPEED_RES * hi; it++) {
        const lsm_real mid = (lo + hi) / LSM_R(2.0);
        if (lsm_pl_arrival_ok(s->pl, id_end, mid))
            lo = mid;
        else
            hi = mid;
    }
    s->v1 = lo;
}

/* Override catch-up: slow down at once towards the cap here, then cruise and go on. */
static void plan_catchup(search *s)
{
    pctx *pc = &s->pc;
    const lsm_real v1 = s->v1;
    lsm_real vt = lsm_max2(v1, lsm_min2(s->v0, lsm_pl_range_cap(pc, R0, pc->D)));
    for (int it = 0; it < CATCHUP_TRIES && !s->have; it++) {
        if (feas5(pc, s->v0, vt, v1, s->exact, true, &s->p)) {
            s->best = s->p;
            s->have = true;
        }
        vt = v1 + (vt - v1) * CATCHUP_SHRINK;
    }
}

/* The monotone profile (cruise at lo = max(v0, v1)); if it does not verify, caps below v0 inside the piece (dips
 * that are not nodes): slow down at once to a cruise below them, arriving at the node below its W when the dip is
 * lower than that (W is only the highest speed). */
static void plan_below_dips(search *s, uint32_t id_end, lsm_real lo)
{
    pctx *pc = &s->pc;
    const lsm_real v1 = s->v1;
    if (lo > R0 && feas5(pc, s->v0, lo, v1, s->exact, false, &s->p)) {
        s->best = s->p;
        s->have = true;
        return;
    }
    if (!(s->v0 > v1 || lo > R0))
        return;
    lsm_real l = R0, u = lo;
    for (int it = 0; it < VC_BISECT + DIP_EXTRA_BISECT && u - l > SPEED_RES * u; it++) {
        const lsm_real mid = (l + u) / LSM_R(2.0);
        if (mid > R0 && feas5(pc, s->v0, mid, lsm_min2(v1, mid), s->exact, true, &s->p) &&
            (mid >= v1 || lsm_pl_arrival_ok(s->pl, id_end, mid))) {
            s->best = s->p;
            s->have = true;
            l = mid;
        } else {
            u = mid;
        }
    }
}

/* The piece the node's certificate verified (node_w, arrival_ok): one ramp from v0 down to the next node's W, or a
 * cruise at v0, so that a speed certified at a node always goes on. */
static void plan_certified(search *s)
{
    if (s->have || s->off0 != R0 || !(s->v0 > R0))
        return;
    const lsm_real dt = s->pl->cfg.cycle_s, v0 = s->v0, v1 = s->v1;
    plan5 *p = &s->p;
    ramp r;
    lsm_real xs;
    memset(p, 0, sizeof *p);
    p->v0 = p->vc = v0;
    no_ramp(&p->A, dt, v0);
    if (lsm_pl_w_test(&s->pc, v0, v1, s->exact, &r, &xs)) {
        p->v1 = v0 > v1 ? v1 : v0;
        if (v0 > v1) {
            p->B = r;
            p->xB = xs;
        } else {
            no_ramp(&p->B, dt, v0);
            p->xB = s->pc.D;
        }
        s->best = *p;
        s->have = true;
    }
}

/* The highest cap of the blocks the search's piece spans (plan_cruise's top, slow_cruise_step's reference). */
static lsm_real piece_cap_max(const search *s)
{
    lsm_real mx = R0;
    for (uint32_t id = s->pc.id0; id != s->pc.id_end; id++)
        mx = lsm_max2(mx, cap_of(s->pl, id));
    return mx;
}

/* The cruise search's bracket: l verified, u not, and the room between the ramps (plan5.slack) each left, 0 where
 * not known; `again`: how many times in a row l (> 0) or u (< 0) moved. */
typedef struct bracket {
    lsm_real l, u, fl, fu;
    int again;
} bracket;

/* The next cruise feed to try in (l, u): where the room between the ramps vanishes, interpolated between the ends
 * of the bracket (the room is about linear in the square of the feed: ramp lengths go with v²; the end that stayed
 * twice counts half, so that it moves too), aimed SECANT_AIM of the resolution below that, or SECANT_CLOSE of it
 * above l to close the bracket; the midpoint when the room is not known at both ends or the same end moved
 * SECANT_STALL times in a row. */
static lsm_real cruise_next(const bracket *b)
{
    const lsm_real l = b->l, u = b->u, mid = (l + u) / LSM_R(2.0), w = SPEED_RES * u;
    lsm_real fl = b->fl, fu = b->fu;
    if (!(fl > R0) || !(fu < R0) || b->again >= SECANT_STALL || b->again <= -SECANT_STALL)
        return mid;
    if (b->again >= 2)
        fu /= LSM_R(2.0);
    if (b->again <= -2)
        fl /= LSM_R(2.0);
    const lsm_real r2 = l * l + (u * u - l * l) * fl / (fl - fu);
    lsm_real t = lsm_sqrt(r2) - SECANT_AIM * w;
    if (t - l < SECANT_CLOSE * w)
        t = l + SECANT_CLOSE * w; /* close the bracket from below */
    return t > l && t < u ? t : mid;
}

static void bracket_move(bracket *b, bool ok, lsm_real v, const plan5 *p)
{
    const lsm_real f = p->slack;
    if (ok) {
        b->again = b->again > 0 ? b->again + 1 : 1;
        b->l = v;
        b->fl = f;
    } else {
        b->again = b->again < 0 ? b->again - 1 : -1;
        b->u = v;
        b->fu = f;
    }
}

/* The highest cruise feed between the monotone profile lo and the highest cap of the piece: a bracket [l, u] (l
 * verified, u not) narrowed to SPEED_RES, guided by the room the tries left between their ramps (cruise_next). */
static void plan_cruise(search *s, lsm_real lo)
{
    pctx *pc = &s->pc;
    const lsm_real v0 = s->v0, v1 = s->v1;
    const lsm_real hi = lsm_max2(lo, piece_cap_max(s));
    if (!(hi > lo) || !(s->have || !(v0 > v1)))
        return;
    if (feas5(pc, v0, hi, v1, s->exact, false, &s->p)) {
        s->best = s->p;
        s->have = true;
        return;
    }
    bracket b = {lo, hi, s->have && s->best.vc == lo ? s->best.slack : R0, s->p.slack, 0};
    lsm_real probe = lsm_pl_cruise_for_dist(v0, v1, pc->D, s->ga, s->gj, s->gs, hi);
    for (int it = 0; it < VC_BISECT + (s->have ? 0 : CRUISE_EXTRA_BISECT) && b.u - b.l > SPEED_RES * b.u; it++) {
        const lsm_real mid = it == 0 ? probe_mid(b.l, b.u, &probe) : cruise_next(&b);
        const bool ok = feas5(pc, v0, mid, v1, s->exact, false, &s->p);
        if (ok) {
            s->best = s->p;
            s->have = true;
        }
        bracket_move(&b, ok, mid, &s->p);
    }
}

/* Lower cruises tried when the best plan ends with a trail cruise below its cruise (trail_levels): each this share
 * of the way from v1 to the last one, at most TRAIL_LEVELS of them. */
#define TRAIL_LEVELS 4
#define TRAIL_LEVEL_RATIO LSM_R(0.75)

/* The highest cruise is not always the fastest piece: where ramp B cannot verify late (it would cross a block whose
 * budgets vanish near its cap at that speed), it moves early and the piece trails the rest at v1 (a corner run at
 * 1.4 mm/s instead of 29 mm/s: the float build's crawl_random, seed 6). A few lower cruises, whose ramp B can cross
 * that block, are tried, and the one with the shortest piece time is kept. */
static void trail_levels(search *s)
{
    const lsm_real dt = s->pl->cfg.cycle_s;
    plan5 *b = &s->best;
    const lsm_real D = s->pc.D;
    if (!s->have || !(b->vc > b->v1) || !(D - (b->xB + b->B.dist) > LEN_EPS * (R1 + D)))
        return;
    lsm_real t_best = plan_time(b, dt, D);
    lsm_real vc = b->vc;
    const lsm_real v0 = b->v0, v1 = b->v1;
    for (int k = 0; k < TRAIL_LEVELS; k++) {
        vc = v1 + (vc - v1) * TRAIL_LEVEL_RATIO;
        if (!(vc > lsm_max2(v0, v1) * (R1 + STAIR_MIN_STEP)))
            break;
        if (!feas5(&s->pc, v0, vc, v1, s->exact, false, &s->p))
            continue;
        const lsm_real t = plan_time(&s->p, dt, D);
        if (t < t_best - STAIR_MIN_GAIN_CYCLES * dt) {
            t_best = t;
            *b = s->p;
        }
    }
}

/* The stages of the search for the piece to the candidate node id_end (s->pc and s->w1 set). */
static void plan_to_node(search *s, uint32_t id_end)
{
    pctx *pc = &s->pc;
    s->exact = !(s->w1 > R0);
    s->catchup = s->v0 > lsm_pl_range_cap(pc, R0, R0) * (R1 + CAP_SLACK);
    if (s->catchup)
        pc->floor = s->v0;
    s->v1 = s->w1;
    lsm_pl_guess_limits(pc, R0, &s->ga, &s->gj, &s->gs);
    reach_speed(s);
    arrival_speed(s, id_end);
    if (s->catchup) {
        plan_catchup(s);
        return;
    }
    const lsm_real lo = lsm_max2(s->v0, s->v1);
    plan_below_dips(s, id_end, lo);
    plan_certified(s);
    plan_cruise(s, lo);
    trail_levels(s);
}

/* One pass over the candidate nodes (planner.h: to the next node; if no verified piece reaches it, to the one
 * after, and so on). Pass 0 plans across a valley node closer than SHORT_PIECE_CYCLES of travel; returns whether
 * it skipped one. */
static bool search_pass(search *s, int pass)
{
    const lsm_planner *pl = s->pl;
    uint32_t id_end = s->id0;
    bool skipped_here = false, skipped_short = false;
    for (int cand = 0; cand < NODE_CANDIDATES && !s->have; cand++) {
        if (id_end == pl->tail || (cand > 0 && !skipped_here && (blk(pl, id_end)->flags & LSM_PB_STOP)))
            break;
        id_end = lsm_pl_node_after(pl, id_end, &s->w1);
        if (id_lt(s->far, id_end))
            s->far = id_end;
        lsm_pl_pctx_init(&s->pc, pl, s->id0, s->off0, id_end);
        skipped_here = false;
        if (!(s->pc.D > LEN_EPS * (R1 + s->pc.D)) && id_end != pl->tail) {
            /* a node right here (we stand on it): the next one (the end itself is planned, however short the
             * rest: a hold may stop just before it) */
            skipped_here = true;
            continue;
        }
        if (pass == 0 && id_end != pl->tail && !(blk(pl, id_end)->flags & LSM_PB_STOP) &&
            s->pc.D < SHORT_PIECE_CYCLES * pl->cfg.cycle_s * lsm_max2(s->v0, s->w1)) {
            skipped_here = true;
            skipped_short = true;
            continue;
        }
        plan_to_node(s, id_end);
    }
    return skipped_short;
}

/* A piece has one cruise: a dip near its start that is no node (closer than SHORT_PIECE_CYCLES, or passed by ramp
 * A while it slows down) holds the whole cruise at the dip's speed, however long and fast the rest (fuzz_gcode_path:
 * a 90 degree corner 0.5 um after a reversal stop, then 79 mm at 0.24 mm/s; a corner at 10 mm/s reached while
 * braking from 36 mm/s, then 12 mm at 0.4 mm/s). Such a piece, a long cruise far below the highest cap of its piece
 * after a ramp A, is a step (lsm_piece.step): the interpolator re-plans at the end of ramp A (a = 0), where the dip
 * may be behind. The piece itself is complete and verified, so a re-plan that finds nothing better keeps it; a
 * step needs a ramp A of some length (the re-planned piece, starting at its cruise, has none unless it finds a
 * higher one), so the re-plans never repeat at one point. */
static void slow_cruise_step(search *s)
{
    plan5 *b = &s->best;
    const lsm_planner *pl = s->pl;
    if (b->step || !(b->A.dist > R0) || b->vc == b->v0 || !(b->vc > R0))
        return;
    const lsm_real cruise = b->xB - (b->xA + b->A.dist);
    if (!(cruise > SLOW_CRUISE_CYCLES * pl->cfg.cycle_s * b->vc))
        return;
    if (b->vc < (R1 - pl->cfg.node_drop) * piece_cap_max(s))
        b->step = true;
}

/* One past the last block the search read (the piece memo): every piece it tried ends at a candidate node, read with
 * the blocks before it (lsm_pl_node_after, the pctx of the piece); lsm_pl_arrival_ok at a candidate reads on to the
 * node after it (its flags and W, the blocks between). The farthest candidate bounds both (the node after an
 * earlier candidate is a later candidate), unless it is a stop or the tail, where lsm_pl_arrival_ok reads nothing
 * further. If the tail is read (compared with), reach is tail + 1: the next block pushed changes the search. */
static uint32_t search_reach(const search *s)
{
    const lsm_planner *pl = s->pl;
    uint32_t r = s->far;
    if (r != pl->tail && !(blk(pl, r)->flags & LSM_PB_STOP)) {
        lsm_real w;
        r = lsm_pl_node_after(pl, r, &w);
    }
    return r + 1u;
}

/* The NORMAL piece from (id0, off0) at v0 (a = 0): true and the plan, or false (pc: the last piece tried). Pass 1
 * (only if pass 0 found nothing and skipped a short piece) also stops at the close valley node. reach (if not NULL):
 * search_reach. */
static bool plan_normal(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, pctx *pcp, plan5 *bestp,
                        uint32_t *reach)
{
    search s;
    memset(&s, 0, sizeof s);
    s.pl = pl;
    s.id0 = id0;
    s.far = id0;
    s.off0 = off0;
    s.v0 = v0;
    const bool skipped_short = search_pass(&s, 0);
    if (!s.have && skipped_short)
        (void)search_pass(&s, 1);
    if (s.have && !s.catchup)
        staircase(&s.pc, &s.best);
    if (s.have)
        slow_cruise_step(&s);
    *pcp = s.pc;
    if (s.have)
        *bestp = s.best;
    if (reach != NULL)
        *reach = search_reach(&s);
    return s.have;
}

/* Does a verified piece start at the interpolator's commitment point (planner.h, lsm_planner_set_horizon)?
 * Unless `force`, a backward pass that stopped at an unchanged node after that point left the piece from there
 * unchanged: nothing to check. (After a corner trimmed the block the current piece ends in, the piece from there
 * is always checked: that piece must be replaced.) */
bool lsm_pl_horizon_feasible(lsm_planner *pl, bool force)
{
    uint32_t id = pl->horizon_blk;
    lsm_real off = pl->horizon_off;
    if (!(pl->horizon_v > R0) || id_lt(id, pl->head) || !id_lt(id, pl->tail))
        return true;
    if (!force && id_lt(id, pl->bp_stop))
        return true;
    while (off > blk(pl, id)->g.len && id + 1u != pl->tail) {
        off -= blk(pl, id)->g.len;
        id++;
    }
    if (off >= blk(pl, id)->g.len && id + 1u == pl->tail)
        return false; /* moving at the very end of the buffer */
    pctx pc;
    plan5 p;
    return plan_normal(pl, id, off, pl->horizon_v, &pc, &p, NULL);
}
