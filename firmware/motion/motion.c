/* motion.c: the CiA 402 motion layer (motion.h). */
#include "motion.h"

#include <string.h>

#include "lsm_math.h"

/* Cycles between taking a PP set-point and starting its move when the background plans it (lead_cycles > 0): a
 * move plan is ~40-250 k instructions on the M4, under two ticks of background; 8 leave room for a path piece plan
 * running at the same time. */
#define MO_PP_PLAN_CYCLES 8u

/* Longest CSP interpolation period in cycles (0x60C2 beyond it is clamped): 100 s at 1 ms. */
#define MO_CSP_CYCLES_MAX 100000u
/* Profile type 0: the snap limit that makes a jerk rise one cycle long (as axprof.h). */
#define MO_LINEAR_SNAP_MARGIN ((lsm_real)1.0001)

static bool limits_ok(const lsm_axis_limits *l)
{
    const lsm_real v[4] = {l->v_max_mm_s, l->a_max_mm_s2, l->j_max_mm_s3, l->snap_max_mm_s4};
    for (unsigned i = 0; i < 4; i++) {
        if (lsm_check_finite(v[i]) != 0 || !(v[i] > 0))
            return false;
    }
    return true;
}

lsm_status lsm_motion_init(lsm_motion *m, const lsm_motion_config *cfg, lsm_canopen *co)
{
    if (m == NULL || cfg == NULL || co == NULL)
        return LSM_E_NULL;
    if (cfg->n_axes < 1u || cfg->n_axes > LSM_MAX_AXES || co->n_axes != cfg->n_axes || !(cfg->cycle_s > 0) ||
        (cfg->path_exec != LSM_MOTION_PATH_PLANNER && cfg->path_exec != LSM_MOTION_PATH_EXACT) ||
        cfg->lead_cycles > LSM_MPIPE_LEAD_MAX)
        return LSM_E_ARG;
    for (unsigned k = 0; k < cfg->n_axes; k++) {
        if (!limits_ok(&cfg->lim[k]))
            return LSM_E_LIMIT;
    }
    memset(m, 0, sizeof *m);
    m->n_axes = cfg->n_axes;
    m->path_exec = cfg->path_exec;
    m->cycle_s = cfg->cycle_s;
    m->lead_cycles = cfg->lead_cycles;
    for (unsigned k = 0; k < cfg->n_axes; k++) {
        m->lim[k] = cfg->lim[k];
        lsm_axprof_init(&m->ax[k].prof, m->cycle_s, 0);
        m->ax[k].prof.plan_outside = m->lead_cycles > 0u;
        m->ax[k].mode = lsm_canopen_axis(co, k)->mode_display;
    }
    const lsm_real zero[LSM_MAX_AXES] = {0};
    lsm_status st = lsm_pathexact_init(&m->path, m->n_axes, m->cycle_s, m->lim, zero);
    if (st != LSM_OK)
        return st;
    return lsm_pathfeed_init(&m->feed, m->n_axes, m->cycle_s, m->lim, zero, &cfg->feed);
}

/* Stop limits for a stop request of this kind (see motion.h), in mm units. */
static lsm_jstop_limits stop_limits(const lsm_motion *m, unsigned k, const lsm_cia402 *ax, uint8_t kind)
{
    const lsm_axis_limits *l = &m->lim[k];
    const lsm_real cpm = (lsm_real)ax->counts_per_mm;
    lsm_jstop_limits s;
    if (kind == LSM_CIA402_STOP_EMERGENCY) {
        s.decel_mm_s2 = l->a_max_mm_s2;
        s.jerk_mm_s3 = l->j_max_mm_s3;
        s.snap_mm_s4 = l->snap_max_mm_s4;
    } else {
        const lsm_real d = kind == LSM_CIA402_STOP_QUICK ? (lsm_real)ax->quick_stop_decel : (lsm_real)ax->profile_decel;
        s.decel_mm_s2 = lsm_min2(d / cpm, l->a_max_mm_s2);
        s.jerk_mm_s3 = lsm_min2((lsm_real)ax->profile_jerk / cpm, l->j_max_mm_s3);
        s.snap_mm_s4 = lsm_min2((lsm_real)ax->profile_snap / cpm, l->snap_max_mm_s4);
    }
    /* profile type 0 (the linear ramp: a move's jerk steps within one cycle, axprof.h): every stop's too, the
     * E-stop's included; a sin² jerk rise at the machine's snap limit would brake later than the move it stops
     * and take the velocity past the profile's (test_pp_props: 20.13 against 20 mm/s) */
    if (ax->profile_type == 0)
        s.snap_mm_s4 = MO_LINEAR_SNAP_MARGIN * (lsm_real)LSM_PI * s.jerk_mm_s3 / (2 * m->cycle_s);
    return s;
}

