#include "node_path.h"

#include <math.h>
#include <string.h>

#define PI_D 3.14159265358979323846

void node_path_init(node_path *np, uint8_t n_axes, double cycle_s, const node_axis_limits *lim, const double *pos)
{
    memset(np, 0, sizeof *np);
    np->n_axes = n_axes;
    np->cycle_s = cycle_s;
    for (unsigned k = 0; k < n_axes; k++) {
        np->lim[k] = lim[k];
        np->pos[k] = pos != NULL ? pos[k] : 0;
    }
    node_prof_init(&np->s, cycle_s, 0);
}

bool node_path_moving(const node_path *np)
{
    return !node_prof_at_rest(&np->s);
}

void node_path_sync(node_path *np, const double *pos)
{
    if (np->active || node_path_moving(np))
        return;
    for (unsigned k = 0; k < np->n_axes; k++) {
        np->pos[k] = pos[k];
        np->vel[k] = 0;
    }
}

static void plane_axes(uint8_t plane, uint8_t *a, uint8_t *b)
{
    switch (plane) {
    case 1: *a = 2; *b = 0; break; /* ZX (G18) */
    case 2: *a = 1; *b = 2; break; /* YZ (G19) */
    default: *a = 0; *b = 1; break; /* XY (G17) */
    }
}

/* Limits of a coordinate that moves linearly with s, fraction f = |d_i| / L of it. */
static void limit_linear(node_prof_limits *pl, const node_axis_limits *l, double f)
{
    if (!(f > 1e-12))
        return;
    pl->v_max = fmin(pl->v_max, l->v_max / f);
    pl->a_max = fmin(pl->a_max, l->a_max / f);
    pl->j_max = fmin(pl->j_max, l->j_max / f);
    pl->snap_max = fmin(pl->snap_max, l->snap_max / f);
}

/* Geometry and limits of the block just taken. Returns false if the executor cannot run it. */
static bool setup_block(node_path *np, const double *cpm)
{
    const lsm_co_path_block *b = &np->blk;
    np->type = b->type;
    for (unsigned k = 0; k < np->n_axes; k++) {
        np->start[k] = np->pos[k];
        np->end[k] = (double)b->end[k] / cpm[k];
    }
    np->feed = (double)b->feed_um_s / 1000.0;
    node_prof_limits pl = {np->feed, INFINITY, INFINITY, INFINITY, 1};
    if (b->type == LSM_CO_PATH_LINE) {
        double l2 = 0;
        for (unsigned k = 0; k < np->n_axes; k++)
            l2 += (np->end[k] - np->start[k]) * (np->end[k] - np->start[k]);
        np->length = sqrt(l2);
        for (unsigned k = 0; k < np->n_axes && np->length > 0; k++)
            limit_linear(&pl, &np->lim[k], fabs(np->end[k] - np->start[k]) / np->length);
    } else {
        uint8_t a, c;
        plane_axes(b->plane, &a, &c);
        if (a >= np->n_axes || c >= np->n_axes)
            return false;
        np->pa = a;
        np->pb = c;
        np->c[0] = (double)b->centre[0] / cpm[a];
        np->c[1] = (double)b->centre[1] / cpm[c];
        const double sa = np->start[a] - np->c[0], sb = np->start[c] - np->c[1];
        const double ea = np->end[a] - np->c[0], eb = np->end[c] - np->c[1];
        np->r0 = hypot(sa, sb);
        np->r1 = hypot(ea, eb);
        const double tol = fmax((double)b->tol_um / 1000.0, 2.0 / fmin(cpm[a], cpm[c]));
        if (!(np->r0 > 0) || !(np->r1 > 0) || fabs(np->r0 - np->r1) > tol)
            return false;
        np->th0 = atan2(sb, sa);
        double d = atan2(eb, ea) - np->th0;
        if (b->type == LSM_CO_PATH_ARC_CCW) {
            while (d <= 1e-12)
                d += 2 * PI_D;
        } else {
            while (d >= -1e-12)
                d -= 2 * PI_D;
        }
        np->sweep = d;
        const double planar = fabs(d) * (np->r0 + np->r1) / 2;
        double l2 = planar * planar;
        for (unsigned k = 0; k < np->n_axes; k++) {
            if (k != a && k != c)
                l2 += (np->end[k] - np->start[k]) * (np->end[k] - np->start[k]);
        }
        np->length = sqrt(l2);
        const node_axis_limits *la = &np->lim[a], *lc = &np->lim[c];
        const double r = fmin(np->r0, np->r1);
        const double vq = fmin(la->v_max, lc->v_max), aq = fmin(la->a_max, lc->a_max);
        const double jq = fmin(la->j_max, lc->j_max), sq = fmin(la->snap_max, lc->snap_max);
        pl.v_max = fmin(pl.v_max, fmin(vq, sqrt(aq * r / 2)));
        pl.v_max = fmin(pl.v_max, fmin(cbrt(jq * r * r / 2), pow(sq * r * r * r / 2, 0.25)));
        pl.a_max = aq / 2;
        pl.j_max = jq / 2;
        pl.snap_max = sq / 2;
        for (unsigned k = 0; k < np->n_axes; k++) {
            if (k != a && k != c)
                limit_linear(&pl, &np->lim[k], fabs(np->end[k] - np->start[k]) / np->length);
        }
    }
    if (!isfinite(pl.a_max)) { /* nothing moves (a zero-length line): any finite limits will do */
        pl.a_max = np->lim[0].a_max;
        pl.j_max = np->lim[0].j_max;
        pl.snap_max = np->lim[0].snap_max;
    }
    np->plim = pl;
    return true;
}

