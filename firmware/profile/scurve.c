#include "scurve.h"

#include "lsm_math.h"

#define PI_R ((lsm_real)LSM_PI)
/* Largest interval count accepted: keeps 4 n1 + 2 n2 + n4 and whole moves within a 32-bit counter. */
#define LSM_MAX_INTERVAL_CYCLES 0x10000000u
/* Guard for whole multiples in the paper rule's floor (NOTES.md): floor(x / dt + 1e-9). */
#define PAPER_FLOOR_GUARD ((lsm_real)1e-9)

static lsm_status check_value(lsm_real x)
{
    return (lsm_status)lsm_check_finite(x);
}

lsm_status lsm_scurve_check_limits(const lsm_scurve_limits *lim, lsm_real cycle_s)
{
    if (lim == NULL)
        return LSM_E_NULL;
    const lsm_real v[3] = {lim->a_max_mm_s2, lim->j_max_mm_s3, lim->snap_max_mm_s4};
    for (int i = 0; i < 3; i++) {
        lsm_status st = check_value(v[i]);
        if (st != LSM_OK)
            return st;
    }
    lsm_status st = check_value(cycle_s);
    if (st != LSM_OK)
        return st;
    for (int i = 0; i < 3; i++)
        if (!(v[i] > 0))
            return LSM_E_LIMIT;
    if (!(cycle_s > 0))
        return LSM_E_CYCLE;
    return LSM_OK;
}

lsm_real lsm_scurve_jerk_den(const lsm_scurve_intervals *iv, lsm_real cycle_s)
{
    const lsm_real t1 = (lsm_real)iv->n1_cycles * cycle_s;
    const lsm_real t2 = (lsm_real)iv->n2_cycles * cycle_s;
    const lsm_real t4 = (lsm_real)iv->n4_cycles * cycle_s;
    return (t1 + t2) * (2 * t1 + t2 + t4); /* = 2 t1² + 3 t1 t2 + t2² + t4 (t1 + t2), eq 34 */
}

uint32_t lsm_scurve_total_cycles(const lsm_scurve_intervals *iv)
{
    return 4u * iv->n1_cycles + 2u * iv->n2_cycles + iv->n4_cycles;
}

/* The jerk that the intervals allow: min(Jmax, Amax / (t1 + t2), 2 t1 DJmax / pi) (eqs 10, 16, 22). */
static lsm_real jerk_cap(const lsm_scurve_limits *lim, lsm_real t1, lsm_real t2)
{
    lsm_real cap = lim->j_max_mm_s3;
    cap = lsm_min2(cap, lim->a_max_mm_s2 / (t1 + t2));
    cap = lsm_min2(cap, 2 * t1 * lim->snap_max_mm_s4 / PI_R);
    return cap;
}

lsm_real lsm_scurve_dv_capacity(const lsm_scurve_limits *lim, lsm_real cycle_s, const lsm_scurve_intervals *iv)
{
    if (iv->n1_cycles == 0)
        return 0;
    const lsm_real t1 = (lsm_real)iv->n1_cycles * cycle_s;
    const lsm_real t2 = (lsm_real)iv->n2_cycles * cycle_s;
    return jerk_cap(lim, t1, t2) * lsm_scurve_jerk_den(iv, cycle_s);
}

/* True if the corrected peak jerk dv / den keeps every limit (no slack: strict means strict). */
static bool within_limits(const lsm_scurve_limits *lim, lsm_real t1, lsm_real t2, lsm_real den, lsm_real dv)
{
    const lsm_real jp = dv / den;
    return jp <= lim->j_max_mm_s3 && jp * (t1 + t2) <= lim->a_max_mm_s2 && jp * PI_R <= 2 * t1 * lim->snap_max_mm_s4;
}

/* Rounding can leave the corrected jerk an ulp above a limit: min_n4 steps n4 up at most this often. */
#define N4_ROUNDING_STEPS 4

/* ceil(x) for 0 <= x < LSM_MAX_INTERVAL_CYCLES, without the library call: the truncation is floor(x), and the count
 * converts back exactly (in float below 2^24; above it x is itself a whole number; in double always). */