static lsm_axprof_limits pp_limits(const lsm_motion *m, unsigned k, const lsm_cia402_setpoint *sp, lsm_real cpm)
{
    const lsm_axis_limits *l = &m->lim[k];
    lsm_axprof_limits p;
    p.v_max_mm_s = lsm_min2((lsm_real)sp->velocity / cpm, l->v_max_mm_s);
    p.a_max_mm_s2 = lsm_min2((lsm_real)(sp->accel < sp->decel ? sp->accel : sp->decel) / cpm, l->a_max_mm_s2);
    p.j_max_mm_s3 = lsm_min2((lsm_real)sp->jerk / cpm, l->j_max_mm_s3);
    p.snap_max_mm_s4 = lsm_min2((lsm_real)sp->snap / cpm, l->snap_max_mm_s4);
    p.profile_type = sp->profile_type == 0 ? LSM_AXPROF_TYPE_LINEAR : LSM_AXPROF_TYPE_SIN2;
    return p;
}

/* 10^e as a real (the 0x60C2 index). */
static lsm_real pow10_of(int e)
{
#if LSM_REAL_IS_FLOAT
    lsm_real r = 1;
    for (int i = 0; i < e; i++)
        r *= 10;
    for (int i = 0; i > e; i--)
        r /= 10;
    return r;
#else
    return pow(10.0, (double)e);
#endif
}

/* The CSP interpolation period 0x60C2 in whole cycles (nearest, 1..MO_CSP_CYCLES_MAX). */
static uint32_t ip_cycles(const lsm_motion *m, const lsm_cia402 *ax)
{
    const lsm_real period = (lsm_real)ax->ip_period_value * pow10_of(ax->ip_period_index);
    lsm_real n = lsm_floor(period / m->cycle_s + (lsm_real)0.5);
    if (!(n >= 1))
        n = 1;
    if (n > (lsm_real)MO_CSP_CYCLES_MAX)
        n = (lsm_real)MO_CSP_CYCLES_MAX;
    return (uint32_t)n;
}

/* A stop request on a non-path axis. */
static void axis_stop(lsm_motion *m, unsigned k, const lsm_cia402 *ax, lsm_cia402_stop kind)
{
    lsm_motion_axis *a = &m->ax[k];
    const lsm_jstop_limits sl = stop_limits(m, k, ax, (uint8_t)kind);
    if (a->csp_active) {
        const lsm_real n_s = (lsm_real)a->csp_n * m->cycle_s;
        lsm_real acc = (a->csp_v_mm_s - a->csp_v_prev_mm_s) / n_s;
        acc = lsm_max2(-sl.decel_mm_s2, lsm_min2(sl.decel_mm_s2, acc));
        a->prof.k.v_mm_s = a->csp_v_mm_s;
        a->prof.k.a_mm_s2 = acc;
        a->csp_active = false;
    }
    (void)lsm_axprof_stop(&a->prof, &sl, (uint8_t)kind); /* every stop begins in this cycle */
    a->pp_running = false;
    a->pp_wait = false; /* a plan in the background is dropped */
}

/* Posts axis k's PP plan request (lead_cycles > 0): the move starts MO_PP_PLAN_CYCLES cycles from now, planned from
 * the generator's state then (the background steps a copy there, as the tick steps its own). stepped: posted after
 * this cycle's step (the generator's waiting move), so the copy is already one cycle on and the plan is taken one
 * cycle later (before: taken a cycle early, the demand jumped by a cycle of travel). */
static void pp_post(lsm_motion *m, unsigned k, bool stepped)
{
    lsm_motion_axis *a = &m->ax[k];
    a->pp_wait = true;
    a->pp_have = false;
    a->pp_unsent = lsm_spsc_room(&m->pipe.pp_req_idx, LSM_MPIPE_PP) == 0u;
    if (a->pp_unsent)
        return;
    lsm_mpipe_pp *r = &m->pipe.pp_req[lsm_spsc_wr(&m->pipe.pp_req_idx) & (LSM_MPIPE_PP - 1u)];
    r->base = a->prof;
    r->lim = a->pp_lim;
    r->target_mm = a->pp_target_mm;
    r->gen = ++a->pp_gen;
    r->steps = MO_PP_PLAN_CYCLES;
    r->axis = (uint8_t)k;
    lsm_spsc_push(&m->pipe.pp_req_idx);
    a->pp_due = m->tk.cycle + MO_PP_PLAN_CYCLES + (stepped ? 1u : 0u);
    a->pp_from_rest = a->prof.mode == LSM_AXPROF_IDLE && a->prof.k.v_mm_s == 0 && a->prof.k.a_mm_s2 == 0;
}

