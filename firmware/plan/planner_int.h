/*
 * planner_int.h: private types and helpers of the look-ahead planner (planner.h has the model). Only the planner's
 * own files include this:
 *   planner.c     configuration, the public append entry points (validation), the interpolator's commitment
 *   plan_block.c  block intake: geometry bounds, budget coefficients, caps, the corner before a new block
 *   plan_fit.c    arc fitting of dense G1 polylines (arcfit.h)
 *   plan_ramp.c   pieces of path addressed by a position x; one sin² ramp and its verification; ramp placement
 *   plan_nodes.c  the backward pass: nodes, their W, the distance probes; the feed override
 *   plan_piece.c  the forward step: the piece to the next node, staircases, feed hold, the horizon check
 * Every function here runs in the background (never in the control-cycle interrupt), as the public calls that
 * use them. Units: mm, s (planner.h).
 */
#ifndef LSM_PLANNER_INT_H
#define LSM_PLANNER_INT_H

#include <string.h>

#include "lsm_math.h"
#include "planner.h"

#define PI_R ((lsm_real)LSM_PI)
#define R0 LSM_R(0.0)
#define R1 LSM_R(1.0)

/* Relative slack when comparing a speed with a cap (rounding of values that are equal by construction). */
#if LSM_REAL_IS_FLOAT
#define CAP_SLACK LSM_R(2e-6)
#define LEN_EPS LSM_R(1e-5)
/* A line too short to append: within a few ulp of its coordinates (its end minus its start is exact, so its
 * direction is well defined above that). LEN_EPS (84 eps) dropped 0.015 mm lines at 700 mm, and the program's
 * exact end with them. */
#define LINE_LEN_EPS (LSM_R(4.0) * LSM_REAL_EPS)
#else
#define CAP_SLACK LSM_R(1e-9)
#define LEN_EPS LSM_R(1e-9)
#define LINE_LEN_EPS LEN_EPS
#endif
/* Iteration caps of the ramp fitting and of the bisections. */
#define FIT_ITER 40
#define W_BISECT 14
#define VC_BISECT 12
#define STAIR_LEVELS 6
/* Searches over a speed stop when the bracket is this narrow (relative): W and cruise feeds a fraction of a percent
 * below the best cost a fraction of a percent of time, and every candidate is verified in full anyway. */
#define SPEED_RES LSM_R(0.004)

/* ---- storage: block ids are uint32 counters (they wrap); the ring slot of id is (head_slot + id - head) % cap -- */

static inline uint32_t slot_of(const lsm_planner *pl, uint32_t id)
{
    return (pl->head_slot + (uint32_t)(id - pl->head)) % pl->cap;
}

static inline lsm_pblock *blk(const lsm_planner *pl, uint32_t id)
{
    return &pl->blk[slot_of(pl, id)];
}

static inline bool id_lt(uint32_t a, uint32_t b)
{
    return (int32_t)(a - b) < 0;
}

/* Block id and every block after it changed (pushed, trimmed, or its node flag or W set): the piece memo
 * (lsm_planner_memo) stays only if its search read nothing from there on. Every write to a block calls this (or
 * lsm_pl_changed_all), and so does every change of what the caps and budgets read (override, limits). */
void lsm_pl_changed(lsm_planner *pl, uint32_t id);

static inline void lsm_pl_changed_all(lsm_planner *pl)
{
    pl->memo.ok = 0;
}

/* ---- the six budget coefficients of a block (planner.h, "Limits"), stored as bfloat16 rounded up ---- */

typedef struct coef {
    lsm_real aa, ba, aj, bj, gj, as; /* alpha_a, beta_a, alpha_j, beta_j, gamma_j, alpha_s */
} coef;

static inline lsm_real bf16_val(uint16_t h)
{
    const uint32_t u = (uint32_t)h << 16;
    float f;
    memcpy(&f, &u, sizeof f);
    return (lsm_real)f;
}

static inline void coef_get(const lsm_pblock *b, coef *c)
{
    c->aa = bf16_val(b->coef[0]);
    c->ba = bf16_val(b->coef[1]);
    c->aj = bf16_val(b->coef[2]);
    c->bj = bf16_val(b->coef[3]);
    c->gj = bf16_val(b->coef[4]);
    c->as = bf16_val(b->coef[5]);
}

