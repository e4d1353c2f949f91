/* pathrun.c: a G-code program through the planner and interpolator, measured (see pathrun.h). */
#include "pathrun.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "arc_centre.h"
#include "simprog.h"
#include "drive.h"
#include "gcode.h"
#include "geom.h"
#include "vpop.h"

/* ---------------------------------------------------------------------------------------------------------- */

char *sim_read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap + 1);
    if (!buf) {
        fclose(f);
        return NULL;
    }
    for (;;) {
        if (n == cap) {
            char *nb = realloc(buf, 2 * cap + 1);
            if (!nb) {
                free(buf);
                fclose(f);
                return NULL;
            }
            buf = nb;
            cap *= 2;
        }
        size_t k = fread(buf + n, 1, cap - n, f);
        n += k;
        if (k == 0)
            break;
    }
    fclose(f);
    buf[n] = '\0';
    if (len)
        *len = n;
    return buf;
}

void sim_run_planner_config(const sim_machine *m, lsm_planner_config *cfg)
{
    lsm_planner_default_config(cfg);
    cfg->cycle_s = m->cycle_s;
    cfg->axis_mask = 0;
    for (int i = 0; i < m->n_axes; i++) {
        const sim_machine_axis *a = &m->axes[i];
        const int k = a->index;
        cfg->axis_mask |= (uint8_t)(1u << k);
        cfg->axis[k].v_max = a->v_max_u_s;
        cfg->axis[k].a_max = a->a_max_u_s2;
        cfg->axis[k].j_max = a->j_max_u_s3;
        cfg->axis[k].snap_max = a->snap_max_u_s4;
    }
}

/* ---------------------------------------------------------------------------------------------------------- */

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

/* The measurement of the setpoints (pathrun.h), one setpoint at a time: axis v, a, j by backward differences with
 * the machine at rest on the program's start before the first setpoint and on the last one after it, the deviation
 * from the programmed path, and (streaming, with drives) the simulated drives' following error. Constant memory:
 * a run without CSVs (summary_only) measures while it runs and keeps no setpoint; a run that keeps them measures
 * them afterwards with the same code, so both give the same numbers. */
typedef struct meter {
    const sim_prog *p;
    const sim_machine *m;
    sim_run_result *r;
    double dt, reach;
    size_t n;
    double q1[LSM_MAX_AXES], q2[LSM_MAX_AXES], q3[LSM_MAX_AXES]; /* q[k-1], q[k-2], q[k-3] */
    double last[LSM_MAX_AXES];
    bool drives; /* step the drives here (summary_only) */
    sim_drive drv[SIM_MACHINE_MAX_AXES];
    double dq1[LSM_MAX_AXES], dq2[LSM_MAX_AXES]; /* the drives' own history (at rest on the start) */
    size_t elem_lo;       /* the first path element the last deviation looked at (sim_prog_deviation) */
    size_t window_misses; /* deviations whose path elements were no longer held (a windowed program) */
} meter;

static void meter_init(meter *mt, const sim_prog *p, const sim_machine *m, sim_run_result *r, bool drives)
{
    memset(mt, 0, sizeof *mt);
    mt->p = p;
    mt->m = m;
    mt->r = r;
    mt->dt = m->cycle_s;
    mt->drives = drives;
    double vmax = 0;
    for (int i = 0; i < m->n_axes; i++)
        if (m->axes[i].v_max_u_s > vmax && !m->axes[i].rotary)
            vmax = m->axes[i].v_max_u_s;
    mt->reach = 2 * vmax * mt->dt + 1.0;
    for (int a = 0; a < LSM_MAX_AXES; a++)
        r->max_v[a] = r->max_a[a] = r->max_j[a] = 0;
    r->max_dev_mm = 0;
}

static void meter_diff(meter *mt, int a, double q0)
{
    sim_run_result *r = mt->r;
    const double dt = mt->dt, q1 = mt->q1[a], q2 = mt->q2[a], q3 = mt->q3[a];
    const double v = fabs(q0 - q1) / dt;
    const double acc = fabs(q0 - 2 * q1 + q2) / (dt * dt);
    const double j = fabs(q0 - 3 * q1 + 3 * q2 - q3) / (dt * dt * dt);
    if (v > r->max_v[a])
        r->max_v[a] = v;
    if (acc > r->max_a[a])
        r->max_a[a] = acc;
    if (j > r->max_j[a])
        r->max_j[a] = j;
    mt->q3[a] = q2;
    mt->q2[a] = q1;
    mt->q1[a] = q0;
}

static void meter_drives(meter *mt, const double q[LSM_MAX_AXES])
{
    const sim_machine *m = mt->m;
    const double dt = mt->dt;
    for (int i = 0; i < m->n_axes; i++) {
        const int a = m->axes[i].index;
        if (mt->n == 0) { /* validated before the run (sim_run_program) */
            (void)sim_drive_init(&mt->drv[i], &m->axes[i].drive, dt, q[a]);
            mt->dq1[a] = mt->dq2[a] = mt->p->total ? mt->p->start[a] : q[a];
        }
        const double q0 = q[a], q1 = mt->dq1[a], q2 = mt->dq2[a];
        const double v = (q0 - q1) / dt, acc = (q0 - 2 * q1 + q2) / (dt * dt);
        double act;
        sim_drive_step_ff(&mt->drv[i], q0, v, acc, &act);
        const double fe = fabs(q0 - act);
        if (fe > mt->r->max_follow_err[a])
            mt->r->max_follow_err[a] = fe;
        mt->dq2[a] = q1;
        mt->dq1[a] = q0;
    }
}

static void meter_push(meter *mt, const double q[LSM_MAX_AXES], uint32_t line)
{
    for (int a = 0; a < LSM_MAX_AXES; a++) {
        if (mt->n == 0) /* at rest on the program's start before the first setpoint */
            mt->q1[a] = mt->q2[a] = mt->q3[a] = mt->p->total ? mt->p->start[a] : q[a];
        meter_diff(mt, a, q[a]);
    }
    const double d = sim_prog_deviation(mt->p, q, line, mt->reach, &mt->elem_lo);
    if (d < 0)
        mt->window_misses++;
    if (d > mt->r->max_dev_mm) {
        mt->r->max_dev_mm = d;
        if (getenv("LSM_DEV_DEBUG"))
            fprintf(stderr, "dev %g at k %zu line %u pos %g %g %g\n", d, mt->n, line, q[0], q[1], q[2]);
    }
    if (mt->drives)
        meter_drives(mt, q);
    memcpy(mt->last, q, sizeof mt->last);
    mt->n++;
}

/* The machine at rest on the last setpoint for three more cycles; the end error. */
static void meter_finish(meter *mt)
{
    sim_run_result *r = mt->r;
    r->end_error = 0;
    if (mt->n == 0)
        return;
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < LSM_MAX_AXES; a++)
            meter_diff(mt, a, mt->last[a]);
    for (int i = 0; i < mt->m->n_axes; i++) {
        const int a = mt->m->axes[i].index;
        const double e = fabs(mt->last[a] - mt->p->end[a]);
        if (e > r->end_error)
            r->end_error = e;
    }
}

typedef struct rec {
    double *q, *feed;
    uint32_t *line;
    size_t n, cap;
    meter *stream; /* summary_only: measure each setpoint here and keep none */
} rec;

static int rec_push(rec *r, const double pos[LSM_MAX_AXES], double feed, uint32_t line)
{
    if (r->stream) {
        meter_push(r->stream, pos, line);
        r->n++;
        return 0;
    }
    if (r->n == r->cap) {
        size_t nc = r->cap ? 2 * r->cap : 4096;
        double *nq = realloc(r->q, nc * LSM_MAX_AXES * sizeof *nq);
        if (!nq)
            return -1;
        r->q = nq;
        double *nf = realloc(r->feed, nc * sizeof *nf);
        if (!nf)
            return -1;
        r->feed = nf;
        uint32_t *nl = realloc(r->line, nc * sizeof *nl);
        if (!nl)
            return -1;
        r->line = nl;
        r->cap = nc;
    }
    memcpy(r->q + r->n * LSM_MAX_AXES, pos, LSM_MAX_AXES * sizeof(double));
    r->feed[r->n] = feed;
    r->line[r->n] = line;
    r->n++;
    return 0;
}

/* A run that neither moves nor takes a block for this long (machine time, s) has stalled. */
#define SIM_STALL_S 10.0

static lsm_status append_block(lsm_planner *pl, const sim_prog_block *q)
{
    const lsm_gcode_block *b = &q->b;
    lsm_planner_move mv;
    memset(&mv, 0, sizeof mv);
    mv.rapid = b->type == LSM_GCODE_BLOCK_RAPID;
    const bool xyz = b->start[0] != b->end[0] || b->start[1] != b->end[1] || b->start[2] != b->end[2] ||
                     b->type == LSM_GCODE_BLOCK_ARC;
    mv.feed_mm_s = xyz ? b->feed_mm_s : b->feed_rot_rad_s;
    mv.tol_mm = q->tol_mm;
    mv.seq = b->line;
    if (b->type == LSM_GCODE_BLOCK_ARC) {
        for (int k = 3; k < 6; k++)
            if (b->start[k] != b->end[k])
                return LSM_E_PL_AXIS; /* arcs that turn A B C are not supported */
        return lsm_planner_append_arc(pl, b->end, b->centre, (lsm_geom_plane)b->plane, b->dir, b->turns, &mv);
    }
    return lsm_planner_append_line(pl, b->end, &mv);
}

