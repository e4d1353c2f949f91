#include "move.h"

#include "lsm_math.h"

/* Largest number of cycles in one move (fits the 32-bit cycle counters with margin). */
#define LSM_MOVE_MAX_CYCLES 0x40000000u
#define FIT_MAX_ITER 64
#if LSM_REAL_IS_FLOAT
#define BISECT_ITER 24
#else
#define BISECT_ITER 32
#endif
/* False position's smallest step, as a fraction of the bracket: keeps it shrinking when d is far from linear. */
#define FALSEPOS_MIN LSM_R(0.02)

typedef struct shape {
    lsm_scurve_intervals acc, dec;
    uint32_t nc;
} shape;

static lsm_scurve_limits ramp_limits(const lsm_axis_limits *L)
{
    lsm_scurve_limits s = {L->a_max_mm_s2, L->j_max_mm_s3, L->snap_max_mm_s4};
    return s;
}

static bool ramp(const lsm_axis_limits *L, lsm_real dt, lsm_real dv, lsm_scurve_rule rule, lsm_scurve_intervals *iv)
{
    const lsm_scurve_limits sl = ramp_limits(L);
    return lsm_scurve_rule_intervals(&sl, dt, lsm_fabs(dv), rule, iv);
}

static bool ramp_fits(const lsm_axis_limits *L, lsm_real dt, const lsm_scurve_intervals *iv, lsm_real dv,
                      lsm_scurve_rule rule)
{
    if (rule == LSM_SCURVE_RULE_PAPER) /* the paper's rounding does not promise the limits */
        return dv == 0 || iv->n1_cycles > 0;
    const lsm_scurve_limits sl = ramp_limits(L);
    return lsm_scurve_fits(&sl, dt, iv, dv);
}

/* Distance of the two quantised ramps v0 -> vp -> v1 (mm), or -1 on overflow; their intervals in *sh (nc
 * untouched). With v0 = v1 (from rest to rest) both ramps are the same velocity change: sized once. */
static lsm_real ramps_shape(const lsm_axis_limits *L, lsm_real dt, lsm_real v0, lsm_real vp, lsm_real v1,
                            lsm_scurve_rule rule, shape *sh)
{
    if (!ramp(L, dt, vp - v0, rule, &sh->acc))
        return -1;
    if (v1 == v0)
        sh->dec = sh->acc;
    else if (!ramp(L, dt, vp - v1, rule, &sh->dec))
        return -1;
    return ((v0 + vp) * (lsm_real)lsm_scurve_total_cycles(&sh->acc) +
            (vp + v1) * (lsm_real)lsm_scurve_total_cycles(&sh->dec)) *
           dt / 2;
}

static bool iv_equal(const lsm_scurve_intervals *a, const lsm_scurve_intervals *b)
{
    return a->n1_cycles == b->n1_cycles && a->n2_cycles == b->n2_cycles && a->n4_cycles == b->n4_cycles;
}

static lsm_scurve_intervals iv_max(const lsm_scurve_intervals *a, const lsm_scurve_intervals *b)
{
    lsm_scurve_intervals r;
    r.n1_cycles = a->n1_cycles > b->n1_cycles ? a->n1_cycles : b->n1_cycles;
    r.n2_cycles = a->n2_cycles > b->n2_cycles ? a->n2_cycles : b->n2_cycles;
    r.n4_cycles = a->n4_cycles > b->n4_cycles ? a->n4_cycles : b->n4_cycles;
    return r;
}

/*
 * The minimal-time shape of one axis alone (before the exact fit); *vp_out gets its peak feed. The peak is
 * bisected on the distance of the quantised ramps, which is non-decreasing in it; only the ramps' intervals
 * matter downstream (window_nc and fit solve the cruise feed exactly for given intervals), so the bisection
 * stops as soon as both ends of its bracket have the same intervals.
 */
static lsm_status single_shape(const lsm_axis_limits *L, lsm_real dt, lsm_real D, lsm_real v0, lsm_real v1,
                               lsm_scurve_rule rule, shape *sh, lsm_real *vp_out)
{
    const lsm_real vlo = lsm_max2(v0, v1);
    shape s_lo, s_hi;
    const lsm_real d_lo = ramps_shape(L, dt, v0, vlo, v1, rule, &s_lo);
    if (d_lo < 0)
        return LSM_E_TOO_LONG;
    if (d_lo > D)
        return LSM_E_INFEASIBLE;
    lsm_real vp = L->v_max_mm_s, dist = ramps_shape(L, dt, v0, vp, v1, rule, &s_hi);
    if (dist < 0 || dist > D) {
        lsm_real lo = vlo, hi = vp; /* d(lo) <= D < d(hi); d is non-decreasing in vp */
        bool hi_sized = dist >= 0;  /* s_hi holds hi's intervals (not an overflow) */
        /* false position (Illinois) on d(vp) - D while hi is sized, else halving: d is close to smooth between
         * the jumps of the whole-cycle intervals, so the bracket closes on one interval set in a few steps */
        lsm_real f_lo = d_lo - D, f_hi = hi_sized ? dist - D : 0;
        int side = 0; /* which end the last step moved: -1 lo, +1 hi */
        dist = d_lo;
        for (int i = 0; i < BISECT_ITER && hi - lo > LSM_REAL_EPS * hi; i++) {
            if (hi_sized && iv_equal(&s_lo.acc, &s_hi.acc) && iv_equal(&s_lo.dec, &s_hi.dec))
                break; /* every peak in the bracket has these intervals */
            lsm_real frac = LSM_R(0.5);
            if (hi_sized && f_hi > f_lo)
                frac = lsm_min2(lsm_max2(-f_lo / (f_hi - f_lo), FALSEPOS_MIN), 1 - FALSEPOS_MIN);
            const lsm_real mid = lo + (hi - lo) * frac;
            shape s_mid;
            const lsm_real dm = ramps_shape(L, dt, v0, mid, v1, rule, &s_mid);
            if (dm >= 0 && dm <= D) {
                lo = mid;
                s_lo = s_mid;
                dist = dm;
                f_lo = dm - D;
                if (side < 0)
                    f_hi /= 2; /* Illinois: the far end has not moved twice, halve its weight */
                side = -1;
            } else {
                hi = mid;
                s_hi = s_mid;
                hi_sized = dm >= 0;
                f_hi = dm - D;
                if (side > 0)
                    f_lo /= 2;
                side = 1;
            }
        }
        vp = lo;
        s_hi = s_lo;
    }
    sh->acc = s_hi.acc;
    sh->dec = s_hi.dec;
    const lsm_real rest = D - dist;
    lsm_real nc = 0;
    if (vp > 0 && rest > 0) {
        nc = lsm_ceil(rest / (vp * dt));
        if (!(nc < (lsm_real)LSM_MOVE_MAX_CYCLES))
            return LSM_E_TOO_LONG;
    }
    sh->nc = (uint32_t)nc;
    *vp_out = vp;
    return LSM_OK;
}

/* One tried peak feed of the strict search: its quantised ramps and their distance. */
typedef struct peak_try {
    lsm_real v;      /* peak feed vp */
    lsm_real d;      /* distance of the two ramps v0 -> vp -> v1 (mm); -1 on overflow */
    uint32_t ta, td; /* their total cycles */
    shape sh;        /* their intervals (nc unused) */
} peak_try;

/* The largest number of peaks the strict search tries (it usually stops after 2-5). */
#define PEAK_TRIES 64

/* Sizes both ramps of peak vp (as ramps_shape does, strict rule, with the axis's sizer). */
static bool try_peak(const lsm_scurve_sizer *sz, lsm_real v0, lsm_real v1, lsm_real vp, peak_try *p)
{
    p->v = vp;
    p->d = -1;
    if (!lsm_scurve_sizer_intervals(sz, lsm_fabs(vp - v0), &p->sh.acc))
        return false;
    if (v1 == v0)
        p->sh.dec = p->sh.acc;
    else if (!lsm_scurve_sizer_intervals(sz, lsm_fabs(vp - v1), &p->sh.dec))
        return false;
    p->ta = lsm_scurve_total_cycles(&p->sh.acc);
    p->td = lsm_scurve_total_cycles(&p->sh.dec);
    p->d = ((v0 + vp) * (lsm_real)p->ta + (vp + v1) * (lsm_real)p->td) * sz->cycle_s / 2;
    return true;
}

