/* jstop.c: the jerk- and snap-limited stop of jstop.h. */
#include "jstop.h"

#include <string.h>

#include "lsm_math.h"

#define JSTOP_PI ((lsm_real)LSM_PI)

/* Bisection of the intermediate acceleration stops at this relative width: two ulps of the real type. */
#if LSM_REAL_IS_FLOAT
#define JSTOP_BISECT_REL 2.4e-7f
/* A first stage that ends faster than this fraction of the stop's scale overshot v = 0 (braking harder than the
 * limits undo): a second stage follows. Below it the end velocity is rounding (float: about 100 ulps). */
#define JSTOP_OVERSHOOT_REL 1e-5f
#else
#define JSTOP_BISECT_REL 4e-16
#define JSTOP_OVERSHOOT_REL 1e-9
#endif
/* Upper bound of bisection steps: far more than the width ever needs (about 60 in double), a guard only. */
#define JSTOP_BISECT_MAX 2000

lsm_real lsm_jstop_ramp_time(lsm_real da_mm_s2, lsm_real j_mm_s3, lsm_real snap_mm_s4, lsm_real *jp_mm_s3,
                             lsm_real *t1_s, lsm_real *t2_s)
{
    const lsm_real J = j_mm_s3, S = snap_mm_s4;
    lsm_real p = 0, r = 0, c = 0;
    if (da_mm_s2 > 0) {
        const lsm_real knee = JSTOP_PI * J * J / (2 * S);
        if (da_mm_s2 >= knee) {
            p = J;
            r = JSTOP_PI * J / (2 * S);
            c = da_mm_s2 / J - r;
            if (c < 0)
                c = 0;
        } else {
            r = lsm_sqrt(JSTOP_PI * da_mm_s2 / (2 * S));
            p = 2 * S * r / JSTOP_PI;
            c = 0;
        }
    }
    if (jp_mm_s3 != NULL)
        *jp_mm_s3 = p;
    if (t1_s != NULL)
        *t1_s = r;
    if (t2_s != NULL)
        *t2_s = c;
    return 2 * r + c;
}

/* The first ramp of a stop that starts braking with a jerk j0 < 0 (travel frame) and brakes harder than the plain
 * release of j0 does (da <= -pi j0² / (4 S)): the jerk goes on from j0 to the peak jp <= j0 by a sin² transition
 * (duration t0), is held for t2 and released by a cos² fall (t3); jstop.h, "A stop that is braking already". */
typedef struct jramp {
    lsm_real jp, t0, t2, t3;
} jramp;

static void ramp_from(lsm_real j0, lsm_real da, const lsm_jstop_limits *l, jramp *r)
{
    const lsm_real S = l->snap_mm_s4;
    const lsm_real q = 4 * S / JSTOP_PI; /* da of a max-snap sin² segment j_s -> j_e: (j_e² - j_s²) / q */
    const lsm_real jl = lsm_max2(l->jerk_mm_s3, -j0); /* a jerk beyond J that the stop starts with is not raised */
    lsm_real x = (j0 * j0 - q * da) / 2;
    lsm_real jp = -lsm_sqrt(x > 0 ? x : 0), t2 = 0;
    if (jp > j0)
        jp = j0; /* rounding at da = the release's own */
    if (-jp > jl) {
        jp = -jl;
        t2 = (da - (j0 * j0 - 2 * jl * jl) / q) / jp;
    }
    r->jp = jp;
    r->t0 = JSTOP_PI * (j0 - jp) / (2 * S);
    r->t2 = t2 > 0 ? t2 : 0;
    r->t3 = JSTOP_PI * -jp / (2 * S);
}

/* Velocity gained over the ramp of ramp_from from (a0, j0) (closed form of the three phases, eqs 19-21). */
static lsm_real ramp_from_dv(lsm_real a0, lsm_real j0, const jramp *r)
{
    const lsm_real pi2 = JSTOP_PI * JSTOP_PI;
    const lsm_real t0 = r->t0, t2 = r->t2, t3 = r->t3, jp = r->jp;
    lsm_real dv = a0 * t0 + j0 * t0 * t0 / 2 + (jp - j0) * (t0 * t0 / 4 - t0 * t0 / pi2);
    const lsm_real a1 = a0 + (j0 + jp) * t0 / 2;
    dv += a1 * t2 + jp * t2 * t2 / 2;
    const lsm_real a2 = a1 + jp * t2;
    return dv + a2 * t3 + jp * (t3 * t3 / 4 + t3 * t3 / pi2);
}

