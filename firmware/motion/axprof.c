/* axprof.c: one coordinate's motion generator (axprof.h). */
#include "axprof.h"

#include <string.h>

#include "lsm_math.h"

/* Profile type 0: the snap limit that makes a sin² jerk rise exactly one cycle long (eq 22, t1 = dt), with a
 * margin of 1e-4 so that the strict rounding rule never needs a second cycle. */
#define AXPROF_LINEAR_SNAP_MARGIN ((lsm_real)1.0001)
/* Retarget at cruise: |a| below this fraction of the acceleration limit counts as a = 0 (rounding of the
 * closed-form evaluation: a few hundred ulps of the real type). */
#if LSM_REAL_IS_FLOAT
#define AXPROF_CRUISE_A_REL 1e-5f
#else
#define AXPROF_CRUISE_A_REL 1e-9
#endif

/* A retarget's settle needs the target this many cycles of cruise beyond the stop distance from its cruise: the
 * owner's plan of the move from the cruise may start that much later (motion.c: 9 cycles), with a margin. */
#define AXPROF_SETTLE_LEAD_CYCLES 16u

void lsm_axprof_init(lsm_axprof *p, lsm_real cycle_s, lsm_real pos_mm)
{
    memset(p, 0, sizeof *p);
    p->cycle_s = cycle_s;
    p->k.s_mm = pos_mm;
    p->origin_mm = p->target_mm = pos_mm;
    p->mode = LSM_AXPROF_IDLE;
}

lsm_axprof_limits lsm_axprof_effective(const lsm_axprof_limits *lim, lsm_real cycle_s)
{
    lsm_axprof_limits e = *lim;
    if (lim->profile_type == LSM_AXPROF_TYPE_LINEAR)
        e.snap_max_mm_s4 = AXPROF_LINEAR_SNAP_MARGIN * (lsm_real)LSM_PI * lim->j_max_mm_s3 / (2 * cycle_s);
    return e;
}

static lsm_status plan(lsm_axprof *p, lsm_real target, lsm_real v0, const lsm_axprof_limits *lim)
{
    const lsm_axprof_limits e = lsm_axprof_effective(lim, p->cycle_s);
    lsm_move_request rq;
    memset(&rq, 0, sizeof rq);
    rq.n_axes = 1;
    rq.cycle_s = p->cycle_s;
    rq.rule = LSM_SCURVE_RULE_STRICT;
    rq.distance_mm[0] = target - p->k.s_mm;
    rq.v0_mm_s[0] = v0;
    rq.v1_mm_s[0] = 0;
    rq.lim[0].v_max_mm_s = e.v_max_mm_s;
    rq.lim[0].a_max_mm_s2 = e.a_max_mm_s2;
    rq.lim[0].j_max_mm_s3 = e.j_max_mm_s3;
    rq.lim[0].snap_max_mm_s4 = e.snap_max_mm_s4;
    lsm_status st = lsm_move_plan(&p->mv, &rq);
    if (st != LSM_OK)
        return st;
    p->origin_mm = p->k.s_mm;
    p->target_mm = target;
    p->cycle = 0;
    const lsm_real start = p->origin_mm;
    st = lsm_stepgen_init(&p->gen, &p->mv, &start);
    if (st != LSM_OK)
        return st;
    p->mode = LSM_AXPROF_MOVE;
    p->stop_kind = 0;
    p->have_after = false;
    return LSM_OK;
}

/* The jerk phase the running move is in at its present cycle (a lead for a stop, jstop.h). False when the move has
 * ended or sits on the last cycle. */
static bool move_lead(const lsm_axprof *p, lsm_jstop_lead *out)
{
    lsm_phase ph[LSM_MOVE_PHASES];
    lsm_move_phases(&p->mv, 0, ph);
    uint32_t c0 = 0;
    for (unsigned i = 0; i < LSM_MOVE_PHASES; i++) {
        if (p->cycle < c0 + ph[i].n_cycles) {
            out->shape = ph[i].shape;
            out->full_s = (lsm_real)ph[i].n_cycles * p->cycle_s;
            out->off_s = (lsm_real)(p->cycle - c0) * p->cycle_s;
            out->jerk_mm_s3 = p->mv.axis[0].dir * ph[i].jerk_mm_s3;
            return true;
        }
        c0 += ph[i].n_cycles;
    }
    return false;
}

/* Plans a jerk-limited stop from the axis's present state and switches to it (IDLE at once if already at rest).
 * Inside a jerk phase of a move or of a stop, the stop continues that phase where jstop.h says so. */
