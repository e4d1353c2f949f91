/* motion.c: the CiA 402 motion layer (motion.h). */
#include "motion.h"

#include <string.h>

#include "lsm_math.h"

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
        (cfg->path_exec != LSM_MOTION_PATH_PLANNER && cfg->path_exec != LSM_MOTION_PATH_EXACT))
        return LSM_E_ARG;
    for (unsigned k = 0; k < cfg->n_axes; k++) {
        if (!limits_ok(&cfg->lim[k]))
            return LSM_E_LIMIT;
    }
    memset(m, 0, sizeof *m);
    m->n_axes = cfg->n_axes;
    m->path_exec = cfg->path_exec;
    m->cycle_s = cfg->cycle_s;
    for (unsigned k = 0; k < cfg->n_axes; k++) {
        m->lim[k] = cfg->lim[k];
        lsm_axprof_init(&m->ax[k].prof, m->cycle_s, 0);
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
        return s;
    }
    const lsm_real d = kind == LSM_CIA402_STOP_QUICK ? (lsm_real)ax->quick_stop_decel : (lsm_real)ax->profile_decel;
    s.decel_mm_s2 = lsm_min2(d / cpm, l->a_max_mm_s2);
    s.jerk_mm_s3 = lsm_min2((lsm_real)ax->profile_jerk / cpm, l->j_max_mm_s3);
    s.snap_mm_s4 = lsm_min2((lsm_real)ax->profile_snap / cpm, l->snap_max_mm_s4);
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
    (void)lsm_axprof_stop(&a->prof, &sl, (uint8_t)kind);
    a->pp_running = false;
}

static void axis_pp(lsm_motion *m, unsigned k, lsm_canopen *co, lsm_cia402 *ax)
{
    lsm_motion_axis *a = &m->ax[k];
    lsm_cia402_setpoint sp;
    if (lsm_cia402_pp_fetch(ax, &sp) == LSM_CIA402_SP_NONE)
        return;
    const lsm_real cpm = (lsm_real)ax->counts_per_mm;
    const lsm_axprof_limits pl = pp_limits(m, k, &sp, cpm);
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
        a->mode = ax->mode_display;
        a->pp_running = false;
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
    else if (a->mode == LSM_CIA402_MODE_CSP)
        axis_csp_fetch(m, k, ax);
    if (a->prof.mode != LSM_AXPROF_IDLE)
        (void)lsm_axprof_step(&a->prof);
    else if (a->csp_active)
        axis_csp_step(a);
    else
        a->prof.k.v_mm_s = a->prof.k.a_mm_s2 = a->prof.k.j_mm_s3 = 0;
}

/* The path executor's cycle; path-mode axes take its output. */
static void path_step(lsm_motion *m, lsm_canopen *co, const lsm_real *cpm, const lsm_real *pos)
{
    lsm_co_path *cp = lsm_canopen_path(co);
    lsm_co_path_report rep;
    if (m->path_exec == LSM_MOTION_PATH_EXACT) {
        lsm_pathexact_sync(&m->path, pos);
        lsm_pathexact_step(&m->path, cp, cpm, &rep);
        memcpy(m->path_pos_mm, m->path.pos_mm, sizeof m->path_pos_mm);
        memcpy(m->path_vel_mm_s, m->path.vel_mm_s, sizeof m->path_vel_mm_s);
        m->path_moving = lsm_pathexact_moving(&m->path);
    } else {
        lsm_pathfeed_sync(&m->feed, pos);
        lsm_pathfeed_step(&m->feed, cp, cpm, &rep);
        memcpy(m->path_pos_mm, m->feed.pos_mm, sizeof m->path_pos_mm);
        memcpy(m->path_vel_mm_s, m->feed.vel_mm_s, sizeof m->path_vel_mm_s);
        m->path_moving = lsm_pathfeed_moving(&m->feed);
    }
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

void lsm_motion_cycle(lsm_motion *m, lsm_canopen *co)
{
    lsm_real cpm[LSM_MAX_AXES], pos[LSM_MAX_AXES];
    for (unsigned k = 0; k < m->n_axes; k++) {
        axis_step(m, k, co);
        cpm[k] = (lsm_real)lsm_canopen_axis(co, k)->counts_per_mm;
        pos[k] = m->ax[k].prof.k.s_mm;
    }
    path_step(m, co, cpm, pos);
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
        if (a->pp_running && a->prof.mode == LSM_AXPROF_IDLE && !a->prof.have_after) {
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
