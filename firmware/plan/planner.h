/*
 * planner.h: look-ahead velocity planner over a ring of path blocks (lsm_planner_*).
 *
 * Model. The path is a chain of blocks (lines in up to 6 axes, circular/helical arcs, and the clothoid pairs
 * that corner smoothing inserts between them, geom.h / corner.h), parametrised by arc length s. The motion along
 * it is one tangential profile s(t), built from "pieces" that join with a = j = 0:
 *
 *   v ^          node                          node                 node (stop)
 *     |           :      ramp A   cruise vc      :  ramp A    ramp B   :
 *     |           :       ____________________   :    _______          :
 *     |   ramp B  :      /                    \  :   /       \         :
 *     |  \________:_____/                      \_:__/         \        :
 *     |           : lead cruise (v0)     ramp B  :             \_______:
 *     +-----------+------------------------------+---------------------+--> s
 *       piece k-1           piece k                    piece k+1
 *
 * Every piece is [lead cruise at v0][ramp A: v0 -> vc][cruise vc][ramp B: vc -> v1][trail cruise at v1]. Each
 * ramp is a sin² velocity change with the strict whole-cycle rule of scurve.h (Kombarov eqs 17, 22-37, every
 * interval a whole number of cycles (eq 33), J_P corrected by eq 34); the cruises take any length, so a ramp may
 * start anywhere and every piece ends exactly on its node (the interpolator samples the profile at the cycle
 * instants, carrying the fraction of a cycle from piece to piece). A ramp may span any number of blocks: nothing
 * ties velocity changes to block boundaries, so dense CAM code (0.05-0.2 mm segments) accelerates over hundreds
 * of blocks in one ramp. Nodes (where pieces meet) sit at the valleys of the speed-limit profile, at significant
 * drops of it, at exact stops, and at the end of the buffer.
 *
 * Limits. The setpoint of axis i is q_i(s(t)) and (Beudaert eqs 1-3, with the last term of eq 3 as q_s s''')
 *     q'   = q_s v,   q'' = q_ss v² + q_s a,   q''' = q_sss v³ + 3 q_ss v a + q_s j        (v, a, j of s(t))
 * Per block, bounds Q1_i >= |q_s,i|, Q2_i >= |q_ss,i|, Q3_i >= |q_sss,i| over the whole block are computed from
 * its geometry (line: dir; arc: r w, r w², r w³ along the swept angle range; clothoid: T, kappa N,
 * c N - kappa² T along the turning range) and reduced to six numbers per block
 *     alpha_a = max_i Q1_i/A_i   beta_a = max_i Q2_i/A_i
 *     alpha_j = max_i Q1_i/J_i   beta_j = max_i Q2_i/J_i   gamma_j = max_i Q3_i/J_i    alpha_s = max_i Q1_i/S_i
 * so that, for every axis at once, within that block
 *     |a| <= (1 - beta_a v²) / alpha_a,   |j| <= (1 - gamma_j v³ - 3 beta_j v |a|) / alpha_j,
 *     tangential snap <= 1 / alpha_s                                                       (budgets)
 * hold every axis's acceleration and jerk (and Q1_i v <= V_i for velocity). The speed cap of a block is
 *     cap = min(F * override, V_i / Q1_i, sqrt(rho / beta_a), cbrt(rho / gamma_j))
 * (rho = cap_margin < 1 leaves part of A and J for changing speed at the cap). For a path whose normal may point
 * along any axis this is eq 7 (sqrt(a/kappa)) and eq 8 (cbrt(j/c), plus the kappa² v³ term eq 8 drops); explicit
 * path limits (path_a_max, path_j_max) add eqs 7 and 8 literally as one more "axis".
 * Every ramp is verified against these budgets before it is used: it is cut into sub-intervals (phase
 * boundaries and quarters/eighths of each phase, where v and |a| are monotone), and for every block that a
 * sub-interval touches, the largest v, |a|, |j| of the sub-interval must fit that block's budgets and cap. A ramp
 * that does not fit is re-planned with smaller tangential limits, or moved. Hence the true (continuous) axis
 * v, a and j stay within the limits, and so do the backward differences of the setpoints (Beudaert eq 6): the
 * third difference is the jerk averaged with a non-negative kernel. Axis snap is only held in its tangential part
 * (q_s s''''); the other snap terms are not bounded.
 *
 * Look-ahead invariants.
 *  - Backward pass: from the end of the buffer (speed 0) back to the interpolator, every node gets W, the highest
 *    speed with a = 0 from which one ramp (with cruises) reaches the next node's W, verified pointwise. So from
 *    every node at or below its W the machine can stop within the buffered blocks: a buffer underrun is a clean
 *    stop. The pass stops as soon as a node's W does not change (bounded, incremental replanning).
 *  - Forward step (when the interpolator needs the next piece): v1 = min(W of the next node, what one ramp from v0
 *    can reach), then the highest cruise vc whose ramps verify. One ramp up to that cruise must fit every block
 *    it crosses (out of a curved valley: lowered limits, or a late start); when a lower ramp followed by a
 *    second one planned from its end reaches the same cruise sooner, the lower one is taken as one step of a
 *    staircase (lsm_piece.step): the interpolator re-plans at the end of its ramp A and climbs on (if no new
 *    piece is found there, the step piece itself is complete and verified).
 *  - Commitment. Only the current ramp is ever committed: the interpolator re-plans (a = 0) in cruises and
 *    exactly at the end of a ramp when blocks arrived or the override changed, and it tells the planner that
 *    point and its speed there, and where its current piece ends and at what speed (lsm_planner_set_horizon).
 *    An append changes nothing before that point. If it invalidates the current piece (a corner trims the block
 *    the piece ends in, or the piece's end is no longer a speed from which the machine can go on: valleys near the
 *    end of the buffer move when blocks are appended), a verified piece from the horizon must exist, and the
 *    interpolator must take a new piece there (lsm_planner_piece_stale); if none exists (the new block, or the trim of its
 *    corner, took room the machine needs to slow down), the junction becomes an exact stop instead, which restores
 *    the previous plan exactly (stats.horizon_stops; the node detection never looks across an exact stop). A lower
 *    override applies from a block far enough out that the same holds (at worst, to blocks appended later only).
 *  - Arrivals. Feasibility is not strictly monotone in the speed (near the caps the budgets vanish and the
 *    whole-cycle ramps change shape with the speed), so a W says nothing of the speeds below it: a piece arrives
 *    at a node below its W only at a speed that passed W's own test, the forward search always tries, last, the
 *    piece the node's certificate verified, and the backward pass keeps an old W only if it still passes its test.
 *  - Contexts. The planner and its interpolator (interp.h) are one context's: the appends, lsm_interp_prepare
 *    and lsm_interp_step run in turn, never preempting each other. On a controller that context is the
 *    background: the motion layer (motion.h) runs lsm_interp_step lead_cycles ahead of the control cycle and
 *    hands the finished setpoints to the tick through a single-producer ring (mpipe.h), so the tick never
 *    reads the planner. In a synchronous loop (the host simulator, the contour image in lock-step) the cycle
 *    calls lsm_interp_step itself, after the background's work of the cycle. The step writes nothing of the
 *    planner's directly: it posts requests (lsm_planner_req: the blocks it is done with, its commitment
 *    horizon, the piece invalidation it has seen) under a sequence counter, which the next planner call
 *    applies; but it reads head, tail, gen and the blocks with no hand-off of their own, so a step may not
 *    preempt an append or lsm_interp_prepare on the same planner (docs/architecture.md, "Contexts").
 *  - The control cycle does not plan: pieces are planned ahead by lsm_interp_prepare (interp.h).
 *    Hence a buffer underrun is a clean, verified stop on the path, and the interpolator starts again by itself
 *    when blocks are appended behind it.
 *  - Feed hold: one verified ramp to rest, started at the next point where a = 0, within the path up to the
 *    next exact stop (else the current plan, which stops there, is followed and the hold takes effect there).
 *  - Every piece ends exactly on its end point, so stops (exact stop, end of buffer, end of program) land exactly
 *    on their point and the next piece starts exactly where the certificate of its node was computed.
 *
 * Blocks and corners. A corner between two blocks is replaced by a G2 clothoid pair (corner.h) within the
 * tolerance in force (G64 P, lsm_planner_move.tol_mm > 0); with tol_mm = 0 (G61) or where no transition exists
 * (reversal, rotary axes, non-planar) the machine stops at the corner. Only the last block of the buffer is ever
 * modified (its end trimmed), and only beyond the interpolator's commitment horizon.
 * Dense G1 polylines are first fitted with arcs (arcfit.h) within fit_share of the tolerance where the per-vertex
 * transitions would limit the feed; those points wait in the planner until their run ends (or flush / finish).
 * An append pushes one block with its corner smoothing and backward pass: a block whose append already pushed one
 * (the run it emitted, or the block the call before held) is held, its slots reserved, until the next planner call
 * (or flush / finish) pushes it first.
 * Append validates its input first and changes nothing on error (except that the block the call before held may
 * have been pushed, as any call does first): no accepted block is ever lost.
 *
 * Dense G1 points are fitted with arcs only where the arc's evaluation error (about R eps of lsm_real) stays far
 * below the tolerance (float builds: radius up to ~40 mm at a 0.01 mm fit tolerance; larger radii are lines).
 * Memory: caller-owned block storage (lsm_pblock, 92 bytes in the float build, 168 in double) and the
 * lsm_planner object. User documentation: docs/planner.md.
 * Units: mm, s, rad (rotary axes), and their derivatives; a rotary-only line uses rad as its path unit.
 */
