/* plan_fit.c: dense G1 polylines fitted with arcs or lines within fit_share of the tolerance (arcfit.h), where the
 * per-vertex transitions would limit the feed (planner.h, "Blocks and corners"). */
#include "planner_int.h"

/* How far (share of the fit tolerance) the points may leave the plane of a chain of fitted arcs: the rest is for the
 * line in that plane that closes the chain when they leave it (its error is their offset plus its sagitta). */
#define CHAIN_DRIFT LSM_R(0.5)
/* tail_switch after a closing line whose chain was too short to measure its plane: a free line, then as after any
 * line (run_plane) */
#define SW_BACK_ONLY 4u
/* A vertex turning by less than this (rad) is straight: no transition, no feed limit. */
#define VERTEX_STRAIGHT_RAD LSM_R(1e-9)
/* Small-angle closed form of corner.h: a transition's half-length is this many tolerances per radian of turn. */
#define VERTEX_L_PER_EPS LSM_R(6.0)
/* A line lies in a fitted arc's plane when its direction's component along the normal is below this (rounding). */
#if LSM_REAL_IS_FLOAT
#define PLANE_DOT_TOL LSM_R(1e-6)
#else
#define PLANE_DOT_TOL LSM_R(1e-10)
#endif

/* ------------------------------------------------------------------------------------------------------------ */
/* polyline fitting (arcfit.h)                                                                                  */

/* Feed a clothoid pair on a vertex of a polyline would allow (estimate): a vertex turning by delta between segments
 * h1, h2 gets transitions of half-length L = min(6 eps / delta, min(h1, h2) / 2) (small-angle closed form of
 * corner.h), curvature delta / L and sharpness delta / L²; then eqs 7 and 8 (with the kappa² term) with the
 * smallest axis limits. */
static lsm_real vertex_speed(const lsm_planner *pl, lsm_real h1, lsm_real h2, lsm_real delta, lsm_real eps)
{
    if (!(delta > VERTEX_STRAIGHT_RAD))
        return LSM_REAL_MAX;
    const lsm_real L = lsm_min2(VERTEX_L_PER_EPS * eps / delta, LSM_R(0.5) * lsm_min2(h1, h2));
    if (!(L > R0))
        return R0;
    lsm_real amin = LSM_REAL_MAX, jmin = LSM_REAL_MAX;
    for (int i = 0; i < 3; i++) {
        if (!(pl->cfg.axis_mask & (1u << i)))
            continue;
        amin = lsm_min2(amin, pl->cfg.axis[i].a_max);
        jmin = lsm_min2(jmin, pl->cfg.axis[i].j_max);
    }
    const lsm_real k = delta / L, c = delta / (L * L), rho = pl->cfg.cap_margin;
    return lsm_min2(lsm_sqrt(rho * amin / k), lsm_cbrt(rho * jmin / (c + k * k)));
}

/* Would a clothoid pair on vertex a (segments prev -> a -> b) limit the feed below `feed` (tolerance eps)? */
static bool vertex_limits(const lsm_planner *pl, const lsm_real *prev, const lsm_real *a, const lsm_real *b,
                          lsm_real eps, lsm_real feed)
{
    lsm_real u[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = a[k] - prev[k];
        w[k] = b[k] - a[k];
    }
    const lsm_real h1 = lsm_sqrt(lsm_dot3(u, u));
    const lsm_real h2 = lsm_sqrt(lsm_dot3(w, w));
    if (!(h1 > R0 && h2 > R0))
        return false;
    lsm_real cs = lsm_dot3(u, w) / (h1 * h2);
    cs = lsm_min2(R1, lsm_max2(-R1, cs));
    const lsm_real delta = lsm_atan2(lsm_sqrt(lsm_max2(R0, R1 - cs * cs)), cs);
    return vertex_speed(pl, h1, h2, delta, eps) < feed;
}

/* Would clothoid pairs on the run's own vertices limit the feed below the programmed one? */
static bool run_needs_fit(const lsm_planner *pl, uint32_t n)
{
    const lsm_real *prev = pl->tail_pos;
    for (uint32_t i = 0; i + 1u < n; i++) {
        if (vertex_limits(pl, prev, pl->fit_pt[i].p, pl->fit_pt[i + 1u].p, pl->fit_tol, pl->fit_feed))
            return true;
        prev = pl->fit_pt[i].p;
    }
    return false;
}

