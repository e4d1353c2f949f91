/* pathfeed.c: the look-ahead path feed (pathfeed.h). */
#include "pathfeed.h"

#include <string.h>

#include "lsm_math.h"

/* Cycles the interpolator may stay IDLE with blocks in the planner while the path runs before the underrun
 * workaround acts (one cycle is normal: a piece is taken in the next cycle). */
#define PF_IDLE_CYCLES_MAX 2u

/* A line block's end counts as reached within this distance (mm): the interpolator ends exactly on it. */
#define PF_END_TOL_MM ((lsm_real)1e-9)
#if LSM_REAL_IS_FLOAT
/* float: the end conversion rounds; a few ulps of the coordinate on top. */
#define PF_END_TOL_REL (4 * LSM_REAL_EPS)
#else
#define PF_END_TOL_REL 0
#endif

/* Counts to mm, the same conversion for appends and end checks. */
static lsm_real to_mm(int32_t counts, lsm_real cpm)
{
    return (lsm_real)counts / cpm;
}

static lsm_status restart(lsm_pathfeed *pf, const lsm_real *pos)
{
    lsm_real start[LSM_MAX_AXES] = {0};
    for (unsigned k = 0; k < pf->n_axes; k++)
        start[k] = pos[k];
    lsm_status st = lsm_planner_init(&pf->pl, &pf->cfg, pf->storage, pf->capacity, start);
    if (st != LSM_OK)
        return st;
    (void)lsm_interp_init(&pf->ip, &pf->pl);
    if (pf->override_pct != 100u)
        (void)lsm_interp_set_override(&pf->ip, (lsm_real)pf->override_pct / 100);
    for (unsigned k = 0; k < pf->n_axes; k++) {
        pf->pos_mm[k] = pos[k];
        pf->vel_mm_s[k] = 0;
    }
    pf->holding = false;
    pf->dirty = false;
    pf->n_saved = 0u;
    pf->saved_head = 0u;
    pf->idle_cycles = 0u;
    return LSM_OK;
}

lsm_status lsm_pathfeed_init(lsm_pathfeed *pf, uint8_t n_axes, lsm_real cycle_s, const lsm_axis_limits *lim,
                             const lsm_real *pos_mm, const lsm_pathfeed_storage *mem)
{
    if (pf == NULL || lim == NULL || mem == NULL || mem->blocks == NULL || mem->saved == NULL)
        return LSM_E_NULL;
    if (n_axes < 1u || n_axes > LSM_MAX_AXES || mem->capacity < LSM_PLANNER_MIN_BLOCKS ||
        mem->saved_cap <= mem->capacity)
        return LSM_E_ARG;
    memset(pf, 0, sizeof *pf);
    pf->storage = mem->blocks;
    pf->capacity = mem->capacity;
    pf->saved = mem->saved;
    pf->saved_cap = mem->saved_cap;
    pf->n_axes = n_axes;
    pf->cycle_s = cycle_s;
    pf->override_pct = 100u;
    lsm_planner_default_config(&pf->cfg);
    pf->cfg.cycle_s = cycle_s;
    pf->cfg.axis_mask = (uint8_t)((1u << n_axes) - 1u);
    for (unsigned k = 0; k < n_axes; k++) {
        pf->cfg.axis[k].v_max = lim[k].v_max_mm_s;
        pf->cfg.axis[k].a_max = lim[k].a_max_mm_s2;
        pf->cfg.axis[k].j_max = lim[k].j_max_mm_s3;
        pf->cfg.axis[k].snap_max = lim[k].snap_max_mm_s4;
    }
    const lsm_real zero[LSM_MAX_AXES] = {0};
    lsm_status st = restart(pf, pos_mm != NULL ? pos_mm : zero);
    pf->restarts = 0;
    return st;
}

bool lsm_pathfeed_moving(const lsm_pathfeed *pf)
{
    return lsm_interp_state_of(&pf->ip) == LSM_INTERP_RUN;
}

