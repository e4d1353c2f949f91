/* planner.c: look-ahead velocity planner, its public entry points (see planner.h for the model). The parts:
 * plan_block.c (block intake, geometry bounds, corners), plan_fit.c (arc fitting of dense polylines),
 * plan_ramp.c (ramp verification), plan_nodes.c (the backward pass and its nodes), plan_piece.c (the forward
 * piece search). Private types and helpers: planner_int.h. */
#include <string.h>

#include "planner_int.h"

/* ------------------------------------------------------------------------------------------------------------ */
/* configuration                                                                                                */

void lsm_planner_default_config(lsm_planner_config *cfg)
{
    if (cfg == NULL)
        return;
    memset(cfg, 0, sizeof *cfg);
    cfg->cycle_s = LSM_R(0.001);
    cfg->axis_mask = 0x07u;
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        cfg->axis[i].v_max = LSM_R(250.0);
        cfg->axis[i].a_max = LSM_R(3000.0);
        cfg->axis[i].j_max = LSM_R(60000.0);
        cfg->axis[i].snap_max = LSM_R(1.2e7);
    }
    cfg->cap_margin = (lsm_real)LSM_PLANNER_CAP_MARGIN;
    cfg->node_hyst = (lsm_real)LSM_PLANNER_NODE_HYST;
    cfg->node_drop = (lsm_real)LSM_PLANNER_NODE_DROP;
    cfg->trim_share = (lsm_real)LSM_PLANNER_TRIM_SHARE;
    cfg->fit_share = (lsm_real)LSM_PLANNER_FIT_SHARE;
}

lsm_status lsm_pl_check_vals(const lsm_real *v, int n)
{
    for (int i = 0; i < n; i++) {
        int r = lsm_check_finite(v[i]);
        if (r)
            return (lsm_status)r;
    }
    return LSM_OK;
}

static lsm_status check_config(const lsm_planner_config *c)
{
    const lsm_real sc[8] = {c->cycle_s,   c->cap_margin, c->path_a_max_mm_s2, c->path_j_max_mm_s3,
                            c->node_hyst, c->node_drop,  c->trim_share,       c->fit_share};
    lsm_status st = lsm_pl_check_vals(sc, 8);
    if (st != LSM_OK)
        return st;
    if (!(c->cycle_s > R0))
        return LSM_E_CYCLE;
    if (c->axis_mask == 0 || c->axis_mask > 0x3Fu)
        return LSM_E_ARG;
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        if (!(c->axis_mask & (1u << i)))
            continue;
        const lsm_real v[4] = {c->axis[i].v_max, c->axis[i].a_max, c->axis[i].j_max, c->axis[i].snap_max};
        st = lsm_pl_check_vals(v, 4);
        if (st != LSM_OK)
            return st;
        for (int k = 0; k < 4; k++)
            if (!(v[k] > R0))
                return LSM_E_LIMIT;
    }
    if (c->path_a_max_mm_s2 < R0 || c->path_j_max_mm_s3 < R0)
        return LSM_E_LIMIT;
    if (!(c->cap_margin > R0 && c->cap_margin < R1))
        return LSM_E_ARG;
    if (!(c->node_hyst >= R0 && c->node_hyst < R1) || !(c->node_drop > R0 && c->node_drop < R1))
        return LSM_E_ARG;
    if (!(c->trim_share > R0 && c->trim_share <= LSM_R(0.5)))
        return LSM_E_ARG;
    if (!(c->fit_share >= R0 && c->fit_share < R1))
        return LSM_E_ARG;
    return LSM_OK;
}

