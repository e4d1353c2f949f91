/* plan_nodes.c: the backward pass: nodes at the valleys of the cap profile and their W (planner.h, "Look-ahead
 * invariants"), with the continuous-ramp distance probes of the searches, and the feed override. */
#include "planner_int.h"

/* The distance probes (continuous ramps, cheap): bisected to a quarter of SPEED_RES, at most PROBE_ITER steps. */
#define PROBE_ITER 40
#define PROBE_RES_SHARE LSM_R(0.25)
/* Steps below the guesses that failed (ws_guess), at most, all guesses together (2.4 % of the speed), and their size
 * (share of SPEED_RES: the bracket then closes). */
#define W_DESCENT 6
#define W_STEP LSM_R(0.98)
/* Tests of a node's W at most: the cap, the guesses with their closing tests and the steps below, the bisection. */
#define W_TESTS (W_BISECT + W_DESCENT + 2)
/* A lowered override (or a raised one the commitment does not allow at once): the stopping distance from the current
 * speed is estimated with OVR_LIMIT_SHARE of the block's limits at rest (a conservative ramp), scaled by
 * OVR_NEED_SCALE, plus OVR_NEED_CYCLES cycles of travel; the switch moves further out (doubling) at most OVR_TRIES
 * times, then to the blocks appended later. */
#define OVR_LIMIT_SHARE LSM_R(0.5)
#define OVR_UNBOUNDED_A LSM_R(1e12)
#define OVR_UNBOUNDED_J LSM_R(1e15)
#define OVR_UNBOUNDED_S LSM_R(1e18)
#define OVR_NEED_SCALE LSM_R(2.0)
#define OVR_NEED_CYCLES LSM_R(4.0)
#define OVR_TRIES 8

/* ------------------------------------------------------------------------------------------------------------ */
/* distance probes (continuous ramps)                                                                           */

/* Time of one continuous sin² velocity change by dv with the tangential limits a, j, s (Kombarov eqs 25-31, before
 * quantisation: the whole-cycle profile of the strict rule takes a few cycles more). */
static lsm_real ramp_time_cont(lsm_real dv, lsm_real a, lsm_real j, lsm_real s)
{
    if (!(dv > R0))
        return R0;
    lsm_real t1 = PI_R * j / (LSM_R(2.0) * s);                 /* eq 25 */
    t1 = lsm_min2(t1, lsm_sqrt(PI_R * a / (LSM_R(2.0) * s)));  /* eq 26 */
    t1 = lsm_min2(t1, lsm_cbrt(PI_R * dv / (LSM_R(4.0) * s))); /* eq 29 */
    const lsm_real jc = LSM_R(2.0) * t1 * s / PI_R;            /* eq 32 */
    const lsm_real t2 = lsm_max2(lsm_min2(a / jc - t1, lsm_sqrt(t1 * t1 / LSM_R(4.0) + dv / jc) - LSM_R(1.5) * t1), R0);
    const lsm_real ap = jc * (t1 + t2);                               /* eq 23 */
    const lsm_real t4 = lsm_max2(dv / ap - LSM_R(2.0) * t1 - t2, R0); /* eq 31 */
    return LSM_R(4.0) * t1 + LSM_R(2.0) * t2 + t4;
}

/* Highest speed v in [w, vmax] from which one continuous ramp to w (or from w up to v) fits in distance D:
 * (v + w) t(v - w) / 2 <= D, the travel being monotone in v. A first probe for the searches below. */