void lsm_pathfeed_sync(lsm_pathfeed *pf, const lsm_real *pos_mm)
{
    if (lsm_pathfeed_moving(pf) || lsm_planner_count(&pf->pl) != 0u)
        return;
    for (unsigned k = 0; k < pf->n_axes; k++) {
        if (pos_mm[k] != pf->pos_mm[k]) {
            if (restart(pf, pos_mm) == LSM_OK)
                pf->restarts++;
            return;
        }
    }
}

static lsm_geom_plane plane_of(uint8_t plane, unsigned *a, unsigned *b)
{
    switch (plane) {
    case 1:
        *a = 2;
        *b = 0;
        return LSM_GEOM_PLANE_ZX;
    case 2:
        *a = 1;
        *b = 2;
        return LSM_GEOM_PLANE_YZ;
    default:
        *a = 0;
        *b = 1;
        return LSM_GEOM_PLANE_XY;
    }
}

/* Appends one co_path block to the planner. Returns the planner's status. */
static lsm_status append(lsm_pathfeed *pf, const lsm_co_path_block *b, const lsm_real *cpm)
{
    lsm_planner_move mv;
    memset(&mv, 0, sizeof mv);
    mv.feed_mm_s = (lsm_real)b->feed_um_s / 1000;
    mv.tol_mm = (lsm_real)b->tol_um / 1000;
    mv.seq = b->seq;
    if (b->type == LSM_CO_PATH_LINE) {
        lsm_real end[LSM_MAX_AXES] = {0};
        for (unsigned k = 0; k < pf->n_axes; k++)
            end[k] = to_mm(b->end[k], cpm[k]);
        return lsm_planner_append_line(&pf->pl, end, &mv);
    }
    for (unsigned k = 3; k < pf->n_axes; k++) { /* the planner's arcs move X Y Z only */
        if (to_mm(b->end[k], cpm[k]) != pf->pl.tail_pos[k])
            return LSM_E_PL_AXIS;
    }
    unsigned a, c;
    const lsm_geom_plane plane = plane_of(b->plane, &a, &c);
    lsm_real end[3], centre[3];
    for (unsigned k = 0; k < 3; k++) {
        end[k] = k < pf->n_axes ? to_mm(b->end[k], cpm[k]) : 0;
        centre[k] = pf->pl.tail_pos[k];
    }
    centre[a] = to_mm(b->centre[0], cpm[a]);
    centre[c] = to_mm(b->centre[1], cpm[c]);
    return lsm_planner_append_arc(&pf->pl, end, centre, plane, b->type == LSM_CO_PATH_ARC_CCW ? 1 : -1, 0u, &mv);
}

/* The i-th copy, 0 = oldest. */
static lsm_co_path_block *saved_at(lsm_pathfeed *pf, uint32_t i)
{
    return &pf->saved[(pf->saved_head + i) % pf->saved_cap];
}

static void save(lsm_pathfeed *pf, const lsm_co_path_block *b)
{
    if (pf->n_saved == pf->saved_cap) { /* the oldest copy is long executed (the planner holds fewer blocks) */
        pf->saved_head = (pf->saved_head + 1u) % pf->saved_cap;
        pf->n_saved--;
    }
    lsm_co_path_block *slot = saved_at(pf, pf->n_saved);
    if (slot != b)
        *slot = *b;
    pf->n_saved++;
}

/* True if the axes stand on the programmed end of block b (arcs: within the planner's arc tolerance, since
 * the planner's arc keeps its start radius). */
static bool stands_on_end(const lsm_pathfeed *pf, const lsm_co_path_block *b, const lsm_real *cpm)
{
    const lsm_real tol = b->type == LSM_CO_PATH_LINE ? PF_END_TOL_MM : (lsm_real)LSM_GEOM_ARC_TOL_MM + PF_END_TOL_MM;
    for (unsigned k = 0; k < pf->n_axes; k++) {
        const lsm_real e = to_mm(b->end[k], cpm[k]);
        if (lsm_fabs(pf->pos_mm[k] - e) > tol + PF_END_TOL_REL * lsm_fabs(e))
            return false;
    }
    return true;
}