/* End velocity (travel frame) without a plateau, for the intermediate acceleration a1, from (v, a, j0). */
static lsm_real end_velocity(lsm_real v, lsm_real a, lsm_real j0, lsm_real a1, const lsm_jstop_limits *l)
{
    const lsm_real tc = lsm_jstop_ramp_time(lsm_fabs(a1), l->jerk_mm_s3, l->snap_mm_s4, NULL, NULL, NULL);
    if (j0 != 0) {
        jramp r;
        ramp_from(j0, a1 - a, l, &r);
        return v + ramp_from_dv(a, j0, &r) + a1 * tc / 2;
    }
    const lsm_real ta = lsm_jstop_ramp_time(lsm_fabs(a - a1), l->jerk_mm_s3, l->snap_mm_s4, NULL, NULL, NULL);
    return v + (a + a1) * ta / 2 + a1 * tc / 2;
}

static void add_phase_full(lsm_jstop *s, lsm_phase_shape shape, lsm_real dur, lsm_real full, lsm_real off, lsm_real jb,
                           lsm_real jerk)
{
    if (!(dur > 0))
        return;
    s->shape[s->n_phases] = shape;
    s->dur_s[s->n_phases] = dur;
    s->full_s[s->n_phases] = full;
    s->off_s[s->n_phases] = off;
    s->jb_mm_s3[s->n_phases] = jb;
    s->jerk_mm_s3[s->n_phases] = jerk;
    s->n_phases++;
}

static void add_phase(lsm_jstop *s, lsm_phase_shape shape, lsm_real dur, lsm_real jerk)
{
    add_phase_full(s, shape, dur, dur, 0, 0, jerk);
}

static void add_ramp(lsm_jstop *s, lsm_real from, lsm_real to)
{
    lsm_real jp, t1, t2;
    (void)lsm_jstop_ramp_time(lsm_fabs(to - from), s->lim.jerk_mm_s3, s->lim.snap_mm_s4, &jp, &t1, &t2);
    if (!(t1 > 0))
        return;
    const lsm_real sg = to > from ? 1 : -1;
    add_phase(s, LSM_PHASE_RISE, t1, sg * jp);
    add_phase(s, LSM_PHASE_CONST, t2, sg * jp);
    add_phase(s, LSM_PHASE_FALL, t1, sg * jp);
}

/* The first ramp from (from, j0 != 0) to the acceleration `to`: transition j0 -> jp, plateau, fall (ramp_from). */
static void add_ramp_from(lsm_jstop *s, lsm_real from, lsm_real j0, lsm_real to)
{
    jramp r;
    ramp_from(j0, to - from, &s->lim, &r);
    add_phase_full(s, LSM_PHASE_RISE, r.t0, r.t0, 0, j0, r.jp - j0); /* none when jp = j0: j0 is held */
    add_phase(s, LSM_PHASE_CONST, r.t2, r.jp);
    add_phase(s, LSM_PHASE_FALL, r.t3, r.jp);
}

/* State after tau seconds of phase i, from its start state (travel frame). */
static void advance(const lsm_jstop *s, unsigned i, lsm_real tau, lsm_kin *out)
{
    lsm_real u[4];
    lsm_phase_unit(s->shape[i], s->full_s[i], s->off_s[i] + tau, u);
    if (s->off_s[i] > 0) { /* the rest of a phase entered off_s before: its integrals from there */
        lsm_real w[4];
        lsm_phase_unit(s->shape[i], s->full_s[i], s->off_s[i], w);
        u[3] -= w[3] + w[2] * tau + w[1] * tau * tau / 2;
        u[2] -= w[2] + w[1] * tau;
        u[1] -= w[1];
    }
    const lsm_kin k = s->start[i];
    const lsm_real jk = s->jerk_mm_s3[i], jb = s->jb_mm_s3[i];
    out->j_mm_s3 = jk * u[0] + jb;
    out->a_mm_s2 = k.a_mm_s2 + jk * u[1] + jb * tau;
    out->v_mm_s = k.v_mm_s + k.a_mm_s2 * tau + jk * u[2] + jb * tau * tau / 2;
    out->s_mm = k.s_mm + k.v_mm_s * tau + k.a_mm_s2 * tau * tau / 2 + jk * u[3] + jb * tau * tau * tau / 6;
}

