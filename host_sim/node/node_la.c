#include "node_la.h"

#include <math.h>
#include <string.h>

static lsm_status restart(node_la *la, const double *pos)
{
    lsm_real start[LSM_MAX_AXES] = {0};
    for (unsigned k = 0; k < la->n_axes; k++)
        start[k] = (lsm_real)pos[k];
    lsm_status st = lsm_planner_init(&la->pl, &la->cfg, la->storage, la->capacity, start);
    if (st != LSM_OK)
        return st;
    (void)lsm_interp_init(&la->ip, &la->pl);
    if (la->override_pct != 100u)
        (void)lsm_interp_set_override(&la->ip, (lsm_real)la->override_pct / 100);
    for (unsigned k = 0; k < la->n_axes; k++) {
        la->pos[k] = pos[k];
        la->vel[k] = 0;
    }
    la->holding = false;
    la->dirty = false;
    la->n_saved = 0u;
    la->idle_cycles = 0u;
    return LSM_OK;
}

lsm_status node_la_init(node_la *la, uint8_t n_axes, double cycle_s, const node_axis_limits *lim, const double *pos,
                        uint32_t capacity)
{
    memset(la, 0, sizeof *la);
    la->capacity = capacity < LSM_PLANNER_MIN_BLOCKS ? LSM_PLANNER_MIN_BLOCKS
                   : capacity > NODE_LA_BLOCKS     ? NODE_LA_BLOCKS
                                                   : capacity;
    la->n_axes = n_axes;
    la->cycle_s = cycle_s;
    la->override_pct = 100u;
    lsm_planner_default_config(&la->cfg);
    la->cfg.cycle_s = (lsm_real)cycle_s;
    la->cfg.axis_mask = (uint8_t)((1u << n_axes) - 1u);
    for (unsigned k = 0; k < n_axes; k++) {
        la->cfg.axis[k].v_max = (lsm_real)lim[k].v_max;
        la->cfg.axis[k].a_max = (lsm_real)lim[k].a_max;
        la->cfg.axis[k].j_max = (lsm_real)lim[k].j_max;
        la->cfg.axis[k].snap_max = (lsm_real)lim[k].snap_max;
    }
    double zero[LSM_MAX_AXES] = {0};
    lsm_status st = restart(la, pos != NULL ? pos : zero);
    la->restarts = 0;
    return st;
}

bool node_la_moving(const node_la *la)
{
    return lsm_interp_state_of(&la->ip) == LSM_INTERP_RUN;
}

void node_la_sync(node_la *la, const double *pos)
{
    if (node_la_moving(la) || lsm_planner_count(&la->pl) != 0u)
        return;
    for (unsigned k = 0; k < la->n_axes; k++) {
        if (pos[k] != la->pos[k]) {
            if (restart(la, pos) == LSM_OK)
                la->restarts++;
            return;
        }
    }
}

static lsm_geom_plane plane_of(uint8_t plane, unsigned *a, unsigned *b)
{
    switch (plane) {
    case 1: *a = 2; *b = 0; return LSM_GEOM_PLANE_ZX;
    case 2: *a = 1; *b = 2; return LSM_GEOM_PLANE_YZ;
    default: *a = 0; *b = 1; return LSM_GEOM_PLANE_XY;
    }
}

/* Appends one co_path block to the planner. Returns the planner's status. */
static lsm_status append(node_la *la, const lsm_co_path_block *b, const double *cpm)
{
    lsm_planner_move mv;
    memset(&mv, 0, sizeof mv);
    mv.feed_mm_s = (lsm_real)((double)b->feed_um_s / 1000.0);
    mv.tol_mm = (lsm_real)((double)b->tol_um / 1000.0);
    mv.seq = b->seq;
    if (b->type == LSM_CO_PATH_LINE) {
        lsm_real end[LSM_MAX_AXES] = {0};
        for (unsigned k = 0; k < la->n_axes; k++)
            end[k] = (lsm_real)((double)b->end[k] / cpm[k]);
        return lsm_planner_append_line(&la->pl, end, &mv);
    }
    for (unsigned k = 3; k < la->n_axes; k++) { /* the planner's arcs move X Y Z only */
        if ((lsm_real)((double)b->end[k] / cpm[k]) != la->pl.tail_pos[k])
            return LSM_E_PL_AXIS;
    }
    unsigned a, c;
    const lsm_geom_plane plane = plane_of(b->plane, &a, &c);
    lsm_real end[3], centre[3];
    for (unsigned k = 0; k < 3; k++) {
        end[k] = k < la->n_axes ? (lsm_real)((double)b->end[k] / cpm[k]) : 0;
        centre[k] = la->pl.tail_pos[k];
    }
    centre[a] = (lsm_real)((double)b->centre[0] / cpm[a]);
    centre[c] = (lsm_real)((double)b->centre[1] / cpm[c]);
    return lsm_planner_append_arc(&la->pl, end, centre, plane, b->type == LSM_CO_PATH_ARC_CCW ? 1 : -1, 0u, &mv);
}