/*
 * The root of a tried peak's distance line: with its ramp totals Ta, Td (cycles) fixed, the ramps travel
 * ((v0 + vp) Ta + (vp + v1) Td) dt / 2, linear in vp; it equals D at (2 D / dt - v0 Ta - v1 Td) / (Ta + Td).
 * Totals never decrease with the peak, so the quantised distance is at least this line above the tried peak and
 * at most it below: a feasible try's root bounds the answer from above, an infeasible try's root from below.
 */
static lsm_real peak_root(const peak_try *p, lsm_real d2_dt, lsm_real v0, lsm_real v1)
{
    const uint32_t n = p->ta + p->td;
    if (n == 0)
        return LSM_REAL_MAX;
    return (d2_dt - v0 * (lsm_real)p->ta - v1 * (lsm_real)p->td) / (lsm_real)n;
}

static bool same_totals(const peak_try *a, const peak_try *b)
{
    return a->ta == b->ta && a->td == b->td;
}

/* No ramp total lies strictly between the two tries' (so no third distance line lies between them). */
static bool adjacent_totals(const peak_try *lo, const peak_try *hi, bool one_ramp)
{
    const uint32_t da = hi->ta - lo->ta, dd = hi->td - lo->td;
    return one_ramp ? da == 1 : da + dd == 1;
}

/* Relative step past a ramp's velocity capacity (2 ulp of the feed: float slivers where another interval set of
 * the same totals holds are a few ulp wide; last_intervals steps further while the sizing keeps the intervals). */
#define PAST_CAPACITY (2 * LSM_REAL_EPS)

/* The peak just past the velocity capacity of lo's intervals (by a relative `past`): where the first of lo's two
 * ramps must change its intervals (no larger velocity change fits them; the sizing then takes others). */
static lsm_real past_capacity(const lsm_scurve_sizer *sz, lsm_real v0, lsm_real v1, const peak_try *lo, lsm_real past)
{
    const lsm_real cap = lsm_min2(v0 + lsm_scurve_dv_capacity(&sz->lim, sz->cycle_s, &lo->sh.acc),
                                  v1 + lsm_scurve_dv_capacity(&sz->lim, sz->cycle_s, &lo->sh.dec));
    return lsm_max2(cap, lo->v) * (1 + past);
}

/*
 * lo and hi are on adjacent lines and every feasible peak between them has lo's totals. Several intervals can
 * share those totals (n1, n2 and n4 traded against each other); the sizing takes the one with the larger eq-34
 * denominator while it holds the velocity change, so the intervals change within lo's line as the peak grows.
 * The answer is the one just below the jump: step past the velocity capacity of lo's intervals until the totals
 * change (usually once).
 */
static void last_intervals(const lsm_scurve_sizer *sz, lsm_real v0, lsm_real v1, peak_try *lo, const peak_try *hi,
                           lsm_real D)
{
    lsm_real past = PAST_CAPACITY;
    for (int k = 0; k < 6; k++) {
        const lsm_real x = past_capacity(sz, v0, v1, lo, past);
        peak_try m;
        if (!(x > lo->v && x < hi->v) || !try_peak(sz, v0, v1, x, &m))
            return;
        if (!same_totals(&m, lo) || m.d > D)
            return;
        if (iv_equal(&m.sh.acc, &lo->sh.acc) && iv_equal(&m.sh.dec, &lo->sh.dec))
            past *= 8; /* the capacity's rounding kept the intervals: step further */
        *lo = m;
    }
}

typedef enum peak_kind { PEAK_ROOT_LO, PEAK_ROOT_HI, PEAK_VMAX, PEAK_INNER } peak_kind;

/* False position's share of the bracket kept clear at either end (the inner step never lands on an end). */
#define PEAK_INNER_MIN LSM_R(0.05)
/* Ramp totals (summed over both ramps) within which lo and hi are near: a few transitions apart. */
#define PEAK_NEAR 4u

/*
 * The inner step, inside the bracket:
 *   - lo and hi near (PEAK_NEAR): just past the velocity capacity of lo's intervals, the next transition up (one
 *     ramp changes its intervals there; false position would fall on hi's side of a small middle line);
 *   - hi overflowed, or the last two inner steps moved the same end (false position creeping): half way;
 *   - otherwise false position on the distance, within [max(lo, root(hi)), min(hi, root(lo))], clear of its ends.
 */
static lsm_real inner_peak(const lsm_scurve_sizer *sz, lsm_real v0, lsm_real v1, const peak_try *lo, const peak_try *hi,
                           bool hi_sized, bool creeping, lsm_real rl, lsm_real rh, lsm_real D)
{
    if (hi_sized && (hi->ta - lo->ta) + (hi->td - lo->td) <= PEAK_NEAR) {
        const lsm_real x = past_capacity(sz, v0, v1, lo, PAST_CAPACITY);
        if (x > lo->v && x < hi->v)
            return x;
    }
    if (!hi_sized || creeping || !(hi->d > lo->d))
        return lo->v + (hi->v - lo->v) / 2;
    const lsm_real a = lsm_max2(lo->v, rh), b = lsm_min2(hi->v, rl);
    const lsm_real x = lo->v + (hi->v - lo->v) * ((D - lo->d) / (hi->d - lo->d));
    const lsm_real w = (b - a) * PEAK_INNER_MIN;
    return b > a ? lsm_min2(lsm_max2(x, a + w), b - w) : lo->v + (hi->v - lo->v) / 2;
}

/*
 * A first guess at the peak of a move from rest to rest, from the continuous (unquantised) ramp of scurve.h: the
 * ramps v -> 0 and 0 -> v travel d(v) = v Tc(v), with Tc = 4 t1 + 2 t2 + t4 the ramp's duration, and d(v) = D is
 * solved in the regime that binds (derived here from eqs 25-37):
 *   eq 29 binds (v < v_a = 4 DJ t1³ / pi):  Tc = 4 cbrt(pi v / (4 DJ)),  so v = (D³ DJ / (16 pi))^(1/4);
 *   t1 fixed, T2 grows (t2 <= t2a):         with u = 2 t1 + t2, v = jc (u - t1) u and D = 2 jc (u - t1) u²
 *                                            (Newton from cbrt(D / 2jc) + t1, an upper bound of u);
 *   A binds, T4 grows:                       Tc = 2 t1 + t2a + v / A,  so v² / A + (2 t1 + t2a) v = D.
 * Only a starting point for the search (which checks everything on the quantised ramps); non-finite if the
 * limits overflow it.
 */
static lsm_real rest_peak_guess(const lsm_scurve_sizer *sz, lsm_real D)
{
    const lsm_real A = sz->lim.a_max_mm_s2, DJ = sz->lim.snap_max_mm_s4, t1 = sz->t1_s, jc = sz->jc_mm_s3;
    const lsm_real pi = (lsm_real)LSM_PI;
    const lsm_real v_a = 4 * DJ * t1 * t1 * t1 / pi;
    if (D <= 4 * t1 * v_a)
        return lsm_sqrt(lsm_sqrt(D * D * D * DJ / (16 * pi)));
    const lsm_real b = 2 * t1 + lsm_max2(sz->t2a_s, 0);
    if (D <= 2 * jc * (b - t1) * b * b) {
        const lsm_real c = D / (2 * jc);
        lsm_real u = lsm_min2(lsm_cbrt(c) + t1, b);
        for (int k = 0; k < 2; k++)
            u -= (u * u * (u - t1) - c) / (u * (3 * u - 2 * t1));
        return jc * (u - t1) * u;
    }
    return 2 * D / (b + lsm_sqrt(b * b + 4 * D / A));
}

/*
 * Strict rule: the ramp intervals of the largest peak vp in [max(v0, v1), v_max] whose quantised ramps travel at
 * most D (the minimal-time shape before the exact fit, as single_shape finds it). The distance is a step-wise
 * linear, non-decreasing function of vp (one line per pair of ramp totals). The search alternates a false-position
 * step with a step to the root of the line of the peak it just tried (peak_root), and ends when
 *   - a root tried has the totals of the peak whose root it is: the distance crosses D there, on that line;
 *   - the bracket's two ends have the same totals: the answer is at the root of their common line;
 *   - lo and hi have adjacent totals, lo's root lies beyond hi and hi's before lo: the distance jumps over D
 *     between them, the answer is lo's line.
 * v_max is tried only when lo's root reaches it.
 */
