/*
 * interp.h: per-cycle interpolator of the look-ahead planner (lsm_interp_*): one call per control cycle gives
 * every axis's absolute position setpoint (mm, rad).
 *
 * Model. The planner hands out pieces of the tangential profile s(t) (planner.h), each a list of phases whose
 * lengths are whole cycles. Per cycle the interpolator
 *   1. advances the piece's clock by one cycle (crossing phase ends, which lie anywhere between samples: cruises
 *      have any length, ramp phases whole cycles) and evaluates the phase-local travel with the closed forms of
 *      scurve.h,
 *        s(tau) = v0 tau + a0 tau²/2 + J f(tau),  f = tau³/6 (constant jerk) or
 *        f = tau³/12 -+ tau T²/(2 pi²) +- sin(pi tau / T) T³/(2 pi³)          (sin² rise / fall, Kombarov eq 15)
 *      where sin(pi tau / T) comes from a rotation recurrence by pi / n1 per cycle, entered at every phase with
 *      the ramp's entry angle (the samples of a ramp keep one offset to its phases, since their lengths are whole
 *      cycles): four trigonometric calls per ramp, none per cycle. It takes the difference ds from the previous
 *      sample (small numbers: no cancellation in float);
 *   2. moves the path cursor (block, offset) by ds and evaluates the block there: a line directly (p0 + dir s),
 *      an arc from an anchor point P_a on it, a clothoid with the incremental stepper of clothoid.h
 *      (lsm_clothoid_step). An arc (both builds; the double build used c + r u(phi), whose rounding, ulp(r), was
 *      noise on every setpoint: 0.15 % of a 1942 mm/s³ jerk limit on an R 96160 arc at 0.5 ms): P_a is exact
 *      (lsm_geom_eval from the arc's start point, geom.h), and the cursor is reached by the chord, d = w (s - s_a),
 *        p = P_a + (cos d - 1) A + sin d B + L (s - s_a),   A = r u(phi_a), B = r u'(phi_a),
 *      (cos d - 1 and sin d by short polynomials, no cancellation), so a setpoint is off by a few ulp of the
 *      coordinates, whatever the radius (c + r u(phi) with a float centre c is off by ulp(r): 5e-4 mm at
 *      R = 1e4). L = n axial / len + (E - p(len)) / len: E is the exact end of the block (the next block's start,
 *      or the end of the buffer), so the setpoints reach it exactly, however the arc's float parameters rounded;
 *      the linear term spreads that rounding (a few ulp) over the arc instead of a step at its end.
 * Float build: the cursor adds ds with a compensated (Kahan) sum, so over a piece of N cycles it stays within an ulp
 * of the sum of the travel instead of drifting by up to N/2 ulp (the drift came back as a step where the cursor is
 * put exactly on the piece's end).
 * The phases of a piece can add up to a little more than the piece (a ramp's float rounding where no cruise is left to
 * absorb it: up to ~1e-5 of it), or a few ulp less; the float build scales the travel by len / sum, so that the cursor
 * arrives exactly at the piece's end (a factor 1 - 1e-5 .. 1 + 2^-20 on v, a and j, instead of a step where the
 * cursor is put on the end), and its switch points and horizons with it. The factor is kept as 1 + e, and the
 * cursor adds ds e to its compensation: ds times a float factor near 1 rounded by up to ulp/2 of ds in the same
 * direction every cycle of a cruise (7e-5 mm over a 320 mm piece, a step where it ended).
 * Float: every whole cycle's travel is dt times the cycle's mean rate (interp.c, phase_step), summed compensated; the
 * phase clock is tau0 + n dt (no summed drift); arc anchors take the angle as an exact sum (arc_point). Each setpoint
 * is then within a few ulp of the largest coordinate of the exact curve (tests/common/float_noise.h: K = 4).
 * When a piece ends between two samples, the next one is planned at once and sampled at the rest of the cycle.
 * Replanning happens only where a = 0: at samples in cruises and at ramp starts, and exactly at the end of a
 * ramp (between two samples: the new piece is sampled at the rest of the cycle). There the interpolator takes a
 * new piece when the planner changed (blocks appended, override changed), a feed hold was requested, or the
 * ramp was one step of a staircase (planner.h). After every cycle it tells the planner where it will next be
 * able to re-plan and at what speed (lsm_planner_set_horizon: the end of the current ramp, or the cursor); if
 * no new piece is found, the current one stays valid and runs on.
 *
 * Background planning (lsm_interp_prepare). Every new piece starts where a = 0: at the start from rest, at the end
 * of the current piece (its successor), or, to replace the rest of the current piece, at a "switch point" of it: a
 * sample in a cruise, the start of a ramp, or the end of a ramp (exactly, between samples). lsm_interp_prepare plans
 * the next piece the interpolator will need into one slot, tagged with its switch point and the planner generation
 * it was planned for; lsm_interp_step takes it when it reaches that point. Called between cycles (from the
 * background, or before each step in a synchronous loop), it leaves the control cycle with no planning: the cycle
 * only evaluates. A cycle that reaches a switch point where a piece is needed and none is prepared plans it itself
 * (as a cycle without lsm_interp_prepare always does) and counts it in tick_plans, by cause (tick_cause[],
 * lsm_interp_tick_cause). The background prepares what the step will need, including where a first choice fails:
 *   - a hold (or replacement) that fits nowhere at the last switch point before the piece's end (a boundary, or a
 *     sample of its last cruise), when that end comes within the same cycle: the successor is planned in the same
 *     call (prep.skip_phase remembers a failed boundary; a failed sample is tried again at the next sample);
 *   - a stale piece (lsm_planner_piece_stale) that nothing fits in the hold or replan mode where the step must replace
 *     it (a sample, a ramp's end): the piece planned normally, as the step would;
 *   - a stale piece waits for its replacement prepared ahead, at a sample (lead_cycles) or at the start of the ramp
 *     that ends its cruise (a cruise shorter than lead_cycles + 1 cycles), and the step stops at a boundary only for
 *     a piece of the mode it asks for (a piece left from a hold since cancelled is not taken).
 * What remains for the step: TP_SHORT (the successor of a piece that started and ended in one cycle, which the one
 * slot held), TP_STALE (lead_cycles > 0 only) and TP_LATE (a request between lsm_interp_prepare and the step). Pieces planned ahead of a switch point
 * at lead_cycles > 0 leave the background that many cycles to finish.
 *
 * Feed override 0 .. 200 %: decreases take effect beyond the distance the machine needs to slow down, increases
 * at once; both through the planner, so every change is a verified sin² ramp (jerk-limited). 0 % is a feed hold.
 * Feed hold: at the next point where a = 0 the machine decelerates along the path with one ramp to rest (verified
 * against every block it crosses), then waits; resume starts again from rest on the path.
 * Ends: a stop (exact stop, end of buffer, end of program) puts the cursor exactly on its point, and the last
 * setpoint of the program is the programmed end (planner's tail position) bit for bit. An integer-count drive
 * converts each setpoint with one rounding, round(x * counts_per_mm): the last one is then the count of the
 * programmed end, i.e. 0 counts error by construction (no accumulated travel is converted).
 * Buffer underrun: the current piece already plans a stop at the end of the buffer (planner.h invariants), so the
 * machine stops cleanly there (IDLE) and restarts from rest by itself when blocks are appended (a block appended
 * while it decelerates only joins at speed if the planner verified that it still can from the interpolator's
 * commitment point; else the junction is an exact stop).
 *
 * Contexts. The interpolator and its planner are one context's (planner.h): lsm_interp_step, lsm_interp_prepare,
 * hold, resume and the override run in turn, never preempting each other. On a controller that is the background
 * (motion.h: the step runs lead_cycles ahead of the tick, whose hand-off is a ring of finished setpoints, mpipe.h);
 * in a synchronous loop (host simulator, the contour image) the cycle steps after the cycle's background work.
 * The step writes nothing of the planner's directly: what it used to set there (the blocks it is done with, its
 * commitment horizon, the acknowledgement of a stale piece) it posts as requests (planner.h, lsm_planner_req:
 * single writer, sequence counter), which the next planner call applies. It still reads the planner's tail, gen,
 * blocks and the prepared slot, and lsm_interp_prepare reads the step's cursor and pieces, with no hand-off of their
 * own: that is why a step may not preempt the background's calls on the same interpolator, and why the motion layer
 * moves the whole interpolator to the background rather than splitting it. A step that reaches a switch point with
 * no piece prepared plans it itself (tick_plans, tick_cause[]).
 *
 * Units: mm, s, rad.
 */
