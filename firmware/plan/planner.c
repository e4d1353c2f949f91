/* planner.c: look-ahead velocity planner (see planner.h for the model). */
#include "planner.h"

#include <string.h>

#include "corner.h"
#include "lsm_math.h"

#define PI_R ((lsm_real)LSM_PI)
#define R0 LSM_R(0.0)
#define R1 LSM_R(1.0)

/* Relative slack when comparing a speed with a cap (rounding of values that are equal by construction). */
#if LSM_REAL_IS_FLOAT
#define CAP_SLACK LSM_R(2e-6)
#define LEN_EPS LSM_R(1e-5)
#else
#define CAP_SLACK LSM_R(1e-9)
#define LEN_EPS LSM_R(1e-9)
#endif
/* Iteration caps of the ramp fitting and of the bisections. */
#define FIT_ITER 40
#define W_BISECT 14
#define VC_BISECT 12
#define STAIR_LEVELS 6
/* Searches over a speed stop when the bracket is this narrow (relative): W and cruise feeds a fraction of a percent
 * below the best cost a fraction of a percent of time, and every candidate is verified in full anyway. */
#define SPEED_RES LSM_R(0.004)

/* ------------------------------------------------------------------------------------------------------------ */
/* storage                                                                                                       */

static uint32_t slot_of(const lsm_planner *pl, uint32_t id)
{
    return (pl->head_slot + (uint32_t)(id - pl->head)) % pl->cap;
}

static lsm_pblock *blk(const lsm_planner *pl, uint32_t id)
{
    return &pl->blk[slot_of(pl, id)];
}

static bool id_lt(uint32_t a, uint32_t b)
{
    return (int32_t)(a - b) < 0;
}

/* bfloat16 (the upper half of an IEEE float), rounded up: the coefficients are bounds, never smaller. */
static uint16_t bf16_up(lsm_real x)
{
    if (!(x > R0))
        return 0;
    float f = (float)(x * (lsm_real)1.000001);
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    if (u == 0)
        u = 1;
    if (u & 0xFFFFu)
        u += 0x10000u;
    if ((u >> 23) >= 0xFFu) /* would round to inf: clamp to the largest finite bfloat16 */
        u = 0x7F7F0000u;
    return (uint16_t)(u >> 16);
}

static lsm_real bf16_val(uint16_t h)
{
    uint32_t u = (uint32_t)h << 16;
    float f;
    memcpy(&f, &u, sizeof f);
    return (lsm_real)f;
}

typedef struct coef {
    lsm_real aa, ba, aj, bj, gj, as; /* alpha_a, beta_a, alpha_j, beta_j, gamma_j, alpha_s */
} coef;

static void coef_get(const lsm_pblock *b, coef *c)
{
    c->aa = bf16_val(b->coef[0]);
    c->ba = bf16_val(b->coef[1]);
    c->aj = bf16_val(b->coef[2]);
    c->bj = bf16_val(b->coef[3]);
    c->gj = bf16_val(b->coef[4]);
    c->as = bf16_val(b->coef[5]);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* configuration                                                                                                 */

void lsm_planner_default_config(lsm_planner_config *cfg)
{
    if (cfg == NULL)
        return;
    memset(cfg, 0, sizeof *cfg);
    cfg->cycle_s = LSM_R(0.001);
    cfg->axis_mask = 0x07u;
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        cfg->axis[i].v_max = LSM_R(250.0);
        cfg->axis[i].a_max = LSM_R(3000.0);
        cfg->axis[i].j_max = LSM_R(60000.0);
        cfg->axis[i].snap_max = LSM_R(1.2e7);
    }
    cfg->cap_margin = (lsm_real)LSM_PLANNER_CAP_MARGIN;
    cfg->node_hyst = (lsm_real)LSM_PLANNER_NODE_HYST;
    cfg->node_drop = (lsm_real)LSM_PLANNER_NODE_DROP;
    cfg->trim_share = (lsm_real)LSM_PLANNER_TRIM_SHARE;
    cfg->fit_share = (lsm_real)LSM_PLANNER_FIT_SHARE;
}

static lsm_status check_vals(const lsm_real *v, int n)
{
    for (int i = 0; i < n; i++) {
        int r = lsm_check_finite(v[i]);
        if (r)
            return (lsm_status)r;
    }
    return LSM_OK;
}

static lsm_status check_config(const lsm_planner_config *c)
{
    const lsm_real sc[8] = {c->cycle_s, c->cap_margin, c->path_a_max_mm_s2, c->path_j_max_mm_s3,
                            c->node_hyst, c->node_drop, c->trim_share, c->fit_share};
    lsm_status st = check_vals(sc, 8);
    if (st != LSM_OK)
        return st;
    if (!(c->cycle_s > R0))
        return LSM_E_CYCLE;
    if (c->axis_mask == 0 || c->axis_mask > 0x3Fu)
        return LSM_E_ARG;
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        if (!(c->axis_mask & (1u << i)))
            continue;
        const lsm_real v[4] = {c->axis[i].v_max, c->axis[i].a_max, c->axis[i].j_max, c->axis[i].snap_max};
        st = check_vals(v, 4);
        if (st != LSM_OK)
            return st;
        for (int k = 0; k < 4; k++)
            if (!(v[k] > R0))
                return LSM_E_LIMIT;
    }
    if (c->path_a_max_mm_s2 < R0 || c->path_j_max_mm_s3 < R0)
        return LSM_E_LIMIT;
    if (!(c->cap_margin > R0 && c->cap_margin < R1))
        return LSM_E_ARG;
    if (!(c->node_hyst >= R0 && c->node_hyst < R1) || !(c->node_drop > R0 && c->node_drop < R1))
        return LSM_E_ARG;
    if (!(c->trim_share > R0 && c->trim_share <= LSM_R(0.5)))
        return LSM_E_ARG;
    if (!(c->fit_share >= R0 && c->fit_share < R1))
        return LSM_E_ARG;
    return LSM_OK;
}

lsm_status lsm_planner_init(lsm_planner *pl, const lsm_planner_config *cfg, lsm_pblock *storage, uint32_t capacity,
                            const lsm_real start[LSM_MAX_AXES])
{
    if (pl == NULL || cfg == NULL || storage == NULL || start == NULL)
        return LSM_E_NULL;
    lsm_status st = check_config(cfg);
    if (st != LSM_OK)
        return st;
    st = check_vals(start, LSM_MAX_AXES);
    if (st != LSM_OK)
        return st;
    if (capacity < LSM_PLANNER_MIN_BLOCKS)
        return LSM_E_PL_CAPACITY;
    memset(pl, 0, sizeof *pl);
    pl->cfg = *cfg;
    pl->blk = storage;
    pl->cap = capacity;
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pl->tail_pos[i] = pl->tail_prog[i] = start[i];
    pl->ovr_near = pl->ovr_far = R1;
    pl->horizon_off = R0;
    return LSM_OK;
}

uint32_t lsm_planner_free(const lsm_planner *pl)
{
    return pl ? pl->cap - (pl->tail - pl->head) : 0;
}

uint32_t lsm_planner_count(const lsm_planner *pl)
{
    return pl ? pl->tail - pl->head : 0;
}

const lsm_pblock *lsm_planner_block(const lsm_planner *pl, uint32_t id)
{
    if (pl == NULL || id_lt(id, pl->head) || !id_lt(id, pl->tail))
        return NULL;
    return blk(pl, id);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* per-block bounds of the geometric derivatives and the budget coefficients                                     */

/* max |A cos t + B sin t| over t in [t0, t1] (t0 <= t1). */
static lsm_real max_abs_cs(lsm_real A, lsm_real B, lsm_real t0, lsm_real t1)
{
    const lsm_real R = lsm_sqrt(A * A + B * B);
    if (!(R > R0))
        return R0;
    if (t1 - t0 >= PI_R)
        return R;
    const lsm_real psi = lsm_atan2(B, A); /* A cos t + B sin t = R cos(t - psi): peaks at psi + k pi */
    const lsm_real k = lsm_ceil((t0 - psi) / PI_R);
    if (psi + k * PI_R <= t1)
        return R;
    const lsm_real f0 = lsm_fabs(A * lsm_cos(t0) + B * lsm_sin(t0));
    const lsm_real f1 = lsm_fabs(A * lsm_cos(t1) + B * lsm_sin(t1));
    const lsm_real m = lsm_max2(f0, f1);
    return lsm_min2(R, m * (R1 + LSM_R(1e-6)) + LSM_REAL_EPS * R); /* rounding of the end values */
}

/* Fills Q1, Q2, Q3 per axis (LSM_MAX_AXES) and the curvature bounds of the block. */
static void geom_bounds(const lsm_geom *g, lsm_real q1[LSM_MAX_AXES], lsm_real q2[LSM_MAX_AXES],
                        lsm_real q3[LSM_MAX_AXES], lsm_real *kmax, lsm_real *cmax)
{
    for (int i = 0; i < LSM_MAX_AXES; i++)
        q1[i] = q2[i] = q3[i] = R0;
    *kmax = *cmax = R0;
    if (g->kind == LSM_GEOM_LINE) {
        for (int i = 0; i < LSM_MAX_AXES; i++)
            q1[i] = lsm_fabs(g->u.line.dir[i]);
        return;
    }
    const lsm_real *e1, *e2;
    lsm_real t0, t1, k, c = R0, sT = R1; /* sT: in-plane speed per unit s (helix) */
    lsm_real n[3] = {R0, R0, R0}, ax = R0;
    if (g->kind == LSM_GEOM_ARC) {
        const lsm_geom_arc *a = &g->u.arc;
        e1 = a->e1;
        e2 = a->e2;
        const lsm_real w = a->sweep_rad / g->len; /* dphi/ds */
        /* the unit tangent of the in-plane part rotates with phi; its direction is phi + pi/2 (or - for cw) */
        const lsm_real p0 = a->phi0_rad, p1 = a->phi0_rad + a->sweep_rad;
        t0 = lsm_min2(p0, p1);
        t1 = lsm_max2(p0, p1);
        sT = a->radius_mm * lsm_fabs(w);
        k = a->radius_mm * w * w; /* in-plane curvature of the helix */
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        ax = a->axial_mm / g->len;
        /* q_s = sT (-sin phi e1 + cos phi e2) sgn + n ax; q_ss = -k (cos phi e1 + sin phi e2);
         * q_sss = k |w| (sin phi e1 - cos phi e2) sgn */
        for (int i = 0; i < 3; i++) {
            const lsm_real mT = max_abs_cs(e2[i], -e1[i], t0, t1); /* |-sin e1 + cos e2| */
            const lsm_real mN = max_abs_cs(e1[i], e2[i], t0, t1);  /* |cos e1 + sin e2| */
            q1[i] = sT * mT + lsm_fabs(n[i] * ax);
            q2[i] = k * mN;
            q3[i] = k * lsm_fabs(w) * mT;
        }
        *kmax = k;
        *cmax = R0;
        return;
    }
    /* clothoid: theta(s) = theta0 + k0 s + c s²/2; T = cos e1 + sin e2, N = -sin e1 + cos e2 */
    const lsm_geom_clothoid *cl = &g->u.clo;
    e1 = cl->e1;
    e2 = cl->e2;
    const lsm_real L = g->len, k0 = cl->kappa0_per_mm;
    c = cl->c_per_mm2;
    const lsm_real th0 = cl->theta0_rad, thL = th0 + L * (k0 + LSM_R(0.5) * c * L);
    t0 = lsm_min2(th0, thL);
    t1 = lsm_max2(th0, thL);
    if (c != R0) {
        const lsm_real sv = -k0 / c;
        if (sv > R0 && sv < L) {
            const lsm_real thv = th0 + sv * (k0 + LSM_R(0.5) * c * sv);
            t0 = lsm_min2(t0, thv);
            t1 = lsm_max2(t1, thv);
        }
    }
    k = lsm_max2(lsm_fabs(k0), lsm_fabs(k0 + c * L));
    for (int i = 0; i < 3; i++) {
        const lsm_real mT = max_abs_cs(e1[i], e2[i], t0, t1);
        const lsm_real mN = max_abs_cs(e2[i], -e1[i], t0, t1);
        q1[i] = mT;
        q2[i] = k * mN;
        q3[i] = lsm_fabs(c) * mN + k * k * mT;
    }
    *kmax = k;
    *cmax = lsm_fabs(c);
    (void)sT;
}

/* Computes cap_geo and the six coefficients of a block from its geometry. */
static void block_coef(const lsm_planner *pl, lsm_pblock *b)
{
    const lsm_planner_config *cf = &pl->cfg;
    lsm_real q1[LSM_MAX_AXES], q2[LSM_MAX_AXES], q3[LSM_MAX_AXES], kmax, cmax;
    geom_bounds(&b->g, q1, q2, q3, &kmax, &cmax);
    lsm_real av = R0, aa = R0, ba = R0, aj = R0, bj = R0, gj = R0, as = R0;
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        if (!(cf->axis_mask & (1u << i)))
            continue;
        const lsm_planner_axis *x = &cf->axis[i];
        av = lsm_max2(av, q1[i] / x->v_max);
        aa = lsm_max2(aa, q1[i] / x->a_max);
        ba = lsm_max2(ba, q2[i] / x->a_max);
        aj = lsm_max2(aj, q1[i] / x->j_max);
        bj = lsm_max2(bj, q2[i] / x->j_max);
        gj = lsm_max2(gj, q3[i] / x->j_max);
        as = lsm_max2(as, q1[i] / x->snap_max);
    }
    if (!b->g.rotary_only) { /* the tangential frame: |T| = 1, |kappa N| = kappa, |q_sss| = sqrt(c² + kappa⁴) */
        if (cf->path_a_max_mm_s2 > R0) {
            aa = lsm_max2(aa, R1 / cf->path_a_max_mm_s2);
            ba = lsm_max2(ba, kmax / cf->path_a_max_mm_s2);
        }
        if (cf->path_j_max_mm_s3 > R0) {
            aj = lsm_max2(aj, R1 / cf->path_j_max_mm_s3);
            bj = lsm_max2(bj, kmax / cf->path_j_max_mm_s3);
            gj = lsm_max2(gj, lsm_sqrt(cmax * cmax + kmax * kmax * kmax * kmax) / cf->path_j_max_mm_s3);
        }
    }
    b->coef[0] = bf16_up(aa);
    b->coef[1] = bf16_up(ba);
    b->coef[2] = bf16_up(aj);
    b->coef[3] = bf16_up(bj);
    b->coef[4] = bf16_up(gj);
    b->coef[5] = bf16_up(as);
    /* the cap uses the rounded coefficients, so the budget at the cap is never negative */
    coef c;
    coef_get(b, &c);
    lsm_real cap = av > R0 ? R1 / av : LSM_REAL_MAX;
    if (c.ba > R0)
        cap = lsm_min2(cap, lsm_sqrt(cf->cap_margin / c.ba));
    if (c.gj > R0)
        cap = lsm_min2(cap, lsm_cbrt(cf->cap_margin / c.gj));
    b->cap_geo_mm_s = cap * (R1 - LSM_R(4.0) * LSM_REAL_EPS);
}