#ifndef LSM_PLANNER_H
#define LSM_PLANNER_H

#include "arcfit.h"
#include "geom.h"
#include "lsm_atomic.h"
#include "scurve.h"

/* Smallest block storage accepted (a corner needs three slots). */
#define LSM_PLANNER_MIN_BLOCKS 8
/* Phases of one piece: lead cruise, ramp A (7), cruise, ramp B (7), trail cruise. */
#define LSM_PIECE_PHASES 17

/* Compile-time settings (LSM_PLANNER_CAP_MARGIN, LSM_PLANNER_NODE_HYST, LSM_PLANNER_NODE_DROP,
 * LSM_PLANNER_FIT_SHARE, LSM_PLANNER_TRIM_SHARE): lsm_config.h. */

/* Block flags. */
enum {
    LSM_PB_STOP = 1u,   /* the machine stops at the start of this block (v = 0) */
    LSM_PB_NODE = 2u,   /* a node of the look-ahead starts at this block (w_mm_s is its W) */
    LSM_PB_CORNER = 4u, /* a clothoid inserted by corner smoothing */
    LSM_PB_RAPID = 8u   /* G0 */
};

/* Limits of one axis, in its unit u (mm, or rad for A B C): u/s, u/s², u/s³, u/s⁴. */
typedef struct lsm_planner_axis {
    lsm_real v_max;
    lsm_real a_max;
    lsm_real j_max;
    lsm_real snap_max;
} lsm_planner_axis;