/* The plane a run's element keeps to (arcfit.h); NULL: any (then an arc must hold the line before it:
 * arc_fits_tail). Chains of fitted arcs and their change of plane (lsm_arcfit_chain):
 *   - in a chain (the last block a fitted arc), its elements stay in its plane, and the points may leave it by
 *     CHAIN_DRIFT of the fit tolerance (its first plane came from one run's rounded points: a tilted ring leaves it
 *     within a turn);
 *   - the first run that leaves it is a line in that plane, which closes the chain (arcfit.h: `drifted`); then, with
 *     the plane measured over the chain's points, a free line (back onto the points: the closing line ended off them
 *     by their offset from the chain's plane), a line in the measured plane through that line's end (a programmed
 *     point), and a new chain in the measured plane (tail_switch 1, 2, 3). Every joint is planar (an arc and a line
 *     in its plane, or two lines), so corner.h blends it G2 within the tolerance; the lines cost a dip of the feed
 *     where they are (the trims of their corners are short), once: the measured plane holds (test_planner_scale). */
static const lsm_arcfit_plane *run_plane(const lsm_planner *pl, lsm_arcfit_plane *pc)
{
    if (pl->tail == pl->head)
        return NULL;
    const lsm_real tfit = pl->cfg.fit_share * pl->fit_tol;
    for (int i = 0; i < 3; i++)
        pc->v[i] = pl->tail_n[i];
    pc->drift_mm = CHAIN_DRIFT * tfit;
    if (pl->tail_arc) {
        pc->kind = LSM_ARCFIT_PLANE_NORMAL;
        return pc;
    }
    const lsm_pblock *prev = blk(pl, pl->tail - 1u);
    if (prev->g.kind != LSM_GEOM_LINE || prev->g.rotary_only)
        return NULL;
    if (pl->tail_switch == 0) { /* after a line that ends on a programmed point: a plane that holds it */
        pc->kind = LSM_ARCFIT_PLANE_CONTAINS;
        for (int i = 0; i < 3; i++)
            pc->v[i] = prev->g.u.line.dir[i];
        return pc;
    }
    pc->kind = pl->tail_switch == 1 || pl->tail_switch == SW_BACK_ONLY ? LSM_ARCFIT_LINE_FREE
               : pl->tail_switch == 2                                  ? LSM_ARCFIT_LINE_IN
                                                                       : LSM_ARCFIT_PLANE_NORMAL;
    return pc;
}

/* The previous block and a fitted arc must share a plane (corner.h blends planar joints only). */
static bool arc_fits_tail(const lsm_planner *pl, const lsm_arcfit_result *fr)
{
    if (pl->tail == pl->head || pl->tail_arc)
        return true; /* nothing before, or the arc was fitted in the previous arc's plane */
    const lsm_pblock *prev = blk(pl, pl->tail - 1u);
    if (prev->g.kind != LSM_GEOM_LINE)
        return false;
    const lsm_real *d = prev->g.u.line.dir;
    const lsm_real dn = lsm_dot3(d, fr->normal);
    return lsm_fabs(dn) <= PLANE_DOT_TOL;
}

/* The element a run of the first n pending points is emitted as: one fitted arc or line (true: g, fr) where that
 * helps (an arc only where the per-vertex transitions would limit the feed, and in the previous block's plane),
 * else its segments as they are (false). */
static bool run_element(const lsm_planner *pl, uint32_t n, lsm_geom *g, lsm_arcfit_result *fr)
{
    const lsm_real tfit = pl->cfg.fit_share * pl->fit_tol;
    lsm_arcfit_plane pc;
    bool fitted = n >= 2u && lsm_arcfit_fit(pl->tail_pos, pl->fit_pt, (int)n, tfit, run_plane(pl, &pc), g, fr);
    if (fitted && fr->kind == LSM_ARCFIT_ARC && (!arc_fits_tail(pl, fr) || !run_needs_fit(pl, n)))
        fitted = false;
    if (fitted && fr->kind == LSM_ARCFIT_LINE) {
        /* (its end: the last point, or in a fitted arc's plane that point's projection there: arcfit.h) */
        lsm_real end[LSM_MAX_AXES];
        for (int i = 0; i < LSM_MAX_AXES; i++)
            end[i] = i < 3 ? fr->end_mm[i] : pl->tail_pos[i];
        if (lsm_geom_line_init(g, pl->tail_pos, end) != LSM_OK)
            fitted = false;
    }
    return fitted;
}

