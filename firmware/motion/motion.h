/*
 * motion.h: the CiA 402 motion layer (lsm_motion_*): what each axis of the CANopen node (canopen.h, cia402.h,
 * co_path.h) asks for becomes a demand position per control cycle, on caller-owned memory, with no allocation
 * and time as an argument. The port owns the drives: it sends each demand to its drive and reports the
 * feedback back. One control cycle of a node:
 *
 *   lsm_canopen_estop / lsm_canopen_process (port)  ->  lsm_motion_cycle  ->  drives (port)
 *       ->  lsm_motion_feedback  ->  lsm_canopen_drive_enable / lsm_canopen_in_position (port outputs)
 *
 * lsm_motion_cycle, per axis (CiA 402 mode display 0x6061):
 *   a stop request (halt, quick stop, disable, fault reaction; lsm_cia402_stop_request) -> a jerk-limited stop
 *     from the present state (jstop.h, Kombarov eq 6 shape) with: halt / slow 0x6084, quick 0x6085 (jerk
 *     0x2060, snap 0x2061; profile type 0 replaces the snap as axprof.h says), emergency (E-stop, following
 *     error, application fault) the machine's own limits (the fastest jerk-limited stop the machine can do);
 *     every requested value is clamped to the machine's limits. A CSP axis stops from its interpolation
 *     velocity and the acceleration of its last period (clamped to the stop's deceleration);
 *   PP (0x6060 = 1): a new set-point -> lsm_axprof_move (0x6086 1 sin², 0 linear ramp: see axprof.h), with
 *     v = min(0x6081, v_max), a = min(0x6083, 0x6084, a_max), j = min(0x2060, j_max), snap = min(0x2061,
 *     snap_max); single set-point (bit 5 = 1: REPLACE, retarget from the present state) and set of set-points
 *     (bit 5 = 0: the next one starts in the cycle after lsm_cia402_pp_done at the end of the active one);
 *   CSP (0x6060 = 8): each new 0x607A is passed through: the demand goes linearly from the present demand to
 *     it over the interpolation period 0x60C2 (rounded to whole cycles, at least 1); without a new target the
 *     demand holds;
 *   path (-1): the path executor moves every axis: the look-ahead feed (pathfeed.h, default) or the exact-stop
 *     executor (pathexact.h); its report goes to lsm_co_path_update.
 * A move the engine refuses (e.g. a distance too large to represent) is an application fault on that axis:
 * 0x603F = 0x6100, EMCY 0x6100, fault reaction.
 * lsm_motion_feedback, per axis: demand, actual and velocity in counts (0x6062, 0x6064, 0x606C; counts per mm
 * 0x2001, rounded to nearest) and the standstill go to lsm_cia402_update; a PP set-point whose move ended is
 * reported done (lsm_cia402_pp_done).
 * Heartbeat loss, bus-off, NMT state changes reach the axes through canopen.c (0x6007, default quick stop), so
 * they end in the same jerk-limited stops.
 *
 * Contexts. Two: the control cycle (tick: an interrupt on the board) and the background (the main loop).
 *   tick        lsm_motion_tick (= _tick_begin + _tick_end), lsm_motion_feedback, lsm_motion_stop_all: the node's
 *               axis objects and path buffer are the tick's (canopen.h: the dictionary is the tick's; the SDO
 *               protocol may run in the background). Stops, PP, CSP are evaluated here; every stop begins in the
 *               cycle it is seen in (lsm_axprof_stop; a stop plan is a bisection, bounded). With lead_cycles > 0 a PP
 *               set-point's move plan (lsm_axprof_move, 40-250 k instructions on the M4) is the background's: the
 *               move starts 8 cycles after the set-point is taken (MO_PP_PLAN_CYCLES); with lead 0 the tick plans
 *               it at once. For the path the tick only takes the set-point the background made and reports it.
 *   background  lsm_motion_background: PP move plans, then the path feed's planner (pathfeed.h: block appends,
 *               lsm_interp_prepare) and its interpolator, run lead_cycles ahead of the tick; nothing of the node.
 *   Hand-off: mpipe.h (single-writer rings with release / acquire indices, lock-step, the tick never waits).
 *   Every field of lsm_motion is written by one context: tk and ax[] and path_* by the tick, bg and feed by the
 *   background, pipe per mpipe.h. lsm_motion_cycle runs both halves in one context (synchronous loop).
 *   lsm_motion_init: before either runs. Accessors: the tick.
 *   The exact-stop executor (path_exec = EXACT) runs wholly in the tick (its moves are per-axis plans).
 *
 * Units: mm (or rad), s in the layer; counts, counts/s .. on the bus (cia402.h).
 */
