/*
 * node_app.h: the application inside lissom-node (node_app_*): the firmware's CANopen node (canopen.h) with its
 * CiA 402 axes and path buffer, the motion that the node asks for (node_prof.h, node_path.h), and one simulated
 * drive per axis (host_sim/drive.h). Pure computation, like the firmware: frames in, frames out, time as an
 * argument, no I/O. node_main.c connects it to the Linux port; tests can drive it directly.
 *
 * One control cycle (node_app_cycle), in this order:
 *   1. E-stop level -> lsm_canopen_estop; pending port bus events -> lsm_canopen_bus_event (done by the caller
 *      through node_app_bus_event before the cycle); received frames were served by node_app_rx;
 *   2. lsm_canopen_process (timers, heartbeats, EMCY, path/axis coupling);
 *   3. per axis (CiA 402 mode display 0x6061):
 *        a stop request (halt, quick stop, disable, fault reaction) -> a jerk-limited stop from the present state
 *          (node_stop.h) with: halt/slow 0x6084, quick 0x6085 (jerk 0x2060, snap 0x2061), emergency (E-stop,
 *          following error, application fault) the machine's own limits (the fastest the machine can do);
 *          every requested value is clamped to the machine's limits;
 *        PP: a new set-point -> node_prof_move (0x6086 1 sin², 0 linear ramp: see node_prof.h); at the end
 *          lsm_cia402_pp_done (set of set-points: the next one starts in the following cycle);
 *        CSP: each new 0x607A is passed through: the demand goes linearly from the present demand to it over
 *          the interpolation period 0x60C2 (rounded to whole cycles, at least 1);
 *        path (-1): the path executor moves every axis: the look-ahead planner (node_la.h, default) or the
 *          exact-stop executor (node_path.h);
 *   4. each drive gets its demand (and the demand velocity as feed-forward); the feedback (0x6062, 0x6064,
 *      0x606C in counts with 0x2001) and the standstill go back through lsm_cia402_update / lsm_co_path_update;
 *   5. outputs: drive enable = some axis powered; in position = every axis in position.
 * Heartbeat loss, bus-off, NMT state changes reach the axes through canopen.c (0x6007, default quick stop), so
 * they end in the same jerk-limited stops. A plan that the move engine refuses (e.g. a distance too large to
 * represent) is an application fault on that axis: 0x603F = 0x6100, EMCY 0x6100, fault reaction.
 */
#ifndef NODE_APP_H
#define NODE_APP_H

#include "canopen.h"
#include "drive.h"
#include "machine.h"
#include "node_la.h"
#include "node_path.h"
#include "node_prof.h"

#ifndef NODE_APP_TXQ
#define NODE_APP_TXQ 128
#endif
#define NODE_APP_PATH_SLOTS_MAX 1024
#define NODE_APP_PATH_PLANNER 0
#define NODE_APP_PATH_EXACT 1

typedef struct node_app_config {
    uint8_t node_id;             /* 1..127 */
    uint8_t n_axes;              /* 1..machine axes */
    uint32_t cycle_us;           /* control cycle */
    uint16_t heartbeat_ms;       /* 0x1017 default */
    uint8_t master_id;           /* 0x1016 sub 1 default: monitored node, 0 = none */
    uint16_t master_timeout_ms;
    uint16_t path_slots;         /* path buffer capacity, 1..NODE_APP_PATH_SLOTS_MAX */
    uint16_t lookahead_blocks;   /* planner storage (0: the machine's lookahead_blocks) */
    uint8_t path_exec;           /* NODE_APP_PATH_PLANNER (look-ahead, node_la.h) or NODE_APP_PATH_EXACT (node_path.h) */
    const sim_machine *machine;  /* limits and drives; copied */
} node_app_config;

typedef struct node_axis {
    node_prof prof;             /* demand of the axis (mm), also in CSP / path (kept in step) */
    int8_t mode;                /* mode display handled last cycle */
    bool pp_running;            /* a PP set-point is executing: lsm_cia402_pp_done at its end */
    bool csp_active;            /* CSP interpolation in progress */
    double csp_from, csp_to, csp_v, csp_v_prev;
    uint32_t csp_i, csp_n;
    double actual, actual_vel;  /* drive feedback (mm, mm/s) */
    uint32_t plan_errors;
} node_axis;

typedef struct node_app {
    lsm_canopen co;
    lsm_can_frame txbuf[NODE_APP_TXQ];
    lsm_co_path_block blocks[NODE_APP_PATH_SLOTS_MAX];
    node_app_config cfg;
    sim_machine machine;
    double cycle_s;
    node_axis_limits lim[LSM_MAX_AXES];
    node_axis ax[LSM_MAX_AXES];
    node_path path;             /* exact-stop executor (path_exec = EXACT) */
    node_la la;                 /* look-ahead executor (path_exec = PLANNER) */
    double path_pos[LSM_MAX_AXES], path_vel[LSM_MAX_AXES]; /* the executor's output this cycle */
    bool path_moving;
    sim_drive drv[LSM_MAX_AXES];
    uint64_t cycles;
    bool estop;
    bool out_enable, out_inpos;
    uint32_t rx_errors;         /* frames lsm_canopen_rx refused (malformed, wrong NMT state) */
} node_app;

/* The built-in machine (used without --machine): n linear axes named X Y Z U V W, limits 250 mm/s,
 * 3000 mm/s², 60000 mm/s³, 1.18e7 mm/s⁴, 1000 counts/mm, drives from sim_drive_params_default with full
 * velocity feed-forward, cycle 1 ms. */
void node_app_default_machine(sim_machine *m, int n_axes);

/* Errors: LSM_E_NULL, LSM_E_ARG (axes, cycle, path slots), LSM_E_CO_NODE_ID, a drive validation error. */
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
