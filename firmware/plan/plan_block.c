/* plan_block.c: block intake: per-block bounds of the geometric derivatives, the budget coefficients and caps
 * (planner.h, "Limits"), and the corner between the last block and a new one (planner.h, "Blocks and corners"). */
#include <string.h>

#include "corner.h"
#include "planner_int.h"

/* max |A cos t + B sin t| from its end values: this relative slack covers the rounding of cos and sin there. */
#define END_VALUE_SLACK LSM_R(1e-6)
/* The coefficients are scaled up by this before rounding to bfloat16 (a bound, never smaller than the exact value,
 * even after the double -> float conversion). */
#define BF16_PRE_SCALE ((lsm_real)1.000001)
/* The direction range of a clothoid's q_sss (clothoid_psi) is widened by this many eps of the angles' size: the
 * rounding of atan2 (a few ulp) and of the sums. */
#define PSI_SLACK_EPS LSM_R(64.0)
/* cap_geo is lowered by this many eps, so that the budget at the cap is never negative through rounding. */
#define CAP_GEO_EPS LSM_R(4.0)
/* Two lines are collinear when their unit directions differ by less than this (squared): rounding of dir only. */
#if LSM_REAL_IS_FLOAT
#define COLLINEAR_D2 LSM_R(1e-12)
#else
#define COLLINEAR_D2 LSM_R(1e-22)
#endif

/* ------------------------------------------------------------------------------------------------------------ */
/* per-block bounds of the geometric derivatives and the budget coefficients                                    */

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
    lsm_real s0, c0, s1, c1; /* (one argument reduction for both) */
    lsm_sincos(t0, &s0, &c0);
    lsm_sincos(t1, &s1, &c1);
    const lsm_real f0 = lsm_fabs(A * c0 + B * s0);
    const lsm_real f1 = lsm_fabs(A * c1 + B * s1);
    const lsm_real m = lsm_max2(f0, f1);
    return lsm_min2(R, m * (R1 + END_VALUE_SLACK) + LSM_REAL_EPS * R); /* rounding of the end values */
}

/* The range [*plo, *phi] of the direction psi of a clothoid's q_sss = c N - kappa² T in its plane (psi = theta +
 * alpha, alpha = atan2(c, -kappa²)): theta over [t0, t1], kappa from k0 to k1 (kappa² from 0 where it changes sign).
 * alpha is monotone in kappa² (from +-pi/2 at kappa = 0 towards +-pi), so its range is that of its ends; c = 0 gives
 * alpha = pi (q_sss = -kappa² T). Widened by PSI_SLACK_EPS eps of the angles' size for the rounding of atan2 and of
 * the sums. */
static void clothoid_psi(lsm_real k0, lsm_real k1, lsm_real c, lsm_real t0, lsm_real t1, lsm_real *plo, lsm_real *phi)
{
    const lsm_real k2hi = lsm_max2(k0 * k0, k1 * k1);
    const lsm_real k2lo = k0 * k1 <= R0 ? R0 : lsm_min2(k0 * k0, k1 * k1);
    lsm_real alo = PI_R, ahi = PI_R;
    if (c != R0) {
        const lsm_real a1 = lsm_atan2(c, -k2lo), a2 = lsm_atan2(c, -k2hi);
        alo = lsm_min2(a1, a2);
        ahi = lsm_max2(a1, a2);
    }
    const lsm_real pad = PSI_SLACK_EPS * LSM_REAL_EPS * (R1 + PI_R + lsm_fabs(t0) + lsm_fabs(t1));
    *plo = t0 + alo - pad;
    *phi = t1 + ahi + pad;
}

/* Fills Q1, Q2, Q3 per axis (LSM_MAX_AXES; the caller zeroes them: the entries not written stay 0), the curvature
 * bound of the block and the bound of |q_sss| (the path's own third derivative: sqrt(c² + kappa⁴) on a clothoid,
 * kappa |w| on a helix, kappa² on a planar arc). */