static lsm_status strict_peak_shape(const lsm_axis_limits *L, lsm_real dt, lsm_real D, lsm_real v0, lsm_real v1,
                                    shape *sh)
{
    const lsm_real vmax = L->v_max_mm_s, d2_dt = 2 * D / dt;
    const bool one_ramp = v0 == v1;
    const lsm_scurve_limits sl = ramp_limits(L);
    lsm_scurve_sizer sz;
    lsm_scurve_sizer_init(&sz, &sl, dt);
    peak_try lo, hi, m;
    if (!try_peak(&sz, v0, v1, lsm_max2(v0, v1), &lo))
        return LSM_E_TOO_LONG;
    if (lo.d > D)
        return LSM_E_INFEASIBLE;
    hi = lo;
    hi.v = vmax;
    bool hi_tried = false, hi_sized = false; /* hi: an infeasible try (sized: not an overflow) */
    bool root_next = false;                  /* the last try was an inner one: try its root next */
    bool last_lo = true;                     /* ... and it became lo (else hi); lo is the first try */
    int inner_side[2] = {0, 0};              /* the ends the last two inner steps moved: -1 lo, +1 hi */
    const peak_try *ans = &lo;
    for (int i = 0; i < PEAK_TRIES; i++) {
        const lsm_real rl = peak_root(&lo, d2_dt, v0, v1);
        const lsm_real rh = hi_sized ? peak_root(&hi, d2_dt, v0, v1) : lo.v;
        if (hi_sized && same_totals(&lo, &hi)) {
            /* one line spans the bracket: the answer is at its root */
            if (!(iv_equal(&lo.sh.acc, &hi.sh.acc) && iv_equal(&lo.sh.dec, &hi.sh.dec)) &&
                try_peak(&sz, v0, v1, lsm_min2(lsm_max2(rl, lo.v), hi.v), &m))
                ans = &m;
            break;
        }
        if (!(rl > lo.v))
            break; /* lo is at its own line's root */
        if (hi_tried && !(rh > lo.v) && !(rl < hi.v) && hi_sized && adjacent_totals(&lo, &hi, one_ramp)) {
            /* the distance jumps over D between lo's line and hi's: the answer is the intervals that lo's totals
             * have just below the jump */
            last_intervals(&sz, v0, v1, &lo, &hi, D);
            break;
        }
        lsm_real x;
        peak_kind kind;
        if (i == 0 && v0 == 0 && v1 == 0) {
            /* from rest to rest: start at the continuous model's peak (or v_max if that is beyond it) */
            x = rest_peak_guess(&sz, D);
            kind = PEAK_INNER;
            if (!(x < vmax)) {
                x = vmax;
                kind = PEAK_VMAX;
            } else if (!(x > lo.v)) {
                x = lo.v + (vmax - lo.v) / 2;
            }
        } else if (!hi_tried && !(rl < vmax)) {
            x = vmax;
            kind = PEAK_VMAX;
        } else if ((root_next || !hi_tried) && last_lo && rl < hi.v) {
            x = rl;
            kind = PEAK_ROOT_LO;
        } else if (root_next && !last_lo && rh > lo.v && rh < hi.v) {
            x = rh;
            kind = PEAK_ROOT_HI;
        } else {
            x = inner_peak(&sz, v0, v1, &lo, &hi, hi_sized, inner_side[0] != 0 && inner_side[0] == inner_side[1], rl,
                           rh, D);
            kind = PEAK_INNER;
            if (!(x > lo.v && x < hi.v))
                break; /* the bracket is down to adjacent feeds */
        }
        const bool sized = try_peak(&sz, v0, v1, x, &m);
        if (sized &&
            ((kind == PEAK_ROOT_LO && same_totals(&m, &lo)) || (kind == PEAK_ROOT_HI && same_totals(&m, &hi)))) {
            ans = &m; /* the distance crosses D at this root, on this line */
            break;
        }
        root_next = kind == PEAK_INNER || kind == PEAK_VMAX;
        last_lo = sized && m.d <= D;
        if (kind == PEAK_INNER) {
            inner_side[1] = inner_side[0];
            inner_side[0] = last_lo ? -1 : 1;
        }
        if (last_lo) {
            lo = m;
            if (kind == PEAK_VMAX)
                break; /* v_max itself fits */
        } else {
            hi = m;
            hi_tried = true;
            hi_sized = sized;
        }
    }
    sh->acc = ans->sh.acc;
    sh->dec = ans->sh.dec;
    return LSM_OK;
}

/*
 * With the ramp intervals of sh fixed, the fastest cruise length for which this axis's cruise feed keeps both
 * ramps within the limits and under v_max. The feed is vc(nc) = num / (ta/2 + nc dt + td/2) (eq (1) of move.h)
 * and the ramps hold any vc in [max(v0 - cap_a, v1 - cap_d), min(v0 + cap_a, v1 + cap_d)] (cap: the
 * largest velocity change the intervals make within the limits), so the cruise lengths that work form an
 * interval: take its start, verified exactly. False if there is none.
 */
static bool window_nc(const lsm_axis_limits *L, lsm_real dt, lsm_real D, lsm_real v0, lsm_real v1, shape *sh)
{
    const lsm_scurve_limits sl = ramp_limits(L);
    const lsm_real ta = (lsm_real)lsm_scurve_total_cycles(&sh->acc) * dt;
    const lsm_real td = (lsm_real)lsm_scurve_total_cycles(&sh->dec) * dt;
    const lsm_real cap_a = lsm_scurve_dv_capacity(&sl, dt, &sh->acc);
    const lsm_real cap_d = lsm_scurve_dv_capacity(&sl, dt, &sh->dec);
    const lsm_real lo_v = lsm_max2(v0 - cap_a, v1 - cap_d);
    const lsm_real hi_v = lsm_min2(lsm_min2(v0 + cap_a, v1 + cap_d), L->v_max_mm_s);
    const lsm_real num = D - v0 * ta / 2 - v1 * td / 2;
    const lsm_real base = ta / 2 + td / 2;
    if (!(hi_v > 0) || hi_v < lo_v || !(num > 0))
        return false;
    lsm_real nlo = lsm_ceil((num / hi_v - base) / dt);
    if (!(nlo >= 0))
        nlo = 0;
    if (base == 0 && nlo < 1)
        nlo = 1;
    lsm_real nhi = lo_v > 0 ? lsm_floor((num / lo_v - base) / dt) : (lsm_real)(LSM_MOVE_MAX_CYCLES - 1);
    if (!(nhi < (lsm_real)(LSM_MOVE_MAX_CYCLES - 1)))
        nhi = (lsm_real)(LSM_MOVE_MAX_CYCLES - 1);
    if (!(nlo <= nhi))
        return false; /* (also a window beyond the cycle counter) */
    /* integer counts: in float, a real n + 1 stops changing above 2^24 */
    const uint32_t k0 = (uint32_t)nlo, k1 = (uint32_t)nhi;
    for (uint32_t n = k0; n <= k1 && n - k0 < 3; n++) { /* rounding at the window's edge: check exactly */
        const lsm_real vc = num / (base + (lsm_real)n * dt);
        if (vc > 0 && vc <= L->v_max_mm_s && ramp_fits(L, dt, &sh->acc, vc - v0, LSM_SCURVE_RULE_STRICT) &&
            ramp_fits(L, dt, &sh->dec, vc - v1, LSM_SCURVE_RULE_STRICT)) {
            sh->nc = n;
            return true;
        }
    }
    return false;
}

/* For total t and T1 = n1 cycles, the n2 of the largest velocity capacity (see widest_of_total): into *iv and *best if
 * it beats *best. */
static void widest_of_n1(const lsm_scurve_limits *sl, lsm_real dt, uint32_t t, uint32_t n1, lsm_scurve_intervals *iv,
                         lsm_real *best)
{
    const lsm_real t1 = (lsm_real)n1 * dt;
    const lsm_real jc = lsm_min2(sl->j_max_mm_s3, 2 * t1 * sl->snap_max_mm_s4 / (lsm_real)LSM_PI);
    const lsm_real u = sl->a_max_mm_s2 / (jc * dt) - (lsm_real)n1; /* the crossing's n2 (real) */
    const uint32_t n2_top = (t - 4u * n1) / 2u;
    uint32_t n2 = 0;
    if (u > 0)
        n2 = u < (lsm_real)n2_top ? (uint32_t)u : n2_top;
    for (uint32_t k = 0; k < 2 && n2 + k <= n2_top; k++) {
        const lsm_scurve_intervals c = {n1, n2 + k, t - 4u * n1 - 2u * (n2 + k)};
        const lsm_real cap = lsm_scurve_dv_capacity(sl, dt, &c);
        if (cap > *best) {
            *best = cap;
            *iv = c;
        }
    }
}