/* Override factor that applies to block id. */
static lsm_real ovr_of(const lsm_planner *pl, uint32_t id)
{
    return id_lt(id, pl->ovr_switch) ? pl->ovr_near : pl->ovr_far;
}

/* Speed cap: min(F * o, cap_geo * min(o, 1)), with the feed part raised to `floor` (override catch-up). */
static lsm_real cap_floor(const lsm_planner *pl, uint32_t id, const lsm_pblock *b, lsm_real floor)
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

static lsm_real cap_of(const lsm_planner *pl, uint32_t id)
{
    return cap_floor(pl, id, blk(pl, id), R0);
}

lsm_real lsm_planner_block_cap(const lsm_planner *pl, uint32_t id)
{
    if (lsm_planner_block(pl, id) == NULL)
        return R0;
    return cap_of(pl, id);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* append                                                                                                        */

static lsm_status check_move(const lsm_planner_move *mv)
{
    if (mv == NULL)
        return LSM_E_NULL;
    const lsm_real v[2] = {mv->feed_mm_s, mv->tol_mm};
    lsm_status st = check_vals(v, mv->rapid ? 0 : 1);
    if (st == LSM_OK)
        st = check_vals(v + 1, 1);
    if (st != LSM_OK)
        return st;
    if (!mv->rapid && !(mv->feed_mm_s > R0))
        return LSM_E_NEG_FEED;
    if (mv->tol_mm < R0)
        return LSM_E_TOLERANCE;
    return LSM_OK;
}

static bool geom_moves_rotary(const lsm_geom *g)
{
    if (g->kind != LSM_GEOM_LINE)
        return false;
    return g->u.line.dir[3] != R0 || g->u.line.dir[4] != R0 || g->u.line.dir[5] != R0;
}

/* Two lines in the same direction in all axes (nothing to smooth, no stop). */
static bool lines_collinear(const lsm_geom *a, const lsm_geom *b)
{
    if (a->kind != LSM_GEOM_LINE || b->kind != LSM_GEOM_LINE || a->rotary_only != b->rotary_only)
        return false;
    lsm_real d = R0;
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        const lsm_real e = a->u.line.dir[i] - b->u.line.dir[i];
        d += e * e;
    }
#if LSM_REAL_IS_FLOAT
    return d <= LSM_R(1e-12);
#else
    return d <= LSM_R(1e-22);
#endif
}

static void push_block(lsm_planner *pl, const lsm_geom *g, lsm_real feed, uint32_t seq, uint8_t flags)
{
    lsm_pblock *b = blk(pl, pl->tail);
    memset(b, 0, sizeof *b);
    b->g = *g;
    b->feed_mm_s = feed;
    b->seq = seq;
    b->flags = flags;
    block_coef(pl, b);
    pl->tail++;
}

static void backward_pass(lsm_planner *pl);
static bool horizon_feasible(lsm_planner *pl, bool force);
static bool commitment_kept(lsm_planner *pl);
static bool arrival_ok(lsm_planner *pl, uint32_t id, lsm_real v);
static uint32_t node_after(const lsm_planner *pl, uint32_t after, lsm_real *w);