/* The plan results that arrived: kept by their axis if still wanted. */
static void pp_collect(lsm_motion *m)
{
    while (lsm_spsc_avail(&m->pipe.pp_res_idx) != 0u) {
        const lsm_mpipe_pp *r = &m->pipe.pp_res[lsm_spsc_rd(&m->pipe.pp_res_idx) & (LSM_MPIPE_PP - 1u)];
        lsm_motion_axis *a = &m->ax[r->axis];
        if (a->pp_wait && !a->pp_unsent && r->gen == a->pp_gen) {
            a->pp_res = r->base;
            a->pp_st = r->st;
            a->pp_have = true;
        }
        lsm_spsc_pop(&m->pipe.pp_res_idx);
    }
}

/* Axis k's requested plan, before the cycle's step: taken at its cycle (or later if it starts from rest and the axis
 * still rests); requested again if it came too late for a moving axis. */
static void pp_take(lsm_motion *m, unsigned k, lsm_canopen *co)
{
    lsm_motion_axis *a = &m->ax[k];
    if (!a->pp_wait)
        return;
    const bool resting = a->prof.mode == LSM_AXPROF_IDLE && a->prof.k.v_mm_s == 0 && a->prof.k.a_mm_s2 == 0;
    if (a->pp_unsent || (!(a->pp_from_rest && resting) && m->tk.cycle > a->pp_due) ||
        (!a->pp_have && !(a->pp_from_rest && resting) && m->tk.cycle == a->pp_due)) {
        if (!a->pp_unsent)
            a->pp_late++;
        pp_post(m, k, false);
        return;
    }
    if (!a->pp_have || (m->tk.cycle < a->pp_due && !a->pp_from_rest))
        return;
    if (m->tk.cycle < a->pp_due)
        return; /* from rest: the move starts at its cycle */
    a->pp_wait = false;
    if (a->pp_st == LSM_OK) {
        a->prof = a->pp_res;
        a->prof.gen.mv = &a->prof.mv; /* the copy's generator reads its own plan */
        a->pp_running = true;
    } else {
        a->plan_errors++;
        (void)lsm_canopen_axis_fault(co, k, LSM_CO_EMCY_SOFTWARE);
    }
}

/* The generator's waiting move (the retarget after a stop, or after a jerk pulse) is due: planned in the
 * background like a set-point, unless a newer set-point's plan is already requested. */
static void pp_after_due(lsm_motion *m, unsigned k)
{
    lsm_motion_axis *a = &m->ax[k];
    if (!a->prof.after_due)
        return;
    a->prof.after_due = false;
    if (a->pp_wait)
        return;
    a->pp_target_mm = a->prof.after_target_mm;
    a->pp_lim = a->prof.after_lim;
    pp_post(m, k, true);
}

static void axis_pp(lsm_motion *m, unsigned k, lsm_canopen *co, lsm_cia402 *ax)
{
    lsm_motion_axis *a = &m->ax[k];
    lsm_cia402_setpoint sp;
    if (lsm_cia402_pp_fetch(ax, &sp) == LSM_CIA402_SP_NONE)
        return;
    const lsm_real cpm = (lsm_real)ax->counts_per_mm;
    const lsm_axprof_limits pl = pp_limits(m, k, &sp, cpm);
    if (m->lead_cycles > 0u) { /* the background plans it (mpipe.h) */
        a->pp_target_mm = (lsm_real)sp.target / cpm;
        a->pp_lim = pl;
        pp_post(m, k, false);
        return;
    }
    if (lsm_axprof_move(&a->prof, (lsm_real)sp.target / cpm, &pl) == LSM_OK) {
        a->pp_running = true;
    } else {
        a->plan_errors++;
        (void)lsm_canopen_axis_fault(co, k, LSM_CO_EMCY_SOFTWARE);
    }
}

static void axis_csp_fetch(lsm_motion *m, unsigned k, lsm_cia402 *ax)
{
    lsm_motion_axis *a = &m->ax[k];
    int32_t t;
    if (!lsm_cia402_csp_fetch(ax, &t))
        return;
    a->csp_n = ip_cycles(m, ax);
    a->csp_i = 0;
    a->csp_from_mm = a->prof.k.s_mm;
    a->csp_to_mm = (lsm_real)t / (lsm_real)ax->counts_per_mm;
    a->csp_v_prev_mm_s = a->csp_active ? a->csp_v_mm_s : 0;
    a->csp_v_mm_s = (a->csp_to_mm - a->csp_from_mm) / ((lsm_real)a->csp_n * m->cycle_s);
    a->csp_active = true;
}