/* How far from the sized T1 (cycles) widest_of_total looks: the sizing's n1 is near the best for its total. */
#define WIDEST_N1_SPAN 2u

/*
 * The intervals of the same total as *iv with the largest velocity capacity (into *iv). Several intervals share
 * a total (n1, n2 and n4 traded against each other) and the sizing takes the shortest for its velocity change, not
 * the one that carries the most; with the totals fixed, the cruise feed of every cruise length is fixed too
 * (eq (1) of move.h), so only the capacity decides whether the ramps hold it. For fixed n1 the capacity is
 * min(Jc den, A den / (t1 + t2)) with Jc = min(Jmax, 2 t1 DJmax / pi) and den (eq 34) rising in n2 while
 * den / (t1 + t2) = (T - 2 n1 - n2) dt falls: the best n2 is on either side of t1 + t2 = A / Jc. n1 is scanned
 * within WIDEST_N1_SPAN of the given one. Only a choice: window_nc checks the limits exactly.
 */
static void widest_of_total(const lsm_scurve_limits *sl, lsm_real dt, lsm_scurve_intervals *iv)
{
    if (iv->n1_cycles == 0)
        return;
    const uint32_t t = lsm_scurve_total_cycles(iv);
    lsm_real best = lsm_scurve_dv_capacity(sl, dt, iv);
    const uint32_t n1_lo = iv->n1_cycles > WIDEST_N1_SPAN ? iv->n1_cycles - WIDEST_N1_SPAN : 1;
    const uint32_t n1_hi = iv->n1_cycles + WIDEST_N1_SPAN;
    for (uint32_t n1 = n1_lo; n1 <= n1_hi && 4u * n1 <= t; n1++)
        widest_of_n1(sl, dt, t, n1, iv, &best);
}

/* *w: sh with each ramp's widest intervals of the same totals (widest_of_total); false if that is sh itself. */
static bool widest_shape(const lsm_axis_limits *L, lsm_real dt, const shape *sh, shape *w)
{
    const lsm_scurve_limits sl = ramp_limits(L);
    *w = *sh;
    widest_of_total(&sl, dt, &w->acc);
    widest_of_total(&sl, dt, &w->dec);
    return !(iv_equal(&w->acc, &sh->acc) && iv_equal(&w->dec, &sh->dec));
}

/* window_nc, and if it finds no cruise length, again with each ramp's widest intervals of the same totals. */
static bool window_nc_wide(const lsm_axis_limits *L, lsm_real dt, lsm_real D, lsm_real v0, lsm_real v1, shape *sh)
{
    if (window_nc(L, dt, D, v0, v1, sh))
        return true;
    shape w;
    if (!widest_shape(L, dt, sh, &w) || !window_nc(L, dt, D, v0, v1, &w))
        return false;
    *sh = w;
    return true;
}

/* The fallback's cruise-feed candidates (see single_plan). */
#define ALT_ABOVE 4 /* peaks between vp* and v_max */
#define ALT_GRID 32 /* an even grid of feeds from max(v0, v1) down to 0 */
#define ALT_NEAR 24 /* per end feed, feeds 2^-1 .. 2^-24 of the way from it to the other end feed or to 0 */
#define ALT_PEAKS (ALT_ABOVE + ALT_GRID + 4 * ALT_NEAR)

/* Candidate k of the fallback: a cruise feed in [0, v_max]. */
static lsm_real alt_peak(int k, lsm_real vp, lsm_real v0, lsm_real v1, lsm_real vmax)
{
    static const lsm_real up[ALT_ABOVE] = {LSM_R(0.03125), LSM_R(0.125), LSM_R(0.5), LSM_R(1.0)};
    if (k < ALT_ABOVE)
        return vp + (vmax - vp) * up[k];
    k -= ALT_ABOVE;
    const lsm_real vtop = lsm_max2(v0, v1);
    if (k < ALT_GRID)
        return vtop * (lsm_real)(ALT_GRID - 1 - k) / ALT_GRID;
    k -= ALT_GRID;
    /* close to an end feed e, towards the other end feed o or towards 0: a cruise that lingers near the start or
     * end feed (the quantised ramp between them then absorbs the distance the direct ramp leaves over) */
    const int which = k / ALT_NEAR, step = k % ALT_NEAR + 1;
    const lsm_real e = (which & 1) ? v1 : v0;
    const lsm_real o = (which & 2) ? 0 : ((which & 1) ? v0 : v1);
    lsm_real f = 1;
    for (int i = 0; i < step; i++)
        f /= 2; /* exact powers of two */
    return e + (o - e) * f;
}

/*
 * The complete stage (single_plan's last): a search over the two ramps' totals Ta, Td (cycles) directly, rather
 * than over sampled cruise feeds. A total's intervals are its widest: the largest velocity capacity C(T) over every
 * n1 (and the best n2 for it, widest_of_n1) of that total; C is non-decreasing in T (n4 + 1 only adds to eq 34's
 * denominator). With Ta, Td fixed, the cruise feed of nc cycles is vc = (2 D / dt - v0 Ta - v1 Td) / (Ta + Td + 2 nc)
 * (eq (1) of move.h, in cycles), falling with nc, and the ramps (J_P corrected by eq 34) hold it exactly when vc lies
 * in [v0 - C(Ta), v0 + C(Ta)] n [v1 - C(Td), v1 + C(Td)] n (0, v_max]: the pair's shortest cruise is a closed form.
 * The domain: Ta up to the smallest total whose capacity reaches max(v0, v_max - v0) (any velocity change from v0 to a
 * feed in [0, v_max]), Td likewise from v1, both capped at SEARCH_TOTALS and by the distance (total_cap); every cruise
 * length. Stages:
 *   0. ends_may_meet: O(1), no pair can bridge v0 and v1 (a bound of C from A and J alone): refuse;
 *   1. fill_totals: the table of C(T) over the domain;
 *   2. may_reach: the least distance any plan of the domain travels; D below it: refuse;
 *   3. the pairs in order of Ta; each Td from the least whose band meets ramp A's (td_meet) to the largest whose vc
 *      without cruise still reaches v0 - C(Ta) (td_reach), and only while Ta + Td is below the shortest plan found.
 *      A pair that improves is verified exactly (window_nc on its widest intervals) before it is kept.
 * Worst case: the table, SEARCH_TOTALS + 1 totals of about 2 WIDEST_N1_SPAN + 1 n1 each (2 capacities per n1); the
 * certificate, 4 binary searches of the table per total; SEARCH_TOTALS² pair tries of a few operations; and
 * SEARCH_VERIFY_MAX verifications of 2 x SEARCH_TOTALS / 4 n1 each. Stack: the table, SEARCH_TOTALS + 1 reals.
 * Integer cycle counts throughout; the reals are products and quotients of feeds and counts (no trigonometry).
 */
#define SEARCH_TOTALS 256u    /* largest ramp total (cycles) searched: 65 536 pairs at worst; the table is 257 reals */
#define SEARCH_VERIFY_MAX 64u /* exact verifications (each sizes two ramps' widest intervals); a few suffice */
#define SEARCH_FIRST 4u       /* a ramp that changes the feed has n1 >= 1: at least 4 cycles */
/* Relative slack of the reach bound (its rounding): the velocity changes it looks up are shrunk by it, so that the
 * totals it takes are never above the true ones (a lower bound stays one). */
#define REACH_SLACK (64 * LSM_REAL_EPS)

typedef struct total_table {
    lsm_real cap[SEARCH_TOTALS + 1]; /* C(T) (mm/s), for T <= filled */
    uint32_t filled;                 /* the last total in the table */
    uint32_t ta_max, td_max;         /* the domain: Ta <= ta_max, Td <= td_max */
} total_table;

/* The widest intervals of total t into *iv; returns their capacity (0 below SEARCH_FIRST cycles). For the best n2 the
 * capacity rises with n1 while the snap's jerk cap 2 t1 DJ / pi binds and falls once J or A caps it, and the best n1
 * grows with t: the scan starts WIDEST_N1_SPAN below n1_from (the previous total's) and climbs while the top of its
 * window improves. (Against a scan of every n1: the same capacity within 2 ulp on 5.1e6 random totals; the plan is
 * verified on widest_all's intervals, whose capacity is never below this one.) */