/* Machine functions run by the Lissom run (see sim_run_mfunc). */
typedef struct mf_gate {
    size_t i;             /* next event to run */
    uint64_t dwell_until; /* the stream waits up to this cycle (G4) */
    bool flushed;         /* the planner was flushed for the pending exact stop */
} mf_gate;

/* True when the machine rests on the programmed end of the blocks before `next`. */
static bool mf_at_rest(const sim_prog *p, size_t next, const lsm_interp *ip)
{
    if (lsm_interp_state_of(ip) != LSM_INTERP_IDLE)
        return false;
    for (int k = 0; k < LSM_MAX_AXES; k++) {
        const double want = next > 0 ? (double)sim_prog_block_at(p, next - 1)->b.end[k] : p->start[k];
        if (fabs(ip->pos[k] - want) > 1e-6)
            return false;
    }
    return true;
}

/* Runs the machine functions due before block `next` at cycle k: those without a stop at once; for one with a stop,
 * the stream waits (the planner is flushed) until the machine rests on the end of the block before it; a dwell then
 * holds the stream for its whole cycles. Returns true while the stream must wait. */
static bool mf_step(const sim_prog *p, mf_gate *g, size_t next, lsm_planner *pl, const lsm_interp *ip, uint64_t k,
                    double cycle_s)
{
    if (k < g->dwell_until)
        return true;
    while (g->i < p->n_ev && p->ev[g->i].before_block <= next) {
        sim_run_mfunc *m = &p->ev[g->i];
        if (m->ev.kind == LSM_GCODE_EV_END)
            return false; /* the planner's finish is the end's stop; its time is set after the run */
        if (m->ev.exact_stop && p->total > 0) {
            if (!g->flushed) {
                if (lsm_planner_flush(pl) != LSM_OK)
                    return true;
                g->flushed = true;
            }
            if (!mf_at_rest(p, next, ip))
                return true;
        }
        m->t_s = (double)k * cycle_s;
        g->i++;
        g->flushed = false;
        if (m->ev.kind == LSM_GCODE_EV_DWELL) {
            g->dwell_until = k + (uint64_t)ceil((double)m->ev.value / cycle_s - 1e-9);
            if (k < g->dwell_until)
                return true;
        }
    }
    return false;
}

typedef struct feed_state {
    size_t next;     /* the next program block to append */
    size_t appended; /* blocks appended */
    bool fin;        /* the planner was told the program ended */
    mf_gate gate;
    double t_append; /* host time in appends (ns) */
} feed_state;

/* Stage 1 of a cycle: the machine functions due, then blocks into the planner while it has room. A windowed
 * program is parsed one block ahead of the append, so that a machine function after a block is known (and its
 * exact stop set) before the block goes in, as when the whole program is loaded first. Returns 0, or -1 with
 * r->err set. */
static int feed_stage(const sim_run_opts *o, sim_prog *p, feed_state *fs, lsm_planner *pl, const lsm_interp *ip,
                      uint64_t k, sim_run_result *r)
{
    const bool slow = o->feed_every > 0;
    const double cycle_s = pl->cfg.cycle_s;
    if (sim_prog_need(p, fs->next + 1, r->err, sizeof r->err) != 0)
        return -1;
    bool wait = mf_step(p, &fs->gate, fs->next, pl, ip, k, cycle_s);
    while (!wait && fs->next < p->n && lsm_planner_free(pl) >= 3 && (!slow || k % o->feed_every == 0)) {
        const sim_prog_block *q = sim_prog_block_at(p, fs->next);
        const double t0 = now_ns();
        const lsm_status st = append_block(pl, q);
        fs->t_append += now_ns() - t0;
        if (st == LSM_E_FULL) /* the planner holds points for fitting: run the machine and retry */
            break;
        if (st != LSM_OK && st != LSM_E_ZERO_LENGTH) {
            snprintf(r->err, sizeof r->err, "G-code line %u: planner: %s", (unsigned)q->b.line, lsm_status_str(st));
            return -1;
        }
        fs->next++; /* LSM_E_ZERO_LENGTH: too short to represent, dropped (the parser dropped exact zeros) */
        if (sim_prog_need(p, fs->next + 1, r->err, sizeof r->err) != 0)
            return -1;
        if (st == LSM_E_ZERO_LENGTH)
            continue;
        fs->appended++;
        wait = fs->gate.i < p->n_ev && p->ev[fs->gate.i].before_block <= fs->next &&
               p->ev[fs->gate.i].ev.kind != LSM_GCODE_EV_END; /* run it on the next cycle */
        if (slow)
            break;
    }
    if (!wait && fs->next == p->n && p->done && lsm_planner_finish(pl) == LSM_OK)
        fs->fin = true;
    return 0;
}

