/* plan_ramp.c: pieces of path addressed by a position x, one sin² ramp, and its verification against the
 * budgets of every block it crosses (planner.h, "Limits"); ramps fitted and placed on a stretch of path. */
#include "planner_int.h"

/* Longest ramp accepted (cycles): far beyond any real velocity change; keeps the cycle counts in range. */
#define RAMP_MAX_CYCLES 0x1000000u
/* When 3 beta_j v |a| takes more than CROSS_SHARE_MAX of the jerk room, the acceleration is lowered so that it takes
 * CROSS_SHARE_TARGET of it (and the jerk the rest): balancing the two instead of starving the jerk. */
#define CROSS_SHARE_MAX LSM_R(0.9)
#define CROSS_SHARE_TARGET LSM_R(0.5)
/* Position at a speed: Newton steps stop below this share of a cycle, after at most SPEED_POS_ITER steps. */
#define SPEED_POS_TOL_CYCLES LSM_R(1e-7)
#define SPEED_POS_ITER 24
/* Rescaling after a failed check: just below the measured ratio first; after RESCALE_FINE_ITER tries, bigger
 * steps (whole-cycle quantisation can keep the peaks where they were). */
#define RESCALE_FINE LSM_R(0.995)
#define RESCALE_COARSE LSM_R(0.9)
#define RESCALE_FINE_ITER 12
/* A phase whose ratios as a whole are at least those a failing check has found (capped at 1) times 1 +
 * PARTS_SKIP_SLACK is not checked in parts (parts_covered): the slack covers the rounding of the parts' ends, which
 * are within the whole's in exact arithmetic (float: 1e-3 is over 10^4 ulp). */
#define PARTS_SKIP_SLACK LSM_R(1e-3)
/* Limits below this are no ramp at all (the fit gives up). */
#define LIMIT_FLOOR LSM_R(1e-9)
/* Tuning up a verified ramp: only when a ratio leaves this much room, to just below it, by at most TUNE_UP_MAX at a
 * time and at most TUNE_UPS times (each try costs a full verification). */
#define TUNE_UP_ROOM LSM_R(1.2)
#define TUNE_UP_SHARE LSM_R(0.99)
#define TUNE_UP_MAX LSM_R(8.0)
#define TUNE_UPS 2
/* A ramp moved off a block that caps it moves at least this much (relative): progress of the placement loops. */
#define MOVE_NUDGE LSM_R(1e-6)
/* The vector bounds of a clothoid (plane_limits) are used with this share of the smallest limit: they are computed
 * in lsm_real from the geometry (not rounded up like the coefficients), so this covers their rounding. */
#define VEC_LIMIT_SHARE (R1 - LSM_R(64.0) * LSM_REAL_EPS)
/* Tangential limits of a block whose axes do not bound them (no motion along any limited axis): very large. */
#define UNBOUNDED_A LSM_R(1e12)
#define UNBOUNDED_J LSM_R(1e15)
#define UNBOUNDED_S LSM_R(1e18)

/* ------------------------------------------------------------------------------------------------------------ */
/* pieces of path: blocks addressed by a position x relative to a start (id0, off0)                             */

void lsm_pl_pctx_init(pctx *pc, const lsm_planner *pl, uint32_t id0, lsm_real off0, uint32_t id_end)
{
    pc->pl = pl;
    pc->id0 = id0;
    pc->off0 = off0;
    pc->id_end = id_end;
    pc->floor = R0;
    pc->cid = id0;
    pc->cx = -off0;
    lsm_real d = -off0;
    for (uint32_t id = id0; id != id_end; id++)
        d += blk(pl, id)->g.len;
    pc->D = d;
}

/* Moves the cursor to the block that contains x (clamped to the piece's blocks). */
void lsm_pl_seek(pctx *pc, lsm_real x)
{
    const lsm_planner *pl = pc->pl;
    while (pc->cid != pc->id0 && x < pc->cx) {
        pc->cid--;
        pc->cx -= blk(pl, pc->cid)->g.len;
    }
    for (;;) {
        const lsm_real len = blk(pl, pc->cid)->g.len;
        if (x < pc->cx + len || pc->cid + 1u == pc->id_end)
            break;
        pc->cx += len;
        pc->cid++;
    }
}

/* Lowest cap over [xa, xb]. */
lsm_real lsm_pl_range_cap(pctx *pc, lsm_real xa, lsm_real xb)
{
    lsm_pl_seek(pc, xa);
    lsm_real m = LSM_REAL_MAX;
    uint32_t id = pc->cid;
    lsm_real x = pc->cx;
    for (;;) {
        const lsm_pblock *b = blk(pc->pl, id);
        m = lsm_min2(m, cap_floor(pc->pl, id, b, pc->floor));
        x += b->g.len;
        id++;
        if (!(x < xb) || id == pc->id_end)
            break;
    }
    return m;
}

bool lsm_pl_last_below(pctx *pc, lsm_real xa, lsm_real xb, lsm_real v, lsm_real *x_end)
{
    lsm_pl_seek(pc, xa);
    uint32_t id = pc->cid;
    lsm_real x = pc->cx;
    bool found = false;
    for (;;) {
        const lsm_pblock *b = blk(pc->pl, id);
        x += b->g.len;
        if (v > cap_floor(pc->pl, id, b, pc->floor) * (R1 + CAP_SLACK)) {
            found = true;
            *x_end = x;
        }
        id++;
        if (!(x < xb) || id == pc->id_end)
            break;
    }
    return found;
}