static void geometry(node_path *np, double s)
{
    const double f = np->length > 0 ? s / np->length : 1;
    if (np->type == LSM_CO_PATH_LINE) {
        for (unsigned k = 0; k < np->n_axes; k++)
            np->pos[k] = np->start[k] + (np->end[k] - np->start[k]) * f;
        return;
    }
    const double th = np->th0 + np->sweep * f;
    const double r = np->r0 + (np->r1 - np->r0) * f;
    for (unsigned k = 0; k < np->n_axes; k++) {
        if (k == np->pa)
            np->pos[k] = np->c[0] + r * cos(th);
        else if (k == np->pb)
            np->pos[k] = np->c[1] + r * sin(th);
        else
            np->pos[k] = np->start[k] + (np->end[k] - np->start[k]) * f;
    }
}

/* Plans s from where it is to the block's end with the present override. */
static bool plan_rest(node_path *np, const lsm_co_path *cp)
{
    if (cp->override_pct == 0u)
        return false;
    node_prof_limits l = np->plim;
    l.v_max = fmin(np->plim.v_max, np->feed * (double)cp->override_pct / 100.0);
    if (!(l.v_max > 0))
        return false;
    return node_prof_move(&np->s, np->length, &l) == LSM_OK;
}

static void finish_block(node_path *np)
{
    for (unsigned k = 0; k < np->n_axes; k++)
        np->pos[k] = np->end[k];
    np->last_seq = np->blk.seq;
    np->blocks_done++;
    np->active = false;
}

/* Takes the next block and plans it. */
static void start_next(node_path *np, lsm_co_path *cp, const double *cpm)
{
    while (!np->active && cp->override_pct > 0u && lsm_co_path_pop(cp, &np->blk) == LSM_OK) {
        np->epoch = cp->epoch;
        if (!setup_block(np, cpm)) {
            np->rejected++;
            lsm_co_path_reject(cp, np->blk.seq);
            return;
        }
        node_prof_init(&np->s, np->cycle_s, 0);
        np->active = true;
        if (np->length <= 0) {
            finish_block(np); /* nothing to move: done at once */
            continue;
        }
        if (!plan_rest(np, cp)) {
            np->rejected++;
            np->active = false;
            lsm_co_path_reject(cp, np->blk.seq);
            return;
        }
    }
}

void node_path_step(node_path *np, lsm_co_path *cp, const double *cpm, lsm_co_path_report *rep)
{
    double before[LSM_MAX_AXES];
    memcpy(before, np->pos, sizeof before);
    const lsm_co_path_motion motion = lsm_co_path_get_motion(cp);
    const bool stale = np->active && np->epoch != cp->epoch;

    if (np->active && (motion == LSM_CO_PATH_MOTION_HOLD || motion == LSM_CO_PATH_MOTION_QUICK || stale)) {
        node_stop_limits sl = {np->plim.a_max, np->plim.j_max, np->plim.snap_max};
        (void)node_prof_stop(&np->s, &sl, motion == LSM_CO_PATH_MOTION_HOLD && !stale ? 1u : 2u);
    }
    if (np->active && node_prof_at_rest(&np->s) && (stale || motion == LSM_CO_PATH_MOTION_IDLE))
        np->active = false; /* cleared: the rest of the block is dropped at standstill */
    if (motion == LSM_CO_PATH_MOTION_RUN) {
        if (np->active && node_prof_at_rest(&np->s) && np->s.k.s_mm != np->length)
            (void)plan_rest(np, cp); /* resume after a hold */
        if (!np->active)
            start_next(np, cp, cpm);
    }
    if (np->active) {
        const bool was_moving = node_path_moving(np);
        (void)node_prof_step(&np->s);
        geometry(np, np->s.k.s_mm);
        if (was_moving && node_prof_at_rest(&np->s) && np->s.k.s_mm == np->length) {
            finish_block(np);
            if (motion == LSM_CO_PATH_MOTION_RUN)
                start_next(np, cp, cpm); /* the next block starts moving in the next cycle */
        }
    }
    for (unsigned k = 0; k < np->n_axes; k++)
        np->vel[k] = (np->pos[k] - before[k]) / np->cycle_s;
    rep->active_seq = np->active ? np->blk.seq : np->last_seq;
    const double f = fabs(np->s.k.v_mm_s) * 1000.0;
    rep->feed_um_s = np->active ? (f > 4.0e9 ? 4000000000u : (uint32_t)(f + 0.5)) : 0u;
    rep->standstill = !node_path_moving(np);
    rep->starved = motion == LSM_CO_PATH_MOTION_RUN && !np->active && lsm_co_path_count(cp) == 0u;
}
