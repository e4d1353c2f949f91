#include "node_app.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define PI_D 3.14159265358979323846

void node_app_default_machine(sim_machine *m, int n_axes)
{
    static const char names[] = "XYZUVW";
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "built-in");
    snprintf(m->description, sizeof m->description, "lissom-node built-in machine: %d linear axes", n_axes);
    m->cycle_s = 0.001;
    m->lookahead_blocks = 64;
    m->blend_tol_mm = 0.02;
    m->n_axes = n_axes;
    for (int k = 0; k < n_axes && k < SIM_MACHINE_MAX_AXES; k++) {
        sim_machine_axis *a = &m->axes[k];
        a->name = names[k];
        a->index = k;
        a->rotary = false;
        a->v_max_u_s = 250;
        a->a_max_u_s2 = 3000;
        a->j_max_u_s3 = 60000;
        a->snap_max_u_s4 = 1.18e7;
        a->counts_per_u = 1000;
        sim_drive_params_default(&a->drive, false);
        a->drive.vff_gain = 1.0;
        a->drive.encoder_counts_per_mm = 1000;
        m->axis_mask = (uint8_t)(m->axis_mask | (1u << k));
    }
}

lsm_status node_app_init(node_app *app, const node_app_config *cfg, uint32_t now_us)
{
    if (app == NULL || cfg == NULL)
        return LSM_E_NULL;
    if (cfg->n_axes < 1u || cfg->n_axes > LSM_MAX_AXES || cfg->cycle_us < 100u || cfg->cycle_us > 100000u ||
        cfg->path_slots < 1u || cfg->path_slots > NODE_APP_PATH_SLOTS_MAX)
        return LSM_E_ARG;
    memset(app, 0, sizeof *app);
    app->cfg = *cfg;
    if (cfg->machine != NULL)
        app->machine = *cfg->machine;
    else
        node_app_default_machine(&app->machine, cfg->n_axes);
    if (app->machine.n_axes < cfg->n_axes)
        return LSM_E_ARG;
    app->cfg.machine = NULL;
    app->cycle_s = (double)cfg->cycle_us * 1e-6;
    for (unsigned k = 0; k < cfg->n_axes; k++) {
        const sim_machine_axis *a = &app->machine.axes[k];
        app->lim[k].v_max = a->v_max_u_s;
        app->lim[k].a_max = a->a_max_u_s2;
        app->lim[k].j_max = a->j_max_u_s3;
        app->lim[k].snap_max = a->snap_max_u_s4;
        lsm_status st = sim_drive_init(&app->drv[k], &a->drive, app->cycle_s, 0.0);
        if (st != LSM_OK)
            return st;
        node_prof_init(&app->ax[k].prof, app->cycle_s, 0.0);
    }
    lsm_canopen_config cc = lsm_canopen_default_config();
    cc.node_id = cfg->node_id;
    cc.n_axes = cfg->n_axes;
    cc.heartbeat_ms = cfg->heartbeat_ms;
    cc.master_node_id = cfg->master_id;
    cc.master_timeout_ms = cfg->master_timeout_ms;
    cc.device_name = "Lissom motion controller (lissom-node)";
    cc.tx_storage = app->txbuf;
    cc.tx_cap = NODE_APP_TXQ;
    cc.path_storage = app->blocks;
    cc.path_cap = cfg->path_slots;
    lsm_status st = lsm_canopen_init(&app->co, &cc, now_us);
    if (st != LSM_OK)
        return st;
    for (unsigned k = 0; k < cfg->n_axes; k++)
        app->ax[k].mode = lsm_canopen_axis(&app->co, k)->mode_display;
    double zero[LSM_MAX_AXES] = {0};
    node_path_init(&app->path, cfg->n_axes, app->cycle_s, app->lim, zero);
    if (cfg->path_exec != NODE_APP_PATH_EXACT && cfg->path_exec != NODE_APP_PATH_PLANNER)
        return LSM_E_ARG;
    uint32_t la_cap = cfg->lookahead_blocks != 0u ? cfg->lookahead_blocks
                      : app->machine.lookahead_blocks > 0 ? (uint32_t)app->machine.lookahead_blocks
                                                           : 64u;
    return node_la_init(&app->la, cfg->n_axes, app->cycle_s, app->lim, zero, la_cap);
}

lsm_status node_app_rx(node_app *app, const lsm_can_frame *f, uint32_t now_us)
{
    lsm_status st = lsm_canopen_rx(&app->co, f, now_us);
    if (st != LSM_OK)
        app->rx_errors++;
    return st;
}

void node_app_bus_event(node_app *app, lsm_can_bus_event ev, uint32_t now_us)
{
    lsm_canopen_bus_event(&app->co, ev, now_us);
}

bool node_app_tx_pop(node_app *app, lsm_can_frame *f)
{
    return lsm_canopen_tx_pop(&app->co, f);
}