bool lsm_pl_region_ok(pctx *pc, lsm_real xa, lsm_real xb, lsm_real v)
{
    if (!(v > R0))
        return true;
    if (xb < xa)
        return true;
    return v <= lsm_pl_range_cap(pc, xa, xb) * (R1 + CAP_SLACK);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* ramps: one sin² velocity change                                                                              */

bool lsm_pl_ramp_plan(ramp *r, lsm_real dt, lsm_real v0, lsm_real v1, lsm_real a, lsm_real j, lsm_real s)
{
    r->v0 = v0;
    r->v1 = v1;
    r->a_lim = a;
    r->j_lim = j;
    r->s_lim = s;
    const lsm_real dv = lsm_fabs(v1 - v0);
    r->iv.n1_cycles = r->iv.n2_cycles = r->iv.n4_cycles = 0;
    r->jp = R0;
    r->dist = R0;
    if (!(dv > R0))
        return true;
    if (!(a > R0) || !(j > R0) || !(s > R0))
        return false;
    const lsm_scurve_limits lim = {a, j, s};
    if (!lsm_scurve_strict_intervals(&lim, dt, dv, &r->iv))
        return false;
    const uint32_t n = lsm_scurve_total_cycles(&r->iv);
    if (n == 0 || n > RAMP_MAX_CYCLES)
        return false;
    r->jp = (v1 - v0) / lsm_scurve_jerk_den(&r->iv, dt);
    r->dist = (v0 + v1) * (lsm_real)n * dt / LSM_R(2.0);
    return true;
}

static lsm_real ramp_apeak(const ramp *r, lsm_real dt)
{
    return lsm_fabs(r->jp) * (lsm_real)(r->iv.n1_cycles + r->iv.n2_cycles) * dt;
}

static lsm_real ramp_speak(const ramp *r, lsm_real dt)
{
    if (r->iv.n1_cycles == 0)
        return R0;
    return lsm_fabs(r->jp) * PI_R / (LSM_R(2.0) * (lsm_real)r->iv.n1_cycles * dt);
}

/* sin and cos of pi q / 8, q = 0..8 */
static const lsm_real k_sin8[9] =
    {LSM_R(0.0), LSM_R(0.38268343236508977), LSM_R(0.70710678118654752), LSM_R(0.92387953251128676),
     LSM_R(1.0), LSM_R(0.92387953251128676), LSM_R(0.70710678118654752), LSM_R(0.38268343236508977),
     LSM_R(0.0)};
static const lsm_real k_cos8[9] =
    {LSM_R(1.0), LSM_R(0.92387953251128676),  LSM_R(0.70710678118654752),  LSM_R(0.38268343236508977),
     LSM_R(0.0), LSM_R(-0.38268343236508977), LSM_R(-0.70710678118654752), LSM_R(-0.92387953251128676),
     LSM_R(-1.0)};

/* What the state of a phase at a time tau into it (phase_at) needs beyond tau: its length T, and for sin² phases the
 * sign of its shape and the denominators 4 w, 8 w², 16 w³ (w = pi / (2 T)), computed once per phase (the same
 * expressions on the same inputs as per part: the same values). */
typedef struct phase_form {
    const lsm_phase *ph;
    lsm_real T, sg, d1, d2, d3;
} phase_form;

static void phase_form_of(const lsm_phase *ph, lsm_real dt, phase_form *f)
{
    f->ph = ph;
    f->T = (lsm_real)ph->n_cycles * dt;
    if (ph->shape == LSM_PHASE_CONST)
        return;
    const lsm_real w = PI_R / (LSM_R(2.0) * f->T);
    f->sg = ph->shape == LSM_PHASE_RISE ? R1 : -R1;
    f->d1 = LSM_R(4.0) * w;
    f->d2 = LSM_R(8.0) * w * w;
    f->d3 = LSM_R(16.0) * w * w * w;
}

/* State after tau into the phase f, given sin and cos of phi = pi tau / T (sin² phases). */
static void phase_at(const phase_form *f, const lsm_kin *s0, lsm_real tau, lsm_real sphi, lsm_real cphi, lsm_kin *out)
{
    lsm_real u0, u1, u2, u3;
    const lsm_real t = tau;
    if (f->ph->shape == LSM_PHASE_CONST) {
        u0 = R1;
        u1 = t;
        u2 = t * t / LSM_R(2.0);
        u3 = t * t * t / LSM_R(6.0);
    } else {
        const lsm_real sg = f->sg;
        u0 = (R1 - sg * cphi) / LSM_R(2.0);
        u1 = t / LSM_R(2.0) - sg * sphi / f->d1;
        u2 = t * t / LSM_R(4.0) - sg * (R1 - cphi) / f->d2;
        u3 = t * t * t / LSM_R(12.0) - sg * t / f->d2 + sg * sphi / f->d3;
    }
    const lsm_real jk = f->ph->jerk_mm_s3;
    const lsm_kin a = *s0;
    out->j_mm_s3 = jk * u0;
    out->a_mm_s2 = a.a_mm_s2 + jk * u1;
    out->v_mm_s = a.v_mm_s + a.a_mm_s2 * t + jk * u2;
    out->s_mm = a.s_mm + a.v_mm_s * t + a.a_mm_s2 * t * t / LSM_R(2.0) + jk * u3;
}

/* The ranges of v, a and j (signed) over a sub-interval of a ramp: those of its ends (they are monotone there). */
typedef struct kspan {
    lsm_real vlo, vhi, alo, ahi, jlo, jhi;
} kspan;

static void kspan_of(const lsm_kin *p, const lsm_kin *q, kspan *k)
{
    k->vlo = lsm_min2(p->v_mm_s, q->v_mm_s);
    k->vhi = lsm_max2(p->v_mm_s, q->v_mm_s);
    k->alo = lsm_min2(p->a_mm_s2, q->a_mm_s2);
    k->ahi = lsm_max2(p->a_mm_s2, q->a_mm_s2);
    k->jlo = lsm_min2(p->j_mm_s3, q->j_mm_s3);
    k->jhi = lsm_max2(p->j_mm_s3, q->j_mm_s3);
}

/* A planar curved block in its Frenet frame (T, N): signed curvature kappa(s) in [klo, khi] and its sharpness c
 * (kappa'; 0 on arcs). Then (Beudaert eqs 2, 3, with q_ss = kappa N, q_sss = c N - kappa² T)
 *     q''  = a T + kappa v² N,    q''' = jt T + jn N,   jt = j - kappa² v³,   jn = c v³ + 3 kappa v a,
 * and for every axis |q_i'''| <= |jt| max|T_i| + |jn| max|N_i| and |q_i'''| <= |q'''| (likewise q''). These bounds
 * credit what the magnitude budgets of the coefficients cannot: the cancellation of c v³ and 3 kappa v a
 * (decelerating into a rising curvature, accelerating out of it), of j and kappa² v³, and that T and N are
 * orthogonal. They are used where the magnitude budgets fail (check_block). */
typedef struct cframe {
    lsm_real klo, khi, c;
} cframe;

/* The frame of a clothoid (arcs are left to the magnitude budgets: their only credit would be j against kappa² v³
 * and the orthogonality of T and N, c being 0, worth 0.3 % of the time on the circle and the pocket, and their frame
 * bounds cost a fifth of a piece's planning on the dense M4 benchmark). */
static void frame_of(const lsm_geom *g, cframe *f)
{
    const lsm_geom_clothoid *cl = &g->u.clo;
    const lsm_real k1 = cl->kappa0_per_mm + cl->c_per_mm2 * g->len;
    f->klo = lsm_min2(cl->kappa0_per_mm, k1);
    f->khi = lsm_max2(cl->kappa0_per_mm, k1);
    f->c = cl->c_per_mm2;
}

/* The smallest acceleration and jerk limits of the axes the plane of clothoid g touches, with the path limits,
 * times VEC_LIMIT_SHARE (the bounds of |q''| and |q'''|); false: none. */
static bool plane_limits(const lsm_planner *pl, const lsm_geom *g, lsm_real *amax, lsm_real *jmax)
{
    const lsm_real *e1 = g->u.clo.e1, *e2 = g->u.clo.e2;
    const lsm_planner_config *cf = &pl->cfg;
    lsm_real am = LSM_REAL_MAX, jm = LSM_REAL_MAX;
    for (int i = 0; i < 3; i++) {
        if (!(cf->axis_mask & (1u << i)) || (e1[i] == R0 && e2[i] == R0))
            continue;
        am = lsm_min2(am, cf->axis[i].a_max);
        jm = lsm_min2(jm, cf->axis[i].j_max);
    }
    if (cf->path_a_max_mm_s2 > R0)
        am = lsm_min2(am, cf->path_a_max_mm_s2);
    if (cf->path_j_max_mm_s3 > R0)
        jm = lsm_min2(jm, cf->path_j_max_mm_s3);
    *amax = am * VEC_LIMIT_SHARE;
    *jmax = jm * VEC_LIMIT_SHARE;
    return am < LSM_REAL_MAX && jm < LSM_REAL_MAX;
}

/* max |x| over [lo, hi] */
static lsm_real max_abs_in(lsm_real lo, lsm_real hi)
{
    return lsm_max2(lsm_fabs(lo), lsm_fabs(hi));
}

/* The jerk ratio of a bound |jt| wT + |jn| wN <= 1 (jt's range [tlo, thi], jn's largest magnitude bn; tq: the part
 * of |jt| that does not scale with j; jmag: the largest |j|): >= 1 when it holds, else the factor the largest |j|
 * may take (0 when the normal part alone breaks it). */
static lsm_real jerk_ratio(lsm_real wT, lsm_real wN, lsm_real tlo, lsm_real thi, lsm_real bn, lsm_real tq,
                           lsm_real jmag)
{
    const lsm_real room = R1 - wN * bn;
    if (!(room > R0) || !(wT > R0))
        return R0;
    const lsm_real troom = room / wT;
    const lsm_real scaled = jmag > R0 ? (troom - tq) / jmag : (troom >= tq ? LSM_REAL_MAX : R0);
    return max_abs_in(tlo, thi) <= troom ? lsm_max2(R1, scaled) : lsm_max2(R0, scaled);
}

/* The frame's jerk ratio over the span k (the block's coefficients c): per axis, |jt| alpha_j + |jn| beta_j /
 * kappa_max <= 1 (max|T_i| / J_i <= alpha_j, max|N_i| / J_i <= beta_j / kappa_max: the axes' directions are
 * credited as in the coefficients), and, if that fails, the vector bound jt² + jn² <= J² (J: plane_limits). */
static lsm_real frame_jerk_ratio(const lsm_planner *pl, const lsm_geom *g, const cframe *f, const coef *c,
                                 const kspan *k)
{
    const lsm_real kabs = max_abs_in(f->klo, f->khi);
    if (!(kabs > R0))
        return R0;
    const lsm_real k2lo = (f->klo <= R0 && f->khi >= R0) ? R0 : lsm_min2(f->klo * f->klo, f->khi * f->khi);
    const lsm_real v3 = k->vhi * k->vhi * k->vhi, vlo2 = k->vlo * k->vlo;
    /* jn = v (c v² + 3 kappa a), kappa a over the corners of [klo, khi] x [alo, ahi] */
    const lsm_real p1 = f->klo * k->alo, p2 = f->klo * k->ahi, p3 = f->khi * k->alo, p4 = f->khi * k->ahi;
    const lsm_real pmin = lsm_min2(lsm_min2(p1, p2), lsm_min2(p3, p4));
    const lsm_real pmax = lsm_max2(lsm_max2(p1, p2), lsm_max2(p3, p4));
    const lsm_real cv_a = f->c * vlo2, cv_b = f->c * k->vhi * k->vhi;
    const lsm_real in_lo = lsm_min2(cv_a, cv_b) + LSM_R(3.0) * pmin;
    const lsm_real in_hi = lsm_max2(cv_a, cv_b) + LSM_R(3.0) * pmax;
    const lsm_real jn = k->vhi * max_abs_in(in_lo, in_hi);
    /* jt = j - kappa² v³ */
    const lsm_real tq = kabs * kabs * v3;
    const lsm_real tlo = k->jlo - tq, thi = k->jhi - k2lo * vlo2 * k->vlo;
    const lsm_real jmag = max_abs_in(k->jlo, k->jhi);
    const lsm_real r = jerk_ratio(c->aj, c->bj / kabs, tlo, thi, jn, tq, jmag);
    lsm_real am, jm;
    if (r >= R1 || !plane_limits(pl, g, &am, &jm) || !(jn < jm))
        return r;
    const lsm_real troom = lsm_sqrt((jm - jn) * (jm + jn));
    return lsm_max2(r, jerk_ratio(R1 / troom, R0, tlo, thi, R0, tq, jmag));
}

/* The frame's acceleration ratio over the span k: a² + kappa² v⁴ <= A² (A: plane_limits). */
static lsm_real frame_acc_ratio(const lsm_planner *pl, const lsm_geom *g, const cframe *f, const kspan *k)
{
    lsm_real am, jm;
    if (!plane_limits(pl, g, &am, &jm))
        return R0;
    const lsm_real an = max_abs_in(f->klo, f->khi) * k->vhi * k->vhi;
    const lsm_real aroom = am > an ? lsm_sqrt((am - an) * (am + an)) : R0;
    const lsm_real amag = max_abs_in(k->alo, k->ahi);
    return amag > R0 ? aroom / amag : (aroom > R0 ? LSM_REAL_MAX : R0);
}

typedef struct rcheck {
    lsm_real ra, rj, rs; /* >= 1: the budgets hold; < 1: scale the ramp's a, j, snap by this */
    int vviol;           /* a speed above a block's cap */
    lsm_real vx0, vx1;   /* that block's extent (x) */
    lsm_real vcap;       /* and its cap */
    int cut;             /* a block's jerk ratio is CROSS_SHARE_TARGET (the acceleration ate its jerk budget): a
                            part of the span may have a lower one (parts_covered) */
} rcheck;

static void rcheck_init(rcheck *res)
{
    res->ra = res->rj = res->rs = LSM_REAL_MAX;
    res->vviol = 0;
    res->cut = 0;
}

/* The ratios of one block (magnitude budgets of its coefficients; where they fail, the bounds of a planar curved
 * block in its frame too, each ratio the better of the two) into res (planner_int.h, lsm_pl_block_ratios). */
/* The magnitudes of a span, computed once for all the blocks it touches. */
/* A sub-interval of a ramp: its two ends (v, a and j are monotone between them), its tangential snap bound (0:
 * none), and the magnitudes every block's check uses, computed once. */
typedef struct kmag {
    const lsm_kin *p, *q;
    lsm_real sn;
    lsm_real v, v2, v3, amax, jmax;
} kmag;

static void kmag_of(const lsm_kin *p, const lsm_kin *q, lsm_real sn, kmag *m)
{
    m->p = p;
    m->q = q;
    m->sn = sn;
    m->v = lsm_max2(p->v_mm_s, q->v_mm_s);
    m->v2 = m->v * m->v;
    m->v3 = m->v2 * m->v;
    m->amax = lsm_max2(lsm_fabs(p->a_mm_s2), lsm_fabs(q->a_mm_s2));
    m->jmax = lsm_max2(lsm_fabs(p->j_mm_s3), lsm_fabs(q->j_mm_s3));
}

/* Where a clothoid fails its magnitude budgets: the ratios raised by its frame bounds, but only where it would set
 * the span's ratios (below those of the blocks before it): elsewhere they cannot change the result. */
static void frame_improve(const lsm_planner *pl, const lsm_pblock *b, const kmag *m, const coef *c, const rcheck *res,
                          lsm_real *ra_acc, lsm_real *ra_cross, lsm_real *rj)
{
    const lsm_real ra_floor = lsm_min2(res->ra, R1), rj_floor = lsm_min2(res->rj, R1);
    const bool j_binds = *rj < rj_floor;
    if (!(lsm_min2(*ra_acc, *ra_cross) < ra_floor || j_binds))
        return;
    cframe f;
    frame_of(&b->g, &f);
    kspan k;
    kspan_of(m->p, m->q, &k);
    if (*ra_acc < ra_floor)
        *ra_acc = lsm_max2(*ra_acc, frame_acc_ratio(pl, &b->g, &f, &k));
    if (*ra_cross < ra_floor || j_binds) {
        const lsm_real fj = frame_jerk_ratio(pl, &b->g, &f, c, &k);
        if (fj >= R1) /* the jerk holds: the acceleration need not make room for it */
            *ra_cross = lsm_max2(*ra_cross, R1);
        *rj = lsm_max2(*rj, fj);
    }
}

/* The block a check last met, with its cap and (once asked) its budget coefficients: consecutive spans of a check
 * (the parts of a phase, the next phase) mostly lie in the same block, whose values are then read once. They hold
 * for the whole check (the planner and pc->floor do not change during it). */
typedef struct blkmemo {
    uint32_t id;
    bool on; /* off: every span reads its blocks afresh and seeks (the full walk, the tests' reference) */
    bool valid, have_coef;
    const lsm_pblock *b;
    lsm_real cap;
    coef c;
} blkmemo;

/* Block id into bm (from the memo when it is the block last met). */
static void blkmemo_at(const pctx *pc, uint32_t id, blkmemo *bm)
{
    if (bm->valid && bm->id == id)
        return;
    bm->id = id;
    bm->valid = true;
    bm->have_coef = false;
    bm->b = blk(pc->pl, id);
    bm->cap = cap_floor(pc->pl, id, bm->b, pc->floor);
}

/* Is x in the cursor's block, which the memo holds? Then lsm_pl_seek(pc, x) would not move the cursor (the same
 * two tests on the same values). */
static bool blkmemo_holds_cursor(const pctx *pc, const blkmemo *bm, lsm_real x)
{
    return bm->valid && bm->id == pc->cid && !(x < pc->cx) && x < pc->cx + bm->b->g.len;
}

static const coef *blkmemo_coef(blkmemo *bm)
{
    if (!bm->have_coef) {
        coef_get(bm->b, &bm->c);
        bm->have_coef = true;
    }
    return &bm->c;
}

static void check_block(const lsm_planner *pl, const lsm_pblock *b, const coef *c, const kmag *m, rcheck *res)
{
    lsm_real ra_acc = LSM_REAL_MAX, ra_cross = LSM_REAL_MAX, rj = LSM_REAL_MAX;
    bool cross_cut = false; /* rj cut to CROSS_SHARE_TARGET */
    if (m->amax > R0 && c->aa > R0) {
        const lsm_real al = (R1 - c->ba * m->v2) / c->aa;
        ra_acc = al > R0 ? al / m->amax : R0;
    }
    if (c->aj > R0) {
        const lsm_real room = R1 - c->gj * m->v3;
        const lsm_real cross = LSM_R(3.0) * c->bj * m->v * m->amax;
        if (cross > CROSS_SHARE_MAX * room) { /* the acceleration eats the jerk budget: lower the acceleration */
            ra_cross = (cross > R0 && room > R0) ? CROSS_SHARE_TARGET * room / cross : R0;
            rj = CROSS_SHARE_TARGET;
            cross_cut = true;
        } else if (m->jmax > R0) {
            rj = (room - cross) / c->aj / m->jmax;
        }
    }
    if ((ra_acc < R1 || ra_cross < R1 || rj < R1) && b->g.kind == LSM_GEOM_CLOTHOID)
        frame_improve(pl, b, m, c, res, &ra_acc, &ra_cross, &rj);
    if (cross_cut && rj < R1)
        res->cut = 1;
    res->ra = lsm_min2(res->ra, lsm_min2(ra_acc, ra_cross));
    res->rj = lsm_min2(res->rj, rj);
    if (m->sn > R0 && c->as > R0) {
        const lsm_real r = (R1 / c->as) / m->sn;
        if (r < res->rs)
            res->rs = r;
    }
}

/* One sub-interval [xa, xb] (either order) against the blocks it touches: their caps, and unless caps_only their
 * budgets. */
static void check_span(pctx *pc, lsm_real xa, lsm_real xb, const lsm_kin *p, const lsm_kin *q, lsm_real sn,
                       bool caps_only, blkmemo *bm, rcheck *res)
{
    kmag km;
    kmag_of(p, q, sn, &km);
    const kmag *m = &km;
    const lsm_planner *pl = pc->pl;
    if (xb < xa) {
        const lsm_real t = xa;
        xa = xb;
        xb = t;
    }
    if (!bm->on)
        bm->valid = false; /* (the full walk: afresh) */
    if (!blkmemo_holds_cursor(pc, bm, xa))
        lsm_pl_seek(pc, xa);
    uint32_t id = pc->cid;
    lsm_real x = pc->cx;
    for (;;) {
        blkmemo_at(pc, id, bm);
        const lsm_pblock *b = bm->b;
        const lsm_real cap = bm->cap;
        if (m->v > cap * (R1 + CAP_SLACK)) {
            if (!res->vviol) {
                res->vviol = 1;
                res->vx0 = x;
                res->vx1 = x + b->g.len;
                res->vcap = cap;
            }
            return;
        }
        if (!caps_only)
            check_block(pl, b, blkmemo_coef(bm), m, res);
        x += b->g.len;
        id++;
        if (!(x < xb) || id == pc->id_end)
            break;
    }
}

void lsm_pl_block_ratios(const lsm_planner *pl, uint32_t id, const lsm_kin *lo, const lsm_kin *hi, lsm_real *ra,
                         lsm_real *rj)
{
    pctx pc;
    lsm_pl_pctx_init(&pc, pl, id, R0, id + 1u);
    rcheck res;
    rcheck_init(&res);
    blkmemo bm = {0}; /* (off: one span) */
    check_span(&pc, R0, R0, lo, hi, R0, false, &bm, &res);
    *ra = res.vviol ? R0 : res.ra;
    *rj = res.vviol ? R0 : res.rj;
}

static bool rcheck_ok(const rcheck *c)
{
    return !c->vviol && c->ra >= R1 && c->rj >= R1 && c->rs >= R1;
}

static bool rcheck_fails(const rcheck *c)
{
    return c->ra < R1 || c->rj < R1 || c->rs < R1;
}

/* Can the parts of a phase lower none of the ratios a failed check reports (a check that already fails: its
 * rescale takes only the ratios below 1)? Each part's ratio is at least the whole phase's (c: v, |a|, |j| of a part
 * are within those of the whole, which the ratios fall with), except a jerk ratio cut to CROSS_SHARE_TARGET, whose
 * part may drop to the other branch; so when the whole's ratios are at least those found so far, capped at 1, with
 * PARTS_SKIP_SLACK for the rounding of the parts' ends, the parts' budgets are not needed. */
static bool parts_covered(const rcheck *whole, const rcheck *res)
{
    const lsm_real k = R1 + PARTS_SKIP_SLACK;
    return rcheck_fails(res) && !whole->vviol && !whole->cut && whole->ra >= lsm_min2(res->ra, R1) * k &&
           whole->rj >= lsm_min2(res->rj, R1) * k && whole->rs >= lsm_min2(res->rs, R1) * k;
}

/* The parts of a phase of n cycles the speed test sees (their ends at the eighths): 8, 4, 2 or 1. */
static int phase_part_count(uint32_t n)
{
    return n >= 8u ? 8 : n >= 4u ? 4 : n >= 2u ? 2 : 1;
}

/* The state at the end of part q (1..Q - 1) of phase f from st (the phase's end itself is lsm_phase_end's). */
static void part_end(const phase_form *f, const lsm_kin *st, int q, int Q, lsm_kin *out)
{
    const int k8 = q * (8 / Q);
    phase_at(f, st, f->T * (lsm_real)q / (lsm_real)Q, k_sin8[k8], k_cos8[k8], out);
}

/* The parts of phase ph (from st to its end e, Q of them, ends at the eighths) against the blocks they cross: their
 * budgets into res, or with caps_only their speeds alone. True: a speed above a block's cap (res says where; the walk
 * stops there). */
static bool phase_parts(pctx *pc, const lsm_phase *ph, lsm_real x_s, const lsm_kin *st, const lsm_kin *e, int Q,
                        lsm_real sn, bool caps_only, blkmemo *bm, rcheck *res)
{
    const lsm_real psn = ph->shape == LSM_PHASE_CONST ? R0 : sn;
    phase_form f;
    phase_form_of(ph, pc->pl->cfg.cycle_s, &f);
    lsm_kin prev = *st, cur;
    for (int q = 1; q <= Q; q++) {
        if (q < Q)
            part_end(&f, st, q, Q, &cur);
        else
            cur = *e;
        check_span(pc, x_s + prev.s_mm, x_s + cur.s_mm, &prev, &cur, psn, caps_only, bm, res);
        if (res->vviol)
            return true;
        prev = cur;
    }
    return false;
}

/* Verifies a ramp placed at x_s (its start). The shortcuts (quick; off only in the tests' reference walk,
 * lsm_pl_ramp_verify: there every span also reads its blocks afresh and seeks, blkmemo off) leave what the caller
 * uses as the full walk has it: the verdict; the speed test's record; the ratios of a passing ramp; those below 1 of
 * a failing one (its rescale takes no other); and the position cursor (its path: pc->cx adds up the block lengths
 * it passes, so its rounding depends on the blocks it moved over). */
static void ramp_check(pctx *pc, const ramp *r, lsm_real x_s, bool quick, rcheck *res)
{
    lsm_planner *pl = (lsm_planner *)pc->pl; /* statistics only */
    pl->stats.checks++;
    rcheck_init(res);
    const lsm_real dt = pl->cfg.cycle_s;
    lsm_phase ph[7];
    lsm_scurve_phases(&r->iv, r->jp, ph);
    lsm_kin st = {R0, r->v0, R0, R0};
    const lsm_real sn = ramp_speak(r, dt);
    blkmemo bm;
    bm.on = quick;
    bm.valid = false;
    if (lsm_scurve_total_cycles(&r->iv) == 0) {
        check_span(pc, x_s, x_s, &st, &st, R0, false, &bm, res);
        return;
    }
    for (int p = 0; p < 7; p++) {
        const uint32_t n = ph[p].n_cycles;
        if (n == 0)
            continue;
        const int Q = phase_part_count(n);
        lsm_kin e; /* the phase's end (its last part's end too) */
        lsm_phase_end(&ph[p], dt, &st, &e);
        if (Q > 1) {
            /* the whole phase as one span first (v, |a| and |j| are monotone in a phase: their extremes are the
             * end values, and they bound those of every part): where that holds, so do the parts; the finer
             * sub-intervals are only needed where the budgets fall with the speed (curved blocks) */
            rcheck whole;
            rcheck_init(&whole);
            check_span(pc, x_s + st.s_mm, x_s + e.s_mm, &st, &e, ph[p].shape == LSM_PHASE_CONST ? R0 : sn, false, &bm,
                       &whole);
            if (!rcheck_fails(res) && rcheck_ok(&whole)) {
                res->ra = lsm_min2(res->ra, whole.ra); /* (ratios of the coarser check: a lower bound of the finer) */
                res->rj = lsm_min2(res->rj, whole.rj);
                res->rs = lsm_min2(res->rs, whole.rs);
                st = e;
                continue;
            }
            /* where the parts' budgets cannot matter, only their speeds are tested: a cap exceeded (the walk stops
             * at the first part that exceeds one), or parts_covered */
            if (quick && (whole.vviol || parts_covered(&whole, res))) {
                const uint32_t cid = pc->cid; /* (the cursor, to walk the parts again from where the walk was) */
                const lsm_real cx = pc->cx;
                if (phase_parts(pc, &ph[p], x_s, &st, &e, Q, sn, true, &bm, res))
                    return;
                if (!whole.vviol) {
                    st = e;
                    continue;
                }
                pc->cid = cid; /* no part exceeds a cap, by rounding: their budgets below */
                pc->cx = cx;
            }
        }
        if (phase_parts(pc, &ph[p], x_s, &st, &e, Q, sn, false, &bm, res))
            return;
        st = e;
    }
}

void lsm_pl_ramp_verify(pctx *pc, const ramp *r, lsm_real x_s, bool quick, lsm_pl_verdict *out)
{
    rcheck res;
    ramp_check(pc, r, x_s, quick, &res);
    out->ok = rcheck_ok(&res);
    out->vviol = res.vviol != 0;
    out->ra = res.ra;
    out->rj = res.rj;
    out->rs = res.rs;
    out->vx0 = res.vviol ? res.vx0 : R0;
    out->vx1 = res.vviol ? res.vx1 : R0;
    out->vcap = res.vviol ? res.vcap : R0;
}

/* Ramp-relative position where the speed equals c (the ramp is monotone; c between v0 and v1). */
static lsm_real ramp_pos_at_speed(const ramp *r, lsm_real dt, lsm_real c)
{
    lsm_phase ph[7];
    lsm_scurve_phases(&r->iv, r->jp, ph);
    lsm_kin st = {R0, r->v0, R0, R0};
    const bool up = r->v1 > r->v0;
    for (int p = 0; p < 7; p++) {
        if (ph[p].n_cycles == 0)
            continue;
        lsm_kin e;
        lsm_phase_end(&ph[p], dt, &st, &e);
        const bool crosses = up ? (e.v_mm_s >= c) : (e.v_mm_s <= c);
        if (crosses) {
            /* v is monotone in the phase and its derivative a is known: Newton steps kept inside the bracket
             * [lo, hi] (bisection when a step would leave it) until a step is far below a cycle; the answer is
             * taken on the side where the speed has been reached (hi), as the bisection it replaces did */
            lsm_real lo = R0, hi = (lsm_real)ph[p].n_cycles * dt;
            const lsm_real tol = SPEED_POS_TOL_CYCLES * dt;
            const lsm_real dv_ph = e.v_mm_s - st.v_mm_s;
            lsm_real t = dv_ph != R0 ? hi * (c - st.v_mm_s) / dv_ph : hi;
            lsm_kin m_hi; /* the state at hi, once evaluated there (hi_known) */
            bool hi_known = false;
            for (int it = 0; it < SPEED_POS_ITER && hi - lo > tol; it++) {
                if (!(t > lo && t < hi))
                    t = (lo + hi) / LSM_R(2.0);
                lsm_kin m;
                lsm_phase_advance(&ph[p], dt, &st, t, &m);
                const bool past = up ? (m.v_mm_s >= c) : (m.v_mm_s <= c);
                if (past) {
                    hi = t;
                    m_hi = m;
                    hi_known = true;
                } else {
                    lo = t;
                }
                const lsm_real step = m.a_mm_s2 != R0 ? (c - m.v_mm_s) / m.a_mm_s2 : hi - lo;
                if (lsm_fabs(step) < tol) {
                    if (!past && t + tol < hi) {
                        hi = t + tol; /* (v moves by a tol there: reached within rounding) */
                        hi_known = false;
                    }
                    break;
                }
                t += step;
            }
            if (!hi_known)
                lsm_phase_advance(&ph[p], dt, &st, hi, &m_hi);
            return m_hi.s_mm;
        }
        st = e;
    }
    return r->dist;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* an accelerating ramp placed past the caps ahead in one pass over the blocks                                  */

/* The parts of a ramp as its verification's speed test sees them (ramp_check, phase_parts): phase p from st[p] to
 * st[p + 1], in Q parts (ends at the eighths), each part tested at the higher of its two end speeds against every
 * block it overlaps. The phase ends are computed once; the parts' ends of one phase at a time, when asked. Every
 * value is computed as the verification computes it (the same calls on the same inputs): bit for bit the same. */
typedef struct rprof {
    lsm_real dt;
    lsm_phase ph[7];
    lsm_kin st[8]; /* st[p]: start of phase p; st[7]: the ramp's end */
    int cp, cq;    /* the phase whose parts' ends pe[1..cq] are known (-1: none), and its closed form */
    phase_form form;
    lsm_kin pe[8];
} rprof;

static void rprof_init(rprof *pf, const ramp *r, lsm_real dt)
{
    pf->dt = dt;
    pf->cp = -1;
    pf->cq = 0;
    lsm_scurve_phases(&r->iv, r->jp, pf->ph);
    const lsm_kin k0 = {R0, r->v0, R0, R0};
    pf->st[0] = k0;
    for (int p = 0; p < 7; p++) {
        if (pf->ph[p].n_cycles == 0)
            pf->st[p + 1] = pf->st[p];
        else
            lsm_phase_end(&pf->ph[p], dt, &pf->st[p], &pf->st[p + 1]);
    }
}

/* The end of part q (1..Q) of phase p. */
static const lsm_kin *rprof_part_end(rprof *pf, int p, int q, int Q)
{
    if (q == Q)
        return &pf->st[p + 1];
    if (pf->cp != p) {
        pf->cp = p;
        pf->cq = 0;
        phase_form_of(&pf->ph[p], pf->dt, &pf->form);
    }
    while (pf->cq < q) {
        const int k = ++pf->cq;
        part_end(&pf->form, &pf->st[p], k, Q, &pf->pe[k]);
    }
    return &pf->pe[q];
}

/* Where the first part of an accelerating ramp whose speed the verification finds above ceff (a cap with its slack)
 * starts, ramp-relative (false: none). The speeds of the parts rise along the ramp: every later part is above too. */
static bool rprof_first_above(rprof *pf, lsm_real ceff, lsm_real *s_out)
{
    for (int p = 0; p < 7; p++) {
        const uint32_t n = pf->ph[p].n_cycles;
        if (n == 0 || !(lsm_max2(pf->st[p].v_mm_s, pf->st[p + 1].v_mm_s) > ceff))
            continue;
        const int Q = phase_part_count(n);
        const lsm_kin *prev = &pf->st[p];
        for (int q = 1; q <= Q; q++) {
            const lsm_kin *e = rprof_part_end(pf, p, q, Q);
            if (lsm_max2(prev->v_mm_s, e->v_mm_s) > ceff) {
                *s_out = prev->s_mm;
                return true;
            }
            prev = e;
        }
    }
    return false;
}

/*
 * Moves *xs, the start of the accelerating ramp r, past every block whose cap the ramp would exceed there, as its
 * verification tests the caps (each part at its higher end speed against every block it overlaps), in one pass over
 * the blocks: the verification at the start it returns finds no speed above a cap (up to the rounding of the block
 * ends, which the verification then reports like any cap: the fitting moves the ramp after that block). A block
 * [x, x1) with cap c below the ramp's end speed is exceeded by the parts from the first one above c on (ramp-relative
 * start s_c, rprof_first_above) and by no earlier one, so at a start xs it is exceeded exactly when xs + s_c < x1 (and
 * the ramp reaches it: x < xs + its length). The ramp then starts at x1, after the block, as the move of the fitting
 * did (a start at x1 - s_c, the earliest, leaves the ramp on that block, often a curve whose budgets then lower the
 * whole ramp: on the M4 benchmark it cost 0.9 % of the motion time). A later start keeps every block before it
 * passed (their exceeded parts only move further on), so the pass never looks back.
 * False: a cap below v0 is in the way (no lead cruise passes it), the ramp starts from rest and would have to move
 * (there is no lead cruise at 0), or it no longer fits before X1 (*xs: the start it was moved to).
 */
bool lsm_pl_accel_past_caps(pctx *pc, const ramp *r, lsm_real X0, lsm_real X1, lsm_real *xs)
{
    if (lsm_scurve_total_cycles(&r->iv) == 0)
        return true;
    const lsm_planner *pl = pc->pl;
    const lsm_real tol = LEN_EPS * (R1 + lsm_fabs(X0) + lsm_fabs(X1));
    rprof pf;
    bool have_pf = false;
    lsm_real x_s = *xs, len = r->dist; /* (len: the ramp's length; its parts' exact end once pf is known) */
    lsm_pl_seek(pc, x_s);
    uint32_t id = pc->cid;
    lsm_real x = pc->cx;
    while (x < x_s + len) {
        const lsm_pblock *b = blk(pl, id);
        const lsm_real x1 = x + b->g.len;
        const lsm_real cap = cap_floor(pl, id, b, pc->floor);
        const lsm_real ceff = cap * (R1 + CAP_SLACK);
        if (r->v1 > ceff && x1 > x_s) {
            if (cap < r->v0 * (R1 - CAP_SLACK))
                return false;
            if (!have_pf) {
                rprof_init(&pf, r, pl->cfg.cycle_s);
                have_pf = true;
                len = pf.st[7].s_mm;
            }
            lsm_real s;
            if (x < x_s + len && rprof_first_above(&pf, ceff, &s) && x_s + s < x1) { /* (s >= 0: x1 > x_s) */
                if (!(r->v0 > R0))
                    return false; /* (from rest there is no lead cruise: the ramp starts at *xs or not at all) */
                x_s = x1;
                if (x_s + r->dist > X1 + tol) {
                    *xs = x_s;
                    return false;
                }
            }
        }
        x = x1;
        if (++id == pc->id_end)
            break;
    }
    *xs = x_s;
    return true;
}

/* First guess of the tangential limits near x: the block's budgets at rest. */
void lsm_pl_guess_limits(pctx *pc, lsm_real x, lsm_real *a, lsm_real *j, lsm_real *s)
{
    lsm_pl_seek(pc, x);
    coef c;
    coef_get(blk(pc->pl, pc->cid), &c);
    *a = c.aa > R0 ? R1 / c.aa : UNBOUNDED_A;
    *j = c.aj > R0 ? R1 / c.aj : UNBOUNDED_J;
    *s = c.as > R0 ? R1 / c.as : UNBOUNDED_S;
}

/* Lowers the limits after a check that failed on the budgets. */
static bool rescale(ramp *r, lsm_real dt, const rcheck *c, int it)
{
    const lsm_real k = it > RESCALE_FINE_ITER ? RESCALE_COARSE : RESCALE_FINE;
    bool changed = false;
    if (c->ra < R1) {
        const lsm_real na = lsm_min2(r->a_lim, ramp_apeak(r, dt) * c->ra * k);
        changed |= na < r->a_lim;
        r->a_lim = na;
    }
    if (c->rj < R1) {
        const lsm_real nj = lsm_min2(r->j_lim, lsm_fabs(r->jp) * c->rj * k);
        changed |= nj < r->j_lim;
        r->j_lim = nj;
    }
    if (c->rs < R1) {
        const lsm_real ns = lsm_min2(r->s_lim, ramp_speak(r, dt) * c->rs * k);
        changed |= ns < r->s_lim;
        r->s_lim = ns;
    }
    if (!changed) { /* quantisation kept the peaks: force progress */
        r->a_lim *= RESCALE_COARSE;
        r->j_lim *= RESCALE_COARSE;
        r->s_lim *= RESCALE_COARSE;
    }
    return r->a_lim > LIMIT_FLOOR && r->j_lim > LIMIT_FLOOR && r->s_lim > LIMIT_FLOOR;
}

/*
 * Plans r (v0 -> v1) at one placement and fits its tangential limits to the budgets of the blocks it crosses:
 * lower when the check fails, higher (twice at most) when it holds with room. The placement is the start x_at, or
 * the end when anchor_end. Returns 1 (verified; r and *xs set), 0 (no limits fit), -1 (a speed above a block's cap:
 * c says where).
 */
static int tune_ramp(pctx *pc, ramp *r, lsm_real v0, lsm_real v1, bool anchor_end, lsm_real x_at, lsm_real X0,
                     lsm_real X1, lsm_real *xs, rcheck *c)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    ramp best;
    bool have = false;
    int ups = 0;
    for (int it = 0; it < FIT_ITER; it++) {
        const lsm_real x = anchor_end ? x_at - r->dist : x_at;
        const lsm_real tol = LEN_EPS * (R1 + lsm_fabs(X0) + lsm_fabs(X1));
        if (x < X0 - tol || x + r->dist > X1 + tol) {
            if (have) {
                *r = best;
                *xs = anchor_end ? x_at - r->dist : x_at;
                return 1;
            }
            return 0;
        }
        ramp_check(pc, r, x, true, c);
        if (c->vviol) {
            if (have) {
                *r = best;
                *xs = anchor_end ? x_at - r->dist : x_at;
                return 1;
            }
            return -1;
        }
        if (rcheck_ok(c)) {
            best = *r;
            have = true;
            *xs = x;
            const lsm_real room = TUNE_UP_ROOM;
            if (ups >= TUNE_UPS || !(c->ra > room || c->rj > room))
                return 1;
            /* try faster */
            ups++;
            const lsm_real na =
                c->ra > room ? lsm_min2(ramp_apeak(r, dt) * c->ra * TUNE_UP_SHARE, r->a_lim * TUNE_UP_MAX) : r->a_lim;
            const lsm_real nj =
                c->rj > room ? lsm_min2(lsm_fabs(r->jp) * c->rj * TUNE_UP_SHARE, r->j_lim * TUNE_UP_MAX) : r->j_lim;
            const lsm_real ns =
                c->rs > room ? lsm_min2(ramp_speak(r, dt) * c->rs * TUNE_UP_SHARE, r->s_lim * TUNE_UP_MAX) : r->s_lim;
            if (!(na > r->a_lim || nj > r->j_lim || ns > r->s_lim))
                return 1;
            if (!lsm_pl_ramp_plan(r, dt, v0, v1, lsm_max2(na, r->a_lim), lsm_max2(nj, r->j_lim),
                                  lsm_max2(ns, r->s_lim)) ||
                lsm_scurve_total_cycles(&r->iv) >= lsm_scurve_total_cycles(&best.iv)) {
                *r = best;
                return 1;
            }
            continue;
        }
        if (have) {
            *r = best;
            *xs = anchor_end ? x_at - r->dist : x_at;
            return 1;
        }
        if (!rescale(r, dt, c, it) || !lsm_pl_ramp_plan(r, dt, v0, v1, r->a_lim, r->j_lim, r->s_lim))
            return 0;
    }
    if (have) {
        *r = best;
        *xs = anchor_end ? x_at - r->dist : x_at;
        return 1;
    }
    return 0;
}

/* After a move of the ramp: its limits raised to at least a, j, s (the budgets at rest where it now starts). r was
 * planned with its own limits (lsm_pl_ramp_plan keeps them): when none is raised, r is already that plan and the
 * sizing is not repeated. */
static bool replan_at_least(ramp *r, lsm_real dt, lsm_real a, lsm_real j, lsm_real s)
{
    if (!(a > r->a_lim) && !(j > r->j_lim) && !(s > r->s_lim))
        return true;
    return lsm_pl_ramp_plan(r, dt, r->v0, r->v1, lsm_max2(a, r->a_lim), lsm_max2(j, r->j_lim), lsm_max2(s, r->s_lim));
}

/*
 * Decelerating ramp v0 -> v1 (v0 > v1) on [X0, X1]: placed as late as it verifies, ending at X1 exactly when
 * `exact`. Region checks: lead cruise at v0 on [X0, start] (if check_lead), trail cruise at v1 on [end, X1].
 * Returns the ramp and its start.
 */
bool lsm_pl_fit_decel(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, bool exact, bool check_lead,
                      ramp *r, lsm_real *xs_out)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    lsm_real a, j, s;
    lsm_pl_guess_limits(pc, X1, &a, &j, &s);
    if (!lsm_pl_ramp_plan(r, dt, v0, v1, a, j, s))
        return false;
    lsm_real xe = X1, last_vx = LSM_REAL_MAX;
    for (int it = 0; it < FIT_ITER; it++) {
        rcheck c;
        lsm_real xs;
        const int t = tune_ramp(pc, r, v0, v1, true, xe, X0, X1, &xs, &c);
        if (t == 0)
            return false;
        if (t < 0) {
            xs = xe - r->dist;
            if (exact || c.vcap < v1 * (R1 - CAP_SLACK) || c.vx0 <= xs)
                return false;
            /* (the same block again: the position at its cap would be discarded, not computed) */
            lsm_real nxs = c.vx0 == last_vx ? xs : c.vx0 - ramp_pos_at_speed(r, dt, c.vcap);
            if (c.vx0 == last_vx || !(nxs < xs))
                nxs = c.vx0 - r->dist; /* end the ramp before the block */
            if (!(nxs < xs))
                nxs = xs - MOVE_NUDGE * (R1 + r->dist);
            last_vx = c.vx0;
            xe = nxs + r->dist;
            lsm_pl_guess_limits(pc, xe, &a, &j, &s);
            if (!replan_at_least(r, dt, a, j, s))
                return false;
            continue;
        }
        if (check_lead && !lsm_pl_region_ok(pc, X0, xs, v0))
            return false;
        if (!lsm_pl_region_ok(pc, xs + r->dist, X1, v1))
            return false;
        *xs_out = xs;
        return true;
    }
    return false;
}