static int run_lissom(const sim_run_opts *o, sim_prog *p, rec *out, sim_run_result *r)
{
    lsm_planner_config cfg;
    if (o->cfg_override)
        cfg = *o->cfg_override;
    else
        sim_run_planner_config(o->machine, &cfg);
    uint32_t cap = o->capacity;
    if (cap == 0) {
        cap = 3u * (uint32_t)o->machine->lookahead_blocks + 8u;
        if (cap < 256)
            cap = 256;
    }
    lsm_pblock *store = calloc(cap, sizeof *store);
    lsm_planner *pl = calloc(1, sizeof *pl);
    lsm_interp *ip = calloc(1, sizeof *ip);
    if (!store || !pl || !ip) {
        free(store);
        free(pl);
        free(ip);
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    lsm_real start[LSM_MAX_AXES] = {0};
    for (int i = 0; i < LSM_MAX_AXES; i++)
        start[i] = (lsm_real)p->start[i];
    lsm_status st = lsm_planner_init(pl, &cfg, store, cap, start);
    if (st != LSM_OK) {
        snprintf(r->err, sizeof r->err, "planner init: %s", lsm_status_str(st));
        free(store);
        free(pl);
        free(ip);
        return -1;
    }
    lsm_interp_init(ip, pl);
    feed_state fs = {0};
    /* no cap on machine time unless asked for (long jobs run for hours); a stall ends the run instead */
    const double max_t = o->max_time_s;
    const uint64_t max_cycles = max_t > 0 ? (uint64_t)(max_t / cfg.cycle_s) + 1 : UINT64_MAX;
    const uint64_t stall_cycles = (uint64_t)(SIM_STALL_S / cfg.cycle_s) + 1;
    uint64_t still = 0;              /* cycles without progress */
    lsm_real last_pos[LSM_MAX_AXES]; /* the setpoints' own type (float on the host-float build) */
    memcpy(last_pos, start, sizeof last_pos);
    double t_step = 0, t_prep = 0;
    size_t ev = 0;
    int rc = 0;
    uint64_t k_done = 0;
    for (uint64_t k = 0;; k++) {
        const size_t next_before = fs.next;
        if (!fs.fin && feed_stage(o, p, &fs, pl, ip, k, r) != 0) {
            rc = -1;
            goto done;
        }
        while (ev < o->n_events && o->events[ev].cycle <= k) {
            const sim_run_event *e = &o->events[ev++];
            if (e->kind == 1)
                lsm_interp_hold(ip);
            else if (e->kind == 2)
                lsm_interp_resume(ip);
            else if (e->kind == 3)
                lsm_interp_set_override(ip, e->value);
        }
        lsm_real pos[LSM_MAX_AXES];
        const double tp = now_ns();
        (void)lsm_interp_prepare(ip); /* background planning, between cycles */
        const double t0 = now_ns();
        t_prep += t0 - tp;
        const lsm_interp_state s = lsm_interp_step(ip, pos);
        t_step += now_ns() - t0;
        const lsm_pblock *cb = lsm_planner_block(pl, ip->blk);
        double posd[LSM_MAX_AXES]; /* (a float core's setpoints, widened exactly) */
        for (int i = 0; i < LSM_MAX_AXES; i++)
            posd[i] = pos[i];
        if (rec_push(out, posd, lsm_interp_feed(ip), cb ? cb->seq : 0) != 0) {
            snprintf(r->err, sizeof r->err, "out of memory");
            rc = -1;
            goto done;
        }
        if (out->stream) /* windowed: what lies behind the planner and the deviation check goes */
            sim_prog_trim(p, fs.next ? fs.next - 1 : 0, out->stream->elem_lo);
        if (s == LSM_INTERP_DONE) {
            k_done = k;
            break;
        }
        if (k >= max_cycles) {
            snprintf(r->err, sizeof r->err, "run exceeded %.0f s of machine time (--max-time)", max_t);
            rc = -1;
            goto done;
        }
        /* progress: the setpoint moved, a block was taken, a dwell (G4) runs, or an event (a resume) is still to
         * come */
        const bool moved = memcmp(pos, last_pos, sizeof last_pos) != 0;
        memcpy(last_pos, pos, sizeof last_pos);
        still = (moved || fs.next != next_before || k < fs.gate.dwell_until || ev < o->n_events) ? 0 : still + 1;
        if (still >= stall_cycles) {
            snprintf(r->err, sizeof r->err,
                     "stalled: no motion and no block taken for %.0f s of machine time (at %.3f s, interpolator %s, "
                     "G-code line %u, %zu of %zu blocks taken)",
                     SIM_STALL_S, (double)k * cfg.cycle_s,
                     s == LSM_INTERP_IDLE   ? "idle"
                     : s == LSM_INTERP_HELD ? "held"
                                            : "running",
                     cb ? (unsigned)cb->seq : 0u, fs.next, p->total);
            rc = -1;
            goto done;
        }
        if (o->progress && (k & 0xFFF) == 0 && p->total) /* done: the source line being run, of the last one */
            o->progress(o->progress_ctx, SIM_RUN_PHASE_PLAN, cb ? (double)cb->seq / (double)p->last_line : 0,
                        (double)k * cfg.cycle_s);
    }
    r->cycles = k_done + 1;
    r->duration_s = (double)r->cycles * cfg.cycle_s;
    r->plan_ns_per_block = fs.appended ? fs.t_append / (double)fs.appended : 0;
    r->interp_ns_per_cycle = out->n ? t_step / (double)out->n : 0;
    r->prepare_ns_per_piece = ip->prepared ? t_prep / (double)ip->prepared : 0;
done:
    r->stats = pl->stats;
    r->replans = ip->replans;
    r->plan_errors = ip->plan_errors;
    r->tick_plans = ip->tick_plans;
    r->prepared = ip->prepared;
    free(store);
    free(pl);
    free(ip);
    return rc;
}

/* The planner's geometry (after fitting and corner smoothing) as a path q(s) for VPOp. */
typedef struct gpath {
    /* a cubic Hermite table of X Y Z (positions and unit tangents), per block: block k has tab_m[k] equal
     * intervals (about 0.004 mm) starting at node tab_off[k], so that no interval straddles a junction (where the
     * curvature jumps) and every block end and stop is a node; intervals turn by at most 0.02 rad. Exact
     * evaluation of the clothoids costs 2-3x the planning time; the table is within 6e-10 mm of them on the
     * example programs (measured on 2e6 points per program) */
    double *tab; /* 6 per node: x y z tx ty tz */
    size_t *tab_off;
    uint32_t *tab_m;
    lsm_geom *g;
    double *s0;   /* cumulative start of each block */
    double *rot;  /* A B C at each block's start (3 per block) */
    double *feed; /* programmed feed of each block (mm/s; inf for rapids) */
    size_t n;
    double len;
    int has_rot;   /* the machine has A B or C */
    size_t hint;   /* the block of the last evaluation */
    double *stops; /* where the planner stops (LSM_PB_STOP), ascending: VPOp comes to rest there too */
    size_t n_stops;
    double *cbound; /* vpop-cstep: per block, the largest |C''| and a bound of |C'''| on it (vp_cstep_bounds) */
} gpath;

static double gpath_next_stop(void *ctx, double s)
{
    const gpath *gp = ctx;
    size_t lo = 0, hi = gp->n_stops; /* the first stop >= s */
    while (lo < hi) {
        const size_t mid = (lo + hi) / 2;
        if (gp->stops[mid] < s)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < gp->n_stops ? gp->stops[lo] : gp->len;
}

static void gpath_exact(const gpath *gp, double s, double q[SIM_VPOP_AXES], double t[3]);

/* The block of gp that holds arc length s (binary search on the block starts). */
static size_t vp_block_at(const gpath *gp, double s)
{
    size_t lo = 0, hi = gp->n;
    while (hi - lo > 1) {
        const size_t mid = (lo + hi) / 2;
        if (gp->s0[mid] <= s)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* The block holding s (the last one whose start is <= s); the last answer is tried first (the searches stay
 * local). */
static size_t gpath_block(gpath *gp, double s)
{
    const size_t h = gp->hint;
    if (h < gp->n && gp->s0[h] <= s && (h + 1 == gp->n || s < gp->s0[h + 1]))
        return h;
    if (h + 1 < gp->n && gp->s0[h + 1] <= s && (h + 2 == gp->n || s < gp->s0[h + 2]))
        return gp->hint = h + 1;
    return gp->hint = vp_block_at(gp, s);
}

/* Positions (and dq/ds if d) from the Hermite table; A B C from the blocks if the machine has them. */
static void gpath_eval_d(void *ctx, double s, double q[SIM_VPOP_AXES], double d[SIM_VPOP_AXES])
{
    gpath *gp = ctx;
    if (!gp->tab) {
        double t[3] = {0, 0, 0};
        gpath_exact(gp, s, q, t);
        if (d)
            for (int i = 0; i < SIM_VPOP_AXES; i++)
                d[i] = i < 3 ? t[i] : 0; /* (rotary slopes: 0; only the search's linearisation uses them) */
        return;
    }
    const size_t blk = gpath_block(gp, s);
    const uint32_t m = gp->tab_m[blk];
    const double h = gp->g[blk].len / m;
    double x = (s - gp->s0[blk]) / h;
    if (x < 0)
        x = 0;
    size_t k = (size_t)x;
    if (k >= m)
        k = m - 1;
    double u = x - (double)k;
    if (u > 1)
        u = 1;
    const double u2 = u * u, u3 = u2 * u;
    const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
    const double *a = gp->tab + 6 * (gp->tab_off[blk] + k), *b = a + 6;
    for (int i = 0; i < 3; i++)
        q[i] = h00 * a[i] + h10 * h * a[3 + i] + h01 * b[i] + h11 * h * b[3 + i];
    if (d) {
        const double d00 = (6 * u2 - 6 * u) / h, d10 = 3 * u2 - 4 * u + 1, d01 = -d00, d11 = 3 * u2 - 2 * u;
        for (int i = 0; i < 3; i++)
            d[i] = d00 * a[i] + d10 * a[3 + i] + d01 * b[i] + d11 * b[3 + i];
        for (int i = 3; i < SIM_VPOP_AXES; i++)
            d[i] = 0;
    }
    if (gp->has_rot) {
        double rest[SIM_VPOP_AXES];
        gpath_exact(gp, s, rest, NULL); /* A B C (lines only: cheap) */
        for (int i = 3; i < SIM_VPOP_AXES; i++)
            q[i] = rest[i];
        if (d && gp->g[blk].kind == LSM_GEOM_LINE) /* A B C change linearly along a line block */
            for (int i = 3; i < SIM_VPOP_AXES; i++)
                d[i] = gp->g[blk].u.line.dir[i];
    } else {
        for (int i = 3; i < SIM_VPOP_AXES; i++)
            q[i] = 0;
    }
}

static void gpath_eval(void *ctx, double s, double q[SIM_VPOP_AXES])
{
    gpath_eval_d(ctx, s, q, NULL);
}

static void gpath_exact(const gpath *gp, double s, double q[SIM_VPOP_AXES], double t[3])
{
    const size_t lo = vp_block_at(gp, s);
    lsm_real pos[LSM_MAX_AXES];
    pos[3] = (lsm_real)gp->rot[3 * lo];
    pos[4] = (lsm_real)gp->rot[3 * lo + 1];
    pos[5] = (lsm_real)gp->rot[3 * lo + 2];
    if (t == NULL && gp->tab && gp->g[lo].kind != LSM_GEOM_LINE) { /* only A B C wanted: constant there */
        for (int i = 3; i < LSM_MAX_AXES; i++)
            q[i] = pos[i];
        return;
    }
    lsm_real tr[3];
    lsm_geom_eval(&gp->g[lo], (lsm_real)(s - gp->s0[lo]), pos, t ? tr : NULL, NULL);
    for (int i = 0; i < LSM_MAX_AXES; i++)
        q[i] = pos[i];
    for (int i = 0; t != NULL && i < 3; i++)
        t[i] = tr[i];
}

static double gpath_feed(void *ctx, double s)
{
    gpath *gp = ctx;
    return gp->feed[gpath_block(gp, s)];
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y ? 1 : 0;
}

/* max_i |d³q_i/dt³| / J_i of the motion at path point s with s' = v, s'' = a, s''' = j (Beudaert eq 3: exact
 * tangent and curvature vector of the geometry, q_sss from a central difference of q_ss within the block), against the limits lim. */
static double vp_jerk_ratio(const gpath *gp, const sim_vpop_limits *lim, double s, double v, double a, double j)
{
    const size_t lo = vp_block_at(gp, s);
    const lsm_geom *g = &gp->g[lo];
    const double len = (double)g->len, u = fmin(len, fmax(0, s - gp->s0[lo]));
    lsm_real pos[LSM_MAX_AXES] = {0}, t[3], c[3], c1[3], c2[3];
    lsm_geom_eval(g, (lsm_real)u, pos, t, c);
    double q3[3] = {0, 0, 0};
    if (g->kind != LSM_GEOM_LINE) {
        const double h = fmin(1e-4, 0.25 * len);
        const double ua = fmax(0, u - h), ub = fmin(len, u + h);
        lsm_geom_eval(g, (lsm_real)ua, pos, NULL, c1);
        lsm_geom_eval(g, (lsm_real)ub, pos, NULL, c2);
        for (int i = 0; i < 3; i++)
            q3[i] = ub > ua ? ((double)c2[i] - (double)c1[i]) / (ub - ua) : 0;
    }
    double worst = 0;
    for (int i = 0; i < 3; i++) {
        if (!(lim->axis_mask & (1u << i)) || !(lim->j[i] > 0))
            continue;
        const double qs = g->kind == LSM_GEOM_LINE ? (double)g->u.line.dir[i] : (double)t[i];
        worst = fmax(worst, fabs(qs * j + 3 * (double)c[i] * v * a + q3[i] * v * v * v) / lim->j[i]);
    }
    return worst;
}

/*
 * What VPOp's motion asks of each axis between its samples: VPOp holds the limits on the backward differences of
 * the samples only (Beudaert eq 6). At every sample, with the path derivatives of the geometry at s_k (exact
 * tangent q_s and curvature vector q_ss, q_sss from a central difference of q_ss within the block) and s', s'',
 * s''' from central differences of the planned s_k, the continuous jerk of axis i is
 *     q_i''' = q_s,i s''' + 3 q_ss,i s' s'' + q_sss,i s'^3          (Beudaert eq 3)
 * Reported: the largest and the 99th percentile over the samples of max_i |q_i'''| / J_i (X Y Z). The real-time
 * planner holds this continuous jerk (planner.h), so this tells how much of VPOp's lead comes from the samples.
 */
static void vpop_intersample(const gpath *gp, const sim_vpop_limits *lim, const double *S, size_t n, double dt,
                             sim_run_result *r)
{
    r->intersample_jerk_max = r->intersample_jerk_p99 = -1;
    if (n < 5)
        return;
    double *ratio = malloc(n * sizeof *ratio);
    if (!ratio)
        return;
    size_t m = 0;
    for (size_t k = 2; k + 2 < n; k++) {
        const double v = (S[k + 1] - S[k - 1]) / (2 * dt);
        const double a = (S[k + 1] - 2 * S[k] + S[k - 1]) / (dt * dt);
        const double j = (S[k + 2] - 2 * S[k + 1] + 2 * S[k - 1] - S[k - 2]) / (2 * dt * dt * dt);
        ratio[m++] = vp_jerk_ratio(gp, lim, S[k], v, a, j);
    }
    qsort(ratio, m, sizeof *ratio, cmp_double);
    r->intersample_jerk_max = m ? ratio[m - 1] : 0;
    r->intersample_jerk_p99 = m ? ratio[(size_t)(0.99 * (double)(m - 1))] : 0;
    free(ratio);
}

/*
 * The continuous-limit reference (pathrun.h: SIM_RUN_VPOP_CONT): VPOp whose every step is also checked between its
 * samples (vpop.h: step_cont).
 *
 * Interpolation model. The motion between the samples is s(t) = the uniform cubic B-spline whose control points are
 * the samples S_k (at rest before and after: 0 .. 0, S_0 .. S_n-1 = L, L .. L), i.e. the triple integrator driven by
 * the step's own discrete jerk held over one cycle: on the segment that step j+1 adds (control points s_j-2, s_j-1,
 * s_j, s_j+1; u in [0, 1] over one cycle dt)
 *     s''' = (s_j+1 - 3 s_j + 3 s_j-1 - s_j-2) / dt³ (VPOp's discrete jerk, constant over the cycle),
 *     s''  = ((1-u) (s_j-2 - 2 s_j-1 + s_j) + u (s_j-1 - 2 s_j + s_j+1)) / dt² (its two discrete accelerations),
 *     s'   the quadratic B-spline of its three discrete velocities, s the cubic one.
 * s is C2 in t and passes through (S_k-1 + 4 S_k + S_k+1) / 6 at the cycle times (within a dt² / 6 of S_k), and
 * the motion takes the same n cycles as the samples. Each axis then moves as (Beudaert eq 3)
 *     q' = C' s',  q'' = C'' s'² + C' s'',  q''' = C''' s'³ + 3 C'' s' s'' + C' s'''
 * with C' the exact tangent and C'' the exact curvature vector of the block at s (lsm_geom_eval), C''' in closed form
 * (vp_cstep_c3). The step passes if |q'| <= V, |q''| <= A, |q'''| <= J for every axis, checked block by block
 * over the part of the path the segment covers: on each block's part at its share (by length) of VP_CSTEP_POINTS
 * points, at least VP_CSTEP_BLOCK_POINTS, and at both ends of the part (so on both sides of every junction: the
 * curvature may jump there, the acceleration then steps, and the jerk is held on each block up to its end). No
 * point is needed where a bound holds already: inside one line block the check is implied by the discrete bounds
 * VPOp holds on the same four samples (the B-spline's s', s'' are convex combinations of the discrete v and a, s'''
 * is the discrete jerk); otherwise vp_cstep_easy (the whole segment) and vp_cstep_line_easy (a line part) bound eq 3
 * from those discrete values and the blocks' largest |C''| and |C'''|. Between the points a peak can exceed the
 * limit by O(1 / VP_CSTEP_POINTS²) of its curvature, less after the golden-section steps (VP_CSTEP_REFINE) around
 * the largest point: measured by vp_cont_verify, 1e-8 of the limit on the shipped paths, at most 1.1e-5 on random
 * programs.
 */
#define VP_CSTEP_POINTS 16      /* points per cycle where a step's motion is checked, shared among the blocks ... */
#define VP_CSTEP_BLOCK_POINTS 4 /* ... and at least this many in every block that needs them (short corner blocks) */
#define VP_CSTEP_REFINE 4       /* golden-section steps (2 points each) around each part's largest point */

/* s, s', s'', s''' at u in [0, 1] of the B-spline segment with control points P (one cycle dt). */
static void vp_bs_eval(const double P[4], double u, double dt, double d[4])
{
    const double w = 1 - u, u2 = u * u, u3 = u2 * u;
    d[0] = (w * w * w * P[0] + (3 * u3 - 6 * u2 + 4) * P[1] + (-3 * u3 + 3 * u2 + 3 * u + 1) * P[2] + u3 * P[3]) / 6;
    d[1] = (-3 * w * w * P[0] + (9 * u2 - 12 * u) * P[1] + (-9 * u2 + 6 * u + 3) * P[2] + 3 * u2 * P[3]) / (6 * dt);
    d[2] = (w * P[0] + (3 * u - 2) * P[1] + (1 - 3 * u) * P[2] + u * P[3]) / (dt * dt);
    d[3] = (P[3] - 3 * P[2] + 3 * P[1] - P[0]) / (dt * dt * dt);
}

/* C''' of an arc or clothoid at offset u, from its tangent t and curvature vector c2 (|c2|^2 = k2): a clothoid in
 * the plane (e1, e2) with curvature k = k0 + c u turns its normal N = c2 / k as N' = -k T, so C''' = c N - k^2 T; an
 * arc (a helix of radius R about n = e1 x e2) has C''' = -(|C''| / R) (T - (T.n) n) (-T / R^2 in the plane). */
static void vp_cstep_c3(const lsm_geom *g, double u, const double t[3], const double c2[3], double k2, double c3[3])
{
    if (g->kind == LSM_GEOM_CLOTHOID) {
        const lsm_geom_clothoid *c = &g->u.clo;
        const double k = (double)c->kappa0_per_mm + (double)c->c_per_mm2 * u;
        double nv[3];
        if (fabs(k) > 1e-9) {
            for (int i = 0; i < 3; i++)
                nv[i] = c2[i] / k;
        } else {
            const double th = (double)c->theta0_rad + u * ((double)c->kappa0_per_mm + 0.5 * (double)c->c_per_mm2 * u);
            for (int i = 0; i < 3; i++)
                nv[i] = -sin(th) * (double)c->e1[i] + cos(th) * (double)c->e2[i];
        }
        for (int i = 0; i < 3; i++)
            c3[i] = (double)c->c_per_mm2 * nv[i] - k2 * t[i];
        return;
    }
    const lsm_geom_arc *a = &g->u.arc;
    const double n[3] = {(double)(a->e1[1] * a->e2[2] - a->e1[2] * a->e2[1]),
                         (double)(a->e1[2] * a->e2[0] - a->e1[0] * a->e2[2]),
                         (double)(a->e1[0] * a->e2[1] - a->e1[1] * a->e2[0])};
    const double tn = t[0] * n[0] + t[1] * n[1] + t[2] * n[2], f = sqrt(k2) / (double)a->radius_mm;
    for (int i = 0; i < 3; i++)
        c3[i] = -f * (t[i] - tn * n[i]);
}

/* The segment as a polynomial in u: s = c0 + c1 u + c2 u² + c3 u³, c0 = (P0 + 4 P1 + P2) / 6, c1 = (P2 - P0) / 2,
 * c2 = (P0 - 2 P1 + P2) / 2, c3 = (P3 - 3 P2 + 3 P1 - P0) / 6 (the same curve as vp_bs_eval). */
typedef struct vp_bspoly {
    double c[4], dt;
} vp_bspoly;

static vp_bspoly vp_bs_poly(const double P[4], double dt)
{
    const vp_bspoly b = {{(P[0] + 4 * P[1] + P[2]) / 6, (P[2] - P[0]) / 2, (P[0] - 2 * P[1] + P[2]) / 2,
                          (P[3] - 3 * P[2] + 3 * P[1] - P[0]) / 6},
                         dt};
    return b;
}

static void vp_bs_poly_eval(const vp_bspoly *b, double u, double d[4])
{
    const double *c = b->c, dt = b->dt;
    d[0] = c[0] + u * (c[1] + u * (c[2] + u * c[3]));
    d[1] = (c[1] + u * (2 * c[2] + 3 * u * c[3])) / dt;
    d[2] = (2 * c[2] + 6 * u * c[3]) / (dt * dt);
    d[3] = 6 * c[3] / (dt * dt * dt);
}

/* The segment b where it passes path point x in [s(0), s(1)]: Newton on u from *u (the last point's u, or < 0: a
 * linear guess), kept inside a bracket that bisection narrows when a step leaves it (s is monotone in u, as the
 * samples are). *u: the answer. */
static void vp_bs_at(const vp_bspoly *b, double x, double *uio, double d[4])
{
    const double *c = b->c, s1 = c[0] + c[1] + c[2] + c[3];
    double lo = 0, hi = 1, u = *uio >= 0 ? *uio : s1 > c[0] ? fmin(1, fmax(0, (x - c[0]) / (s1 - c[0]))) : 0.5;
    for (int it = 0; it < 60; it++) {
        const double f = c[0] + u * (c[1] + u * (c[2] + u * c[3])) - x;
        if (fabs(f) <= 1e-15 * (1 + fabs(x)) || hi - lo < 1e-15)
            break;
        if (f < 0)
            lo = u;
        else
            hi = u;
        const double du = c[1] + u * (2 * c[2] + 3 * u * c[3]), nu = du > 0 ? u - f / du : -1;
        u = nu > lo && nu < hi ? nu : 0.5 * (lo + hi);
    }
    *uio = u;
    vp_bs_poly_eval(b, u, d);
}

/* The largest |q_i'| / V_i, |q_i''| / A_i, |q_i'''| / J_i over the constrained axes (into r[0..2], raised) of the
 * motion at offset x of block blk with s' s'' s''' = d[1..3] (eq 3, above). */
static void vp_cstep_ratio(const gpath *gp, const sim_vpop_limits *lim, size_t blk, double x, const double d[4],
                           double r[3])
{
    const lsm_geom *g = &gp->g[blk];
    const double len = (double)g->len, u = fmin(len, fmax(0, x));
    double t[LSM_MAX_AXES] = {0}, c2[LSM_MAX_AXES] = {0}, c3[LSM_MAX_AXES] = {0};
    if (g->kind == LSM_GEOM_LINE) {
        for (int i = 0; i < LSM_MAX_AXES; i++)
            t[i] = (double)g->u.line.dir[i];
    } else {
        lsm_real tr[3], cr[3];
        lsm_geom_eval(g, (lsm_real)u, NULL, tr, cr);
        double k2 = 0;
        for (int i = 0; i < 3; i++) {
            t[i] = (double)tr[i];
            c2[i] = (double)cr[i];
            k2 += c2[i] * c2[i];
        }
        vp_cstep_c3(g, u, t, c2, k2, c3);
    }
    const double v = d[1], a = d[2], j = d[3];
    for (int i = 0; i < SIM_VPOP_AXES; i++) {
        if (!(lim->axis_mask & (1u << i)))
            continue;
        const double rv = fabs(t[i] * v) / lim->v[i], ra = fabs(c2[i] * v * v + t[i] * a) / lim->a[i];
        const double rj = fabs(c3[i] * v * v * v + 3 * c2[i] * v * a + t[i] * j) / lim->j[i];
        r[0] = rv > r[0] ? rv : r[0];
        r[1] = ra > r[1] ? ra : r[1];
        r[2] = rj > r[2] ? rj : r[2];
    }
}

/* The block holding s, searched forward from block b (s >= its start). */
static size_t vp_block_from(const gpath *gp, size_t b, double s)
{
    while (b + 1 < gp->n && gp->s0[b + 1] <= s)
        b++;
    return b;
}

/* gp->cbound: per block, max |C''| and a bound of |C'''| (lines 0, 0; a clothoid with k = k0 + c u: max |k| at its
 * ends and |c| + k², since C''' = c N - k² T; an arc: |C''| and |C''| / R). Returns 0 without memory. */
static int vp_cstep_bounds(gpath *gp)
{
    gp->cbound = malloc(2 * gp->n * sizeof *gp->cbound);
    if (!gp->cbound)
        return 0;
    for (size_t k = 0; k < gp->n; k++) {
        const lsm_geom *g = &gp->g[k];
        double k2 = 0, k3 = 0;
        if (g->kind == LSM_GEOM_CLOTHOID) {
            const double c = (double)g->u.clo.c_per_mm2, k0 = (double)g->u.clo.kappa0_per_mm;
            k2 = fmax(fabs(k0), fabs(k0 + c * (double)g->len));
            k3 = fabs(c) + k2 * k2;
        } else if (g->kind == LSM_GEOM_ARC) {
            lsm_real tr[3], cr[3];
            lsm_geom_eval(g, 0, NULL, tr, cr);
            k2 = sqrt((double)(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]));
            k3 = k2 / (double)g->u.arc.radius_mm;
        }
        gp->cbound[2 * k] = k2 * (1 + 1e-12);
        gp->cbound[2 * k + 1] = k3 * (1 + 1e-12);
    }
    return 1;
}

/* A sufficient condition (no evaluation of the geometry): with |s'| <= the largest of the segment's three discrete
 * velocities, |s''| <= the larger of its two discrete accelerations (the B-spline's s' and s'' are convex
 * combinations of them), s''' its discrete jerk, |C'_i| <= 1 (|dir_i| on lines) and the largest |C''|, |C'''| of the
 * blocks over [P0, P3], eq 3 is bounded by |C'''| v³ + 3 |C''| v a + |C'_i| j per axis (and likewise v, a). */
static int vp_cstep_easy(const gpath *gp, const sim_vpop_limits *lim, double dt, const double P[4], size_t b0)
{
    const double vm = fmax(fabs(P[1] - P[0]), fmax(fabs(P[2] - P[1]), fabs(P[3] - P[2]))) / dt;
    const double am = fmax(fabs(P[0] - 2 * P[1] + P[2]), fabs(P[1] - 2 * P[2] + P[3])) / (dt * dt);
    const double jm = fabs(P[3] - 3 * P[2] + 3 * P[1] - P[0]) / (dt * dt * dt);
    double k2 = 0, k3 = 0, t[SIM_VPOP_AXES] = {0};
    for (size_t k = b0; k < gp->n && (k == b0 || gp->s0[k] <= P[3]); k++) {
        k2 = fmax(k2, gp->cbound[2 * k]);
        k3 = fmax(k3, gp->cbound[2 * k + 1]);
        for (int i = 0; i < SIM_VPOP_AXES; i++)
            t[i] = fmax(t[i], gp->g[k].kind == LSM_GEOM_LINE ? fabs((double)gp->g[k].u.line.dir[i]) : i < 3 ? 1 : 0);
    }
    for (int i = 0; i < SIM_VPOP_AXES; i++) {
        if (!(lim->axis_mask & (1u << i)))
            continue;
        if (t[i] * vm > lim->v[i] || k2 * vm * vm + t[i] * am > lim->a[i] ||
            k3 * vm * vm * vm + 3 * k2 * vm * am + t[i] * jm > lim->j[i])
            return 0;
    }
    return 1;
}

/* The largest of the three ratios (vp_cstep_ratio) at path point x of block k on the segment b (*u: vp_bs_at). */
static double vp_cstep_point(const gpath *gp, const sim_vpop_limits *lim, const vp_bspoly *b, size_t k, double x,
                             double *u)
{
    double d[4], r[3] = {0, 0, 0};
    vp_bs_at(b, x, u, d);
    vp_cstep_ratio(gp, lim, k, x - gp->s0[k], d, r);
    return fmax(r[0], fmax(r[1], r[2]));
}

/* The bound of vp_cstep_easy on one line block with direction dir: |dir_i| times the segment's largest discrete
 * velocity, acceleration and jerk of s (P) within the limits. */
static int vp_cstep_line_easy(const lsm_geom *g, const sim_vpop_limits *lim, double dt, const double P[4])
{
    const double vm = fmax(fabs(P[1] - P[0]), fmax(fabs(P[2] - P[1]), fabs(P[3] - P[2]))) / dt;
    const double am = fmax(fabs(P[0] - 2 * P[1] + P[2]), fabs(P[1] - 2 * P[2] + P[3])) / (dt * dt);
    const double jm = fabs(P[3] - 3 * P[2] + 3 * P[1] - P[0]) / (dt * dt * dt);
    for (int i = 0; i < SIM_VPOP_AXES; i++) {
        const double t = fabs((double)g->u.line.dir[i]);
        if ((lim->axis_mask & (1u << i)) && (t * vm > lim->v[i] || t * am > lim->a[i] || t * jm > lim->j[i]))
            return 0;
    }
    return 1;
}

/* Whether the segment with control points P holds the limits (checked as above, block by block over the path range
 * [s(0), s(1)] it covers: a line block whose bound (vp_cstep_line_easy) holds needs no point; any other block gets
 * its share of VP_CSTEP_POINTS by length, at least VP_CSTEP_BLOCK_POINTS inside it, and both ends of its part;
 * stops at the first point that fails). */
static int vp_cstep_segment(const gpath *gp, const sim_vpop_limits *lim, double dt, const double P[4])
{
    const size_t b0 = vp_block_at(gp, P[0]);
    if (gp->g[b0].kind == LSM_GEOM_LINE && vp_block_from(gp, b0, P[3]) == b0)
        return 1; /* implied by the discrete bounds (above) */
    if (gp->cbound && vp_cstep_easy(gp, lim, dt, P, b0))
        return 1;
    double e0[4], e1[4];
    const vp_bspoly bp = vp_bs_poly(P, dt);
    vp_bs_poly_eval(&bp, 0, e0);
    vp_bs_poly_eval(&bp, 1, e1);
    const double span = e1[0] - e0[0];
    for (size_t k = vp_block_from(gp, b0, e0[0]); k < gp->n && (gp->s0[k] < e1[0] || span <= 0); k++) {
        const lsm_geom *g = &gp->g[k];
        if (g->kind == LSM_GEOM_LINE && vp_cstep_line_easy(g, lim, dt, P)) {
            if (span <= 0)
                break;
            continue;
        }
        const double ka = fmax(gp->s0[k], e0[0]), kb = fmin(gp->s0[k] + (double)g->len, e1[0]);
        const int np = span > 0 ? (int)fmax(VP_CSTEP_BLOCK_POINTS, ceil(VP_CSTEP_POINTS * (kb - ka) / span)) : 0;
        double u = -1, xs[VP_CSTEP_POINTS + 2], worst = -1;
        int mw = 0;
        for (int m = 0; m <= np + 1; m++) { /* the part's ends and np points inside it */
            const double x = m == 0 ? ka : m > np ? kb : ka + (kb - ka) * (m - 0.5) / np;
            const double w = vp_cstep_point(gp, lim, &bp, k, x, &u);
            if (w > 1)
                return 0;
            xs[m] = x;
            if (w > worst) {
                worst = w;
                mw = m;
            }
            if (span <= 0)
                break;
        }
        if (span <= 0)
            break;
        /* the largest point's neighbourhood, by golden section: the peak between the points */
        double a = xs[mw > 0 ? mw - 1 : 0], b = xs[mw <= np ? mw + 1 : np + 1];
        for (int it = 0; it < VP_CSTEP_REFINE && b > a; it++) {
            const double x1 = b - 0.618033988749895 * (b - a), x2 = a + 0.618033988749895 * (b - a);
            double u1 = -1, u2 = -1;
            const double w1 = vp_cstep_point(gp, lim, &bp, k, x1, &u1), w2 = vp_cstep_point(gp, lim, &bp, k, x2, &u2);
            if (w1 > 1 || w2 > 1)
                return 0;
            if (w1 > w2)
                b = x2;
            else
                a = x1;
        }
    }
    return 1;
}

/* sim_vpop_path.step_cont of the continuous-limit reference. */
static int gpath_step_cont(void *ctx, const sim_vpop_limits *lim, double dt, const double s4[4])
{
    return vp_cstep_segment(ctx, lim, dt, s4);
}

/*
 * The independent check of a motion's continuous limits (run --json: continuous_ratio): the B-spline s(t) of the
 * samples (the model above) resampled VP_VERIFY_PER_CYCLE times per cycle, the axis positions there from the exact
 * geometry (lsm_geom_eval, no derivatives), and their backward differences over that fine step h: velocity,
 * acceleration and jerk over the limits (r[0..2]), largest over the whole motion. A jerk difference whose four points
 * are not all in one block is left out (where the curvature jumps at a junction the acceleration steps, and its
 * difference grows as 1 / h; the jerk on both sides is measured up to 3 h from the junction). For the jerk the
 * positions are taken relative to the block (its geometry moved to start at the origin, the offset into it computed
 * in long double from the control points relative to the block's start; lines evaluated in long double), so that
 * their rounding is not that of the coordinates or of s: about 8 eps (R + chord) / (J h³) on arcs and clothoids
 * (eps of double) and 8 eps_ld len / (J h³) on lines (eps_ld = 1.1e-19; below 1e-7).
 */
#define VP_VERIFY_PER_CYCLE 32

/* Position at path point P-spline u (control points P) of block blk: absolute (q) and relative to the block (qr). */
static void vp_verify_pos(const gpath *gp, const double P[4], double u, double dt, size_t *blk, double q[LSM_MAX_AXES],
                          long double qr[LSM_MAX_AXES])
{
    double d[4];
    vp_bs_eval(P, u, dt, d);
    const size_t lo = vp_block_at(gp, d[0]);
    /* the offset into the block, in long double from the control points relative to the block's start */
    const long double w = 1 - (long double)u, U = u;
    long double offl =
        (w * w * w * (P[0] - gp->s0[lo]) + (3 * U * U * U - 6 * U * U + 4) * (P[1] - gp->s0[lo]) +
         (-3 * U * U * U + 3 * U * U + 3 * U + 1) * (P[2] - gp->s0[lo]) + U * U * U * (P[3] - gp->s0[lo])) /
        6;
    offl = offl < 0 ? 0 : offl > (long double)gp->g[lo].len ? (long double)gp->g[lo].len : offl;
    const double off = (double)offl;
    lsm_real pos[LSM_MAX_AXES] = {0};
    pos[3] = (lsm_real)gp->rot[3 * lo];
    pos[4] = (lsm_real)gp->rot[3 * lo + 1];
    pos[5] = (lsm_real)gp->rot[3 * lo + 2];
    lsm_geom_eval(&gp->g[lo], (lsm_real)off, pos, NULL, NULL);
    lsm_geom g = gp->g[lo]; /* the block moved to the origin */
    if (g.kind == LSM_GEOM_LINE)
        memset(g.u.line.p0, 0, sizeof g.u.line.p0);
    else if (g.kind == LSM_GEOM_ARC)
        memset(g.u.arc.start_mm, 0, sizeof g.u.arc.start_mm);
    else
        memset(g.u.clo.origin_mm, 0, sizeof g.u.clo.origin_mm);
    lsm_real pr[LSM_MAX_AXES] = {0};
    lsm_geom_eval(&g, (lsm_real)off, pr, NULL, NULL);
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        q[i] = (double)pos[i];
        qr[i] = g.kind == LSM_GEOM_LINE ? (long double)g.u.line.dir[i] * offl : (long double)pr[i];
    }
    *blk = lo;
}

static void vp_cont_verify(const gpath *gp, const sim_vpop_limits *lim, const double *S, size_t n, double dt,
                           double r[3])
{
    r[0] = r[1] = r[2] = 0;
    if (n == 0)
        return;
    const double h = dt / VP_VERIFY_PER_CYCLE;
    double q[4][LSM_MAX_AXES]; /* [0] newest */
    long double qr[4][LSM_MAX_AXES];
    size_t blk[4];
    const double P0[4] = {0, 0, 0, 0};
    vp_verify_pos(gp, P0, 0, dt, &blk[1], q[1], qr[1]);
    for (int m = 2; m < 4; m++) {
        memcpy(q[m], q[1], sizeof q[1]);
        memcpy(qr[m], qr[1], sizeof qr[1]);
        blk[m] = blk[1];
    }
    const long last = ((long)n + 2) * VP_VERIFY_PER_CYCLE + 3; /* at rest on L from (n + 2) K on */
    for (long i = 1; i <= last; i++) {
        const long k = i / VP_VERIFY_PER_CYCLE;
        double P[4];
        for (int m = 0; m < 4; m++) {
            const long c = k - 3 + m;
            P[m] = c < 0 ? 0 : S[c >= (long)n ? (long)n - 1 : c];
        }
        vp_verify_pos(gp, P, (double)(i % VP_VERIFY_PER_CYCLE) / VP_VERIFY_PER_CYCLE, dt, &blk[0], q[0], qr[0]);
        for (int a = 0; a < SIM_VPOP_AXES; a++) {
            if (!(lim->axis_mask & (1u << a)))
                continue;
            r[0] = fmax(r[0], fabs(q[0][a] - q[1][a]) / h / lim->v[a]);
            r[1] = fmax(r[1], fabs(q[0][a] - 2 * q[1][a] + q[2][a]) / (h * h) / lim->a[a]);
            if (blk[0] == blk[3]) {
                const double rj =
                    (double)fabsl(qr[0][a] - 3 * qr[1][a] + 3 * qr[2][a] - qr[3][a]) / (h * h * h) / lim->j[a];
                if (rj > r[2] && getenv("VPOP_DEBUG") && rj > 1)
                    fprintf(stderr, "verify: j %.9f axis %d block %zu kind %d len %.6g k %ld\n", rj, a, blk[0],
                            gp->g[blk[0]].kind, (double)gp->g[blk[0]].len, k);
                r[2] = fmax(r[2], rj);
            }
        }
        memmove(q[1], q[0], 3 * sizeof q[0]);
        memmove(qr[1], qr[0], 3 * sizeof qr[0]);
        memmove(&blk[1], &blk[0], 3 * sizeof blk[0]);
    }
}

/* The Hermite table of the path (gpath). */
#define VP_TAB_STEP_MM 0.004         /* node spacing: the table is within 6e-10 mm of the exact clothoids */
#define VP_TAB_MAX_NODES 2e6         /* coarser steps on long paths, so that the table stays about 2e6 nodes */
#define VP_TAB_MAX_TURN_RAD 0.02     /* and at most this turning per interval (tiny, tight clothoids) */
#define VP_TAB_MAX_INTERVALS 1e6     /* per block */
#define VP_DEFAULT_MAX_TIME_S 3600.0 /* VPOp's motion is cut off after this (unless --max-time says otherwise) */

/* The program through the look-ahead planner (its geometry: lines, arcs, corner clothoids; VPOp then plans the
 * motion along it). Returns 0, or -1 with r->err set. */
static int vp_plan_geometry(lsm_planner *pl, const lsm_planner_config *cfg, lsm_pblock *store, uint32_t cap,
                            const lsm_real start[LSM_MAX_AXES], const sim_prog *p, sim_run_result *r)
{
    lsm_status st = lsm_planner_init(pl, cfg, store, cap, start);
    if (st != LSM_OK) {
        snprintf(r->err, sizeof r->err, "planner init: %s", lsm_status_str(st));
        return -1;
    }
    for (size_t i = 0; i < p->n; i++) {
        st = append_block(pl, &p->v[i]);
        if (st != LSM_OK && st != LSM_E_ZERO_LENGTH) {
            snprintf(r->err, sizeof r->err, "G-code line %u: planner: %s", (unsigned)p->v[i].b.line,
                     lsm_status_str(st));
            return -1;
        }
    }
    if (lsm_planner_finish(pl) != LSM_OK) {
        snprintf(r->err, sizeof r->err, "planner: cannot finish");
        return -1;
    }
    return 0;
}

/* Measurement only: with LISSOM_DUMP_BLOCKS=FILE in the environment, the blocks VPOp runs on (the planner's
 * geometry) go to FILE as CSV: index, start s, length, kind, the curvature at both ends, the clothoid's sharpness,
 * the block's geometric cap and flags (docs/planner.md, "Where the trident loses its time"). */
static void vp_dump_blocks(const gpath *gp, const lsm_planner *pl)
{
    const char *fn = getenv("LISSOM_DUMP_BLOCKS");
    FILE *f = fn ? fopen(fn, "w") : NULL;
    if (!f)
        return;
    fprintf(f, "k,s0,len,kind,k0,k1,c,cap_geo,feed,flags\n");
    for (size_t k = 0; k < gp->n; k++) {
        const lsm_pblock *b = lsm_planner_block(pl, pl->head + (uint32_t)k);
        const lsm_geom *g = &b->g;
        double k0 = 0, k1 = 0, c = 0;
        if (g->kind == LSM_GEOM_ARC)
            k0 = k1 = 1.0 / g->u.arc.radius_mm;
        else if (g->kind == LSM_GEOM_CLOTHOID) {
            k0 = g->u.clo.kappa0_per_mm;
            c = g->u.clo.c_per_mm2;
            k1 = k0 + c * g->len;
        }
        fprintf(f, "%zu,%.9g,%.9g,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%u\n", k, gp->s0[k], (double)g->len, (int)g->kind, k0, k1,
                c, (double)b->cap_geo_mm_s, (double)b->feed_mm_s, (unsigned)b->flags);
    }
    fclose(f);
}

/* The planner's blocks into gp: geometry, cumulative starts, A B C at each start, feeds, and the stops. */
static int vp_gpath_fill(gpath *gp, const lsm_planner *pl, const lsm_real start[LSM_MAX_AXES])
{
    double rot[3] = {start[3], start[4], start[5]};
    for (uint32_t id = pl->head; id != pl->tail; id++) {
        const lsm_pblock *b = lsm_planner_block(pl, id);
        const size_t k = gp->n++;
        gp->g[k] = b->g;
        gp->s0[k] = gp->len;
        if (b->g.kind == LSM_GEOM_LINE)
            for (int a = 0; a < 3; a++)
                rot[a] = b->g.u.line.p0[3 + a];
        memcpy(&gp->rot[3 * k], rot, sizeof rot);
        if (b->g.kind == LSM_GEOM_LINE)
            for (int a = 0; a < 3; a++)
                rot[a] = b->g.u.line.p0[3 + a] + b->g.u.line.dir[3 + a] * b->g.len;
        gp->feed[k] = (b->flags & LSM_PB_RAPID) ? (double)INFINITY : b->feed_mm_s;
        gp->len += b->g.len;
    }
    gp->s0[gp->n] = gp->len;
    vp_dump_blocks(gp, pl);
    gp->stops = calloc(gp->n + 1, sizeof *gp->stops);
    if (!gp->stops)
        return -1;
    for (size_t k = 1; k < gp->n; k++)
        if (lsm_planner_block(pl, pl->head + (uint32_t)k)->flags & LSM_PB_STOP)
            gp->stops[gp->n_stops++] = gp->s0[k];
    return 0;
}

/* The Hermite table (gpath): intervals of about VP_TAB_STEP_MM in every block, turning at most VP_TAB_MAX_TURN_RAD.
 * Without memory for it, gp evaluates exactly (slower). */
static void vp_gpath_table(gpath *gp)
{
    const double ds = fmax(VP_TAB_STEP_MM, gp->len / VP_TAB_MAX_NODES);
    size_t nodes = 0;
    gp->tab_off = malloc(gp->n * sizeof *gp->tab_off);
    gp->tab_m = malloc(gp->n * sizeof *gp->tab_m);
    if (gp->tab_off && gp->tab_m) {
        for (size_t k = 0; k < gp->n; k++) {
            double kmax = 0;
            for (int e = 0; e <= 2; e++) {
                lsm_real pos[LSM_MAX_AXES] = {0}, t[LSM_MAX_AXES] = {0}, cv[LSM_MAX_AXES] = {0};
                lsm_geom_eval(&gp->g[k], gp->g[k].len * 0.5 * e, pos, t, cv);
                kmax = fmax(kmax, sqrt(cv[0] * cv[0] + cv[1] * cv[1] + cv[2] * cv[2]));
            }
            const double m = fmin(VP_TAB_MAX_INTERVALS,
                                  fmax(ceil(gp->g[k].len / ds), ceil(gp->g[k].len * kmax / VP_TAB_MAX_TURN_RAD)));
            gp->tab_m[k] = m < 1 ? 1u : (uint32_t)m;
            gp->tab_off[k] = nodes;
            nodes += gp->tab_m[k] + 1;
        }
        gp->tab = malloc(nodes * 6 * sizeof(double));
    }
    if (!gp->tab) {
        free(gp->tab_off);
        free(gp->tab_m);
        gp->tab_off = NULL;
        gp->tab_m = NULL; /* exact evaluation (slower) */
        return;
    }
    for (size_t k = 0; k < gp->n; k++) {
        for (uint32_t i = 0; i <= gp->tab_m[k]; i++) {
            lsm_real pos[LSM_MAX_AXES] = {0}, t[LSM_MAX_AXES] = {0};
            const double u = i == gp->tab_m[k] ? gp->g[k].len : gp->g[k].len * i / gp->tab_m[k];
            lsm_geom_eval(&gp->g[k], u, pos, t, NULL);
            double *row = gp->tab + 6 * (gp->tab_off[k] + i);
            for (int a = 0; a < 3; a++) {
                row[a] = pos[a];
                row[3 + a] = t[a];
            }
        }
    }
}

/* VPOp's motion along the path: the faster of the two switching rules (vpop.h: refine_iters; neither is always
 * faster). The samples in *S (malloc'd; NULL if neither found one), their count in *n. */
static void vp_best_motion(const sim_run_opts *o, const sim_vpop_path *path, sim_vpop_limits *lim, double cycle_s,
                           double **S, size_t *n)
{
    const double max_t = o->max_time_s > 0 ? o->max_time_s : VP_DEFAULT_MAX_TIME_S;
    sim_vpop_stats vs;
    *S = NULL;
    *n = 0;
    for (int pass = 0; pass < 2; pass++) {
        lim->refine_iters = pass ? SIM_VPOP_REFINE : 0;
        if (o->progress)
            o->progress(o->progress_ctx, SIM_RUN_PHASE_PLAN, 0.5 * pass, -1);
        double *S2 = NULL;
        size_t n2 = 0;
        if (sim_vpop_plan(path, lim, cycle_s, (size_t)(max_t / cycle_s), &S2, &n2, &vs) != 0)
            continue;
        if (!*S || n2 < *n) {
            free(*S);
            *S = S2;
            *n = n2;
        } else {
            free(S2);
        }
    }
}

/* The samples as setpoints (the last one exactly the programmed end), with feed and block sequence number. */
static int vp_record(gpath *gp, const lsm_planner *pl, const double *S, size_t n, double cycle_s, rec *out,
                     sim_run_result *r)
{
    double prev = 0;
    for (size_t k = 0; k < n; k++) {
        double q[SIM_VPOP_AXES];
        gpath_eval(gp, S[k], q);
        if (k + 1 == n)
            for (int i = 0; i < LSM_MAX_AXES; i++)
                q[i] = pl->tail_pos[i]; /* the end, exactly */
        const size_t lo = vp_block_at(gp, S[k]);
        const lsm_pblock *b = lsm_planner_block(pl, pl->head + (uint32_t)lo);
        if (rec_push(out, q, (S[k] - prev) / cycle_s, b ? b->seq : 0) != 0) {
            snprintf(r->err, sizeof r->err, "out of memory");
            return -1;
        }
        prev = S[k];
    }
    return 0;
}

static int run_vpop(const sim_run_opts *o, const sim_prog *p, rec *out, sim_run_result *r)
{
    lsm_planner_config cfg;
    if (o->cfg_override)
        cfg = *o->cfg_override;
    else
        sim_run_planner_config(o->machine, &cfg);
    const uint32_t cap = (uint32_t)(4 * p->total + 64);
    lsm_pblock *store = calloc(cap, sizeof *store);
    lsm_planner *pl = calloc(1, sizeof *pl);
    gpath gp = {0};
    gp.g = calloc(cap, sizeof *gp.g);
    gp.s0 = calloc(cap + 1, sizeof *gp.s0);
    gp.rot = calloc(3 * (size_t)cap, sizeof *gp.rot);
    gp.feed = calloc(cap, sizeof *gp.feed);
    for (int i = 0; i < o->machine->n_axes; i++)
        if (o->machine->axes[i].index >= 3)
            gp.has_rot = 1;
    int rc = -1;
    double *S = NULL;
    if (!store || !pl || !gp.g || !gp.s0 || !gp.rot || !gp.feed) {
        snprintf(r->err, sizeof r->err, "out of memory");
        goto done;
    }
    lsm_real start[LSM_MAX_AXES];
    for (int i = 0; i < LSM_MAX_AXES; i++)
        start[i] = (lsm_real)p->start[i];
    if (vp_plan_geometry(pl, &cfg, store, cap, start, p, r) != 0)
        goto done;
    if (vp_gpath_fill(&gp, pl, start) != 0) {
        snprintf(r->err, sizeof r->err, "out of memory");
        goto done;
    }
    vp_gpath_table(&gp);
    sim_vpop_path path = {gp.len, gpath_eval, gpath_feed, &gp, gpath_eval_d, gpath_next_stop, NULL};
    if (o->planner == SIM_RUN_VPOP_CONT) {
        path.step_cont = gpath_step_cont;
        (void)vp_cstep_bounds(&gp); /* (without memory: every segment is sampled) */
    }
    sim_vpop_limits lim;
    memset(&lim, 0, sizeof lim);
    for (int i = 0; i < o->machine->n_axes; i++) {
        const sim_machine_axis *ax = &o->machine->axes[i];
        lim.axis_mask |= (uint8_t)(1u << ax->index);
        lim.v[ax->index] = ax->v_max_u_s;
        lim.a[ax->index] = ax->a_max_u_s2;
        lim.j[ax->index] = ax->j_max_u_s3;
    }
    size_t n = 0;
    const double t0 = now_ns();
    vp_best_motion(o, &path, &lim, cfg.cycle_s, &S, &n);
    if (!S) {
        snprintf(r->err, sizeof r->err, "vpop: no motion found");
        goto done;
    }
    r->interp_ns_per_cycle = n ? (now_ns() - t0) / (double)n : 0;
    if (vp_record(&gp, pl, S, n, cfg.cycle_s, out, r) != 0)
        goto done;
    vpop_intersample(&gp, &lim, S, n, cfg.cycle_s, r);
    vp_cont_verify(&gp, &lim, S, n, cfg.cycle_s, r->cont_ratio);
    r->cycles = n;
    r->duration_s = (double)n * cfg.cycle_s;
    r->stats = pl->stats;
    rc = 0;
done:
    free(S);
    free(store);
    free(pl);
    free(gp.g);
    free(gp.s0);
    free(gp.rot);
    free(gp.feed);
    free(gp.tab);
    free(gp.stops);
    free(gp.tab_off);
    free(gp.tab_m);
    free(gp.cbound);
    return rc;
}

int sim_run_program(const sim_run_opts *o, sim_run_result *r)
{
    memset(r, 0, sizeof *r);
    r->pl_block_bytes = (uint32_t)sizeof(lsm_pblock);
    r->intersample_jerk_max = r->intersample_jerk_p99 = -1;
    r->cont_ratio[0] = r->cont_ratio[1] = r->cont_ratio[2] = -1;
    const sim_machine *m = o->machine;
    r->cycle_s = m->cycle_s;
    r->n_axes = m->n_axes;
    for (int i = 0; i < m->n_axes; i++) {
        r->axis_index[i] = m->axes[i].index;
        r->axis_name[i] = m->axes[i].name;
    }
    /* constant memory where nothing is kept for later: the Lissom run measured as it goes */
    const bool windowed = o->summary_only && o->planner == SIM_RUN_LISSOM;
    sim_prog p;
    if (sim_prog_open(&p, o->text, o->len, o->path, windowed, o->machine->axis_mask, o->machine->blend_tol_mm, r->err,
                      sizeof r->err) != 0)
        return -1;
    memcpy(r->prog_end, p.end, sizeof r->prog_end);
    memcpy(r->start, p.start, sizeof r->start);
    r->prog_blocks = p.total;
    r->prog_length_mm = p.length_mm;

    meter mt;
    meter_init(&mt, &p, m, r, o->summary_only && o->drives);
    if (mt.drives) { /* the drives' parameters are checked before the run (they start on the first setpoint) */
        for (int i = 0; i < m->n_axes; i++) {
            lsm_status st = sim_drive_init(&mt.drv[i], &m->axes[i].drive, m->cycle_s, 0.0);
            if (st != LSM_OK) {
                snprintf(r->err, sizeof r->err, "drive %c: %s", m->axes[i].name, lsm_status_str(st));
                sim_prog_free(&p);
                return -1;
            }
        }
    }
    rec out = {0};
    out.stream = o->summary_only ? &mt : NULL;
    int rc;
    if (o->planner != SIM_RUN_LISSOM)
        rc = run_vpop(o, &p, &out, r);
    else
        rc = run_lissom(o, &p, &out, r);
    r->mfuncs = p.ev; /* the result owns the machine functions from here */
    r->n_mfuncs = p.n_ev;
    p.ev = NULL;
    p.n_ev = 0;
    for (size_t i = 0; i < r->n_mfuncs && rc == 0 && o->planner == SIM_RUN_LISSOM; i++)
        if (r->mfuncs[i].ev.kind == LSM_GCODE_EV_END)
            r->mfuncs[i].t_s = r->duration_s;
    if (rc != 0) {
        free(out.q);
        free(out.feed);
        free(out.line);
        sim_prog_free(&p);
        return rc;
    }
    r->n = o->summary_only ? 0 : out.n;
    r->q = out.q;
    r->feed = out.feed;
    r->line = out.line;
    r->has_act = o->drives && mt.n + r->n > 0; /* (as act != NULL when the setpoints are kept) */
    r->prog_held_max = p.held_max;
    if (!o->summary_only) /* measured now, else while it ran */
        for (size_t k = 0; k < r->n; k++)
            meter_push(&mt, r->q + k * LSM_MAX_AXES, r->line[k]);
    meter_finish(&mt);
    if (mt.window_misses) {
        snprintf(r->err, sizeof r->err, "internal: %zu deviations needed path elements no longer held",
                 mt.window_misses);
        sim_prog_free(&p);
        return -1;
    }
    if (o->summary_only) {
        sim_prog_free(&p);
        return 0;
    }
    /* drives */
    const double dt = m->cycle_s;
    if (o->drives && r->n) {
        r->act = calloc(r->n * LSM_MAX_AXES, sizeof *r->act);
        if (!r->act) {
            snprintf(r->err, sizeof r->err, "out of memory");
            sim_prog_free(&p);
            return -1;
        }
        for (int i = 0; i < m->n_axes; i++) {
            const int a = m->axes[i].index;
            sim_drive d;
            lsm_status st = sim_drive_init(&d, &m->axes[i].drive, dt, r->q[a]);
            if (st != LSM_OK) {
                snprintf(r->err, sizeof r->err, "drive %c: %s", m->axes[i].name, lsm_status_str(st));
                sim_prog_free(&p);
                return -1;
            }
            double q1 = p.total ? p.start[a] : r->q[a], q2 = q1;
            for (size_t k = 0; k < r->n; k++) {
                const double q0 = r->q[k * LSM_MAX_AXES + a];
                const double v = (q0 - q1) / dt, acc = (q0 - 2 * q1 + q2) / (dt * dt);
                double act;
                sim_drive_step_ff(&d, q0, v, acc, &act);
                r->act[k * LSM_MAX_AXES + a] = act;
                const double fe = fabs(q0 - act);
                if (fe > r->max_follow_err[a])
                    r->max_follow_err[a] = fe;
                q2 = q1;
                q1 = q0;
                if (o->progress && (k & 0xFFF) == 0)
                    o->progress(o->progress_ctx, SIM_RUN_PHASE_DRIVES, (i + (double)k / (double)r->n) / m->n_axes,
                                (double)k * dt);
            }
        }
    }
    sim_prog_free(&p);
    return 0;
}

void sim_run_free(sim_run_result *r)
{
    free(r->q);
    free(r->feed);
    free(r->line);
    free(r->act);
    free(r->mfuncs);
    r->mfuncs = NULL;
    r->n_mfuncs = 0;
    r->q = r->feed = r->act = NULL;
    r->line = NULL;
}
