/*
 * fz_measure.h: with FZ_MEASURE=1 in the environment, the float build of a path fuzz target (fz_path.h) measures
 * its float noise and prints one line "FZ_MEASURE ..." at the end of a run (scripts/fuzz_float_noise.py reads it):
 *   excess   per difference order n = 1, 2, 3, the largest excess of |D_n q| over L_n dt^n (1 + 1e-6), in units
 *            of 2^n u, u = FLT_EPSILON x span (span: the largest |coordinate| seen): the position error, in u, that
 *            a noise of the setpoints must have to explain it (0: none over the limit);
 *   geom     the largest |q - q*| / u, q* the exact curve of the float block at the float cursor: lines
 *            p0 + dir s, arcs p0 + chord(aw s) + n axial s / len + (E - p(len)) s / len (aw = sweep / len rounded
 *            to float, the phase rate the interpolator runs the arc at, and the end correction it applies,
 *            interp.h), both evaluated in double from the float parameters; s = off_mm + off_lo_mm in double.
 *            Clothoids are not measured;
 *   travel   the largest |s - s*| / u along the path: s the cursor's distance from the piece's start (off_mm +
 *            off_lo_mm, over the blocks between), s* = (1 + ds_stretch) x the piece's travel at the exact time of the sample,
 *            evaluated in double from the float piece (the closed forms of interp.h, with sin). The time is the
 *            piece's clock at its first sample (sum of the phases before + tau, then small) plus k dt exactly.
 * The position error against the exact curve at the exact time is at most geom + travel (a unit tangent).
 *   keff     per order n, the largest |D_n e| / (2^n u), e = q - q*(t) the setpoint's error against the exact curve
 *            (lines, arcs) at the exact travel of the sample's time: the share of the setpoint noise in the n-th
 *            difference, as the K of a noise of K u (|D_n e| <= 2^n max|e|). A smooth drift of e (a float time
 *            scale, an arc's phase rate rounded) adds nothing here, unlike in geom and travel.
 * Test-only (reads the interpolator's and planner's state); nothing in the double build.
 */
#ifndef FZ_MEASURE_H
#define FZ_MEASURE_H

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "interp.h"
#include "planner.h"

typedef struct fz_meas {
    int on; /* -1 unknown, 0 off, 1 on */
    double excess[3];
    double ratio[3];
    long ex_cycle[3];
    int ex_axis[3];
    double geom;
    int geom_kind;
    double travel;
    double e[4][3]; /* q - q* of the last samples (e[0] the newest) */
    int ne;         /* how many consecutive samples have e */
    double keff[3]; /* the largest |D_n e| / (2^n u): the noise's own share of the n-th difference, in u */
    uint32_t serial;
    int running;
    double t_piece; /* the piece's clock at the last sample (exact: the first sample's + k dt) */
    long cycles;
} fz_meas;

#if LSM_REAL_IS_FLOAT
static void fz_meas_exact_end(const lsm_planner *pl, uint32_t id, double e[3])
{
    const lsm_pblock *n = id + 1u != pl->tail ? lsm_planner_block(pl, id + 1u) : NULL;
    for (int i = 0; i < 3; i++) {
        if (n == NULL)
            e[i] = (double)pl->tail_pos[i];
        else if (n->g.kind == LSM_GEOM_LINE)
            e[i] = (double)n->g.u.line.p0[i];
        else if (n->g.kind == LSM_GEOM_ARC)
            e[i] = (double)n->g.u.arc.start_mm[i];
        else
            e[i] = (double)n->g.u.clo.origin_mm[i];
    }
}