#ifndef LSM_MOTION_H
#define LSM_MOTION_H

#include "axprof.h"
#include "canopen.h"
#include "mpipe.h"
#include "pathexact.h"
#include "pathfeed.h"

typedef enum lsm_motion_path_exec {
    LSM_MOTION_PATH_PLANNER = 0, /* look-ahead feed (pathfeed.h) */
    LSM_MOTION_PATH_EXACT = 1    /* exact stop at every block end (pathexact.h) */
} lsm_motion_path_exec;

typedef struct lsm_motion_config {
    uint8_t n_axes;                    /* 1..LSM_MAX_AXES, as the node's */
    lsm_real cycle_s;                  /* control cycle, > 0 */
    lsm_axis_limits lim[LSM_MAX_AXES]; /* the machine's limits per axis, all > 0 */
    uint8_t path_exec;                 /* lsm_motion_path_exec */
    lsm_pathfeed_storage feed;         /* planner storage of the look-ahead feed (pathfeed.h) */
    uint32_t lead_cycles;              /* path set-points computed this many cycles ahead by the background
                                          (0: the synchronous loop, lsm_motion_cycle; >= 1 with lsm_motion_tick and
                                          a preempted background), <= LSM_MPIPE_LEAD_MAX */
} lsm_motion_config;

/* The tick's side of the path hand-off (mpipe.h); written by the control cycle only. */
typedef struct lsm_motion_tk {
    uint32_t posted;       /* records posted (the tick's count) */
    uint32_t consumed;     /* set-points consumed */
    uint32_t blocks_in;    /* blocks handed over */
    uint32_t rejects_seen; /* refusals passed on to co_path */
    uint32_t abort;        /* path aborts by the tick (underruns while moving) */
    uint32_t sync_gen;     /* axes that entered path mode (their demand goes to the feed) */
    uint32_t cycle;        /* ticks run */
    bool aborting;         /* the path axes run the tick's abort stop, until the background restarted */
    bool have_last;
    lsm_mpipe_out last;                    /* the last set-point consumed */
    lsm_real prev_vel_mm_s[LSM_MAX_AXES];  /* velocity of the set-point before it (a, j estimates) ... */
    lsm_real prev2_vel_mm_s[LSM_MAX_AXES]; /* ... and of the one before that */
    uint32_t underruns;                    /* a set-point was due and none was there while the path moved: abort stop */
    uint32_t stalls;                       /* ... while the path was at rest: the demand held (no abort) */
    uint32_t in_full;                      /* records not posted: the background is LSM_MPIPE_CAP cycles behind */
    uint32_t min_ahead; /* fewest set-points ready when one was due while the path moved, + 1 (0: never) */
} lsm_motion_tk;

/* The background's side of the path hand-off; written by the background only. */
typedef struct lsm_motion_bg {
    uint32_t blocks_used; /* blocks consumed */
    uint32_t rejects, reject_seq;
    uint32_t abort_seen; /* the tick's abort the planner was restarted for */
    uint32_t sync_seen;  /* the tick's sync_gen the feed was synced to */
    uint16_t drop_epoch; /* blocks of this epoch are dropped (after a refusal, until the epoch changes) */
    bool drop_valid;
    const lsm_mpipe_in *rec; /* the record being turned into a set-point */
    uint32_t cycles;         /* set-points produced */
} lsm_motion_bg;

typedef struct lsm_motion_axis {
    lsm_axprof prof; /* demand of the axis (mm), also in CSP / path (kept in step) */
    int8_t mode;     /* mode display handled last cycle */
    bool pp_running; /* a PP set-point is executing: lsm_cia402_pp_done at its end */
    bool csp_active; /* CSP interpolation in progress */
    lsm_real csp_from_mm, csp_to_mm, csp_v_mm_s, csp_v_prev_mm_s;
    uint32_t csp_i, csp_n;               /* cycle within the period, cycles of the period */
    lsm_real actual_mm, actual_vel_mm_s; /* drive feedback of the last cycle */
    uint32_t plan_errors;
    /* PP move plans in the background (lead_cycles > 0; tick-owned): */
    bool pp_wait;            /* a plan is requested: the running state goes on until it is taken */
    bool pp_unsent;          /* ... the request ring was full: post it next cycle */
    bool pp_from_rest;       /* ... from rest (it stays valid while the axis rests) */
    bool pp_have;            /* ... its result arrived (pp_res) */
    uint32_t pp_gen, pp_due; /* its generation, the cycle it starts at */
    lsm_real pp_target_mm;
    lsm_axprof_limits pp_lim;
    lsm_axprof pp_res; /* the planned generator, until pp_due */
    lsm_status pp_st;  /* lsm_axprof_move's status for it */
    uint32_t pp_late;  /* plans that came too late for their cycle while moving: requested again */
} lsm_motion_axis;

