/*
 * ctl_motion_cia402.c: ctl_motion.h on the CiA 402 layer of firmware/motion (ctl_motion_cia402.h).
 *
 * Contexts as the layer offers them today: lsm_motion_cycle runs the path feed's background half (block appends,
 * lsm_interp_prepare) inside the control cycle as a synchronous loop (motion.h), so ctl_motion_background has
 * nothing to do and a tick that appends a block or plans a piece carries that work (0x5F00 sub 3 shows it).
 * When the layer offers the split (the appends and lsm_interp_prepare in the background with a hand-off), the
 * background half goes into ctl_motion_background.
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
    return lsm_motion_init(&m->m, &mc, co);
}

void ctl_motion_tick(ctl_motion *m, lsm_canopen *co, uint32_t now_us)
{
    lsm_motion_cycle(&m->m, co);
    lsm_motion_feedback(&m->m, co, NULL, NULL, now_us);
}

bool ctl_motion_background(ctl_motion *m)
{
    (void)m;
    return false;
}

const char *ctl_motion_name(void)
{
    return "cia402 (firmware/motion, path feed synchronous in the tick)";
}