/* ---- speed caps ---- */

/* Override factor that applies to block id. */
static inline lsm_real ovr_of(const lsm_planner *pl, uint32_t id)
{
    return id_lt(id, pl->ovr_switch) ? pl->ovr_near : pl->ovr_far;
}

/* Speed cap: min(F * o, cap_geo * min(o, 1)), with the feed part raised to `floor` (override catch-up). */
static inline lsm_real cap_floor(const lsm_planner *pl, uint32_t id, const lsm_pblock *b, lsm_real floor)
{
    const lsm_real o = ovr_of(pl, id);
    lsm_real c = b->cap_geo_mm_s * lsm_min2(o, R1);
    if (!(b->flags & LSM_PB_RAPID)) {
        lsm_real f = b->feed_mm_s * o;
        if (f < floor)
            f = floor;
        c = lsm_min2(c, f);
    }
    return c;
}

static inline lsm_real cap_of(const lsm_planner *pl, uint32_t id)
{
    return cap_floor(pl, id, blk(pl, id), R0);
}

/* ---- pieces of path: blocks addressed by a position x relative to a start (id0, off0) (plan_ramp.c) ---- */

typedef struct pctx {
    const lsm_planner *pl;
    uint32_t id0;    /* first block */
    lsm_real off0;   /* start offset in it */
    uint32_t id_end; /* one past the last block */
    lsm_real D;      /* length from the start to the start of id_end */
    lsm_real floor;  /* feed caps raised to this (override catch-up) */
    uint32_t cid;    /* cursor: block cid starts at x = cx */
    lsm_real cx;
} pctx;

void lsm_pl_pctx_init(pctx *pc, const lsm_planner *pl, uint32_t id0, lsm_real off0, uint32_t id_end);
/* Moves the cursor to the block that contains x (clamped to the piece's blocks). */
void lsm_pl_seek(pctx *pc, lsm_real x);
/* Lowest cap over [xa, xb]. */
lsm_real lsm_pl_range_cap(pctx *pc, lsm_real xa, lsm_real xb);
/* The end of the last block over [xa, xb] whose cap is below v (false: none). */
bool lsm_pl_last_below(pctx *pc, lsm_real xa, lsm_real xb, lsm_real v, lsm_real *x_end);
/* A cruise at v fits every cap over [xa, xb]. */
bool lsm_pl_region_ok(pctx *pc, lsm_real xa, lsm_real xb, lsm_real v);

/* ---- ramps: one sin² velocity change (plan_ramp.c) ---- */

typedef struct ramp {
    lsm_scurve_intervals iv;
    lsm_real v0, v1, jp; /* jp signed (eq 34 corrected) */
    lsm_real dist;       /* (v0 + v1) tp / 2 */
    lsm_real a_lim, j_lim, s_lim;
} ramp;

/* The budget ratios of block id over a sub-interval of a ramp whose ends are lo and hi (v, a, j: each between its
 * values there), as a ramp's check takes them: >= 1 where every axis's acceleration (ra) and jerk (rj) hold; below
 * 1, about the factor the ramp's peak may take (0: the speed is above the block's cap). The magnitude budgets of the
 * coefficients, and on a clothoid where they fail, the bounds in its Frenet frame, which credit the cancellation of
 * c v³ and 3 kappa v a and of j and kappa² v³ (planner.h, "Limits"; plan_ramp.c, check_block). */
void lsm_pl_block_ratios(const lsm_planner *pl, uint32_t id, const lsm_kin *lo, const lsm_kin *hi, lsm_real *ra,
                         lsm_real *rj);
/* What one verification of a ramp found (lsm_pl_ramp_verify): ok (every budget and cap holds), or a speed above a
 * block's cap (vviol: that block's extent [vx0, vx1] and its cap vcap), else the ratios the ramp's a, j and snap may
 * take (>= 1: that budget holds). */
typedef struct lsm_pl_verdict {
    bool ok, vviol;
    lsm_real ra, rj, rs, vx0, vx1, vcap;
} lsm_pl_verdict;