static uint32_t ceil_count(lsm_real x)
{
    const uint32_t n = (uint32_t)x;
    return (lsm_real)n < x ? n + 1u : n;
}

/* For fixed n1, n2: the smallest n4 that keeps the limits, and eq 34's denominator with it (the expression of
 * lsm_scurve_jerk_den, so the same value). Returns false on overflow. */
static bool min_n4(const lsm_scurve_limits *lim, lsm_real dt, lsm_real dv, uint32_t n1, uint32_t n2, uint32_t *n4,
                   lsm_real *den)
{
    const lsm_real t1 = (lsm_real)n1 * dt;
    const lsm_real t2 = (lsm_real)n2 * dt;
    const lsm_real s12 = t1 + t2;
    const lsm_real den0 = s12 * (2 * t1 + t2);
    const lsm_real need = dv / jerk_cap(lim, t1, t2);
    uint32_t n = 0;
    if (need > den0) {
        const lsm_real x = (need - den0) / (s12 * dt);
        if (!(x < (lsm_real)LSM_MAX_INTERVAL_CYCLES))
            return false;
        n = ceil_count(x);
        if (!(n < LSM_MAX_INTERVAL_CYCLES))
            return false;
    }
    lsm_real d = s12 * (2 * t1 + t2 + (lsm_real)n * dt);
    for (int guard = 0; guard < N4_ROUNDING_STEPS && !within_limits(lim, t1, t2, d, dv); guard++) {
        n++;
        d = s12 * (2 * t1 + t2 + (lsm_real)n * dt);
    }
    *n4 = n;
    *den = d;
    return true;
}

/* The whole cycles in x (>= 0; truncation is floor there), clamped to the representable range: to_count(x + 0.5)
 * rounds to the nearest count, to_count(floor(x)) is to_count(x). */
static uint32_t to_count(lsm_real x)
{
    if (!(x > 0))
        return 0;
    if (!(x < (lsm_real)LSM_MAX_INTERVAL_CYCLES))
        return LSM_MAX_INTERVAL_CYCLES;
    return (uint32_t)x;
}

/*
 * Lower bounds of a candidate's total cycles, from the limits alone (derived here). With r = 2 n1 + n2 + n4 and
 * s = n1 + n2, eq 34's denominator is dt² s r, and the corrected J_P = dv / den keeps the jerk cap (eqs 10, 16,
 * 22) only if r >= max(KJ / s, KA, KS / (n1 s)), with KJ = dv / (J dt²), KA = dv / (A dt), KS = pi dv / (2 DJ dt³);
 * also r >= 2 n1 + n2 (n4 >= 0). The total 4 n1 + 2 n2 + n4 is 2 n1 + n2 + r. The constants are shrunk by
 * LB_MARGIN so that the bound holds for the rounded n4 that min_n4 computes (a few ulp, relative), in float too.
 */
#define LB_MARGIN LSM_R(1e-4)

typedef struct total_bound {
    lsm_real kj, ka, ks; /* KJ, KA, KS of the comment above, times (1 - LB_MARGIN) */
} total_bound;

/* What the bounds say of a candidate against the best total: it may tie (size it), or it certainly takes more
 * cycles, by the total's floor 2 q or KA (TIE_LONGER), or by KJ / s or KS / (n1 s) (TIE_TOO_SHORT: s = n1 + n2
 * is too small for the jerk or the snap). */
typedef enum tie_verdict { TIE_MAYBE = 0, TIE_LONGER = 1, TIE_TOO_SHORT = 2 } tie_verdict;

static tie_verdict cannot_tie(const total_bound *b, uint32_t n1, uint32_t n2, uint32_t best_total)
{
    const uint32_t q = 2 * n1 + n2; /* < 2^30: n1, n2 <= LSM_MAX_INTERVAL_CYCLES + 2 (32-bit: no libgcc helper) */
    if (q > best_total / 2)
        return TIE_LONGER; /* the total is at least 2 q (n4 >= 0) */
    /* room: the largest r that still ties (an integer: r > room means a longer total); the relative margin
     * absorbs the rounding of the products below */
    const lsm_real room = (lsm_real)(best_total - q) * (1 + LB_MARGIN);
    if (b->ka > room)
        return TIE_LONGER;
    const lsm_real s = (lsm_real)(n1 + n2);
    return b->kj > room * s || b->ks > room * s * (lsm_real)n1 ? TIE_TOO_SHORT : TIE_MAYBE;
}