/* One cycle of the CSP interpolation (linear over the period). */
static void axis_csp_step(lsm_motion_axis *a)
{
    if (a->csp_i < a->csp_n) {
        a->csp_i++;
        a->prof.k.s_mm = a->csp_i == a->csp_n ? a->csp_to_mm
                                              : a->csp_from_mm + (a->csp_to_mm - a->csp_from_mm) * (lsm_real)a->csp_i /
                                                                     (lsm_real)a->csp_n;
        a->prof.k.v_mm_s = a->csp_v_mm_s;
    } else { /* the period ended without a new set-point: the demand holds */
        a->csp_active = false;
        a->csp_v_mm_s = 0;
        a->prof.k.v_mm_s = 0;
    }
    a->prof.k.a_mm_s2 = a->prof.k.j_mm_s3 = 0;
}

static void axis_step(lsm_motion *m, unsigned k, lsm_canopen *co)
{
    lsm_cia402 *ax = lsm_canopen_axis(co, k);
    lsm_motion_axis *a = &m->ax[k];
    if (ax->mode_display != a->mode) { /* the display changes only at rest */
        if (ax->mode_display == LSM_CIA402_MODE_PATH)
            m->tk.sync_gen++; /* the feed takes this axis's demand (tick_post) */
        a->mode = ax->mode_display;
        a->pp_running = false;
        a->pp_wait = false;
        a->csp_active = false;
    }
    if (a->mode == LSM_CIA402_MODE_PATH)
        return;
    lsm_cia402_stop_req req;
    const lsm_cia402_stop kind = lsm_cia402_stop_request(ax, &req);
    if (kind != LSM_CIA402_STOP_NONE)
        axis_stop(m, k, ax, kind);
    else if (a->mode == LSM_CIA402_MODE_PP)
        axis_pp(m, k, co, ax);
    if (a->mode == LSM_CIA402_MODE_PP)
        pp_take(m, k, co);
    else if (a->mode == LSM_CIA402_MODE_CSP)
        axis_csp_fetch(m, k, ax);
    if (a->prof.mode != LSM_AXPROF_IDLE) {
        (void)lsm_axprof_step(&a->prof);
        pp_after_due(m, k);
    } else if (a->csp_active)
        axis_csp_step(a);
    else
        a->prof.k.v_mm_s = a->prof.k.a_mm_s2 = a->prof.k.j_mm_s3 = 0;
}

/* The exact-stop executor's cycle (wholly in the tick); path-mode axes take its output. */
static void path_exact_step(lsm_motion *m, lsm_canopen *co, const lsm_real *cpm, const lsm_real *pos)
{
    lsm_co_path *cp = lsm_canopen_path(co);
    lsm_co_path_report rep;
    lsm_pathexact_sync(&m->path, pos);
    lsm_pathexact_step(&m->path, cp, cpm, &rep);
    memcpy(m->path_pos_mm, m->path.pos_mm, sizeof m->path_pos_mm);
    memcpy(m->path_vel_mm_s, m->path.vel_mm_s, sizeof m->path_vel_mm_s);
    m->path_moving = lsm_pathexact_moving(&m->path);
    for (unsigned k = 0; k < m->n_axes; k++) {
        lsm_motion_axis *a = &m->ax[k];
        if (a->mode == LSM_CIA402_MODE_PATH) {
            a->prof.k.s_mm = m->path_pos_mm[k];
            a->prof.k.v_mm_s = m->path_vel_mm_s[k];
            a->prof.k.a_mm_s2 = a->prof.k.j_mm_s3 = 0;
        }
    }
    lsm_co_path_update(cp, &rep);
}

/* ---- the tick's side of the path hand-off (mpipe.h) ---- */

/* Blocks from the node's co_path buffer into the block ring, as far as the set-points consumed say it has room
 * (deterministic: mpipe.h). */
static void tick_hand_blocks(lsm_motion *m, lsm_co_path *cp)
{
    lsm_motion_tk *t = &m->tk;
    const uint32_t used = t->have_last ? t->last.blocks_used : 0u;
    if (lsm_co_path_get_motion(cp) != LSM_CO_PATH_MOTION_RUN)
        return; /* the feed appends only while the path runs: the blocks stay in co_path (0x5003) */
    lsm_co_path_block b;
    while (t->blocks_in - used < LSM_MPIPE_BLOCKS && lsm_co_path_peek(cp, 0, &b)) {
        (void)lsm_co_path_pop(cp, &b);
        lsm_mpipe_blk *e = &m->pipe.blk[lsm_spsc_wr(&m->pipe.blk_idx) & (LSM_MPIPE_BLOCKS - 1u)];
        e->b = b;
        e->epoch = cp->epoch;
        lsm_spsc_push(&m->pipe.blk_idx);
        t->blocks_in++;
    }
}