/* The intermediate acceleration a1 (travel frame) and the plateau at it (see jstop.h), from (vt, at) with the jerk
 * jt (0, or < 0 with f(hi) >= 0 checked by the caller), a1 in [-D, hi]. */
static lsm_real intermediate(lsm_real vt, lsm_real at, lsm_real jt, lsm_real hi, const lsm_jstop_limits *lim,
                             lsm_real *tb)
{
    const lsm_real D = lim->decel_mm_s2;
    *tb = 0;
    if (jt == 0 && end_velocity(vt, at, 0, 0, lim) <= 0)
        return 0; /* braking harder than the limits can undo: ramp a to 0, a second stage follows */
    const lsm_real fd = end_velocity(vt, at, jt, -D, lim);
    if (fd >= 0) {
        *tb = fd / D;
        return -D;
    }
    lsm_real lo = -D; /* f(lo) < 0 <= f(hi); f is continuous: the bisection ends on a root */
    for (int it = 0; it < JSTOP_BISECT_MAX && hi - lo > JSTOP_BISECT_REL * (lsm_fabs(lo) + lsm_fabs(hi)); it++) {
        const lsm_real mid = (lo + hi) / 2;
        if (mid <= lo || mid >= hi)
            break; /* no real number left between them */
        if (end_velocity(vt, at, jt, mid, lim) > 0)
            hi = mid;
        else
            lo = mid;
    }
    return (lo + hi) / 2;
}

/* A stop braking already (jerk j1 < 0 after the lead-in): true if it brakes harder than the plain release of j1
 * (jstop.h), i.e. the first ramp goes on from j1; *hi is then the bound of the intermediate acceleration. */
static bool brakes_on(const lsm_kin *k0, lsm_real j1, const lsm_jstop_limits *lim, lsm_real *hi)
{
    const lsm_real a_rel = k0->a_mm_s2 - JSTOP_PI * j1 * j1 / (4 * lim->snap_mm_s4); /* a after the release */
    if (!(j1 < 0) || a_rel < -lim->decel_mm_s2)
        return false;
    *hi = lsm_min2(a_rel, 0);
    return end_velocity(k0->v_mm_s, k0->a_mm_s2, j1, *hi, lim) >= 0;
}

/* The direction of travel of a state: that of v, else of a, else of j. */
static lsm_real direction(lsm_real v, lsm_real a, lsm_real j)
{
    const lsm_real x = v != 0 ? v : a != 0 ? a : j;
    return x > 0 ? 1 : -1;
}

static lsm_status check_lead(const lsm_jstop_lead *lead)
{
    if (lead == NULL)
        return LSM_OK;
    const lsm_real in[3] = {lead->full_s, lead->off_s, lead->jerk_mm_s3};
    for (int i = 0; i < 3; i++) {
        int st = lsm_check_finite(in[i]);
        if (st != 0)
            return (lsm_status)st;
    }
    if (lead->shape > (uint8_t)LSM_PHASE_FALL || !(lead->full_s > 0) || !(lead->off_s >= 0) ||
        !(lead->off_s < lead->full_s))
        return LSM_E_ARG;
    return LSM_OK;
}

/* The lead-in (jstop.h): the rest of the present jerk phase, or the release of a jerk that raises the acceleration.
 * Returns the jerk the first ramp starts with (travel frame). */