lsm_real lsm_pl_speed_for_dist(lsm_real w, lsm_real D, lsm_real a, lsm_real j, lsm_real s, lsm_real vmax)
{
    if (!(vmax > w) || !(D > R0))
        return w;
    if ((vmax + w) * ramp_time_cont(vmax - w, a, j, s) <= LSM_R(2.0) * D)
        return vmax;
    lsm_real lo = w, hi = vmax;
    for (int it = 0; it < PROBE_ITER && hi - lo > SPEED_RES * PROBE_RES_SHARE * hi; it++) {
        const lsm_real mid = (lo + hi) / LSM_R(2.0);
        if ((mid + w) * ramp_time_cont(mid - w, a, j, s) <= LSM_R(2.0) * D)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Highest cruise vc in [max(v0, v1), vmax] for which two continuous ramps v0 -> vc -> v1 fit in distance D. */
lsm_real lsm_pl_cruise_for_dist(lsm_real v0, lsm_real v1, lsm_real D, lsm_real a, lsm_real j, lsm_real s, lsm_real vmax)
{
    lsm_real lo = lsm_max2(v0, v1), hi = vmax;
    if (!(hi > lo) || !(D > R0))
        return lo;
    for (int it = 0; it < PROBE_ITER && hi - lo > SPEED_RES * PROBE_RES_SHARE * hi; it++) {
        const lsm_real mid = it == 0 ? hi : (lo + hi) / LSM_R(2.0);
        const lsm_real d =
            (v0 + mid) * ramp_time_cont(mid - v0, a, j, s) + (mid + v1) * ramp_time_cont(mid - v1, a, j, s);
        if (d <= LSM_R(2.0) * D) {
            if (it == 0)
                return hi;
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* nodes and their W                                                                                            */

/* The test of a node's W for speed v over the piece pc (from the node to the next one, whose W is w1; exactly if
 * exact): one verified ramp from v reaches w1 by its end (*r, starting at *xs), or a cruise at v goes through. */
bool lsm_pl_w_test(pctx *pc, lsm_real v, lsm_real w1, bool exact, ramp *r, lsm_real *xs)
{
    return v <= w1 ? lsm_pl_region_ok(pc, R0, pc->D, v) : lsm_pl_fit_decel(pc, R0, pc->D, v, w1, exact, true, r, xs);
}

/* The search of a node's W: [lo, hi] with lo certified (it passed the test, or a cruise at it goes through, or 0
 * before an exact stop) and hi failed (or the cap). */
typedef struct wsearch {
    pctx pc;
    lsm_real w1;
    bool exact;
    lsm_real lo, hi;
    int tests;
    int descents; /* steps below failed guesses left */
} wsearch;

/* Tests v if it lies inside the bracket (and the test budget is not spent); true if it passed. */
static bool ws_try(wsearch *s, lsm_real v)
{
    if (!(v > s->lo && v < s->hi) || s->tests >= W_TESTS)
        return false;
    s->tests++;
    ramp r;
    lsm_real xs;
    const bool ok = lsm_pl_w_test(&s->pc, v, s->w1, s->exact, &r, &xs);
    if (ok)
        s->lo = v;
    else
        s->hi = v;
    return ok;
}

static bool ws_open(const wsearch *s)
{
    return s->hi - s->lo > SPEED_RES * s->hi && s->tests < W_TESTS;
}

/* A guess g of W and the tests that close the bracket next to it: one just above it when it passes; when it fails,
 * steps just under SPEED_RES below it, W_DESCENT at most for all guesses (W is then within SPEED_RES of the first that passes: as
 * close as the bisection gets, in two to four tests instead of five or more: a guess fails mostly for want of room,
 * told before any verification, or just above the speed the budgets allow). Further below, the bisection. */
static void ws_guess(wsearch *s, lsm_real g)
{
    if (!ws_open(s) || !(g > s->lo && g < s->hi))
        return;
    if (ws_try(s, g)) {
        (void)ws_try(s, g * (R1 + W_STEP * SPEED_RES));
        return;
    }
    while (s->descents > 0 && ws_open(s)) {
        s->descents--;
        if (ws_try(s, s->hi * (R1 - W_STEP * SPEED_RES)))
            return;
    }
}

/* W of a node: highest v0 <= c0 from which the piece [0, D] reaches w1 at its end (exactly if exact), to SPEED_RES:
 * between the speed that can cruise through the piece (or 0 before an exact stop) and c0. The guesses first, each
 * with its closing test (ws_guess): the node's previous W (an append mostly leaves it where it was: the search then
 * ends on it, and the backward pass stops there), before an exact stop the lowest cap of the piece (a stop close
 * behind a slower block: W sits just below that cap), and the speed from which one continuous ramp with the budgets
 * at the node's end fits in D (the whole-cycle, verified ramp needs at least that room); then bisection. Feasibility
 * is not strictly monotone in the speed near the caps (whole-cycle ramps against budgets that vanish at the cap), so
 * a W may move either way when w1 changes: the interpolator's commitment is checked after every append
 * (commitment_kept). */
static lsm_real node_w(lsm_planner *pl, uint32_t id, uint32_t id_end, lsm_real w1, bool exact)
{
    pl->stats.bp_nodes++;
    wsearch s;
    lsm_pl_pctx_init(&s.pc, pl, id, R0, id_end);
    s.w1 = w1;
    s.exact = exact;
    s.tests = 0;
    s.descents = W_DESCENT;
    const lsm_real c0 = cap_of(pl, id);
    const lsm_real D = s.pc.D;
    const lsm_real mincap = lsm_pl_range_cap(&s.pc, R0, D);
    s.lo = exact ? R0 : lsm_min2(mincap, w1); /* cruising at lo through the piece always works */
    s.hi = c0;
    if (!(s.hi > s.lo))
        return s.hi;
    {
        ramp r;
        lsm_real xs;
        s.tests++;
        if (lsm_pl_w_test(&s.pc, s.hi, w1, exact, &r, &xs))
            return s.hi;
    }
    const lsm_pblock *b = blk(pl, id);
    if (b->flags & LSM_PB_NODE)
        ws_guess(&s, b->w_mm_s);
    if (exact)
        ws_guess(&s, mincap);
    lsm_real ga, gj, gs;
    lsm_pl_guess_limits(&s.pc, D, &ga, &gj, &gs);
    ws_guess(&s, lsm_pl_speed_for_dist(lsm_max2(w1, s.lo), D, ga, gj, gs, s.hi));
    while (ws_open(&s))
        (void)ws_try(&s, (s.lo + s.hi) / LSM_R(2.0));
    return s.lo;
}

/* The test of node_w for speed v at node id: one verified ramp from v reaches w1 by the next node id_end (exactly
 * if exact), or a cruise at v goes through. */
static bool cert_ok(lsm_planner *pl, uint32_t id, uint32_t id_end, lsm_real v, lsm_real w1, bool exact)
{
    pctx pc;
    lsm_pl_pctx_init(&pc, pl, id, R0, id_end);
    if (!(pc.D > LEN_EPS * (R1 + pc.D)))
        return v <= w1;
    ramp r;
    lsm_real xs;
    return lsm_pl_w_test(&pc, v, w1, exact, &r, &xs);
}

/* Can a piece that arrives at node `id` (a = 0) at speed v go on? The test of node_w: one verified ramp from v
 * reaches the next node's W (or a cruise at v goes through). A piece that arrives below the node's W needs this:
 * W itself was verified, but whole-cycle ramps make the lower speeds not always so. */
bool lsm_pl_arrival_ok(lsm_planner *pl, uint32_t id, lsm_real v)
{
    if (!(v > R0) || id == pl->tail || !id_lt(id, pl->tail) || (blk(pl, id)->flags & LSM_PB_STOP))
        return true;
    lsm_real w2;
    const uint32_t n2 = lsm_pl_node_after(pl, id, &w2);
    return cert_ok(pl, id, n2, v, w2, !(w2 > R0));
}

/* Valley detection while walking backwards (see planner.h: nodes at valleys and significant drops). */
typedef struct vstate {
    lsm_real M; /* highest cap since the last node (walking back) */
    lsm_real m; /* lowest cap after the peak */
    uint32_t m_id;
    uint8_t desc;
    uint8_t has_last;
    lsm_real last_c;
    uint32_t last_id;
    lsm_real lo; /* lowest cap since the last node */
} vstate;

LSM_NOINLINE static void vreset(vstate *s)
{
    s->M = -R1;
    s->m = LSM_REAL_MAX;
    s->m_id = 0;
    s->desc = 0;
    s->has_last = 0;
    s->last_c = R0;
    s->last_id = 0;
    s->lo = LSM_REAL_MAX;
}

/* Feeds block id (cap c); returns 1 and *node when a node is found (at an id after `id`). */
static int vstep(vstate *s, uint32_t id, lsm_real c, lsm_real h, lsm_real drop, uint32_t *node)
{
    /* a drop: some cap after this block (since the last node) is that much lower, the node right after it. (Not
     * only the next block's: a feed that falls by steps of less than node_drop each made one piece of the whole
     * descent, whose one cruise ran at the lowest cap: F3000, 2400, 1920, ... crawled at the last feed.) */
    if (s->has_last && s->lo < c * (R1 - drop)) {
        *node = s->last_id;
        return 1;
    }
    if (!s->desc) {
        if (c >= s->M)
            s->M = c;
        else if (c * (R1 + h) < s->M) {
            s->desc = 1;
            s->m = c;
            s->m_id = id;
        }
    } else {
        if (c <= s->m) {
            s->m = c;
            s->m_id = id;
        } else if (c > s->m * (R1 + h)) {
            *node = s->m_id;
            return 1;
        }
    }
    s->has_last = 1;
    s->last_c = c;
    s->last_id = id;
    s->lo = lsm_min2(s->lo, c);
    return 0;
}

/*
 * Cap seen by the node detection: for a block shorter than 2 ERODE_CYCLES cycles of travel, the lowest cap from
 * its start to that distance ahead, the travel measured at the speed of the dips ahead (two passes). This removes
 * humps too short to change speed in (e.g. the lines between the corners of a dense polyline), so that valleys are
 * those of the envelope, and keeps the detection local (a node depends only on the caps after it, never on the
 * interpolator's position or on other nodes).
 */
#define ERODE_CYCLES 4
static lsm_real min_cap_ahead(const lsm_planner *pl, uint32_t id, lsm_real d)
{
    lsm_real m = cap_of(pl, id), x = blk(pl, id)->g.len;
    /* (not across an exact stop: what comes after one never moves the nodes before it, so that a junction made an
     * exact stop restores the nodes before it; their W, lsm_pl_wseed) */
    for (uint32_t q = id + 1u; q != pl->tail && x < d && !(blk(pl, q)->flags & LSM_PB_STOP); q++) {
        m = lsm_min2(m, cap_of(pl, q));
        x += blk(pl, q)->g.len;
    }
    return m;
}

static lsm_real eroded_cap(const lsm_planner *pl, uint32_t id)
{
    const lsm_real c = cap_of(pl, id);
    const lsm_real k = LSM_R(2.0) * (lsm_real)ERODE_CYCLES * pl->cfg.cycle_s;
    const lsm_real len = blk(pl, id)->g.len;
    if (len >= k * c)
        return c; /* a plateau of its own */
    /* the window is measured at the speed the dips ahead allow: a hump matters if there is room to speed up from
     * them, not from its own cap */
    const lsm_real m1 = min_cap_ahead(pl, id, k * c);
    if (len >= k * m1)
        return c;
    return min_cap_ahead(pl, id, k * m1);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* backward pass                                                                                                */

void lsm_pl_changed(lsm_planner *pl, uint32_t id)
{
    if (id_lt(id, pl->memo.reach))
        pl->memo.ok = 0;
}

void lsm_pl_backward_pass(lsm_planner *pl)
{
    if (pl->tail == pl->head)
        return;
    const lsm_real h = pl->cfg.node_hyst, drop = pl->cfg.node_drop;
    uint32_t n_id = pl->tail; /* the end of the buffer: a stop */
    lsm_real n_w = R0;
    bool n_exact = true;
    vstate vs;
    vreset(&vs);
    const uint32_t lo = pl->head;
    uint32_t k = pl->tail;
    while (k != lo) {
        k--;
        lsm_pblock *b = blk(pl, k);
        uint32_t node = 0;
        int found = 0;
        if (b->flags & LSM_PB_STOP) {
            /* pending valley between here and the next node first; then a drop of the cap right after this block
             * (a fast block from a stop followed by a slow one: without that node, one piece from the stop ran the
             * fast block at the slow block's cap, one cruise for both); then the stop itself */
            if (vs.desc && id_lt(k, vs.m_id)) {
                node = vs.m_id;
                found = 1;
            } else if (vstep(&vs, k, eroded_cap(pl, k), h, drop, &node)) {
                found = 1;
            } else {
                node = k;
                found = 2;
            }
        } else {
            found = vstep(&vs, k, eroded_cap(pl, k), h, drop, &node);
        }
        if (!found)
            continue; /* (its node flag is settled when the node before it is found: a block may turn out to be the
                         valley once the walk has gone past it, and its old flag tells whether its W changed) */
        /* a node at `node` (node >= k) */
        lsm_pblock *nb = blk(pl, node);
        lsm_real w = (nb->flags & LSM_PB_STOP) ? R0 : node_w(pl, node, n_id, n_w, n_exact);
        /* unchanged, or higher by less than the searches resolve and the old W still certified against the node
         * after it (feasibility is not strictly monotone in the speed, so a lower W is not certified by a higher
         * one): the old W stays, and so does everything before it */
        const bool was = (nb->flags & LSM_PB_NODE) != 0 && !pl->full_pass;
        const bool same = was && (nb->w_mm_s == w || (w > nb->w_mm_s && w <= nb->w_mm_s * (R1 + SPEED_RES) &&
                                                      cert_ok(pl, node, n_id, nb->w_mm_s, n_w, n_exact)));
        if (same)
            w = nb->w_mm_s;
        nb->flags |= LSM_PB_NODE;
        nb->w_mm_s = w;
        for (uint32_t q = node + 1u; q != n_id; q++) /* blocks inside the piece are not nodes */
            blk(pl, q)->flags &= (uint8_t)~LSM_PB_NODE;
        n_id = node;
        n_w = w;
        n_exact = (nb->flags & LSM_PB_STOP) != 0;
        if (same) {
            pl->bp_stop = node;
            lsm_pl_changed(pl, node + 1u); /* (the node itself kept its flag and W) */
            return;                        /* everything before is unchanged */
        }
        /* restart the detection just before the node and walk again down to k */
        vreset(&vs);
        k = node;
    }
    /* a valley still pending at the interpolator stays inside the first piece (verified pointwise there) */
    for (uint32_t q = pl->head; q != n_id; q++)
        blk(pl, q)->flags &= (uint8_t)~LSM_PB_NODE;
    lsm_pl_changed_all(pl);
    pl->full_pass = 0;
    pl->bp_stop = pl->head;
}

void lsm_planner_update(lsm_planner *pl)
{
    if (pl == NULL)
        return;
    lsm_planner_apply_requests(pl); /* the tick's requests first (planner.h) */
    lsm_pl_backward_pass(pl);
}

/* Sets the override state and plans with it. */
LSM_NOINLINE static void ovr_apply(lsm_planner *pl, lsm_real near, lsm_real far, uint32_t sw)
{
    pl->ovr_near = near;
    pl->ovr_far = far;
    pl->ovr_switch = sw;
    lsm_pl_changed_all(pl); /* (every cap) */
    pl->full_pass = 1;
    pl->gen++;
    lsm_pl_backward_pass(pl);
}

/* The stopping-scale distance from v_now at block cur (a conservative ramp with OVR_LIMIT_SHARE of its limits). */
static lsm_real ovr_need(const lsm_planner *pl, uint32_t cur, lsm_real v_now)
{
    coef c;
    coef_get(blk(pl, cur), &c);
    ramp r;
    const lsm_real a = c.aa > R0 ? OVR_LIMIT_SHARE / c.aa : OVR_UNBOUNDED_A;
    const lsm_real j = c.aj > R0 ? OVR_LIMIT_SHARE / c.aj : OVR_UNBOUNDED_J;
    const lsm_real s = c.as > R0 ? OVR_LIMIT_SHARE / c.as : OVR_UNBOUNDED_S;
    if (v_now > R0 && lsm_pl_ramp_plan(&r, pl->cfg.cycle_s, v_now, R0, a, j, s))
        return OVR_NEED_SCALE * r.dist + OVR_NEED_CYCLES * v_now * pl->cfg.cycle_s;
    return R0;
}

/* The W of the first nodes from the end of the interpolator's current piece on, as they were before a trial that may
 * be undone (planner_int.h, lsm_pl_wseed). */
void lsm_pl_wseed_take(const lsm_planner *pl, lsm_pl_wseed *s)
{
    const uint32_t e = pl->horizon_end;
    s->n = 0;
    for (uint32_t id = id_lt(e, pl->head) || !id_lt(e, pl->tail) ? pl->head : e;
         id != pl->tail && s->n < LSM_PL_SEED_NODES; id++) {
        const lsm_pblock *b = blk(pl, id);
        if (b->flags & LSM_PB_NODE) {
            s->id[s->n] = id;
            s->w[s->n] = b->w_mm_s;
            s->n++;
        }
    }
}

/* Puts the seeded W back as the nodes' previous W (the restoring pass starts its searches from them). */
void lsm_pl_wseed_put(lsm_planner *pl, const lsm_pl_wseed *s)
{
    for (uint32_t i = 0; i < s->n; i++) { /* (every id is in the buffer: nothing before the old tail is released) */
        lsm_pblock *b = blk(pl, s->id[i]);
        b->flags |= LSM_PB_NODE;
        b->w_mm_s = s->w[i];
    }
}

/* Restores the override state (near, far, sw) with the seeded W as the nodes' first guesses; counts a restored plan
 * that still does not keep the commitment (stats.restore_unkept: should stay 0). */
static void ovr_restore(lsm_planner *pl, const lsm_pl_wseed *s, lsm_real near, lsm_real far, uint32_t sw)
{
    lsm_pl_wseed_put(pl, s);
    ovr_apply(pl, near, far, sw);
    if (!lsm_pl_commitment_ok(pl))
        pl->stats.restore_unkept++;
}

#ifdef LSM_TEST_OVR_UNDO
/* Fault injection, in test builds only (tests/plan, test_planner_undo): the next lsm_test_ovr_undo_left switch searches
 * fail as if no switch had been verified, so that the undo and its restore run on any path (the real failure is rarer
 * than 1 in 140,000 random override cases). The trials still run and change the plan before the restore, as they do
 * when they really fail. */
extern unsigned lsm_test_ovr_undo_left;
static bool ovr_fail_injected(void)
{
    return lsm_pl_fault_take(&lsm_test_ovr_undo_left);
}
#else
static bool ovr_fail_injected(void)
{
    return false;
}
#endif

/* The new factor f from a switch block on, beyond the stopping-scale distance from v_now (further out until a verified
 * piece starts at the interpolator's commitment point), the factor in force at the cursor (`keep`) before it: nothing
 * the machine is committed to changes. A factor raised where the piece ends may lower W there too (feasibility is not
 * monotone in the caps: node_w), so the blocks before the switch keep the factor they had, not the larger one (a
 * decrease from 95.6 % to 55.8 % raised them to 100 %, the current piece's end speed was no longer one from which the
 * machine could go on, and no piece at all was found there: the machine stood still, RUN at 6.5 mm/s, seed 22514).
 * At worst only the blocks appended later get f; if even that is not verified (an earlier switch still ahead of the
 * cursor: blocks beyond it back at `keep`), the previous state stays. */
static bool ovr_switch_search(lsm_planner *pl, lsm_real f, uint32_t cur, lsm_real v_now, const lsm_pl_wseed *seed)
{
    const lsm_real near0 = pl->ovr_near, far0 = pl->ovr_far;
    const uint32_t sw0 = pl->ovr_switch;
    const lsm_real keep = ovr_of(pl, cur);
    const bool fail = ovr_fail_injected();
    lsm_real need = ovr_need(pl, cur, v_now);
    for (int tries = 0; tries < OVR_TRIES; tries++) {
        uint32_t id = cur;
        lsm_real d = R0;
        while (id != pl->tail && d <= need) {
            d += blk(pl, id)->g.len;
            id++;
        }
        if (id == pl->tail)
            break;
        ovr_apply(pl, keep, f, id);
        if (lsm_pl_horizon_feasible(pl, false) && !fail) {
            if (!lsm_pl_commitment_kept(pl))
                lsm_pl_mark_stale(pl); /* (a verified piece from the horizon: just checked) */
            return true;
        }
        need = OVR_NEED_SCALE * need + blk(pl, cur)->g.len;
    }
    ovr_apply(pl, keep, f, pl->tail);
    if (lsm_pl_commitment_ok(pl) && !fail)
        return true;
    ovr_restore(pl, seed, near0, far0, sw0); /* the plan the machine runs on, as it was */
    return false;
}

lsm_status lsm_planner_set_override(lsm_planner *pl, lsm_real f, uint32_t cur, lsm_real v_now)
{
    if (pl == NULL)
        return LSM_E_NULL;
    lsm_planner_apply_requests(pl); /* the tick's requests first (planner.h) */
    if (f != f)
        return LSM_E_NAN;
    if (!(f >= R0 && f <= LSM_R(2.0)))
        return LSM_E_PL_OVERRIDE;
    if (id_lt(cur, pl->head) || !id_lt(cur, pl->tail))
        cur = pl->head;
    if (pl->tail == pl->head) {
        ovr_apply(pl, f, f, cur);
        return LSM_OK;
    }
    const lsm_real near0 = pl->ovr_near, far0 = pl->ovr_far;
    const uint32_t sw0 = pl->ovr_switch;
    lsm_pl_wseed seed;
    lsm_pl_wseed_take(pl, &seed);
    if (f >= ovr_of(pl, cur)) {
        /* an increase (no block from the cursor on has a higher factor: near >= far) at once, if the machine can go
         * on with it (else as a decrease, beyond a switch) */
        ovr_apply(pl, f, f, cur);
        if (lsm_pl_commitment_ok(pl))
            return LSM_OK;
        pl->ovr_near = near0;
        pl->ovr_far = far0;
        pl->ovr_switch = sw0;
    }
    return ovr_switch_search(pl, f, cur, v_now, &seed) ? LSM_OK : LSM_E_PL_OVR_LATER;
}