typedef struct lsm_planner_config {
    lsm_real cycle_s;                    /* control cycle */
    uint8_t axis_mask;                   /* bit k: axis k (X Y Z A B C) exists; the others must never move */
    lsm_planner_axis axis[LSM_MAX_AXES]; /* limits of the existing axes */
    lsm_real cap_margin;                 /* rho in (0, 1) */
    lsm_real path_a_max_mm_s2;           /* optional tangential-frame limits (eqs 7, 8); 0: none */
    lsm_real path_j_max_mm_s3;
    lsm_real node_hyst;  /* [0, 1) */
    lsm_real node_drop;  /* (0, 1) */
    lsm_real trim_share; /* (0, 0.5] */
    lsm_real fit_share;  /* [0, 1): share of the blend tolerance used to fit arcs through dense G1
                                             polylines (arcfit.h); 0 turns fitting off */
} lsm_planner_config;

/* One look-ahead block (caller storage). */
typedef struct lsm_pblock {
    lsm_geom g;            /* geometry (geom.h) */
    lsm_real feed_mm_s;    /* programmed feed (path units / s); LSM_REAL_MAX for rapids */
    lsm_real cap_geo_mm_s; /* speed cap from the axis limits and the geometry (no feed, no override) */
    lsm_real w_mm_s;       /* W of the node starting here (backward pass), when LSM_PB_NODE */
    uint32_t seq;          /* the caller's tag (source line) */
    uint16_t coef[6];      /* alpha_a, beta_a, alpha_j, beta_j, gamma_j, alpha_s as bfloat16, rounded up */
    uint8_t flags;         /* LSM_PB_* */
    uint8_t reserved;
} lsm_pblock;

