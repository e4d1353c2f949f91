/* interp.c: per-cycle interpolator (see interp.h). */
#include "interp.h"

#include <string.h>

#include "lsm_math.h"

#define PI_R ((lsm_real)LSM_PI)
#define R0 LSM_R(0.0)
#define R1 LSM_R(1.0)
#define ARC_ANCHOR_CYCLES 256u
#define CLOTHOID_ANCHOR_STEPS 64u

static bool id_lt_pub(uint32_t a, uint32_t b)
{
    return (int32_t)(a - b) < 0;
}

static const lsm_pblock *bk(const lsm_interp *ip, uint32_t id)
{
    return lsm_planner_block(ip->pl, id);
}

/* sin and cos of a small angle (|x| <= 0.5: Taylor to x^13, error below 3e-17); larger angles use libm. */
static void sincos_small(lsm_real x, lsm_real *s, lsm_real *c)
{
    if (!(lsm_fabs(x) <= LSM_R(0.5))) {
        *s = lsm_sin(x);
        *c = lsm_cos(x);
        return;
    }
    const lsm_real x2 = x * x;
    *s = x * (R1 - x2 * (R1 / LSM_R(6.0)) *
                       (R1 - x2 * (R1 / LSM_R(20.0)) *
                                 (R1 - x2 * (R1 / LSM_R(42.0)) *
                                           (R1 - x2 * (R1 / LSM_R(72.0)) *
                                                     (R1 - x2 * (R1 / LSM_R(110.0)) * (R1 - x2 * (R1 / LSM_R(156.0))))))));
    *c = R1 - x2 * LSM_R(0.5) *
                  (R1 - x2 * (R1 / LSM_R(12.0)) *
                            (R1 - x2 * (R1 / LSM_R(30.0)) *
                                      (R1 - x2 * (R1 / LSM_R(56.0)) *
                                                (R1 - x2 * (R1 / LSM_R(90.0)) * (R1 - x2 * (R1 / LSM_R(132.0)))))));
}

/* ---------------------------------------------------------------------------------------------------------- */
/* geometry of the current block                                                                               */

static void arc_anchor(lsm_interp *ip, const lsm_geom *g)
{
    const lsm_geom_arc *a = &g->u.arc;
    ip->aw = a->sweep_rad / g->len;
    const lsm_real phi = a->phi0_rad + ip->aw * ip->off_mm;
    ip->ac = lsm_cos(phi);
    ip->as = lsm_sin(phi);
    ip->anchor = 0;
}