_Static_assert(3 * LSM_ARCFIT_MAX <= 255, "lsm_planner.fit_slots is a uint8_t");

/* Slots a run of n points takes when it is emitted (run_element): one element and the clothoid pair of its corner,
 * or a block and a corner pair per segment. `fits`, fr: the run's fit; needs_fit: run_needs_fit of the run. */
LSM_NOINLINE static uint32_t run_slots(const lsm_planner *pl, uint32_t n, bool fits, const lsm_arcfit_result *fr,
                                       bool needs_fit)
{
    if (n >= 2u && fits && (fr->kind == LSM_ARCFIT_LINE || (needs_fit && arc_fits_tail(pl, fr))))
        return 3u;
    return 3u * n;
}

/* After a fitted element of the first n pending points was appended (it started at `start`; before it: a fitted
 * arc of plane chain_n (in_chain), or the change of plane at step sw (run_plane)): the chain's measurement, and the
 * next step of a change of plane. */
static void chain_step(lsm_planner *pl, const lsm_geom *g, const lsm_arcfit_result *fr, uint32_t n,
                       const lsm_real start[3], bool in_chain, uint8_t sw, const lsm_real chain_n[3])
{
    if (fr->kind == LSM_ARCFIT_ARC) {
        if (!in_chain)
            lsm_arcfit_chain_reset(&pl->chain, start);
        lsm_arcfit_chain_add(&pl->chain, fr->normal, pl->fit_pt, (int)n);
        return;
    }
    if (g->kind != LSM_GEOM_LINE)
        return;
    lsm_real nn[3];
    if (in_chain && fr->drifted) { /* the line that closes the chain: its points left the chain's plane */
        lsm_arcfit_chain_add(&pl->chain, chain_n, pl->fit_pt, (int)n);
        if (!lsm_arcfit_chain_plane(&pl->chain, chain_n, nn)) {
            /* too few points to measure: back onto the points, then as after any line */
            pl->tail_switch = SW_BACK_ONLY;
            return;
        }
        sw = 0u;
    } else if (sw == 0u || sw == SW_BACK_ONLY) {
        return;
    } else {
        for (int i = 0; i < 3; i++)
            nn[i] = chain_n[i];
    }
    for (int i = 0; i < 3; i++)
        pl->tail_n[i] = nn[i];
    pl->tail_switch = (uint8_t)(sw < 3u ? sw + 1u : 3u);
}