static lsm_status start_stop(lsm_axprof *p, const lsm_jstop_limits *lim, uint8_t kind)
{
    lsm_jstop_lead lead;
    bool have = false;
    if (p->mode == LSM_AXPROF_MOVE)
        have = move_lead(p, &lead);
    else if (p->mode == LSM_AXPROF_STOP)
        have = lsm_jstop_lead_now(&p->stop, &lead);
    lsm_status st =
        lsm_jstop_plan_lead(&p->stop, p->k.s_mm, p->k.v_mm_s, p->k.a_mm_s2, p->k.j_mm_s3, have ? &lead : NULL, lim);
    if (st != LSM_OK)
        return st;
    p->mode = p->stop.active ? LSM_AXPROF_STOP : LSM_AXPROF_IDLE;
    p->stop_kind = kind;
    if (p->mode == LSM_AXPROF_IDLE)
        p->k.v_mm_s = p->k.a_mm_s2 = p->k.j_mm_s3 = 0;
    return LSM_OK;
}

/* Retarget at cruise (see axprof.h): true if the new move continues from the cruise velocity. */
static bool retarget_at_cruise(lsm_axprof *p, lsm_real target, const lsm_axprof_limits *lim)
{
    const lsm_real d = target - p->k.s_mm;
    if (!((p->mode == LSM_AXPROF_MOVE || p->mode == LSM_AXPROF_CRUISE) &&
          lsm_fabs(p->k.a_mm_s2) <= AXPROF_CRUISE_A_REL * lim->a_max_mm_s2 && d * p->k.v_mm_s > 0 &&
          lsm_fabs(p->k.v_mm_s) <= lim->v_max_mm_s))
        return false;
    const lsm_move saved = p->mv;
    const lsm_stepgen saved_gen = p->gen;
    const lsm_real o = p->origin_mm, t = p->target_mm;
    const uint32_t c = p->cycle;
    if (plan(p, target, lsm_fabs(p->k.v_mm_s), lim) == LSM_OK)
        return true;
    p->mv = saved;
    p->gen = saved_gen;
    p->gen.mv = &p->mv;
    p->origin_mm = o;
    p->target_mm = t;
    p->cycle = c;
    return false;
}

/* Cruises at v_mm_s from the present position (the end of a retarget's settle: axprof.h). */
static void start_cruise(lsm_axprof *p, lsm_real v_mm_s)
{
    p->mode = LSM_AXPROF_CRUISE;
    p->stop_kind = 0;
    p->cruise_origin_mm = p->k.s_mm;
    p->cruise_v_mm_s = v_mm_s;
    p->cruise_cycles = 0;
    p->k.v_mm_s = v_mm_s;
    p->k.a_mm_s2 = p->k.j_mm_s3 = 0;
}

/* Distance (>= 0) of the stop from (v, 0, 0) with these limits. */
static lsm_real stop_distance(lsm_real v_mm_s, const lsm_jstop_limits *sl)
{
    lsm_jstop st;
    if (lsm_jstop_plan(&st, 0, lsm_fabs(v_mm_s), 0, 0, sl) != LSM_OK || !st.active)
        return 0;
    lsm_kin e;
    lsm_jstop_eval(&st, st.t_end_s, &e);
    return lsm_fabs(e.s_mm);
}

/* A retarget of a running move to a target ahead (axprof.h): the velocity settles (a = j = 0) from the present
 * state, continuing its jerk phase (lsm_jstop_plan_settle), and the new move is planned from that cruise, if the
 * cruise is within the new velocity limit and the target far enough past the settle's end to stop there from it
 * (with AXPROF_SETTLE_LEAD_CYCLES of cruise). Two stop plans: bounded. */
static bool settle(lsm_axprof *p, lsm_real target, const lsm_axprof_limits *lim, const lsm_jstop_limits *sl)
{
    const lsm_real v = p->k.v_mm_s;
    if (p->mode != LSM_AXPROF_MOVE || !((target - p->k.s_mm) * v > 0))
        return false;
    lsm_jstop_lead lead;
    const bool have = move_lead(p, &lead);
    lsm_jstop st;
    if (lsm_jstop_plan_settle(&st, p->k.s_mm, v, p->k.a_mm_s2, p->k.j_mm_s3, have ? &lead : NULL, sl) != LSM_OK)
        return false;
    const lsm_real sg = v > 0 ? 1 : -1, ve = st.v_end_mm_s;
    lsm_real pe = p->k.s_mm;
    if (st.active) {
        lsm_kin e;
        lsm_jstop_eval(&st, st.t_end_s, &e);
        pe = e.s_mm;
    }
    const lsm_real need = stop_distance(ve, sl) + lsm_fabs(ve) * p->cycle_s * (lsm_real)AXPROF_SETTLE_LEAD_CYCLES;
    if (!(sg * ve > 0 && lsm_fabs(ve) <= lim->v_max_mm_s && sg * (target - pe) >= need))
        return false;
    if (!st.active) {
        start_cruise(p, ve);
        return true;
    }
    p->stop = st;
    p->mode = LSM_AXPROF_STOP;
    p->stop_kind = 0;
    return true;
}

