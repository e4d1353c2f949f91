/* interp.c: per-cycle interpolator (see interp.h). */
#include "interp.h"

#include <string.h>

#include "lsm_math.h"

#define PI_R ((lsm_real)LSM_PI)
#define R0 LSM_R(0.0)
#define R1 LSM_R(1.0)
#define ARC_ANCHOR_CYCLES 256u
#if LSM_REAL_IS_FLOAT
#define PATH_DS(ip, ds) ((ds) + (ds) * (ip)->ds_stretch) /* interp.h: the piece's phases scaled to its length */
#define PATH_LO(ip, ds) ((ds) * (ip)->ds_stretch) /* the cursor adds it to its low part: no rounding of ds (1 + e) */
#else
#define PATH_DS(ip, ds) (ds)
#define PATH_LO(ip, ds) R0
#endif
/* The cursor's exact offset is off_mm + off_lo_mm (float: a compensated sum); the evaluation uses both, so the
 * setpoints carry the rounding of the coordinates, not ulp(off_mm)/2 of the offset along the path (ulp(off) is
 * up to 16 ulp of the coordinates on an arc of three turns). The anchor's offset a_off is a float (exact), and
 * off_mm - a_off is exact (Sterbenz) within the anchor's range. */
#if LSM_REAL_IS_FLOAT
#define CURSOR_TERM(d, ip) ((d) * (ip)->off_mm + (d) * (ip)->off_lo_mm)
#define ARC_DS(ip) (((ip)->off_mm - (ip)->a_off) + (ip)->off_lo_mm)
#else
#define CURSOR_TERM(d, ip) ((d) * (ip)->off_mm)
#define ARC_DS(ip) ((ip)->off_mm - (ip)->a_off)
#endif
/* Float: phases that add up to less than their piece by at most this (relative) are stretched to it, like those that
 * add up to more are shrunk: the rounding of 17 float phase lengths, a few ulp, left the cursor short of the end by
 * up to 2e-4 mm on a 640 mm helix, a setpoint jump where end_piece put it on the end. 2^-20: 8 ulp, and within the
 * planner's 1e-6 relative margin on v, a and j (a larger shortfall is not rounding: it stays visible). */
#define DS_STRETCH_MAX LSM_R(9.5367431640625e-7)
#define ARC_ANCHOR_RAD LSM_R(0.25) /* float arcs: re-anchor beyond this angle (the polynomials' range) */
#define CLOTHOID_ANCHOR_STEPS 64u
/* the piece being run, and the buffer of the piece planned ahead */
/* A failed boundary's successor is prepared when the piece ends within this many cycles (the step crosses both in
 * one cycle; a margin for the rounding of the phase times, and planning it one cycle early costs nothing) */
#define SUCCESSOR_AHEAD_CYCLES LSM_R(2.0)
#define HZ_NOT_POSTED 0xFFu /* hz_posted_phase: no phase of the current piece posted its horizon whole yet */
#define CUR(ip) ((ip)->pcs[(ip)->cur])
#define NXT(ip) ((ip)->pcs[(ip)->cur ^ 1u])

static bool id_lt_pub(uint32_t a, uint32_t b)
{
    return (int32_t)(a - b) < 0;
}

static const lsm_pblock *bk(const lsm_interp *ip, uint32_t id)
{
    return lsm_planner_block(ip->pl, id);
}


#if LSM_REAL_IS_FLOAT
/* The travel of phase p of piece pc: its closed form at tau = T (the travel the cycle's steps add up to; sin(pi) = 0,
 * cos(pi) = -1 exactly). */
static lsm_real phase_len(const lsm_piece *pc, uint8_t p)
{
    const lsm_piece_phase *ph = &pc->ph[p];
    const lsm_kin *st = &pc->st[p];
    const lsm_real T = ph->T_s, sv = st->v_mm_s * T;
    if (p == 0u || p == 8u || p == LSM_PIECE_PHASES - 1u)
        return sv;
    lsm_real k = R1 / LSM_R(6.0); /* T^3 k: the jerk's share, t^3/6, or t^3/12 -+ t T^2/(2 pi^2) at t = T */
    if (ph->shape != LSM_PHASE_CONST)
        k = R1 / LSM_R(12.0) + (ph->shape == LSM_PHASE_RISE ? -R1 : R1) * (R1 / (LSM_R(2.0) * PI_R * PI_R));
    return sv + st->a_mm_s2 * T * T * LSM_R(0.5) + ph->jerk_mm_s3 * T * T * T * k;
}

/* Float, when a piece is planned (plan_switch): each phase's length becomes its closed-form travel (phase_len) and
 * each phase's start their sum, instead of the planner's: those come from piece-relative positions and carry their rounding, ulp(s) of
 * up to the whole piece (a 6e-5 mm phase length, negative, on a 586 mm helix, whose travel is 6e-6 mm), which the
 * cursor jumped by at the phase's end. Writes the piece's travel, their sum, as hi + lo. (The piece buffer is the
 * interpolator's; the planner only writes the other one.) */
static void own_phase_lengths(lsm_piece *pc, lsm_real sum[2])
{
    lsm_real s = R0, lo = R0; /* the sum, compensated (TwoSum): its rounding set the stretch off by 2 ulp of a 666 mm
                                 piece, the cursor ending 1.3e-4 mm beyond it */
    for (uint8_t p = 0; p < LSM_PIECE_PHASES; p++) {
        pc->st[p].s_mm = s;
        const lsm_real x = pc->ph[p].T_s > R0 ? phase_len(pc, p) : R0, t = s + x, xx = t - s;
        pc->ph[p].len_mm = x;
        lo += (s - (t - xx)) + (x - xx);
        s = t;
    }
    sum[0] = s;
    sum[1] = lo;
}
#endif

/* ---------------------------------------------------------------------------------------------------------- */
/* geometry of the current block                                                                               */

/* sin x and cos x - 1 of a small angle (|x| <= ARC_ANCHOR_RAD), cos x - 1 directly, without the cancellation of
 * cos x - 1. Float: Taylor to x^9 / x^10, error below 1e-9, under float's rounding. Double: to x^15 / x^16, error
 * below 1e-21 relative (double arcs are anchored the same way since the centre form, c + r u(phi), put ulp(r) of
 * noise into every setpoint: R 1e5 arcs showed 0.15 % of jerk on a 2e3 mm/s^3 axis at 0.5 ms). */
static void sincos_m1_small(lsm_real x, lsm_real *s, lsm_real *cm1)
{
    const lsm_real x2 = x * x;
#if LSM_REAL_IS_FLOAT
    const lsm_real ts = R1, tc = R1;
#else
    const lsm_real ts =
        R1 - x2 * (R1 / LSM_R(110.0)) * (R1 - x2 * (R1 / LSM_R(156.0)) * (R1 - x2 * (R1 / LSM_R(210.0))));
    const lsm_real tc =
        R1 - x2 * (R1 / LSM_R(132.0)) * (R1 - x2 * (R1 / LSM_R(182.0)) * (R1 - x2 * (R1 / LSM_R(240.0))));
#endif
    *s = x * (R1 - x2 * (R1 / LSM_R(6.0)) *
                       (R1 - x2 * (R1 / LSM_R(20.0)) *
                                 (R1 - x2 * (R1 / LSM_R(42.0)) * (R1 - x2 * (R1 / LSM_R(72.0)) * ts))));
    *cm1 = -x2 * LSM_R(0.5) *
           (R1 -
            x2 * (R1 / LSM_R(12.0)) *
                (R1 - x2 * (R1 / LSM_R(30.0)) * (R1 - x2 * (R1 / LSM_R(56.0)) * (R1 - x2 * (R1 / LSM_R(90.0)) * tc))));
}

/* The exact end of block id: where the next one starts (the end of the buffer for the last). */
static void block_end(const lsm_interp *ip, uint32_t id, lsm_real e[3])
{
    const lsm_pblock *n = id + 1u != ip->pl->tail ? bk(ip, id + 1u) : NULL;
    for (int i = 0; i < 3; i++) {
        if (n == NULL)
            e[i] = ip->pl->tail_pos[i];
        else if (n->g.kind == LSM_GEOM_LINE)
            e[i] = n->g.u.line.p0[i];
        else if (n->g.kind == LSM_GEOM_ARC)
            e[i] = n->g.u.arc.start_mm[i];
        else
            e[i] = n->g.u.clo.origin_mm[i];
    }
}