#ifndef LSM_INTERP_H
#define LSM_INTERP_H

#include "clothoid.h"
#include "planner.h"

typedef enum lsm_interp_state {
    LSM_INTERP_IDLE = 0, /* at rest, waiting for blocks (start, or underrun) */
    LSM_INTERP_RUN = 1,  /* moving */
    LSM_INTERP_HELD = 2, /* at rest after a feed hold (or 0 % override) */
    LSM_INTERP_DONE = 3  /* at rest on the end of a finished program */
} lsm_interp_state;

/* Where a prepared piece starts. */
typedef enum lsm_interp_switch {
    LSM_INTERP_SW_NONE = 0,
    LSM_INTERP_SW_SAMPLE = 1,   /* at the start of the cycle whose count is `cycle`, from the sample before it */
    LSM_INTERP_SW_BOUNDARY = 2, /* at phase boundary `phase` of the piece `serial` (1, 9: ramp starts; 8, 16: ramp
                                   ends; LSM_PIECE_PHASES: its end) */
    LSM_INTERP_SW_REST = 3      /* at rest: the next piece from the cursor */
} lsm_interp_switch;

/* A piece planned ahead (lsm_interp_prepare), which lives in the interpolator's second piece buffer, and the switch
 * point it starts at. */
typedef struct lsm_interp_prep {
    uint64_t cycle;  /* SW_SAMPLE: the cycle count it starts at */
    uint32_t serial; /* the piece it follows or replaces (SW_SAMPLE, SW_BOUNDARY); the last piece (SW_REST) */
    uint32_t gen;    /* planner generation it was planned for */
    uint32_t blk;    /* where it starts (block id, offset) and its speed there */
    lsm_real off_mm;
    lsm_real v_mm_s;
    uint8_t kind;       /* lsm_interp_switch */
    uint8_t phase;      /* SW_BOUNDARY */
    uint8_t ready;      /* the second piece buffer holds the piece */
    uint8_t failed;     /* no piece fits at this switch point for this generation (do not try again) */
    uint8_t mode;       /* lsm_piece_mode it was planned with */
    uint8_t skip_phase; /* SW_BOUNDARY: boundary skip_phase (before `phase`) of the same piece failed in mode skip_mode
                           for this generation, and the slot holds the piece needed after it (0: none) */
    uint8_t skip_mode;
    uint8_t reserved;
    uint32_t stale_seen; /* the planner's invalidation count when it was planned (lsm_planner_stale_count) */
} lsm_interp_prep;