lsm_status lsm_axprof_move(lsm_axprof *p, lsm_real target_mm, const lsm_axprof_limits *lim)
{
    if (p->mode == LSM_AXPROF_IDLE) {
        if (target_mm - p->k.s_mm == 0) {
            p->target_mm = target_mm;
            return LSM_OK;
        }
        return plan(p, target_mm, 0, lim);
    }
    /* moving: continue from the cruise velocity if possible, else stop first (from the present state, at once) */
    if (retarget_at_cruise(p, target_mm, lim))
        return LSM_OK;
    const lsm_axprof_limits e = lsm_axprof_effective(lim, p->cycle_s);
    const lsm_jstop_limits sl = {e.a_max_mm_s2, e.j_max_mm_s3, e.snap_max_mm_s4};
    if (p->mode == LSM_AXPROF_CRUISE || (p->mode == LSM_AXPROF_MOVE && !settle(p, target_mm, lim, &sl))) {
        lsm_status st = start_stop(p, &sl, 0);
        if (st != LSM_OK)
            return st;
    }
    if (p->mode == LSM_AXPROF_IDLE)
        return lsm_axprof_move(p, target_mm, lim);
    if (p->mode == LSM_AXPROF_CRUISE) { /* settled at once: the move from the cruise */
        p->after_target_mm = target_mm;
        p->after_lim = *lim;
        if (p->plan_outside) { /* the owner plans it */
            p->after_due = true;
            return LSM_OK;
        }
        return retarget_at_cruise(p, target_mm, lim) ? LSM_OK : lsm_axprof_move(p, target_mm, lim);
    }
    p->have_after = true;
    p->after_target_mm = target_mm;
    p->after_lim = *lim;
    return LSM_OK;
}

lsm_status lsm_axprof_stop(lsm_axprof *p, const lsm_jstop_limits *lim, uint8_t kind)
{
    p->have_after = false;
    if (p->mode == LSM_AXPROF_IDLE && p->k.v_mm_s == 0 && p->k.a_mm_s2 == 0)
        return LSM_OK; /* at rest (an IDLE profile with a velocity is a CSP axis that the caller moves) */
    const bool stopping = p->mode == LSM_AXPROF_STOP && !p->stop.settle; /* a retarget's settle is no stop */
    if (stopping && p->stop_kind >= kind)
        return LSM_OK;
    if (stopping && p->stop.lim.decel_mm_s2 >= lim->decel_mm_s2 && p->stop.lim.jerk_mm_s3 >= lim->jerk_mm_s3 &&
        p->stop.lim.snap_mm_s4 >= lim->snap_mm_s4) {
        p->stop_kind = kind; /* the running stop is already at least as fast */
        return LSM_OK;
    }
    return start_stop(p, lim, kind);
}

static void step_move(lsm_axprof *p)
{
    lsm_real pos;
    const bool running = lsm_stepgen_next(&p->gen, &pos);
    p->cycle++;
    if (!running) {
        p->k.s_mm = p->target_mm;
        p->k.v_mm_s = p->k.a_mm_s2 = p->k.j_mm_s3 = 0;
        p->mode = LSM_AXPROF_IDLE;
    } else {
        lsm_kin e;
        lsm_move_eval_cycle(&p->mv, 0, p->cycle, 0, &e);
        p->k.s_mm = pos;
        p->k.v_mm_s = e.v_mm_s;
        p->k.a_mm_s2 = e.a_mm_s2;
        p->k.j_mm_s3 = e.j_mm_s3;
    }
}

static void step_stop(lsm_axprof *p)
{
    lsm_kin e;
    const bool running = lsm_jstop_step(&p->stop, p->cycle_s, &e);
    p->k = e;
    if (running)
        return;
    if (p->stop.settle)
        start_cruise(p, e.v_mm_s); /* a retarget's settle ended: the move from the cruise follows */
    else
        p->mode = LSM_AXPROF_IDLE;
    p->stop_kind = 0;
    if (p->have_after && p->plan_outside) {
        p->have_after = false;
        p->after_due = true;
        return;
    }
    if (p->have_after) {
        p->have_after = false;
        const lsm_axprof_limits l = p->after_lim;
        (void)lsm_axprof_move(p, p->after_target_mm, &l);
    }
}

/* One cycle of a cruise (exact: origin + v n dt, no accumulated rounding). */
static void step_cruise(lsm_axprof *p)
{
    p->cruise_cycles++;
    p->k.s_mm = p->cruise_origin_mm + p->cruise_v_mm_s * ((lsm_real)p->cruise_cycles * p->cycle_s);
    p->k.v_mm_s = p->cruise_v_mm_s;
    p->k.a_mm_s2 = p->k.j_mm_s3 = 0;
}

bool lsm_axprof_step(lsm_axprof *p)
{
    switch (p->mode) {
    case LSM_AXPROF_MOVE: step_move(p); return true;
    case LSM_AXPROF_STOP: step_stop(p); return true;
    case LSM_AXPROF_CRUISE: step_cruise(p); return true;
    default: p->k.v_mm_s = p->k.a_mm_s2 = p->k.j_mm_s3 = 0; return false;
    }
}