static void fz_meas_arc(const lsm_geom *g, double s, double p[3])
{
    const lsm_geom_arc *a = &g->u.arc;
    const lsm_real awf = a->sweep_rad / g->len; /* the phase rate of the cycle's evaluation (interp.c) */
    const double len = (double)g->len, dphi = (double)awf * s, h = 0.5 * dphi;
    const double k = 2.0 * (double)a->radius_mm * sin(h), sm = sin((double)a->phi0_rad + h),
                 cm = cos((double)a->phi0_rad + h);
    const double e1[3] = {a->e1[0], a->e1[1], a->e1[2]}, e2[3] = {a->e2[0], a->e2[1], a->e2[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    for (int i = 0; i < 3; i++)
        p[i] = (double)a->start_mm[i] + k * (cm * e2[i] - sm * e1[i]) + n[i] * (double)a->axial_mm * s / len;
}
#endif

#if LSM_REAL_IS_FLOAT
/* The exact curve of block id at offset s (lines and arcs, as for geom above); 0 for a clothoid or a released block. */
static int fz_meas_exact_pos(const lsm_planner *pl, uint32_t id, double s, double p[3])
{
    const lsm_pblock *b = lsm_planner_block(pl, id);
    if (b == NULL)
        return 0;
    if (b->g.kind == LSM_GEOM_LINE) {
        for (int i = 0; i < 3; i++)
            p[i] = (double)b->g.u.line.p0[i] + (double)b->g.u.line.dir[i] * s;
        return 1;
    }
    if (b->g.kind != LSM_GEOM_ARC)
        return 0;
    double pe[3], e[3];
    const double len = (double)b->g.len;
    fz_meas_arc(&b->g, len, pe);
    fz_meas_exact_end(pl, id, e);
    fz_meas_arc(&b->g, s, p);
    for (int i = 0; i < 3; i++)
        p[i] += (e[i] - pe[i]) * s / len;
    return 1;
}

/* The travel of piece pc's phase k at time t into it (the closed forms of interp.h, in double). */
static double fz_meas_phase(const lsm_piece *pc, int k, double t)
{
    const lsm_piece_phase *ph = &pc->ph[k];
    const double v0 = pc->st[k].v_mm_s, a0 = pc->st[k].a_mm_s2, T = ph->T_s, J = ph->jerk_mm_s3;
    double s = v0 * t;
    if (k == 0 || k == 8 || k == 16)
        return s;
    double f = t * t * t / 6;
    if (ph->shape != LSM_PHASE_CONST) {
        const double sg = ph->shape == LSM_PHASE_RISE ? 1 : -1, pi = 3.14159265358979323846;
        f = t * t * t / 12 - sg * t * T * T / (2 * pi * pi) + sg * sin(pi * t / T) * T * T * T / (2 * pi * pi * pi);
    }
    return s + a0 * t * t / 2 + J * f;
}

/* The travel of piece pc at time t into its phase k, from the piece's start: the phases before, each its closed form
 * at its end (as interp.c's phase_len), and phase k's. */
static double fz_meas_travel(const lsm_piece *pc, int k, double t)
{
    double s = fz_meas_phase(pc, k, t);
    for (int q = 0; q < k; q++)
        s += fz_meas_phase(pc, q, (double)pc->ph[q].T_s);
    return s;
}
#endif

#if LSM_REAL_IS_FLOAT
/* Shifts the error history (e[0] the newest, just written when have) and takes the differences of the error. */
static void fz_meas_noise(fz_meas *ms, int have, double u)
{
    ms->ne = have ? ms->ne + 1 : 0;
    if (ms->ne >= 4) {
        for (int i = 0; i < 3; i++) {
            const double *e0 = &ms->e[0][i];
            const double d[3] = {fabs(e0[0] - e0[3]), fabs(e0[0] - 2 * e0[3] + e0[6]),
                                 fabs(e0[0] - 3 * e0[3] + 3 * e0[6] - e0[9])};
            for (int n = 0; n < 3; n++) {
                const double k = d[n] / (ldexp(1.0, n + 1) * u);
                if (k > ms->keff[n])
                    ms->keff[n] = k;
            }
        }
    }
    memmove(&ms->e[1], &ms->e[0], 3 * sizeof ms->e[0]);
}
#endif

static void fz_measure_step(fz_meas *ms, const lsm_interp *ip, const lsm_planner *pl, const double q[4][3], double span,
                            double dt, const double *vl, const double *al, const double *jl)
{
    if (ms->on < 0) {
        const char *e = getenv("FZ_MEASURE");
        ms->on = e && *e && *e != '0';
    }
    if (!ms->on || !LSM_REAL_IS_FLOAT)
        return;
#if LSM_REAL_IS_FLOAT
    ms->cycles++;
    const double u = FLT_EPSILON * span;
    const char *tr = getenv("FZ_TRACE"); /* FZ_TRACE=c0:c1 prints the cycles c0 .. c1 */
    if (tr) {
        long c0 = 0, c1 = 0;
        if (sscanf(tr, "%ld:%ld", &c0, &c1) == 2 && ms->cycles >= c0 && ms->cycles <= c1)
            fprintf(stderr, "T %ld q %.9g %.9g %.9g blk %u off %.9g lo %.3g ph %u tau %.9g v %.9g ser %u\n", ms->cycles,
                    q[0][0], q[0][1], q[0][2], (unsigned)ip->blk, (double)ip->off_mm, (double)ip->off_lo_mm,
                    (unsigned)ip->phase, (double)ip->tau, (double)ip->v_mm_s, (unsigned)ip->serial);
        if (sscanf(tr, "%ld:%ld", &c0, &c1) == 2 && ms->cycles >= c0 && ms->cycles <= c1 && ip->serial != ms->serial) {
            const lsm_piece *pc = &ip->pcs[ip->cur];
            fprintf(stderr, "  piece blk %u off %.9g len %.9g sum %.9g v0 %g v1 %g end_blk %u stop %u scale %.9g\n",
                    (unsigned)pc->blk, (double)pc->off_mm, (double)pc->len_mm,
                    (double)pc->st[LSM_PIECE_PHASES - 1].s_mm + (double)pc->ph[LSM_PIECE_PHASES - 1].len_mm,
                    (double)pc->v0_mm_s, (double)pc->v1_mm_s, (unsigned)pc->end_blk, (unsigned)pc->stop,
                    1.0 + (double)ip->ds_stretch);
            for (int ph = 0; ph < LSM_PIECE_PHASES; ph++) {
                const double T = pc->ph[ph].T_s, v0 = pc->st[ph].v_mm_s, a0 = pc->st[ph].a_mm_s2;
                double J = pc->ph[ph].jerk_mm_s3;
                double f;
                if (ph == 0 || ph == 8 || ph == 16)
                    f = 0, J = 0;
                else if (pc->ph[ph].shape == LSM_PHASE_CONST)
                    f = T * T * T / 6;
                else
                    f = T * T * T / 12 -
                        (pc->ph[ph].shape == LSM_PHASE_RISE ? 1 : -1) * T * T * T / (2 * LSM_PI * LSM_PI);
                const double se = v0 * T + a0 * T * T / 2 + J * f;
                if (T > 0)
                    fprintf(stderr, "   ph %d T %.9g n %u len %.9g eval %.9g diff %.3g s %.9g v %.9g a %.9g j %.9g\n",
                            ph, T, (unsigned)pc->ph[ph].n_cycles, (double)pc->ph[ph].len_mm, se, se - pc->ph[ph].len_mm,
                            (double)pc->st[ph].s_mm, v0, a0, J);
            }
            for (uint32_t k = ip->blk > 2 ? ip->blk - 2 : 0; k <= ip->blk + 1; k++) {
                const lsm_pblock *bb = lsm_planner_block(pl, k);
                if (bb)
                    fprintf(stderr, "  blk %u kind %d len %.9g cap %.6g\n", (unsigned)k, bb->g.kind, (double)bb->g.len,
                            (double)bb->cap_geo_mm_s);
            }
        }
    }
    if (ms->cycles >= 4) {
        for (int a = 0; a < 3; a++) {
            const double d[3] = {fabs(q[0][a] - q[1][a]), fabs(q[0][a] - 2 * q[1][a] + q[2][a]),
                                 fabs(q[0][a] - 3 * q[1][a] + 3 * q[2][a] - q[3][a])};
            const double L[3] = {vl[a] * dt, al[a] * dt * dt, jl[a] * dt * dt * dt};
            for (int n = 0; n < 3; n++) {
                const double lim = L[n] * (1 + 1e-6), ex = (d[n] - lim) / (ldexp(1.0, n + 1) * u);
                if (d[n] / L[n] > ms->ratio[n])
                    ms->ratio[n] = d[n] / L[n];
                if (ex > ms->excess[n]) {
                    ms->excess[n] = ex;
                    ms->ex_cycle[n] = ms->cycles;
                    ms->ex_axis[n] = a;
                }
            }
        }
    }
    /* the geometry at the cursor */
    const lsm_pblock *b = lsm_planner_block(pl, ip->blk);
    double p[3];
    if (b != NULL && ip->act_ok && ip->act_blk == ip->blk &&
        fz_meas_exact_pos(pl, ip->blk, (double)ip->off_mm + (double)ip->off_lo_mm, p)) {
        for (int i = 0; i < 3; i++) {
            const double err = fabs((double)ip->pos[i] - p[i]) / u;
            if (err > ms->geom) {
                ms->geom = err;
                ms->geom_kind = b->g.kind;
            }
        }
    }
    /* the travel along the piece */
    if (ip->running && ip->phase < LSM_PIECE_PHASES) {
        const lsm_piece *pc = &ip->pcs[ip->cur];
        if (ms->running && ms->serial == ip->serial) {
            ms->t_piece += (double)(lsm_real)dt; /* the float build's cycle (its rounding is a time scale, not noise) */
        } else {
            ms->t_piece = (double)ip->tau;
            for (int k = 0; k < ip->phase; k++)
                ms->t_piece += (double)pc->ph[k].T_s;
        }
        double t = ms->t_piece, sx = 0;
        int k = 0;
        while (k < LSM_PIECE_PHASES - 1 && t > (double)pc->ph[k].T_s) {
            t -= (double)pc->ph[k].T_s;
            k++;
        }
        sx = fz_meas_travel(pc, k, t);
        double sc = 0; /* the cursor from the piece's start */
        int ok = 1;
        for (uint32_t id = pc->blk; id != ip->blk && ok; id++) {
            const lsm_pblock *bb = lsm_planner_block(pl, id);
            ok = bb != NULL && id - pc->blk < 64u;
            if (ok)
                sc += (double)bb->g.len;
        }
        sc += (double)ip->off_mm + (double)ip->off_lo_mm - (double)pc->off_mm;
        int have = 0;
        if (ok) {
            const double sx_path = (1.0 + (double)ip->ds_stretch) * sx;
            const double err = fabs(sc - sx_path) / u;
            if (err > ms->travel)
                ms->travel = err;
            /* the exact curve at the exact time: the block and offset sx_path from the piece's start */
            double o = (double)pc->off_mm + sx_path;
            uint32_t id = pc->blk;
            const lsm_pblock *bb = lsm_planner_block(pl, id);
            while (bb != NULL && o > (double)bb->g.len && id + 1u != pl->tail && id - pc->blk < 64u) {
                o -= (double)bb->g.len;
                bb = lsm_planner_block(pl, ++id);
            }
            double qx[3];
            if (bb != NULL && fz_meas_exact_pos(pl, id, o, qx)) {
                have = 1;
                for (int i = 0; i < 3; i++)
                    ms->e[0][i] = q[0][i] - qx[i];
            }
        }
        fz_meas_noise(ms, have, u);
    } else {
        fz_meas_noise(ms, 0, u);
    }
    ms->running = ip->running;
    ms->serial = ip->serial;
#else
    (void)ip;
    (void)pl;
    (void)q;
    (void)span;
    (void)dt;
    (void)vl;
    (void)al;
    (void)jl;
#endif
}

static void fz_measure_report(const fz_meas *ms, const char *machine, double span)
{
    if (ms->on != 1)
        return;
    fprintf(stderr,
            "FZ_MEASURE machine %s span %.6g ex1 %.3g ex2 %.3g ex3 %.3g ratio1 %.6g ratio2 %.6g ratio3 %.6g "
            "ex3_cycle %ld ex3_axis %d geom %.3g geom_kind %d travel %.3g keff1 %.3g keff2 %.3g keff3 %.3g\n",
            machine, span, ms->excess[0], ms->excess[1], ms->excess[2], ms->ratio[0], ms->ratio[1], ms->ratio[2],
            ms->ex_cycle[2], ms->ex_axis[2], ms->geom, ms->geom_kind, ms->travel, ms->keff[0], ms->keff[1],
            ms->keff[2]);
}

#endif
