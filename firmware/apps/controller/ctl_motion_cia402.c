/*
 * ctl_motion_cia402.c: ctl_motion.h on the CiA 402 layer of firmware/motion (ctl_motion_cia402.h).
 *
 * Contexts (motion.h): the tick runs lsm_motion_tick (stops, PP, CSP, the path set-point due) and the feedback;
 * the main loop runs lsm_motion_background (the path feed: appends, lsm_interp_prepare, the interpolator) up to
 * CTL_MOTION_LEAD_CYCLES cycles ahead of the tick, handed over through the layer's rings (mpipe.h).
 */
#include "ctl_motion_cia402.h"

#include <string.h>

lsm_status ctl_motion_init(ctl_motion *m, const ctl_motion_config *cfg, lsm_canopen *co)
{
    if (m == NULL || cfg == NULL || co == NULL)
        return LSM_E_NULL;
    if (cfg->n_axes < 1u || cfg->n_axes > LSM_MAX_AXES || !(cfg->cycle_s > 0))
        return LSM_E_ARG;
    memset(m, 0, sizeof *m);
    lsm_motion_config mc;
    memset(&mc, 0, sizeof mc);
    mc.n_axes = cfg->n_axes;
    mc.cycle_s = cfg->cycle_s;
    for (unsigned k = 0; k < cfg->n_axes; k++) {
        mc.lim[k].v_max_mm_s = (lsm_real)250;
        mc.lim[k].a_max_mm_s2 = (lsm_real)3000;
        mc.lim[k].j_max_mm_s3 = (lsm_real)60000;
        mc.lim[k].snap_max_mm_s4 = (lsm_real)1.18e7;
    }
    mc.path_exec = LSM_MOTION_PATH_PLANNER;
    mc.feed.blocks = m->blocks;
    mc.feed.capacity = CTL_LOOKAHEAD_BLOCKS;
    mc.feed.saved = m->saved;
    mc.feed.saved_cap = CTL_LOOKAHEAD_BLOCKS + 1u;
    mc.lead_cycles = CTL_MOTION_LEAD_CYCLES;
    return lsm_motion_init(&m->m, &mc, co);
}

void ctl_motion_tick(ctl_motion *m, lsm_canopen *co, uint32_t now_us)
{
    lsm_motion_tick(&m->m, co);
    lsm_motion_feedback(&m->m, co, NULL, NULL, now_us);
}

bool ctl_motion_background(ctl_motion *m)
{
    return lsm_motion_background(&m->m);
}

void ctl_motion_stats(const ctl_motion *m, uint32_t *underruns, uint32_t *min_ahead)
{
    *underruns = m->m.tk.underruns;
    *min_ahead = m->m.tk.min_ahead == 0u ? 0xFFFFFFFFu : m->m.tk.min_ahead - 1u;
}

const char *ctl_motion_name(void)
{
    return "cia402 (firmware/motion: tick / background split)";
}
