/*
 * mpipe.h: the hand-off between the two contexts of the CiA 402 motion layer (motion.h): the control cycle (tick)
 * and the background. Three single-producer single-consumer rings of caller-visible fixed size, each with one
 * writer context per field (lsm_atomic.h):
 *
 *   tick -> background   in     one record per tick: the co_path commands (epoch, override 0x5001, run / hold /
 *                               quick), the axes' demands (for lsm_pathfeed_sync), the blocks handed over so far,
 *                               the tick's abort count; stamped with the tick's count.
 *   tick -> background   blk    the 0x5010 blocks, taken from the node's co_path buffer by the tick (the node is
 *                               the tick's: canopen.h), each tagged with its co_path epoch.
 *   tick -> background   pp_req a PP set-point's move plan (lead_cycles > 0): the axis's generator and the
 *                               set-point; the background steps a copy of the generator to the cycle the move
 *                               will start at and plans it there (lsm_axprof_move);
 *   background -> tick   pp_res the planned generator, taken by the tick at that cycle (motion.h);
 *   background -> tick   out    one path set-point per record: every axis's position and velocity, the report
 *                               for lsm_co_path_update, blocks consumed, refusals, the abort count it follows.
 *
 * Protocol (lock-step pipeline). The background turns record n into set-point n and nothing else: it reads only
 * record n and the blocks the tick had handed over by tick n. The sequence of set-points is therefore a function of
 * the records alone, whatever the timing: bit-identical to running tick and background alternately in one context
 * (tests/motion/test_motion_pipe.c checks it with the tick in another thread, under ThreadSanitizer too). The tick
 * of cycle n consumes set-point n - lead (lead >= 1 when the background runs preempted; 0 in the synchronous
 * loop, where the background runs between the two halves of the tick: lsm_motion_cycle). The tick never waits:
 * the background had lead cycles to produce the set-point; if it has not (underrun) the tick stops the path
 * itself (motion.h). The block ring's room the tick uses is computed from the consumption count carried by the
 * set-points it has consumed (also a function of the records), so block hand-over is deterministic too.
 *
 * Barriers: an element is written with plain stores and published by a release store of the producer's index;
 * the consumer reads the index with an acquire load before it reads the element, and frees the slot with a
 * release store of its own index after it read it (the producer's acquire load of that index orders its next
 * write after the read). On the single-core M4 these are compiler fences (LSM_HANDOFF_SINGLE_CORE).
 *
 * Contexts: lsm_spsc_* producer calls from the producer's context only, consumer calls from the consumer's.
 * Units: positions mm (rad), velocities mm/s.
 */
#ifndef LSM_MPIPE_H
#define LSM_MPIPE_H

#include <stdbool.h>
#include <stdint.h>

#include "axprof.h"
#include "co_path.h"
#include "lsm_atomic.h"
#include "lsm_config.h"

/* Records and set-points in flight: the lead plus what a slow background may fall behind by before the tick's
 * underrun stop (64 cycles: 64 ms at 1 ms). Power of two. */
#define LSM_MPIPE_CAP 64u
/* Blocks handed over but not yet appended: the planner takes them as it has room; a few are enough (the node's
 * co_path buffer holds the rest and keeps 0x5003 meaningful). Power of two. */
#define LSM_MPIPE_BLOCKS 4u
/* PP move plans in flight (requests, results): one per axis, and a stale one each. Power of two. */
#define LSM_MPIPE_PP 16u
/* The longest lead: the in ring must hold it and the set-points in flight. */
#define LSM_MPIPE_LEAD_MAX 48u

/* One index pair: head written by the producer only, tail by the consumer only (free-running counts). */
typedef struct lsm_spsc {
    lsm_atomic_u32 head;
    lsm_atomic_u32 tail;
} lsm_spsc;

