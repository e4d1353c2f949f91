/*
 * ctl_motion_cia402.h: the controller image's motion layer (ctl_motion.h) on the firmware's CiA 402 layer
 * (firmware/motion, lsm_motion_*): PP (profile types 0/1, single and set of set-points), CSP, the jerk-limited
 * halt / quick / fault-reaction / E-stop stops, and the path blocks of 0x5010 through the look-ahead planner
 * (path_exec PLANNER). Feedback: ideal loopback (lsm_motion_feedback with NULL: actual = demand).
 * Machine: CTL_MOTION_AXIS_LIMITS on every axis (lissom-node's built-in machine, hil/lissom_hil/rig.py
 * BUILTIN_LIMITS): 250 mm/s, 3000 mm/s², 60000 mm/s³, 1.18e7 mm/s⁴; CTL_LOOKAHEAD_BLOCKS planner blocks.
 */
#ifndef CTL_MOTION_CIA402_H
#define CTL_MOTION_CIA402_H

#include "ctl_motion.h"
#include "motion.h"

#ifndef CTL_LOOKAHEAD_BLOCKS
#define CTL_LOOKAHEAD_BLOCKS 64u /* as lissom-node's default (--lookahead): 5.9 KB of planner blocks */
#endif

#ifndef CTL_MOTION_LEAD_CYCLES
/* Path set-points the background computes ahead of the tick (motion.h lead_cycles): room for its longest stretch
 * without one (a piece plan, up to 1.26 M instructions = 7.5 ticks of 168 k, plus a few block appends) with margin;
 * the price is the latency of a path command (hold, override) by as many cycles: 24 ms. */
#define CTL_MOTION_LEAD_CYCLES 24u
#endif

struct ctl_motion {
    lsm_motion m;
    lsm_pblock blocks[CTL_LOOKAHEAD_BLOCKS];
    lsm_co_path_block saved[CTL_LOOKAHEAD_BLOCKS + 1u]; /* pathfeed.h: saved_cap > capacity */
};

#endif /* CTL_MOTION_CIA402_H */