/* Sizing candidates are ranked by total cycles, then by the larger eq-34 denominator (the lower jerk), then by
 * their place in the window's scan order (n1 ascending, n2 ascending, n2 = 0 last): the scan's first winner. */
typedef struct cand_best {
    uint32_t total;
    uint32_t order;
    lsm_real den;
    bool found;
} cand_best;

/* Sizes candidate (n1, n2) (scan position `order`) and keeps it in *best / *iv if it ranks higher. */
static void try_candidate(const lsm_scurve_limits *lim, lsm_real dt, lsm_real dv, uint32_t n1, uint32_t n2,
                          uint32_t order, cand_best *best, lsm_scurve_intervals *iv)
{
    uint32_t n4;
    lsm_real den;
    if (!min_n4(lim, dt, dv, n1, n2, &n4, &den))
        return;
    const uint64_t total = 4ull * n1 + 2ull * n2 + n4;
    if (total >= LSM_MAX_INTERVAL_CYCLES)
        return;
    const lsm_scurve_intervals cand = {n1, n2, n4};
    if (best->found && (total > best->total ||
                        (total == best->total && (den < best->den || (den == best->den && order > best->order)))))
        return;
    best->total = (uint32_t)total;
    best->order = order;
    best->den = den;
    best->found = true;
    *iv = cand;
}

/* If x >= this factor times m³, cbrt(x) >= m by far more than its rounding (the guide's min skips the cbrt);
 * CBRT_SKIP_MIN keeps m³ a normal number, where that relative margin means something. */
#define CBRT_SKIP LSM_R(1.001)
#define CBRT_SKIP_MIN LSM_R(1e-30)

void lsm_scurve_sizer_init(lsm_scurve_sizer *sz, const lsm_scurve_limits *lim, lsm_real cycle_s)
{
    const lsm_real A = lim->a_max_mm_s2, J = lim->j_max_mm_s3, DJ = lim->snap_max_mm_s4, dt = cycle_s;
    sz->lim = *lim;
    sz->cycle_s = dt;
    /* the guide's dv-free part (eqs 25, 26), exactly as lsm_scurve_strict_intervals computes it */
    lsm_real t1 = PI_R * J / (2 * DJ);
    t1 = lsm_min2(t1, lsm_sqrt(PI_R * A / (2 * DJ)));
    sz->t1_s = t1;
    const lsm_real m3 = t1 * t1 * t1;
    sz->cbrt_skip_s3 = m3 >= CBRT_SKIP_MIN ? CBRT_SKIP * m3 : LSM_REAL_MAX;
    sz->cbrt_x_per_dv = PI_R / (4 * DJ) * (1 - LB_MARGIN); /* x_f per unit dv, rounded down (skip test only) */
    sz->jc_mm_s3 = 2 * t1 * DJ / PI_R;
    sz->t2a_s = A / sz->jc_mm_s3 - t1;
    sz->c1_cycles = to_count(t1 / dt + (lsm_real)0.5);
    const lsm_real keep = 1 - LB_MARGIN;
    sz->kj_per_dv = keep / (J * dt * dt);
    sz->ka_per_dv = keep / (A * dt);
    sz->ks_per_dv = keep * PI_R / (2 * DJ * dt * dt * dt);
}