static void geom_bounds(const lsm_geom *g, lsm_real q1[LSM_MAX_AXES], lsm_real q2[LSM_MAX_AXES],
                        lsm_real q3[LSM_MAX_AXES], lsm_real *kmax, lsm_real *q3max)
{
    *kmax = *q3max = R0;
    if (g->kind == LSM_GEOM_LINE) {
        for (int i = 0; i < LSM_MAX_AXES; i++)
            q1[i] = lsm_fabs(g->u.line.dir[i]);
        return;
    }
    const lsm_real *e1, *e2;
    lsm_real t0, t1, k, c = R0, sT = R1; /* sT: in-plane speed per unit s (helix) */
    lsm_real n[3] = {R0, R0, R0}, ax = R0;
    lsm_real q3n = R0, q3t;      /* q3 = q3n mN + q3t mT */
    lsm_real plo = R0, phi = R0; /* a clothoid's range of the direction of q_sss (clothoid_psi) */
    bool arc = false;
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
        lsm_cross3(e1, e2, n);
        ax = a->axial_mm / g->len;
        /* q_s = sT (-sin phi e1 + cos phi e2) sgn + n ax; q_ss = -k (cos phi e1 + sin phi e2);
         * q_sss = k |w| (sin phi e1 - cos phi e2) sgn: mT = |-sin e1 + cos e2|, mN = |cos e1 + sin e2| below */
        arc = true;
        q3t = k * lsm_fabs(w);
        *q3max = q3t;
    } else {
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
        q3n = lsm_fabs(c);
        q3t = k * k;
        *q3max = lsm_sqrt(c * c + k * k * k * k);
        /* q_sss = c N - kappa² T = M (cos psi e1 + sin psi e2), M = sqrt(c² + kappa⁴), psi = theta + alpha, alpha =
         * atan2(c, -kappa²) (monotone in kappa²): its range from those of theta and kappa² (clothoid_psi) */
        clothoid_psi(k0, k0 + c * L, c, t0, t1, &plo, &phi);
    }
    /* one loop for both: an arc's q1 adds |n ax| (a clothoid's n and ax are 0, sT 1: + 0 and * 1 are exact), its q3
     * has no mN term (q3n = 0, + 0 exact) */
    for (int i = 0; i < 3; i++) {
        const lsm_real mu = max_abs_cs(e1[i], e2[i], t0, t1);  /* |cos e1 + sin e2| */
        const lsm_real mv = max_abs_cs(e2[i], -e1[i], t0, t1); /* |-sin e1 + cos e2| */
        const lsm_real mT = arc ? mv : mu, mN = arc ? mu : mv;
        q1[i] = sT * mT + lsm_fabs(n[i] * ax);
        q2[i] = k * mN;
        q3[i] = q3n * mN + q3t * mT;
        if (!arc) /* a clothoid: the better of the magnitudes and the direction bound (both hold) */
            q3[i] = lsm_min2(q3[i], *q3max * max_abs_cs(e1[i], e2[i], plo, phi));
    }
    *kmax = k;
}