/* Appends g (which starts at tail_pos), with corner handling at its start. prog_end: its programmed end. */
static lsm_status append_geom(lsm_planner *pl, lsm_geom *g, const lsm_planner_move *mv, const lsm_real prog_end[6],
                              const lsm_arcfit_result *fr)
{
    const lsm_real fit_err = fr ? fr->err_mm : R0;
    if (lsm_planner_free(pl) < 3)
        return LSM_E_FULL;
    const bool has_prev = pl->tail != pl->head;
    lsm_pblock *prev = has_prev ? blk(pl, pl->tail - 1u) : NULL;
    const lsm_real feed = mv->rapid ? LSM_REAL_MAX : mv->feed_mm_s;
    uint8_t flags = mv->rapid ? (uint8_t)LSM_PB_RAPID : (uint8_t)0;
    bool corner = false;
    lsm_corner_result cr;
    lsm_geom g1, g_orig = *g, prev_orig = *g;
    if (!has_prev) {
        flags |= LSM_PB_STOP; /* nothing before: start from rest */
    } else if (pl->tail_tol_mm > R0 && lines_collinear(&prev->g, g)) {
        /* joins G2 as it is */
    } else if (pl->tail_tol_mm > R0 && !pl->tail_rotary && !geom_moves_rotary(g)) {
        /* the trim of the previous block must stay beyond the interpolator's commitment */
        lsm_real room = prev->g.len;
        const uint32_t pid = pl->tail - 1u;
        if (id_lt(pid, pl->horizon_blk))
            room = R0;
        else if (pid == pl->horizon_blk)
            room = prev->g.len - pl->horizon_off;
        lsm_corner_params cp;
        /* the corner gets what the fits of its two blocks left of the tolerance */
        cp.tolerance_mm = lsm_max2(pl->tail_tol_mm - lsm_max2(pl->tail_fit_err, fit_err), LSM_R(0.25) * pl->tail_tol_mm);
        cp.max_trim1_mm = lsm_min2(pl->cfg.trim_share * prev->g.len, LSM_R(0.999) * room);
        cp.max_trim2_mm = pl->cfg.trim_share * g->len;
        lsm_status cs = (cp.max_trim1_mm > R0) ? lsm_corner_smooth(&prev->g, g, &cp, &cr) : LSM_E_CORNER_NO_SOLUTION;
        /* a transition of (almost) no length is a numerical corner case (its curvature, hence its cap, is
         * unbounded): stop there instead */
        const bool degenerate =
            cs == LSM_OK && !(cr.trans[0].len + cr.trans[1].len > LEN_EPS * (R1 + prev->g.len + g->len));
        if (cs == LSM_OK && !degenerate && cr.trim1_mm < prev->g.len && cr.trim2_mm < g->len && cr.trim1_mm <= room) {
            g1 = prev->g;
            lsm_geom g2 = *g;
            if (lsm_geom_trim_end(&g1, cr.trim1_mm) == LSM_OK && lsm_geom_trim_start(&g2, cr.trim2_mm) == LSM_OK &&
                g1.len > R0 && g2.len > R0) {
                corner = true;
                *g = g2;
            } else {
                flags |= LSM_PB_STOP;
            }
        } else if (cs == LSM_E_COLLINEAR) {
            /* already G2 */
        } else {
            flags |= LSM_PB_STOP;
        }
    } else {
        flags |= LSM_PB_STOP;
    }
    if ((flags & LSM_PB_STOP) && has_prev)
        pl->stats.corner_stops++;
    if (corner) {
        prev_orig = prev->g;
        prev->g = g1;
        block_coef(pl, prev);
        push_block(pl, &cr.trans[0], feed, mv->seq, (uint8_t)(LSM_PB_CORNER | (flags & LSM_PB_RAPID)));
        push_block(pl, &cr.trans[1], feed, mv->seq, (uint8_t)(LSM_PB_CORNER | (flags & LSM_PB_RAPID)));
        /* the corner's feed is the slower of the two blocks */
        lsm_pblock *a = blk(pl, pl->tail - 2u), *b = blk(pl, pl->tail - 1u);
        const lsm_real f = lsm_min2(prev->feed_mm_s, feed);
        a->feed_mm_s = b->feed_mm_s = f;
        if (!((prev->flags & LSM_PB_RAPID) && (flags & LSM_PB_RAPID)))
            a->flags &= (uint8_t)~LSM_PB_RAPID, b->flags &= (uint8_t)~LSM_PB_RAPID;
        pl->stats.corners++;
    }
    push_block(pl, g, feed, mv->seq, flags);
    /* where the next block starts: the geometric end (lines: the programmed point itself) */
    if (g->kind == LSM_GEOM_LINE) {
        for (int i = 0; i < LSM_MAX_AXES; i++)
            pl->tail_pos[i] = prog_end[i];
    } else {
        lsm_real p[LSM_MAX_AXES];
        for (int i = 0; i < LSM_MAX_AXES; i++)
            p[i] = pl->tail_pos[i];
        (void)lsm_geom_eval(g, g->len, p, NULL, NULL);
        /* a geometric end within rounding of the programmed one is the programmed one (exact program ends): an arc's
         * end carries the rounding of its radius too (double: its centre, R eps) */
        lsm_real d2 = R0, sc = R1 + (g->kind == LSM_GEOM_ARC ? g->u.arc.radius_mm : R0);
        for (int i = 0; i < 3; i++) {
            d2 += (p[i] - prog_end[i]) * (p[i] - prog_end[i]);
            sc += lsm_fabs(prog_end[i]);
        }
        const bool same = lsm_sqrt(d2) <= LSM_R(64.0) * LSM_REAL_EPS * sc;
        for (int i = 0; i < LSM_MAX_AXES; i++)
            pl->tail_pos[i] = same ? prog_end[i] : p[i];
    }
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pl->tail_prog[i] = prog_end[i];
    pl->tail_tol_mm = mv->tol_mm;
    pl->tail_rotary = geom_moves_rotary(g) ? 1u : 0u;
    pl->tail_fit_err = fit_err;
    pl->tail_arc = 0;
    if (g->kind == LSM_GEOM_ARC && fr != NULL && fr->kind == LSM_ARCFIT_ARC) {
        pl->tail_arc = 1; /* a fitted arc: the next run's arc stays in its plane */
        for (int i = 0; i < 3; i++)
            pl->tail_n[i] = fr->normal[i];
    }
    pl->gen++;
    backward_pass(pl);
    /* a corner that trimmed the block the interpolator's current piece ends in (it runs to the end of the buffer):
     * a verified piece from its commitment point must exist (it will be taken there) */
    const bool stales = (corner && pl->horizon_end == pl->tail - 3u && pl->horizon_v > R0) || pl->piece_stale ||
                        !commitment_kept(pl);
    /* (while a new piece is due at the horizon, every append keeps it possible: the nodes ahead may change) */
    if (has_prev && !(flags & LSM_PB_STOP) && stales && !horizon_feasible(pl, true)) {
        /* the new block (or the trim of its corner) took something the interpolator needs from its commitment
         * on: the machine stops at the junction instead, which restores the previous plan (a stop there) */
        pl->tail -= corner ? 3u : 1u;
        if (corner) {
            prev->g = prev_orig;
            block_coef(pl, prev);
            pl->stats.corners--;
        }
        push_block(pl, &g_orig, feed, mv->seq, (uint8_t)(flags | LSM_PB_STOP));
        pl->stats.corner_stops++;
        pl->stats.horizon_stops++;
        pl->full_pass = 1;
        backward_pass(pl);
    } else if (stales) {
        pl->piece_stale = 1;
    }
    return LSM_OK;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* polyline fitting (arcfit.h)                                                                                   */

/* Feed a clothoid pair on a vertex of a polyline would allow (estimate): a vertex turning by delta between segments
 * h1, h2 gets transitions of half-length L = min(6 eps / delta, min(h1, h2) / 2) (small-angle closed form of
 * corner.h), curvature delta / L and sharpness delta / L²; then eqs 7 and 8 (with the kappa² term) with the
 * smallest axis limits. */
static lsm_real vertex_speed(const lsm_planner *pl, lsm_real h1, lsm_real h2, lsm_real delta, lsm_real eps)
{
    if (!(delta > LSM_R(1e-9)))
        return LSM_REAL_MAX;
    const lsm_real L = lsm_min2(LSM_R(6.0) * eps / delta, LSM_R(0.5) * lsm_min2(h1, h2));
    if (!(L > R0))
        return R0;
    lsm_real amin = LSM_REAL_MAX, jmin = LSM_REAL_MAX;
    for (int i = 0; i < 3; i++) {
        if (!(pl->cfg.axis_mask & (1u << i)))
            continue;
        amin = lsm_min2(amin, pl->cfg.axis[i].a_max);
        jmin = lsm_min2(jmin, pl->cfg.axis[i].j_max);
    }
    const lsm_real k = delta / L, c = delta / (L * L), rho = pl->cfg.cap_margin;
    return lsm_min2(lsm_sqrt(rho * amin / k), lsm_cbrt(rho * jmin / (c + k * k)));
}

/* Would clothoid pairs on the run's own vertices limit the feed below the programmed one? */
static bool run_needs_fit(const lsm_planner *pl, uint32_t n)
{
    const lsm_real eps = pl->fit_tol;
    const lsm_real *prev = pl->tail_pos;
    for (uint32_t i = 0; i + 1u < n; i++) {
        const lsm_real *a = pl->fit_pt[i].p, *b = pl->fit_pt[i + 1u].p;
        lsm_real u[3], w[3];
        for (int k = 0; k < 3; k++) {
            u[k] = a[k] - prev[k];
            w[k] = b[k] - a[k];
        }
        const lsm_real h1 = lsm_sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        const lsm_real h2 = lsm_sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        if (h1 > R0 && h2 > R0) {
            lsm_real cs = (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / (h1 * h2);
            cs = lsm_min2(R1, lsm_max2(-R1, cs));
            const lsm_real delta = lsm_atan2(lsm_sqrt(lsm_max2(R0, R1 - cs * cs)), cs);
            if (vertex_speed(pl, h1, h2, delta, eps) < pl->fit_feed)
                return true;
        }
        prev = a;
    }
    return false;
}

/* The previous block and a fitted arc must share a plane (corner.h blends planar joints only). */
static bool arc_fits_tail(const lsm_planner *pl, const lsm_arcfit_result *fr)
{
    if (pl->tail == pl->head || pl->tail_arc)
        return true; /* nothing before, or the arc was fitted in the previous arc's plane */
    const lsm_pblock *prev = blk(pl, pl->tail - 1u);
    if (prev->g.kind != LSM_GEOM_LINE)
        return false;
    const lsm_real *d = prev->g.u.line.dir;
    const lsm_real dn = d[0] * fr->normal[0] + d[1] * fr->normal[1] + d[2] * fr->normal[2];
#if LSM_REAL_IS_FLOAT
    return lsm_fabs(dn) <= LSM_R(1e-6);
#else
    return lsm_fabs(dn) <= LSM_R(1e-10);
#endif
}

/* Emits the first n pending points: one fitted arc or line if that helps, else their segments as they are. */
static lsm_status emit_run(lsm_planner *pl, uint32_t n)
{
    if (n == 0)
        return LSM_OK;
    if (lsm_planner_free(pl) < 3u * n)
        return LSM_E_FULL;
    const lsm_real tfit = pl->cfg.fit_share * pl->fit_tol;
    lsm_planner_move mv;
    mv.feed_mm_s = pl->fit_feed;
    mv.tol_mm = pl->fit_tol;
    mv.rapid = 0;
    lsm_geom g;
    lsm_arcfit_result fr;
    bool fitted = n >= 2u && lsm_arcfit_fit(pl->tail_pos, pl->fit_pt, (int)n, tfit, pl->tail_arc ? pl->tail_n : NULL,
                                            &g, &fr);
    if (fitted && fr.kind == LSM_ARCFIT_ARC && (!arc_fits_tail(pl, &fr) || !run_needs_fit(pl, n)))
        fitted = false;
    lsm_real end[LSM_MAX_AXES];
    for (int i = 0; i < LSM_MAX_AXES; i++)
        end[i] = pl->tail_pos[i];
    if (fitted) {
        for (int i = 0; i < 3; i++)
            end[i] = pl->fit_pt[n - 1u].p[i];
        if (fr.kind == LSM_ARCFIT_LINE && lsm_geom_line_init(&g, pl->tail_pos, end) != LSM_OK)
            fitted = false;
    }
    lsm_status st = LSM_OK;
    if (fitted) {
        mv.seq = pl->fit_pt[n - 1u].seq;
        st = append_geom(pl, &g, &mv, end, &fr);
    } else {
        for (uint32_t i = 0; i < n && st == LSM_OK; i++) {
            for (int k = 0; k < 3; k++)
                end[k] = pl->fit_pt[i].p[k];
            mv.seq = pl->fit_pt[i].seq;
            if (lsm_geom_line_init(&g, pl->tail_pos, end) != LSM_OK)
                continue; /* a point on the previous one (cannot happen: zero lengths are rejected) */
            st = append_geom(pl, &g, &mv, end, NULL);
        }
    }
    for (uint32_t i = n; i < pl->fit_n; i++)
        pl->fit_pt[i - n] = pl->fit_pt[i];
    pl->fit_n -= n;
    return st;
}

/* A line that may join the pending polyline run. */
static lsm_status append_line_fit(lsm_planner *pl, lsm_geom *g, const lsm_real end[LSM_MAX_AXES],
                                  const lsm_planner_move *mv)
{
    const bool eligible = pl->cfg.fit_share > R0 && !mv->rapid && mv->tol_mm > R0 && !g->rotary_only &&
                          g->u.line.dir[3] == R0 && g->u.line.dir[4] == R0 && g->u.line.dir[5] == R0;
    lsm_status st;
    if (!eligible || (pl->fit_n > 0 && (mv->feed_mm_s != pl->fit_feed || mv->tol_mm != pl->fit_tol))) {
        st = emit_run(pl, pl->fit_n);
        if (st != LSM_OK)
            return st;
    }
    if (!eligible) {
        if (lsm_planner_free(pl) < 3)
            return LSM_E_FULL;
        st = append_geom(pl, g, mv, end, NULL);
        if (st == LSM_OK)
            pl->stats.appended++;
        return st;
    }
    /* the pending run is emitted early when its worst case (every segment a block) would not fit */
    if (lsm_planner_free(pl) < 3u * (pl->fit_n + 1u)) {
        if (pl->fit_n == 0 || lsm_planner_free(pl) < 3u * pl->fit_n)
            return LSM_E_FULL;
        st = emit_run(pl, pl->fit_n);
        if (st != LSM_OK)
            return st;
    }
    if (pl->fit_n > 0) {
        lsm_arcfit_pt cand[LSM_ARCFIT_MAX + 1];
        for (uint32_t i = 0; i < pl->fit_n; i++)
            cand[i] = pl->fit_pt[i];
        for (int k = 0; k < 3; k++)
            cand[pl->fit_n].p[k] = end[k];
        cand[pl->fit_n].seq = mv->seq;
        lsm_geom tg;
        lsm_arcfit_result fr;
        const bool fits = lsm_arcfit_fit(pl->tail_pos, cand, (int)pl->fit_n + 1, pl->cfg.fit_share * mv->tol_mm,
                                         pl->tail_arc ? pl->tail_n : NULL, &tg, &fr);
        if (!fits) {
            st = emit_run(pl, pl->fit_n); /* the run ends before this point */
            if (st != LSM_OK)
                return st;
        }
    }
    pl->fit_feed = mv->feed_mm_s;
    pl->fit_tol = mv->tol_mm;
    for (int k = 0; k < 3; k++)
        pl->fit_pt[pl->fit_n].p[k] = end[k];
    pl->fit_pt[pl->fit_n].seq = mv->seq;
    pl->fit_n++;
    pl->stats.appended++;
    if (pl->fit_n == LSM_ARCFIT_MAX)
        return emit_run(pl, pl->fit_n);
    return LSM_OK;
}

static lsm_status check_append(const lsm_planner *pl, const lsm_planner_move *mv)
{
    if (pl == NULL || mv == NULL)
        return LSM_E_NULL;
    lsm_status st = check_move(mv);
    if (st != LSM_OK)
        return st;
    if (pl->finished)
        return LSM_E_PL_FINISHED;
    return LSM_OK;
}

lsm_status lsm_planner_append_line(lsm_planner *pl, const lsm_real end[LSM_MAX_AXES], const lsm_planner_move *mv)
{
    if (end == NULL)
        return LSM_E_NULL;
    lsm_status st = check_append(pl, mv);
    if (st != LSM_OK)
        return st;
    st = check_vals(end, LSM_MAX_AXES);
    if (st != LSM_OK)
        return st;
    for (int i = 0; i < LSM_MAX_AXES; i++)
        if (!(pl->cfg.axis_mask & (1u << i)) && end[i] != pl->tail_pos[i])
            return LSM_E_PL_AXIS;
    /* the line starts at the last point held for fitting, or at the end of the last block */
    lsm_real from[LSM_MAX_AXES];
    for (int i = 0; i < LSM_MAX_AXES; i++)
        from[i] = (i < 3 && pl->fit_n > 0) ? pl->fit_pt[pl->fit_n - 1u].p[i] : pl->tail_pos[i];
    lsm_geom g;
    st = lsm_geom_line_init(&g, from, end);
    if (st != LSM_OK)
        return st;
    if (g.len <= LEN_EPS * (R1 + lsm_fabs(end[0]) + lsm_fabs(end[1]) + lsm_fabs(end[2])) && !g.rotary_only)
        return LSM_E_ZERO_LENGTH;
    st = append_line_fit(pl, &g, end, mv);
    return st;
}

lsm_status lsm_planner_append_arc(lsm_planner *pl, const lsm_real end[3], const lsm_real centre[3], lsm_geom_plane plane,
                                  int dir, uint32_t turns, const lsm_planner_move *mv)
{
    if (end == NULL || centre == NULL)
        return LSM_E_NULL;
    lsm_status st = check_append(pl, mv);
    if (st != LSM_OK)
        return st;
    st = check_vals(end, 3);
    if (st == LSM_OK)
        st = check_vals(centre, 3);
    if (st != LSM_OK)
        return st;
    lsm_real pe[LSM_MAX_AXES];
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pe[i] = i < 3 ? end[i] : pl->tail_pos[i];
    for (int i = 0; i < 3; i++)
        if (!(pl->cfg.axis_mask & (1u << i)) && end[i] != pl->tail_pos[i])
            return LSM_E_PL_AXIS;
    /* an arc ends a pending polyline run: emit it first (the arc starts at its last point) */
    if (pl->fit_n > 0 && lsm_planner_free(pl) < 3u * pl->fit_n + 3u)
        return LSM_E_FULL;
    lsm_real from[3];
    for (int i = 0; i < 3; i++)
        from[i] = pl->fit_n > 0 ? pl->fit_pt[pl->fit_n - 1u].p[i] : pl->tail_pos[i];
    lsm_geom g;
    st = lsm_geom_arc_init(&g, from, end, centre, plane, dir, turns);
    if (st != LSM_OK)
        return st;
    /* the arc's plane must lie in the existing axes */
    for (int i = 0; i < 3; i++)
        if (!(pl->cfg.axis_mask & (1u << i)) &&
            (g.u.arc.e1[i] != R0 || g.u.arc.e2[i] != R0 || (g.u.arc.axial_mm != R0 && i == (plane == LSM_GEOM_PLANE_XY ? 2 : plane == LSM_GEOM_PLANE_ZX ? 1 : 0))))
            return LSM_E_PL_AXIS;
    if (!(g.len > LEN_EPS))
        return LSM_E_ZERO_LENGTH;
    st = emit_run(pl, pl->fit_n);
    if (st != LSM_OK)
        return st;
    if (lsm_planner_free(pl) < 3)
        return LSM_E_FULL;
    st = append_geom(pl, &g, mv, pe, NULL);
    if (st == LSM_OK)
        pl->stats.appended++;
    return st;
}

lsm_status lsm_planner_flush(lsm_planner *pl)
{
    if (pl == NULL)
        return LSM_E_NULL;
    return emit_run(pl, pl->fit_n);
}

lsm_status lsm_planner_finish(lsm_planner *pl)
{
    if (pl == NULL)
        return LSM_E_NULL;
    if (pl->finished)
        return LSM_OK;
    lsm_status st = emit_run(pl, pl->fit_n);
    if (st != LSM_OK)
        return st;
    pl->finished = 1;
    pl->gen++;
    return LSM_OK;
}

void lsm_planner_set_horizon(lsm_planner *pl, uint32_t id, lsm_real off_mm, lsm_real v_mm_s, uint32_t end_blk,
                             lsm_real end_v_mm_s)
{
    if (pl == NULL)
        return;
    pl->horizon_blk = id;
    pl->horizon_off = off_mm;
    pl->horizon_v = v_mm_s > R0 ? v_mm_s : R0;
    const lsm_real ev = end_v_mm_s > R0 ? end_v_mm_s : R0;
    if (end_blk != pl->horizon_end || ev != pl->horizon_end_v)
        pl->commit_dirty = 1;
    pl->horizon_end = end_blk;
    pl->horizon_end_v = ev;
}

/* Does the interpolator's current piece still end where it may go on (planner.h, lsm_planner_set_horizon)? */
static bool commitment_kept(lsm_planner *pl)
{
    const uint32_t e = pl->horizon_end;
    if (!(pl->horizon_v > R0) || !(pl->horizon_end_v > R0) || id_lt(e, pl->head) || !id_lt(e, pl->tail))
        return true;
    if (blk(pl, e)->flags & LSM_PB_STOP)
        return false;
    /* The test depends on the blocks from e to the node after it and on that node's W. A backward pass that stopped
     * at or after that node (bp_stop: everything before it unchanged) changed none of it, unless the stretch runs
     * to the end of the buffer (a trim, or new blocks behind it). Else verified afresh, not read from the node's
     * W: valleys move when blocks are appended (a node can vanish, or the one after it change). */
    lsm_real w2;
    const uint32_t n2 = node_after(pl, e, &w2);
    if (n2 != pl->tail && !id_lt(pl->bp_stop, n2) && !pl->commit_dirty)
        return true;
    const bool ok = arrival_ok(pl, e, pl->horizon_end_v);
    if (ok)
        pl->commit_dirty = 0;
    return ok;
}

void lsm_planner_release(lsm_planner *pl, uint32_t id)
{
    if (pl == NULL)
        return;
    while (id_lt(pl->head, id) && pl->head != pl->tail) {
        pl->head++;
        pl->head_slot = (pl->head_slot + 1u) % pl->cap;
    }
}

/* ------------------------------------------------------------------------------------------------------------ */
/* pieces of path: blocks addressed by a position x relative to a start (id0, off0)                             */

typedef struct pctx {
    const lsm_planner *pl;
    uint32_t id0;     /* first block */
    lsm_real off0;    /* start offset in it */
    uint32_t id_end;  /* one past the last block */
    lsm_real D;       /* length from the start to the start of id_end */
    lsm_real floor;   /* feed caps raised to this (override catch-up) */
    uint32_t cid;     /* cursor: block cid starts at x = cx */
    lsm_real cx;
} pctx;

static void pctx_init(pctx *pc, const lsm_planner *pl, uint32_t id0, lsm_real off0, uint32_t id_end)
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
static void seek(pctx *pc, lsm_real x)
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
static lsm_real range_cap(pctx *pc, lsm_real xa, lsm_real xb)
{
    seek(pc, xa);
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

static bool region_ok(pctx *pc, lsm_real xa, lsm_real xb, lsm_real v)
{
    if (!(v > R0))
        return true;
    if (xb < xa)
        return true;
    return v <= range_cap(pc, xa, xb) * (R1 + CAP_SLACK);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* ramps: one sin² velocity change                                                                               */

typedef struct ramp {
    lsm_scurve_intervals iv;
    lsm_real v0, v1, jp; /* jp signed (eq 34 corrected) */
    lsm_real dist;       /* (v0 + v1) tp / 2 */
    lsm_real a_lim, j_lim, s_lim;
} ramp;

static bool ramp_plan(ramp *r, lsm_real dt, lsm_real v0, lsm_real v1, lsm_real a, lsm_real j, lsm_real s)
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
    if (n == 0 || n > 0x1000000u)
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
static const lsm_real k_sin8[9] = {LSM_R(0.0), LSM_R(0.38268343236508977), LSM_R(0.70710678118654752),
                                   LSM_R(0.92387953251128676), LSM_R(1.0), LSM_R(0.92387953251128676),
                                   LSM_R(0.70710678118654752), LSM_R(0.38268343236508977), LSM_R(0.0)};
static const lsm_real k_cos8[9] = {LSM_R(1.0), LSM_R(0.92387953251128676), LSM_R(0.70710678118654752),
                                   LSM_R(0.38268343236508977), LSM_R(0.0), LSM_R(-0.38268343236508977),
                                   LSM_R(-0.70710678118654752), LSM_R(-0.92387953251128676), LSM_R(-1.0)};

/* State after tau into a phase of length T, given sin and cos of phi = pi tau / T (sin² phases). */
static void phase_at(const lsm_phase *ph, lsm_real T, const lsm_kin *s0, lsm_real tau, lsm_real sphi, lsm_real cphi,
                     lsm_kin *out)
{
    lsm_real u0, u1, u2, u3;
    const lsm_real t = tau;
    if (ph->shape == LSM_PHASE_CONST) {
        u0 = R1;
        u1 = t;
        u2 = t * t / LSM_R(2.0);
        u3 = t * t * t / LSM_R(6.0);
    } else {
        const lsm_real w = PI_R / (LSM_R(2.0) * T);
        const lsm_real sg = ph->shape == LSM_PHASE_RISE ? R1 : -R1;
        u0 = (R1 - sg * cphi) / LSM_R(2.0);
        u1 = t / LSM_R(2.0) - sg * sphi / (LSM_R(4.0) * w);
        u2 = t * t / LSM_R(4.0) - sg * (R1 - cphi) / (LSM_R(8.0) * w * w);
        u3 = t * t * t / LSM_R(12.0) - sg * t / (LSM_R(8.0) * w * w) + sg * sphi / (LSM_R(16.0) * w * w * w);
    }
    const lsm_real jk = ph->jerk_mm_s3;
    const lsm_kin a = *s0;
    out->j_mm_s3 = jk * u0;
    out->a_mm_s2 = a.a_mm_s2 + jk * u1;
    out->v_mm_s = a.v_mm_s + a.a_mm_s2 * t + jk * u2;
    out->s_mm = a.s_mm + a.v_mm_s * t + a.a_mm_s2 * t * t / LSM_R(2.0) + jk * u3;
}

typedef struct rcheck {
    lsm_real ra, rj, rs;  /* >= 1: the budgets hold; < 1: scale the ramp's a, j, snap by this */
    int vviol;            /* a speed above a block's cap */
    lsm_real vx0, vx1;    /* that block's extent (x) */
    lsm_real vcap;        /* and its cap */
} rcheck;

/* One sub-interval against the blocks it touches. */
static void check_span(pctx *pc, lsm_real xa, lsm_real xb, lsm_real vhi, lsm_real amax, lsm_real jmax, lsm_real sn,
                       rcheck *res)
{
    const lsm_planner *pl = pc->pl;
    if (xb < xa) {
        const lsm_real t = xa;
        xa = xb;
        xb = t;
    }
    seek(pc, xa);
    uint32_t id = pc->cid;
    lsm_real x = pc->cx;
    for (;;) {
        const lsm_pblock *b = blk(pl, id);
        const lsm_real cap = cap_floor(pl, id, b, pc->floor);
        if (vhi > cap * (R1 + CAP_SLACK)) {
            if (!res->vviol) {
                res->vviol = 1;
                res->vx0 = x;
                res->vx1 = x + b->g.len;
                res->vcap = cap;
            }
            return;
        }
        coef c;
        coef_get(b, &c);
        const lsm_real v = vhi;
        if (amax > R0 && c.aa > R0) {
            const lsm_real al = (R1 - c.ba * v * v) / c.aa;
            const lsm_real r = al > R0 ? al / amax : R0;
            if (r < res->ra)
                res->ra = r;
        }
        if (c.aj > R0) {
            const lsm_real room = R1 - c.gj * v * v * v;
            const lsm_real cross = LSM_R(3.0) * c.bj * v * amax;
            if (cross > LSM_R(0.9) * room) { /* the acceleration eats the jerk budget: lower the acceleration */
                const lsm_real r = (cross > R0 && room > R0) ? LSM_R(0.5) * room / cross : R0;
                if (r < res->ra)
                    res->ra = r;
                if (res->rj > LSM_R(0.5))
                    res->rj = LSM_R(0.5);
            } else if (jmax > R0) {
                const lsm_real r = (room - cross) / c.aj / jmax;
                if (r < res->rj)
                    res->rj = r;
            }
        }
        if (sn > R0 && c.as > R0) {
            const lsm_real r = (R1 / c.as) / sn;
            if (r < res->rs)
                res->rs = r;
        }
        x += b->g.len;
        id++;
        if (!(x < xb) || id == pc->id_end)
            break;
    }
}

/* Verifies a ramp placed at x_s (its start). */
static void ramp_check(pctx *pc, const ramp *r, lsm_real x_s, rcheck *res)
{
    lsm_planner *pl = (lsm_planner *)pc->pl; /* statistics only */
    pl->stats.checks++;
    res->ra = res->rj = res->rs = LSM_REAL_MAX;
    res->vviol = 0;
    const lsm_real dt = pl->cfg.cycle_s;
    lsm_phase ph[7];
    lsm_scurve_phases(&r->iv, r->jp, ph);
    lsm_kin st = {R0, r->v0, R0, R0};
    const lsm_real sn = ramp_speak(r, dt);
    if (lsm_scurve_total_cycles(&r->iv) == 0) {
        check_span(pc, x_s, x_s, r->v0, R0, R0, R0, res);
        return;
    }
    for (int p = 0; p < 7; p++) {
        const uint32_t n = ph[p].n_cycles;
        if (n == 0)
            continue;
        const lsm_real T = (lsm_real)n * dt;
        int Q = n >= 8u ? 8 : n >= 4u ? 4 : n >= 2u ? 2 : 1;
        lsm_kin prev = st, cur;
        if (Q > 1) {
            /* the whole phase as one span first (v, |a| and |j| are monotone in a phase: their extremes are the
             * end values, and they bound those of every part): where that holds, so do the parts; the finer
             * sub-intervals are only needed where the budgets fall with the speed (curved blocks) */
            lsm_kin e;
            lsm_phase_end(&ph[p], dt, &st, &e);
            rcheck whole = *res;
            check_span(pc, x_s + st.s_mm, x_s + e.s_mm, lsm_max2(st.v_mm_s, e.v_mm_s),
                       lsm_max2(lsm_fabs(st.a_mm_s2), lsm_fabs(e.a_mm_s2)),
                       lsm_max2(lsm_fabs(st.j_mm_s3), lsm_fabs(e.j_mm_s3)), ph[p].shape == LSM_PHASE_CONST ? R0 : sn,
                       &whole);
            if (!whole.vviol && whole.ra >= R1 && whole.rj >= R1 && whole.rs >= R1) {
                res->ra = lsm_min2(res->ra, whole.ra); /* (ratios of the coarser check: a lower bound of the finer) */
                res->rj = lsm_min2(res->rj, whole.rj);
                res->rs = lsm_min2(res->rs, whole.rs);
                st = e;
                continue;
            }
        }
        for (int q = 1; q <= Q; q++) {
            const int k8 = q * (8 / Q);
            if (q == Q)
                lsm_phase_end(&ph[p], dt, &st, &cur);
            else
                phase_at(&ph[p], T, &st, T * (lsm_real)q / (lsm_real)Q, k_sin8[k8], k_cos8[k8], &cur);
            const lsm_real vhi = lsm_max2(prev.v_mm_s, cur.v_mm_s);
            const lsm_real amax = lsm_max2(lsm_fabs(prev.a_mm_s2), lsm_fabs(cur.a_mm_s2));
            const lsm_real jmax = lsm_max2(lsm_fabs(prev.j_mm_s3), lsm_fabs(cur.j_mm_s3));
            check_span(pc, x_s + prev.s_mm, x_s + cur.s_mm, vhi, amax, jmax, ph[p].shape == LSM_PHASE_CONST ? R0 : sn,
                       res);
            if (res->vviol)
                return;
            prev = cur;
        }
        st = cur;
    }
}

static bool rcheck_ok(const rcheck *c)
{
    return !c->vviol && c->ra >= R1 && c->rj >= R1 && c->rs >= R1;
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
            const lsm_real tol = LSM_R(1e-7) * dt;
            const lsm_real dv_ph = e.v_mm_s - st.v_mm_s;
            lsm_real t = dv_ph != R0 ? hi * (c - st.v_mm_s) / dv_ph : hi;
            for (int it = 0; it < 24 && hi - lo > tol; it++) {
                if (!(t > lo && t < hi))
                    t = (lo + hi) / LSM_R(2.0);
                lsm_kin m;
                lsm_phase_advance(&ph[p], dt, &st, t, &m);
                const bool past = up ? (m.v_mm_s >= c) : (m.v_mm_s <= c);
                if (past)
                    hi = t;
                else
                    lo = t;
                const lsm_real step = m.a_mm_s2 != R0 ? (c - m.v_mm_s) / m.a_mm_s2 : hi - lo;
                if (lsm_fabs(step) < tol) {
                    if (!past)
                        hi = lsm_min2(hi, t + tol); /* (v moves by a tol there: reached within rounding) */
                    break;
                }
                t += step;
            }
            lsm_kin m;
            lsm_phase_advance(&ph[p], dt, &st, hi, &m);
            return m.s_mm;
        }
        st = e;
    }
    return r->dist;
}

/* First guess of the tangential limits near x: the block's budgets at rest. */
static void guess_limits(pctx *pc, lsm_real x, lsm_real *a, lsm_real *j, lsm_real *s)
{
    seek(pc, x);
    coef c;
    coef_get(blk(pc->pl, pc->cid), &c);
    *a = c.aa > R0 ? R1 / c.aa : LSM_R(1e12);
    *j = c.aj > R0 ? R1 / c.aj : LSM_R(1e15);
    *s = c.as > R0 ? R1 / c.as : LSM_R(1e18);
}

/* Lowers the limits after a check that failed on the budgets. */
static bool rescale(ramp *r, lsm_real dt, const rcheck *c, int it)
{
    const lsm_real k = it > 12 ? LSM_R(0.9) : LSM_R(0.995);
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
        r->a_lim *= LSM_R(0.9);
        r->j_lim *= LSM_R(0.9);
        r->s_lim *= LSM_R(0.9);
    }
    return r->a_lim > LSM_R(1e-9) && r->j_lim > LSM_R(1e-9) && r->s_lim > LSM_R(1e-9);
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
        ramp_check(pc, r, x, c);
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
            const lsm_real room = LSM_R(1.2);
            if (ups >= 2 || !(c->ra > room || c->rj > room))
                return 1;
            /* try faster */
            ups++;
            const lsm_real na = c->ra > room ? lsm_min2(ramp_apeak(r, dt) * c->ra * LSM_R(0.99), r->a_lim * LSM_R(8.0)) : r->a_lim;
            const lsm_real nj = c->rj > room ? lsm_min2(lsm_fabs(r->jp) * c->rj * LSM_R(0.99), r->j_lim * LSM_R(8.0)) : r->j_lim;
            const lsm_real ns = c->rs > room ? lsm_min2(ramp_speak(r, dt) * c->rs * LSM_R(0.99), r->s_lim * LSM_R(8.0)) : r->s_lim;
            if (!(na > r->a_lim || nj > r->j_lim || ns > r->s_lim))
                return 1;
            if (!ramp_plan(r, dt, v0, v1, lsm_max2(na, r->a_lim), lsm_max2(nj, r->j_lim), lsm_max2(ns, r->s_lim)) ||
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
        if (!rescale(r, dt, c, it) || !ramp_plan(r, dt, v0, v1, r->a_lim, r->j_lim, r->s_lim))
            return 0;
    }
    if (have) {
        *r = best;
        *xs = anchor_end ? x_at - r->dist : x_at;
        return 1;
    }
    return 0;
}

/*
 * Decelerating ramp v0 -> v1 (v0 > v1) on [X0, X1]: placed as late as it verifies, ending at X1 exactly when
 * `exact`. Region checks: lead cruise at v0 on [X0, start] (if check_lead), trail cruise at v1 on [end, X1].
 * Returns the ramp and its start.
 */
static bool fit_decel(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, bool exact, bool check_lead,
                      ramp *r, lsm_real *xs_out)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    lsm_real a, j, s;
    guess_limits(pc, X1, &a, &j, &s);
    if (!ramp_plan(r, dt, v0, v1, a, j, s))
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
            lsm_real nxs = c.vx0 - ramp_pos_at_speed(r, dt, c.vcap);
            if (c.vx0 == last_vx || !(nxs < xs))
                nxs = c.vx0 - r->dist; /* end the ramp before the block */
            if (!(nxs < xs))
                nxs = xs - LSM_R(1e-6) * (R1 + r->dist);
            last_vx = c.vx0;
            xe = nxs + r->dist;
            guess_limits(pc, xe, &a, &j, &s);
            if (!ramp_plan(r, dt, v0, v1, lsm_max2(a, r->a_lim), lsm_max2(j, r->j_lim), lsm_max2(s, r->s_lim)))
                return false;
            continue;
        }
        if (check_lead && !region_ok(pc, X0, xs, v0))
            return false;
        if (!region_ok(pc, xs + r->dist, X1, v1))
            return false;
        *xs_out = xs;
        return true;
    }
    return false;
}