#if LSM_REAL_IS_FLOAT
/* a b = *hi + *lo exactly (Dekker's product with Veltkamp's split; + - * only, so the Cortex-M4F gives the same bits) */
static void two_prod(lsm_real a, lsm_real b, lsm_real *hi, lsm_real *lo)
{
    const lsm_real k = LSM_R(4097.0); /* 2^12 + 1: splits a float's 24 bits into 12 + 12 */
    const lsm_real ca = k * a, cb = k * b;
    const lsm_real ah = ca - (ca - a), al = a - ah, bh = cb - (cb - b), bl = b - bh;
    *hi = a * b;
    *lo = ((ah * bh - *hi) + ah * bl + al * bh) + al * bl;
}

/* The float arc at offset s along the curve the cycle evaluates (phase rate aw = sweep / len): its point p (the
 * chord from the start, geom.h) and, in (cp, sp), the unit vector's cos and sin of phi0 + aw s. The angle aw s is
 * carried as an exact sum hi + lo and added to phi0 by rotating (cos phi0, sin phi0): no rounding of the angle to
 * ulp(phi0 + aw s), which is 1e-6 rad at 16 rad, r 1e-6 of position (10 ulp of the coordinates seen on R 100
 * arcs at every re-anchoring). The angle's error is then a few ulp of 1 rad, whatever the sweep. */
static void arc_point(const lsm_interp *ip, const lsm_geom *g, lsm_real s, lsm_real p[3], lsm_real *cp, lsm_real *sp)
{
    const lsm_geom_arc *a = &g->u.arc;
    lsm_real dh, dl, s0, c0, sh, ch;
    two_prod(ip->aw, s, &dh, &dl);
    lsm_sincos(a->phi0_rad, &s0, &c0);
    lsm_sincos(LSM_R(0.5) * dh, &sh, &ch); /* the half angle (exact halving) ... */
    const lsm_real hl = LSM_R(0.5) * dl;   /* ... and its low part, to first order (hl^2 < 1e-12) */
    const lsm_real shc = sh + ch * hl, chc = ch - sh * hl;
    const lsm_real cm = c0 * chc - s0 * shc, sm = s0 * chc + c0 * shc; /* phi0 + half the angle */
    const lsm_real k = LSM_R(2.0) * a->radius_mm * shc, ax = a->axial_mm * (s / g->len);
    lsm_real n[3];
    lsm_cross3(a->e1, a->e2, n);
    for (int i = 0; i < 3; i++)
        p[i] = a->start_mm[i] + k * (cm * a->e2[i] - sm * a->e1[i]) + n[i] * ax;
    *cp = cm * chc - sm * shc;
    *sp = sm * chc + cm * shc;
}
#endif

/* Sets the float arc anchor at the cursor (interp.h); the end correction is computed afresh on a block's entry and
 * when its length changed (a trim), else kept from the previous anchor. */
static void arc_anchor(lsm_interp *ip, const lsm_geom *g)
{
    const lsm_geom_arc *a = &g->u.arc;
    lsm_real n[3];
    lsm_cross3(a->e1, a->e2, n);
    lsm_real c[3];
    ip->aw = a->sweep_rad / g->len;
    if (ip->anchor == 0u || g->len != ip->a_len) {
        lsm_real pe[LSM_MAX_AXES], e[3];
#if LSM_REAL_IS_FLOAT
        lsm_real ce, se;
        arc_point(ip, g, g->len, pe, &ce, &se);
#else
        (void)lsm_geom_eval(g, g->len, pe, NULL, NULL);
#endif
        block_end(ip, ip->blk, e);
        for (int i = 0; i < 3; i++)
            c[i] = (e[i] - pe[i]) / g->len;
    } else {
        for (int i = 0; i < 3; i++)
            c[i] = ip->a_L[i] - n[i] * (a->axial_mm / g->len);
    }
    ip->anchor = 0;
    ip->a_len = g->len;
    ip->a_off = ip->off_mm;
    lsm_real p[LSM_MAX_AXES];
    lsm_real sp, cp;
#if LSM_REAL_IS_FLOAT
    arc_point(ip, g, ip->a_off, p, &cp, &sp);
#else
    (void)lsm_geom_eval(g, ip->a_off, p, NULL, NULL);
    lsm_sincos(a->phi0_rad + ip->aw * ip->a_off, &sp, &cp);
#endif
    for (int i = 0; i < 3; i++) {
        const lsm_real corr = c[i];
        ip->a_p[i] = p[i] + corr * ip->a_off;
        ip->a_A[i] = a->radius_mm * (cp * a->e1[i] + sp * a->e2[i]);
        ip->a_B[i] = a->radius_mm * (cp * a->e2[i] - sp * a->e1[i]);
        ip->a_L[i] = n[i] * (a->axial_mm / g->len) + corr;
    }
}

static void activate(lsm_interp *ip)
{
    const lsm_pblock *b = bk(ip, ip->blk);
    if (b == NULL)
        return;
    ip->act_blk = ip->blk;
    ip->act_b = b;
    ip->act_ok = 1;
    const lsm_geom *g = &b->g;
    ip->gkind = g->kind;
    if (g->kind == LSM_GEOM_ARC) {
        ip->anchor = 0; /* a block entry: its end correction afresh */
        arc_anchor(ip, g);
    } else if (g->kind == LSM_GEOM_CLOTHOID) {
        lsm_clothoid seg;
        (void)lsm_clothoid_init(&seg, R0, R0, g->u.clo.theta0_rad, g->u.clo.kappa0_per_mm, g->u.clo.c_per_mm2, g->len);
        lsm_real s0 = ip->off_mm;
        if (s0 > g->len)
            s0 = g->len;
        if (s0 < R0)
            s0 = R0;
        (void)lsm_clothoid_stepper_init(&ip->cs, &seg, s0, CLOTHOID_ANCHOR_STEPS);
    }
}

/* Position of the current block b (the block ip->blk) at the cursor (after activate or an incremental update). */
static void eval_pos_in(lsm_interp *ip, const lsm_pblock *b)
{
    const lsm_geom *g = &b->g;
    if (g->kind == LSM_GEOM_LINE) {
        for (int i = 0; i < LSM_MAX_AXES; i++)
            ip->pos[i] = g->u.line.p0[i] + CURSOR_TERM(g->u.line.dir[i], ip);
    } else if (g->kind == LSM_GEOM_ARC) {
        const lsm_real ds = ARC_DS(ip);
        lsm_real sn, cm1;
        sincos_m1_small(ip->aw * ds, &sn, &cm1);
        for (int i = 0; i < 3; i++)
            ip->pos[i] = ip->a_p[i] + (cm1 * ip->a_A[i] + sn * ip->a_B[i] + ds * ip->a_L[i]);
    } else {
        const lsm_geom_clothoid *c = &g->u.clo;
        for (int i = 0; i < 3; i++)
            ip->pos[i] = c->origin_mm[i] + c->e1[i] * ip->cs.x_mm + c->e2[i] * ip->cs.y_mm;
    }
}

/* eval_pos_in on the block the cursor is on (none: nothing). */
static void eval_pos(lsm_interp *ip)
{
    const lsm_pblock *b = bk(ip, ip->blk);
    if (b != NULL)
        eval_pos_in(ip, b);
}

/* Moves the cursor by ds (>= 0) plus ds_lo (a small correction, float: the piece's stretch) and evaluates the position
 * there. */