/* bfloat16 (the upper half of an IEEE float), rounded up: the coefficients are bounds, never smaller. */
static uint16_t bf16_up(lsm_real x)
{
    if (!(x > R0))
        return 0;
    float f = (float)(x * BF16_PRE_SCALE);
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

/* Computes cap_geo and the six coefficients of a block from its geometry. */
static void block_coef(const lsm_planner *pl, lsm_pblock *b)
{
    const lsm_planner_config *cf = &pl->cfg;
    lsm_real q[3][LSM_MAX_AXES], kmax, q3max; /* Q1, Q2, Q3 per axis */
    memset(q, 0, sizeof q);                   /* (one call: the axes geom_bounds leaves are 0) */
    geom_bounds(&b->g, q[0], q[1], q[2], &kmax, &q3max);
    const lsm_real *q1 = q[0], *q2 = q[1], *q3 = q[2];
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
    if (!b->g.rotary_only) { /* the tangential frame: |T| = 1, |kappa N| = kappa, |q_sss| <= q3max */
        if (cf->path_a_max_mm_s2 > R0) {
            aa = lsm_max2(aa, R1 / cf->path_a_max_mm_s2);
            ba = lsm_max2(ba, kmax / cf->path_a_max_mm_s2);
        }
        if (cf->path_j_max_mm_s3 > R0) {
            aj = lsm_max2(aj, R1 / cf->path_j_max_mm_s3);
            bj = lsm_max2(bj, kmax / cf->path_j_max_mm_s3);
            gj = lsm_max2(gj, q3max / cf->path_j_max_mm_s3);
        }
    }
    const lsm_real co[6] = {aa, ba, aj, bj, gj, as}; /* (in the order of b->coef) */
    for (int i = 0; i < 6; i++)
        b->coef[i] = bf16_up(co[i]);
    /* the cap uses the rounded coefficients, so the budget at the cap is never negative */
    coef c;
    coef_get(b, &c);
    lsm_real cap = av > R0 ? R1 / av : LSM_REAL_MAX;
    if (c.ba > R0)
        cap = lsm_min2(cap, lsm_sqrt(cf->cap_margin / c.ba));
    if (c.gj > R0)
        cap = lsm_min2(cap, lsm_cbrt(cf->cap_margin / c.gj));
    b->cap_geo_mm_s = cap * (R1 - CAP_GEO_EPS * LSM_REAL_EPS);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* append                                                                                                       */

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
    return d <= COLLINEAR_D2;
}

static void push_block(lsm_planner *pl, const lsm_geom *g, lsm_real feed, uint32_t seq, uint8_t flags)
{
    lsm_pl_changed(pl, pl->tail); /* (a search that met the buffer's end read up to here) */
    lsm_pblock *b = blk(pl, pl->tail);
    memset(b, 0, sizeof *b);
    b->g = *g;
    b->feed_mm_s = feed;
    b->seq = seq;
    b->flags = flags;
    block_coef(pl, b);
    pl->tail++;
}

/* Corner smoothing: the tolerance left for the corner is at least this share of the whole (the fits of its two
 * blocks may take the rest). */
#define CORNER_TOL_FLOOR LSM_R(0.25)
/* The trim of the previous block stays this share inside the room beyond the interpolator's commitment. */
#define TRIM_ROOM_SHARE LSM_R(0.999)
/* A computed arc end within this many eps of the programmed end (relative to its size) is the programmed end. */
#define END_SNAP_EPS LSM_R(64.0)

/* The corner between the last block (prev) and g, which starts where prev ends. */
typedef struct corner_try {
    bool corner; /* a clothoid pair replaces the corner: g1 is prev trimmed, g2 g trimmed, cr the pair */
    bool stop;   /* the machine stops at the junction */
    lsm_geom g1, g2;
    lsm_corner_result cr;
} corner_try;

/* Room to trim the end of block pid: beyond the interpolator's commitment only. */
static lsm_real trim_room(const lsm_planner *pl, uint32_t pid, const lsm_pblock *prev)
{
    if (id_lt(pid, pl->horizon_blk))
        return R0;
    if (pid == pl->horizon_blk)
        return prev->g.len - pl->horizon_off;
    return prev->g.len;
}

/* Tries a clothoid pair (corner.h) between prev and g within the tolerance left by the fits; on success ct->g1 is
 * prev trimmed at its end and ct->g2 is g trimmed at its start. Else ct->stop (or, collinear, a plain G2 join). */
LSM_NOINLINE static void try_corner(const lsm_planner *pl, const lsm_pblock *prev, const lsm_geom *g, lsm_real fit_err,
                                    corner_try *ct)
{
    const lsm_real room = trim_room(pl, pl->tail - 1u, prev);
    lsm_corner_params cp;
    /* the corner gets what the fits of its two blocks left of the tolerance */
    cp.tolerance_mm =
        lsm_max2(pl->tail_tol_mm - lsm_max2(pl->tail_fit_err, fit_err), CORNER_TOL_FLOOR * pl->tail_tol_mm);
    cp.max_trim1_mm = lsm_min2(pl->cfg.trim_share * prev->g.len, TRIM_ROOM_SHARE * room);
    cp.max_trim2_mm = pl->cfg.trim_share * g->len;
    lsm_corner_result *cr = &ct->cr;
    lsm_status cs = (cp.max_trim1_mm > R0) ? lsm_corner_smooth(&prev->g, g, &cp, cr) : LSM_E_CORNER_NO_SOLUTION;
    /* a transition of (almost) no length is a numerical corner case (its curvature, hence its cap, is
     * unbounded): stop there instead */
    const bool degenerate =
        cs == LSM_OK && !(cr->trans[0].len + cr->trans[1].len > LEN_EPS * (R1 + prev->g.len + g->len));
    if (cs == LSM_OK && !degenerate && cr->trim1_mm < prev->g.len && cr->trim2_mm < g->len && cr->trim1_mm <= room) {
        ct->g1 = prev->g;
        ct->g2 = *g;
        if (lsm_geom_trim_end(&ct->g1, cr->trim1_mm) == LSM_OK &&
            lsm_geom_trim_start(&ct->g2, cr->trim2_mm) == LSM_OK && ct->g1.len > R0 && ct->g2.len > R0) {
            ct->corner = true;
        } else {
            ct->stop = true;
        }
    } else if (cs == LSM_E_COLLINEAR) {
        /* already G2 */
    } else {
        ct->stop = true;
    }
}

/* Pushes the corner's clothoid pair after prev (trimmed to ct->g1). Each transition keeps the feed (and the rapid
 * flag) of the block it was cut from: the first prev's, the second the new block's. (With the slower feed for both,
 * a small turn from a fast block into a slow one, whose transitions may take half of each block, ran that half of
 * the fast block at the slow feed: G1 X30 F3000 / G1 X60 Y1.5 F30 took 63.1 s, G61 60.8 s.) */
static void push_corner(lsm_planner *pl, lsm_pblock *prev, const corner_try *ct, lsm_real feed, uint32_t seq,
                        uint8_t flags)
{
    lsm_pl_changed(pl, pl->tail - 1u);
    prev->g = ct->g1;
    block_coef(pl, prev);
    push_block(pl, &ct->cr.trans[0], prev->feed_mm_s, seq, (uint8_t)(LSM_PB_CORNER | (prev->flags & LSM_PB_RAPID)));
    push_block(pl, &ct->cr.trans[1], feed, seq, (uint8_t)(LSM_PB_CORNER | (flags & LSM_PB_RAPID)));
    pl->stats.corners++;
}

bool lsm_pl_geom_end(const lsm_geom *g, const lsm_real start[LSM_MAX_AXES], const lsm_real prog_end[LSM_MAX_AXES],
                     lsm_real end[LSM_MAX_AXES])
{
    for (int i = 0; i < LSM_MAX_AXES; i++)
        end[i] = start[i];
    (void)lsm_geom_eval(g, g->len, end, NULL, NULL);
    /* a geometric end within rounding of the programmed one is the programmed one (exact program ends): an arc's
     * end carries the rounding of its radius too (double: its centre, R eps; R 1e4 ended 9.1e-13 off) */
    lsm_real d2 = R0, sc = R1 + (g->kind == LSM_GEOM_ARC ? g->u.arc.radius_mm : R0);
    for (int i = 0; i < 3; i++) {
        d2 += (end[i] - prog_end[i]) * (end[i] - prog_end[i]);
        sc += lsm_fabs(prog_end[i]);
    }
    return lsm_sqrt(d2) <= END_SNAP_EPS * LSM_REAL_EPS * sc;
}

/* After g was pushed: where the next block starts (the geometric end; lines: the programmed point itself) and the
 * state the next corner needs. */
static void set_tail(lsm_planner *pl, const lsm_geom *g, const lsm_planner_move *mv, const lsm_real prog_end[6],
                     const lsm_arcfit_result *fr, lsm_real fit_err)
{
    if (g->kind == LSM_GEOM_LINE && (fr == NULL || fr->kind != LSM_ARCFIT_LINE)) {
        for (int i = 0; i < LSM_MAX_AXES; i++)
            pl->tail_pos[i] = prog_end[i];
    } else { /* (a fitted line may end on its last point's projection into a fitted arc's plane: arcfit.h) */
        lsm_real p[LSM_MAX_AXES];
        const bool same = lsm_pl_geom_end(g, pl->tail_pos, prog_end, p);
        for (int i = 0; i < LSM_MAX_AXES; i++)
            pl->tail_pos[i] = same ? prog_end[i] : p[i];
    }
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pl->tail_prog[i] = prog_end[i];
    pl->tail_tol_mm = mv->tol_mm;
    pl->tail_rotary = lsm_geom_moves_rotary(g) ? 1u : 0u;
    pl->tail_fit_err = fit_err;
    pl->tail_arc = 0;
    pl->tail_switch = 0; /* (plan_fit.c sets it after a chain's closing line) */
    if (g->kind == LSM_GEOM_ARC && fr != NULL && fr->kind == LSM_ARCFIT_ARC) {
        pl->tail_arc = 1; /* a fitted arc: the next run's arc stays in its plane */
        for (int i = 0; i < 3; i++)
            pl->tail_n[i] = fr->normal[i];
    }
}

#ifdef LSM_TEST_OVR_UNDO
/* Fault injection, in test builds only (tests/plan, test_planner_undo): the next lsm_test_hz_stop_left appends that may
 * be made an exact stop at their junction are, as if the horizon check had failed, so that the restore runs on any
 * path (the real case needs the interpolator just before a node whose W the append lowers). */
extern unsigned lsm_test_hz_stop_left;
static bool hz_stop_injected(void)
{
    return lsm_pl_fault_take(&lsm_test_hz_stop_left);
}
#else
static bool hz_stop_injected(void)
{
    return false;
}
#endif

/* Appends g (which starts at tail_pos), with corner handling at its start (the block pushed is then g trimmed, a copy:
 * g itself is left as it was). prog_end: its programmed end. */
lsm_status lsm_pl_append_geom(lsm_planner *pl, const lsm_geom *g, const lsm_planner_move *mv,
                              const lsm_real prog_end[6], const lsm_arcfit_result *fr)
{
    const lsm_real fit_err = fr ? fr->err_mm : R0;
    if (lsm_planner_free(pl) < 3)
        return LSM_E_FULL;
    const bool has_prev = pl->tail != pl->head;
    lsm_pblock *prev = has_prev ? blk(pl, pl->tail - 1u) : NULL;
    const lsm_real feed = mv->rapid ? LSM_REAL_MAX : mv->feed_mm_s;
    uint8_t flags = mv->rapid ? (uint8_t)LSM_PB_RAPID : (uint8_t)0;
    corner_try ct;
    ct.corner = ct.stop = false;
    lsm_geom prev_orig;                                  /* (set and used only with a corner) */
    const bool blend = has_prev && pl->tail_tol_mm > R0; /* G64 after a block */
    if (blend && lines_collinear(&prev->g, g)) {
        /* joins G2 as it is */
    } else if (blend && !pl->tail_rotary && !lsm_geom_moves_rotary(g)) {
        try_corner(pl, prev, g, fit_err, &ct);
        if (ct.stop)
            flags |= LSM_PB_STOP;
    } else {
        flags |= LSM_PB_STOP; /* nothing before (start from rest), G61, or a rotary move: an exact stop */
    }
    const bool corner = ct.corner;
    const lsm_geom *gp = corner ? &ct.g2 : g; /* the block pushed */
    if ((flags & LSM_PB_STOP) && has_prev)
        pl->stats.corner_stops++;
    /* (the W the machine's commitment rests on, before the append, for a restore: taken only where one can happen,
     * see below) */
    const bool may_stop = has_prev && !(flags & LSM_PB_STOP);
    lsm_pl_wseed seed;
    if (may_stop)
        lsm_pl_wseed_take(pl, &seed);
    if (corner) {
        prev_orig = prev->g;
        push_corner(pl, prev, &ct, feed, mv->seq, flags);
    }
    push_block(pl, gp, feed, mv->seq, flags);
    set_tail(pl, gp, mv, prog_end, fr, fit_err);
    pl->gen++;
    lsm_pl_backward_pass(pl);
    /* a corner that trimmed the block the interpolator's current piece ends in (it runs to the end of the buffer):
     * a verified piece from its commitment point must exist (it will be taken there) */
    const bool stales = (corner && pl->horizon_end == pl->tail - 3u && pl->horizon_v > R0) ||
                        lsm_planner_piece_stale(pl) || !lsm_pl_commitment_kept(pl);
    /* (while a new piece is due at the horizon, every append keeps it possible: the nodes ahead may change) */
    if (may_stop && ((stales && !lsm_pl_horizon_feasible(pl, true)) || hz_stop_injected())) {
        /* the new block (or the trim of its corner) took something the interpolator needs from its commitment
         * on: the machine stops at the junction instead, which restores the previous plan (a stop there; the W the
         * commitment rests on searched again from their values before the append: lsm_pl_wseed) */
        pl->tail -= corner ? 3u : 1u;
        lsm_pl_changed(pl, pl->tail - 1u);
        if (corner) {
            prev->g = prev_orig;
            block_coef(pl, prev);
            pl->stats.corners--;
        }
        push_block(pl, g, feed, mv->seq, (uint8_t)(flags | LSM_PB_STOP));
        pl->stats.corner_stops++;
        pl->stats.horizon_stops++;
        lsm_pl_wseed_put(pl, &seed); /* (the restoring pass starts from the W before the append: lsm_pl_wseed) */
        pl->full_pass = 1;
        lsm_pl_backward_pass(pl);
        if (!lsm_pl_commitment_ok(pl))
            pl->stats.restore_unkept++;
    } else if (stales) {
        lsm_pl_mark_stale(pl);
    }
    return LSM_OK;
}