/* Producer: slots free (acquire load of tail). */
static inline uint32_t lsm_spsc_room(lsm_spsc *r, uint32_t cap)
{
    return cap - (lsm_atomic_get(&r->head) - lsm_atomic_get_acquire(&r->tail));
}
/* Producer: the slot index of the next element to write (room checked by the caller). */
static inline uint32_t lsm_spsc_wr(lsm_spsc *r)
{
    return lsm_atomic_get(&r->head);
}
/* Producer: publishes the written element (release). */
static inline void lsm_spsc_push(lsm_spsc *r)
{
    lsm_atomic_put_release(&r->head, lsm_atomic_get(&r->head) + 1u);
}
/* Consumer: elements available (acquire load of head). */
static inline uint32_t lsm_spsc_avail(lsm_spsc *r)
{
    return lsm_atomic_get_acquire(&r->head) - lsm_atomic_get(&r->tail);
}
/* Consumer: the slot index of the oldest element (availability checked by the caller). */
static inline uint32_t lsm_spsc_rd(lsm_spsc *r)
{
    return lsm_atomic_get(&r->tail);
}
/* Consumer: frees the oldest element (release: the read is done). */
static inline void lsm_spsc_pop(lsm_spsc *r)
{
    lsm_atomic_put_release(&r->tail, lsm_atomic_get(&r->tail) + 1u);
}

/* tick -> background, one per tick. */
typedef struct lsm_mpipe_in {
    uint32_t stamp;       /* the tick's count */
    uint32_t blocks_in;   /* blocks handed over up to and including this tick (count) */
    uint32_t cp_count;    /* blocks left in the node's co_path buffer after the hand-over */
    uint32_t abort;       /* the tick's path aborts so far */
    uint16_t epoch;       /* co_path epoch */
    uint8_t override_pct; /* 0x5001 */
    uint8_t motion;       /* lsm_co_path_motion */
    uint8_t abort_rest;   /* the tick's abort stop has reached rest at pos_mm: restart the planner there */
    uint8_t path_mask;    /* axes in path mode (bit k): their pos_mm lags the feed by the lead, not synced */
    uint32_t sync_gen;    /* the tick's count of axes entering path mode: sync the feed to pos_mm (all axes) */
    uint8_t reserved[3];
    lsm_real pos_mm[LSM_MAX_AXES]; /* every axis's demand after the tick's own axis steps */
    lsm_real cpm[LSM_MAX_AXES];    /* counts per mm (0x2001) */
} lsm_mpipe_in;

/* tick -> background: a block with the co_path epoch it belongs to. */
typedef struct lsm_mpipe_blk {
    lsm_co_path_block b;
    uint16_t epoch;
} lsm_mpipe_blk;

/* background -> tick, one per record. */
typedef struct lsm_mpipe_out {
    lsm_real pos_mm[LSM_MAX_AXES];
    lsm_real vel_mm_s[LSM_MAX_AXES];
    lsm_co_path_report rep;
    uint32_t blocks_used; /* blocks consumed (appended, refused or dropped) through this record */
    uint32_t rejects;     /* blocks refused so far; the last one is reject_seq */
    uint32_t reject_seq;
    uint32_t abort;    /* the tick's abort count this set-point follows */
    uint32_t sync_gen; /* the tick's sync_gen the feed had synced to when it made this set-point */
    bool moving;
} lsm_mpipe_out;

/* A PP move plan: tick -> background the request (base: the axis's generator as the tick had it when it took the
 * set-point, to be stepped `steps` cycles, then lsm_axprof_move to target_mm), background -> tick the result (base:
 * the generator with the planned move, st: lsm_axprof_move's status). gen tells a stale result. */
typedef struct lsm_mpipe_pp {
    lsm_axprof base;
    lsm_axprof_limits lim;
    lsm_real target_mm;
    uint32_t gen;
    uint32_t steps;
    uint8_t axis;
    lsm_status st;
} lsm_mpipe_pp;

typedef struct lsm_mpipe {
    lsm_spsc in_idx, blk_idx, out_idx, pp_req_idx, pp_res_idx;
    lsm_mpipe_pp pp_req[LSM_MPIPE_PP];
    lsm_mpipe_pp pp_res[LSM_MPIPE_PP];
    lsm_mpipe_in in[LSM_MPIPE_CAP];
    lsm_mpipe_blk blk[LSM_MPIPE_BLOCKS];
    lsm_mpipe_out out[LSM_MPIPE_CAP];
} lsm_mpipe;

#endif /* LSM_MPIPE_H */
