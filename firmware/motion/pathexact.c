/* pathexact.c: the exact-stop path executor (pathexact.h). */
#include "pathexact.h"

#include <string.h>

#include "lsm_math.h"

#if LSM_REAL_IS_FLOAT
#define PX_HYPOT(a, b) lsm_sqrt((a) * (a) + (b) * (b))
#define PX_ROOT4(x) lsm_sqrt(lsm_sqrt(x))
#else
#define PX_HYPOT(a, b) hypot((a), (b))
#define PX_ROOT4(x) pow((x), 0.25)
#endif
#define PX_INF ((lsm_real)INFINITY)
#define PX_PI ((lsm_real)LSM_PI)
/* A coordinate whose share of the block's length is below this does not limit it (division guard). */
#define PX_SHARE_MIN ((lsm_real)1e-12)
/* Arc sweep: an end angle within this of the start angle is a full circle (rounding of atan2). */
#define PX_SWEEP_MIN ((lsm_real)1e-12)
/* Arc radius mismatch accepted beyond the block's tolerance: this many counts of the coarser plane axis. */
#define PX_RADIUS_COUNTS ((lsm_real)2)

lsm_status lsm_pathexact_init(lsm_pathexact *np, uint8_t n_axes, lsm_real cycle_s, const lsm_axis_limits *lim,
                              const lsm_real *pos_mm)
{
    if (np == NULL || lim == NULL)
        return LSM_E_NULL;
    if (n_axes < 1u || n_axes > LSM_MAX_AXES || !(cycle_s > 0))
        return LSM_E_ARG;
    memset(np, 0, sizeof *np);
    np->n_axes = n_axes;
    np->cycle_s = cycle_s;
    for (unsigned k = 0; k < n_axes; k++) {
        np->lim[k] = lim[k];
        np->pos_mm[k] = pos_mm != NULL ? pos_mm[k] : 0;
    }
    lsm_axprof_init(&np->s, cycle_s, 0);
    return LSM_OK;
}

bool lsm_pathexact_moving(const lsm_pathexact *np)
{
    return !lsm_axprof_at_rest(&np->s);
}

void lsm_pathexact_sync(lsm_pathexact *np, const lsm_real *pos_mm)
{
    if (np->active || lsm_pathexact_moving(np))
        return;
    for (unsigned k = 0; k < np->n_axes; k++) {
        np->pos_mm[k] = pos_mm[k];
        np->vel_mm_s[k] = 0;
    }
}

static void plane_axes(uint8_t plane, uint8_t *a, uint8_t *b)
{
    switch (plane) {
    case 1:
        *a = 2;
        *b = 0;
        break; /* ZX (G18) */
    case 2:
        *a = 1;
        *b = 2;
        break; /* YZ (G19) */
    default:
        *a = 0;
        *b = 1;
        break; /* XY (G17) */
    }
}

/* Limits of a coordinate that moves linearly with s, fraction f = |d_i| / L of it. */
static void limit_linear(lsm_axprof_limits *pl, const lsm_axis_limits *l, lsm_real f)
{
    if (!(f > PX_SHARE_MIN))
        return;
    pl->v_max_mm_s = lsm_min2(pl->v_max_mm_s, l->v_max_mm_s / f);
    pl->a_max_mm_s2 = lsm_min2(pl->a_max_mm_s2, l->a_max_mm_s2 / f);
    pl->j_max_mm_s3 = lsm_min2(pl->j_max_mm_s3, l->j_max_mm_s3 / f);
    pl->snap_max_mm_s4 = lsm_min2(pl->snap_max_mm_s4, l->snap_max_mm_s4 / f);
}

static void setup_line(lsm_pathexact *np, lsm_axprof_limits *pl)
{
    lsm_real l2 = 0;
    for (unsigned k = 0; k < np->n_axes; k++)
        l2 += (np->end_mm[k] - np->start_mm[k]) * (np->end_mm[k] - np->start_mm[k]);
    np->length_mm = lsm_sqrt(l2);
    for (unsigned k = 0; k < np->n_axes && np->length_mm > 0; k++)
        limit_linear(pl, &np->lim[k], lsm_fabs(np->end_mm[k] - np->start_mm[k]) / np->length_mm);
}