/* True when every path-mode axis's abort stop has come to rest. */
static bool abort_at_rest(const lsm_motion *m)
{
    for (unsigned k = 0; k < m->n_axes; k++) {
        if (m->ax[k].mode == LSM_CIA402_MODE_PATH && !lsm_axprof_at_rest(&m->ax[k].prof))
            return false;
    }
    return true;
}

/* The path axes during the tick's abort stop: their own stop generators. */
static void tick_abort_step(lsm_motion *m, lsm_co_path *cp)
{
    for (unsigned k = 0; k < m->n_axes; k++) {
        lsm_motion_axis *a = &m->ax[k];
        if (a->mode != LSM_CIA402_MODE_PATH)
            continue;
        (void)lsm_axprof_step(&a->prof);
        m->path_pos_mm[k] = a->prof.k.s_mm;
        m->path_vel_mm_s[k] = a->prof.k.v_mm_s;
    }
    m->path_moving = !abort_at_rest(m);
    lsm_co_path_report rep = m->tk.last.rep;
    rep.feed_um_s = 0u;
    rep.standstill = !m->path_moving;
    rep.starved = false;
    lsm_co_path_update(cp, &rep);
}

/* The record of this cycle (mpipe.h). */
static void tick_post(lsm_motion *m, lsm_co_path *cp, const lsm_real *cpm, const lsm_real *pos)
{
    lsm_motion_tk *t = &m->tk;
    if (lsm_spsc_room(&m->pipe.in_idx, LSM_MPIPE_CAP) == 0u) {
        t->in_full++;
        return;
    }
    lsm_mpipe_in *r = &m->pipe.in[lsm_spsc_wr(&m->pipe.in_idx) & (LSM_MPIPE_CAP - 1u)];
    r->stamp = t->posted;
    r->blocks_in = t->blocks_in;
    r->cp_count = (uint32_t)lsm_co_path_count(cp);
    r->abort = t->abort;
    r->abort_rest = (uint8_t)(t->aborting && abort_at_rest(m));
    r->epoch = cp->epoch;
    r->override_pct = cp->override_pct;
    r->motion = (uint8_t)lsm_co_path_get_motion(cp);
    r->sync_gen = t->sync_gen;
    r->path_mask = 0u;
    for (unsigned k = 0; k < m->n_axes; k++) {
        if (m->ax[k].mode == LSM_CIA402_MODE_PATH)
            r->path_mask |= (uint8_t)(1u << k);
    }
    for (unsigned k = 0; k < LSM_MAX_AXES; k++) {
        r->pos_mm[k] = k < m->n_axes ? pos[k] : 0;
        r->cpm[k] = k < m->n_axes ? cpm[k] : 1;
    }
    lsm_spsc_push(&m->pipe.in_idx);
    t->posted++;
}

void lsm_motion_tick_begin(lsm_motion *m, lsm_canopen *co)
{
    lsm_real cpm[LSM_MAX_AXES] = {0}, pos[LSM_MAX_AXES] = {0};
    m->tk.cycle++;
    pp_collect(m);
    for (unsigned k = 0; k < m->n_axes; k++) {
        axis_step(m, k, co);
        cpm[k] = (lsm_real)lsm_canopen_axis(co, k)->counts_per_mm;
        pos[k] = m->ax[k].prof.k.s_mm;
    }
    lsm_co_path *cp = lsm_canopen_path(co);
    if (m->path_exec == LSM_MOTION_PATH_EXACT) {
        path_exact_step(m, co, cpm, pos);
        return;
    }
    if (m->tk.aborting) {
        tick_abort_step(m, cp);
        for (unsigned k = 0; k < m->n_axes; k++)
            pos[k] = m->ax[k].prof.k.s_mm;
    }
    tick_hand_blocks(m, cp);
    tick_post(m, cp, cpm, pos);
}

/* Axis k's state at the last set-point, from the set-point velocities (backward differences: v1 is the velocity
 * half a cycle before it, a1 = (v1 - v0) / dt one cycle before, j from the two differences), clamped to the
 * machine's limits. */