static int32_t to_counts(double x_mm, double cpm)
{
    double c = llround(x_mm * cpm);
    if (c > 2147483647.0)
        return INT32_MAX;
    if (c < -2147483648.0)
        return INT32_MIN;
    return (int32_t)c;
}

/* Stop limits for a stop request of this kind (see node_app.h), in mm units. */
static node_stop_limits stop_limits(const node_app *app, unsigned k, const lsm_cia402 *ax, uint8_t kind)
{
    const node_axis_limits *l = &app->lim[k];
    const double cpm = (double)ax->counts_per_mm;
    node_stop_limits s;
    if (kind == LSM_CIA402_STOP_EMERGENCY) {
        s.decel = l->a_max;
        s.jerk = l->j_max;
        s.snap = l->snap_max;
        return s;
    }
    const double d = kind == LSM_CIA402_STOP_QUICK ? (double)ax->quick_stop_decel : (double)ax->profile_decel;
    s.decel = fmin(d / cpm, l->a_max);
    s.jerk = fmin((double)ax->profile_jerk / cpm, l->j_max);
    s.snap = fmin((double)ax->profile_snap / cpm, l->snap_max);
    if (ax->profile_type == 0)
        s.snap = 1.0001 * PI_D * s.jerk / (2 * app->cycle_s);
    return s;
}

static node_prof_limits pp_limits(const node_app *app, unsigned k, const lsm_cia402_setpoint *sp, double cpm)
{
    const node_axis_limits *l = &app->lim[k];
    node_prof_limits p;
    p.v_max = fmin((double)sp->velocity / cpm, l->v_max);
    p.a_max = fmin((double)(sp->accel < sp->decel ? sp->accel : sp->decel) / cpm, l->a_max);
    p.j_max = fmin((double)sp->jerk / cpm, l->j_max);
    p.snap_max = fmin((double)sp->snap / cpm, l->snap_max);
    p.profile_type = sp->profile_type == 0 ? 0 : 1;
    return p;
}

static uint32_t ip_cycles(const node_app *app, const lsm_cia402 *ax)
{
    double period = (double)ax->ip_period_value * pow(10.0, (double)ax->ip_period_index);
    double n = floor(period / app->cycle_s + 0.5);
    if (!(n >= 1))
        n = 1;
    if (n > 100000)
        n = 100000;
    return (uint32_t)n;
}

static void axis_step(node_app *app, unsigned k)
{
    lsm_cia402 *ax = lsm_canopen_axis(&app->co, k);
    node_axis *a = &app->ax[k];
    const double cpm = (double)ax->counts_per_mm;
    if (ax->mode_display != a->mode) { /* the display changes only at rest */
        a->mode = ax->mode_display;
        a->pp_running = false;
        a->csp_active = false;
    }
    if (a->mode == LSM_CIA402_MODE_PATH)
        return;
    lsm_cia402_stop_req req;
    const lsm_cia402_stop kind = lsm_cia402_stop_request(ax, &req);
    if (kind != LSM_CIA402_STOP_NONE) {
        const node_stop_limits sl = stop_limits(app, k, ax, (uint8_t)kind);
        if (a->csp_active) {
            const double n_s = (double)a->csp_n * app->cycle_s;
            double acc = (a->csp_v - a->csp_v_prev) / n_s;
            acc = fmax(-sl.decel, fmin(sl.decel, acc));
            a->prof.k.v_mm_s = a->csp_v;
            a->prof.k.a_mm_s2 = acc;
            a->csp_active = false;
        }
        (void)node_prof_stop(&a->prof, &sl, (uint8_t)kind);
        a->pp_running = false;
    } else if (a->mode == LSM_CIA402_MODE_PP) {
        lsm_cia402_setpoint sp;
        if (lsm_cia402_pp_fetch(ax, &sp) != LSM_CIA402_SP_NONE) {
            const node_prof_limits pl = pp_limits(app, k, &sp, cpm);
            if (node_prof_move(&a->prof, (double)sp.target / cpm, &pl) == LSM_OK) {
                a->pp_running = true;
            } else {
                a->plan_errors++;
                (void)lsm_canopen_axis_fault(&app->co, k, LSM_CO_EMCY_SOFTWARE);
            }
        }
    } else if (a->mode == LSM_CIA402_MODE_CSP) {
        int32_t t;
        if (lsm_cia402_csp_fetch(ax, &t)) {
            a->csp_n = ip_cycles(app, ax);
            a->csp_i = 0;
            a->csp_from = a->prof.k.s_mm;
            a->csp_to = (double)t / cpm;
            a->csp_v_prev = a->csp_active ? a->csp_v : 0.0;
            a->csp_v = (a->csp_to - a->csp_from) / ((double)a->csp_n * app->cycle_s);
            a->csp_active = true;
        }
    }
    if (a->prof.mode != NODE_PROF_IDLE) {
        (void)node_prof_step(&a->prof);
    } else if (a->csp_active) {
        if (a->csp_i < a->csp_n) {
            a->csp_i++;
            a->prof.k.s_mm = a->csp_i == a->csp_n
                                 ? a->csp_to
                                 : a->csp_from + (a->csp_to - a->csp_from) * (double)a->csp_i / (double)a->csp_n;
            a->prof.k.v_mm_s = a->csp_v;
        } else { /* the period ended without a new set-point: the demand holds */
            a->csp_active = false;
            a->csp_v = 0;
            a->prof.k.v_mm_s = 0;
        }
        a->prof.k.a_mm_s2 = a->prof.k.j_mm_s3 = 0;
    } else {
        a->prof.k.v_mm_s = a->prof.k.a_mm_s2 = a->prof.k.j_mm_s3 = 0;
    }
}