/* Emits the first n pending points: one fitted arc or line if that helps, else their segments as they are. */
lsm_status lsm_pl_emit_run(lsm_planner *pl, uint32_t n)
{
    if (n == 0)
        return LSM_OK;
    lsm_geom g;
    lsm_arcfit_result fr;
    const bool fitted = run_element(pl, n, &g, &fr);
    if (lsm_planner_free(pl) < (fitted ? 3u : 3u * n))
        return LSM_E_FULL;
    lsm_planner_move mv;
    mv.feed_mm_s = pl->fit_feed;
    mv.tol_mm = pl->fit_tol;
    mv.rapid = 0;
    lsm_real end[LSM_MAX_AXES];
    for (int i = 0; i < LSM_MAX_AXES; i++)
        end[i] = pl->tail_pos[i];
    lsm_status st = LSM_OK;
    if (fitted) {
        for (int i = 0; i < 3; i++)
            end[i] = pl->fit_pt[n - 1u].p[i];
        mv.seq = pl->fit_pt[n - 1u].seq;
        const lsm_real start[3] = {pl->tail_pos[0], pl->tail_pos[1], pl->tail_pos[2]};
        const lsm_real chain_n[3] = {pl->tail_n[0], pl->tail_n[1], pl->tail_n[2]};
        const bool in_chain = pl->tail_arc != 0;
        const uint8_t sw = pl->tail_switch;
        st = lsm_pl_append_geom(pl, &g, &mv, end, &fr);
        if (st == LSM_OK)
            chain_step(pl, &g, &fr, n, start, in_chain, sw, chain_n);
    } else {
        for (uint32_t i = 0; i < n && st == LSM_OK; i++) {
            for (int k = 0; k < 3; k++)
                end[k] = pl->fit_pt[i].p[k];
            mv.seq = pl->fit_pt[i].seq;
            if (lsm_geom_line_init(&g, pl->tail_pos, end) != LSM_OK)
                continue; /* a point on the previous one (cannot happen: zero lengths are rejected) */
            st = lsm_pl_append_geom(pl, &g, &mv, end, NULL);
        }
    }
    for (uint32_t i = n; i < pl->fit_n; i++)
        pl->fit_pt[i - n] = pl->fit_pt[i];
    pl->fit_n -= n;
    /* (the callers emit the whole run; what would remain is kept at its worst case) */
    pl->fit_need = pl->fit_n > 0 && run_needs_fit(pl, pl->fit_n) ? 1u : 0u;
    pl->fit_slots = (uint8_t)(3u * pl->fit_n);
    return st;
}

/*
 * The whole pending run, ending exactly on its last point (end of program). An arc fitted in the previous arc's
 * plane (arcfit.h: consecutive arcs share a plane, so that their corner can be blended) ends off its last point by
 * that point's distance from the plane (within the fit tolerance; a ring in a tilted plane, rounded to 0.1 um: a
 * few um). The next block then starts where the arc ends; at the end of the program there is none: the last point
 * gets a line of its own (lines end exactly on their point), after the run without it.
 */
lsm_status lsm_pl_emit_run_exact(lsm_planner *pl)
{
    const uint32_t n = pl->fit_n;
    if (n < 2u)
        return lsm_pl_emit_run(pl, n);
    lsm_geom g;
    lsm_arcfit_result fr;
    lsm_real end[LSM_MAX_AXES], prog[LSM_MAX_AXES];
    if (!run_element(pl, n, &g, &fr))
        return lsm_pl_emit_run(pl, n);
    for (int i = 0; i < LSM_MAX_AXES; i++)
        prog[i] = i < 3 ? pl->fit_pt[n - 1u].p[i] : pl->tail_pos[i];
    if (lsm_pl_geom_end(&g, pl->tail_pos, prog, end))
        return lsm_pl_emit_run(pl, n);
    const uint32_t head = run_element(pl, n - 1u, &g, &fr) ? 3u : 3u * (n - 1u);
    if (lsm_planner_free(pl) < head + 3u) /* the run without its last point, then a line */
        return LSM_E_FULL;
    const lsm_status st = lsm_pl_emit_run(pl, n - 1u);
    return st != LSM_OK ? st : lsm_pl_emit_run(pl, pl->fit_n);
}

/* Slots the pending run would take when emitted (what lsm_pl_emit_run checks). */
uint32_t lsm_pl_run_slots(const lsm_planner *pl)
{
    return pl->fit_slots;
}

/*
 * A point that may join the pending run. The run is held while its points fit one arc or line; the slots its
 * emission will take are reserved as it grows (run_slots): 3 while it fits one element, so that a full buffer (a
 * feeder that appends whenever 3 slots are free) still lets runs grow to LSM_ARCFIT_MAX points. (Reserving the
 * worst case, a block and a corner per point, cut the runs to a point or two once the buffer was full: every
 * vertex then got its own clothoid pair, whose curvature on the scale of the segments capped the feed; long dense
 * programs collapsed once the buffer first filled.)
 */