/*
 * Accelerating ramp v0 -> v1 (v1 > v0) starting at or after X0, placed as early as it verifies (a lead cruise
 * at v0 if needed; none from rest). With check_trail, cruising at v1 from its end to X1 must fit too.
 */
static bool fit_accel(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, bool check_trail, ramp *r,
                      lsm_real *xs_out)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    lsm_real a, j, s;
    guess_limits(pc, X0, &a, &j, &s);
    if (!ramp_plan(r, dt, v0, v1, a, j, s))
        return false;
    lsm_real xs = X0, last_vx = -LSM_REAL_MAX;
    for (int it = 0; it < FIT_ITER; it++) {
        rcheck c;
        lsm_real xr;
        const int t = tune_ramp(pc, r, v0, v1, false, xs, X0, X1, &xr, &c);
        if (t == 0)
            return false;
        if (t < 0) {
            if (!(v0 > R0) || c.vcap < v0 * (R1 - CAP_SLACK))
                return false;
            /* move the start so that the ramp reaches the cap at the block's end; if the same block is hit again
             * (the sub-interval bound is coarser than the ramp), start after the block */
            lsm_real nxs = c.vx1 - ramp_pos_at_speed(r, dt, c.vcap);
            if (c.vx1 == last_vx || !(nxs > xs))
                nxs = c.vx1;
            if (!(nxs > xs))
                nxs = xs + LSM_R(1e-6) * (R1 + r->dist);
            last_vx = c.vx1;
            xs = nxs;
            guess_limits(pc, xs, &a, &j, &s);
            if (!ramp_plan(r, dt, v0, v1, lsm_max2(a, r->a_lim), lsm_max2(j, r->j_lim), lsm_max2(s, r->s_lim)))
                return false;
            continue;
        }
        if (!region_ok(pc, X0, xr, v0))
            return false;
        if (check_trail && !region_ok(pc, xr + r->dist, X1, v1))
            return false;
        *xs_out = xr;
        return true;
    }
    return false;
}

