#include "node_app.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

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
    lsm_motion_config mc;
    memset(&mc, 0, sizeof mc);
    for (unsigned k = 0; k < cfg->n_axes; k++) {
        const sim_machine_axis *a = &app->machine.axes[k];
        mc.lim[k].v_max_mm_s = a->v_max_u_s;
        mc.lim[k].a_max_mm_s2 = a->a_max_u_s2;
        mc.lim[k].j_max_mm_s3 = a->j_max_u_s3;
        mc.lim[k].snap_max_mm_s4 = a->snap_max_u_s4;
        lsm_status st = sim_drive_init(&app->drv[k], &a->drive, app->cycle_s, 0.0);
        if (st != LSM_OK)
            return st;
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
    cc.sdo_background = true; /* the firmware's split; this synchronous loop runs the server (lsm_canopen_sdo_sync) */
    lsm_status st = lsm_canopen_init(&app->co, &cc, now_us);
    if (st != LSM_OK)
        return st;
    if (cfg->path_exec != NODE_APP_PATH_EXACT && cfg->path_exec != NODE_APP_PATH_PLANNER)
        return LSM_E_ARG;
    uint32_t la_cap = cfg->lookahead_blocks != 0u         ? cfg->lookahead_blocks
                      : app->machine.lookahead_blocks > 0 ? (uint32_t)app->machine.lookahead_blocks
                                                          : 64u;
    la_cap = la_cap < LSM_PLANNER_MIN_BLOCKS   ? LSM_PLANNER_MIN_BLOCKS
             : la_cap > NODE_APP_LOOKAHEAD_MAX ? NODE_APP_LOOKAHEAD_MAX
                                               : la_cap;
    mc.n_axes = cfg->n_axes;
    mc.cycle_s = app->cycle_s;
    mc.path_exec = cfg->path_exec;
    mc.feed.blocks = app->la_blocks;
    mc.feed.capacity = la_cap;
    mc.feed.saved = app->la_saved;
    mc.feed.saved_cap = NODE_APP_LOOKAHEAD_MAX + 1u;
    return lsm_motion_init(&app->mo, &mc, &app->co);
}

lsm_status node_app_rx(node_app *app, const lsm_can_frame *f, uint32_t now_us)
{
    lsm_status st = lsm_canopen_rx(&app->co, f, now_us);
    if (st != LSM_OK)
        app->rx_errors++;
    else if (f->id == app->co.sdo_cob_rx)
        lsm_canopen_sdo_sync(&app->co, now_us); /* answered in arrival order, as by a node served in one context */
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

void node_app_cycle(node_app *app, bool estop_active, uint32_t now_us)
{
    const unsigned n = app->cfg.n_axes;
    app->estop = estop_active;
    lsm_canopen_estop(&app->co, estop_active, now_us);
    lsm_canopen_sdo_sync(&app->co, now_us); /* the background's SDO step (its timeout), then the tick's */
    (void)lsm_canopen_process(&app->co, now_us);
    lsm_motion_cycle(&app->mo, &app->co);
    for (unsigned k = 0; k < n; k++) {
        const lsm_kin *d = lsm_motion_demand(&app->mo, k);
        double actual = d->s_mm;
        if (sim_drive_step(&app->drv[k], d->s_mm, d->v_mm_s, &actual) == LSM_OK) {
            sim_drive_state ds;
            sim_drive_get_state(&app->drv[k], &ds);
            app->actual[k] = actual;
            app->actual_vel[k] = ds.load_vel;
        }
    }
    lsm_motion_feedback(&app->mo, &app->co, app->actual, app->actual_vel, now_us);
    app->out_enable = lsm_canopen_drive_enable(&app->co);
    app->out_inpos = lsm_canopen_in_position(&app->co);
    app->cycles++;
}

void node_app_stop_all(node_app *app)
{
    lsm_motion_stop_all(&app->mo, &app->co);
}

bool node_app_at_rest(const node_app *app)
{
    return lsm_motion_at_rest(&app->mo);
}