lsm_status lsm_planner_init(lsm_planner *pl, const lsm_planner_config *cfg, lsm_pblock *storage, uint32_t capacity,
                            const lsm_real start[LSM_MAX_AXES])
{
    if (pl == NULL || cfg == NULL || storage == NULL || start == NULL)
        return LSM_E_NULL;
    lsm_status st = check_config(cfg);
    if (st != LSM_OK)
        return st;
    st = lsm_pl_check_vals(start, LSM_MAX_AXES);
    if (st != LSM_OK)
        return st;
    if (capacity < LSM_PLANNER_MIN_BLOCKS)
        return LSM_E_PL_CAPACITY;
    memset(pl, 0, sizeof *pl);
    pl->cfg = *cfg;
    pl->blk = storage;
    pl->cap = capacity;
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pl->tail_pos[i] = pl->tail_prog[i] = start[i];
    pl->ovr_near = pl->ovr_far = R1;
    pl->horizon_off = R0;
    return LSM_OK;
}

/* The first block the tick still needs: head, advanced by the release it posted and the background has not
 * applied yet (as lsm_planner_release would: at most to the tail). */
static uint32_t live_head(const lsm_planner *pl)
{
    const uint32_t r = lsm_atomic_get_acquire((lsm_atomic_u32 *)&pl->req.release_blk);
    if (!id_lt(pl->head, r))
        return pl->head;
    return id_lt(r, pl->tail) ? r : pl->tail;
}

/* Slots a held block will take (planner.c, "one block per append"). */
#define HELD_SLOTS 3u

uint32_t lsm_planner_free(const lsm_planner *pl)
{
    if (pl == NULL)
        return 0;
    const uint32_t f = pl->cap - (pl->tail - live_head(pl));
    const uint32_t h = pl->held ? HELD_SLOTS : 0u;
    return f > h ? f - h : 0u;
}

uint32_t lsm_planner_count(const lsm_planner *pl)
{
    return pl ? pl->tail - live_head(pl) + (pl->held ? 1u : 0u) : 0;
}

const lsm_pblock *lsm_planner_block(const lsm_planner *pl, uint32_t id)
{
    if (pl == NULL || id_lt(id, live_head(pl)) || !id_lt(id, pl->tail))
        return NULL;
    return blk(pl, id);
}