/* The window search: the best-ranked candidate (total, den, scan order) of the window around (c1, c2). */
static bool window_best(const lsm_scurve_sizer *sz, lsm_real dv, uint32_t c1, uint32_t c2, lsm_scurve_intervals *iv)
{
    const uint32_t n1_lo = c1 > 3 ? c1 - 2 : 1, n1_hi = c1 + 2;
    const uint32_t n2_lo = c2 > 2 ? c2 - 2 : 0, n2_hi = c2 + 2;
    /* the window: n1 in [n1_lo, n1_hi]; n2 in [n2_lo, n2_hi], plus 0 (the profile without T2 and T6) */
    const uint32_t n_k = n2_hi - n2_lo + (n2_lo > 0 ? 2 : 1);
    /* the bounds' constants scale with dv (products: their rounding is inside LB_MARGIN's) */
    const total_bound bnd = {sz->kj_per_dv * dv, sz->ka_per_dv * dv, sz->ks_per_dv * dv};
    cand_best best = {0, 0, 0, false};
    /* the guide's own candidate first: usually the winner, it lets the bounds skip most of the others */
    const uint32_t g1 = c1 < n1_lo ? n1_lo : c1;
    const uint32_t g_order = (g1 - n1_lo) * n_k + (c2 - n2_lo);
    try_candidate(&sz->lim, sz->cycle_s, dv, g1, c2, g_order, &best, iv);
    const uint32_t n_up = n2_hi - n2_lo + 1; /* the row's n2 = n2_lo .. n2_hi (then 0, when n2_lo > 0) */
    for (uint32_t n1 = n1_lo; n1 <= n1_hi; n1++) {
        /* every candidate from here on has q = 2 n1 + n2 >= 2 n1: past half the best total, cannot_tie skips them all */
        if (best.found && 2 * n1 > best.total / 2)
            break;
        /* the row by s = n1 + n2 descending (the rank keeps the scan order), from the largest n2 with q <= T / 2
         * (cannot_tie skips the larger ones; T only decreases); see below for the end */
        const uint32_t n2_room = best.found ? best.total / 2 - 2 * n1 : UINT32_MAX;
        const uint32_t i0 = n2_hi > n2_room ? n2_hi - n2_room : 0;
        for (uint32_t i = i0 < n_up ? i0 : n_up; i < n_k; i++) {
            const uint32_t k = i < n_up ? n_up - 1 - i : n_up;
            const uint32_t n2 = k < n_up ? n2_lo + k : 0;
            const uint32_t order = (n1 - n1_lo) * n_k + k;
            if (order == g_order)
                continue;
            const tie_verdict v = best.found ? cannot_tie(&bnd, n1, n2, best.total) : TIE_MAYBE;
            /* too short: KJ > (T - q) s or KS > (T - q) s n1 (T the best total, with LB_MARGIN to spare). cannot_tie
             * got there with q <= T / 2, so 2 s <= T - 2 n1, where (T - n1 - s) s grows with s: every smaller s of
             * the row is too short as well */
            if (v == TIE_TOO_SHORT)
                break;
            if (v == TIE_MAYBE)
                try_candidate(&sz->lim, sz->cycle_s, dv, n1, n2, order, &best, iv);
        }
    }
    return best.found;
}

bool lsm_scurve_sizer_intervals(const lsm_scurve_sizer *sz, lsm_real dv_mm_s, lsm_scurve_intervals *iv)
{
    iv->n1_cycles = iv->n2_cycles = iv->n4_cycles = 0;
    if (!(dv_mm_s > 0))
        return true;
    const lsm_real A = sz->lim.a_max_mm_s2, DJ = sz->lim.snap_max_mm_s4, dt = sz->cycle_s;
    /* continuous optimum as a guide (eqs 25, 26, 29, 35, 32, 27, 30); the dv-free part is the sizer's */
    lsm_real t1c = sz->t1_s, jc = sz->jc_mm_s3, t2a = sz->t2a_s;
    uint32_t c1 = sz->c1_cycles;
    if (!(dv_mm_s * sz->cbrt_x_per_dv >= sz->cbrt_skip_s3)) {
        const lsm_real t1f = lsm_cbrt(PI_R * dv_mm_s / (4 * DJ));
        if (t1f < t1c) { /* eq 29 binds: the dv-free part changes */
            t1c = t1f;
            jc = 2 * t1c * DJ / PI_R;
            t2a = A / jc - t1c;
            c1 = to_count(t1c / dt + (lsm_real)0.5);
        }
    }
    const lsm_real t2f = lsm_sqrt(t1c * t1c / 4 + dv_mm_s / jc) - 3 * t1c / 2;
    const lsm_real t2c = lsm_max2(lsm_min2(t2a, t2f), 0);
    const uint32_t c2 = to_count(t2c / dt + (lsm_real)0.5);
    if (c1 >= LSM_MAX_INTERVAL_CYCLES || c2 >= LSM_MAX_INTERVAL_CYCLES)
        return false;
    return window_best(sz, dv_mm_s, c1, c2, iv);
}