/* What comes with a block. */
typedef struct lsm_planner_move {
    lsm_real feed_mm_s; /* programmed feed > 0 (mm/s; rad/s for a rotary-only line); ignored for rapids */
    lsm_real tol_mm;    /* corner at the END of this block: > 0 blends within this deviation (G64 P),
                             0 stops exactly there (G61) */
    uint32_t seq;       /* tag (e.g. the source line), reported back */
    uint8_t rapid;      /* G0: feed = the axes' v_max */
} lsm_planner_move;

/* One phase of a piece: a sin² jerk rise or fall, constant jerk, or a cruise. */
typedef struct lsm_piece_phase {
    lsm_real T_s;        /* duration: whole cycles for ramp phases (Kombarov eq 33), any length for cruises */
    lsm_real len_mm;     /* distance travelled in it */
    lsm_real jerk_mm_s3; /* jerk amplitude (0 for cruises and T4) */
    uint32_t n_cycles;   /* T_s in cycles for ramp phases, 0 for cruises */
    uint8_t shape;       /* lsm_phase_shape */
    uint8_t reserved[3];
} lsm_piece_phase;

/* One piece of the tangential profile, ready for the interpolator. It ends exactly on its end point. */
typedef struct lsm_piece {
    uint32_t blk;    /* id of the block where it starts */
    lsm_real off_mm; /* offset into that block */
    lsm_real len_mm; /* distance to its end (a node, the end of the buffer, or a hold) */
    lsm_real v0_mm_s, v1_mm_s, vc_mm_s;
    uint32_t end_blk; /* it ends at the start of this block (tail: the end of the buffer) */
    lsm_real T_s;     /* duration */
    uint8_t stop;     /* ends with v = 0 */
    uint8_t hold;     /* a feed-hold stop (ends anywhere) */
    uint8_t step;     /* ramp A is a step of a staircase: re-plan at its end */
    uint8_t reserved;
    lsm_piece_phase ph[LSM_PIECE_PHASES]; /* lead cruise, ramp A (7), cruise, ramp B (7), trail cruise */
    lsm_kin st[LSM_PIECE_PHASES];         /* state at each phase start (s piece-relative) */
} lsm_piece;

typedef struct lsm_planner_stats {
    uint32_t appended;       /* blocks accepted by append */
    uint32_t corners;        /* corners smoothed with a clothoid pair */
    uint32_t corner_stops;   /* corners where the machine must stop */
    uint32_t horizon_stops;  /* of these: junctions made exact stops because the interpolator was too close */
    uint32_t pieces;         /* pieces planned */
    uint32_t plan_fallbacks; /* pieces that needed the conservative fallback (should stay 0) */
    uint32_t checks;         /* ramp verifications (cost indicator) */
    uint32_t bp_nodes;       /* node evaluations in backward passes */
    uint32_t restore_unkept; /* plans restored after a change the machine could not follow (an override change
                                undone, a junction made an exact stop) that still do not keep its commitment (should
                                stay 0) */
    uint32_t pieces_kept;    /* of pieces: the memo's (lsm_planner_memo), no search */
} lsm_planner_stats;