static lsm_status add_fit_point(lsm_planner *pl, const lsm_real end[LSM_MAX_AXES], const lsm_planner_move *mv)
{
    lsm_status st;
    bool fits = false, needs = false;
    lsm_arcfit_result fr;
    fr.kind = LSM_ARCFIT_NONE;
    if (pl->fit_n > 0) {
        lsm_arcfit_pt cand[LSM_ARCFIT_MAX + 1];
        for (uint32_t i = 0; i < pl->fit_n; i++)
            cand[i] = pl->fit_pt[i];
        for (int k = 0; k < 3; k++)
            cand[pl->fit_n].p[k] = end[k];
        cand[pl->fit_n].seq = mv->seq;
        lsm_geom tg;
        lsm_arcfit_plane pc;
        fits = lsm_arcfit_fit(pl->tail_pos, cand, (int)pl->fit_n + 1, pl->cfg.fit_share * mv->tol_mm,
                              run_plane(pl, &pc), &tg, &fr);
        if (!fits) {
            st = lsm_pl_emit_run(pl, pl->fit_n); /* the run ends before this point (its room was reserved) */
            if (st != LSM_OK)
                return st;
        } else {
            const lsm_real *prev = pl->fit_n >= 2u ? pl->fit_pt[pl->fit_n - 2u].p : pl->tail_pos;
            needs =
                pl->fit_need || vertex_limits(pl, prev, pl->fit_pt[pl->fit_n - 1u].p, end, mv->tol_mm, mv->feed_mm_s);
        }
    }
    uint32_t slots = run_slots(pl, pl->fit_n + 1u, fits, &fr, needs);
    if (lsm_planner_free(pl) < slots) {
        /* the run with this point could not be emitted: it ends before this point */
        if (pl->fit_n == 0 || lsm_planner_free(pl) < pl->fit_slots)
            return LSM_E_FULL;
        st = lsm_pl_emit_run(pl, pl->fit_n);
        if (st != LSM_OK)
            return st;
        needs = false;
        slots = 3u;
        if (lsm_planner_free(pl) < slots)
            return LSM_E_FULL; /* (the run was emitted; this point is not taken: append it again) */
    }
    pl->fit_feed = mv->feed_mm_s;
    pl->fit_tol = mv->tol_mm;
    for (int k = 0; k < 3; k++)
        pl->fit_pt[pl->fit_n].p[k] = end[k];
    pl->fit_pt[pl->fit_n].seq = mv->seq;
    pl->fit_n++;
    pl->fit_need = needs ? 1u : 0u;
    pl->fit_slots = (uint8_t)slots;
    pl->stats.appended++;
    if (pl->fit_n == LSM_ARCFIT_MAX)
        return lsm_pl_emit_run(pl, pl->fit_n);
    return LSM_OK;
}

/*
 * May a new run start here? Not right after a block that no fitted arc may follow (a programmed arc: a fitted arc
 * needs a line or a fitted arc in its plane before it, arc_fits_tail). Such a run could only become a fitted line,
 * and holding its first point moved that segment's corner and backward pass into the next append: an arc after it
 * then did two appends' work in one call (the emitted segment and the arc, two corners and two backward passes; the
 * worst append of the M4 dense benchmark, docs/cortex_m.md). Appended at once, the segment also lets the points
 * after it be fitted with arcs (they follow a line).
 */
static bool run_may_start(const lsm_planner *pl)
{
    if (pl->fit_n > 0 || pl->tail == pl->head || pl->tail_arc)
        return true;
    return blk(pl, pl->tail - 1u)->g.kind == LSM_GEOM_LINE;
}

/* A line that may join the pending polyline run. */
lsm_status lsm_pl_append_line_fit(lsm_planner *pl, lsm_geom *g, const lsm_real end[LSM_MAX_AXES],
                                  const lsm_planner_move *mv)
{
    const bool eligible = pl->cfg.fit_share > R0 && !mv->rapid && mv->tol_mm > R0 && !g->rotary_only &&
                          !lsm_geom_moves_rotary(g) && run_may_start(pl);
    lsm_status st;
    if (!eligible || (pl->fit_n > 0 && (mv->feed_mm_s != pl->fit_feed || mv->tol_mm != pl->fit_tol))) {
        st = lsm_pl_emit_run(pl, pl->fit_n);
        if (st != LSM_OK)
            return st;
    }
    if (!eligible) {
        st = lsm_pl_push_or_hold(pl, g, mv, end);
        if (st == LSM_OK)
            pl->stats.appended++;
        return st;
    }
    return add_fit_point(pl, end, mv);
}
