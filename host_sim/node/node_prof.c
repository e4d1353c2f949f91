#include "node_prof.h"

#include <math.h>
#include <string.h>

#define PI_D 3.14159265358979323846

void node_prof_init(node_prof *p, double cycle_s, double pos)
{
    memset(p, 0, sizeof *p);
    p->cycle_s = cycle_s;
    p->k.s_mm = pos;
    p->origin = p->target = pos;
    p->mode = NODE_PROF_IDLE;
}

node_prof_limits node_prof_effective(const node_prof_limits *lim, double cycle_s)
{
    node_prof_limits e = *lim;
    if (lim->profile_type == 0)
        e.snap_max = 1.0001 * PI_D * lim->j_max / (2 * cycle_s);
    return e;
}

static lsm_status plan(node_prof *p, double target, double v0, const node_prof_limits *lim)
{
    const node_prof_limits e = node_prof_effective(lim, p->cycle_s);
    lsm_move_request rq;
    memset(&rq, 0, sizeof rq);
    rq.n_axes = 1;
    rq.cycle_s = p->cycle_s;
    rq.rule = LSM_SCURVE_RULE_STRICT;
    rq.distance_mm[0] = target - p->k.s_mm;
    rq.v0_mm_s[0] = v0;
    rq.v1_mm_s[0] = 0;
    rq.lim[0].v_max_mm_s = e.v_max;
    rq.lim[0].a_max_mm_s2 = e.a_max;
    rq.lim[0].j_max_mm_s3 = e.j_max;
    rq.lim[0].snap_max_mm_s4 = e.snap_max;
    lsm_status st = lsm_move_plan(&p->mv, &rq);
    if (st != LSM_OK)
        return st;
    p->origin = p->k.s_mm;
    p->target = target;
    p->cycle = 0;
    const lsm_real start = p->origin;
    st = lsm_stepgen_init(&p->gen, &p->mv, &start);
    if (st != LSM_OK)
        return st;
    p->mode = NODE_PROF_MOVE;
    p->stop_kind = 0;
    p->have_after = false;
    return LSM_OK;
}

lsm_status node_prof_move(node_prof *p, double target, const node_prof_limits *lim)
{
    const double d = target - p->k.s_mm;
    if (p->mode == NODE_PROF_IDLE) {
        if (d == 0) {
            p->target = target;
            return LSM_OK;
        }
        return plan(p, target, 0, lim);
    }
    /* moving: continue from the cruise velocity if possible, else stop first */
    if (p->mode == NODE_PROF_MOVE && fabs(p->k.a_mm_s2) <= 1e-9 * lim->a_max && d * p->k.v_mm_s > 0 &&
        fabs(p->k.v_mm_s) <= lim->v_max) {
        lsm_move saved = p->mv;
        lsm_stepgen saved_gen = p->gen;
        double o = p->origin, t = p->target;
        uint32_t c = p->cycle;
        if (plan(p, target, fabs(p->k.v_mm_s), lim) == LSM_OK)
            return LSM_OK;
        p->mv = saved;
        p->gen = saved_gen;
        p->gen.mv = &p->mv;
        p->origin = o;
        p->target = t;
        p->cycle = c;
    }
    const node_prof_limits e = node_prof_effective(lim, p->cycle_s);
    node_stop_limits sl = {e.a_max, e.j_max, e.snap_max};
    if (p->mode == NODE_PROF_MOVE) {
        lsm_status st = node_stop_plan(&p->stop, p->k.s_mm, p->k.v_mm_s, p->k.a_mm_s2, &sl);
        if (st != LSM_OK)
            return st;
        p->mode = p->stop.active ? NODE_PROF_STOP : NODE_PROF_IDLE;
        p->stop_kind = 0;
    }
    if (p->mode == NODE_PROF_IDLE)
        return node_prof_move(p, target, lim);
    p->have_after = true;
    p->after_target = target;
    p->after_lim = *lim;
    return LSM_OK;
}

lsm_status node_prof_stop(node_prof *p, const node_stop_limits *lim, uint8_t kind)
{
    p->have_after = false;
    if (p->mode == NODE_PROF_IDLE && p->k.v_mm_s == 0 && p->k.a_mm_s2 == 0)
        return LSM_OK; /* at rest (an IDLE profile with a velocity is a CSP axis that the caller moves) */
    if (p->mode == NODE_PROF_STOP && p->stop_kind >= kind)
        return LSM_OK;
    if (p->mode == NODE_PROF_STOP && p->stop.lim.decel >= lim->decel && p->stop.lim.jerk >= lim->jerk &&
        p->stop.lim.snap >= lim->snap) {
        p->stop_kind = kind; /* the running stop is already at least as fast */
        return LSM_OK;
    }
    lsm_status st = node_stop_plan(&p->stop, p->k.s_mm, p->k.v_mm_s, p->k.a_mm_s2, lim);
    if (st != LSM_OK)
        return st;
    p->mode = p->stop.active ? NODE_PROF_STOP : NODE_PROF_IDLE;
    p->stop_kind = kind;
    if (p->mode == NODE_PROF_IDLE)
        p->k.v_mm_s = p->k.a_mm_s2 = p->k.j_mm_s3 = 0;
    return LSM_OK;
}

bool node_prof_step(node_prof *p)
{
    switch (p->mode) {
    case NODE_PROF_MOVE: {
        lsm_real pos;
        const bool running = lsm_stepgen_next(&p->gen, &pos);
        p->cycle++;
        if (!running) {
            p->k.s_mm = p->target;
            p->k.v_mm_s = p->k.a_mm_s2 = p->k.j_mm_s3 = 0;
            p->mode = NODE_PROF_IDLE;
            return true;
        }
        lsm_kin e;
        lsm_move_eval_cycle(&p->mv, 0, p->cycle, 0, &e);
        p->k.s_mm = pos;
        p->k.v_mm_s = e.v_mm_s;
        p->k.a_mm_s2 = e.a_mm_s2;
        p->k.j_mm_s3 = e.j_mm_s3;
        return true;
    }
    case NODE_PROF_STOP: {
        lsm_kin e;
        const bool running = node_stop_step(&p->stop, p->cycle_s, &e);
        p->k = e;
        if (!running) {
            p->mode = NODE_PROF_IDLE;
            p->stop_kind = 0;
            if (p->have_after) {
                p->have_after = false;
                node_prof_limits l = p->after_lim;
                (void)node_prof_move(p, p->after_target, &l);
            }
        }
        return true;
    }
    default:
        p->k.v_mm_s = p->k.a_mm_s2 = p->k.j_mm_s3 = 0;
        return false;
    }
}