lsm_real lsm_planner_block_cap(const lsm_planner *pl, uint32_t id)
{
    if (lsm_planner_block(pl, id) == NULL)
        return R0;
    return cap_of(pl, id);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* one block per append                                                                                         */

/*
 * A block costs its corner smoothing and a backward pass when it is pushed (tens of thousands of instructions on the
 * M4 each). An append that first emits the pending polyline run, or completes the block the call before held, has
 * pushed one already: its own block is held (its slots reserved: lsm_planner_free, lsm_planner_count count it) and
 * pushed at the start of the next planner call (an append, flush or finish), so that no append pays for two. (An
 * arc after a G1 that was held for fitting did both in one call: the worst append of the M4 dense benchmark,
 * docs/cortex_m.md.) The plan the interpolator sees ends before the held block until then, exactly as with the G1
 * points held for fitting: a paused stream calls lsm_planner_flush.
 */
static void call_begin(lsm_planner *pl)
{
    pl->call_tail = pl->tail;
}

static lsm_status push_held(lsm_planner *pl)
{
    if (!pl->held)
        return LSM_OK;
    pl->held = 0; /* (its slots count free again for the push) */
    lsm_status st = lsm_planner_free(pl) < HELD_SLOTS ? LSM_E_FULL : LSM_OK;
    if (st == LSM_OK)
        st = lsm_pl_append_geom(pl, &pl->held_g, &pl->held_mv, pl->held_end, NULL);
    if (st != LSM_OK)
        pl->held = 1;
    return st;
}

lsm_status lsm_pl_push_or_hold(lsm_planner *pl, lsm_geom *g, const lsm_planner_move *mv, const lsm_real prog_end[6])
{
    if (lsm_planner_free(pl) < HELD_SLOTS)
        return LSM_E_FULL;
    if (pl->tail == pl->call_tail)
        return lsm_pl_append_geom(pl, g, mv, prog_end, NULL);
    pl->held_g = *g;
    pl->held_mv = *mv;
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pl->held_end[i] = prog_end[i];
    pl->held = 1;
    return LSM_OK;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* append (validation; the blocks themselves: plan_block.c, plan_fit.c)                                         */

static lsm_status check_move(const lsm_planner_move *mv)
{
    if (mv == NULL)
        return LSM_E_NULL;
    const lsm_real v[2] = {mv->feed_mm_s, mv->tol_mm};
    lsm_status st = lsm_pl_check_vals(v, mv->rapid ? 0 : 1);
    if (st == LSM_OK)
        st = lsm_pl_check_vals(v + 1, 1);
    if (st != LSM_OK)
        return st;
    if (!mv->rapid && !(mv->feed_mm_s > R0))
        return LSM_E_NEG_FEED;
    if (mv->tol_mm < R0)
        return LSM_E_TOLERANCE;
    return LSM_OK;
}

static lsm_status check_append(const lsm_planner *pl, const lsm_planner_move *mv)
{
    if (pl == NULL || mv == NULL)
        return LSM_E_NULL;
    lsm_status st = check_move(mv);
    if (st != LSM_OK)
        return st;
    if (pl->finished)
        return LSM_E_PL_FINISHED;
    return LSM_OK;
}

/* The last check of an append, then its start: an axis outside the mask must stay where it is (the first n_axes
 * of end); the call begins, and the block the call before held is pushed first (it was checked then). */
static lsm_status begin_append(lsm_planner *pl, const lsm_real *end, int n_axes)
{
    for (int i = 0; i < n_axes; i++)
        if (!(pl->cfg.axis_mask & (1u << i)) && end[i] != pl->tail_pos[i])
            return LSM_E_PL_AXIS;
    call_begin(pl);
    return push_held(pl);
}

lsm_status lsm_planner_append_line(lsm_planner *pl, const lsm_real end[LSM_MAX_AXES], const lsm_planner_move *mv)
{
    if (end == NULL)
        return LSM_E_NULL;
    lsm_planner_apply_requests(pl); /* the tick's requests first (planner.h) */
    lsm_status st = check_append(pl, mv);
    if (st != LSM_OK)
        return st;
    st = lsm_pl_check_vals(end, LSM_MAX_AXES);
    if (st != LSM_OK)
        return st;
    st = begin_append(pl, end, LSM_MAX_AXES);
    if (st != LSM_OK)
        return st;
    /* the line starts at the last point held for fitting, or at the end of the last block */
    lsm_real from[LSM_MAX_AXES];
    for (int i = 0; i < LSM_MAX_AXES; i++)
        from[i] = (i < 3 && pl->fit_n > 0) ? pl->fit_pt[pl->fit_n - 1u].p[i] : pl->tail_pos[i];
    lsm_geom g;
    st = lsm_geom_line_init(&g, from, end);
    if (st != LSM_OK)
        return st;
    if (g.len <= LINE_LEN_EPS * (R1 + lsm_fabs(end[0]) + lsm_fabs(end[1]) + lsm_fabs(end[2])) && !g.rotary_only)
        return LSM_E_ZERO_LENGTH;
    st = lsm_pl_append_line_fit(pl, &g, end, mv);
    return st;
}

lsm_status lsm_planner_append_arc(lsm_planner *pl, const lsm_real end[3], const lsm_real centre[3],
                                  lsm_geom_plane plane, int dir, uint32_t turns, const lsm_planner_move *mv)
{
    if (end == NULL || centre == NULL)
        return LSM_E_NULL;
    lsm_planner_apply_requests(pl); /* the tick's requests first (planner.h) */
    lsm_status st = check_append(pl, mv);
    if (st != LSM_OK)
        return st;
    st = lsm_pl_check_vals(end, 3);
    if (st == LSM_OK)
        st = lsm_pl_check_vals(centre, 3);
    if (st != LSM_OK)
        return st;
    st = begin_append(pl, end, 3);
    if (st != LSM_OK)
        return st;
    lsm_real pe[LSM_MAX_AXES];
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pe[i] = i < 3 ? end[i] : pl->tail_pos[i];
    /* an arc ends a pending polyline run: emit it first (the arc starts at its last point) */
    if (pl->fit_n > 0 && lsm_planner_free(pl) < lsm_pl_run_slots(pl) + 3u)
        return LSM_E_FULL;
    lsm_real from[3];
    for (int i = 0; i < 3; i++)
        from[i] = pl->fit_n > 0 ? pl->fit_pt[pl->fit_n - 1u].p[i] : pl->tail_pos[i];
    lsm_geom g;
    st = lsm_geom_arc_init(&g, from, end, centre, plane, dir, turns);
    if (st != LSM_OK)
        return st;
    /* the arc's plane must lie in the existing axes */
    for (int i = 0; i < 3; i++)
        if (!(pl->cfg.axis_mask & (1u << i)) && (g.u.arc.e1[i] != R0 || g.u.arc.e2[i] != R0 ||
                                                 (g.u.arc.axial_mm != R0 && i == (plane == LSM_GEOM_PLANE_XY   ? 2
                                                                                  : plane == LSM_GEOM_PLANE_ZX ? 1
                                                                                                               : 0))))
            return LSM_E_PL_AXIS;
    if (!(g.len > LEN_EPS))
        return LSM_E_ZERO_LENGTH;
    st = lsm_pl_emit_run(pl, pl->fit_n);
    if (st != LSM_OK)
        return st;
    st = lsm_pl_push_or_hold(pl, &g, mv, pe);
    if (st == LSM_OK)
        pl->stats.appended++;
    return st;
}

lsm_status lsm_planner_flush(lsm_planner *pl)
{
    if (pl == NULL)
        return LSM_E_NULL;
    lsm_planner_apply_requests(pl); /* the tick's requests first (planner.h) */
    call_begin(pl);
    const lsm_status st = push_held(pl);
    return st != LSM_OK ? st : lsm_pl_emit_run(pl, pl->fit_n);
}

/* The program ends exactly on its programmed end: a fitted arc or line that ends off it (kept in the previous arc's
 * plane, it ends off its last point by that point's distance from the plane, within the fit tolerance: plan_fit.c) is
 * followed by a line to it. (A pending run is split for that by lsm_pl_emit_run_exact; this covers a run emitted
 * when it reached LSM_ARCFIT_MAX points with the program's last point.) */
static lsm_status end_exactly(lsm_planner *pl)
{
    /* (tail_arc: the last block is a fitted arc; a fitted line has a fit error, and may end on its last point's
     * projection into the plane of the arc before it) */
    if (pl->tail == pl->head || !(pl->tail_arc || pl->tail_fit_err > R0))
        return LSM_OK;
    if (pl->tail_pos[0] == pl->tail_prog[0] && pl->tail_pos[1] == pl->tail_prog[1] &&
        pl->tail_pos[2] == pl->tail_prog[2])
        return LSM_OK;
    if (lsm_planner_free(pl) < 3)
        return LSM_E_FULL;
    const lsm_pblock *last = blk(pl, pl->tail - 1u);
    lsm_planner_move mv;
    mv.feed_mm_s = last->feed_mm_s;
    mv.tol_mm = R0;
    mv.seq = last->seq;
    mv.rapid = 0;
    lsm_geom g;
    lsm_real end[LSM_MAX_AXES];
    for (int i = 0; i < LSM_MAX_AXES; i++)
        end[i] = pl->tail_prog[i];
    if (lsm_geom_line_init(&g, pl->tail_pos, end) != LSM_OK || !(g.len > R0))
        return LSM_OK;
    return lsm_pl_append_geom(pl, &g, &mv, end, NULL);
}

lsm_status lsm_planner_finish(lsm_planner *pl)
{
    if (pl == NULL)
        return LSM_E_NULL;
    lsm_planner_apply_requests(pl); /* the tick's requests first (planner.h) */
    if (pl->finished)
        return LSM_OK;
    call_begin(pl);
    lsm_status st = push_held(pl);
    if (st == LSM_OK)
        st = lsm_pl_emit_run_exact(pl);
    if (st == LSM_OK)
        st = end_exactly(pl);
    if (st != LSM_OK)
        return st;
    pl->finished = 1;
    pl->gen++;
    return LSM_OK;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* the interpolator's commitment                                                                                */

void lsm_planner_set_horizon(lsm_planner *pl, uint32_t id, lsm_real off_mm, lsm_real v_mm_s, uint32_t end_blk,
                             lsm_real end_v_mm_s)
{
    if (pl == NULL)
        return;
    pl->horizon_blk = id;
    pl->horizon_off = off_mm;
    pl->horizon_v = v_mm_s > R0 ? v_mm_s : R0;
    const lsm_real ev = end_v_mm_s > R0 ? end_v_mm_s : R0;
    if (end_blk != pl->horizon_end || ev != pl->horizon_end_v)
        pl->commit_dirty = 1;
    pl->horizon_end = end_blk;
    pl->horizon_end_v = ev;
}

/* Does the interpolator's current piece still end where it may go on (planner.h, lsm_planner_set_horizon)? */
bool lsm_pl_commitment_kept(lsm_planner *pl)
{
    const uint32_t e = pl->horizon_end;
    if (!(pl->horizon_v > R0) || !(pl->horizon_end_v > R0) || id_lt(e, pl->head) || !id_lt(e, pl->tail))
        return true;
    if (blk(pl, e)->flags & LSM_PB_STOP)
        return false;
    /* The test depends on the blocks from e to the node after it and on that node's W. A backward pass that stopped
     * at or after that node (bp_stop: everything before it unchanged) changed none of it, unless the stretch runs
     * to the end of the buffer (a trim, or new blocks behind it). Else verified afresh, not read from the node's
     * W: valleys move when blocks are appended (a node can vanish, or the one after it change).
     * That holds for a new commitment too (commit_dirty, a piece taken since the last check): the interpolator
     * takes a piece only on the planner generation it was planned on (interp.h; every append changes it), so no
     * backward pass ran between its planning, which verified its arrival at e, and this one. (Verifying every new
     * commitment afresh cost an arrival test per piece, 1-3 ramp verifications, in the append after it.) */
    lsm_real w2;
    const uint32_t n2 = lsm_pl_node_after(pl, e, &w2);
    if (n2 != pl->tail && !id_lt(pl->bp_stop, n2))
        return true;
    const bool ok = lsm_pl_arrival_ok(pl, e, pl->horizon_end_v);
    if (ok)
        pl->commit_dirty = 0;
    return ok;
}

/* Does the plan just made keep the interpolator going (planner.h, "Commitment")? Its current piece still ends where it
 * can go on, or a verified piece starts at its horizon (then the current piece is stale: it is replaced there). */
bool lsm_pl_commitment_ok(lsm_planner *pl)
{
    if (lsm_pl_commitment_kept(pl))
        return true;
    if (!lsm_pl_horizon_feasible(pl, true))
        return false;
    lsm_pl_mark_stale(pl);
    return true;
}

void lsm_planner_release(lsm_planner *pl, uint32_t id)
{
    if (pl == NULL)
        return;
    while (id_lt(pl->head, id) && pl->head != pl->tail) {
        pl->head++;
        pl->head_slot = (pl->head_slot + 1u) % pl->cap;
    }
}

/* ------------------------------------------------------------------------------------------------------------ */
/* the tick's requests (planner.h, lsm_planner_req; lsm_atomic.h)                                               */

void lsm_planner_post_release(lsm_planner *pl, uint32_t id)
{
    if (pl == NULL || !id_lt(lsm_atomic_get(&pl->req.release_blk), id))
        return; /* releases only grow (an earlier id frees nothing more) */
    lsm_seq_write_begin(&pl->req.seq);
    lsm_seq_put(&pl->req.release_blk, id);
    lsm_seq_write_end(&pl->req.seq);
}

void lsm_planner_post_horizon(lsm_planner *pl, uint32_t id, lsm_real off_mm, lsm_real v_mm_s, uint32_t end_blk,
                              lsm_real end_v_mm_s)
{
    if (pl == NULL)
        return;
    lsm_planner_req *r = &pl->req;
    const lsm_real ev = end_v_mm_s > R0 ? end_v_mm_s : R0;
    /* the tick's own previous post (or the initial commitment) is what lsm_planner_set_horizon compares with */
    const bool changed = end_blk != lsm_atomic_get(&r->hz_end) || ev != lsm_atomic_get(&r->hz_end_v);
    lsm_seq_write_begin(&r->seq);
    lsm_seq_put(&r->hz_blk, id);
    lsm_seq_put(&r->hz_off, off_mm);
    lsm_seq_put(&r->hz_v, v_mm_s > R0 ? v_mm_s : R0);
    lsm_seq_put(&r->hz_end, end_blk);
    lsm_seq_put(&r->hz_end_v, ev);
    if (changed)
        lsm_seq_put(&r->end_changes, lsm_atomic_get(&r->end_changes) + 1u);
    lsm_seq_put(&r->hz_posted, 1u);
    lsm_seq_write_end(&r->seq);
}

void lsm_planner_post_stale_ack(lsm_planner *pl, uint32_t stale_seen)
{
    if (pl == NULL)
        return;
    lsm_seq_write_begin(&pl->req.seq);
    lsm_seq_put(&pl->req.stale_ack, stale_seen);
    lsm_seq_write_end(&pl->req.seq);
}

/* One consistent copy of the requests (sequence lock, reader side). */
typedef struct req_copy {
    uint32_t seq, release_blk, hz_posted, hz_blk, hz_end, end_changes;
    lsm_real hz_off, hz_v, hz_end_v;
} req_copy;

static void read_requests(lsm_planner_req *r, req_copy *c)
{
    uint32_t s;
    do {
        s = lsm_seq_read_begin(&r->seq);
        c->release_blk = lsm_seq_get(&r->release_blk);
        c->hz_posted = lsm_seq_get(&r->hz_posted);
        c->hz_blk = lsm_seq_get(&r->hz_blk);
        c->hz_off = lsm_seq_get(&r->hz_off);
        c->hz_v = lsm_seq_get(&r->hz_v);
        c->hz_end = lsm_seq_get(&r->hz_end);
        c->hz_end_v = lsm_seq_get(&r->hz_end_v);
        c->end_changes = lsm_seq_get(&r->end_changes);
    } while (lsm_seq_read_retry(&r->seq, s));
    c->seq = s;
}

void lsm_planner_apply_requests(lsm_planner *pl)
{
    if (pl == NULL)
        return;
    req_copy c;
    read_requests(&pl->req, &c);
    if (c.seq == pl->req_seq_applied)
        return;
    pl->req_seq_applied = c.seq;
    lsm_planner_release(pl, c.release_blk);
    if (c.hz_posted) {
        pl->horizon_blk = c.hz_blk;
        pl->horizon_off = c.hz_off;
        pl->horizon_v = c.hz_v;
        pl->horizon_end = c.hz_end;
        pl->horizon_end_v = c.hz_end_v;
        if (c.end_changes != pl->end_changes_applied) /* as lsm_planner_set_horizon: the end moved */
            pl->commit_dirty = 1;
        pl->end_changes_applied = c.end_changes;
    }
}

void lsm_pl_mark_stale(lsm_planner *pl)
{
    /* counted even when already stale: a piece planned before this change must not clear it when taken */
    lsm_atomic_put_release(&pl->stale_set, lsm_atomic_get(&pl->stale_set) + 1u);
}