static void abort_state(const lsm_motion *m, unsigned k, lsm_kin *st)
{
    const lsm_motion_tk *t = &m->tk;
    const lsm_axis_limits *l = &m->lim[k];
    const lsm_real dt = m->cycle_s;
    const lsm_real v1 = t->last.vel_mm_s[k], v0 = t->prev_vel_mm_s[k], vm = t->prev2_vel_mm_s[k];
    const lsm_real a1 = (v1 - v0) / dt;
    lsm_real j = (a1 - (v0 - vm) / dt) / dt;
    j = lsm_max2(-l->j_max_mm_s3, lsm_min2(l->j_max_mm_s3, j));
    lsm_real a = a1 + j * dt;
    a = lsm_max2(-l->a_max_mm_s2, lsm_min2(l->a_max_mm_s2, a));
    st->s_mm = t->last.pos_mm[k];
    st->v_mm_s = v1 + (a1 + j * dt / 2) * dt / 2;
    st->a_mm_s2 = a;
    st->j_mm_s3 = j;
}

/* Underrun while the path moves: every path axis stops from its last state at the machine's limits. */
static void tick_abort(lsm_motion *m, lsm_co_path *cp)
{
    lsm_motion_tk *t = &m->tk;
    t->underruns++;
    t->abort++;
    t->aborting = true;
    for (unsigned k = 0; k < m->n_axes; k++) {
        lsm_motion_axis *a = &m->ax[k];
        if (a->mode != LSM_CIA402_MODE_PATH)
            continue;
        const lsm_axis_limits *l = &m->lim[k];
        const lsm_jstop_limits sl = {l->a_max_mm_s2, l->j_max_mm_s3, l->snap_max_mm_s4};
        abort_state(m, k, &a->prof.k);
        (void)lsm_axprof_stop(&a->prof, &sl, (uint8_t)LSM_CIA402_STOP_EMERGENCY);
    }
    lsm_co_path_reject(cp, t->last.rep.active_seq); /* the path is dropped: EMCY 0xFF01, buffer flushed */
    tick_abort_step(m, cp);
}

/* Applies a consumed set-point. */
static void tick_apply(lsm_motion *m, lsm_co_path *cp, const lsm_mpipe_out *o)
{
    lsm_motion_tk *t = &m->tk;
    if (o->rejects != t->rejects_seen) {
        t->rejects_seen = o->rejects;
        lsm_co_path_reject(cp, o->reject_seq);
    }
    if (t->aborting) {
        if (o->abort != t->abort)
            return; /* made before the background saw the abort: dropped */
        t->aborting = false;
    }
    for (unsigned k = 0; k < m->n_axes; k++) {
        t->prev2_vel_mm_s[k] = t->prev_vel_mm_s[k];
        t->prev_vel_mm_s[k] = m->path_vel_mm_s[k];
        m->path_pos_mm[k] = o->pos_mm[k];
        m->path_vel_mm_s[k] = o->vel_mm_s[k];
        lsm_motion_axis *a = &m->ax[k];
        if (a->mode == LSM_CIA402_MODE_PATH && o->sync_gen == t->sync_gen) { /* made after the feed took its demand */
            a->prof.k.s_mm = o->pos_mm[k];
            a->prof.k.v_mm_s = o->vel_mm_s[k];
            a->prof.k.a_mm_s2 = a->prof.k.j_mm_s3 = 0;
        }
    }
    m->path_moving = o->moving;
    lsm_co_path_update(cp, &o->rep);
}

void lsm_motion_tick_end(lsm_motion *m, lsm_canopen *co)
{
    lsm_motion_tk *t = &m->tk;
    if (m->path_exec == LSM_MOTION_PATH_EXACT || t->posted - t->consumed <= m->lead_cycles)
        return; /* nothing due yet (the first lead cycles) */
    lsm_co_path *cp = lsm_canopen_path(co);
    const uint32_t ready = lsm_spsc_avail(&m->pipe.out_idx);
    if (t->have_last && t->last.moving && (t->min_ahead == 0u || ready + 1u < t->min_ahead))
        t->min_ahead = ready + 1u;
    if (ready == 0u) {
        if (t->aborting)
            return;
        if (t->have_last && t->last.moving)
            tick_abort(m, cp);
        else
            t->stalls++;
        return;
    }
    t->last = m->pipe.out[lsm_spsc_rd(&m->pipe.out_idx) & (LSM_MPIPE_CAP - 1u)];
    lsm_spsc_pop(&m->pipe.out_idx);
    t->consumed++;
    t->have_last = true;
    tick_apply(m, cp, &t->last);
}

void lsm_motion_tick(lsm_motion *m, lsm_canopen *co)
{
    lsm_motion_tick_begin(m, co);
    lsm_motion_tick_end(m, co);
}

/* ---- the background's side ---- */

/* The block source of lsm_pathfeed_background_io: the block ring, as far as the record's tick had handed over;
 * blocks of another epoch than the record's, or of a refused epoch, are dropped. */