/* The last piece the forward search found for lsm_planner_plan_piece (mode NORMAL), kept to answer the same call again
 * while nothing the search read has changed (plan_piece.c, "The piece memo"): the call, how far the search read, the
 * piece's end and length, and the plan the piece is built from (plan_piece.c's private plan5, copied as bytes: one
 * copy each way; plan_piece.c checks the size). */
#define LSM_PLANNER_MEMO_PLAN_BYTES (sizeof(lsm_real) == 4u ? 108u : 200u)
typedef struct lsm_planner_memo {
    uint32_t id0; /* the call: start block, offset and speed (compared bit for bit) */
    lsm_real off0_mm, v0_mm_s;
    uint32_t reach;   /* the search read blocks [id0, reach) and no further (tail + 1: it met the buffer's end) */
    uint32_t end_blk; /* the piece's end node and length */
    lsm_real len_mm;
    uint8_t plan[LSM_PLANNER_MEMO_PLAN_BYTES];
    uint8_t ok;  /* it holds a piece, and no block before reach, no override, no limit changed since */
    uint8_t off; /* tests: no memo, every piece searched (tests/plan/test_plan_memo.c compares the two) */
    uint8_t reserved[2];
} lsm_planner_memo;

/* The requests of the control cycle (interp.c's lsm_interp_step, the tick) to the planner, which belongs to the
 * background: the tick is done with the blocks before release_blk (their slots may be reused), its commitment
 * horizon (lsm_planner_set_horizon's arguments), and the piece it runs was planned when stale_set had the value
 * stale_ack. Written only by the tick (lsm_planner_post_*), published with the sequence counter `seq`
 * (lsm_atomic.h); the background applies them (lsm_planner_apply_requests) at the start of every background call
 * of this header, and lsm_planner_free / count / block count the posted release at once. */
typedef struct lsm_planner_req {
    lsm_atomic_u32 seq;         /* sequence counter: odd while the tick writes */
    lsm_atomic_u32 release_blk; /* the tick is done with the blocks before this id (only grows) */
    lsm_atomic_u32 hz_posted;   /* a horizon was posted */
    lsm_atomic_u32 hz_blk;      /* lsm_planner_set_horizon's blk, off_mm, v_mm_s, end_blk, end_v_mm_s */
    lsm_atomic_real hz_off, hz_v;
    lsm_atomic_u32 hz_end;
    lsm_atomic_real hz_end_v;
    lsm_atomic_u32 end_changes; /* posts whose end (end_blk, end_v) differed from the one before */
    lsm_atomic_u32 stale_ack;   /* the stale_set value the tick's present piece was planned on */
} lsm_planner_req;