static lsm_real widest_intervals(const lsm_scurve_limits *sl, lsm_real dt, uint32_t t, uint32_t n1_from,
                                 lsm_scurve_intervals *iv)
{
    lsm_real best = 0;
    iv->n1_cycles = iv->n2_cycles = 0;
    iv->n4_cycles = t;
    uint32_t top = n1_from + WIDEST_N1_SPAN;
    for (uint32_t n1 = n1_from > WIDEST_N1_SPAN ? n1_from - WIDEST_N1_SPAN : 1; n1 <= top && 4u * n1 <= t; n1++) {
        widest_of_n1(sl, dt, t, n1, iv, &best);
        if (iv->n1_cycles == n1 && n1 + WIDEST_N1_SPAN > top)
            top = n1 + WIDEST_N1_SPAN; /* still climbing */
    }
    return best;
}

/* The widest intervals of total t over every n1 (at least the table's capacity: the plan found is verified on these). */
static void widest_all(const lsm_scurve_limits *sl, lsm_real dt, uint32_t t, lsm_scurve_intervals *iv)
{
    lsm_real best = 0;
    iv->n1_cycles = iv->n2_cycles = 0;
    iv->n4_cycles = t;
    for (uint32_t n1 = 1; 4u * n1 <= t; n1++)
        widest_of_n1(sl, dt, t, n1, iv, &best);
}

/* The move's ends in the search's units: 2 D / dt (mm/s times cycles), the end feeds and v_max. */
typedef struct move_ends {
    lsm_real d2_dt, v0, v1, vmax;
} move_ends;

/* The longest ramp from (or to) feed v that the distance allows: it alone travels more than v T (times dt / 2). */
static uint32_t total_cap(const move_ends *e, lsm_real v)
{
    const lsm_real t = v > 0 ? e->d2_dt / v : (lsm_real)SEARCH_TOTALS;
    return t < (lsm_real)SEARCH_TOTALS ? (uint32_t)t : SEARCH_TOTALS;
}

/* An upper bound of C(T) from the limits alone: over T dt the acceleration stays within A and within J times the time
 * to the nearer end, so no ramp of T cycles changes the feed by more than min(A T dt, J (T dt)² / 4). */
static lsm_real cap_bound(const lsm_scurve_limits *sl, lsm_real dt, uint32_t t)
{
    const lsm_real tp = (lsm_real)t * dt;
    return lsm_min2(sl->a_max_mm_s2 * tp, sl->j_max_mm_s3 * tp * tp / 4);
}

/* Stage 0: false if no pair of the domain can bridge v0 and v1 (their bands never meet): O(1), before the table. */
static bool ends_may_meet(const lsm_scurve_limits *sl, lsm_real dt, const move_ends *e)
{
    const lsm_real reach = cap_bound(sl, dt, total_cap(e, e->v0)) + cap_bound(sl, dt, total_cap(e, e->v1));
    return lsm_fabs(e->v1 - e->v0) <= reach * (1 + REACH_SLACK);
}

/* Stage 1: C(T) up to the domain's totals: those that make any velocity change from v0 (from v1), capped by the
 * distance (total_cap) and by SEARCH_TOTALS. */
static void fill_totals(const lsm_scurve_limits *sl, lsm_real dt, const move_ends *e, total_table *tb)
{
    const lsm_real need_a = lsm_max2(e->v0, e->vmax - e->v0), need_d = lsm_max2(e->v1, e->vmax - e->v1);
    tb->ta_max = total_cap(e, e->v0);
    tb->td_max = total_cap(e, e->v1);
    bool found_a = false, found_d = false;
    uint32_t n1 = 1, t = 0;
    for (;; t++) {
        lsm_scurve_intervals iv;
        tb->cap[t] = widest_intervals(sl, dt, t, n1, &iv);
        n1 = iv.n1_cycles > 0 ? iv.n1_cycles : 1;
        if (!found_a && (tb->cap[t] >= need_a || t == tb->ta_max)) {
            found_a = true;
            tb->ta_max = t;
        }
        if (!found_d && (tb->cap[t] >= need_d || t == tb->td_max)) {
            found_d = true;
            tb->td_max = t;
        }
        if (found_a && found_d)
            break;
    }
    tb->filled = t;
}

/* Stage 3's pair test: the shortest cruise (cycles, into *nc) with which the pair (ta, td) lands on D and both ramps
 * hold vc by the table's capacities; false if none. */
static bool pair_cruise(const total_table *tb, const move_ends *e, uint32_t ta, uint32_t td, lsm_real *nc)
{
    const lsm_real ca = tb->cap[ta], cd = tb->cap[td];
    const lsm_real lo = lsm_max2(e->v0 - ca, e->v1 - cd);
    const lsm_real hi = lsm_min2(lsm_min2(e->v0 + ca, e->v1 + cd), e->vmax);
    const lsm_real num = e->d2_dt - e->v0 * (lsm_real)ta - e->v1 * (lsm_real)td, m = (lsm_real)(ta + td);
    if (!(hi > 0) || hi < lo || !(num > 0))
        return false;
    const lsm_real z = lsm_max2(lsm_ceil((num / hi - m) / 2), 0);
    if (lo > 0 && z > (num / lo - m) / 2)
        return false; /* the window of cruise lengths holds no whole cycle */
    *nc = z;
    return true;
}

/* The largest Td for which vc with no cruise still reaches lo_a = v0 - C(Ta) (no cruise can raise it), capped. */
static uint32_t td_reach(const total_table *tb, const move_ends *e, uint32_t ta)
{
    const lsm_real lo_a = lsm_max2(e->v0 - tb->cap[ta], 0), den = e->v1 + lo_a;
    if (!(den > 0))
        return tb->td_max;
    const lsm_real y = (e->d2_dt - (e->v0 + lo_a) * (lsm_real)ta) / den;
    if (!(y >= (lsm_real)SEARCH_FIRST))
        return 0;
    return y < (lsm_real)tb->td_max ? (uint32_t)y : tb->td_max;
}

