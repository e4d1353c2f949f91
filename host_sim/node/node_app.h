/*
 * node_app.h: the application inside lissom-node (node_app_*): the firmware's CANopen node (canopen.h) with its
 * CiA 402 axes and path buffer, the firmware's CiA 402 motion layer (firmware/motion/motion.h: PP, CSP,
 * jerk-limited stops, the path feed into the look-ahead planner or the exact-stop executor), and one simulated
 * drive per axis (host_sim/drive.h). Pure computation, like the firmware: frames in, frames out, time as an
 * argument, no I/O. node_main.c connects it to the Linux port; tests can drive it directly.
 *
 * One control cycle (node_app_cycle), in this order:
 *   1. E-stop level -> lsm_canopen_estop; pending port bus events -> lsm_canopen_bus_event (done by the caller
 *      through node_app_bus_event before the cycle); received frames were served by node_app_rx;
 *   2. lsm_canopen_sdo_sync (the background SDO server's step and the tick's side of its hand-off: canopen.h; also
 *      after each SDO request in node_app_rx, so responses keep their place), lsm_canopen_process (timers,
 *      heartbeats, EMCY, path/axis coupling);
 *   3. lsm_motion_cycle: the demand of every axis (motion.h);
 *   4. each drive gets its demand (and the demand velocity as feed-forward); its feedback goes back through
 *      lsm_motion_feedback (0x6062, 0x6064, 0x606C, standstill, PP set-point done);
 *   5. outputs: drive enable = some axis powered; in position = every axis in position.
 * Position feedback: the simulated drive's load position and velocity (a drive whose step fails keeps its
 * previous feedback).
 */
#ifndef NODE_APP_H
#define NODE_APP_H

#include "canopen.h"
#include "drive.h"
#include "machine.h"
#include "motion.h"

#ifndef NODE_APP_TXQ
#define NODE_APP_TXQ 128
#endif
#define NODE_APP_PATH_SLOTS_MAX 1024
#define NODE_APP_PATH_PLANNER LSM_MOTION_PATH_PLANNER
#define NODE_APP_PATH_EXACT LSM_MOTION_PATH_EXACT
#define NODE_APP_LOOKAHEAD_MAX 256 /* largest planner block storage (look-ahead depth, corner transitions included) */

typedef struct node_app_config {
    uint8_t node_id;       /* 1..127 */
    uint8_t n_axes;        /* 1..machine axes */
    uint32_t cycle_us;     /* control cycle */
    uint16_t heartbeat_ms; /* 0x1017 default */
    uint8_t master_id;     /* 0x1016 sub 1 default: monitored node, 0 = none */
    uint16_t master_timeout_ms;
    uint16_t path_slots;       /* path buffer capacity, 1..NODE_APP_PATH_SLOTS_MAX */
    uint16_t lookahead_blocks; /* planner storage (0: the machine's lookahead_blocks) */
    uint8_t path_exec;         /* NODE_APP_PATH_PLANNER (look-ahead, pathfeed.h) or NODE_APP_PATH_EXACT (pathexact.h) */
    const sim_machine *machine; /* limits and drives; copied */
} node_app_config;

typedef struct node_app {
    lsm_canopen co;
    lsm_can_frame txbuf[NODE_APP_TXQ];
    lsm_co_path_block blocks[NODE_APP_PATH_SLOTS_MAX];
    node_app_config cfg;
    sim_machine machine;
    double cycle_s;
    lsm_motion mo;                                          /* the CiA 402 motion layer */
    lsm_pblock la_blocks[NODE_APP_LOOKAHEAD_MAX];           /* its planner storage */
    lsm_co_path_block la_saved[NODE_APP_LOOKAHEAD_MAX + 1]; /* its block copies (pathfeed.h) */
    sim_drive drv[LSM_MAX_AXES];
    double actual[LSM_MAX_AXES], actual_vel[LSM_MAX_AXES]; /* drive feedback (mm, mm/s) */
    uint64_t cycles;
    bool estop;
    bool out_enable, out_inpos;
    uint32_t rx_errors; /* frames lsm_canopen_rx refused (malformed, wrong NMT state) */
} node_app;

/* The built-in machine (used without --machine): n linear axes named X Y Z U V W, limits 250 mm/s,
 * 3000 mm/s², 60000 mm/s³, 1.18e7 mm/s⁴, 1000 counts/mm, drives from sim_drive_params_default with full
 * velocity feed-forward, cycle 1 ms. */
void node_app_default_machine(sim_machine *m, int n_axes);

/* Errors: LSM_E_NULL, LSM_E_ARG (axes, cycle, path slots, path executor), LSM_E_CO_NODE_ID, a drive validation
 * error, those of lsm_motion_init. */
lsm_status node_app_init(node_app *app, const node_app_config *cfg, uint32_t now_us);

lsm_status node_app_rx(node_app *app, const lsm_can_frame *f, uint32_t now_us);
void node_app_bus_event(node_app *app, lsm_can_bus_event ev, uint32_t now_us);
void node_app_cycle(node_app *app, bool estop_active, uint32_t now_us);
bool node_app_tx_pop(node_app *app, lsm_can_frame *f);

/* Quick-stops every axis and holds the path (as for an NMT reset node); for a clean shutdown. */
void node_app_stop_all(node_app *app);
/* True when no axis and no path moves. */
bool node_app_at_rest(const node_app *app);

#endif /* NODE_APP_H */
