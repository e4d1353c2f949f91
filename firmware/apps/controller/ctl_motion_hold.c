/*
 * ctl_motion_hold.c: INTERIM motion layer of the controller image (ctl_motion.h): no motion generator. Every
 * axis holds the position it has; what would move it is refused so that the master knows at once:
 *   PP or CSP set-point -> application fault on that axis (0x603F = 0x6100, EMCY 0x6100, fault reaction, which
 *                          completes at once because the axis is at rest);
 *   path block          -> rejected (lsm_co_path_reject: EMCY 0xFF01, buffer flushed).
 * Feedback: ideal loopback (actual = demand, velocity 0, standstill).
 */
#include "ctl_motion_hold.h"

#include <string.h>

lsm_status ctl_motion_init(ctl_motion *m, const ctl_motion_config *cfg, lsm_canopen *co)
{
    if (m == NULL || cfg == NULL || co == NULL)
        return LSM_E_NULL;
    if (cfg->n_axes < 1u || cfg->n_axes > LSM_MAX_AXES || cfg->n_axes != co->n_axes || !(cfg->cycle_s > 0))
        return LSM_E_ARG;
    memset(m, 0, sizeof *m);
    m->n_axes = cfg->n_axes;
    return LSM_OK;
}

static void axis_tick(ctl_motion *m, lsm_canopen *co, unsigned k, uint32_t now_us)
{
    lsm_cia402 *ax = lsm_canopen_axis(co, k);
    lsm_cia402_stop_req req;
    lsm_cia402_setpoint sp;
    int32_t target;
    (void)lsm_cia402_stop_request(ax, &req); /* at rest: a stop is complete as soon as it is asked for */
    if (lsm_cia402_pp_fetch(ax, &sp) != LSM_CIA402_SP_NONE || lsm_cia402_csp_fetch(ax, &target)) {
        m->refused[k]++;
        (void)lsm_canopen_axis_fault(co, k, LSM_CO_EMCY_SOFTWARE);
    }
    lsm_cia402_feedback fb;
    fb.demand = m->demand[k];
    fb.actual = m->demand[k];
    fb.velocity = 0;
    fb.standstill = true;
    lsm_cia402_update(ax, &fb, now_us);
}

void ctl_motion_tick(ctl_motion *m, lsm_canopen *co, uint32_t now_us)
{
    for (unsigned k = 0; k < m->n_axes; k++)
        axis_tick(m, co, k, now_us);
    lsm_co_path *cp = lsm_canopen_path(co);
    lsm_co_path_block b;
    if (lsm_co_path_get_motion(cp) == LSM_CO_PATH_MOTION_RUN && lsm_co_path_pop(cp, &b) == LSM_OK) {
        m->blocks_refused++;
        lsm_co_path_reject(cp, b.seq);
    }
    lsm_co_path_report rep = {0};
    rep.active_seq = cp->active_seq;
    rep.standstill = true;
    lsm_co_path_update(cp, &rep);
}

bool ctl_motion_background(ctl_motion *m)
{
    (void)m;
    return false;
}

const char *ctl_motion_name(void)
{
    return "hold (interim: no motion layer linked)";
}

void ctl_motion_stats(const ctl_motion *m, uint32_t *underruns, uint32_t *min_ahead)
{
    (void)m;
    *underruns = 0u;
    *min_ahead = 0xFFFFFFFFu;
}