bool lsm_scurve_strict_intervals(const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real dv_mm_s,
                                 lsm_scurve_intervals *iv)
{
    if (!(dv_mm_s > 0)) {
        iv->n1_cycles = iv->n2_cycles = iv->n4_cycles = 0;
        return true;
    }
    lsm_scurve_sizer sz;
    lsm_scurve_sizer_init(&sz, lim, cycle_s);
    return lsm_scurve_sizer_intervals(&sz, dv_mm_s, iv);
}

static void paper_intervals(const lsm_scurve_limits *lim, lsm_real dt, lsm_real dv, lsm_scurve_intervals *iv,
                            lsm_scurve_info *info)
{
    const lsm_real A = lim->a_max_mm_s2, DJ = lim->snap_max_mm_s4;
    const lsm_real t1 = lsm_min2(info->dt1j_s, lsm_min2(info->dt1a_s, info->dt1f_s));
    lsm_real n1 = lsm_floor(t1 / dt + PAPER_FLOOR_GUARD);
    if (n1 < 1)
        n1 = 1; /* the paper gives no rule when dt1 floors to zero cycles: keep one cycle */
    const lsm_real dt1 = n1 * dt;
    const lsm_real jp = 2 / PI_R * dt1 * DJ; /* eq 32 */
    info->jp_initial_mm_s3 = jp;
    info->dt2a_s = A / jp - PI_R * jp / (2 * DJ);                                                         /* eq 27 */
    info->dt2f_s = lsm_sqrt(jp * jp * PI_R * PI_R / (16 * DJ * DJ) + dv / jp) - 3 * jp * PI_R / (4 * DJ); /* eq 30 */
    lsm_real n2 =
        lsm_min2(lsm_floor(info->dt2a_s / dt + PAPER_FLOOR_GUARD), lsm_floor(info->dt2f_s / dt + (lsm_real)0.5));
    n2 = lsm_max2(n2, 0); /* eq 36 */
    const lsm_real dt2 = n2 * dt;
    const lsm_real ap = jp * (dt1 + dt2); /* eq 23 */
    info->ap_mm_s2 = ap;
    info->dt4f_s = dv / ap - PI_R * jp / (2 * DJ) - ap / jp;                       /* eq 31, last term -A_P/J_P */
    const lsm_real n4 = lsm_max2(lsm_floor(info->dt4f_s / dt + (lsm_real)0.5), 0); /* eq 37 */
    iv->n1_cycles = to_count(n1);
    iv->n2_cycles = to_count(n2);
    iv->n4_cycles = to_count(n4);
}

bool lsm_scurve_rule_intervals(const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real dv_mm_s, lsm_scurve_rule rule,
                               lsm_scurve_intervals *iv)
{
    if (rule == LSM_SCURVE_RULE_STRICT)
        return lsm_scurve_strict_intervals(lim, cycle_s, dv_mm_s, iv);
    iv->n1_cycles = iv->n2_cycles = iv->n4_cycles = 0;
    if (!(dv_mm_s > 0))
        return true;
    lsm_scurve_info inf;
    inf.dt1j_s = PI_R * lim->j_max_mm_s3 / (2 * lim->snap_max_mm_s4);
    inf.dt1a_s = lsm_sqrt(PI_R * lim->a_max_mm_s2 / (2 * lim->snap_max_mm_s4));
    inf.dt1f_s = lsm_cbrt(PI_R * dv_mm_s / (4 * lim->snap_max_mm_s4));
    paper_intervals(lim, cycle_s, dv_mm_s, iv, &inf);
    return iv->n1_cycles < LSM_MAX_INTERVAL_CYCLES && iv->n2_cycles < LSM_MAX_INTERVAL_CYCLES &&
           iv->n4_cycles < LSM_MAX_INTERVAL_CYCLES;
}