static void advance_path(lsm_interp *ip, lsm_real ds, lsm_real ds_lo)
{
    if (!(ds > R0)) {
        ds = R0;
        ds_lo = R0;
    }
    const lsm_planner *pl = ip->pl;
    const lsm_pblock *b;
    if (ip->act_ok && ip->act_blk == ip->blk) {
        b = ip->act_b; /* the block set up at the cursor: still live (interp.h, act_b), no lookup */
    } else {
        b = bk(ip, ip->blk);
        if (b == NULL)
            return;
        activate(ip); /* (re)started on a block that was never set up */
    }
#if LSM_REAL_IS_FLOAT
    {
        const lsm_real y = ds + (ip->off_lo_mm + ds_lo), t = ip->off_mm + y;
        ip->off_lo_mm = y - (t - ip->off_mm); /* exact when |off| >= |y| (Fast2Sum), and when off is 0 */
        ip->off_mm = t;
    }
#else
    (void)ds_lo;
    ip->off_mm += ds;
#endif
    bool moved = false;
    while (ip->off_mm > b->g.len && ip->blk + 1u != pl->tail) {
        ip->off_mm -= b->g.len;
        ip->blk++;
        b = bk(ip, ip->blk);
        moved = true;
    }
    if (ip->off_mm > b->g.len) {
        ip->off_mm = b->g.len;
        ip->off_lo_mm = R0;
    }
    if (moved) {
        lsm_planner_post_release(ip->pl, ip->blk);
        activate(ip);
    } else if (ip->gkind == LSM_GEOM_ARC && ds > R0) {
        /* re-anchored every ARC_ANCHOR_CYCLES, before the angle leaves the polynomials' range, and when a corner
         * trimmed the block's end (its exact end moved) */
        if (++ip->anchor >= ARC_ANCHOR_CYCLES || lsm_fabs(ip->aw * (ip->off_mm - ip->a_off)) > ARC_ANCHOR_RAD ||
            b->g.len != ip->a_len)
            arc_anchor(ip, &b->g);
    } else if (ip->gkind == LSM_GEOM_CLOTHOID && ds > R0) {
        (void)lsm_clothoid_step(&ip->cs, ds + ds_lo, NULL); /* the stepper keeps its own s: the stretch is in it */
    }
    eval_pos_in(ip, b); /* b is the block at the cursor (looked up once per cycle: a lookup is a call and a division) */
}