typedef struct lsm_planner {
    lsm_planner_config cfg;
    lsm_pblock *blk;
    uint32_t cap;                     /* storage size */
    uint32_t head_slot;               /* storage slot of block id `head` */
    uint32_t head, tail;              /* ids of the blocks held: [head, tail) */
    lsm_real tail_pos[LSM_MAX_AXES];  /* geometric end of the last block (where the next one starts) */
    lsm_real tail_prog[LSM_MAX_AXES]; /* programmed end of the last block (the exact end of the program) */
    lsm_real tail_tol_mm;             /* tolerance for the corner at the end of the last block */
    uint8_t tail_rotary;              /* the last block moves A B C */
    uint8_t finished;                 /* lsm_planner_finish was called */
    uint8_t full_pass;                /* the next backward pass must cover the whole buffer */
    uint8_t reserved;
    lsm_real ovr_near, ovr_far; /* feed override (factor) for blocks below / from ovr_switch */
    uint32_t ovr_switch;
    uint32_t horizon_blk; /* the interpolator is committed up to here (block id, offset), where it will */
    lsm_real horizon_off; /* be able to re-plan (a = 0) at speed horizon_v */
    lsm_real horizon_v;
    uint32_t horizon_end;     /* its current piece ends at the start of this block (the tail: the buffer's end) */
    lsm_real horizon_end_v;   /* at this speed (a = 0): the W of that node must stay at least this */
    lsm_atomic_u32 stale_set; /* counts invalidations of the interpolator's current piece (a corner trimmed the
                                   block it ends in, or its end speed no longer goes on): while it differs from
                                   req.stale_ack the piece is stale (lsm_planner_piece_stale) and a new piece must
                                   start at the horizon (verified to exist there). Background-written. */
    uint8_t commit_dirty;     /* the commitment changed since it was last verified in full */
    uint8_t reserved3[3];
    uint32_t req_seq_applied;     /* req.seq when the requests were last applied */
    uint32_t end_changes_applied; /* req.end_changes then */
    lsm_planner_req req;          /* the tick's requests (above) */
    uint32_t bp_stop;             /* the last backward pass left the nodes before this block unchanged */
    uint32_t gen;                 /* changes whenever the plan may change (append, override, finish) */
    /* polyline fitting: the G1 points pending since the last block emitted (they start at tail_pos) */
    lsm_arcfit_pt fit_pt[LSM_ARCFIT_MAX];
    uint32_t fit_n;
    lsm_real fit_feed, fit_tol;
    lsm_real tail_fit_err; /* fitting error of the last block (its corners get the rest of the tolerance) */
    lsm_real tail_n[3];    /* the last block is a fitted arc with this plane normal (tail_arc), or the line that
                              closed a chain of them and the arcs after it take this plane (tail_switch) */
    uint8_t tail_arc;
    uint8_t fit_need;       /* a vertex of the pending run limits the feed (its arc fit is used) */
    uint8_t fit_slots;      /* slots the pending run takes when it is emitted (reserved as it grows) */
    uint8_t tail_switch;    /* see tail_n */
    lsm_arcfit_chain chain; /* the plane of the current chain of fitted arcs, measured (arcfit.h) */
    /* one block, with its corner and backward pass, per append: a block whose append already pushed one (a pending
       run it emitted, or the block held by the call before) is held for the next planner call (planner.c) */
    lsm_geom held_g;
    lsm_planner_move held_mv;
    lsm_real held_end[LSM_MAX_AXES];
    uint8_t held; /* held_g is held (its 3 slots are not counted free) */
    uint8_t reserved4[3];
    uint32_t call_tail;    /* the tail when the current planner call began */
    lsm_planner_memo memo; /* the last piece searched (plan_piece.c) */
    lsm_planner_stats stats;
} lsm_planner;

/* Defaults: 1 ms cycle, X Y Z at 250 mm/s, 3000 mm/s², 60000 mm/s³, 1.2e7 mm/s⁴, and the macros above. Any
 * context. */
void lsm_planner_default_config(lsm_planner_config *cfg);

/*
 * Initialise with caller storage of `capacity` blocks and the start position (LSM_MAX_AXES values, mm / rad).
 * Errors: LSM_E_NULL, LSM_E_CYCLE, LSM_E_LIMIT (an existing axis's limit <= 0, or a path limit < 0),
 * LSM_E_NAN, LSM_E_INF, LSM_E_ARG (axis_mask 0 or above 0x3F, cap_margin / node_hyst / node_drop / trim_share
 * outside their ranges), LSM_E_PL_CAPACITY (capacity < LSM_PLANNER_MIN_BLOCKS).
 * Background, while no interpolator cycle runs on this planner (re-initialise its interpolator after it).
 */
lsm_status lsm_planner_init(lsm_planner *pl, const lsm_planner_config *cfg, lsm_pblock *storage, uint32_t capacity,
                            const lsm_real start[LSM_MAX_AXES]);