static bool bg_peek(void *ctx, lsm_co_path_block *b)
{
    lsm_motion *m = ctx;
    lsm_motion_bg *g = &m->bg;
    while (g->blocks_used != g->rec->blocks_in) {
        const lsm_mpipe_blk *e = &m->pipe.blk[lsm_spsc_rd(&m->pipe.blk_idx) & (LSM_MPIPE_BLOCKS - 1u)];
        if (e->epoch == g->rec->epoch && !(g->drop_valid && e->epoch == g->drop_epoch)) {
            *b = e->b;
            return true;
        }
        lsm_spsc_pop(&m->pipe.blk_idx);
        g->blocks_used++;
    }
    return false;
}

static void bg_pop(void *ctx)
{
    lsm_motion *m = ctx;
    lsm_spsc_pop(&m->pipe.blk_idx);
    m->bg.blocks_used++;
}

static void bg_reject(void *ctx, uint32_t seq)
{
    lsm_motion_bg *g = &((lsm_motion *)ctx)->bg;
    g->rejects++;
    g->reject_seq = seq;
    g->drop_epoch = g->rec->epoch;
    g->drop_valid = true;
}

static size_t bg_pending(void *ctx)
{
    const lsm_motion_bg *g = &((const lsm_motion *)ctx)->bg;
    return (size_t)g->rec->cp_count + (size_t)(g->rec->blocks_in - g->blocks_used);
}

/* lsm_pathfeed_sync with the axes' demands: a path-mode axis's demand is the feed's own output of lead cycles ago,
 * so it counts only when an axis entered path mode since the last record (its demand then comes from elsewhere). */
static void bg_sync(lsm_motion *m, const lsm_mpipe_in *r)
{
    lsm_real pos[LSM_MAX_AXES] = {0};
    const bool entered = r->sync_gen != m->bg.sync_seen;
    for (unsigned k = 0; k < m->n_axes; k++)
        pos[k] = !entered && (r->path_mask & (1u << k)) != 0u ? m->feed.pos_mm[k] : r->pos_mm[k];
    m->bg.sync_seen = r->sync_gen;
    lsm_pathfeed_sync(&m->feed, pos);
}

/* A tick's abort: once its stop is at rest, the planner restarts there (its blocks dropped). */
static bool bg_follow_abort(lsm_motion *m, const lsm_mpipe_in *r)
{
    lsm_motion_bg *g = &m->bg;
    if (r->abort == g->abort_seen)
        return false;
    if (r->abort_rest) {
        (void)lsm_pathfeed_restart_at(&m->feed, r->pos_mm);
        m->feed.epoch = r->epoch;
        g->abort_seen = r->abort;
        return false;
    }
    return true; /* still stopping: no appends */
}

/* One PP plan request: a copy of the generator stepped to the move's first cycle, the move planned there. */
static bool bg_pp(lsm_motion *m)
{
    if (lsm_spsc_avail(&m->pipe.pp_req_idx) == 0u || lsm_spsc_room(&m->pipe.pp_res_idx, LSM_MPIPE_PP) == 0u)
        return false;
    const lsm_mpipe_pp *q = &m->pipe.pp_req[lsm_spsc_rd(&m->pipe.pp_req_idx) & (LSM_MPIPE_PP - 1u)];
    lsm_mpipe_pp *r = &m->pipe.pp_res[lsm_spsc_wr(&m->pipe.pp_res_idx) & (LSM_MPIPE_PP - 1u)];
    r->base = q->base;
    r->base.gen.mv = &r->base.mv;
    for (uint32_t i = 0; i < q->steps; i++)
        (void)lsm_axprof_step(&r->base);
    r->base.after_due = false; /* this set-point replaces the move that waited */
    r->st = lsm_axprof_move(&r->base, q->target_mm, &q->lim);
    r->gen = q->gen;
    r->axis = q->axis;
    lsm_spsc_push(&m->pipe.pp_res_idx);
    lsm_spsc_pop(&m->pipe.pp_req_idx);
    return true;
}