static void save(node_la *la, const lsm_co_path_block *b)
{
    if (la->n_saved == NODE_LA_BLOCKS) { /* the oldest copy is long executed (the planner holds fewer blocks) */
        memmove(&la->saved[0], &la->saved[1], (NODE_LA_BLOCKS - 1u) * sizeof la->saved[0]);
        la->n_saved--;
    }
    la->saved[la->n_saved++] = *b;
}

/* True if the axes stand on the programmed end of block b (arcs: within the planner's arc tolerance, since
 * the planner's arc keeps its start radius). */
static bool stands_on_end(const node_la *la, const lsm_co_path_block *b, const double *cpm)
{
    const double tol = b->type == LSM_CO_PATH_LINE ? 1e-9 : (double)LSM_GEOM_ARC_TOL_MM + 1e-9;
    for (unsigned k = 0; k < la->n_axes; k++) {
        if (fabs(la->pos[k] - (double)b->end[k] / cpm[k]) > tol)
            return false;
    }
    return true;
}

/* The workaround described in node_la.h. */
static void unstick(node_la *la, const double *cpm)
{
    uint32_t i = la->n_saved;
    while (i > 0u && !stands_on_end(la, &la->saved[i - 1u], cpm))
        i--;
    if (i == 0u) {
        la->stuck++;
        return;
    }
    lsm_co_path_block pending[NODE_LA_BLOCKS];
    const uint32_t n = la->n_saved - i;
    memcpy(pending, &la->saved[i], n * sizeof pending[0]);
    if (restart(la, la->pos) != LSM_OK)
        return;
    la->n_saved = 0u;
    la->underrun_restarts++;
    for (uint32_t k = 0; k < n; k++) {
        if (append(la, &pending[k], cpm) != LSM_OK)
            break; /* cannot happen: each was accepted before from the same point */
        save(la, &pending[k]);
    }
}

void node_la_step(node_la *la, lsm_co_path *cp, const double *cpm, lsm_co_path_report *rep)
{
    const lsm_co_path_motion motion = lsm_co_path_get_motion(cp);
    if (cp->epoch != la->epoch) { /* clear, or a block refused: drop what the planner holds once at rest */
        if (lsm_planner_count(&la->pl) != 0u || node_la_moving(la))
            la->dirty = true;
        la->epoch = cp->epoch;
    }
    if (la->dirty && !la->holding) {
        lsm_interp_hold(&la->ip);
        la->holding = true;
    }
    if (la->dirty && !node_la_moving(la)) {
        if (restart(la, la->pos) == LSM_OK)
            la->restarts++;
    }
    if (cp->override_pct != la->override_pct) {
        if (lsm_interp_set_override(&la->ip, (lsm_real)cp->override_pct / 100) == LSM_OK)
            la->override_pct = cp->override_pct;
    }
    if (motion == LSM_CO_PATH_MOTION_RUN && !la->dirty) {
        if (la->holding) {
            lsm_interp_resume(&la->ip);
            la->holding = false;
        }
        lsm_co_path_block b;
        if (lsm_interp_state_of(&la->ip) == LSM_INTERP_IDLE && lsm_planner_count(&la->pl) != 0u)
            la->idle_cycles++;
        else
            la->idle_cycles = 0u;
        if (la->idle_cycles >= 2u) {
            unstick(la, cpm);
            la->idle_cycles = 0u;
        }
        while (lsm_planner_free(&la->pl) >= 3u && lsm_co_path_peek(cp, 0, &b)) {
            (void)lsm_co_path_pop(cp, &b);
            if (append(la, &b, cpm) != LSM_OK) {
                la->rejected++;
                lsm_co_path_reject(cp, b.seq);
                break;
            }
            save(la, &b);
            la->appended++;
            la->last_seq = b.seq;
        }
        /* the node's buffer ran dry: let the planner emit the G1 points it holds for arc fitting (planner.h),
         * so that the machine does not wait for blocks that may not come */
        if (lsm_co_path_count(cp) == 0u)
            (void)lsm_planner_flush(&la->pl);
    } else if ((motion == LSM_CO_PATH_MOTION_HOLD || motion == LSM_CO_PATH_MOTION_QUICK) && !la->holding) {
        lsm_interp_hold(&la->ip);
        la->holding = true;
    }

    lsm_real p[LSM_MAX_AXES];
    (void)lsm_interp_prepare(&la->ip); /* background planning between cycles */
    (void)lsm_interp_step(&la->ip, p);
    for (unsigned k = 0; k < la->n_axes; k++) {
        la->vel[k] = ((double)p[k] - la->pos[k]) / la->cycle_s;
        la->pos[k] = (double)p[k];
    }
    const lsm_pblock *cur = lsm_planner_block(&la->pl, la->ip.blk);
    rep->active_seq = cur != NULL ? cur->seq : la->last_seq;
    const double f = fabs((double)lsm_interp_feed(&la->ip)) * 1000.0;
    rep->feed_um_s = f > 4.0e9 ? 4000000000u : (uint32_t)(f + 0.5);
    rep->standstill = !node_la_moving(la);
    rep->starved = motion == LSM_CO_PATH_MOTION_RUN && !node_la_moving(la) && lsm_co_path_count(cp) == 0u;
}