/* The workaround described in pathfeed.h. The copies after the block the axes stand on are appended again in
 * place: after the restart the ring starts at the first of them and each append re-saves it onto itself. */
static void unstick(lsm_pathfeed *pf, const lsm_real *cpm)
{
    uint32_t i = pf->n_saved;
    while (i > 0u && !stands_on_end(pf, saved_at(pf, i - 1u), cpm))
        i--;
    if (i == 0u) {
        pf->stuck++;
        return;
    }
    const uint32_t n = pf->n_saved - i;
    const uint32_t first = (pf->saved_head + i) % pf->saved_cap;
    if (restart(pf, pf->pos_mm) != LSM_OK)
        return;
    pf->saved_head = first;
    pf->underrun_restarts++;
    for (uint32_t k = 0; k < n; k++) {
        lsm_co_path_block *b = saved_at(pf, k);
        if (append(pf, b, cpm) != LSM_OK)
            break; /* cannot happen: each was accepted before from the same point */
        save(pf, b);
    }
}

/* Epoch (clear, refused block) and override. */
static void follow_commands(lsm_pathfeed *pf, const lsm_pathfeed_io *cp)
{
    if (cp->epoch != pf->epoch) { /* clear, or a block refused: drop what the planner holds once at rest */
        if (lsm_planner_count(&pf->pl) != 0u || lsm_pathfeed_moving(pf))
            pf->dirty = true;
        pf->epoch = cp->epoch;
    }
    if (pf->dirty && !pf->holding) {
        lsm_interp_hold(&pf->ip);
        pf->holding = true;
    }
    if (pf->dirty && !lsm_pathfeed_moving(pf)) {
        if (restart(pf, pf->pos_mm) == LSM_OK)
            pf->restarts++;
    }
    if (cp->override_pct != pf->override_pct) {
        if (lsm_interp_set_override(&pf->ip, (lsm_real)cp->override_pct / 100) == LSM_OK)
            pf->override_pct = cp->override_pct;
    }
}

/* Moves blocks from the co_path buffer into the planner while it has room (the flow control of 0x5010). */
static void feed_blocks(lsm_pathfeed *pf, const lsm_pathfeed_io *io, const lsm_real *cpm)
{
    lsm_co_path_block b;
    while (lsm_planner_free(&pf->pl) >= LSM_PATHFEED_FREE_MIN && io->peek(io->ctx, &b)) {
        const lsm_status st = append(pf, &b, cpm);
        if (st == LSM_E_FULL)
            break; /* no room yet (the planner emitted the G1 points it held for arc fitting, planner.h): the block
                    * stays first in the node's buffer and is appended again on a later cycle */
        io->pop(io->ctx);
        if (st != LSM_OK) {
            pf->rejected++;
            io->reject(io->ctx, b.seq);
            break;
        }
        save(pf, &b);
        pf->appended++;
        pf->last_seq = b.seq;
    }
    /* the node's buffer ran dry: let the planner emit the G1 points it holds for arc fitting (planner.h),
     * so that the machine does not wait for blocks that may not come */
    if (io->pending(io->ctx) == 0u)
        (void)lsm_planner_flush(&pf->pl);
}