static lsm_real lead_in(lsm_jstop *s, const lsm_jstop_lead *lead, lsm_kin *k0)
{
    const lsm_real jt = k0->j_mm_s3;
    if (jt == 0)
        return 0;
    if (lead != NULL) {
        const lsm_real amp = s->dir * lead->jerk_mm_s3;
        const bool fall = lead->shape == (uint8_t)LSM_PHASE_FALL && amp * jt > 0;
        const bool rise = jt < 0 && lead->shape == (uint8_t)LSM_PHASE_RISE && amp < 0 && -amp <= s->lim.jerk_mm_s3;
        if (fall || rise) {
            add_phase_full(s, (lsm_phase_shape)lead->shape, lead->full_s - lead->off_s, lead->full_s, lead->off_s, 0,
                           amp);
            if (s->n_phases > 0u)
                advance(s, 0, s->dur_s[0], k0);
            return fall ? 0 : amp;
        }
    }
    if (jt < 0)
        return jt; /* braking already: the first ramp may go on from this jerk (brakes_on) */
    add_phase(s, LSM_PHASE_FALL, JSTOP_PI * jt / (2 * s->lim.snap_mm_s4), jt); /* release */
    if (s->n_phases > 0u)
        advance(s, 0, s->dur_s[0], k0);
    return 0;
}

/* Validates the request and resets the plan (inactive, at p_mm). */
static lsm_status begin(lsm_jstop *s, lsm_real p_mm, lsm_real v_mm_s, lsm_real a_mm_s2, lsm_real j_mm_s3,
                        const lsm_jstop_lead *lead, const lsm_jstop_limits *lim)
{
    if (s == NULL || lim == NULL)
        return LSM_E_NULL;
    const lsm_real in[7] = {p_mm, v_mm_s, a_mm_s2, j_mm_s3, lim->decel_mm_s2, lim->jerk_mm_s3, lim->snap_mm_s4};
    for (int i = 0; i < 7; i++) {
        int st = lsm_check_finite(in[i]);
        if (st != 0)
            return (lsm_status)st;
    }
    if (!(lim->decel_mm_s2 > 0) || !(lim->jerk_mm_s3 > 0) || !(lim->snap_mm_s4 > 0))
        return LSM_E_LIMIT;
    lsm_status st = check_lead(lead);
    if (st != LSM_OK)
        return st;
    memset(s, 0, sizeof *s);
    s->lim = *lim;
    s->origin_mm = p_mm;
    s->dir = 1;
    return LSM_OK;
}

/* The planning frame (dir) and the start state in it. */
static void set_frame(lsm_jstop *s, lsm_real dir, lsm_real v_mm_s, lsm_real a_mm_s2, lsm_real j_mm_s3)
{
    s->dir = dir;
    s->start[0].s_mm = 0;
    s->start[0].v_mm_s = dir * v_mm_s;
    s->start[0].a_mm_s2 = dir * a_mm_s2;
    s->start[0].j_mm_s3 = dir * j_mm_s3;
}

/* The phase start states and the duration of the plan; it is active. */
static void finish(lsm_jstop *s)
{
    s->t_end_s = 0;
    for (unsigned i = 0; i < s->n_phases; i++) {
        advance(s, i, s->dur_s[i], &s->start[i + 1]);
        s->t_end_s += s->dur_s[i];
    }
    /* the end has a = j = 0 by construction (up to rounding) */
    s->start[s->n_phases].a_mm_s2 = 0;
    s->start[s->n_phases].j_mm_s3 = 0;
    s->active = true;
}

/* Releases a braking jerk j1 < 0 (travel frame) with a cos² fall within S; k0 becomes the state at its end. */
static void release(lsm_jstop *s, lsm_real j1, lsm_kin *k0)
{
    const unsigned i = s->n_phases;
    add_phase(s, LSM_PHASE_FALL, JSTOP_PI * -j1 / (2 * s->lim.snap_mm_s4), j1);
    if (s->n_phases > i) {
        s->start[i] = *k0;
        advance(s, i, s->dur_s[i], k0);
    }
}

/* The shortest ramp of a from k0's (> 0, travel frame, j = 0) to 0; k0 becomes the state at its end. A single ramp
 * from a > 0 down to the stop's deceleration would have a higher peak jerk and so a slower sin² rise (its snap grows
 * as S² t / J_P): the velocity would rise past the velocity the move itself reaches. */
static void ramp_to_zero(lsm_jstop *s, lsm_kin *k0)
{
    const unsigned first = s->n_phases;
    add_ramp(s, k0->a_mm_s2, 0);
    for (unsigned i = first; i < s->n_phases; i++) {
        s->start[i] = *k0;
        advance(s, i, s->dur_s[i], k0);
    }
    k0->a_mm_s2 = 0;
    k0->j_mm_s3 = 0;
}

