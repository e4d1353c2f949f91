/*
 * ctl_motion_impl.h: the header of the motion implementation linked into lsm_ctl_app (its CMakeLists.txt defines
 * CTL_MOTION_CIA402 when firmware/motion is there), for the code that allocates struct ctl_motion.
 */
#ifndef CTL_MOTION_IMPL_H
#define CTL_MOTION_IMPL_H

#if defined(CTL_MOTION_CIA402)
#include "ctl_motion_cia402.h"
#else
#include "ctl_motion_hold.h"
#endif

#endif /* CTL_MOTION_IMPL_H */