/* Arc geometry and limits (see pathexact.h). False if the arc cannot be run. */
static bool setup_arc(lsm_pathexact *np, const lsm_co_path_block *b, const lsm_real *cpm, lsm_axprof_limits *pl)
{
    uint8_t a, c;
    plane_axes(b->plane, &a, &c);
    if (a >= np->n_axes || c >= np->n_axes)
        return false;
    np->pa = a;
    np->pb = c;
    np->c_mm[0] = (lsm_real)b->centre[0] / cpm[a];
    np->c_mm[1] = (lsm_real)b->centre[1] / cpm[c];
    const lsm_real sa = np->start_mm[a] - np->c_mm[0], sb = np->start_mm[c] - np->c_mm[1];
    const lsm_real ea = np->end_mm[a] - np->c_mm[0], eb = np->end_mm[c] - np->c_mm[1];
    np->r0_mm = PX_HYPOT(sa, sb);
    np->r1_mm = PX_HYPOT(ea, eb);
    const lsm_real tol = lsm_max2((lsm_real)b->tol_um / 1000, PX_RADIUS_COUNTS / lsm_min2(cpm[a], cpm[c]));
    if (!(np->r0_mm > 0) || !(np->r1_mm > 0) || lsm_fabs(np->r0_mm - np->r1_mm) > tol)
        return false;
    np->th0_rad = lsm_atan2(sb, sa);
    lsm_real d = lsm_atan2(eb, ea) - np->th0_rad;
    if (b->type == LSM_CO_PATH_ARC_CCW) {
        while (d <= PX_SWEEP_MIN)
            d += 2 * PX_PI;
    } else {
        while (d >= -PX_SWEEP_MIN)
            d -= 2 * PX_PI;
    }
    np->sweep_rad = d;
    const lsm_real planar = lsm_fabs(d) * (np->r0_mm + np->r1_mm) / 2;
    lsm_real l2 = planar * planar;
    for (unsigned k = 0; k < np->n_axes; k++) {
        if (k != a && k != c)
            l2 += (np->end_mm[k] - np->start_mm[k]) * (np->end_mm[k] - np->start_mm[k]);
    }
    np->length_mm = lsm_sqrt(l2);
    const lsm_axis_limits *la = &np->lim[a], *lc = &np->lim[c];
    const lsm_real r = lsm_min2(np->r0_mm, np->r1_mm);
    const lsm_real vq = lsm_min2(la->v_max_mm_s, lc->v_max_mm_s), aq = lsm_min2(la->a_max_mm_s2, lc->a_max_mm_s2);
    const lsm_real jq = lsm_min2(la->j_max_mm_s3, lc->j_max_mm_s3);
    const lsm_real sq = lsm_min2(la->snap_max_mm_s4, lc->snap_max_mm_s4);
    pl->v_max_mm_s = lsm_min2(pl->v_max_mm_s, lsm_min2(vq, lsm_sqrt(aq * r / 2)));
    pl->v_max_mm_s = lsm_min2(pl->v_max_mm_s, lsm_min2(lsm_cbrt(jq * r * r / 2), PX_ROOT4(sq * r * r * r / 2)));
    pl->a_max_mm_s2 = aq / 2;
    pl->j_max_mm_s3 = jq / 2;
    pl->snap_max_mm_s4 = sq / 2;
    for (unsigned k = 0; k < np->n_axes; k++) {
        if (k != a && k != c)
            limit_linear(pl, &np->lim[k], lsm_fabs(np->end_mm[k] - np->start_mm[k]) / np->length_mm);
    }
    return true;
}

/* Geometry and limits of the block just taken. Returns false if the executor cannot run it. */
static bool setup_block(lsm_pathexact *np, const lsm_real *cpm)
{
    const lsm_co_path_block *b = &np->blk;
    np->type = b->type;
    for (unsigned k = 0; k < np->n_axes; k++) {
        np->start_mm[k] = np->pos_mm[k];
        np->end_mm[k] = (lsm_real)b->end[k] / cpm[k];
    }
    np->feed_mm_s = (lsm_real)b->feed_um_s / 1000;
    lsm_axprof_limits pl = {np->feed_mm_s, PX_INF, PX_INF, PX_INF, LSM_AXPROF_TYPE_SIN2};
    if (b->type == LSM_CO_PATH_LINE)
        setup_line(np, &pl);
    else if (!setup_arc(np, b, cpm, &pl))
        return false;
    if (!isfinite(pl.a_max_mm_s2)) { /* nothing moves (a zero-length line): any finite limits will do */
        pl.a_max_mm_s2 = np->lim[0].a_max_mm_s2;
        pl.j_max_mm_s3 = np->lim[0].j_max_mm_s3;
        pl.snap_max_mm_s4 = np->lim[0].snap_max_mm_s4;
    }
    np->plim = pl;
    return true;
}