bool lsm_scurve_fits(const lsm_scurve_limits *lim, lsm_real cycle_s, const lsm_scurve_intervals *iv, lsm_real dv_mm_s)
{
    const lsm_real dv = lsm_fabs(dv_mm_s);
    if (dv == 0)
        return true;
    if (iv->n1_cycles == 0)
        return false;
    const lsm_real t1 = (lsm_real)iv->n1_cycles * cycle_s;
    const lsm_real t2 = (lsm_real)iv->n2_cycles * cycle_s;
    return within_limits(lim, t1, t2, lsm_scurve_jerk_den(iv, cycle_s), dv);
}

lsm_status lsm_scurve_plan(lsm_scurve *out, const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real v0_mm_s,
                           lsm_real v1_mm_s, lsm_scurve_rule rule, lsm_scurve_info *info)
{
    if (out == NULL || lim == NULL)
        return LSM_E_NULL;
    lsm_status st = check_value(v0_mm_s);
    if (st == LSM_OK)
        st = check_value(v1_mm_s);
    if (st != LSM_OK)
        return st;
    st = lsm_scurve_check_limits(lim, cycle_s);
    if (st != LSM_OK)
        return st;
    if (v0_mm_s < 0 || v1_mm_s < 0)
        return LSM_E_NEG_FEED;
    if (rule != LSM_SCURVE_RULE_STRICT && rule != LSM_SCURVE_RULE_PAPER)
        return LSM_E_ARG;

    lsm_scurve_info tmp;
    lsm_scurve_info *inf = info ? info : &tmp;
    const lsm_real dv = lsm_fabs(v1_mm_s - v0_mm_s);
    const lsm_real A = lim->a_max_mm_s2, J = lim->j_max_mm_s3, DJ = lim->snap_max_mm_s4;
    inf->dt1j_s = PI_R * J / (2 * DJ);            /* eq 25 */
    inf->dt1a_s = lsm_sqrt(PI_R * A / (2 * DJ));  /* eq 26 */
    inf->dt1f_s = lsm_cbrt(PI_R * dv / (4 * DJ)); /* eq 29 */

    out->cycle_s = cycle_s;
    out->v0_mm_s = v0_mm_s;
    out->v1_mm_s = v1_mm_s;
    out->iv.n1_cycles = out->iv.n2_cycles = out->iv.n4_cycles = 0;
    out->jp_mm_s3 = 0;
    inf->dt2a_s = inf->dt2f_s = inf->dt4f_s = 0;
    inf->jp_initial_mm_s3 = inf->ap_mm_s2 = inf->ap_final_mm_s2 = inf->snap_final_mm_s4 = 0;
    if (dv == 0)
        return LSM_OK;

    if (rule == LSM_SCURVE_RULE_PAPER) {
        paper_intervals(lim, cycle_s, dv, &out->iv, inf);
        if (out->iv.n1_cycles >= LSM_MAX_INTERVAL_CYCLES || out->iv.n2_cycles >= LSM_MAX_INTERVAL_CYCLES ||
            out->iv.n4_cycles >= LSM_MAX_INTERVAL_CYCLES)
            return LSM_E_TOO_LONG;
    } else {
        if (!lsm_scurve_strict_intervals(lim, cycle_s, dv, &out->iv))
            return LSM_E_TOO_LONG;
        /* the Table 1 quantities for this n1, n2 (reports only) */
        const lsm_real dt1 = (lsm_real)out->iv.n1_cycles * cycle_s;
        const lsm_real dt2 = (lsm_real)out->iv.n2_cycles * cycle_s;
        const lsm_real jp = 2 / PI_R * dt1 * DJ;
        inf->jp_initial_mm_s3 = jp;
        inf->dt2a_s = A / jp - PI_R * jp / (2 * DJ);
        inf->dt2f_s = lsm_sqrt(jp * jp * PI_R * PI_R / (16 * DJ * DJ) + dv / jp) - 3 * jp * PI_R / (4 * DJ);
        inf->ap_mm_s2 = jp * (dt1 + dt2);
        inf->dt4f_s = dv / inf->ap_mm_s2 - PI_R * jp / (2 * DJ) - inf->ap_mm_s2 / jp;
    }
    if (lsm_scurve_total_cycles(&out->iv) >= LSM_MAX_INTERVAL_CYCLES)
        return LSM_E_TOO_LONG;

    const lsm_real jp = dv / lsm_scurve_jerk_den(&out->iv, cycle_s); /* eq 34 */
    out->jp_mm_s3 = v1_mm_s >= v0_mm_s ? jp : -jp;
    const lsm_real dt1 = (lsm_real)out->iv.n1_cycles * cycle_s;
    const lsm_real dt2 = (lsm_real)out->iv.n2_cycles * cycle_s;
    inf->ap_final_mm_s2 = jp * (dt1 + dt2);
    inf->snap_final_mm_s4 = jp * PI_R / (2 * dt1);
    return LSM_OK;
}