/* Places ramp r past the caps from *xs on (lsm_pl_accel_past_caps); where it moves, it is sized again with at least
 * the budgets at rest at its new start, and placed again when that changed it (shorter: it reaches the caps
 * sooner). False: no placement before X1. */
static bool place_accel(pctx *pc, ramp *r, lsm_real X0, lsm_real X1, lsm_real *xs)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    for (int it = 0; it < FIT_ITER; it++) {
        const lsm_real x_before = *xs;
        if (!lsm_pl_accel_past_caps(pc, r, X0, X1, xs))
            return false;
        if (!(*xs > x_before))
            return true;
        lsm_real a, j, s;
        lsm_pl_guess_limits(pc, *xs, &a, &j, &s);
        const uint32_t n = lsm_scurve_total_cycles(&r->iv);
        if (!replan_at_least(r, dt, a, j, s))
            return false;
        if (lsm_scurve_total_cycles(&r->iv) == n)
            return true; /* (the same length in cycles: the same ramp, or one as long, which the check decides) */
    }
    return true;
}

/*
 * Accelerating ramp v0 -> v1 (v1 > v0) starting at or after X0, placed as early as it verifies (a lead cruise
 * at v0 if needed; none from rest). With check_trail, cruising at v1 from its end to X1 must fit too. The ramp is
 * placed past the caps ahead before each verification (place_accel): a verification that still finds a speed above
 * a cap had its ramp lowered on the budgets (longer: it reaches further), or met the rounding of the positions.
 */
