/*
 * ctl_motion_hold.h: the INTERIM motion implementation of the controller image (ctl_motion.h): every axis holds
 * its position, set-points and path blocks are refused. Replaced by the CiA 402 layer of firmware/motion.
 */
#ifndef CTL_MOTION_HOLD_H
#define CTL_MOTION_HOLD_H

#include "ctl_motion.h"

struct ctl_motion {
    uint8_t n_axes;
    int32_t demand[LSM_MAX_AXES];   /* counts, held */
    uint32_t refused[LSM_MAX_AXES]; /* set-points refused per axis */
    uint32_t blocks_refused;
};

#endif /* CTL_MOTION_HOLD_H */