lsm_real lsm_scurve_duration_s(const lsm_scurve *sc)
{
    return (lsm_real)lsm_scurve_total_cycles(&sc->iv) * sc->cycle_s;
}

lsm_real lsm_scurve_distance_mm(const lsm_scurve *sc)
{
    return (sc->v0_mm_s + sc->v1_mm_s) * lsm_scurve_duration_s(sc) / 2;
}

void lsm_scurve_phases(const lsm_scurve_intervals *iv, lsm_real jp_mm_s3, lsm_phase out[7])
{
    const uint32_t n[7] = {iv->n1_cycles, iv->n2_cycles, iv->n1_cycles, iv->n4_cycles,
                           iv->n1_cycles, iv->n2_cycles, iv->n1_cycles};
    const uint8_t shape[7] = {LSM_PHASE_RISE, LSM_PHASE_CONST, LSM_PHASE_FALL, LSM_PHASE_CONST,
                              LSM_PHASE_RISE, LSM_PHASE_CONST, LSM_PHASE_FALL};
    for (int i = 0; i < 7; i++) {
        out[i].n_cycles = n[i];
        out[i].shape = shape[i];
        out[i].jerk_mm_s3 = (i == 3) ? 0 : (i < 3 ? jp_mm_s3 : -jp_mm_s3);
    }
}

void lsm_phase_unit(lsm_phase_shape shape, lsm_real T_s, lsm_real tau_s, lsm_real out_javs[4])
{
    const lsm_real t = tau_s;
    if (shape == LSM_PHASE_CONST) {
        out_javs[0] = 1;
        out_javs[1] = t;
        out_javs[2] = t * t / 2;
        out_javs[3] = t * t * t / 6;
        return;
    }
    const lsm_real w = PI_R / (2 * T_s);
    const lsm_real phi = 2 * w * t;
    const lsm_real s = lsm_sin(phi), c = lsm_cos(phi);
    const lsm_real sg = shape == LSM_PHASE_RISE ? 1 : -1; /* the sin terms flip sign between rise and fall */
    out_javs[0] = (1 - sg * c) / 2;
    out_javs[1] = t / 2 - sg * s / (4 * w);
    out_javs[2] = t * t / 4 - sg * (1 - c) / (8 * w * w);
    out_javs[3] = t * t * t / 12 - sg * t / (8 * w * w) + sg * s / (16 * w * w * w);
}

void lsm_phase_advance(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_real tau_s, lsm_kin *out)
{
    lsm_real u[4];
    lsm_phase_unit((lsm_phase_shape)ph->shape, (lsm_real)ph->n_cycles * cycle_s, tau_s, u);
    const lsm_real jk = ph->jerk_mm_s3, t = tau_s;
    const lsm_kin s0 = *start; /* out may alias start */
    out->j_mm_s3 = jk * u[0];
    out->a_mm_s2 = s0.a_mm_s2 + jk * u[1];
    out->v_mm_s = s0.v_mm_s + s0.a_mm_s2 * t + jk * u[2];
    out->s_mm = s0.s_mm + s0.v_mm_s * t + s0.a_mm_s2 * t * t / 2 + jk * u[3];
}