lsm_status lsm_jstop_plan_lead(lsm_jstop *s, lsm_real p_mm, lsm_real v_mm_s, lsm_real a_mm_s2, lsm_real j_mm_s3,
                               const lsm_jstop_lead *lead, const lsm_jstop_limits *lim)
{
    lsm_status st = begin(s, p_mm, v_mm_s, a_mm_s2, j_mm_s3, lead, lim);
    if (st != LSM_OK)
        return st;
    if (v_mm_s == 0 && a_mm_s2 == 0 && j_mm_s3 == 0)
        return LSM_OK; /* at rest: nothing to do */
    set_frame(s, direction(v_mm_s, a_mm_s2, j_mm_s3), v_mm_s, a_mm_s2, j_mm_s3);
    lsm_kin k0 = s->start[0];
    const lsm_real j1 = lead_in(s, lead, &k0);
    lsm_real tb, a1, hi = 0;
    if (brakes_on(&k0, j1, lim, &hi)) {
        a1 = intermediate(k0.v_mm_s, k0.a_mm_s2, j1, hi, lim, &tb);
        add_ramp_from(s, k0.a_mm_s2, j1, a1);
    } else {
        if (j1 < 0) /* release the braking jerk first: the stop brakes less than it does */
            release(s, j1, &k0);
        if (k0.a_mm_s2 > 0) /* still accelerating: first a to 0 by the shortest ramp (jstop.h) */
            ramp_to_zero(s, &k0);
        a1 = intermediate(k0.v_mm_s, k0.a_mm_s2, 0, 0, lim, &tb);
        add_ramp(s, k0.a_mm_s2, a1);
    }
    add_phase(s, LSM_PHASE_CONST, tb, 0);
    add_ramp(s, a1, 0);
    finish(s);
    return LSM_OK;
}

lsm_status lsm_jstop_plan_settle(lsm_jstop *s, lsm_real p_mm, lsm_real v_mm_s, lsm_real a_mm_s2, lsm_real j_mm_s3,
                                 const lsm_jstop_lead *lead, const lsm_jstop_limits *lim)
{
    lsm_status st = begin(s, p_mm, v_mm_s, a_mm_s2, j_mm_s3, lead, lim);
    if (st != LSM_OK)
        return st;
    s->settle = true;
    s->v_end_mm_s = v_mm_s;
    if (a_mm_s2 == 0 && j_mm_s3 == 0)
        return LSM_OK; /* at a constant velocity already: nothing to do */
    set_frame(s, direction(a_mm_s2, j_mm_s3, 0), v_mm_s, a_mm_s2, j_mm_s3); /* a >= 0 in this frame */
    lsm_kin k0 = s->start[0];
    const lsm_real j1 = lead_in(s, lead, &k0);
    if (j1 < 0 && k0.a_mm_s2 - JSTOP_PI * j1 * j1 / (4 * lim->snap_mm_s4) >= 0) {
        add_ramp_from(s, k0.a_mm_s2, j1, 0); /* a falls to 0 from the braking jerk j1 on */
    } else {
        if (j1 < 0)
            release(s, j1, &k0);
        add_ramp(s, k0.a_mm_s2, 0);
    }
    finish(s);
    s->v_end_mm_s = s->dir * s->start[s->n_phases].v_mm_s;
    return LSM_OK;
}

lsm_status lsm_jstop_plan(lsm_jstop *s, lsm_real p_mm, lsm_real v_mm_s, lsm_real a_mm_s2, lsm_real j_mm_s3,
                          const lsm_jstop_limits *lim)
{
    return lsm_jstop_plan_lead(s, p_mm, v_mm_s, a_mm_s2, j_mm_s3, NULL, lim);
}

/* Travel-frame state k to the axis frame. */
static void to_axis(const lsm_jstop *s, const lsm_kin *k, lsm_kin *out)
{
    out->s_mm = s->origin_mm + s->dir * k->s_mm;
    out->v_mm_s = s->dir * k->v_mm_s;
    out->a_mm_s2 = s->dir * k->a_mm_s2;
    out->j_mm_s3 = s->dir * k->j_mm_s3;
}