static void geometry(lsm_pathexact *np, lsm_real s)
{
    const lsm_real f = np->length_mm > 0 ? s / np->length_mm : 1;
    if (np->type == LSM_CO_PATH_LINE) {
        for (unsigned k = 0; k < np->n_axes; k++)
            np->pos_mm[k] = np->start_mm[k] + (np->end_mm[k] - np->start_mm[k]) * f;
        return;
    }
    const lsm_real th = np->th0_rad + np->sweep_rad * f;
    const lsm_real r = np->r0_mm + (np->r1_mm - np->r0_mm) * f;
    for (unsigned k = 0; k < np->n_axes; k++) {
        if (k == np->pa)
            np->pos_mm[k] = np->c_mm[0] + r * lsm_cos(th);
        else if (k == np->pb)
            np->pos_mm[k] = np->c_mm[1] + r * lsm_sin(th);
        else
            np->pos_mm[k] = np->start_mm[k] + (np->end_mm[k] - np->start_mm[k]) * f;
    }
}

/* Plans s from where it is to the block's end with the present override. */
static bool plan_rest(lsm_pathexact *np, const lsm_co_path *cp)
{
    if (cp->override_pct == 0u)
        return false;
    lsm_axprof_limits l = np->plim;
    l.v_max_mm_s = lsm_min2(np->plim.v_max_mm_s, np->feed_mm_s * (lsm_real)cp->override_pct / 100);
    if (!(l.v_max_mm_s > 0))
        return false;
    return lsm_axprof_move(&np->s, np->length_mm, &l) == LSM_OK;
}

static void finish_block(lsm_pathexact *np)
{
    for (unsigned k = 0; k < np->n_axes; k++)
        np->pos_mm[k] = np->end_mm[k];
    np->last_seq = np->blk.seq;
    np->blocks_done++;
    np->active = false;
}

/* Takes the next block and plans it. */
static void start_next(lsm_pathexact *np, lsm_co_path *cp, const lsm_real *cpm)
{
    while (!np->active && cp->override_pct > 0u && lsm_co_path_pop(cp, &np->blk) == LSM_OK) {
        np->epoch = cp->epoch;
        if (!setup_block(np, cpm)) {
            np->rejected++;
            lsm_co_path_reject(cp, np->blk.seq);
            return;
        }
        lsm_axprof_init(&np->s, np->cycle_s, 0);
        np->active = true;
        if (np->length_mm <= 0) {
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

/* Feed of the report (µm/s, saturated to what 32 bits hold). */
static uint32_t feed_um_s(lsm_real v_mm_s)
{
    const lsm_real f = lsm_fabs(v_mm_s) * 1000;
    return f > (lsm_real)4.0e9 ? 4000000000u : (uint32_t)(f + (lsm_real)0.5);
}

void lsm_pathexact_step(lsm_pathexact *np, lsm_co_path *cp, const lsm_real *cpm, lsm_co_path_report *rep)
{
    lsm_real before[LSM_MAX_AXES];
    memcpy(before, np->pos_mm, sizeof before);
    const lsm_co_path_motion motion = lsm_co_path_get_motion(cp);
    const bool stale = np->active && np->epoch != cp->epoch;

    if (np->active && (motion == LSM_CO_PATH_MOTION_HOLD || motion == LSM_CO_PATH_MOTION_QUICK || stale)) {
        const lsm_jstop_limits sl = {np->plim.a_max_mm_s2, np->plim.j_max_mm_s3, np->plim.snap_max_mm_s4};
        (void)lsm_axprof_stop(&np->s, &sl, motion == LSM_CO_PATH_MOTION_HOLD && !stale ? 1u : 2u);
    }
    if (np->active && lsm_axprof_at_rest(&np->s) && (stale || motion == LSM_CO_PATH_MOTION_IDLE))
        np->active = false; /* cleared: the rest of the block is dropped at standstill */
    if (motion == LSM_CO_PATH_MOTION_RUN) {
        if (np->active && lsm_axprof_at_rest(&np->s) && np->s.k.s_mm != np->length_mm)
            (void)plan_rest(np, cp); /* resume after a hold */
        if (!np->active)
            start_next(np, cp, cpm);
    }
    if (np->active) {
        const bool was_moving = lsm_pathexact_moving(np);
        (void)lsm_axprof_step(&np->s);
        geometry(np, np->s.k.s_mm);
        if (was_moving && lsm_axprof_at_rest(&np->s) && np->s.k.s_mm == np->length_mm) {
            finish_block(np);
            if (motion == LSM_CO_PATH_MOTION_RUN)
                start_next(np, cp, cpm); /* the next block starts moving in the next cycle */
        }
    }
    for (unsigned k = 0; k < np->n_axes; k++)
        np->vel_mm_s[k] = (np->pos_mm[k] - before[k]) / np->cycle_s;
    rep->active_seq = np->active ? np->blk.seq : np->last_seq;
    rep->feed_um_s = np->active ? feed_um_s(np->s.k.v_mm_s) : 0u;
    rep->standstill = !lsm_pathexact_moving(np);
    rep->starved = motion == LSM_CO_PATH_MOTION_RUN && !np->active && lsm_co_path_count(cp) == 0u;
}
