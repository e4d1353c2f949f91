/*
 * pathrun.h: run a G-code program through the look-ahead planner and the interpolator (or through the VPOp
 * reference planner) on a machine, and measure the result (host only, sim_run_*).
 *
 * The program is parsed with the firmware's streaming parser (gcode.h) and appended block by block while the
 * interpolator runs, cycle by cycle, as the firmware would (the planner holds `capacity` blocks). Every
 * setpoint is recorded. Measured from the setpoints, as Beudaert eq 6 does (backward differences, the machine
 * at rest before the first and after the last setpoint):
 *   max_v/a/j per axis  max |dq|/dt, |d²q|/dt², |d³q|/dt³ (u/s, u/s², u/s³);
 *   max_deviation       largest distance (X Y Z) of a setpoint from the programmed path (lines and arcs, G0
 *                       included), in mm;
 *   end_error           largest |last setpoint - programmed end| over the axes (mm or rad).
 * With drives, every axis also runs the simulated servo (drive.h) with velocity and acceleration
 * feed-forward from the same differences; the actual positions are recorded.
 */
#ifndef LSM_SIM_PATHRUN_H
#define LSM_SIM_PATHRUN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "gcode.h"
#include "interp.h"
#include "machine.h"
#include "planner.h"
#include "simprog.h"

/* SIM_RUN_VPOP_CONT, the continuous-limit reference: VPOp whose every step is also checked between its samples
 * (pathrun.c, vp_cstep_segment): the motion between the samples is the cubic B-spline of the samples (the step's
 * discrete jerk held over the cycle), and each axis's velocity, acceleration and jerk on it (Beudaert eq 3, exact
 * path derivatives) must stay within the limits; the step takes the largest s that passes. */
typedef enum sim_run_planner { SIM_RUN_LISSOM = 0, SIM_RUN_VPOP = 1, SIM_RUN_VPOP_CONT = 2 } sim_run_planner;

static inline const char *sim_run_planner_name(sim_run_planner p)
{
    return p == SIM_RUN_VPOP ? "vpop" : p == SIM_RUN_VPOP_CONT ? "vpop-cont" : "lissom";
}

/* Something to do at a given cycle (tests, CLI): hold, resume, override. */
typedef struct sim_run_event {
    uint64_t cycle;
    int kind; /* 1 hold, 2 resume, 3 override (value) */
    double value;
} sim_run_event;

/* Progress of a run, for a progress bar (optional): the phase, done in [0, 1] within it (the reference planner
 * reports only its passes), and how far the run has got in machine time (s). Called every 4096 cycles of the
 * interpolator and of each drive, and between the reference planner's passes. */
typedef enum sim_run_phase { SIM_RUN_PHASE_PLAN = 0, SIM_RUN_PHASE_DRIVES = 1 } sim_run_phase;
typedef void (*sim_run_progress_fn)(void *ctx, sim_run_phase phase, double done, double machine_time_s);

typedef struct sim_run_opts {
    const sim_machine *machine;
    const char *text; /* the G-code program, text[len] ... */
    size_t len;
    const char *path; /* ... or, with text NULL, the file it is read from (in chunks) */
    sim_run_planner planner;
    uint32_t capacity;   /* planner blocks; 0: max(256, 3 lookahead_blocks + 8) */
    bool drives;         /* also simulate the drives */
    double max_time_s;   /* stop with an error if the run takes longer (0: no limit; the Lissom planner's
                                  run stops with an error when it stalls: no motion and no block taken for 10 s
                                  while no event is pending; the VPOp reference keeps a 3600 s bound) */
    uint32_t feed_every; /* > 0: append at most one block every this many cycles (underrun tests) */
    const sim_run_event *events;
    size_t n_events;
    lsm_planner_config *cfg_override; /* optional: planner configuration to use instead of the machine's */
    /* summary_only: measure the setpoints while running and keep none (constant memory): the result has the
     * summary (the same numbers as a run that keeps them) with n = 0 and q = feed = line = act = NULL; the drives
     * run with the planner (no progress reports of their own). With the Lissom planner the program is windowed
     * too (simprog.h: parsed twice, held only around the look-ahead), so memory does not grow with it */
    bool summary_only;
    sim_run_progress_fn progress; /* optional progress reports (NULL: none) */
    void *progress_ctx;
} sim_run_opts;

