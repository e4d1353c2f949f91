/*
 * selftest_prog.h: the built-in self-test motion program, run identically by the Cortex-M image
 * (lissom-selftest.elf) and by its host twin (lissom-selftest-host). Both use the float core (lsm_core_f);
 * tests/py/test_arm_image.py compares their outputs, i.e. checks that the MCU computes what the host float
 * build computes.
 *
 * Structure, as on a real controller: planning runs in the background (main loop), evaluation runs in the
 * control tick, one cycle per tick. Two plan slots hand over from planner to tick (double buffering): the
 * planner fills a free slot while the tick consumes the other.
 *   lsm_selftest_plan()  main loop: plans the next item into a free slot
 *   lsm_selftest_tick()  control tick: evaluates one cycle of the current slot (or idles if none is ready)
 * Ticks that find no plan ready are idle (the machine stands still); they depend on timing and are not
 * hashed. Everything else is deterministic.
 *
 * Parts (items are fixed tables in selftest_prog.c):
 *   scurve   velocity changes (lsm_scurve_plan, rule strict), closed-form J, A, V, S each cycle
 *   move     synchronised 1-, 3- and 6-axis moves (lsm_move_plan), positions from the per-cycle evaluator
 *            (lsm_stepgen_next) each cycle
 * (The planner's contour program with lines, arcs and clothoid corners joins here once the planner exists.)
 *
 * Results per part: a 32-bit FNV-1a hash over the plan side (status codes, cycle counts, peak jerks) and one
 * over the tick side (bit patterns of every setpoint), plus a few hundred sampled setpoints (every
 * LSM_SELFTEST_SAMPLE_EVERY-th cycle and each item's last cycle), so that a mismatch can be told apart from
 * rounding. No I/O, no allocation: the caller owns the object and prints the results.
 */
#ifndef LSM_SELFTEST_PROG_H
#define LSM_SELFTEST_PROG_H

#include "lsm_config.h"
#include "move.h"
#include "scurve.h"
#include "stepgen.h"

#define LSM_SELFTEST_CYCLE_US 250u /* control cycle of the program (us); the MCU tick runs at it */
#define LSM_SELFTEST_MAX_PARTS 4
#define LSM_SELFTEST_MAX_SAMPLES 512
#define LSM_SELFTEST_SAMPLE_EVERY 97u /* sample cycles 0, 97, 194, ... of each item */
#define LSM_SELFTEST_HASH_INIT 0x811C9DC5u

typedef struct lsm_selftest_part {
    const char *name;
    uint32_t n_plans;    /* items planned (successfully or not) */
    uint32_t n_cycles;   /* cycles evaluated */
    uint32_t plan_hash;  /* plan side: statuses, cycle counts, peak jerks */
    uint32_t cycle_hash; /* tick side: every setpoint's bit pattern */
} lsm_selftest_part;

/* One sampled setpoint: up to 4 values (scurve: j, a, v, s; move: the axis position in v[0]). */
typedef struct lsm_selftest_sample {
    uint8_t part, axis;
    uint16_t item;
    uint32_t cycle;
    lsm_real v[4];
} lsm_selftest_sample;

typedef struct lsm_selftest_slot {
    volatile uint8_t full; /* 0: the planner may fill it; 1: the tick owns it */
    uint8_t part;
    uint16_t item;
    uint32_t n_cycles; /* cycles to evaluate */
    lsm_scurve sc;
    lsm_move mv;
    lsm_stepgen gen;
} lsm_selftest_slot;

typedef struct lsm_selftest {
    /* planner side (main loop) */
    uint32_t plan_part, plan_item, plan_idx;
    volatile uint8_t all_planned;
    /* tick side */
    uint32_t eval_idx, cycle;
    uint32_t idle_ticks;
    volatile uint8_t finished;
    lsm_selftest_slot slot[2];
    lsm_selftest_part result[LSM_SELFTEST_MAX_PARTS];
    uint32_t n_parts;
    lsm_selftest_sample sample[LSM_SELFTEST_MAX_SAMPLES];
    uint32_t n_samples;    /* recorded (at most LSM_SELFTEST_MAX_SAMPLES) */
    uint32_t samples_lost; /* not recorded because the table was full */
} lsm_selftest;

typedef enum lsm_selftest_plan_result {
    LSM_SELFTEST_PLANNED = 0,    /* planned one item (or hashed a rejected one): call again */
    LSM_SELFTEST_SLOTS_BUSY = 1, /* both slots are in use: wait for a tick */
    LSM_SELFTEST_ALL_PLANNED = 2 /* nothing left to plan */
} lsm_selftest_plan_result;

typedef enum lsm_selftest_tick_result {
    LSM_SELFTEST_CYCLE = 0, /* evaluated one cycle */
    LSM_SELFTEST_IDLE = 1,  /* no plan ready (counted in idle_ticks) */
    LSM_SELFTEST_DONE = 2   /* the program has finished */
} lsm_selftest_tick_result;

/* Resets the program to its start. */
void lsm_selftest_init(lsm_selftest *st);

/* Main loop: plans the next item if a slot is free. */
lsm_selftest_plan_result lsm_selftest_plan(lsm_selftest *st);

/* Control tick: one cycle. */
lsm_selftest_tick_result lsm_selftest_tick(lsm_selftest *st);

/* FNV-1a over the 4 bytes of a 32-bit word, little-endian order. */
uint32_t lsm_selftest_hash_u32(uint32_t h, uint32_t word);

/* The bit pattern of a real (float: the 32 bits; double: the low 32 bits XOR the high 32 bits). */
uint32_t lsm_selftest_bits(lsm_real x);

#endif /* LSM_SELFTEST_PROG_H */