void lsm_pathfeed_background_io(lsm_pathfeed *pf, const lsm_pathfeed_io *io, const lsm_real *cpm)
{
    const lsm_co_path_motion motion = (lsm_co_path_motion)io->motion;
    pf->motion = (uint8_t)motion;
    follow_commands(pf, io);
    if (motion == LSM_CO_PATH_MOTION_RUN && !pf->dirty) {
        if (pf->holding) {
            lsm_interp_resume(&pf->ip);
            pf->holding = false;
        }
        if (lsm_interp_state_of(&pf->ip) == LSM_INTERP_IDLE && lsm_planner_count(&pf->pl) != 0u)
            pf->idle_cycles++;
        else
            pf->idle_cycles = 0u;
        if (pf->idle_cycles >= PF_IDLE_CYCLES_MAX) {
            unstick(pf, cpm);
            pf->idle_cycles = 0u;
        }
        feed_blocks(pf, io, cpm);
    } else if ((motion == LSM_CO_PATH_MOTION_HOLD || motion == LSM_CO_PATH_MOTION_QUICK) && !pf->holding) {
        lsm_interp_hold(&pf->ip);
        pf->holding = true;
    }
    (void)lsm_interp_prepare(&pf->ip); /* background planning between cycles */
}

void lsm_pathfeed_tick_io(lsm_pathfeed *pf, size_t pending, lsm_co_path_report *rep)
{
    lsm_real p[LSM_MAX_AXES];
    (void)lsm_interp_step(&pf->ip, p);
    for (unsigned k = 0; k < pf->n_axes; k++) {
        pf->vel_mm_s[k] = (p[k] - pf->pos_mm[k]) / pf->cycle_s;
        pf->pos_mm[k] = p[k];
    }
    const lsm_pblock *cur = lsm_planner_block(&pf->pl, pf->ip.blk);
    rep->active_seq = cur != NULL ? cur->seq : pf->last_seq;
    const lsm_real f = lsm_fabs(lsm_interp_feed(&pf->ip)) * 1000;
    rep->feed_um_s = f > (lsm_real)4.0e9 ? 4000000000u : (uint32_t)(f + (lsm_real)0.5);
    rep->standstill = !lsm_pathfeed_moving(pf);
    rep->starved = pf->motion == LSM_CO_PATH_MOTION_RUN && !lsm_pathfeed_moving(pf) && pending == 0u;
}

/* The synchronous loop's block source: the node's co_path buffer itself. */
static bool cp_peek(void *ctx, lsm_co_path_block *b)
{
    return lsm_co_path_peek((const lsm_co_path *)ctx, 0, b);
}

static void cp_pop(void *ctx)
{
    lsm_co_path_block b;
    (void)lsm_co_path_pop((lsm_co_path *)ctx, &b);
}

static void cp_reject(void *ctx, uint32_t seq)
{
    lsm_co_path_reject((lsm_co_path *)ctx, seq);
}

static size_t cp_pending(void *ctx)
{
    return lsm_co_path_count((const lsm_co_path *)ctx);
}

void lsm_pathfeed_background(lsm_pathfeed *pf, lsm_co_path *cp, const lsm_real *cpm)
{
    lsm_pathfeed_io io;
    io.epoch = cp->epoch;
    io.override_pct = cp->override_pct;
    io.motion = (uint8_t)lsm_co_path_get_motion(cp);
    io.peek = cp_peek;
    io.pop = cp_pop;
    io.reject = cp_reject;
    io.pending = cp_pending;
    io.ctx = cp;
    lsm_pathfeed_background_io(pf, &io, cpm);
}

void lsm_pathfeed_tick(lsm_pathfeed *pf, const lsm_co_path *cp, lsm_co_path_report *rep)
{
    lsm_pathfeed_tick_io(pf, lsm_co_path_count(cp), rep);
}

lsm_status lsm_pathfeed_restart_at(lsm_pathfeed *pf, const lsm_real *pos_mm)
{
    const lsm_status st = restart(pf, pos_mm);
    if (st == LSM_OK)
        pf->restarts++;
    return st;
}

void lsm_pathfeed_step(lsm_pathfeed *pf, lsm_co_path *cp, const lsm_real *cpm, lsm_co_path_report *rep)
{
    lsm_pathfeed_background(pf, cp, cpm);
    lsm_pathfeed_tick(pf, cp, rep);
}