/* sim_run_mfunc (simprog.h): a machine function of the program (gcode.h events), where it comes among the blocks
 * and when it ran. The Lissom planner runs the program up to an event that needs an exact stop, lets the machine
 * come to rest on the end of the block before it, runs it (G4: the dwell's whole cycles at rest; M0/M1: the pause
 * is resumed at once) and goes on. */

typedef struct sim_run_result {
    size_t n; /* setpoints kept (one per cycle; 0 with summary_only) */
    double cycle_s;
    int n_axes;                           /* machine axes */
    int axis_index[SIM_MACHINE_MAX_AXES]; /* their G-code index (X = 0 .. C = 5) */
    char axis_name[SIM_MACHINE_MAX_AXES];
    double *q;         /* n x LSM_MAX_AXES setpoints */
    double *feed;      /* n: path feed (mm/s) */
    uint32_t *line;    /* n: source line of the block being run */
    double *act;       /* n x LSM_MAX_AXES actual positions (drives) or NULL */
    bool has_act;      /* the drives ran (max_follow_err is measured), also with summary_only */
    double duration_s; /* time of the last setpoint that moved (the motion's end) */
    uint64_t cycles;   /* cycles up to then */
    double max_v[LSM_MAX_AXES], max_a[LSM_MAX_AXES], max_j[LSM_MAX_AXES];
    double max_dev_mm;
    double end_error;
    double max_follow_err[LSM_MAX_AXES];
    double prog_end[LSM_MAX_AXES];
    double start[LSM_MAX_AXES];  /* where the machine rests before the first setpoint */
    size_t prog_blocks;          /* motion blocks in the program */
    double prog_length_mm;       /* length of the programmed path (X Y Z) */
    double plan_ns_per_block;    /* host time spent in append (corner smoothing + backward pass) per block */
    double interp_ns_per_cycle;  /* host time per interpolator cycle (lsm_interp_step; tick_plans included) */
    double prepare_ns_per_piece; /* host time of lsm_interp_prepare (background piece planning) per prepared piece */
    double piece_ns;             /* host time per planned piece */
    lsm_planner_stats stats;
    uint32_t replans, plan_errors;
    uint32_t prepared;           /* pieces planned in the background (lsm_interp_prepare) */
    uint32_t tick_plans;         /* pieces planned inside the control cycle (none prepared in time) */
    uint32_t pl_block_bytes;     /* sizeof(lsm_pblock) of this build */
    double intersample_jerk_max; /* --planner vpop: continuous axis jerk its motion asks between samples, largest */
    double intersample_jerk_p99; /* and 99th percentile over the samples, relative to J (pathrun.c); -1: n/a */
    double cont_ratio[3];        /* VPOp planners: largest axis velocity, acceleration, jerk over the limits on the
                                    continuous motion between the samples (their cubic B-spline resampled 32 times a
                                    cycle: pathrun.c, vp_cont_verify); -1: n/a */
    sim_run_mfunc *mfuncs;       /* the program's machine functions, in order */
    size_t n_mfuncs;
    size_t prog_held_max;  /* most program blocks + path elements held at once (simprog.h; windowed with
                              summary_only and the Lissom planner: bounded by the look-ahead, not the program) */
    size_t n_gcode_errors; /* refused lines (the first is in err; `lissom-sim check` lists them all) */
    char err[320];
} sim_run_result;

/* Runs the program. Returns 0 on success; on error r->err says why (G-code line/column, planner status ...). */
int sim_run_program(const sim_run_opts *o, sim_run_result *r);
void sim_run_free(sim_run_result *r);

/* Planner configuration from a machine file. */
void sim_run_planner_config(const sim_machine *m, lsm_planner_config *cfg);

/* Reads a whole file (malloc'd, NUL-terminated). NULL on error. */
char *sim_read_file(const char *path, size_t *len);

#endif /* LSM_SIM_PATHRUN_H */