static bool axis_at_rest(const node_app *app, unsigned k)
{
    const node_axis *a = &app->ax[k];
    if (a->mode == LSM_CIA402_MODE_PATH)
        return !app->path_moving;
    return node_prof_at_rest(&a->prof) && !a->csp_active && a->prof.k.v_mm_s == 0;
}

void node_app_cycle(node_app *app, bool estop_active, uint32_t now_us)
{
    const unsigned n = app->cfg.n_axes;
    app->estop = estop_active;
    lsm_canopen_estop(&app->co, estop_active, now_us);
    (void)lsm_canopen_process(&app->co, now_us);

    double cpm[LSM_MAX_AXES], pos[LSM_MAX_AXES];
    for (unsigned k = 0; k < n; k++) {
        axis_step(app, k);
        cpm[k] = (double)lsm_canopen_axis(&app->co, k)->counts_per_mm;
        pos[k] = app->ax[k].prof.k.s_mm;
    }
    lsm_co_path *cp = lsm_canopen_path(&app->co);
    lsm_co_path_report rep;
    if (app->cfg.path_exec == NODE_APP_PATH_EXACT) {
        node_path_sync(&app->path, pos);
        node_path_step(&app->path, cp, cpm, &rep);
        memcpy(app->path_pos, app->path.pos, sizeof app->path_pos);
        memcpy(app->path_vel, app->path.vel, sizeof app->path_vel);
        app->path_moving = node_path_moving(&app->path);
    } else {
        node_la_sync(&app->la, pos);
        node_la_step(&app->la, cp, cpm, &rep);
        memcpy(app->path_pos, app->la.pos, sizeof app->path_pos);
        memcpy(app->path_vel, app->la.vel, sizeof app->path_vel);
        app->path_moving = node_la_moving(&app->la);
    }
    for (unsigned k = 0; k < n; k++) {
        node_axis *a = &app->ax[k];
        if (a->mode == LSM_CIA402_MODE_PATH) {
            a->prof.k.s_mm = app->path_pos[k];
            a->prof.k.v_mm_s = app->path_vel[k];
            a->prof.k.a_mm_s2 = a->prof.k.j_mm_s3 = 0;
        }
    }
    lsm_co_path_update(cp, &rep);

    for (unsigned k = 0; k < n; k++) {
        node_axis *a = &app->ax[k];
        lsm_cia402 *ax = lsm_canopen_axis(&app->co, k);
        double actual = a->prof.k.s_mm;
        if (sim_drive_step(&app->drv[k], a->prof.k.s_mm, a->prof.k.v_mm_s, &actual) == LSM_OK) {
            sim_drive_state ds;
            sim_drive_get_state(&app->drv[k], &ds);
            a->actual = actual;
            a->actual_vel = ds.load_vel;
        }
        lsm_cia402_feedback fb;
        fb.demand = to_counts(a->prof.k.s_mm, cpm[k]);
        fb.actual = to_counts(a->actual, cpm[k]);
        fb.velocity = to_counts(a->actual_vel, cpm[k]);
        fb.standstill = axis_at_rest(app, k);
        lsm_cia402_update(ax, &fb, now_us);
        if (a->pp_running && a->prof.mode == NODE_PROF_IDLE && !a->prof.have_after) {
            a->pp_running = false;
            lsm_cia402_pp_done(ax);
        }
    }
    app->out_enable = lsm_canopen_drive_enable(&app->co);
    app->out_inpos = lsm_canopen_in_position(&app->co);
    app->cycles++;
}

void node_app_stop_all(node_app *app)
{
    for (unsigned k = 0; k < app->cfg.n_axes; k++) {
        lsm_cia402 *ax = lsm_canopen_axis(&app->co, k);
        if (ax->state == LSM_CIA402_OPERATION_ENABLED) {
            const int16_t keep = ax->abort_option;
            ax->abort_option = 3; /* quick stop */
            lsm_cia402_comm_lost(ax);
            ax->abort_option = keep;
        }
    }
    lsm_co_path_hold(lsm_canopen_path(&app->co), true);
}

bool node_app_at_rest(const node_app *app)
{
    for (unsigned k = 0; k < app->cfg.n_axes; k++) {
        if (!axis_at_rest(app, k))
            return false;
    }
    return !app->path_moving;
}