/* The verification of ramp r placed at x_s as the ramp fitting runs it, with its shortcuts (quick) or without (the
 * full walk: every phase, and in parts where the whole fails); for the tests (tests/plan/test_plan_verify.c: the two
 * agree on what the fitting uses, and leave the cursor of pc in the same state). */
void lsm_pl_ramp_verify(pctx *pc, const ramp *r, lsm_real x_s, bool quick, lsm_pl_verdict *out);
/* Plans v0 -> v1 with the tangential limits a, j, s (strict whole-cycle rule); false if none. */
bool lsm_pl_ramp_plan(ramp *r, lsm_real dt, lsm_real v0, lsm_real v1, lsm_real a, lsm_real j, lsm_real s);
/* First guess of the tangential limits near x: the block's budgets at rest. */
void lsm_pl_guess_limits(pctx *pc, lsm_real x, lsm_real *a, lsm_real *j, lsm_real *s);
/* Decelerating ramp v0 -> v1 on [X0, X1], as late as it verifies (ending at X1 when exact); its start in *xs_out. */
bool lsm_pl_fit_decel(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, bool exact, bool check_lead,
                      ramp *r, lsm_real *xs_out);
/* Accelerating ramp v0 -> v1 from X0 on, as early as it verifies; its start in *xs_out. */
bool lsm_pl_fit_accel(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, bool check_trail, ramp *r,
                      lsm_real *xs_out);
/* Moves *xs, the start of the accelerating ramp r, past every block whose cap the ramp would exceed there as its
 * verification tests the caps (one pass over the blocks: plan_ramp.c); false: a cap below its start speed is in the
 * way, it starts from rest and would have to move, or it no longer fits before X1 (*xs: the start it was moved to).
 * X0: the start of the stretch (the rounding tolerance of the fit, as in the fitting). */
bool lsm_pl_accel_past_caps(pctx *pc, const ramp *r, lsm_real X0, lsm_real X1, lsm_real *xs);
/* Decelerating ramp starting exactly at X0 (override catch-up, feed hold). */
bool lsm_pl_fit_decel_now(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, ramp *r);

/* ---- nodes and the backward pass (plan_nodes.c) ---- */

/* Highest speed in [w, vmax] from which one continuous ramp to w fits in D (a first probe of the searches). */
lsm_real lsm_pl_speed_for_dist(lsm_real w, lsm_real D, lsm_real a, lsm_real j, lsm_real s, lsm_real vmax);
/* Highest cruise in [max(v0, v1), vmax] for which two continuous ramps v0 -> vc -> v1 fit in D. */
lsm_real lsm_pl_cruise_for_dist(lsm_real v0, lsm_real v1, lsm_real D, lsm_real a, lsm_real j, lsm_real s,
                                lsm_real vmax);
/* The test of a node's W for speed v over the piece pc (to the next node, whose W is w1). */
bool lsm_pl_w_test(pctx *pc, lsm_real v, lsm_real w1, bool exact, ramp *r, lsm_real *xs);
/* Can a piece that arrives at node id (a = 0) at speed v go on? */
bool lsm_pl_arrival_ok(lsm_planner *pl, uint32_t id, lsm_real v);
/* Marks the interpolator's current piece stale (planner.h, stale_set). Background. */
void lsm_pl_mark_stale(lsm_planner *pl);
void lsm_pl_backward_pass(lsm_planner *pl);

/* The W of the first nodes from the end of the interpolator's current piece on, as they were before a trial that may
 * be undone: an override change (plan_nodes.c, lsm_planner_set_override) or an append whose junction is then made an
 * exact stop (plan_block.c, lsm_pl_append_geom). A W is not a function of the caps alone: node_w starts from the
 * node's previous W and feasibility is not monotone in the speed, so a fresh pass over the restored blocks after the
 * trial can find a lower W than the one the machine is committed to. Override (seed 30028): 4.7794 instead of 4.78458
 * mm/s at the node after the current piece's end, from which that end speed, 5.01285 mm/s, could no longer go on.
 * Append (path soak, seed 82649, "underrun lines" case 7, with the clothoid direction bound): 18.0005 instead of
 * 18.0714 mm/s at the end of the current piece itself, where the machine arrived at 18.0714 mm/s and no piece was
 * found. Either way the machine stood still. Put back as the nodes' previous W before the restoring pass
 * (lsm_pl_wseed_put), each is found again where it is still verified against the node after it. The nodes beyond the
 * 16th are searched afresh and may come out lower (certified: a slower plan there). Background. */
