/*
 * contour_prog.h: the built-in contour program, run identically by the Cortex-M image (lissom-selftest.elf) and
 * by its host twin (lissom-contour-host), both on the float core (lsm_core_f). tests/py/test_arm_image.py and
 * scripts/arm_check.sh compare their reports: the MCU must compute the same setpoints as the host float build,
 * bit for bit (the float core uses only + - * /, sqrt, floor/ceil and its own sin/cos/cbrt/atan2, lsm_math.h).
 *
 * The program (lsm_contour_item_get) is a closed contour in X Y Z: lines, tangent and non-tangent arcs (G2, G3),
 * a helical arc, a dense polyline (0.25 mm segments on a sine wave, which the planner fits with arcs) and corners
 * that the planner smooths with clothoid pairs (tol_mm > 0), ending with an exact stop on (0, 0, 0). About 165 mm
 * at 80-120 mm/s with the planner's default limits and a 1 ms cycle: about 2 s of motion.
 *
 * Execution, one lsm_contour_cycle per control cycle, which is lsm_contour_background then lsm_contour_step:
 *   1. feed (background): at most one program item is appended per cycle (a streaming reader), while the planner
 *      has room; after the last one, lsm_planner_finish;
 *   2. lsm_interp_prepare (background): the next piece planned ahead of the interpolator;
 *   3. lsm_interp_step (step, the control tick): the setpoints of every axis; each one's bit pattern goes into an
 *      FNV-1a checksum.
 * The result is deterministic: it depends on nothing but the program and the core, as long as the calls keep
 * this order (the image runs 1-2 in its main loop and 3 in SysTick, in lock-step: contour_main.c).
 *
 * Memory: everything is in the caller's lsm_contour object, with a look-ahead of LSM_CONTOUR_BLOCKS blocks.
 * No I/O: lsm_contour_report formats the report lines itself and hands each one to the caller's put function.
 */
#ifndef LSM_CONTOUR_PROG_H
#define LSM_CONTOUR_PROG_H

#include "interp.h"
#include "planner.h"

#define LSM_CONTOUR_BLOCKS 128u       /* look-ahead storage (blocks) */
#define LSM_CONTOUR_CYCLE_US 1000u    /* control cycle (us) */
#define LSM_CONTOUR_MAX_CYCLES 20000u /* 20 s: a run that takes longer is stuck */
#define LSM_CONTOUR_SAMPLE_EVERY 32u  /* sampled setpoints: cycles 0, 32, 64, ... and the last one */
#define LSM_CONTOUR_MAX_SAMPLES 256u
#define LSM_CONTOUR_HASH_INIT 0x811C9DC5u

/* One program item: a line or an arc (G17 plane, helical when Z changes) from the end of the previous one. */
typedef struct lsm_contour_item {
    uint8_t arc;        /* 0: G1 line, 1: arc */
    int8_t dir;         /* arcs: +1 G3 (counter-clockwise), -1 G2 */
    lsm_real end[3];    /* X Y Z (mm) */
    lsm_real centre[3]; /* arcs: centre (X Y; Z ignored) */
    lsm_real feed_mm_s;
    lsm_real tol_mm; /* corner at the end of this item: > 0 blends (clothoids), 0 stops */
} lsm_contour_item;

/* Number of items of the program, and item k (0 <= k < n). The end of the last item is the program's end. */
uint32_t lsm_contour_n_items(void);
void lsm_contour_item_get(uint32_t k, lsm_contour_item *it);

typedef enum lsm_contour_result {
    LSM_CONTOUR_RUNNING = 0, /* one cycle done, call again */
    LSM_CONTOUR_DONE = 1,    /* the program ended (the interpolator reports DONE) */
    LSM_CONTOUR_ERROR = 2    /* an append, finish or the run failed (err, err_item), or it took too long */
} lsm_contour_result;

typedef struct lsm_contour_sample {
    uint32_t cycle;
    lsm_real p[3];
} lsm_contour_sample;

typedef struct lsm_contour {
    lsm_planner pl;
    lsm_interp ip;
    lsm_pblock blk[LSM_CONTOUR_BLOCKS];
    uint32_t next_item; /* next item to append */
    uint8_t finished;   /* lsm_planner_finish accepted */
    uint8_t result;     /* lsm_contour_result */
    uint8_t reserved[2];
    lsm_status err;             /* first error (LSM_OK if none) */
    uint32_t err_item;          /* ... at this item */
    uint32_t cycles;            /* cycles stepped */
    uint32_t appends;           /* items accepted */
    uint32_t full_retries;      /* appends that returned LSM_E_FULL (retried the next cycle) */
    uint32_t hash;              /* FNV-1a over the bit patterns of every setpoint (all LSM_MAX_AXES axes) */
    uint32_t kind_cycles[4];    /* cycles whose cursor ended on: [1] line, [2] arc, [3] clothoid ([0] none) */
    lsm_real pos[LSM_MAX_AXES]; /* last setpoint */
    lsm_real feed_max_mm_s;     /* highest path feed seen */
    lsm_contour_sample sample[LSM_CONTOUR_MAX_SAMPLES];
    uint32_t n_samples;
} lsm_contour;

/* Planner configuration of the program: lsm_planner_default_config with axis_mask (X Y Z: 0x07) and limits for
 * A B C when they exist (bench variants use 0x3F). */
void lsm_contour_config(lsm_planner_config *cfg, uint8_t axis_mask);

/* Resets to the start (0, ..., 0) with the X Y Z configuration. Errors: those of lsm_planner_init. */
lsm_status lsm_contour_init(lsm_contour *c);

/* One control cycle: lsm_contour_background, then lsm_contour_step (the host twin). */
lsm_contour_result lsm_contour_cycle(lsm_contour *c);

/* The background half of a cycle: feed one item (or finish), lsm_interp_prepare. Main loop. */
lsm_contour_result lsm_contour_background(lsm_contour *c);

/* The tick half of a cycle: one interpolator step, checksum, statistics, samples. Control tick. */
lsm_contour_result lsm_contour_step(lsm_contour *c);

/* Whether the last setpoint equals the end of the last item exactly (X Y Z; A B C stay 0). */
bool lsm_contour_end_exact(const lsm_contour *c);

/* Writes the report, one line at a time without '\n' (put is called once per line):
 *   contour result=<0|1|2> err=<status> err_item=<k> cycles=<n> appends=<n> full_retries=<n>
 *           checksum=0x........ end=0x........,0x........,0x........ end_exact=<0|1>
 *   contour_stats corners=<n> corner_stops=<n> pieces=<n> fallbacks=<n> plan_errors=<n> replans=<n>
 *           line_cycles=<n> arc_cycles=<n> clothoid_cycles=<n> feed_max_mm_s=<int>
 *   contour_sample <cycle> 0x........ 0x........ 0x........          (X Y Z bit patterns)
 */
void lsm_contour_report(const lsm_contour *c, void (*put)(const char *line, void *ctx), void *ctx);

#endif /* LSM_CONTOUR_PROG_H */
