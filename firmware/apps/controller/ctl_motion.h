/*
 * ctl_motion.h: the seam between the controller application (ctl_app.h) and a CiA 402 motion layer. The
 * application owns the CANopen node and calls the motion layer at three points; everything else (profiles,
 * stops, the path feed into the planner) is the motion layer's business:
 *
 *   ctl_motion_init        main loop, before the tick starts: binds the layer to the node's axes.
 *   ctl_motion_tick        control tick, after lsm_canopen_process, once per cycle: every axis's demand for this
 *                          cycle (stop requests, PP, CSP, the path executor's per-cycle step), then the feedback
 *                          of the cycle (lsm_cia402_update, lsm_co_path_update). Bounded work only.
 *   ctl_motion_background  main loop, as often as it likes: the work that may take longer than a tick (planner
 *                          appends, lsm_interp_prepare). Returns true when it did something (the main loop then
 *                          does not sleep). It must not touch the node: the tick owns it (canopen.h: one context
 *                          per node); what it needs from the node goes through the layer's own hand-off.
 *
 * Position feedback. The board has no encoder: every implementation reports an ideal loopback, the actual
 * position equals the demand of the same cycle (0x6064 = 0x6062, following error 0), and the velocity is the
 * demand's. The motion layer's limits are therefore checked on the demand, not on a drive.
 *
 * Implementations (one is linked into the image; firmware/apps/controller/CMakeLists.txt chooses):
 *   ctl_motion_cia402.c the CiA 402 layer of firmware/motion (lsm_motion_*), when that component exists;
 *   ctl_motion_hold.c   INTERIM, until it does: every axis holds its position; a PP or CSP set-point and a path
 *                       block are refused (application fault 0x6100, EMCY; path block rejected with EMCY 0xFF01) so
 *                       that a master sees at once that this image cannot move. Stop requests complete at once
 *                       (the axis is at rest).
 * Each implementation defines struct ctl_motion in its own header (ctl_motion_impl.h picks it; the image
 * allocates it statically).
 */
#ifndef CTL_MOTION_H
#define CTL_MOTION_H

#include "canopen.h"

typedef struct ctl_motion ctl_motion;

typedef struct ctl_motion_config {
    uint8_t n_axes;   /* as the node's, 1..LSM_MAX_AXES */
    lsm_real cycle_s; /* control cycle, > 0 */
} ctl_motion_config;

/* Errors: LSM_E_NULL, LSM_E_ARG (axes, cycle), the layer's own. Main loop, before the tick. */
lsm_status ctl_motion_init(ctl_motion *m, const ctl_motion_config *cfg, lsm_canopen *co);

/* One control cycle (see above). now_us: the cycle's time. Control tick. */
void ctl_motion_tick(ctl_motion *m, lsm_canopen *co, uint32_t now_us);

/* Background work; true when something was done. Main loop. */
bool ctl_motion_background(ctl_motion *m);

/* The layer's real-time figures for 0x5F00 sub 7 and 8: path underruns (set-points not made in time) and the
 * fewest set-points ready ahead of a tick while the path moved (0xFFFFFFFF: never moved, or no path). Tick. */
void ctl_motion_stats(const ctl_motion *m, uint32_t *underruns, uint32_t *min_ahead);

/* The name of the implementation, for the boot banner ("hold", "cia402"). Any context. */
const char *ctl_motion_name(void);

#endif /* CTL_MOTION_H */