bool lsm_motion_background(lsm_motion *m)
{
    if (bg_pp(m))
        return true;
    if (m->path_exec == LSM_MOTION_PATH_EXACT || lsm_spsc_avail(&m->pipe.in_idx) == 0u ||
        lsm_spsc_room(&m->pipe.out_idx, LSM_MPIPE_CAP) == 0u)
        return false;
    lsm_motion_bg *g = &m->bg;
    const lsm_mpipe_in *r = &m->pipe.in[lsm_spsc_rd(&m->pipe.in_idx) & (LSM_MPIPE_CAP - 1u)];
    g->rec = r;
    if (g->drop_valid && r->epoch != g->drop_epoch)
        g->drop_valid = false;
    const bool stopping = bg_follow_abort(m, r);
    bg_sync(m, r);
    if (!stopping) {
        const lsm_pathfeed_io io = {r->epoch, r->override_pct, r->motion, bg_peek, bg_pop, bg_reject, bg_pending, m};
        lsm_pathfeed_background_io(&m->feed, &io, r->cpm);
    }
    lsm_mpipe_out *o = &m->pipe.out[lsm_spsc_wr(&m->pipe.out_idx) & (LSM_MPIPE_CAP - 1u)];
    lsm_pathfeed_tick_io(&m->feed, bg_pending(m), &o->rep);
    memcpy(o->pos_mm, m->feed.pos_mm, sizeof o->pos_mm);
    memcpy(o->vel_mm_s, m->feed.vel_mm_s, sizeof o->vel_mm_s);
    o->moving = lsm_pathfeed_moving(&m->feed);
    o->blocks_used = g->blocks_used;
    o->rejects = g->rejects;
    o->reject_seq = g->reject_seq;
    o->abort = g->abort_seen;
    o->sync_gen = g->sync_seen;
    lsm_spsc_push(&m->pipe.out_idx);
    lsm_spsc_pop(&m->pipe.in_idx);
    g->rec = NULL;
    g->cycles++;
    return true;
}

void lsm_motion_cycle(lsm_motion *m, lsm_canopen *co)
{
    lsm_motion_tick_begin(m, co);
    (void)lsm_motion_background(m);
    lsm_motion_tick_end(m, co);
}

static int32_t to_counts(lsm_real x_mm, lsm_real cpm)
{
#if LSM_REAL_IS_FLOAT
    /* half away from zero like llroundf, without its 64-bit conversion (libgcc's __aeabi_f2lz goes through
     * software double on the Cortex-M4F) */
    const lsm_real x = x_mm * cpm;
    const lsm_real c = x >= 0 ? lsm_floor(x + (lsm_real)0.5) : -lsm_floor((lsm_real)0.5 - x);
#else
    const lsm_real c = (lsm_real)llround(x_mm * cpm);
#endif
    if (c > (lsm_real)2147483647.0)
        return INT32_MAX;
    if (c < (lsm_real)-2147483648.0)
        return INT32_MIN;
    return (int32_t)c;
}

static bool axis_at_rest(const lsm_motion *m, unsigned k)
{
    const lsm_motion_axis *a = &m->ax[k];
    if (a->mode == LSM_CIA402_MODE_PATH)
        return !m->path_moving;
    return lsm_axprof_at_rest(&a->prof) && !a->csp_active && a->prof.k.v_mm_s == 0;
}

void lsm_motion_feedback(lsm_motion *m, lsm_canopen *co, const lsm_real *actual_mm, const lsm_real *actual_vel_mm_s,
                         uint32_t now_us)
{
    for (unsigned k = 0; k < m->n_axes; k++) {
        lsm_motion_axis *a = &m->ax[k];
        lsm_cia402 *ax = lsm_canopen_axis(co, k);
        const lsm_real cpm = (lsm_real)ax->counts_per_mm;
        a->actual_mm = actual_mm != NULL ? actual_mm[k] : a->prof.k.s_mm;
        a->actual_vel_mm_s = actual_vel_mm_s != NULL ? actual_vel_mm_s[k] : a->prof.k.v_mm_s;
        lsm_cia402_feedback fb;
        fb.demand = to_counts(a->prof.k.s_mm, cpm);
        fb.actual = to_counts(a->actual_mm, cpm);
        fb.velocity = to_counts(a->actual_vel_mm_s, cpm);
        fb.standstill = axis_at_rest(m, k);
        lsm_cia402_update(ax, &fb, now_us);
        if (a->pp_running && !a->pp_wait && a->prof.mode == LSM_AXPROF_IDLE && !a->prof.have_after) {
            a->pp_running = false;
            lsm_cia402_pp_done(ax);
        }
    }
}

void lsm_motion_stop_all(lsm_motion *m, lsm_canopen *co)
{
    for (unsigned k = 0; k < m->n_axes; k++) {
        lsm_cia402 *ax = lsm_canopen_axis(co, k);
        if (ax->state == LSM_CIA402_OPERATION_ENABLED) {
            const int16_t keep = ax->abort_option;
            ax->abort_option = 3; /* quick stop */
            lsm_cia402_comm_lost(ax);
            ax->abort_option = keep;
        }
    }
    lsm_co_path_hold(lsm_canopen_path(co), true);
}

bool lsm_motion_at_rest(const lsm_motion *m)
{
    for (unsigned k = 0; k < m->n_axes; k++) {
        if (!axis_at_rest(m, k))
            return false;
    }
    return !m->path_moving;
}