/* Why lsm_interp_step planned a piece itself (lsm_interp.tick_cause[], which add up to tick_plans). With
 * lsm_interp_prepare called before every step and nothing requested between the two, only TP_SHORT (and TP_STALE
 * at lead_cycles > 0) can occur. */
typedef enum lsm_interp_tick_cause {
    LSM_INTERP_TP_NO_PREPARE = 0, /* lsm_interp_prepare is not in use: the step plans every piece */
    LSM_INTERP_TP_LATE = 1,       /* since the last lsm_interp_prepare the plan changed (an append, an override), a
                                     piece was invalidated, a hold or resume was requested, or a step ran without one */
    LSM_INTERP_TP_SHORT = 2,      /* the successor of a piece that started and ended inside the same cycle: the one
                                     slot held that piece when the background ran */
    LSM_INTERP_TP_MISSED = 3,     /* none of these: a piece the background should have prepared (a defect) */
    LSM_INTERP_TP_STALE = 4,      /* lead_cycles > 0: the current piece is stale and nothing fits in its mode where the
                                     background prepared its replacement ahead; the planner verified a piece only from
                                     the last sample (its commitment point), so the step replaces it there at once */
    LSM_INTERP_TP_CAUSES = 5
} lsm_interp_tick_cause;

typedef struct lsm_interp {
    lsm_planner *pl;
    lsm_piece pcs[2]; /* the piece being run (pcs[cur]) and the one planned ahead (the other): taking the
                                    prepared piece swaps them, no copy in the control cycle */
    uint8_t cur;
    uint8_t running;       /* pc is valid */
    uint8_t state;         /* lsm_interp_state */
    uint8_t hold_req;      /* feed hold requested (or 0 % override) */
    uint8_t ovr_zero;      /* the hold comes from a 0 % override */
    uint8_t phase;         /* current phase of pc */
    uint8_t gkind;         /* kind of the current block */
    uint16_t anchor;       /* cycles since the arc was re-anchored */
    uint32_t gen;          /* planner generation of pc */
    lsm_real tau;          /* time into the current phase at the last sample */
    lsm_real tau0;         /* float: tau = tau0 + tau_n dt (one rounding per sample, no drift), tau0 the ... */
    uint32_t tau_n;        /* ... phase-local time of the sample the count started at, tau_n the cycles since */
    lsm_real sloc;         /* travel into the current phase at the last sample */
    lsm_real sloc_lo;      /* float: what the additions to sloc rounded off (a cruise advances by v dt, compensated) */
    lsm_real rc, rs;       /* cos, sin of pi tau / T in a sin² phase (rotation recurrence) */
    lsm_real ce[2], se[2]; /* per ramp (A, B): cos, sin of pi e / T1 at a phase entry (e: entry offset) */
    lsm_real ee[2];        /* per ramp: e, the time from a phase start to its first sample, in [0, dt) */
    lsm_real cd[2], sd[2]; /* per ramp: cos, sin of pi / n1 (one cycle) */
    lsm_real nx_cd[2];     /* cd and sd of the piece planned ahead: computed where it is planned, ... */
    lsm_real nx_sd[2];     /* ... not in the cycle that takes it */
    lsm_real nx_sum[2];    /* float: the sum of that piece's phase lengths, hi + lo (exact) */
    lsm_real v_mm_s;       /* feed at the last sample */
    uint32_t act_blk;      /* the block whose geometry state (arc rotation, clothoid stepper) is set up */
    uint8_t act_ok;
    uint8_t reserved[3];
    /* act_b: that block (act_ok), live while the cursor is on it (only the interpolator releases blocks, and only
     * those before the cursor): the cycle needs no lookup */
    const lsm_pblock *act_b;
    uint32_t blk;        /* path cursor: block id ... */
    lsm_real off_mm;     /* ... and offset in it */
    lsm_real ds_stretch; /* float: (len - sum) / sum of the piece's phases: the travel is ds (1 + ds_stretch) */
    lsm_real off_lo_mm;  /* float: what the additions to off_mm rounded off (compensated sum: the cursor
                                    keeps the exact sum of the travel, no drift to snap back at a piece's end) */
    uint32_t hz_blk;     /* end of the current ramp (commitment horizon) */
    lsm_real hz_off;
    lsm_real hz_v;                           /* speed there (a = 0) */
    lsm_real aw;                             /* arc: dphi/ds */
    lsm_real a_p[3], a_A[3], a_B[3], a_L[3]; /* arc anchor: P_a, A, B, L (above) */
    lsm_real a_off;                          /* arc anchor: its offset s_a in the block */
    lsm_real a_len;                          /* arc: the block's length when the anchor was set (a trim re-anchors) */
    lsm_clothoid_stepper cs;                 /* clothoid stepper */
    lsm_real pos[LSM_MAX_AXES];              /* last setpoint */
    lsm_real ovr;                            /* requested override factor */
    uint64_t cycles;                         /* cycles stepped */
    uint32_t replans;                        /* pieces taken while moving (replanning) */
    uint32_t plan_errors;                    /* plan_piece calls that returned an error */
    uint32_t serial;                         /* pieces started */
    uint32_t lead_cycles;    /* SW_SAMPLE switch points are at least this many cycles ahead (0: the next one) */
    uint32_t tick_plans;     /* pieces planned inside lsm_interp_step (none were prepared) */
    uint8_t bg;              /* lsm_interp_prepare is in use: the cycle plans only what it must */
    uint8_t hz_posted_phase; /* the phase of the current piece whose horizon was posted whole (HZ_NOT_POSTED: none) */
    uint8_t reserved2[2];
    uint32_t prepared;                         /* pieces planned by lsm_interp_prepare */
    lsm_interp_prep prep;                      /* the slot of lsm_interp_prepare */
    uint32_t tick_cause[LSM_INTERP_TP_CAUSES]; /* tick_plans by cause (lsm_interp_tick_cause) */
    /* what the last lsm_interp_prepare saw, for TP_LATE: the step count, planner generation and hold request then */
    uint64_t bg_cycles;
    uint64_t took_cycle; /* the step count when a piece was last taken (TP_SHORT: in the current step) */
    uint32_t bg_gen;
    uint8_t bg_hold;
    uint8_t ovr_retry; /* the override ovr is not applied yet (LSM_E_PL_OVR_LATER): lsm_interp_prepare retries it */
    uint8_t ovr_gap;   /* new pieces from one retry to the next (1, doubling after each retry that fails, at most
                          LSM_INTERP_OVR_GAP_MAX) */
    uint8_t reserved3;
    uint32_t ovr_try_serial; /* the piece (serial) when it was last tried */
    uint32_t ovr_later;      /* override changes the planner could not apply at once (then retried) */
} lsm_interp;