#define LSM_PL_SEED_NODES 16 /* the first links of the chain the commitment rests on (16 x 8 B of background stack) */
typedef struct lsm_pl_wseed {
    uint32_t n;
    uint32_t id[LSM_PL_SEED_NODES];
    lsm_real w[LSM_PL_SEED_NODES];
} lsm_pl_wseed;
void lsm_pl_wseed_take(const lsm_planner *pl, lsm_pl_wseed *s);
void lsm_pl_wseed_put(lsm_planner *pl, const lsm_pl_wseed *s);

/* Fault injection, in test builds only (tests/plan, test_planner_undo): true while *left > 0, counting it down. The
 * hooks: plan_nodes.c ovr_fail_injected (override switch searches failed), plan_block.c hz_stop_injected (appends made
 * exact stops); in other builds each is a constant false. */
#ifdef LSM_TEST_OVR_UNDO
static inline bool lsm_pl_fault_take(unsigned *left)
{
    if (*left == 0u)
        return false;
    (*left)--;
    return true;
}
#endif

/* The midpoint of a bisection over [lo, hi], or the first time the probe when it lies inside the bracket (the
 * bracket only narrows: a probe outside it stays outside, so it is used at most once). */
static inline lsm_real probe_mid(lsm_real lo, lsm_real hi, lsm_real *probe)
{
    const lsm_real p = *probe;
    *probe = R0;
    return p > lo && p < hi ? p : (lo + hi) / LSM_R(2.0);
}

/* ---- the forward step (plan_piece.c) ---- */

/* The node after block `after` (exclusive) and its W; tail: the end of the buffer (W = 0). */
uint32_t lsm_pl_node_after(const lsm_planner *pl, uint32_t after, lsm_real *w);
/* Does a verified piece start at the interpolator's commitment point? */
bool lsm_pl_horizon_feasible(lsm_planner *pl, bool force);

/* ---- intake (plan_block.c, plan_fit.c) and the commitment (planner.c) ---- */

lsm_status lsm_pl_check_vals(const lsm_real *v, int n);
/* Appends g (which starts at tail_pos; not changed: with a corner the block pushed is a trimmed copy), with corner
 * handling at its start. prog_end: its programmed end. */
lsm_status lsm_pl_append_geom(lsm_planner *pl, const lsm_geom *g, const lsm_planner_move *mv,
                              const lsm_real prog_end[6], const lsm_arcfit_result *fr);
/* The geometric end of g (which starts at start) in end; true when it is the programmed end prog_end within
 * rounding (it is then taken as exactly that point). */
bool lsm_pl_geom_end(const lsm_geom *g, const lsm_real start[LSM_MAX_AXES], const lsm_real prog_end[LSM_MAX_AXES],
                     lsm_real end[LSM_MAX_AXES]);
/* Emits the first n pending polyline points. */
lsm_status lsm_pl_emit_run(lsm_planner *pl, uint32_t n);
/* Emits the whole pending run so that it ends exactly on its last point (end of program). */
lsm_status lsm_pl_emit_run_exact(lsm_planner *pl);
/* Slots the pending run takes when it is emitted. */
uint32_t lsm_pl_run_slots(const lsm_planner *pl);
/* A line that may join the pending polyline run. */
lsm_status lsm_pl_append_line_fit(lsm_planner *pl, lsm_geom *g, const lsm_real end[LSM_MAX_AXES],
                                  const lsm_planner_move *mv);
/* Appends g (lsm_pl_append_geom), or holds it for the next planner call when this call already pushed a block
 * (planner.c, "one block per append"). */
lsm_status lsm_pl_push_or_hold(lsm_planner *pl, lsm_geom *g, const lsm_planner_move *mv, const lsm_real prog_end[6]);
/* Does the interpolator's current piece still end where it may go on? */
bool lsm_pl_commitment_kept(lsm_planner *pl);
/* Kept, or a verified piece starts at the interpolator's horizon (the current piece is then marked stale)? */
bool lsm_pl_commitment_ok(lsm_planner *pl);

#endif /* LSM_PLANNER_INT_H */