bool lsm_pl_fit_accel(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, bool check_trail, ramp *r,
                      lsm_real *xs_out)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    lsm_real a, j, s;
    lsm_pl_guess_limits(pc, X0, &a, &j, &s);
    if (!lsm_pl_ramp_plan(r, dt, v0, v1, a, j, s))
        return false;
    lsm_real xs = X0;
    for (int it = 0; it < FIT_ITER; it++) {
        if (!place_accel(pc, r, X0, X1, &xs))
            return false;
        rcheck c;
        lsm_real xr;
        const int t = tune_ramp(pc, r, v0, v1, false, xs, X0, X1, &xr, &c);
        if (t == 0)
            return false;
        if (t < 0) {
            if (!(v0 > R0) || c.vcap < v0 * (R1 - CAP_SLACK))
                return false;
            lsm_real nxs = xs;
            if (!lsm_pl_accel_past_caps(pc, r, X0, X1, &nxs))
                return false;
            if (!(nxs > xs))
                nxs = c.vx1; /* (the pass and the check disagree, by rounding: start after the block) */
            if (!(nxs > xs))
                nxs = xs + MOVE_NUDGE * (R1 + r->dist);
            xs = nxs;
            lsm_pl_guess_limits(pc, xs, &a, &j, &s);
            if (!replan_at_least(r, dt, a, j, s))
                return false;
            continue;
        }
        if (!lsm_pl_region_ok(pc, X0, xr, v0))
            return false;
        if (check_trail && !lsm_pl_region_ok(pc, xr + r->dist, X1, v1))
            return false;
        *xs_out = xr;
        return true;
    }
    return false;
}

/* Decelerating ramp starting exactly at X0 (override catch-up, feed hold). */
bool lsm_pl_fit_decel_now(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, ramp *r)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    lsm_real a, j, s;
    lsm_pl_guess_limits(pc, X0, &a, &j, &s);
    if (!lsm_pl_ramp_plan(r, dt, v0, v1, a, j, s))
        return false;
    rcheck c;
    lsm_real xs;
    return tune_ramp(pc, r, v0, v1, false, X0, X0, X1, &xs, &c) == 1;
}