typedef struct lsm_motion {
    uint8_t n_axes;
    uint8_t path_exec;
    lsm_real cycle_s;
    lsm_axis_limits lim[LSM_MAX_AXES];
    lsm_motion_axis ax[LSM_MAX_AXES];
    lsm_pathexact path;                                              /* exact-stop executor (path_exec = EXACT) */
    lsm_pathfeed feed;                                               /* look-ahead feed (path_exec = PLANNER) */
    lsm_real path_pos_mm[LSM_MAX_AXES], path_vel_mm_s[LSM_MAX_AXES]; /* the executor's output this cycle */
    bool path_moving;
    uint32_t lead_cycles;
    lsm_motion_tk tk; /* tick-owned */
    lsm_motion_bg bg; /* background-owned */
    lsm_mpipe pipe;   /* the rings between them (mpipe.h) */
} lsm_motion;

/* Binds the layer to the node (its axes' present modes) with every axis at rest at 0 mm. Errors: LSM_E_NULL,
 * LSM_E_ARG (axes, not the node's axis count, cycle, path executor), LSM_E_LIMIT (a limit not finite > 0),
 * those of lsm_pathfeed_init. Before the cycle runs. */
lsm_status lsm_motion_init(lsm_motion *m, const lsm_motion_config *cfg, lsm_canopen *co);

/* The synchronous loop: lsm_motion_tick_begin, lsm_motion_background, lsm_motion_tick_end in one call, in that
 * order (lissom-node on Linux, the tests). After lsm_canopen_process. Control cycle (which then also owns the
 * background's side). */
void lsm_motion_cycle(lsm_motion *m, lsm_canopen *co);

/* The tick's half of one control cycle: lsm_motion_tick_begin then lsm_motion_tick_end. After
 * lsm_canopen_process. Control cycle (interrupt). Never waits and never plans a path piece or appends a block. */
void lsm_motion_tick(lsm_motion *m, lsm_canopen *co);

/* First part of the tick: every non-path axis's demand (stops, PP, CSP), the record of this cycle and the blocks
 * handed over to the background (mpipe.h). Control cycle. */
void lsm_motion_tick_begin(lsm_motion *m, lsm_canopen *co);

/* Second part of the tick: the path set-point due this cycle (the one the background made lead_cycles records
 * ago), the path report, refusals passed on to co_path. No set-point when one is due: at rest the demand holds
 * (tk.stalls); moving, the path axes stop at once with a jerk-limited stop at the machine's limits from their last
 * state (tk.underruns; the path is dropped like a refused block: EMCY 0xFF01, the co_path buffer flushed) and the
 * background restarts the planner where they came to rest. Control cycle. */
void lsm_motion_tick_end(lsm_motion *m, lsm_canopen *co);

/* The background's half: turns the oldest record into the next path set-point (the co_path commands, block
 * appends, lsm_interp_prepare, the interpolator step). At most one set-point per call; returns false when there
 * was nothing to do (no record, or the set-point ring full). Background (main loop), never the tick. */
bool lsm_motion_background(lsm_motion *m);

/* The drives' feedback of this cycle: actual_mm[n_axes], actual_vel_mm_s[n_axes] (NULL: the demand, an ideal
 * loopback). now_us: the cycle's time. Control cycle, after lsm_motion_cycle. */
void lsm_motion_feedback(lsm_motion *m, lsm_canopen *co, const lsm_real *actual_mm, const lsm_real *actual_vel_mm_s,
                         uint32_t now_us);

/* Quick-stops every enabled axis (as for a lost connection with 0x6007 = 3) and holds the path with a quick
 * stop: for a clean shutdown. Control cycle. */
void lsm_motion_stop_all(lsm_motion *m, lsm_canopen *co);

/* True when no axis and no path moves. */
bool lsm_motion_at_rest(const lsm_motion *m);

/* Demand position, velocity, acceleration and jerk of axis k this cycle (mm, mm/s, ...). */
static inline const lsm_kin *lsm_motion_demand(const lsm_motion *m, unsigned k)
{
    return &m->ax[k].prof.k;
}

#endif /* LSM_MOTION_H */