/* Puts the cursor exactly on (id, off) and evaluates there. */
static void place(lsm_interp *ip, uint32_t id, lsm_real off)
{
    ip->blk = id;
    ip->off_mm = off;
    ip->off_lo_mm = R0;
    lsm_planner_post_release(ip->pl, id);
    activate(ip);
    eval_pos(ip);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* pieces                                                                                                      */

static bool is_ramp_phase(uint8_t p)
{
    return (p >= 1u && p <= 7u) || (p >= 9u && p <= 15u);
}

/* The cursor position `dist` ahead of the current one (for the commitment horizon). */
static void ahead(const lsm_interp *ip, lsm_real dist, uint32_t *id, lsm_real *off)
{
    uint32_t k = ip->blk;
    lsm_real o = ip->off_mm + dist;
    for (;;) {
        const lsm_pblock *b = bk(ip, k);
        if (b == NULL || o <= b->g.len || k + 1u == ip->pl->tail)
            break;
        o -= b->g.len;
        k++;
    }
    *id = k;
    *off = o;
}

/* Starts the piece planned ahead (the second buffer) whose first sample comes `first` after its start
 * (0 < first <= one cycle). */
static void start_piece(lsm_interp *ip, lsm_real first)
{
    const lsm_real dt = ip->pl->cfg.cycle_s;
    ip->cur ^= 1u;
    const lsm_piece *pc = &CUR(ip);
    ip->running = 1;
    ip->serial++;
    ip->hz_posted_phase = HZ_NOT_POSTED;
    lsm_planner_post_stale_ack(ip->pl, ip->prep.stale_seen); /* a piece planned on the geometry of then */
    ip->state = LSM_INTERP_RUN;
    ip->v_mm_s = pc->v0_mm_s;
    ip->phase = 0;
#if LSM_REAL_IS_FLOAT
    {
        const lsm_real sum = ip->nx_sum[0]; /* (piece_constants: this piece's own lengths, summed exactly) */
        const lsm_real d = (pc->len_mm - sum) - ip->nx_sum[1]; /* len - sum exact (Sterbenz: within 1e-5) */
        const bool fits = d < R0 || d <= DS_STRETCH_MAX * sum;
        ip->ds_stretch = pc->len_mm > R0 && sum > R0 && fits ? d / sum : R0;
    }
#endif
    ip->tau = R0;
    ip->tau0 = R0;
    ip->tau_n = 0;
    ip->sloc = R0;
    ip->sloc_lo = R0;
    ip->rc = R1;
    ip->rs = R0;
    /* per ramp: the offset of the samples to its phase starts, and the rotation step */
    lsm_real t0[2];
    t0[0] = CUR(ip).ph[0].T_s;
    t0[1] = t0[0];
    for (int i = 1; i <= 8; i++)
        t0[1] += CUR(ip).ph[i].T_s;
    for (int r = 0; r < 2; r++) {
        const uint32_t n1 = CUR(ip).ph[r == 0 ? 1 : 9].n_cycles;
        ip->ce[r] = R1;
        ip->se[r] = R0;
        ip->cd[r] = R1;
        ip->sd[r] = R0;
        if (n1) {
            /* samples at first + k dt; e = the first at or after the ramp start, minus the ramp start */
            /* e in [0, dt): the phases of a ramp are whole cycles, so every one of them is entered at e */
            lsm_real e = first - t0[r];
            e -= lsm_floor(e / dt) * dt;
            if (e < R0 || e >= dt)
                e = R0;
            ip->ee[r] = e;
            const lsm_real T1 = (lsm_real)n1 * dt;
            lsm_sincos(PI_R * e / T1, &ip->se[r], &ip->ce[r]); /* (the same bits as lsm_sin and lsm_cos) */
            ip->cd[r] = ip->nx_cd[r];                          /* plan_switch's, for this piece */
            ip->sd[r] = ip->nx_sd[r];
        }
    }
}

/* Anything left to move after the cursor? */
static bool path_ahead(const lsm_interp *ip)
{
    const lsm_planner *pl = ip->pl;
    if (pl->tail == pl->head)
        return false;
    if (id_lt_pub(ip->blk, pl->head))
        return true;
    const lsm_pblock *b = bk(ip, ip->blk);
    if (b == NULL)
        return false;
    return ip->blk + 1u != pl->tail || ip->off_mm < b->g.len;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* switch points: where a new piece may start (a = 0)                                                          */

typedef struct swpt {
    uint8_t kind;   /* lsm_interp_switch */
    uint8_t phase;  /* SW_BOUNDARY */
    uint8_t mode;   /* lsm_piece_mode */
    uint64_t cycle; /* SW_SAMPLE */
    uint32_t blk;   /* start (block, offset) and speed */
    lsm_real off;
    lsm_real v;
} swpt;

static bool is_cruise(uint8_t p)
{
    return p == 0u || p == 8u || p == LSM_PIECE_PHASES - 1u;
}

/* At a sample where a = 0 (in a cruise, or exactly at the start of a ramp)? */
static bool at_a_zero(const lsm_interp *ip)
{
    const uint8_t p = ip->phase;
    return is_cruise(p) || (ip->tau == R0 && (p == 1u || p == 9u));
}

/* Start from rest (or from a stop inside the program) wanted now? */
static bool rest_go(const lsm_interp *ip)
{
    const lsm_interp_state s = (lsm_interp_state)ip->state;
    if (s == LSM_INTERP_DONE)
        return false;
    if (s == LSM_INTERP_HELD && ip->hold_req)
        return false;
    if (s != LSM_INTERP_RUN && !path_ahead(ip))
        return false;
    return !(ip->v_mm_s == R0 && ip->hold_req);
}

/* The point of phase boundary b (1 .. LSM_PIECE_PHASES) of the current piece, seen from the last sample. */
static void boundary_point(const lsm_interp *ip, uint8_t b, swpt *w)
{
    w->kind = LSM_INTERP_SW_BOUNDARY;
    w->phase = b;
    if (b >= LSM_PIECE_PHASES) {
        w->blk = CUR(ip).end_blk;
        w->off = R0;
        w->v = CUR(ip).v1_mm_s;
        return;
    }
    if (is_ramp_phase(ip->phase) && b == (ip->phase < 8u ? 8u : 16u)) {
        /* the end of the current ramp: the commitment horizon, exactly the point appends verified */
        w->blk = ip->hz_blk;
        w->off = ip->hz_off;
        w->v = ip->hz_v;
        return;
    }
#if LSM_REAL_IS_FLOAT
    const lsm_real d = (CUR(ip).st[b].s_mm - (CUR(ip).st[ip->phase].s_mm + ip->sloc)) - ip->sloc_lo;
#else
    const lsm_real d = CUR(ip).st[b].s_mm - (CUR(ip).st[ip->phase].s_mm + ip->sloc);
#endif
    ahead(ip, d > R0 ? PATH_DS(ip, d) : R0, &w->blk, &w->off);
    w->v = CUR(ip).st[b].v_mm_s;
}

/* The first switch point of the current piece where a replacement can start, given the lead. */
static void replace_point(const lsm_interp *ip, swpt *w)
{
    const uint8_t p = ip->phase;
    const lsm_real dt = ip->pl->cfg.cycle_s;
    const uint32_t L = ip->lead_cycles;
    if (at_a_zero(ip)) {
        /* the sample L cycles ahead, if the cruise lasts that long (L = 0: the last sample itself) */
        const bool fits = L == 0u || (is_cruise(p) && ip->tau + (lsm_real)(L + 1u) * dt < CUR(ip).ph[p].T_s);
        if (fits) {
            w->kind = LSM_INTERP_SW_SAMPLE;
            w->cycle = ip->cycles + 1u + L;
            ahead(ip, PATH_DS(ip, CUR(ip).st[p].v_mm_s * (lsm_real)L * dt), &w->blk, &w->off);
            w->v = ip->v_mm_s;
            return;
        }
    }
    /* else the next boundary where a = 0: the start or the end of the next ramp, or the piece's end */
    uint8_t b = p < 1u ? 1u : p < 8u ? 8u : p < 9u ? 9u : p < 16u ? 16u : (uint8_t)LSM_PIECE_PHASES;
    boundary_point(ip, b, w);
}

/* The mode of a piece that replaces the rest of the current one: a hold if one is requested, else a replan. */
static inline uint8_t replace_mode(const lsm_interp *ip)
{
    return ip->hold_req ? LSM_PIECE_HOLD : LSM_PIECE_REPLAN;
}

/* What the interpolator needs next, and where; false: nothing. */
static bool next_switch(const lsm_interp *ip, swpt *w)
{
    const lsm_planner *pl = ip->pl;
    memset(w, 0, sizeof *w);
    w->mode = LSM_PIECE_NORMAL;
    if (!ip->running) {
        if (!rest_go(ip))
            return false;
        w->kind = LSM_INTERP_SW_REST;
        w->blk = ip->blk;
        w->off = ip->off_mm;
        if (id_lt_pub(w->blk, pl->head)) {
            w->blk = pl->head;
            w->off = R0;
        }
        w->v = ip->v_mm_s;
        return true;
    }
    if (CUR(ip).hold)
        return false; /* a hold runs to its end */
    if (ip->hold_req || ip->gen != pl->gen) {
        w->mode = replace_mode(ip);
        replace_point(ip, w);
        if (w->kind == LSM_INTERP_SW_BOUNDARY && w->phase >= LSM_PIECE_PHASES && CUR(ip).stop)
            return false; /* the piece ends at rest anyway: the next one starts from there */
        if (w->kind == LSM_INTERP_SW_BOUNDARY && w->phase >= LSM_PIECE_PHASES && w->mode == LSM_PIECE_REPLAN)
            w->mode = LSM_PIECE_NORMAL; /* the successor itself (a piece is needed there) */
        return true;
    }
    if (CUR(ip).step && ip->phase < 8u) {
        boundary_point(ip, 8u, w); /* a step of a staircase: re-plan at the end of its ramp */
        w->mode = LSM_PIECE_REPLAN;
        return true;
    }
    if (CUR(ip).stop)
        return false;
    boundary_point(ip, LSM_PIECE_PHASES, w);
    return true;
}

static bool same_switch(const lsm_interp *ip, const lsm_interp_prep *q, const swpt *w)
{
    if (q->kind != w->kind || q->gen != ip->pl->gen || q->mode != w->mode)
        return false; /* (a hold planned where a piece is needed keeps its mode even if it fell back to normal) */
    switch (w->kind) {
    case LSM_INTERP_SW_SAMPLE: return q->serial == ip->serial && q->cycle == w->cycle;
    case LSM_INTERP_SW_BOUNDARY: return q->serial == ip->serial && q->phase == w->phase;
    case LSM_INTERP_SW_REST: return q->serial == ip->serial && q->blk == w->blk && q->off_mm == w->off;
    default: return false;
    }
}

/* What the cycle needs of the piece just planned into the second buffer, computed with it (the background): per ramp
 * cos and sin of pi / n1 (start_piece), and in the float build its own phase lengths (own_phase_lengths). */
static void piece_constants(lsm_interp *ip)
{
    const lsm_piece *pc = &NXT(ip);
    for (int r = 0; r < 2; r++) {
        const uint32_t n1 = pc->ph[r == 0 ? 1 : 9].n_cycles;
        ip->nx_cd[r] = R1;
        ip->nx_sd[r] = R0;
        if (n1)
            lsm_sincos(PI_R / (lsm_real)n1, &ip->nx_sd[r], &ip->nx_cd[r]);
    }
#if LSM_REAL_IS_FLOAT
    own_phase_lengths(&NXT(ip), ip->nx_sum);
#endif
}

/* Will the step replace a stale current piece at switch point w (lsm_planner_piece_stale), planning it normally if
 * nothing fits in w's mode? At a sample (the step replaces a stale piece at a sample where a = 0, or waits for the one
 * prepared ahead) and at the end of a ramp (stop_at_boundary). */
static bool stale_replaces_at(const lsm_interp *ip, const swpt *w)
{
    if (!ip->running || CUR(ip).hold || !lsm_planner_piece_stale(ip->pl))
        return false;
    /* (a sample lead_cycles ahead is not: the planner verified a piece from the last sample, its commitment point, and
     * a normal piece planned further on may be its fallback stop; there the step replaces the piece at once) */
    return (w->kind == LSM_INTERP_SW_SAMPLE && w->cycle == ip->cycles + 1u) ||
           (w->kind == LSM_INTERP_SW_BOUNDARY && (w->phase == 8u || w->phase == 16u));
}

/* Plans the piece for switch point w into the slot. */
static lsm_status plan_switch(lsm_interp *ip, const swpt *w)
{
    lsm_interp_prep *q = &ip->prep;
    q->ready = 0;
    q->failed = 0;
    q->skip_phase = 0;
    q->kind = w->kind;
    q->mode = w->mode;
    q->phase = w->phase;
    q->cycle = w->cycle;
    q->serial = ip->serial;
    q->gen = ip->pl->gen;
    q->stale_seen = lsm_planner_stale_count(ip->pl);
    q->blk = w->blk;
    q->off_mm = w->off;
    q->v_mm_s = w->v;
    lsm_status st = lsm_planner_plan_piece(ip->pl, w->blk, w->off, w->v, (lsm_piece_mode)w->mode, &NXT(ip));
    const bool needed =
        w->kind == LSM_INTERP_SW_REST || (w->kind == LSM_INTERP_SW_BOUNDARY && w->phase >= LSM_PIECE_PHASES);
    /* A piece planned normally instead where nothing fits in w's mode: (a) a piece is needed here (the current one
     * ends) and no hold fits yet: go on normally (planned stops always exist), the hold takes effect at the next point
     * where a = 0; (b) the current piece is stale and the step must replace it here: what replacement_for would plan
     * in the step, planned here instead (the slot keeps w's mode: the step asks for it). */
    const bool hold_needed = w->mode == LSM_PIECE_HOLD && needed && w->v > R0;
    if (st != LSM_OK && (hold_needed || (w->mode != LSM_PIECE_NORMAL && ip->bg && stale_replaces_at(ip, w))))
        st = lsm_planner_plan_piece(ip->pl, w->blk, w->off, w->v, LSM_PIECE_NORMAL, &NXT(ip));
    if (st == LSM_E_INTERNAL) { /* a fallback piece (counted by the planner): it is still a verified stop */
        ip->plan_errors++;
        st = LSM_OK;
    }
    if (st == LSM_OK)
        piece_constants(ip); /* here, where the piece is planned: not in the cycle that takes it */
    if (st == LSM_OK && NXT(ip).T_s > R0) {
        q->ready = 1;
        return LSM_OK;
    }
    if (st == LSM_OK && w->mode == LSM_PIECE_HOLD) { /* a hold at rest: nothing to run */
        q->ready = 1;
        return LSM_OK;
    }
    q->failed = 1;
    return st == LSM_OK ? LSM_E_EMPTY : st;
}

/* Is switch point w one the background found infeasible before preparing the piece needed after it (prep.skip_phase)? */
static bool skipped(const lsm_interp *ip, const swpt *w)
{
    const lsm_interp_prep *q = &ip->prep;
    return w->kind == LSM_INTERP_SW_BOUNDARY && q->skip_phase != 0u && q->skip_phase == w->phase &&
           q->skip_mode == w->mode && q->kind == LSM_INTERP_SW_BOUNDARY && q->serial == ip->serial &&
           q->gen == ip->pl->gen;
}

/* Why the step plans a piece itself (interp.h, lsm_interp_tick_cause); `successor`: the piece after one that ended. */
static uint8_t tick_cause(const lsm_interp *ip, uint8_t hint)
{
    if (!ip->bg)
        return LSM_INTERP_TP_NO_PREPARE;
    if (ip->bg_cycles + 1u != ip->cycles || ip->bg_gen != ip->pl->gen || ip->bg_hold != ip->hold_req)
        return LSM_INTERP_TP_LATE; /* (a piece is made stale only with a new generation) */
    if (hint == LSM_INTERP_TP_SHORT)
        return ip->took_cycle == ip->cycles ? LSM_INTERP_TP_SHORT : LSM_INTERP_TP_MISSED;
    return hint;
}

/* A change of the override the planner could not apply (lsm_interp_set_override), tried again once the machine has run
 * ovr_gap new pieces since the last try; the gap doubles after each try that fails, up to LSM_INTERP_OVR_GAP_MAX.
 * Called first by lsm_interp_prepare, and without it first by the step, before either finds its switch point: a change
 * applied between finding the point and planning its piece would plan that piece from a point of the plan before it
 * (setpoint jumps and stalls, found by test_planner_undo's retries without lsm_interp_prepare). */
static void retry_override(lsm_interp *ip)
{
    if (!ip->ovr_retry || ip->ovr_zero || ip->serial - ip->ovr_try_serial < ip->ovr_gap)
        return;
    ip->ovr_try_serial = ip->serial;
    if (lsm_planner_set_override(ip->pl, ip->ovr, ip->blk, ip->v_mm_s) != LSM_E_PL_OVR_LATER)
        ip->ovr_retry = 0;
    else if (ip->ovr_gap < LSM_INTERP_OVR_GAP_MAX)
        ip->ovr_gap = (uint8_t)(ip->ovr_gap * 2u);
}

/* The prepared piece for switch point w, planning it now if it is not there (counted); NULL if none fits. */
static const lsm_interp_prep *piece_for(lsm_interp *ip, const swpt *w, uint8_t hint)
{
    lsm_interp_prep *q = &ip->prep;
    if (same_switch(ip, q, w)) {
        if (q->ready)
            return q;
        if (q->failed)
            return NULL;
    }
    if (skipped(ip, w))
        return NULL; /* failed in the background, which prepared the piece after it */
    ip->tick_plans++;
    ip->tick_cause[tick_cause(ip, hint)]++;
    return plan_switch(ip, w) == LSM_OK ? q : NULL;
}

/* piece_for, and where the geometry the current piece runs into has changed (piece_stale) and nothing fits in mode
 * w->mode, a piece planned normally instead: a new piece must start here (a verified one, or at worst a verified
 * stop). */
static const lsm_interp_prep *replacement_for(lsm_interp *ip, swpt *w, uint8_t hint)
{
    const lsm_interp_prep *q = piece_for(ip, w, hint);
    if ((q == NULL || !(NXT(ip).T_s > R0)) && lsm_planner_piece_stale(ip->pl)) {
        w->mode = LSM_PIECE_NORMAL;
        q = piece_for(ip, w, hint);
    }
    return q;
}

/* Is a piece of switch kind `kind` ready in the slot for the current piece and plan? */
static bool prep_ready(const lsm_interp *ip, uint8_t kind)
{
    const lsm_interp_prep *q = &ip->prep;
    return q->ready && q->kind == kind && q->serial == ip->serial && q->gen == ip->pl->gen;
}

/* A replacement prepared (lead_cycles > 0: the cruise was too short for the sample lead_cycles ahead) for the start of
 * the ramp that ends the current cruise, where the step stops for it (stop_at_boundary)? A stale piece waits for it as
 * for a sample prepared ahead: it comes sooner than that sample would. */
static bool ramp_start_ready(const lsm_interp *ip)
{
    const uint8_t p = ip->phase;
    const lsm_interp_prep *q = &ip->prep; /* (prep_ready, written out: a third caller kept it from being inlined) */
    if (!ip->bg || !(p == 0u || p == 8u) || !q->ready || q->kind != LSM_INTERP_SW_BOUNDARY)
        return false;
    return q->serial == ip->serial && q->gen == ip->pl->gen && q->phase == p + 1u && q->mode == replace_mode(ip);
}

/* Takes the prepared piece q at its start: the cursor exactly there, first sample `first` after it. */
static void take(lsm_interp *ip, const lsm_interp_prep *q, lsm_real first, bool replace)
{
    const uint32_t g = q->gen;
    ip->prep.ready = 0;
    ip->took_cycle = ip->cycles;
    if (replace)
        ip->replans++;
    ip->gen = g;
    if (!(NXT(ip).T_s > R0)) { /* a hold at rest */
        ip->running = 0;
        ip->v_mm_s = R0;
        ip->state = LSM_INTERP_HELD;
        return;
    }
    /* the cursor goes exactly onto the piece's start, unless rounding already carried it past (then that block may
     * have been released: the piece starts where the cursor is, within rounding of its start) */
    if (!(id_lt_pub(q->blk, ip->blk) || (q->blk == ip->blk && q->off_mm < ip->off_mm)))
        place(ip, q->blk, q->off_mm);
    start_piece(ip, first);
}

/* Stop the clock at boundary p (entered while advancing)? Only where a piece is prepared for it (or, without
 * lsm_interp_prepare, where one is wanted: the end of a ramp when the plan changed, or of a staircase step). */
static bool stop_at_boundary(lsm_interp *ip, uint8_t p)
{
    if (!(p == 1u || p == 8u || p == 9u || p == 16u))
        return false;
    if (prep_ready(ip, LSM_INTERP_SW_BOUNDARY) && ip->prep.phase == p && ip->prep.mode == replace_mode(ip))
        return true; /* (only a piece run_cycle will take: one for a hold since cancelled is not) */
    if ((p == 8u || p == 16u) && !CUR(ip).hold && lsm_planner_piece_stale(ip->pl))
        return true; /* the horizon of a piece whose path was trimmed beyond it: it must be replaced here */
    if (ip->bg)
        return false;
    if ((p == 8u || p == 16u) && !CUR(ip).hold && CUR(ip).st[p].s_mm > CUR(ip).st[p - 7u].s_mm)
        return ip->gen != ip->pl->gen || (p == 8u && CUR(ip).step);
    return false;
}

/* Travel of phase p at tau (phase-local); updates the rotation for sin² phases (entered: from the entry angle). */
static lsm_real phase_travel(lsm_interp *ip, uint8_t p, lsm_real tau, bool entered, lsm_real *v)
{
    const lsm_piece_phase *ph = &CUR(ip).ph[p];
    const lsm_kin *st = &CUR(ip).st[p];
    if (p == 0u || p == 8u || p == 16u) {
        *v = st->v_mm_s;
        return st->v_mm_s * tau;
    }
    lsm_real f, fv;
    if (ph->shape == LSM_PHASE_CONST) {
        f = tau * tau * tau / LSM_R(6.0);
        fv = tau * tau / LSM_R(2.0);
    } else {
        const int r = p < 8u ? 0 : 1;
        if (entered) {
            if (lsm_fabs(tau - ip->ee[r]) <= LSM_R(1e-6) * ip->pl->cfg.cycle_s) {
                ip->rc = ip->ce[r];
                ip->rs = ip->se[r];
            } else { /* rounding put the boundary on the other side of a sample */
                ip->rc = lsm_cos(PI_R * tau / ph->T_s);
                ip->rs = lsm_sin(PI_R * tau / ph->T_s);
            }
        } else {
            const lsm_real c = ip->rc * ip->cd[r] - ip->rs * ip->sd[r];
            ip->rs = ip->rs * ip->cd[r] + ip->rc * ip->sd[r];
            ip->rc = c;
        }
        const lsm_real T = ph->T_s;
        const lsm_real k8 = T * T / (LSM_R(2.0) * PI_R * PI_R);
        const lsm_real k16 = k8 * T / PI_R;
        const lsm_real sg = ph->shape == LSM_PHASE_RISE ? R1 : -R1;
        f = tau * tau * tau / LSM_R(12.0) - sg * tau * k8 + sg * ip->rs * k16;
        fv = tau * tau / LSM_R(4.0) - sg * (R1 - ip->rc) * k8;
    }
    const lsm_real jk = ph->jerk_mm_s3;
    *v = st->v_mm_s + st->a_mm_s2 * tau + jk * fv;
    return st->v_mm_s * tau + st->a_mm_s2 * tau * tau / LSM_R(2.0) + jk * f;
}

/* The phase clock advanced by dt_adv. Float: a whole cycle counts, tau = tau0 + n dt, so tau is one rounding off
 * its exact value at every sample; tau += dt drifted by up to ulp(tau)/2 per cycle, a velocity error of up to
 * ulp(tau) / (2 dt) relative (1e-4 at tau 2 s, dt 2 ms: a cruise at the axis limit went 0.1 mm/s over it), which
 * snapped back at the phase's end. Any other advance (the rest of a cycle) restarts the count there. */
static lsm_real phase_clock(lsm_interp *ip, lsm_real dt_adv)
{
#if LSM_REAL_IS_FLOAT
    const lsm_real dt = ip->pl->cfg.cycle_s;
    if (dt_adv == dt && ip->tau_n < UINT32_MAX) {
        ip->tau_n++;
        return ip->tau0 + (lsm_real)ip->tau_n * dt;
    }
    ip->tau0 = ip->tau + dt_adv;
    ip->tau_n = 0;
    return ip->tau0;
#else
    return ip->tau + dt_adv;
#endif
}

#if LSM_REAL_IS_FLOAT
/* One whole cycle in phase p, from the last sample (tau = tp) to tk = tp + dt: the travel s(tk) - s(tp) of
 * phase_travel's closed forms, written as dt times the mean rate over the cycle (tk^2 - tp^2 = dt (tk + tp),
 * tk^3 - tp^3 = dt (tk^2 + tk tp + tp^2)) plus, in a sin² phase, J sg T³/(2 pi³) times the step of the rotation's
 * sine. s(tk) - sloc rounded both to ulp(s) of the phase's travel, and tau's rounding moved s by v ulp(tau): on a
 * phase longer than the coordinates (a 285 mm cruise on an arc at coordinates of 73 mm, a 28 mm ramp phase at
 * 17 mm) 3-5 ulp of the coordinates of noise in every setpoint. Here the error is a few ulp of ds itself, and the
 * cursor sums exactly; sloc is summed compensated, so the phase's end takes up only what the steps' own rounding
 * drifted (a few ulp of ds per cycle, mostly cancelling). Updates the rotation and writes the velocity at tk. */
static lsm_real phase_step(lsm_interp *ip, uint8_t p, lsm_real tk, lsm_real *v)
{
    const lsm_kin *st = &CUR(ip).st[p];
    const lsm_real dt = ip->pl->cfg.cycle_s;
    lsm_real ds;
    if (is_cruise(p)) {
        *v = st->v_mm_s;
        ds = st->v_mm_s * dt;
    } else {
        const lsm_piece_phase *ph = &CUR(ip).ph[p];
        const lsm_real tp = ip->tau, jk = ph->jerk_mm_s3, q = tk * tk + tk * tp + tp * tp;
        const lsm_real rate = st->v_mm_s + st->a_mm_s2 * (LSM_R(0.5) * (tk + tp)), va = st->v_mm_s + st->a_mm_s2 * tk;
        if (ph->shape == LSM_PHASE_CONST) {
            *v = va + jk * (LSM_R(0.5) * tk * tk);
            ds = dt * (rate + jk * q * (R1 / LSM_R(6.0)));
        } else { /* the rotation one cycle on (phase_travel's recurrence), the sin² closed forms' steps */
            const int r = p < 8u ? 0 : 1;
            const lsm_real rs0 = ip->rs, c = ip->rc * ip->cd[r] - ip->rs * ip->sd[r];
            ip->rs = ip->rs * ip->cd[r] + ip->rc * ip->sd[r];
            ip->rc = c;
            const lsm_real T = ph->T_s, k8 = T * T * (R1 / (LSM_R(2.0) * PI_R * PI_R)), k16 = k8 * T * (R1 / PI_R);
            const lsm_real sgj = ph->shape == LSM_PHASE_RISE ? jk : -jk;
            *v = va + jk * (LSM_R(0.25) * tk * tk) - sgj * (R1 - c) * k8;
            ds = dt * (rate + jk * q * (R1 / LSM_R(12.0)) - sgj * k8) + sgj * k16 * (ip->rs - rs0);
        }
    }
    /* Fast2Sum: exact once sloc >= ds, i.e. after the phase's first cycle (before, the error is under ulp(ds)) */
    const lsm_real y = ds + ip->sloc_lo, t = ip->sloc + y;
    ip->sloc_lo = y - (t - ip->sloc);
    ip->sloc = t;
    return ds;
}
#endif

/*
 * Advances the piece clock by dt_adv; returns the distance travelled (ds >= 0 modulo rounding) and whether the
 * piece ended (then *left is the time beyond its end), or stopped at a boundary where a new piece starts
 * (*brk; *left as well).
 */
static lsm_real piece_advance(lsm_interp *ip, lsm_real dt_adv, bool *ended, lsm_real *left, bool *brk)
{
    lsm_real ds = R0;
    uint8_t p = ip->phase;
    lsm_real tau = phase_clock(ip, dt_adv);
    bool entered = false;
    *ended = false;
    *brk = false;
    while (p < LSM_PIECE_PHASES && tau >= CUR(ip).ph[p].T_s) {
        ds += (CUR(ip).ph[p].len_mm - ip->sloc) - ip->sloc_lo;
        tau -= CUR(ip).ph[p].T_s;
        ip->tau0 = tau; /* the count restarts at the first sample of the phase entered */
        ip->tau_n = 0;
        ip->sloc = R0;
        ip->sloc_lo = R0;
        p++;
        entered = true;
        if (p == 1u || p == 9u) {
            /* a ramp starts: committed until its end, where a = 0 again and a new piece may be taken (planner.h,
             * lsm_planner_set_horizon) */
            const int e = p == 1u ? 8 : 16;
            ip->hz_v = CUR(ip).st[e].v_mm_s;
            ahead(ip, PATH_DS(ip, CUR(ip).st[e].s_mm - CUR(ip).st[p].s_mm + ds), &ip->hz_blk, &ip->hz_off);
        }
        if (p < LSM_PIECE_PHASES && stop_at_boundary(ip, p)) {
            ip->phase = p;
            ip->tau = R0;
            ip->tau0 = R0;
            ip->tau_n = 0;
            *brk = true;
            *left = tau;
            return ds;
        }
    }
    ip->phase = p;
    if (p >= LSM_PIECE_PHASES) {
        *ended = true;
        *left = tau;
        ip->tau = R0;
        ip->tau0 = R0;
        ip->tau_n = 0;
        return ds;
    }
    lsm_real v;
#if LSM_REAL_IS_FLOAT
    if (!entered && ip->tau_n > 0u) {
        ds += phase_step(ip, p, tau, &v);
        ip->tau = tau;
        ip->v_mm_s = v;
        return ds;
    }
#endif
    const lsm_real s = phase_travel(ip, p, tau, entered, &v);
    ds += s - ip->sloc;
    ip->sloc = s;
    ip->sloc_lo = R0;
    ip->tau = tau;
    ip->v_mm_s = v;
    return ds;
}

/* After a piece: exact position at its end; state for a stop. */
static void end_piece(lsm_interp *ip)
{
    lsm_planner *pl = ip->pl;
    ip->running = 0;
    if (!CUR(ip).hold) {
        if (CUR(ip).end_blk == pl->tail) {
            const lsm_pblock *b = bk(ip, pl->tail - 1u);
            ip->blk = pl->tail - 1u;
            ip->off_mm = b ? b->g.len : R0;
            ip->off_lo_mm = R0;
            lsm_planner_post_release(pl, ip->blk);
            activate(ip);
            if (CUR(ip).stop) {
                for (int i = 0; i < LSM_MAX_AXES; i++) /* the programmed end, exactly */
                    ip->pos[i] = pl->tail_pos[i];
            } else {
                eval_pos(ip);
            }
        } else if (bk(ip, CUR(ip).end_blk) != NULL) {
            place(ip, CUR(ip).end_blk, R0);
        }
    }
    if (!CUR(ip).stop) {
        ip->v_mm_s = CUR(ip).v1_mm_s;
        return;
    }
    ip->v_mm_s = R0;
    if (CUR(ip).hold) {
        ip->state = LSM_INTERP_HELD;
    } else if (!path_ahead(ip)) {
        ip->state = pl->finished ? LSM_INTERP_DONE : LSM_INTERP_IDLE;
    } else {
        ip->state = LSM_INTERP_RUN; /* an exact stop inside the program: go on from rest */
    }
}

/* Posts the commitment horizon after a cycle that runs on in the current piece (lsm_planner_set_horizon): in a ramp
 * its end, in a cruise the cursor. Whole at the first cycle of each phase of a piece; then a ramp's horizon is
 * unchanged (set at the ramp's entry: posted again would change nothing) and a cruise's end is, so only the
 * cursor is posted (a whole post every cycle cost the cycle about 60 instructions). */
static void post_horizon(lsm_interp *ip)
{
    const uint8_t p = ip->phase;
    if (p == ip->hz_posted_phase) {
        if (!is_ramp_phase(p))
            lsm_planner_post_cursor(ip->pl, ip->blk, ip->off_mm, ip->v_mm_s);
        return;
    }
    ip->hz_posted_phase = p;
    if (is_ramp_phase(p))
        lsm_planner_post_horizon(ip->pl, ip->hz_blk, ip->hz_off, ip->hz_v, CUR(ip).end_blk, CUR(ip).v1_mm_s);
    else
        lsm_planner_post_horizon(ip->pl, ip->blk, ip->off_mm, ip->v_mm_s, CUR(ip).end_blk, CUR(ip).v1_mm_s);
}

/* Runs one cycle (or the rest `first` of it) of the current piece, chaining into the next pieces. */
static void run_cycle(lsm_interp *ip, lsm_real first)
{
    lsm_real adv = first;
    for (int guard = 0; guard < 8 && ip->running; guard++) {
        bool ended, brk;
        lsm_real left = R0;
        const lsm_real ds = piece_advance(ip, adv, &ended, &left, &brk);
        if (brk) {
            /* a new piece starts exactly at this boundary (a = 0), between two samples; the cursor is put on its
             * start before it moves there (rounding may carry it just past a block end, which would release it) */
            swpt w;
            memset(&w, 0, sizeof w);
            w.kind = LSM_INTERP_SW_BOUNDARY;
            w.phase = ip->phase;
            w.mode = replace_mode(ip);
            if (ip->phase == 8u || ip->phase == 16u) { /* the end of the ramp: the horizon, as verified */
                w.blk = ip->hz_blk;
                w.off = ip->hz_off;
                w.v = ip->hz_v;
            } else { /* the start of a ramp: ds beyond the last sample */
                ahead(ip, ds > R0 ? PATH_DS(ip, ds) : R0, &w.blk, &w.off);
                w.v = CUR(ip).st[ip->phase].v_mm_s;
            }
            const lsm_interp_prep *q = replacement_for(ip, &w, LSM_INTERP_TP_MISSED);
            if (q != NULL && NXT(ip).T_s > R0) {
                take(ip, q, left, true);
            } else {
                advance_path(ip, ds, PATH_LO(ip, ds));
                ip->gen = ip->pl->gen; /* once per boundary: the current piece stays valid if none was found */
            }
            adv = left;
            continue;
        }
        if (!ended) {
            advance_path(ip, ds, PATH_LO(ip, ds));
            post_horizon(ip);
            return;
        }
        end_piece(ip);
        if (CUR(ip).stop || !(left > R0))
            return;
        /* the next piece starts inside this cycle: take it (or plan it) and sample it at the rest of the cycle */
        swpt w;
        memset(&w, 0, sizeof w);
        w.kind = LSM_INTERP_SW_BOUNDARY;
        w.phase = LSM_PIECE_PHASES;
        w.mode = ip->hold_req ? LSM_PIECE_HOLD : LSM_PIECE_NORMAL;
        w.blk = ip->blk;
        w.off = ip->off_mm;
        w.v = ip->v_mm_s;
        const lsm_interp_prep *q =
            piece_for(ip, &w, LSM_INTERP_TP_SHORT); /* (serial is still the ended piece's: its successor) */
        if (q == NULL || !(NXT(ip).T_s > R0))
            return;
        take(ip, q, left, false);
        adv = left;
    }
}

/* ---------------------------------------------------------------------------------------------------------- */
/* public                                                                                                      */

lsm_status lsm_interp_init(lsm_interp *ip, lsm_planner *pl)
{
    if (ip == NULL || pl == NULL)
        return LSM_E_NULL;
    memset(ip, 0, sizeof *ip);
    ip->pl = pl;
    ip->hz_posted_phase = HZ_NOT_POSTED;
    ip->state = LSM_INTERP_IDLE;
    ip->blk = pl->head;
    ip->off_mm = R0;
    ip->ovr = R1;
    ip->ds_stretch = R0;
    for (int i = 0; i < LSM_MAX_AXES; i++)
        ip->pos[i] = pl->tail_pos[i];
    if (pl->tail != pl->head) {
        const lsm_pblock *b = bk(ip, pl->head);
        if (b && b->g.kind == LSM_GEOM_LINE)
            for (int i = 0; i < LSM_MAX_AXES; i++)
                ip->pos[i] = b->g.u.line.p0[i];
    }
    return LSM_OK;
}

lsm_interp_state lsm_interp_step(lsm_interp *ip, lsm_real pos[LSM_MAX_AXES])
{
    lsm_planner *pl = ip->pl;
    const lsm_real dt = pl->cfg.cycle_s;
    ip->cycles++;
    if (!ip->bg)
        retry_override(ip); /* without lsm_interp_prepare the step is the background too */
    if (!ip->running) {
        /* at rest or between pieces: start when there is something to do */
        bool go = false;
        if (ip->state == LSM_INTERP_RUN)
            go = true;
        else if (ip->state == LSM_INTERP_IDLE)
            go = path_ahead(ip);
        else if (ip->state == LSM_INTERP_HELD)
            go = !ip->hold_req && path_ahead(ip);
        if (ip->state == LSM_INTERP_IDLE && pl->finished && !path_ahead(ip))
            ip->state = LSM_INTERP_DONE;
        if (go && ip->state != LSM_INTERP_DONE) {
            if (id_lt_pub(ip->blk, pl->head)) {
                ip->blk = pl->head;
                ip->off_mm = R0;
                ip->off_lo_mm = R0;
                activate(ip);
            }
            swpt w;
            if (ip->v_mm_s == R0 && ip->hold_req) {
                ip->state = LSM_INTERP_HELD; /* a hold at rest */
            } else if (next_switch(ip, &w)) {
                const lsm_interp_prep *q = piece_for(ip, &w, LSM_INTERP_TP_MISSED);
                if (q != NULL && NXT(ip).T_s > R0)
                    take(ip, q, dt, false);
                else if (!path_ahead(ip))
                    ip->state = pl->finished ? LSM_INTERP_DONE : LSM_INTERP_IDLE;
            }
        }
        if (ip->running)
            run_cycle(ip, dt);
    } else {
        /* a new piece from the last sample (a = 0 there): prepared for this cycle, or (without lsm_interp_prepare)
         * wanted now */
        const lsm_interp_prep *q = &ip->prep;
        const bool sample_ready = prep_ready(ip, LSM_INTERP_SW_SAMPLE);
        if (sample_ready && q->cycle == ip->cycles) {
            take(ip, q, dt, true);
        } else if (at_a_zero(ip) && !CUR(ip).hold &&
                   ((lsm_planner_piece_stale(pl) && !(sample_ready && q->cycle > ip->cycles) &&
                     !ramp_start_ready(ip)) ||
                    (!ip->bg && (ip->hold_req || ip->gen != pl->gen)))) {
            /* (a stale piece waits for a replacement prepared for a sample still ahead in this cruise: planned
             * with the current plan, it is verified, and the rest of the cruise is not what changed) */
            swpt w;
            memset(&w, 0, sizeof w);
            w.kind = LSM_INTERP_SW_SAMPLE;
            w.cycle = ip->cycles;
            w.mode = replace_mode(ip);
            w.blk = ip->blk;
            w.off = ip->off_mm;
            w.v = ip->v_mm_s;
            /* (a stale piece at lead_cycles > 0 whose replacement prepared ahead failed: TP_STALE) */
            const bool stale_lead = ip->bg && ip->lead_cycles > 0u && lsm_planner_piece_stale(pl);
            q = replacement_for(ip, &w, stale_lead ? LSM_INTERP_TP_STALE : LSM_INTERP_TP_MISSED);
            if (q != NULL)
                take(ip, q, dt, true);
            else if (is_cruise(ip->phase) && w.mode == LSM_PIECE_REPLAN)
                ip->gen = pl->gen; /* in a cruise the current piece stays valid: no new try until a change */
        }
        if (ip->running)
            run_cycle(ip, dt);
    }
    if (!ip->running) { /* at rest (or stopped for good): the machine stands here */
        lsm_planner_post_horizon(pl, ip->blk, ip->off_mm, R0, ip->blk, R0);
        ip->hz_posted_phase = HZ_NOT_POSTED;
    }
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pos[i] = ip->pos[i];
    return (lsm_interp_state)ip->state;
}

/* Switch point w of the current piece (a boundary before its end, or a sample in its last cruise) failed: if the
 * piece's end comes within about a cycle, the step will cross both in one cycle, and needs the successor there.
 * Writes it into w; false if not. (Not for a stale piece's sample: the step tries that sample itself.) */
static bool successor_point(const lsm_interp *ip, swpt *w)
{
    const bool boundary = w->kind == LSM_INTERP_SW_BOUNDARY && w->phase < LSM_PIECE_PHASES;
    const bool sample = w->kind == LSM_INTERP_SW_SAMPLE && !lsm_planner_piece_stale(ip->pl);
    if (!(boundary || sample) || !ip->running || CUR(ip).stop || CUR(ip).hold)
        return false;
    lsm_real left = -ip->tau; /* time from the last sample to the piece's end */
    for (uint8_t p = ip->phase; p < LSM_PIECE_PHASES; p++)
        left += CUR(ip).ph[p].T_s;
    if (!(left <= SUCCESSOR_AHEAD_CYCLES * ip->pl->cfg.cycle_s))
        return false;
    const uint8_t mode = w->mode == LSM_PIECE_HOLD ? LSM_PIECE_HOLD : LSM_PIECE_NORMAL; /* (as next_switch) */
    boundary_point(ip, LSM_PIECE_PHASES, w);
    w->mode = mode;
    return true;
}

/* Switch point w failed (the slot says so): where the piece's end follows within about a cycle, its successor is
 * planned now, in the same call (the step would otherwise plan it: it crosses both in one cycle), and the slot
 * remembers w as failed (skip_phase). Returns LSM_OK if that successor is ready, else LSM_E_INFEASIBLE. */
static lsm_status prepare_successor(lsm_interp *ip, swpt *w)
{
    const uint8_t ph = w->phase, mode = w->mode;
    if (!successor_point(ip, w))
        return LSM_E_INFEASIBLE;
    ip->prepared++;
    const lsm_status st = plan_switch(ip, w);
    ip->prep.skip_phase = ph;
    ip->prep.skip_mode = mode;
    return st == LSM_OK ? LSM_OK : LSM_E_INFEASIBLE;
}

lsm_status lsm_interp_prepare(lsm_interp *ip)
{
    if (ip == NULL)
        return LSM_E_NULL;
    retry_override(ip);
    ip->bg = 1;
    ip->bg_cycles = ip->cycles;
    ip->bg_gen = ip->pl->gen;
    ip->bg_hold = ip->hold_req;
    swpt w;
    if (!next_switch(ip, &w))
        return LSM_OK;
    const lsm_interp_prep *q = &ip->prep;
    if (skipped(ip, &w) && !successor_point(ip, &w))
        return LSM_OK;
    if (same_switch(ip, q, &w))
        return q->ready ? LSM_OK : prepare_successor(ip, &w);
    /* a piece prepared for a cruise sample still ahead (lead_cycles) stays: the target moves on with every cycle */
    if (w.kind == LSM_INTERP_SW_SAMPLE && q->kind == LSM_INTERP_SW_SAMPLE && q->serial == ip->serial &&
        q->gen == ip->pl->gen && q->mode == w.mode && q->cycle > ip->cycles && (q->ready || q->failed))
        return q->ready ? LSM_OK : LSM_E_INFEASIBLE;
    ip->prepared++;
    const lsm_status st = plan_switch(ip, &w);
    if (st != LSM_OK && w.kind == LSM_INTERP_SW_SAMPLE && w.mode == LSM_PIECE_REPLAN && is_cruise(ip->phase))
        ip->gen = ip->pl->gen; /* in a cruise the current piece stays valid: accept the change */
    return st == LSM_OK ? LSM_OK : prepare_successor(ip, &w);
}

void lsm_interp_hold(lsm_interp *ip)
{
    if (ip)
        ip->hold_req = 1;
}

void lsm_interp_resume(lsm_interp *ip)
{
    if (ip == NULL)
        return;
    ip->hold_req = 0;
    ip->ovr_zero = 0;
}

lsm_status lsm_interp_set_override(lsm_interp *ip, lsm_real f)
{
    if (ip == NULL)
        return LSM_E_NULL;
    if (f != f)
        return LSM_E_NAN;
    if (!(f >= R0 && f <= LSM_R(2.0)))
        return LSM_E_PL_OVERRIDE;
    if (f == R0) {
        ip->hold_req = 1;
        ip->ovr_zero = 1;
        return LSM_OK;
    }
    if (ip->ovr_zero) {
        ip->ovr_zero = 0;
        ip->hold_req = 0;
    }
    ip->ovr = f;
    ip->ovr_retry = 0;
    const lsm_status st = lsm_planner_set_override(ip->pl, f, ip->blk, ip->v_mm_s);
    if (st != LSM_E_PL_OVR_LATER)
        return st;
    ip->ovr_later++;
    ip->ovr_retry = 1;
    ip->ovr_gap = 1;
    ip->ovr_try_serial = ip->serial;
    return LSM_OK;
}


lsm_real lsm_interp_feed(const lsm_interp *ip)
{
    return ip ? ip->v_mm_s : R0;
}

lsm_interp_state lsm_interp_state_of(const lsm_interp *ip)
{
    return ip ? (lsm_interp_state)ip->state : LSM_INTERP_IDLE;
}