/*
 * Append a straight line from the end of the last block to `end` (LSM_MAX_AXES values).
 * Errors (nothing is changed but the push of a held block, see above): LSM_E_NULL, LSM_E_NAN, LSM_E_INF (end, feed
 * or tolerance not finite), LSM_E_NEG_FEED (feed <= 0 and not rapid), LSM_E_TOLERANCE (tol < 0), LSM_E_PL_AXIS (an
 * axis outside the mask moves), LSM_E_ZERO_LENGTH, LSM_E_RANGE, LSM_E_FULL (fewer than 3 free slots),
 * LSM_E_PL_FINISHED.
 * Background.
 */
lsm_status lsm_planner_append_line(lsm_planner *pl, const lsm_real end[LSM_MAX_AXES], const lsm_planner_move *mv);

/*
 * Append a circular or helical arc from the end of the last block to `end` (X Y Z) around `centre` in a G17/18/19
 * plane, dir = +1 (G3) or -1 (G2), plus `turns` full turns (geom.h). A B C stay where they are.
 * Errors: as lsm_planner_append_line, plus LSM_E_ARG and LSM_E_ARC_GEOMETRY (geom.h). Background.
 */
lsm_status lsm_planner_append_arc(lsm_planner *pl, const lsm_real end[3], const lsm_real centre[3],
                                  lsm_geom_plane plane, int dir, uint32_t turns, const lsm_planner_move *mv);

/* End of program: the last block ends with an exact stop on its programmed end point (pending points are
 * emitted first). Errors: LSM_E_NULL, LSM_E_FULL (room for the pending points is missing: run the interpolator
 * and call again). Background. */
lsm_status lsm_planner_finish(lsm_planner *pl);

/* Emits the G1 points held for fitting and the block held for the next call (a caller that pauses its stream calls
 * this so that the machine does not stop short of them). Errors: LSM_E_NULL, LSM_E_FULL. Background. */
lsm_status lsm_planner_flush(lsm_planner *pl);

/* Free block slots (an append needs up to 3), counting the release the tick posted and without the slots of a
 * block held for the next call. Background. */
uint32_t lsm_planner_free(const lsm_planner *pl);
/* Blocks held (a block held for the next call included), counting the release the tick posted. Background. */
uint32_t lsm_planner_count(const lsm_planner *pl);
/* Block by id (NULL outside [head, tail), head counting the posted release). Background; the tick reads the
 * blocks of its piece (interp.c), which the background does not change before the horizon. */
const lsm_pblock *lsm_planner_block(const lsm_planner *pl, uint32_t id);
/* Speed cap of a block with the current override (mm/s). Background. */
lsm_real lsm_planner_block_cap(const lsm_planner *pl, uint32_t id);

/*
 * Feed override factor 0 .. 2. Decreases take effect beyond the distance the machine needs to slow down from
 * v_now_mm_s (at block cur_blk); increases at once, if the interpolator's commitment still holds (else like a
 * decrease: a higher factor can lower a node's W); the blocks before the switch keep the factor in force at cur_blk.
 * LSM_E_PL_OVR_LATER where it fits nowhere, not even for the blocks appended later: the plan stays as it was (the
 * interpolator retries). Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_PL_OVERRIDE.
 * (The interpolator calls this; 0 is handled there as a feed hold.) Background.
 */
lsm_status lsm_planner_set_override(lsm_planner *pl, lsm_real factor, uint32_t cur_blk, lsm_real v_now_mm_s);

/* ---- interface for the interpolator ---- */

typedef enum lsm_piece_mode {
    LSM_PIECE_NORMAL = 0, /* to the next node at the best feed */
    LSM_PIECE_HOLD = 1,   /* stop as soon as possible (feed hold) */
    LSM_PIECE_REPLAN = 2  /* as NORMAL, for a piece that replaces one still valid: no fallback, LSM_E_INFEASIBLE */
} lsm_piece_mode;