void lsm_jstop_eval(const lsm_jstop *s, lsm_real t_s, lsm_kin *out)
{
    lsm_kin k;
    unsigned i = 0;
    lsm_real t0 = 0;
    while (i < s->n_phases && t_s > t0 + s->dur_s[i]) {
        t0 += s->dur_s[i];
        i++;
    }
    if (i >= s->n_phases)
        k = s->start[s->n_phases];
    else
        advance(s, i, t_s - t0, &k);
    to_axis(s, &k, out);
}

static void rest_at(lsm_jstop *s, lsm_real p_mm, lsm_kin *out)
{
    s->active = false;
    s->origin_mm = p_mm;
    out->s_mm = p_mm;
    out->v_mm_s = s->settle ? s->v_end_mm_s : 0;
    out->a_mm_s2 = out->j_mm_s3 = 0;
}

/* Advances the clock by dt_s. True while the stage runs; else *past_s is the time beyond its end. */
static bool advance_time(lsm_jstop *s, lsm_real dt_s, lsm_real *past_s)
{
#if LSM_REAL_IS_FLOAT
    s->tau_s += dt_s;
    while (s->ph < s->n_phases && s->tau_s >= s->dur_s[s->ph]) {
        s->tau_s -= s->dur_s[s->ph];
        s->ph++;
    }
    *past_s = s->tau_s;
    return s->ph < s->n_phases;
#else
    s->t_s += dt_s;
    *past_s = s->t_s - s->t_end_s;
    return s->t_s < s->t_end_s;
#endif
}

/* The state at the present time of a running stage. */
static void eval_now(const lsm_jstop *s, lsm_kin *out)
{
#if LSM_REAL_IS_FLOAT
    lsm_kin k;
    advance(s, s->ph, s->tau_s, &k);
    to_axis(s, &k, out);
#else
    lsm_jstop_eval(s, s->t_s, out);
#endif
}

bool lsm_jstop_step(lsm_jstop *s, lsm_real dt_s, lsm_kin *out)
{
    if (!s->active) {
        rest_at(s, s->origin_mm, out);
        return false;
    }
    lsm_real past;
    if (advance_time(s, dt_s, &past)) {
        eval_now(s, out);
        return true;
    }
    const lsm_kin e = s->start[s->n_phases];
    const lsm_real p_end = s->origin_mm + s->dir * e.s_mm;
    const lsm_real v_end = s->dir * e.v_mm_s;
    const lsm_real scale = lsm_fabs(s->start[0].v_mm_s) + lsm_fabs(s->start[0].a_mm_s2) * s->t_end_s + (lsm_real)1e-12;
    if (!s->settle && lsm_fabs(v_end) > JSTOP_OVERSHOOT_REL * scale) {
        /* overshoot stage done: stop again from (p_end, v_end, 0) with the rest of this cycle */
        const lsm_jstop_limits lim = s->lim;
        if (lsm_jstop_plan(s, p_end, v_end, 0, 0, &lim) == LSM_OK && s->active)
            return lsm_jstop_step(s, past, out);
    }
    /* a settle goes on at its end velocity for the part of the cycle past its end (a stop is at rest there) */
    rest_at(s, s->settle ? p_end + s->v_end_mm_s * past : p_end, out);
    return false;
}

bool lsm_jstop_lead_now(const lsm_jstop *s, lsm_jstop_lead *out)
{
    if (!s->active)
        return false;
#if LSM_REAL_IS_FLOAT
    const unsigned i = s->ph;
    const lsm_real tau = s->tau_s;
#else
    unsigned i = 0;
    lsm_real t0 = 0;
    while (i < s->n_phases && s->t_s >= t0 + s->dur_s[i]) {
        t0 += s->dur_s[i];
        i++;
    }
    const lsm_real tau = s->t_s - t0;
#endif
    if (i >= s->n_phases || s->jb_mm_s3[i] != 0)
        return false;
    out->shape = (uint8_t)s->shape[i];
    out->full_s = s->full_s[i];
    out->off_s = s->off_s[i] + tau;
    out->jerk_mm_s3 = s->dir * s->jerk_mm_s3[i];
    return out->off_s >= 0 && out->off_s < out->full_s;
}