/* Start at rest at the planner's start position. Errors: LSM_E_NULL. Background, while the cycle does not run. */
lsm_status lsm_interp_init(lsm_interp *ip, lsm_planner *pl);

/* One control cycle: writes LSM_MAX_AXES positions (mm, rad) and returns the state after the cycle. The context
 * that owns the interpolator (above: the background on a controller, running ahead of the tick; the cycle in a
 * synchronous loop). */
lsm_interp_state lsm_interp_step(lsm_interp *ip, lsm_real pos[LSM_MAX_AXES]);

/* Background work between cycles: plans the next piece the interpolator will need (see above). Returns LSM_OK (a
 * piece is ready, or nothing is needed), LSM_E_INFEASIBLE (none fits at the next switch point: the current plan
 * stays valid and is followed), LSM_E_NULL. At most one piece plan per call, two where the first fails and the piece's
 * end follows within the cycle (its successor: see above). Background. */
lsm_status lsm_interp_prepare(lsm_interp *ip);

/* Feed hold and resume. Resume while holding cancels the hold (a hold already decelerating completes first).
 * Background. */
void lsm_interp_hold(lsm_interp *ip);
void lsm_interp_resume(lsm_interp *ip);

/* Feed override factor 0 .. 2 (0 holds; leaving 0 resumes). Where the planner cannot apply it from the machine's
 * state (LSM_E_PL_OVR_LATER: rare, the plan stays as it was), it is kept and tried again until it applies or
 * another factor replaces it, by lsm_interp_prepare (without it: by the step, first, before it looks for its next
 * piece): after the next new piece, then after 2, 4, ... new pieces, at most LSM_INTERP_OVR_GAP_MAX apart, so that a
 * change that stays pending costs at most one planner override call (up to 8 backward passes) per
 * LSM_INTERP_OVR_GAP_MAX pieces, not one per piece. ovr_later counts these changes. Errors: LSM_E_NULL, LSM_E_NAN,
 * LSM_E_PL_OVERRIDE. Background. */
#define LSM_INTERP_OVR_GAP_MAX 16u

lsm_status lsm_interp_set_override(lsm_interp *ip, lsm_real factor);

/* Current feed along the path (mm/s) and state. Control cycle (or after it, in a synchronous loop). */
lsm_real lsm_interp_feed(const lsm_interp *ip);
lsm_interp_state lsm_interp_state_of(const lsm_interp *ip);

#endif /* LSM_INTERP_H */