/*
 * Plan the piece that starts at block id0, off0 mm into it, with speed v0 mm/s (a = 0 there). Errors: LSM_E_NULL,
 * LSM_E_EMPTY (nothing to move: at the end of the buffer), LSM_E_INFEASIBLE (HOLD: no stop fits yet; REPLAN: no
 * verified piece found; follow the current plan and retry), LSM_E_INTERNAL (NORMAL: no verified plan; a fallback
 * piece that stops is returned and counted in stats.plan_fallbacks). Background (lsm_interp_prepare); the
 * interpolator's cycle calls it only in a synchronous loop (interp.h, tick_plans).
 */
lsm_status lsm_planner_plan_piece(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, lsm_piece_mode mode,
                                  lsm_piece *out);

/* The interpolator is committed up to (block id, off_mm), the first point where it can take a new piece (a = 0), at
 * speed v_mm_s there, and its current piece ends at the start of block end_blk (the tail: the end of the buffer)
 * at speed end_v_mm_s. The planner modifies nothing before that point. An append that invalidates the current
 * piece (a corner that trims the block it ends in, or a W of its end node that falls below end_v_mm_s) is only kept
 * if a verified piece from (blk, off_mm) at v_mm_s exists (else the junction becomes an exact stop, which restores
 * the previous plan), and then marks the piece stale (lsm_planner_piece_stale): the interpolator must take a new
 * piece there. Background; the interpolator posts it from the cycle instead (lsm_planner_post_horizon). */
void lsm_planner_set_horizon(lsm_planner *pl, uint32_t id, lsm_real off_mm, lsm_real v_mm_s, uint32_t end_blk,
                             lsm_real end_v_mm_s);

/* Blocks before `id` are no longer needed (their slots are freed). Background (the tick posts it:
 * lsm_planner_post_release). */
void lsm_planner_release(lsm_planner *pl, uint32_t id);

/* Runs the backward pass now (append runs it too; exposed for benchmarks). Background. */
void lsm_planner_update(lsm_planner *pl);

/* ---- the tick's requests (lsm_planner_req) ---- */

/* Control cycle: the tick is done with the blocks before `id` (only a later id than posted before counts). */
void lsm_planner_post_release(lsm_planner *pl, uint32_t id);
/* Control cycle: the commitment horizon, as lsm_planner_set_horizon. */
void lsm_planner_post_horizon(lsm_planner *pl, uint32_t id, lsm_real off_mm, lsm_real v_mm_s, uint32_t end_blk,
                              lsm_real end_v_mm_s);
/* Control cycle: the horizon moves to (id, off_mm) at v_mm_s, its end as posted last (lsm_planner_post_horizon
 * called before: the end is unchanged). Inline: the cruise posts it every cycle. */
static inline void lsm_planner_post_cursor(lsm_planner *pl, uint32_t id, lsm_real off_mm, lsm_real v_mm_s)
{
    lsm_planner_req *r = &pl->req;
    lsm_seq_write_begin(&r->seq);
    lsm_seq_put(&r->hz_blk, id);
    lsm_seq_put(&r->hz_off, off_mm);
    lsm_seq_put(&r->hz_v, v_mm_s > (lsm_real)0 ? v_mm_s : (lsm_real)0);
    lsm_seq_write_end(&r->seq);
}
/* Control cycle: the tick runs a piece planned when lsm_planner_stale_count was `stale_seen`. */
void lsm_planner_post_stale_ack(lsm_planner *pl, uint32_t stale_seen);
/* Background: applies the posted requests (release, horizon). Every background call of this header does it at
 * its start; a caller may call it at any time in the background. */
void lsm_planner_apply_requests(lsm_planner *pl);

/* The count of piece invalidations (stale_set). Any context (acquire load). */
static inline uint32_t lsm_planner_stale_count(const lsm_planner *pl)
{
    return lsm_atomic_get_acquire((lsm_atomic_u32 *)&pl->stale_set);
}

/* True while the interpolator's current piece is stale (invalidated after it was planned). Any context. */
static inline bool lsm_planner_piece_stale(const lsm_planner *pl)
{
    return lsm_planner_stale_count(pl) != lsm_atomic_get((lsm_atomic_u32 *)&pl->req.stale_ack);
}

#endif /* LSM_PLANNER_H */