/* Decelerating ramp starting exactly at X0 (override catch-up, feed hold). */
static bool fit_decel_now(pctx *pc, lsm_real X0, lsm_real X1, lsm_real v0, lsm_real v1, ramp *r)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    lsm_real a, j, s;
    guess_limits(pc, X0, &a, &j, &s);
    if (!ramp_plan(r, dt, v0, v1, a, j, s))
        return false;
    rcheck c;
    lsm_real xs;
    return tune_ramp(pc, r, v0, v1, false, X0, X0, X1, &xs, &c) == 1;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* backward pass                                                                                                 */

/* Time of one continuous sin² velocity change by dv with the tangential limits a, j, s (Kombarov eqs 25-31, before
 * quantisation: the whole-cycle profile of the strict rule takes a few cycles more). */
static lsm_real ramp_time_cont(lsm_real dv, lsm_real a, lsm_real j, lsm_real s)
{
    if (!(dv > R0))
        return R0;
    lsm_real t1 = PI_R * j / (LSM_R(2.0) * s);                          /* eq 25 */
    t1 = lsm_min2(t1, lsm_sqrt(PI_R * a / (LSM_R(2.0) * s)));          /* eq 26 */
    t1 = lsm_min2(t1, lsm_cbrt(PI_R * dv / (LSM_R(4.0) * s)));         /* eq 29 */
    const lsm_real jc = LSM_R(2.0) * t1 * s / PI_R;                    /* eq 32 */
    const lsm_real t2 = lsm_max2(lsm_min2(a / jc - t1, lsm_sqrt(t1 * t1 / LSM_R(4.0) + dv / jc) - LSM_R(1.5) * t1), R0);
    const lsm_real ap = jc * (t1 + t2);                                /* eq 23 */
    const lsm_real t4 = lsm_max2(dv / ap - LSM_R(2.0) * t1 - t2, R0);  /* eq 31 */
    return LSM_R(4.0) * t1 + LSM_R(2.0) * t2 + t4;
}