/* The smallest total whose capacity reaches dv (exceeds it, if `strict`); filled + 1 if none in the table. */
static uint32_t table_total(const total_table *tb, lsm_real dv, bool strict)
{
    uint32_t lo = 0, hi = tb->filled + 1; /* the answer is in [lo, hi] */
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (strict ? tb->cap[mid] > dv : tb->cap[mid] >= dv)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* The least total a ramp between feed v and a cruise feed just above b needs (a lower bound of it). */
static uint32_t total_above(const total_table *tb, lsm_real v, lsm_real b)
{
    const lsm_real keep = 1 - REACH_SLACK;
    return b < v ? table_total(tb, (v - b) * keep, false) : table_total(tb, (b - v) * keep, true);
}

/* The distance (2 D / dt units) of ramps of x and y cycles with cruise feed b and no cruise. */
static lsm_real reach(const move_ends *e, lsm_real b, uint32_t x, uint32_t y)
{
    return (e->v0 + b) * (lsm_real)x + (b + e->v1) * (lsm_real)y;
}

/*
 * Stage 2: a certificate of infeasibility. A plan with cruise feed vc has ramps of at least X(vc), Y(vc) cycles (the
 * smallest totals whose capacities reach |vc - v0|, |vc - v1|), so it travels at least
 * g(vc) = (v0 + vc) X(vc) + (vc + v1) Y(vc) (times dt / 2). X and Y are steps in vc; between their steps g rises
 * linearly, so its least value over (0, v_max] is at 0 or just above a step of X (v0 - C(T), v0 + C(T - 1): X = T
 * there) or of Y (the same about v1). Only the segments of vc whose X and Y are within the search's domain count.
 * False if 2 D / dt is below all of them: then the domain holds no plan. At most 4 steps per filled total, each with
 * one binary search of the table.
 */
static bool may_reach(const total_table *tb, const move_ends *e)
{
    const lsm_real need = e->d2_dt * (1 + REACH_SLACK);
    const uint32_t x0 = total_above(tb, e->v0, 0), y0 = total_above(tb, e->v1, 0);
    if (x0 <= tb->ta_max && y0 <= tb->td_max && reach(e, 0, x0, y0) <= need)
        return true;
    for (uint32_t t = 1; t <= tb->filled; t++) {
        if (!(tb->cap[t] > tb->cap[t - 1]))
            continue; /* no step at t */
        const lsm_real steps[4] = {e->v0 - tb->cap[t], e->v0 + tb->cap[t - 1], e->v1 - tb->cap[t],
                                   e->v1 + tb->cap[t - 1]};
        for (int k = 0; k < 4; k++) {
            const lsm_real b = steps[k];
            if (!(b >= 0 && b <= e->vmax))
                continue;
            const bool of_a = k < 2; /* a step of X (else of Y) */
            if ((of_a ? e->v0 + b : b + e->v1) * (lsm_real)t > need)
                continue; /* that ramp alone goes too far */
            const uint32_t x = of_a ? t : total_above(tb, e->v0, b), y = of_a ? total_above(tb, e->v1, b) : t;
            if (x <= tb->ta_max && y <= tb->td_max && reach(e, b, x, y) <= need)
                return true;
        }
    }
    return false;
}

/* The least Td whose capacity can meet ramp A's band [v0 - C(Ta), v0 + C(Ta)] from v1 (a lower bound of it). */
static uint32_t td_meet(const total_table *tb, const move_ends *e, uint32_t ta)
{
    const lsm_real gap = lsm_max2(e->v1 - (e->v0 + tb->cap[ta]), (e->v0 - tb->cap[ta]) - e->v1);
    const uint32_t t = gap > 0 ? table_total(tb, gap * (1 - REACH_SLACK), false) : 0;
    return t > SEARCH_FIRST ? t : SEARCH_FIRST;
}

/* The complete stage: the shortest exact plan of the domain into *best; false if the domain holds none. */
static bool search_totals(const lsm_axis_limits *L, lsm_real dt, lsm_real D, lsm_real v0, lsm_real v1, shape *best)
{
    const lsm_scurve_limits sl = ramp_limits(L);
    const move_ends e = {2 * D / dt, v0, v1, L->v_max_mm_s};
    if (!ends_may_meet(&sl, dt, &e))
        return false;
    total_table tb;
    fill_totals(&sl, dt, &e, &tb);
    if (!may_reach(&tb, &e))
        return false;
    uint32_t best_n = UINT32_MAX, verified = 0;
    for (uint32_t ta = SEARCH_FIRST; ta <= tb.ta_max && ta + SEARCH_FIRST < best_n; ta++) {
        const uint32_t td_hi = td_reach(&tb, &e, ta);
        for (uint32_t td = td_meet(&tb, &e, ta); td <= td_hi && ta + td < best_n; td++) {
            lsm_real nc;
            if (!pair_cruise(&tb, &e, ta, td, &nc) || !((lsm_real)(ta + td) + nc < (lsm_real)best_n))
                continue;
            if (verified++ >= SEARCH_VERIFY_MAX)
                return best_n < UINT32_MAX;
            shape sh;
            widest_all(&sl, dt, ta, &sh.acc);
            widest_all(&sl, dt, td, &sh.dec);
            if (window_nc(L, dt, D, v0, v1, &sh) && ta + td + sh.nc < best_n) {
                best_n = ta + td + sh.nc;
                *best = sh;
            }
        }
    }
    return best_n < UINT32_MAX;
}

/*
 * One axis alone, strict rule: the fastest whole-cycle shape that lands exactly on D. Tries the minimal-time
 * peak vp* first (the usual answer). Otherwise (short moves between feeds whose remainder a quantised ramp
 * cannot absorb) it tries other cruise feeds: peaks above vp* (ramps with more velocity capacity), an even grid
 * below max(v0, v1), and feeds geometrically close to each end feed (a cruise lingering just above or below v0
 * or v1, the only exact shapes when D exceeds the direct ramp's distance by less than a short ramp travels at
 * the far feed), each also with its ramps stretched at T4 (more capacity for a little more time); keeps the
 * shortest that fits. Where all of these fail, and where D is below the direct ramp's distance, the complete search
 * over the ramp totals (search_totals) decides: it plans whenever its domain holds an exact plan.
 */
static lsm_status single_plan(const lsm_axis_limits *L, lsm_real dt, lsm_real D, lsm_real v0, lsm_real v1, shape *best)
{
    lsm_status st = strict_peak_shape(L, dt, D, v0, v1, best);
    if (st == LSM_E_INFEASIBLE) /* D below the direct ramp's: a descent through a lower feed may still land */
        return search_totals(L, dt, D, v0, v1, best) ? LSM_OK : LSM_E_INFEASIBLE;
    if (st != LSM_OK)
        return st;
    if (window_nc_wide(L, dt, D, v0, v1, best))
        return LSM_OK;
    /* the fallback starts from single_shape's peak (and its shape, which may also fit) */
    lsm_real vp;
    st = single_shape(L, dt, D, v0, v1, LSM_SCURVE_RULE_STRICT, best, &vp);
    if (st != LSM_OK)
        return st;
    if (window_nc_wide(L, dt, D, v0, v1, best))
        return LSM_OK;
    uint64_t best_total = UINT64_MAX;
    /* a ramp lengthened at T4 gains velocity capacity linearly, at a small cost in time */
    static const uint32_t stretch[4] = {0, 2, 8, 32};
    for (int k = 0; k < ALT_PEAKS; k++) {
        const lsm_real p = alt_peak(k, vp, v0, v1, L->v_max_mm_s);
        shape base;
        if (!ramp(L, dt, p - v0, LSM_SCURVE_RULE_STRICT, &base.acc) ||
            !ramp(L, dt, p - v1, LSM_SCURVE_RULE_STRICT, &base.dec))
            return LSM_E_TOO_LONG;
        /* the same totals' widest intervals (sized once per candidate), tried where the sizing's own fail */
        shape wide;
        const bool wider = widest_shape(L, dt, &base, &wide);
        for (int sa = 0; sa < 4; sa++) {
            for (int sd = 0; sd < 4; sd++) {
                if ((stretch[sa] && !base.acc.n1_cycles) || (stretch[sd] && !base.dec.n1_cycles))
                    continue;
                shape sh = base;
                sh.acc.n4_cycles += stretch[sa];
                sh.dec.n4_cycles += stretch[sd];
                if (!window_nc(L, dt, D, v0, v1, &sh)) {
                    if (!wider)
                        continue;
                    sh = wide;
                    sh.acc.n4_cycles += stretch[sa];
                    sh.dec.n4_cycles += stretch[sd];
                    if (!window_nc(L, dt, D, v0, v1, &sh))
                        continue;
                }
                const uint64_t total =
                    (uint64_t)lsm_scurve_total_cycles(&sh.acc) + lsm_scurve_total_cycles(&sh.dec) + sh.nc;
                if (total < best_total) {
                    best_total = total;
                    *best = sh;
                }
            }
        }
    }
    if (best_total < UINT64_MAX)
        return LSM_OK;
    return search_totals(L, dt, D, v0, v1, best) ? LSM_OK : LSM_E_INFEASIBLE;
}

static bool axis_still(const lsm_move_request *req, unsigned i)
{
    return req->distance_mm[i] == 0;
}

/*
 * Solves every axis's cruise feed for the shared shape (eq (1) of move.h) and widens the shape until every
 * axis fits its limits. When a ramp must widen, the cruise is shortened so that the reference axis (the
 * slowest) keeps its current cruise feed: the move does not get slower than it must. Fills mv on success.
 * With `alone`, only the reference axis counts (the others are taken as still), as for one axis planned alone.
 */
static lsm_status fit(const lsm_move_request *req, unsigned ref, bool alone, shape *sh, lsm_move *mv)
{
    const lsm_real dt = req->cycle_s;
    for (int iter = 0; iter < FIT_MAX_ITER; iter++) {
        const lsm_real ta = (lsm_real)lsm_scurve_total_cycles(&sh->acc) * dt;
        const lsm_real td = (lsm_real)lsm_scurve_total_cycles(&sh->dec) * dt;
        const lsm_real tc = (lsm_real)sh->nc * dt;
        const uint64_t total = (uint64_t)lsm_scurve_total_cycles(&sh->acc) + lsm_scurve_total_cycles(&sh->dec) + sh->nc;
        if (total >= LSM_MOVE_MAX_CYCLES)
            return LSM_E_TOO_LONG;
        const lsm_real denom = ta / 2 + tc + td / 2;
        if (!(denom > 0)) {
            sh->nc = 1; /* a move needs at least one cycle */
            continue;
        }
        const lsm_real vc_ref =
            (lsm_fabs(req->distance_mm[ref]) - req->v0_mm_s[ref] * ta / 2 - req->v1_mm_s[ref] * td / 2) / denom;
        bool ok = true, widened = false;
        for (unsigned i = 0; i < req->n_axes && ok; i++) {
            if (axis_still(req, i) || (alone && i != ref))
                continue;
            const lsm_axis_limits *L = &req->lim[i];
            const lsm_real v0 = req->v0_mm_s[i], v1 = req->v1_mm_s[i];
            const lsm_real num = lsm_fabs(req->distance_mm[i]) - v0 * ta / 2 - v1 * td / 2;
            const lsm_real vc = num / denom;
            if (!(vc > 0))
                return LSM_E_INFEASIBLE; /* the ramps alone reach or overrun the distance */
            if (vc > L->v_max_mm_s) {
                const lsm_real need = lsm_ceil((num / L->v_max_mm_s - ta / 2 - td / 2) / dt);
                if (!(need < (lsm_real)LSM_MOVE_MAX_CYCLES))
                    return LSM_E_TOO_LONG;
                sh->nc = (uint32_t)need > sh->nc ? (uint32_t)need : sh->nc + 1;
                ok = false;
                break;
            }
            lsm_scurve_intervals iv;
            if (!ramp_fits(L, dt, &sh->acc, vc - v0, req->rule)) {
                if (!ramp(L, dt, vc - v0, req->rule, &iv))
                    return LSM_E_TOO_LONG;
                sh->acc = iv_max(&sh->acc, &iv);
                ok = false;
                widened = true;
            }
            if (!ramp_fits(L, dt, &sh->dec, vc - v1, req->rule)) {
                if (!ramp(L, dt, vc - v1, req->rule, &iv))
                    return LSM_E_TOO_LONG;
                sh->dec = iv_max(&sh->dec, &iv);
                ok = false;
                widened = true;
            }
        }
        if (widened) {
            /* shorten the cruise so that the reference axis keeps vc_ref (never below 0 cycles) */
            const lsm_real ta2 = (lsm_real)lsm_scurve_total_cycles(&sh->acc) * dt;
            const lsm_real td2 = (lsm_real)lsm_scurve_total_cycles(&sh->dec) * dt;
            const lsm_real num_ref =
                lsm_fabs(req->distance_mm[ref]) - req->v0_mm_s[ref] * ta2 / 2 - req->v1_mm_s[ref] * td2 / 2;
            const lsm_real tc2 = vc_ref > 0 ? num_ref / vc_ref - ta2 / 2 - td2 / 2 : 0;
            const lsm_real nc2 = tc2 > 0 ? lsm_ceil(tc2 / dt) : 0;
            if (!(nc2 < (lsm_real)LSM_MOVE_MAX_CYCLES))
                return LSM_E_TOO_LONG;
            sh->nc = (uint32_t)nc2;
        }
        if (!ok)
            continue;
        mv->acc = sh->acc;
        mv->dec = sh->dec;
        mv->cruise_cycles = sh->nc;
        const lsm_real den_a = lsm_scurve_jerk_den(&sh->acc, dt);
        const lsm_real den_d = lsm_scurve_jerk_den(&sh->dec, dt);
        for (unsigned i = 0; i < req->n_axes; i++) {
            lsm_move_axis *ax = &mv->axis[i];
            const lsm_real v0 = req->v0_mm_s[i], v1 = req->v1_mm_s[i];
            ax->distance_mm = req->distance_mm[i];
            ax->dir = req->distance_mm[i] < 0 ? -1 : 1;
            ax->v0_mm_s = v0;
            ax->v1_mm_s = v1;
            if (axis_still(req, i) || (alone && i != ref)) {
                ax->vc_mm_s = ax->jp_acc_mm_s3 = ax->jp_dec_mm_s3 = 0;
                continue;
            }
            const lsm_real vc = (lsm_fabs(req->distance_mm[i]) - v0 * ta / 2 - v1 * td / 2) / denom;
            ax->vc_mm_s = vc;
            ax->jp_acc_mm_s3 = den_a > 0 ? (vc - v0) / den_a : 0;
            ax->jp_dec_mm_s3 = den_d > 0 ? (v1 - vc) / den_d : 0;
        }
        return LSM_OK;
    }
    return LSM_E_INFEASIBLE;
}

static lsm_status validate(const lsm_move_request *req)
{
    if (req->n_axes < 1 || req->n_axes > LSM_MAX_AXES)
        return LSM_E_ARG;
    if (req->rule != LSM_SCURVE_RULE_STRICT && req->rule != LSM_SCURVE_RULE_PAPER)
        return LSM_E_ARG;
    bool moving = false;
    for (unsigned i = 0; i < req->n_axes; i++) {
        const lsm_axis_limits *L = &req->lim[i];
        const lsm_real vals[6] = {req->distance_mm[i], req->v0_mm_s[i], req->v1_mm_s[i],
                                  L->v_max_mm_s,       L->a_max_mm_s2,  L->j_max_mm_s3};
        for (int k = 0; k < 6; k++) {
            lsm_status st = (lsm_status)lsm_check_finite(vals[k]);
            if (st != LSM_OK)
                return st;
        }
        const lsm_scurve_limits sl = ramp_limits(L);
        lsm_status st = lsm_scurve_check_limits(&sl, req->cycle_s);
        if (st != LSM_OK)
            return st;
        if (!(L->v_max_mm_s > 0))
            return LSM_E_LIMIT;
        if (req->v0_mm_s[i] < 0 || req->v1_mm_s[i] < 0)
            return LSM_E_NEG_FEED;
        if (req->v0_mm_s[i] > L->v_max_mm_s || req->v1_mm_s[i] > L->v_max_mm_s)
            return LSM_E_FEED_ABOVE_VMAX;
        const lsm_real D = lsm_fabs(req->distance_mm[i]);
        if (D > (lsm_real)LSM_MAX_DISTANCE_MM)
            return LSM_E_RANGE;
        if (D / (L->v_max_mm_s * req->cycle_s) >= (lsm_real)LSM_MOVE_MAX_CYCLES)
            return LSM_E_TOO_LONG;
        if (D > 0)
            moving = true;
        else if (req->v0_mm_s[i] > 0 || req->v1_mm_s[i] > 0)
            return LSM_E_INFEASIBLE; /* a still axis cannot start or end with a feed */
    }
    return moving ? LSM_OK : LSM_E_ZERO_LENGTH;
}

lsm_status lsm_move_plan(lsm_move *mv, const lsm_move_request *req)
{
    if (mv == NULL || req == NULL)
        return LSM_E_NULL;
    lsm_status st = validate(req);
    if (st != LSM_OK)
        return st;
    const lsm_real dt = req->cycle_s;
    mv->cycle_s = dt;
    mv->n_axes = req->n_axes;

    /* 1. each axis alone: its minimal-time shape, made exact */
    uint32_t slowest_cycles = 0;
    unsigned moving = 0;
    shape shared = {{0, 0, 0}, {0, 0, 0}, 0};
    mv->slowest_axis = 0;
    for (unsigned i = 0; i < req->n_axes; i++) {
        if (axis_still(req, i))
            continue;
        shape sh;
        const lsm_real D = lsm_fabs(req->distance_mm[i]);
        if (req->rule == LSM_SCURVE_RULE_STRICT) {
            st = single_plan(&req->lim[i], dt, D, req->v0_mm_s[i], req->v1_mm_s[i], &sh);
        } else {
            lsm_real vp;
            st = single_shape(&req->lim[i], dt, D, req->v0_mm_s[i], req->v1_mm_s[i], req->rule, &sh, &vp);
        }
        if (st != LSM_OK)
            return st;
        st = fit(req, i, true, &sh, mv);
        if (st != LSM_OK)
            return st;
        moving++;
        const uint32_t n = lsm_move_total_cycles(mv);
        if (n > slowest_cycles) {
            slowest_cycles = n;
            shared = sh;
            mv->slowest_axis = (uint8_t)i;
        }
    }
    /* 2. all axes on the slowest axis's intervals, each with its own vc and corrected J_P; with one moving axis,
     * its fit alone already is that (the still axes are filled the same) */
    if (moving == 1)
        return LSM_OK;
    return fit(req, mv->slowest_axis, false, &shared, mv);
}

uint32_t lsm_move_total_cycles(const lsm_move *mv)
{
    return lsm_scurve_total_cycles(&mv->acc) + mv->cruise_cycles + lsm_scurve_total_cycles(&mv->dec);
}

lsm_real lsm_move_duration_s(const lsm_move *mv)
{
    return (lsm_real)lsm_move_total_cycles(mv) * mv->cycle_s;
}

void lsm_move_phases(const lsm_move *mv, unsigned axis, lsm_phase out[LSM_MOVE_PHASES])
{
    const lsm_move_axis *ax = &mv->axis[axis];
    lsm_scurve_phases(&mv->acc, ax->jp_acc_mm_s3, out);
    out[7].n_cycles = mv->cruise_cycles;
    out[7].shape = LSM_PHASE_CONST;
    out[7].jerk_mm_s3 = 0;
    lsm_scurve_phases(&mv->dec, ax->jp_dec_mm_s3, out + 8);
}

/* The start states of phases 0..upto (upto <= 7) of the first ramp, forward from the start. out[7] (if asked) is the
 * first ramp's end state as computed: its velocity is the ramp's own end velocity. */
static void ramp1_starts(const lsm_move *mv, const lsm_phase ph[LSM_MOVE_PHASES], unsigned axis, unsigned upto,
                         lsm_kin out[LSM_MOVE_PHASES])
{
    lsm_kin k = {0, mv->axis[axis].v0_mm_s, 0, 0};
    for (unsigned p = 0; p <= upto; p++) {
        out[p] = k;
        if (p < upto)
            lsm_phase_end(&ph[p], mv->cycle_s, &k, &k);
    }
}

/* The start states of phases 14 down to from (from >= 8) of the second ramp, backward from the exact end state.
 * Reversed in time, the ramp vc -> v1 is the standard ramp v1 -> vc with jerk amplitude -jp_dec; the distance left
 * at a phase start is the reversed ramp's travel. */
static void ramp2_starts(const lsm_move *mv, unsigned axis, unsigned from, lsm_kin out[LSM_MOVE_PHASES])
{
    const lsm_move_axis *ax = &mv->axis[axis];
    lsm_phase rev[7];
    lsm_scurve_phases(&mv->dec, -ax->jp_dec_mm_s3, rev);
    lsm_kin r = {0, ax->v1_mm_s, 0, 0};
    const lsm_real D = lsm_fabs(ax->distance_mm);
    /* reversed phase q is forward phase 14 - q; its end is that one's start */
    for (unsigned q = 0; q + from <= 14; q++) {
        lsm_phase_end(&rev[q], mv->cycle_s, &r, &r);
        lsm_kin *o = &out[14 - q];
        o->s_mm = D - r.s_mm;
        o->v_mm_s = r.v_mm_s;
        o->a_mm_s2 = -r.a_mm_s2;
        o->j_mm_s3 = r.j_mm_s3;
    }
}

/* The cruise's position feed: the one that joins the two ramps' positions exactly over tc, (s8 - s7) / tc. */
static lsm_real cruise_feed(const lsm_move *mv, const lsm_kin out[LSM_MOVE_PHASES])
{
    return (out[8].s_mm - out[7].s_mm) / ((lsm_real)mv->cruise_cycles * mv->cycle_s);
}

void lsm_move_phase_starts(const lsm_move *mv, unsigned axis, lsm_kin out[LSM_MOVE_PHASES])
{
    lsm_phase ph[LSM_MOVE_PHASES];
    lsm_move_phases(mv, axis, ph);
    ramp1_starts(mv, ph, axis, 7, out);
    ramp2_starts(mv, axis, 8, out);
    if (mv->cruise_cycles > 0) { /* the positions join exactly: the cruise's position feed (move.h) */
        out[7].v_mm_s = cruise_feed(mv, out);
        out[7].a_mm_s2 = 0;
        out[7].j_mm_s3 = 0;
    }
}

void lsm_move_phase_start(const lsm_move *mv, unsigned axis, unsigned p, lsm_kin *out)
{
    lsm_kin all[LSM_MOVE_PHASES];
    lsm_move_phase_starts(mv, axis, all);
    *out = all[p];
}

/* The state in phase p (p < LSM_MOVE_PHASES), tau_s into it, travel frame. Only the ramp that holds p is evaluated
 * (both for the cruise). In the cruise the position follows the position feed (s7 -> s8 exactly) and the velocity is
 * the planned cruise feed vc, the velocity both ramps were corrected to reach (eq 34) and <= v_max exactly: the
 * ramps' evaluated ends are within a few ulps of it, whereas the position feed is off it by the two end positions'
 * rounding over tc. That difference thus stays a position rounding of a few ulps, not a step of the velocity where
 * the cruise joins the ramps. */
static void eval_phase(const lsm_move *mv, unsigned axis, const lsm_phase ph[LSM_MOVE_PHASES], unsigned p,
                       lsm_real tau_s, lsm_kin *out)
{
    lsm_kin st[LSM_MOVE_PHASES];
    if (p < 7) {
        ramp1_starts(mv, ph, axis, p, st);
        lsm_phase_advance(&ph[p], mv->cycle_s, &st[p], tau_s, out);
        return;
    }
    if (p > 7) {
        ramp2_starts(mv, axis, p, st);
        lsm_phase_advance(&ph[p], mv->cycle_s, &st[p], tau_s, out);
        return;
    }
    ramp1_starts(mv, ph, axis, 7, st);
    ramp2_starts(mv, axis, 8, st);
    const lsm_kin c = {st[7].s_mm, cruise_feed(mv, st), 0, 0};
    lsm_phase_advance(&ph[7], mv->cycle_s, &c, tau_s, out);
    out->v_mm_s = mv->axis[axis].vc_mm_s;
}

/* Closed form in the travel frame: locate the phase, then advance from its start state; no terminal snapping. */
static void eval_travel(const lsm_move *mv, unsigned axis, uint32_t k, lsm_real frac, lsm_kin *out)
{
    lsm_phase ph[LSM_MOVE_PHASES];
    lsm_move_phases(mv, axis, ph);
    uint32_t m = k;
    unsigned p = 0;
    for (; p < LSM_MOVE_PHASES; p++) {
        if (ph[p].n_cycles == 0)
            continue;
        if (m < ph[p].n_cycles || (m == ph[p].n_cycles && frac == 0))
            break;
        m -= ph[p].n_cycles;
    }
    if (p == LSM_MOVE_PHASES) { /* past the end */
        lsm_kin st[LSM_MOVE_PHASES];
        ramp2_starts(mv, axis, LSM_MOVE_PHASES - 1, st);
        lsm_phase_end(&ph[LSM_MOVE_PHASES - 1], mv->cycle_s, &st[LSM_MOVE_PHASES - 1], out);
        out->s_mm += out->v_mm_s * ((lsm_real)m + frac) * mv->cycle_s;
        out->j_mm_s3 = 0;
        return;
    }
    eval_phase(mv, axis, ph, p, ((lsm_real)m + frac) * mv->cycle_s, out);
}

void lsm_move_eval_cycle(const lsm_move *mv, unsigned axis, uint32_t k, lsm_real frac, lsm_kin *out)
{
    const lsm_move_axis *ax = &mv->axis[axis];
    if (k >= lsm_move_total_cycles(mv)) {
        out->s_mm = ax->distance_mm;
        out->v_mm_s = ax->dir * ax->v1_mm_s;
        out->a_mm_s2 = 0;
        out->j_mm_s3 = 0;
        return;
    }
    eval_travel(mv, axis, k, frac, out);
    out->s_mm *= ax->dir;
    out->v_mm_s *= ax->dir;
    out->a_mm_s2 *= ax->dir;
    out->j_mm_s3 *= ax->dir;
}

void lsm_move_eval(const lsm_move *mv, unsigned axis, lsm_real t_s, lsm_kin *out)
{
    const lsm_real x = t_s > 0 ? t_s / mv->cycle_s : 0;
    const lsm_real n = (lsm_real)lsm_move_total_cycles(mv);
    if (x >= n) {
        lsm_move_eval_cycle(mv, axis, lsm_move_total_cycles(mv), 0, out);
        return;
    }
    const lsm_real kf = lsm_floor(x);
    lsm_move_eval_cycle(mv, axis, (uint32_t)kf, x - kf, out);
}

lsm_real lsm_move_end_error_mm(const lsm_move *mv, unsigned axis)
{
    lsm_kin k;
    eval_travel(mv, axis, lsm_move_total_cycles(mv), 0, &k);
    return mv->axis[axis].dir * k.s_mm - mv->axis[axis].distance_mm;
}