void lsm_phase_end(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_kin *out)
{
    /* the unit shape at tau = T with the exact values cos(pi) = -1, sin(pi) = 0 (no trigonometry):
     * rise: a = T/2, v = T²/4 - T²/pi², s = T³/12 - T³/(2 pi²); fall: the same with + (eqs 19-21) */
    const lsm_real T = (lsm_real)ph->n_cycles * cycle_s;
    lsm_real u[4];
    if (ph->shape == LSM_PHASE_CONST) {
        u[0] = 1;
        u[1] = T;
        u[2] = T * T / 2;
        u[3] = T * T * T / 6;
    } else {
        const lsm_real sg = ph->shape == LSM_PHASE_RISE ? 1 : -1;
        const lsm_real k = T * T / (PI_R * PI_R); /* 2 / (8 w²) */
        u[0] = ph->shape == LSM_PHASE_RISE ? 1 : 0;
        u[1] = T / 2;
        u[2] = T * T / 4 - sg * k;
        u[3] = T * T * T / 12 - sg * T * k / 2;
    }
    const lsm_real jk = ph->jerk_mm_s3;
    const lsm_kin s0 = *start;
    out->j_mm_s3 = jk * u[0];
    out->a_mm_s2 = s0.a_mm_s2 + jk * u[1];
    out->v_mm_s = s0.v_mm_s + s0.a_mm_s2 * T + jk * u[2];
    out->s_mm = s0.s_mm + s0.v_mm_s * T + s0.a_mm_s2 * T * T / 2 + jk * u[3];
}

void lsm_phases_eval_cycle(const lsm_phase *ph, unsigned n_phases, lsm_real cycle_s, const lsm_kin *start, uint32_t k,
                           lsm_real frac, lsm_kin *out)
{
    lsm_kin st = *start;
    uint32_t m = k;
    for (unsigned i = 0; i < n_phases; i++) {
        const uint32_t n = ph[i].n_cycles;
        if (n == 0)
            continue;
        if (m < n || (m == n && frac == 0)) {
            lsm_phase_advance(&ph[i], cycle_s, &st, ((lsm_real)m + frac) * cycle_s, out);
            return;
        }
        lsm_phase_end(&ph[i], cycle_s, &st, &st);
        m -= n;
    }
    /* past the last phase: constant velocity */
    const lsm_real tau = ((lsm_real)m + frac) * cycle_s;
    out->s_mm = st.s_mm + st.v_mm_s * tau;
    out->v_mm_s = st.v_mm_s;
    out->a_mm_s2 = 0;
    out->j_mm_s3 = 0;
}

void lsm_scurve_eval_cycle(const lsm_scurve *sc, uint32_t k, lsm_real frac, lsm_kin *out)
{
    lsm_phase ph[7];
    lsm_scurve_phases(&sc->iv, sc->jp_mm_s3, ph);
    const lsm_kin start = {0, sc->v0_mm_s, 0, 0};
    lsm_phases_eval_cycle(ph, 7, sc->cycle_s, &start, k, frac, out);
}

void lsm_scurve_eval(const lsm_scurve *sc, lsm_real t_s, lsm_kin *out)
{
    const lsm_real x = t_s > 0 ? t_s / sc->cycle_s : 0;
    const lsm_real kf = lsm_floor(x);
    const lsm_real cap = (lsm_real)lsm_scurve_total_cycles(&sc->iv) + 1;
    if (kf >= cap) { /* far past the end: constant velocity from the end state */
        lsm_scurve_eval_cycle(sc, (uint32_t)cap - 1u, 0, out);
        out->s_mm += out->v_mm_s * (t_s - (cap - 1) * sc->cycle_s);
        return;
    }
    lsm_scurve_eval_cycle(sc, (uint32_t)kf, x - kf, out);
}