/* Highest speed v in [w, vmax] from which one continuous ramp to w (or from w up to v) fits in distance D:
 * (v + w) t(v - w) / 2 <= D, the travel being monotone in v. A first probe for the searches below. */
static lsm_real speed_for_dist(lsm_real w, lsm_real D, lsm_real a, lsm_real j, lsm_real s, lsm_real vmax)
{
    if (!(vmax > w) || !(D > R0))
        return w;
    if ((vmax + w) * ramp_time_cont(vmax - w, a, j, s) <= LSM_R(2.0) * D)
        return vmax;
    lsm_real lo = w, hi = vmax;
    for (int it = 0; it < 40 && hi - lo > SPEED_RES * LSM_R(0.25) * hi; it++) {
        const lsm_real mid = (lo + hi) / LSM_R(2.0);
        if ((mid + w) * ramp_time_cont(mid - w, a, j, s) <= LSM_R(2.0) * D)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Highest cruise vc in [max(v0, v1), vmax] for which two continuous ramps v0 -> vc -> v1 fit in distance D. */
static lsm_real cruise_for_dist(lsm_real v0, lsm_real v1, lsm_real D, lsm_real a, lsm_real j, lsm_real s,
                                lsm_real vmax)
{
    lsm_real lo = lsm_max2(v0, v1), hi = vmax;
    if (!(hi > lo) || !(D > R0))
        return lo;
    for (int it = 0; it < 40 && hi - lo > SPEED_RES * LSM_R(0.25) * hi; it++) {
        const lsm_real mid = it == 0 ? hi : (lo + hi) / LSM_R(2.0);
        const lsm_real d = (v0 + mid) * ramp_time_cont(mid - v0, a, j, s) + (mid + v1) * ramp_time_cont(mid - v1, a, j, s);
        if (d <= LSM_R(2.0) * D) {
            if (it == 0)
                return hi;
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

/* The test of a node's W for speed v over the piece pc (from the node to the next one, whose W is w1; exactly if
 * exact): one verified ramp from v reaches w1 by its end (*r, starting at *xs), or a cruise at v goes through. */
static bool w_test(pctx *pc, lsm_real v, lsm_real w1, bool exact, ramp *r, lsm_real *xs)
{
    return v <= w1 ? region_ok(pc, R0, pc->D, v) : fit_decel(pc, R0, pc->D, v, w1, exact, true, r, xs);
}

/* The midpoint of a bisection over [lo, hi], or the first time the probe when it lies inside the bracket (the
 * bracket only narrows: a probe outside it stays outside, so it is used at most once). */
static lsm_real probe_mid(lsm_real lo, lsm_real hi, lsm_real *probe)
{
    const lsm_real p = *probe;
    *probe = R0;
    return p > lo && p < hi ? p : (lo + hi) / LSM_R(2.0);
}

/* W of a node: highest v0 <= c0 from which the piece [0, D] reaches w1 at its end (exactly if exact): a bisection
 * between the speed that can cruise through the piece (or 0 before an exact stop) and c0. Feasibility is not
 * strictly monotone in the speed near the caps (whole-cycle ramps against budgets that vanish at the cap), so a W
 * may move either way when w1 changes: the interpolator's commitment is checked after every append
 * (commitment_kept). */
static lsm_real node_w(lsm_planner *pl, uint32_t id, uint32_t id_end, lsm_real w1, bool exact)
{
    pl->stats.bp_nodes++;
    pctx pc;
    pctx_init(&pc, pl, id, R0, id_end);
    const lsm_real c0 = cap_of(pl, id);
    const lsm_real D = pc.D;
    const lsm_real mincap = range_cap(&pc, R0, D);
    lsm_real lo = lsm_min2(mincap, w1); /* cruising at lo through the piece always works */
    if (exact)
        lo = R0;
    lsm_real hi = c0;
    if (!(hi > lo))
        return hi;
    ramp r;
    lsm_real xs;
    if (w_test(&pc, hi, w1, exact, &r, &xs))
        return hi;
    /* first probe: the speed from which one continuous ramp with the budgets at the node's end fits in D (the
     * whole-cycle, verified ramp needs at least that room); then bisection to SPEED_RES */
    lsm_real ga, gj, gs;
    guess_limits(&pc, D, &ga, &gj, &gs);
    lsm_real probe = speed_for_dist(lsm_max2(w1, lo), D, ga, gj, gs, hi);
    for (int it = 0; it < W_BISECT && hi - lo > SPEED_RES * hi; it++) {
        const lsm_real mid = probe_mid(lo, hi, &probe);
        if (w_test(&pc, mid, w1, exact, &r, &xs))
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* The test of node_w for speed v at node id: one verified ramp from v reaches w1 by the next node id_end (exactly
 * if exact), or a cruise at v goes through. */
static bool cert_ok(lsm_planner *pl, uint32_t id, uint32_t id_end, lsm_real v, lsm_real w1, bool exact)
{
    pctx pc;
    pctx_init(&pc, pl, id, R0, id_end);
    if (!(pc.D > LEN_EPS * (R1 + pc.D)))
        return v <= w1;
    ramp r;
    lsm_real xs;
    return w_test(&pc, v, w1, exact, &r, &xs);
}

/* Can a piece that arrives at node `id` (a = 0) at speed v go on? The test of node_w: one verified ramp from v
 * reaches the next node's W (or a cruise at v goes through). A piece that arrives below the node's W needs this:
 * W itself was verified, but whole-cycle ramps make the lower speeds not always so. */
static bool arrival_ok(lsm_planner *pl, uint32_t id, lsm_real v)
{
    if (!(v > R0) || id == pl->tail || !id_lt(id, pl->tail) || (blk(pl, id)->flags & LSM_PB_STOP))
        return true;
    lsm_real w2;
    const uint32_t n2 = node_after(pl, id, &w2);
    return cert_ok(pl, id, n2, v, w2, !(w2 > R0));
}

/* Valley detection while walking backwards (see planner.h: nodes at valleys and significant drops). */
typedef struct vstate {
    lsm_real M;       /* highest cap since the last node (walking back) */
    lsm_real m;       /* lowest cap after the peak */
    uint32_t m_id;
    uint8_t desc;
    uint8_t has_last;
    lsm_real last_c;
    uint32_t last_id;
} vstate;

static void vreset(vstate *s)
{
    s->M = -R1;
    s->m = LSM_REAL_MAX;
    s->m_id = 0;
    s->desc = 0;
    s->has_last = 0;
    s->last_c = R0;
    s->last_id = 0;
}

/* Feeds block id (cap c); returns 1 and *node when a node is found (at an id after `id`). */
static int vstep(vstate *s, uint32_t id, lsm_real c, lsm_real h, lsm_real drop, uint32_t *node)
{
    if (s->has_last && s->last_c < c * (R1 - drop)) {
        *node = s->last_id;
        return 1;
    }
    if (!s->desc) {
        if (c >= s->M)
            s->M = c;
        else if (c * (R1 + h) < s->M) {
            s->desc = 1;
            s->m = c;
            s->m_id = id;
        }
    } else {
        if (c <= s->m) {
            s->m = c;
            s->m_id = id;
        } else if (c > s->m * (R1 + h)) {
            *node = s->m_id;
            return 1;
        }
    }
    s->has_last = 1;
    s->last_c = c;
    s->last_id = id;
    return 0;
}

/*
 * Cap seen by the node detection: for a block shorter than 2 ERODE_CYCLES cycles of travel, the lowest cap from
 * its start to that distance ahead, the travel measured at the speed of the dips ahead (two passes). This removes
 * humps too short to change speed in (e.g. the lines between the corners of a dense polyline), so that valleys are
 * those of the envelope, and keeps the detection local (a node depends only on the caps after it, never on the
 * interpolator's position or on other nodes).
 */
#define ERODE_CYCLES 4
static lsm_real min_cap_ahead(const lsm_planner *pl, uint32_t id, lsm_real d)
{
    lsm_real m = cap_of(pl, id), x = blk(pl, id)->g.len;
    /* (not across an exact stop: what comes after one never moves the nodes before it, so that a junction made an
     * exact stop restores the plan before it exactly) */
    for (uint32_t q = id + 1u; q != pl->tail && x < d && !(blk(pl, q)->flags & LSM_PB_STOP); q++) {
        m = lsm_min2(m, cap_of(pl, q));
        x += blk(pl, q)->g.len;
    }
    return m;
}

static lsm_real eroded_cap(const lsm_planner *pl, uint32_t id)
{
    const lsm_real c = cap_of(pl, id);
    const lsm_real k = LSM_R(2.0) * (lsm_real)ERODE_CYCLES * pl->cfg.cycle_s;
    const lsm_real len = blk(pl, id)->g.len;
    if (len >= k * c)
        return c; /* a plateau of its own */
    /* the window is measured at the speed the dips ahead allow: a hump matters if there is room to speed up from
     * them, not from its own cap */
    const lsm_real m1 = min_cap_ahead(pl, id, k * c);
    if (len >= k * m1)
        return c;
    return min_cap_ahead(pl, id, k * m1);
}

static void backward_pass(lsm_planner *pl)
{
    if (pl->tail == pl->head)
        return;
    const lsm_real h = pl->cfg.node_hyst, drop = pl->cfg.node_drop;
    uint32_t n_id = pl->tail; /* the end of the buffer: a stop */
    lsm_real n_w = R0;
    bool n_exact = true;
    vstate vs;
    vreset(&vs);
    const uint32_t lo = pl->head;
    uint32_t k = pl->tail;
    while (k != lo) {
        k--;
        lsm_pblock *b = blk(pl, k);
        uint32_t node = 0;
        int found = 0;
        if (b->flags & LSM_PB_STOP) {
            /* pending valley between here and the next node first */
            if (vs.desc && id_lt(k, vs.m_id)) {
                node = vs.m_id;
                found = 1;
            } else {
                node = k;
                found = 2;
            }
        } else {
            found = vstep(&vs, k, eroded_cap(pl, k), h, drop, &node);
        }
        if (!found)
            continue; /* (its node flag is settled when the node before it is found: a block may turn out to be the
                         valley once the walk has gone past it, and its old flag tells whether its W changed) */
        /* a node at `node` (node >= k) */
        lsm_pblock *nb = blk(pl, node);
        lsm_real w = (nb->flags & LSM_PB_STOP) ? R0 : node_w(pl, node, n_id, n_w, n_exact);
        /* unchanged, or higher by less than the searches resolve and the old W still certified against the node
         * after it (feasibility is not strictly monotone in the speed, so a lower W is not certified by a higher
         * one): the old W stays, and so does everything before it */
        const bool was = (nb->flags & LSM_PB_NODE) != 0 && !pl->full_pass;
        const bool same = was && (nb->w_mm_s == w || (w > nb->w_mm_s && w <= nb->w_mm_s * (R1 + SPEED_RES) &&
                                                      cert_ok(pl, node, n_id, nb->w_mm_s, n_w, n_exact)));
        if (same)
            w = nb->w_mm_s;
        nb->flags |= LSM_PB_NODE;
        nb->w_mm_s = w;
        for (uint32_t q = node + 1u; q != n_id; q++) /* blocks inside the piece are not nodes */
            blk(pl, q)->flags &= (uint8_t)~LSM_PB_NODE;
        n_id = node;
        n_w = w;
        n_exact = (nb->flags & LSM_PB_STOP) != 0;
        if (same) {
            pl->bp_stop = node;
            return; /* everything before is unchanged */
        }
        /* restart the detection just before the node and walk again down to k */
        vreset(&vs);
        k = node;
    }
    /* a valley still pending at the interpolator stays inside the first piece (verified pointwise there) */
    for (uint32_t q = pl->head; q != n_id; q++)
        blk(pl, q)->flags &= (uint8_t)~LSM_PB_NODE;
    pl->full_pass = 0;
    pl->bp_stop = pl->head;
}

void lsm_planner_update(lsm_planner *pl)
{
    if (pl)
        backward_pass(pl);
}

lsm_status lsm_planner_set_override(lsm_planner *pl, lsm_real f, uint32_t cur, lsm_real v_now)
{
    if (pl == NULL)
        return LSM_E_NULL;
    if (f != f)
        return LSM_E_NAN;
    if (!(f >= R0 && f <= LSM_R(2.0)))
        return LSM_E_PL_OVERRIDE;
    if (id_lt(cur, pl->head) || !id_lt(cur, pl->tail))
        cur = pl->head;
    const lsm_real hi = lsm_max2(pl->ovr_near, pl->ovr_far);
    if (f >= hi || pl->tail == pl->head) {
        pl->ovr_near = pl->ovr_far = f;
        pl->ovr_switch = cur;
    } else {
        /* blocks within twice the stopping-scale distance keep the larger factor; the new one applies beyond */
        pl->ovr_near = hi;
        pl->ovr_far = f;
        coef c;
        coef_get(blk(pl, cur), &c);
        ramp r;
        lsm_real need = R0;
        const lsm_real a = c.aa > R0 ? LSM_R(0.5) / c.aa : LSM_R(1e12);
        const lsm_real j = c.aj > R0 ? LSM_R(0.5) / c.aj : LSM_R(1e15);
        const lsm_real s = c.as > R0 ? LSM_R(0.5) / c.as : LSM_R(1e18);
        if (v_now > R0 && ramp_plan(&r, pl->cfg.cycle_s, v_now, R0, a, j, s))
            need = LSM_R(2.0) * r.dist + LSM_R(4.0) * v_now * pl->cfg.cycle_s;
        /* the switch must leave a verified piece from the interpolator's commitment point (catching up with
         * the lower caps): further out until it does; at worst only blocks appended later get the new factor */
        for (int tries = 0;; tries++) {
            uint32_t id = cur;
            lsm_real d = R0;
            while (id != pl->tail && d <= need) {
                d += blk(pl, id)->g.len;
                id++;
            }
            if (tries >= 8)
                id = pl->tail;
            pl->ovr_switch = id;
            pl->full_pass = 1;
            pl->gen++;
            backward_pass(pl);
            if (id == pl->tail || horizon_feasible(pl, false))
                break;
            need = LSM_R(2.0) * need + blk(pl, cur)->g.len;
        }
        if (!commitment_kept(pl))
            pl->piece_stale = 1; /* (the loop verified a piece from the horizon) */
        return LSM_OK;
    }
    pl->full_pass = 1;
    pl->gen++;
    backward_pass(pl);
    return LSM_OK;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* pieces                                                                                                        */

typedef struct plan5 {
    bool step;        /* ramp A is one step of a staircase (the interpolator re-plans at its end) */
    lsm_real v0, vc, v1;
    ramp A, B;
    lsm_real xA, xB;  /* ramp starts (piece-relative); lead cruise [0, xA], cruise [xA + A.dist, xB],
                         trail cruise [xB + B.dist, D] */
} plan5;

static void no_ramp(ramp *r, lsm_real dt, lsm_real v)
{
    ramp_plan(r, dt, v, v, R1, R1, R1);
}

/* Ramp A from v0 to vc, placed as early as it verifies. */
static bool place_A(pctx *pc, lsm_real v0, lsm_real vc, plan5 *p, bool catchup)
{
    const lsm_real dt = pc->pl->cfg.cycle_s, D = pc->D;
    p->xA = R0;
    if (vc == v0) {
        no_ramp(&p->A, dt, v0);
        return true;
    }
    if (vc < v0) {
        if (!catchup)
            return false;
        return fit_decel_now(pc, R0, D, v0, vc, &p->A);
    }
    return fit_accel(pc, R0, D, v0, vc, false, &p->A, &p->xA);
}

/* The whole piece for cruise feed vc: ramp A as early as it verifies, ramp B as late, the cruise between. */
static bool feas5(pctx *pc, lsm_real v0, lsm_real vc, lsm_real v1, bool exact, bool catchup, plan5 *p)
{
    const lsm_real dt = pc->pl->cfg.cycle_s, D = pc->D;
    p->v0 = v0;
    p->vc = vc;
    p->v1 = v1;
    if (!(vc > R0))
        return false;
    if (!place_A(pc, v0, vc, p, catchup))
        return false;
    const lsm_real xa_end = p->xA + p->A.dist;
    if (vc > v1) {
        if (!fit_decel(pc, xa_end, D, vc, v1, exact, false, &p->B, &p->xB))
            return false;
    } else {
        no_ramp(&p->B, dt, vc);
        p->xB = D;
    }
    if (p->xB < xa_end - LEN_EPS * (R1 + D))
        return false;
    if (p->xB < xa_end)
        p->xB = xa_end;
    return region_ok(pc, xa_end, p->xB, vc);
}

static void put_ramp(lsm_piece *pc, int at, const ramp *r, lsm_real dt)
{
    lsm_phase ph[7];
    lsm_scurve_phases(&r->iv, r->jp, ph);
    for (int i = 0; i < 7; i++) {
        lsm_piece_phase *q = &pc->ph[at + i];
        q->n_cycles = ph[i].n_cycles;
        q->T_s = (lsm_real)ph[i].n_cycles * dt;
        q->shape = ph[i].shape;
        q->jerk_mm_s3 = ph[i].jerk_mm_s3;
    }
}

static void put_cruise(lsm_piece *pc, int at, lsm_real len, lsm_real v)
{
    lsm_piece_phase *q = &pc->ph[at];
    q->n_cycles = 0;
    q->shape = LSM_PHASE_CONST;
    q->jerk_mm_s3 = R0;
    q->len_mm = len > R0 && v > R0 ? len : R0;
    q->T_s = q->len_mm > R0 ? q->len_mm / v : R0;
}

static void fill_piece(const lsm_planner *pl, const pctx *ctx, const plan5 *p, lsm_real end_x, lsm_piece *out)
{
    const lsm_real dt = pl->cfg.cycle_s;
    memset(out, 0, sizeof *out);
    out->blk = ctx->id0;
    out->off_mm = ctx->off0;
    out->v0_mm_s = p->v0;
    out->v1_mm_s = p->v1;
    out->vc_mm_s = p->vc;
    out->end_blk = ctx->id_end;
    out->stop = p->v1 > R0 ? 0u : 1u;
    out->step = p->step ? 1u : 0u;
    const lsm_real xa_end = p->xA + p->A.dist, xb_end = p->xB + p->B.dist;
    put_cruise(out, 0, p->xA, p->v0);
    put_ramp(out, 1, &p->A, dt);
    put_cruise(out, 8, p->xB - xa_end, p->vc);
    put_ramp(out, 9, &p->B, dt);
    put_cruise(out, 16, end_x - xb_end, p->v1);
    /* phase start states and the travel of every ramp phase (exact boundary values, no trigonometry) */
    lsm_kin k = {R0, p->v0, R0, R0};
    lsm_real T = R0;
    for (int i = 0; i < LSM_PIECE_PHASES; i++) {
        lsm_piece_phase *q = &out->ph[i];
        out->st[i] = k;
        out->st[i].j_mm_s3 = R0;
        if (i == 0 || i == 8 || i == 16) { /* cruises run at exactly their feed */
            const lsm_real v = i == 0 ? p->v0 : i == 8 ? p->vc : p->v1;
            if (i > 0) /* up to where the next ramp (or the end) is planned: the phases add up to the piece */
                put_cruise(out, i, (i == 8 ? p->xB : end_x) - k.s_mm, v);
            out->st[i].v_mm_s = v;
            out->st[i].a_mm_s2 = R0;
            k.v_mm_s = v;
            k.a_mm_s2 = R0;
            k.s_mm += q->len_mm;
        } else if (q->n_cycles) {
            const lsm_phase ph = {q->n_cycles, q->shape, q->jerk_mm_s3};
            lsm_kin e;
            lsm_phase_end(&ph, dt, &out->st[i], &e);
            q->len_mm = e.s_mm - out->st[i].s_mm;
            k = e;
        }
        T += q->T_s;
    }
    /* the ramps' ends carry rounding: the cruises start exactly where they are planned */
    out->len_mm = end_x;
    out->T_s = T;
}

/* The node after block `after` (exclusive) and its W; tail: the end of the buffer (W = 0). */
static uint32_t node_after(const lsm_planner *pl, uint32_t after, lsm_real *w)
{
    for (uint32_t id = after + 1u;; id++) {
        if (id == pl->tail) {
            *w = R0;
            return id;
        }
        const lsm_pblock *b = blk(pl, id);
        if (b->flags & LSM_PB_STOP) {
            *w = R0;
            return id;
        }
        if (b->flags & LSM_PB_NODE) {
            *w = b->w_mm_s;
            return id;
        }
    }
}

/* Fallback when no verified piece was found (should not happen; counted): stop as soon as possible with a verified
 * ramp, anywhere ahead; the next piece starts from rest. */
static lsm_status fallback(lsm_planner *pl, pctx *pc, lsm_real v0, lsm_piece *out)
{
    pl->stats.plan_fallbacks++;
    plan5 p;
    memset(&p, 0, sizeof p);
    const lsm_real dt = pl->cfg.cycle_s;
    p.v0 = p.vc = v0;
    p.v1 = R0;
    no_ramp(&p.A, dt, v0);
    no_ramp(&p.B, dt, v0);
    if (v0 > R0) {
        pctx all;
        pctx_init(&all, pl, pc->id0, pc->off0, pl->tail);
        all.floor = v0;
        if (fit_decel_now(&all, R0, all.D, v0, R0, &p.B)) {
            fill_piece(pl, &all, &p, p.B.dist, out);
            out->hold = 1; /* ends anywhere */
            return LSM_E_INTERNAL;
        }
    }
    fill_piece(pl, pc, &p, R0, out);
    out->stop = 1;
    out->hold = 1;
    out->T_s = R0;
    return LSM_E_INTERNAL;
}

static bool plan_normal(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, pctx *pcp, plan5 *bestp);

/* Time from the piece start to x (>= the end of ramp A, <= the start of ramp B) along p. */
static lsm_real time_to(const plan5 *p, lsm_real dt, lsm_real x)
{
    const lsm_real xa_end = p->xA + p->A.dist;
    lsm_real t = (lsm_real)lsm_scurve_total_cycles(&p->A.iv) * dt;
    if (p->xA > R0 && p->v0 > R0)
        t += p->xA / p->v0;
    if (x > xa_end && p->vc > R0)
        t += (x - xa_end) / p->vc;
    return t;
}

/*
 * One sin² ramp from v0 to the highest cruise must fit every block it crosses: where it starts in a slow,
 * curved stretch (out of a valley), that stretch lowers its acceleration and jerk for the whole ramp, or delays
 * its start (a lead cruise at v0). A staircase may be faster: a lower ramp first, then, re-planned at its end
 * (a = 0 there, lsm_piece.step), a second one up to the same cruise. For a few lower cruises (geometric levels
 * from the top), the second ramp is planned too, and the staircase is taken when it reaches the highest cruise
 * (or the end of the first plan's ramp) sooner than the single ramp.
 */
static void staircase(pctx *pc, plan5 *best)
{
    const lsm_real dt = pc->pl->cfg.cycle_s;
    const lsm_real v0 = best->v0, vmax = best->vc;
    if (!(vmax > v0 * LSM_R(1.2) + LSM_R(1e-6)) || best->xB < best->xA + best->A.dist)
        return;
    /* a ramp A that starts at once with (nearly) the limits of its first block at rest was not slowed: no lower
     * step can reach the cruise sooner */
    lsm_real na, nj, ns;
    guess_limits(pc, R0, &na, &nj, &ns);
    if (!(best->xA > R0) && best->A.a_lim >= LSM_R(0.9) * na && best->A.j_lim >= LSM_R(0.9) * nj)
        return;
    const bool exact = !(best->v1 > R0);
    const lsm_real xe = best->xA + best->A.dist;
    lsm_real gain = R0;
    plan5 p, q, found;
    memset(&found, 0, sizeof found);
    bool have = false;
    const lsm_real k = LSM_R(0.6);
    lsm_real dv = (vmax - v0) * k;
    for (int it = 0; it < STAIR_LEVELS; it++, dv *= k) {
        const lsm_real vc = v0 + dv;
        if (!(vc > v0 * (R1 + LSM_R(0.02))))
            break;
        if (!feas5(pc, v0, vc, lsm_min2(best->v1, vc), exact, false, &p))
            continue;
        const lsm_real x1 = p.xA + p.A.dist;
        if (!(x1 < best->xB))
            continue;
        /* the second ramp, from the end of the first one */
        seek(pc, x1);
        pctx sub;
        pctx_init(&sub, pc->pl, pc->cid, x1 - pc->cx, pc->id_end);
        if (!(sub.D > LEN_EPS * (R1 + sub.D)) ||
            !feas5(&sub, vc, vmax, lsm_min2(best->v1, vmax), exact, false, &q))
            continue;
        const lsm_real x2 = x1 + q.xA + q.A.dist;
        const lsm_real X = lsm_max2(x2, xe);
        if (!(X <= best->xB) || !(X - x1 <= q.xB))
            continue;
        const lsm_real g = time_to(best, dt, X) - (time_to(&p, dt, x1) + time_to(&q, dt, X - x1));
        if (g > gain + LSM_R(2.0) * dt) {
            gain = g;
            found = p;
            have = true;
        }
    }
    if (have) {
        found.step = true;
        *best = found;
    }
}

lsm_status lsm_planner_plan_piece(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, lsm_piece_mode mode,
                                  lsm_piece *out)
{
    if (pl == NULL || out == NULL)
        return LSM_E_NULL;
    if (id_lt(id0, pl->head) || !id_lt(id0, pl->tail))
        return LSM_E_EMPTY;
    const lsm_real dt = pl->cfg.cycle_s;
    plan5 p;
    memset(&p, 0, sizeof p);
    if (mode == LSM_PIECE_HOLD) {
        /* within the path up to the next exact stop (a corner the machine cannot pass at speed) */
        uint32_t id_end = id0 + 1u;
        while (id_end != pl->tail && !(blk(pl, id_end)->flags & LSM_PB_STOP))
            id_end++;
        pctx pc;
        pctx_init(&pc, pl, id0, off0, id_end);
        p.v0 = p.vc = v0;
        p.v1 = R0;
        no_ramp(&p.A, dt, v0);
        no_ramp(&p.B, dt, v0);
        if (v0 > R0 && !fit_decel_now(&pc, R0, pc.D, v0, R0, &p.B))
            return LSM_E_INFEASIBLE;
        fill_piece(pl, &pc, &p, p.B.dist, out);
        out->hold = 1;
        pl->stats.pieces++;
        return LSM_OK;
    }
    if (off0 >= blk(pl, id0)->g.len && id0 + 1u == pl->tail)
        return LSM_E_EMPTY;
    pctx pc;
    plan5 best;
    if (!plan_normal(pl, id0, off0, v0, &pc, &best))
        return mode == LSM_PIECE_REPLAN ? LSM_E_INFEASIBLE : fallback(pl, &pc, v0, out);
    fill_piece(pl, &pc, &best, pc.D, out);
    pl->stats.pieces++;
    return LSM_OK;
}

/* The NORMAL piece from (id0, off0) at v0 (a = 0): true and the plan, or false (pc: the last piece tried). */
static bool plan_normal(lsm_planner *pl, uint32_t id0, lsm_real off0, lsm_real v0, pctx *pcp, plan5 *bestp)
{
    /* to the next node; if no verified piece reaches it, to the one after (its dip then lies inside the piece,
     * verified pointwise), and so on: a node that appeared ahead since the speed was committed cannot trap it */
    lsm_real w1 = R0;
    uint32_t id_end = id0;
    pctx pc;
    bool have = false, exact = false, catchup = false;
    plan5 best, p;
    memset(&p, 0, sizeof p);
    memset(&best, 0, sizeof best);
    lsm_real v1 = R0;
    bool skipped_here = false, skipped_short = false;
    /* pass 0 also plans across a valley node closer than 1.5 cycles of travel (a piece that short would start and
     * end inside one control cycle, too soon for the next one to be planned in the background); pass 1, only
     * if that found nothing, stops there as well */
    for (int pass = 0; pass < 2 && !have; pass++) {
    if (pass == 1 && !skipped_short)
        break;
    id_end = id0;
    skipped_here = false;
    for (int cand = 0; cand < 5 && !have; cand++) {
        if (id_end == pl->tail || (cand > 0 && !skipped_here && (blk(pl, id_end)->flags & LSM_PB_STOP)))
            break;
        id_end = node_after(pl, id_end, &w1);
        pctx_init(&pc, pl, id0, off0, id_end);
        skipped_here = false;
        if (!(pc.D > LEN_EPS * (R1 + pc.D)) && id_end != pl->tail) { /* a node right here (we stand on it): the
                                                                           next one (the end itself is planned, however
                                                                           short the rest: a hold may stop just
                                                                           before it) */
            skipped_here = true;
            continue;
        }
        if (pass == 0 && id_end != pl->tail && !(blk(pl, id_end)->flags & LSM_PB_STOP) &&
            pc.D < LSM_R(1.5) * pl->cfg.cycle_s * lsm_max2(v0, w1)) {
            skipped_here = true;
            skipped_short = true;
            continue;
        }
        exact = !(w1 > R0);
        /* catch-up: the current speed is above the caps right here (override lowered) */
        catchup = v0 > range_cap(&pc, R0, R0) * (R1 + CAP_SLACK);
        if (catchup)
            pc.floor = v0;
        v1 = w1;
        /* forward step: what one ramp from v0 reaches (then cruise) */
        lsm_real ga, gj, gs; /* budgets at the start (at rest): the distance probes below */
        guess_limits(&pc, R0, &ga, &gj, &gs);
        if (v1 > v0 && !catchup) {
            if (!feas5(&pc, v0, v1, v1, false, false, &p)) {
                lsm_real lo = v0, hi = v1;
                lsm_real probe = speed_for_dist(v0, pc.D, ga, gj, gs, v1);
                for (int it = 0; it < W_BISECT && hi - lo > SPEED_RES * hi; it++) {
                    const lsm_real mid = probe_mid(lo, hi, &probe);
                    if (feas5(&pc, v0, mid, mid, false, false, &p))
                        lo = mid;
                    else
                        hi = mid;
                }
                v1 = lo;
            }
        }
        if (!catchup && v1 > R0 && v1 < w1 && !arrival_ok(pl, id_end, v1)) {
            /* arriving below the node's W: at a speed from which the machine can go on (verified like W) */
            lsm_real lo = R0, hi = v1;
            for (int it = 0; it < W_BISECT && hi - lo > SPEED_RES * hi; it++) {
                const lsm_real mid = (lo + hi) / LSM_R(2.0);
                if (arrival_ok(pl, id_end, mid))
                    lo = mid;
                else
                    hi = mid;
            }
            v1 = lo;
        }
        if (catchup) {
            /* slow down at once towards the cap here, then cruise and go on */
            lsm_real vt = lsm_max2(v1, lsm_min2(v0, range_cap(&pc, R0, pc.D)));
            for (int it = 0; it < 24 && !have; it++) {
                if (feas5(&pc, v0, vt, v1, exact, true, &p)) {
                    best = p;
                    have = true;
                }
                vt = v1 + (vt - v1) * LSM_R(0.7);
            }
            continue;
        }
        /* the highest cruise feed: bisection between the monotone profile and the highest cap of the piece */
        lsm_real lo = lsm_max2(v0, v1);
        if (lo > R0 && feas5(&pc, v0, lo, v1, exact, false, &p)) {
            best = p;
            have = true;
        } else if (v0 > v1 || lo > R0) {
            /* caps below v0 inside the piece (dips that are not nodes): slow down at once to a cruise below them,
             * arriving at the node below its W when the dip is lower than that (W is only the highest speed) */
            lsm_real l = R0, u = lo;
            for (int it = 0; it < VC_BISECT + 8 && u - l > SPEED_RES * u; it++) {
                const lsm_real mid = (l + u) / LSM_R(2.0);
                if (mid > R0 && feas5(&pc, v0, mid, lsm_min2(v1, mid), exact, true, &p) &&
                    (mid >= v1 || arrival_ok(pl, id_end, mid))) {
                    best = p;
                    have = true;
                    l = mid;
                } else {
                    u = mid;
                }
            }
        }
        if (!have && off0 == R0 && v0 > R0) {
            /* the piece the node's certificate verified (node_w, arrival_ok): one ramp from v0 down to the next
             * node's W, or a cruise at v0, so that a speed certified at a node always goes on */
            ramp r;
            lsm_real xs;
            memset(&p, 0, sizeof p);
            p.v0 = p.vc = v0;
            no_ramp(&p.A, pl->cfg.cycle_s, v0);
            if (w_test(&pc, v0, v1, exact, &r, &xs)) {
                p.v1 = v0 > v1 ? v1 : v0;
                if (v0 > v1) {
                    p.B = r;
                    p.xB = xs;
                } else {
                    no_ramp(&p.B, pl->cfg.cycle_s, v0);
                    p.xB = pc.D;
                }
                best = p;
                have = true;
            }
        }
        lsm_real mx = R0;
        for (uint32_t id = pc.id0; id != pc.id_end; id++)
            mx = lsm_max2(mx, cap_of(pl, id));
        lsm_real hi = lsm_max2(lo, mx);
        if (hi > lo && (have || !(v0 > v1))) {
            if (feas5(&pc, v0, hi, v1, exact, false, &p)) {
                best = p;
                have = true;
            } else {
                lsm_real l = lo, u = hi;
                lsm_real probe = cruise_for_dist(v0, v1, pc.D, ga, gj, gs, hi);
                for (int it = 0; it < VC_BISECT + (have ? 0 : 20) && u - l > SPEED_RES * u; it++) {
                    const lsm_real mid = probe_mid(l, u, &probe);
                    if (feas5(&pc, v0, mid, v1, exact, false, &p)) {
                        best = p;
                        have = true;
                        l = mid;
                    } else {
                        u = mid;
                    }
                }
            }
        }
    }
    }
    if (have && !catchup)
        staircase(&pc, &best);
    *pcp = pc;
    if (have)
        *bestp = best;
    return have;
}

/* Does a verified piece start at the interpolator's commitment point (planner.h, lsm_planner_set_horizon)?
 * Unless `force`, a backward pass that stopped at an unchanged node after that point left the piece from there
 * unchanged: nothing to check. (After a corner trimmed the block the current piece ends in, the piece from there
 * is always checked: that piece must be replaced.) */
static bool horizon_feasible(lsm_planner *pl, bool force)
{
    uint32_t id = pl->horizon_blk;
    lsm_real off = pl->horizon_off;
    if (!(pl->horizon_v > R0) || id_lt(id, pl->head) || !id_lt(id, pl->tail))
        return true;
    if (!force && id_lt(id, pl->bp_stop))
        return true;
    while (off > blk(pl, id)->g.len && id + 1u != pl->tail) {
        off -= blk(pl, id)->g.len;
        id++;
    }
    if (off >= blk(pl, id)->g.len && id + 1u == pl->tail)
        return false; /* moving at the very end of the buffer */
    pctx pc;
    plan5 p;
    return plan_normal(pl, id, off, pl->horizon_v, &pc, &p);
}