static void activate(lsm_interp *ip)
{
    const lsm_pblock *b = bk(ip, ip->blk);
    if (b == NULL)
        return;
    ip->act_blk = ip->blk;
    ip->act_ok = 1;
    const lsm_geom *g = &b->g;
    ip->gkind = g->kind;
    if (g->kind == LSM_GEOM_ARC) {
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

/* Position of the current block at the cursor (after activate or an incremental update). */
static void eval_pos(lsm_interp *ip)
{
    const lsm_pblock *b = bk(ip, ip->blk);
    if (b == NULL)
        return;
    const lsm_geom *g = &b->g;
    if (g->kind == LSM_GEOM_LINE) {
        for (int i = 0; i < LSM_MAX_AXES; i++)
            ip->pos[i] = g->u.line.p0[i] + g->u.line.dir[i] * ip->off_mm;
    } else if (g->kind == LSM_GEOM_ARC) {
        const lsm_geom_arc *a = &g->u.arc;
        const lsm_real n[3] = {a->e1[1] * a->e2[2] - a->e1[2] * a->e2[1], a->e1[2] * a->e2[0] - a->e1[0] * a->e2[2],
                               a->e1[0] * a->e2[1] - a->e1[1] * a->e2[0]};
        const lsm_real h = a->axial_mm * (ip->off_mm / g->len);
        for (int i = 0; i < 3; i++)
            ip->pos[i] = a->centre_mm[i] + a->radius_mm * (ip->ac * a->e1[i] + ip->as * a->e2[i]) + n[i] * h;
    } else {
        const lsm_geom_clothoid *c = &g->u.clo;
        for (int i = 0; i < 3; i++)
            ip->pos[i] = c->origin_mm[i] + c->e1[i] * ip->cs.x_mm + c->e2[i] * ip->cs.y_mm;
    }
}

/* Moves the cursor by ds (>= 0) and evaluates the position there. */
static void advance_path(lsm_interp *ip, lsm_real ds)
{
    if (!(ds > R0))
        ds = R0;
    const lsm_planner *pl = ip->pl;
    const lsm_pblock *b = bk(ip, ip->blk);
    if (b == NULL)
        return;
    if (!ip->act_ok || ip->act_blk != ip->blk)
        activate(ip); /* (re)started on a block that was never set up */
    ip->off_mm += ds;
    bool moved = false;
    while (ip->off_mm > b->g.len && ip->blk + 1u != pl->tail) {
        ip->off_mm -= b->g.len;
        ip->blk++;
        b = bk(ip, ip->blk);
        moved = true;
    }
    if (ip->off_mm > b->g.len)
        ip->off_mm = b->g.len;
    if (moved) {
        lsm_planner_release(ip->pl, ip->blk);
        activate(ip);
    } else if (ip->gkind == LSM_GEOM_ARC && ds > R0) {
        if (++ip->anchor >= ARC_ANCHOR_CYCLES) {
            arc_anchor(ip, &b->g);
        } else {
            lsm_real s, c;
            sincos_small(ip->aw * ds, &s, &c);
            const lsm_real nc = ip->ac * c - ip->as * s;
            const lsm_real ns = ip->as * c + ip->ac * s;
            const lsm_real k = LSM_R(1.5) - LSM_R(0.5) * (nc * nc + ns * ns);
            ip->ac = nc * k;
            ip->as = ns * k;
        }
    } else if (ip->gkind == LSM_GEOM_CLOTHOID && ds > R0) {
        (void)lsm_clothoid_step(&ip->cs, ds, NULL);
    }
    eval_pos(ip);
}

/* Puts the cursor exactly on (id, off) and evaluates there. */
static void place(lsm_interp *ip, uint32_t id, lsm_real off)
{
    ip->blk = id;
    ip->off_mm = off;
    lsm_planner_release(ip->pl, id);
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

/* Starts a piece whose first sample comes `first` after its start (0 < first <= one cycle). */
static void start_piece(lsm_interp *ip, const lsm_piece *pc, lsm_real first)
{
    const lsm_real dt = ip->pl->cfg.cycle_s;
    ip->pc = *pc;
    ip->running = 1;
    ip->gen = ip->pl->gen;
    ip->state = LSM_INTERP_RUN;
    ip->v_mm_s = pc->v0_mm_s;
    ip->phase = 0;
    ip->tau = R0;
    ip->sloc = R0;
    ip->rc = R1;
    ip->rs = R0;
    /* per ramp: the offset of the samples to its phase starts, and the rotation step */
    lsm_real t0[2];
    t0[0] = ip->pc.ph[0].T_s;
    t0[1] = t0[0];
    for (int i = 1; i <= 8; i++)
        t0[1] += ip->pc.ph[i].T_s;
    for (int r = 0; r < 2; r++) {
        const uint32_t n1 = ip->pc.ph[r == 0 ? 1 : 9].n_cycles;
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
            ip->ce[r] = lsm_cos(PI_R * e / T1);
            ip->se[r] = lsm_sin(PI_R * e / T1);
            ip->cd[r] = lsm_cos(PI_R / (lsm_real)n1);
            ip->sd[r] = lsm_sin(PI_R / (lsm_real)n1);
        }
    }
}

static lsm_status plan_from_here(lsm_interp *ip, lsm_real v0, lsm_piece_mode mode, lsm_piece *out)
{
    lsm_status st = lsm_planner_plan_piece(ip->pl, ip->blk, ip->off_mm, v0, mode, out);
    if (st != LSM_OK && st != LSM_E_INTERNAL)
        return st;
    if (st != LSM_OK)
        ip->plan_errors++;
    if (!(out->T_s > R0))
        return st == LSM_OK ? LSM_E_EMPTY : st;
    return st;
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

/* Travel of phase p at tau (phase-local); updates the rotation for sin² phases (entered: from the entry angle). */
static lsm_real phase_travel(lsm_interp *ip, uint8_t p, lsm_real tau, bool entered, lsm_real *v)
{
    const lsm_piece_phase *ph = &ip->pc.ph[p];
    const lsm_kin *st = &ip->pc.st[p];
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

/*
 * Advances the piece clock by dt_adv; returns the distance travelled (ds >= 0 modulo rounding) and whether the
 * piece ended (then *left is the time beyond its end), or stopped at the end of a ramp because the plan changed
 * (*ramp_end; *left as well).
 */
static lsm_real piece_advance(lsm_interp *ip, lsm_real dt_adv, bool *ended, lsm_real *left, bool *ramp_end)
{
    lsm_real ds = R0;
    uint8_t p = ip->phase;
    lsm_real tau = ip->tau + dt_adv;
    bool entered = false;
    const bool stop_at_ramp_end = ip->gen != ip->pl->gen && !ip->pc.hold;
    *ended = false;
    *ramp_end = false;
    while (p < LSM_PIECE_PHASES && tau >= ip->pc.ph[p].T_s) {
        ds += ip->pc.ph[p].len_mm - ip->sloc;
        tau -= ip->pc.ph[p].T_s;
        ip->sloc = R0;
        p++;
        entered = true;
        if (p == 1u || p == 9u) {
            /* a ramp starts: committed until its end, where a = 0 again and a new piece may be taken (planner.h,
             * lsm_planner_set_horizon) */
            const int e = p == 1u ? 8 : 16;
            ip->hz_v = ip->pc.st[e].v_mm_s;
            ahead(ip, ip->pc.st[e].s_mm - ip->pc.st[p].s_mm + ds, &ip->hz_blk, &ip->hz_off);
        }
        if ((p == 8u || p == 16u) && (stop_at_ramp_end || (p == 8u && ip->pc.step && !ip->pc.hold)) &&
            ip->pc.st[p].s_mm > ip->pc.st[p - 7u].s_mm) {
            /* the end of a ramp while the plan changed, or of a step of a staircase: stop the clock here (the
             * caller re-plans) */
            ip->phase = p;
            ip->tau = R0;
            *ramp_end = true;
            *left = tau;
            return ds;
        }
    }
    ip->phase = p;
    if (p >= LSM_PIECE_PHASES) {
        *ended = true;
        *left = tau;
        ip->tau = R0;
        return ds;
    }
    lsm_real v;
    const lsm_real s = phase_travel(ip, p, tau, entered, &v);
    ds += s - ip->sloc;
    ip->sloc = s;
    ip->tau = tau;
    ip->v_mm_s = v;
    return ds;
}

/* After a piece: exact position at its end; state for a stop. */
static void end_piece(lsm_interp *ip)
{
    lsm_planner *pl = ip->pl;
    ip->running = 0;
    if (!ip->pc.hold) {
        if (ip->pc.end_blk == pl->tail) {
            const lsm_pblock *b = bk(ip, pl->tail - 1u);
            ip->blk = pl->tail - 1u;
            ip->off_mm = b ? b->g.len : R0;
            lsm_planner_release(pl, ip->blk);
            activate(ip);
            if (ip->pc.stop) {
                for (int i = 0; i < LSM_MAX_AXES; i++) /* the programmed end, exactly */
                    ip->pos[i] = pl->tail_pos[i];
            } else {
                eval_pos(ip);
            }
        } else if (bk(ip, ip->pc.end_blk) != NULL) {
            place(ip, ip->pc.end_blk, R0);
        }
    }
    if (!ip->pc.stop) {
        ip->v_mm_s = ip->pc.v1_mm_s;
        return;
    }
    ip->v_mm_s = R0;
    if (ip->pc.hold) {
        ip->state = LSM_INTERP_HELD;
    } else if (!path_ahead(ip)) {
        ip->state = pl->finished ? LSM_INTERP_DONE : LSM_INTERP_IDLE;
    } else {
        ip->state = LSM_INTERP_RUN; /* an exact stop inside the program: go on from rest */
    }
}

/* Runs one cycle (or the rest `first` of it) of the current piece, chaining into the next pieces. */
static void run_cycle(lsm_interp *ip, lsm_real first)
{
    lsm_real adv = first;
    for (int guard = 0; guard < 8 && ip->running; guard++) {
        bool ended, ramp_end;
        lsm_real left = R0;
        const lsm_real ds = piece_advance(ip, adv, &ended, &left, &ramp_end);
        if (ramp_end) {
            /* re-plan exactly at the end of the ramp, from the point and speed the planner was told (before the
             * cursor moves there: rounding may carry it just past a block end, which would release that block) */
            lsm_piece np;
            const uint32_t g = ip->pl->gen;
            ip->v_mm_s = ip->hz_v;
            if (lsm_planner_plan_piece(ip->pl, ip->hz_blk, ip->hz_off, ip->hz_v, LSM_PIECE_REPLAN, &np) == LSM_OK &&
                np.T_s > R0) {
                place(ip, ip->hz_blk, ip->hz_off);
                start_piece(ip, &np, left);
                ip->replans++;
            } else {
                advance_path(ip, ds);
            }
            ip->gen = g; /* once per ramp end: the current piece stays valid if none was found */
            adv = left;
            continue;
        }
        if (!ended) {
            advance_path(ip, ds);
            if (is_ramp_phase(ip->phase))
                lsm_planner_set_horizon(ip->pl, ip->hz_blk, ip->hz_off, ip->hz_v);
            else
                lsm_planner_set_horizon(ip->pl, ip->blk, ip->off_mm, ip->v_mm_s);
            return;
        }
        end_piece(ip);
        if (ip->pc.stop || !(left > R0))
            return;
        /* the next piece starts inside this cycle: plan it and sample it at the rest of the cycle */
        lsm_piece np;
        if (plan_from_here(ip, ip->v_mm_s, LSM_PIECE_NORMAL, &np) == LSM_OK || np.T_s > R0) {
            if (np.T_s > R0) {
                start_piece(ip, &np, left);
                adv = left;
                continue;
            }
        }
        return;
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
    ip->state = LSM_INTERP_IDLE;
    ip->blk = pl->head;
    ip->off_mm = R0;
    ip->ovr = R1;
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
    /* at rest or between pieces: start when there is something to do */
    if (!ip->running) {
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
                activate(ip);
            }
            if (ip->v_mm_s == R0 && ip->hold_req) {
                ip->state = LSM_INTERP_HELD; /* a hold at rest */
            } else {
                lsm_piece np;
                if (plan_from_here(ip, ip->v_mm_s, LSM_PIECE_NORMAL, &np) != LSM_E_EMPTY && np.T_s > R0)
                    start_piece(ip, &np, dt);
                else if (!path_ahead(ip))
                    ip->state = pl->finished ? LSM_INTERP_DONE : LSM_INTERP_IDLE;
            }
        }
        if (ip->running) {
            run_cycle(ip, dt);
            goto out;
        }
        goto out;
    }
    {
        /* replanning where a = 0 */
        const uint8_t p = ip->phase;
        const bool a_zero = p == 0u || p == 8u || p == 16u || (ip->tau == R0 && (p == 1u || p == 9u));
        if (a_zero && !ip->pc.hold) {
            lsm_piece np;
            if (ip->hold_req) {
                if (lsm_planner_plan_piece(pl, ip->blk, ip->off_mm, ip->v_mm_s, LSM_PIECE_HOLD, &np) == LSM_OK) {
                    if (np.T_s > R0) {
                        start_piece(ip, &np, dt);
                    } else {
                        ip->running = 0;
                        ip->state = LSM_INTERP_HELD;
                        goto out;
                    }
                }
            } else if (ip->gen != pl->gen) {
                /* In a cruise this is the point the planner verified the change from (lsm_planner_set_horizon):
                 * if no new piece is found, the current one is still valid and runs on. At a ramp start the
                 * planner verified the end of the ramp instead: the ramp end re-plans there. */
                const bool cruise = p == 0u || p == 8u || p == 16u;
                const uint32_t g = pl->gen;
                if (lsm_planner_plan_piece(pl, ip->blk, ip->off_mm, ip->v_mm_s, LSM_PIECE_REPLAN, &np) == LSM_OK &&
                    np.T_s > R0) {
                    ip->replans++;
                    start_piece(ip, &np, dt);
                } else if (cruise) {
                    ip->gen = g;
                }
            }
        }
        run_cycle(ip, dt);
    }
out:
    if (!ip->running) /* at rest (or stopped for good): the machine stands here */
        lsm_planner_set_horizon(pl, ip->blk, ip->off_mm, R0);
    for (int i = 0; i < LSM_MAX_AXES; i++)
        pos[i] = ip->pos[i];
    return (lsm_interp_state)ip->state;
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
    return lsm_planner_set_override(ip->pl, f, ip->blk, ip->v_mm_s);
}

lsm_real lsm_interp_feed(const lsm_interp *ip)
{
    return ip ? ip->v_mm_s : R0;
}

lsm_interp_state lsm_interp_state_of(const lsm_interp *ip)
{
    return ip ? (lsm_interp_state)ip->state : LSM_INTERP_IDLE;
}
