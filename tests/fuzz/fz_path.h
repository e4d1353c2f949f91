/*
 * fz_path.h: the checks shared by the fuzz targets that run a path (fuzz_gcode_path, fuzz_planner), in the
 * double or the float build of the core (lsm_real). Header-only, included by one target source.
 *
 * A run appends blocks to the planner while the interpolator steps one cycle at a time (streaming, a small
 * look-ahead, so the buffer wraps), and checks each setpoint as it comes:
 *   nan       every setpoint is finite;
 *   limit     per axis, |dq|/dt, |d²q|/dt², |d³q|/dt³ (backward differences from rest, Beudaert eq 6) within
 *             1e-6 relative of the axis limit, plus in float the noise of float positions (tests/common/
 *             float_noise.h: 2^n K u / dt^n, each setpoint within K = 4 ulp of the largest coordinate of the exact
 *             curve, derived and measured there; FZ_MEASURE=1 measures it, fz_measure.h);
 *   end       the last setpoint is the programmed end exactly (the end rounded to lsm_real);
 *   crawl     the run ends within 4 x a generous time bound (every block a rest-to-rest move at a speed capped
 *             by the feed, the slowest axis and, on arcs, the centripetal a, j and snap caps, halved) + 0.5 s;
 *   fallback  no piece needed the planner's conservative fallback (stats.plan_fallbacks == 0).
 * A violation prints what and where, then aborts (libFuzzer keeps the input; a replay fails).
 *
 * Known classes. The float limit overshoots (issue 14 item 1), inexact ends (item 2), crawls and fallbacks (the
 * planner issue) are being fixed by others. With LSM_FUZZ_KNOWN=report in the environment, those four classes
 * are printed (the first few) and counted instead of aborting, so a short fuzzing run can look for everything
 * else; nan, a status that is not allowed, a sanitizer report or a stall is always fatal. Default: all fatal.
 * LSM_FUZZ_KNOWN_LOG=FILE appends one line per reported known violation (scripts/fuzz.sh counts them).
 */
#ifndef FZ_PATH_H
#define FZ_PATH_H

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "float_noise.h"
#include "interp.h"
#include "planner.h"

#define FZ_AXES 3
#include "fz_measure.h"
#define FZ_CAPACITY 24u            /* look-ahead storage: small, so that the ring wraps and runs low */
#define FZ_MAX_EST_S 30.0          /* inputs whose time bound is longer are skipped (not interesting, slow) */
#define FZ_MAX_EST_CYCLES 150000.0 /* ... and so are those with more cycles than this */
#define FZ_REL_TOL 1e-6            /* relative slack on every limit (the planner's documented margin) */
#define FZ_CRAWL_FACTOR 4.0        /* a run longer than 4 x the time bound + FZ_CRAWL_SLACK_S is a crawl */
#define FZ_CRAWL_SLACK_S 0.5

typedef struct fz_machine {
    const char *name;
    double cycle_s;
    double v[FZ_AXES], a[FZ_AXES], j[FZ_AXES], s[FZ_AXES];
} fz_machine;

/* The machines the targets run on (the first input byte chooses). */
static const fz_machine k_fz_machines[] = {
    {"router", 0.001, {250, 250, 150}, {3000, 3000, 2000}, {60000, 60000, 40000}, {1.18e7, 1.18e7, 7.85e6}},
    {"fast2ms", 0.002, {1000, 1000, 1000}, {20000, 20000, 20000}, {1e6, 1e6, 1e6}, {1e9, 1e9, 1e9}},
    {"slow", 0.001, {50, 50, 20}, {500, 500, 200}, {1e4, 1e4, 5e3}, {1e7, 1e7, 5e6}},
    {"aniso", 0.00025, {300, 200, 100}, {5000, 3000, 1000}, {1e5, 5e4, 1e4}, {1e8, 5e7, 1e7}},
};
#define FZ_N_MACHINES (sizeof k_fz_machines / sizeof k_fz_machines[0])

enum { FZ_K_LIMIT, FZ_K_END, FZ_K_CRAWL, FZ_K_FALLBACK, FZ_K_N };
static const char *const k_fz_known_names[FZ_K_N] = {"limit", "end", "crawl", "fallback"};
static unsigned long g_fz_known_count[FZ_K_N];
static int g_fz_known_mode = -1; /* 1: report the known classes, 0: fatal */

static void fz_fatal(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "FUZZ VIOLATION (%s build): ", LSM_REAL_IS_FLOAT ? "float" : "double");
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    abort();
}

static void fz_known(int kind, const char *fmt, ...)
{
    if (g_fz_known_mode < 0) {
        const char *e = getenv("LSM_FUZZ_KNOWN");
        g_fz_known_mode = e && strcmp(e, "report") == 0;
    }
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (!g_fz_known_mode)
        fz_fatal("%s: %s", k_fz_known_names[kind], msg);
    const char *logp = getenv("LSM_FUZZ_KNOWN_LOG"); /* one line per report (libFuzzer's fork mode hides stderr) */
    if (logp && *logp) {
        FILE *lf = fopen(logp, "a");
        if (lf) {
            fprintf(lf, "%s %s\n", k_fz_known_names[kind], msg);
            fclose(lf);
        }
    }
    if (g_fz_known_count[kind]++ < 3)
        fprintf(stderr, "FUZZ KNOWN %s (%s build): %s\n", k_fz_known_names[kind],
                LSM_REAL_IS_FLOAT ? "float" : "double", msg);
}

static void fz_config(const fz_machine *m, lsm_planner_config *cfg)
{
    lsm_planner_default_config(cfg);
    cfg->cycle_s = (lsm_real)m->cycle_s;
    cfg->axis_mask = 7;
    for (int k = 0; k < FZ_AXES; k++) {
        cfg->axis[k].v_max = (lsm_real)m->v[k];
        cfg->axis[k].a_max = (lsm_real)m->a[k];
        cfg->axis[k].j_max = (lsm_real)m->j[k];
        cfg->axis[k].snap_max = (lsm_real)m->s[k];
    }
}

static double fz_min3(const double x[FZ_AXES])
{
    return fmin(x[0], fmin(x[1], x[2]));
}

/* An upper bound of the time of one block as a rest-to-rest move (see the header). len: an upper bound of its
 * length; radius 0 for lines. */
static double fz_block_bound_s(const fz_machine *m, double len, double feed, double radius)
{
    const double a = 0.5 * fz_min3(m->a), j = 0.5 * fz_min3(m->j), s = 0.5 * fz_min3(m->s);
    double v = fmin(feed, fz_min3(m->v));
    if (radius > 0)
        v = fmin(v, fmin(sqrt(a * radius), fmin(cbrt(j * radius * radius), sqrt(sqrt(s * radius * radius * radius)))));
    v *= 0.5;
    if (!(v > 0))
        return INFINITY;
    return len / v + 4.0 * (v / a + a / j + j / s) + 40.0 * m->cycle_s;
}

typedef struct fz_run {
    const fz_machine *m;
    lsm_planner pl;
    lsm_interp ip;
    lsm_pblock store[FZ_CAPACITY];
    double q[4][FZ_AXES]; /* the last four setpoints, q[0] newest */
    double span;          /* largest |coordinate| seen (float noise) */
    long cycles;
    long idle_cycles; /* cycles at rest by request (HELD) or for want of blocks (IDLE): not counted as crawl */
    lsm_interp_state state;
    int limit_reported;
    fz_meas ms; /* FZ_MEASURE: the float noise measurement (fz_measure.h) */
} fz_run;

static void fz_run_init(fz_run *r, const fz_machine *m)
{
    memset(r, 0, sizeof *r);
    r->m = m;
    r->ms.on = -1;
    lsm_planner_config cfg;
    fz_config(m, &cfg);
    const lsm_real start[LSM_MAX_AXES] = {0};
    lsm_status st = lsm_planner_init(&r->pl, &cfg, r->store, FZ_CAPACITY, start);
    if (st != LSM_OK)
        fz_fatal("planner init on machine %s: %s", m->name, lsm_status_str(st));
    st = lsm_interp_init(&r->ip, &r->pl);
    if (st != LSM_OK)
        fz_fatal("interp init: %s", lsm_status_str(st));
    r->span = 1.0;
}

/* The float setpoints' noise in the n-th difference over dt^n: tests/common/float_noise.h (each setpoint within
 * K u of the exact curve, u = FLT_EPSILON x the largest |coordinate| seen). The double build is checked without
 * noise (its rounding is far below the relative slack, and every input passes so). */
static double fz_noise(const fz_run *r, int order)
{
    if (!LSM_REAL_IS_FLOAT)
        return 0;
    return float_noise_diff(r->span, order, r->m->cycle_s);
}

/* Checks the newest setpoint (r->q[0]) against the limits. */
static void fz_check_diffs(fz_run *r)
{
    const double dt = r->m->cycle_s;
    for (int a = 0; a < FZ_AXES; a++) {
        const double q0 = r->q[0][a], q1 = r->q[1][a], q2 = r->q[2][a], q3 = r->q[3][a];
        const double v = fabs(q0 - q1) / dt, acc = fabs(q0 - 2 * q1 + q2) / (dt * dt),
                     jk = fabs(q0 - 3 * q1 + 3 * q2 - q3) / (dt * dt * dt);
        const double vl = r->m->v[a] * (1 + FZ_REL_TOL) + fz_noise(r, 1);
        const double al = r->m->a[a] * (1 + FZ_REL_TOL) + fz_noise(r, 2);
        const double jl = r->m->j[a] * (1 + FZ_REL_TOL) + fz_noise(r, 3);
        if ((v > vl || acc > al || jk > jl) && !r->limit_reported) {
            r->limit_reported = 1;
            fz_known(FZ_K_LIMIT, "machine %s cycle %ld axis %d: v %.9g/%g a %.9g/%g j %.9g/%g", r->m->name, r->cycles,
                     a, v, r->m->v[a], acc, r->m->a[a], jk, r->m->j[a]);
        }
    }
}

/* One control cycle: background planning, the step, the checks. Returns the interpolator state. */
static lsm_interp_state fz_step(fz_run *r)
{
    (void)lsm_interp_prepare(&r->ip);
    lsm_real pos[LSM_MAX_AXES];
    r->state = lsm_interp_step(&r->ip, pos);
    memmove(&r->q[1], &r->q[0], 3 * sizeof r->q[0]);
    for (int a = 0; a < FZ_AXES; a++) {
        if (!isfinite((double)pos[a]))
            fz_fatal("machine %s cycle %ld: axis %d setpoint %g is not finite", r->m->name, r->cycles, a,
                     (double)pos[a]);
        r->q[0][a] = (double)pos[a];
        r->span = fmax(r->span, fabs((double)pos[a]));
    }
    for (int a = FZ_AXES; a < LSM_MAX_AXES; a++)
        if (pos[a] != 0)
            fz_fatal("cycle %ld: axis %d (not configured) moved to %g", r->cycles, a, (double)pos[a]);
    r->cycles++;
    if (r->state == LSM_INTERP_HELD || r->state == LSM_INTERP_IDLE)
        r->idle_cycles++;
    fz_check_diffs(r);
    fz_measure_step(&r->ms, &r->ip, &r->pl, r->q, r->span, r->m->cycle_s, r->m->v, r->m->a, r->m->j);
    return r->state;
}

/* Runs on (the program was finished) until DONE, or a crawl / stall. est_s: the sum of the block bounds; the
 * cycles at rest (HELD, IDLE) are not counted against it. */
static void fz_run_out(fz_run *r, double est_s, const lsm_real end[FZ_AXES])
{
    const double bound_s = FZ_CRAWL_FACTOR * est_s + FZ_CRAWL_SLACK_S;
    const long max_cycles = (long)(bound_s / r->m->cycle_s) + 10;
    const long hard = r->cycles + 2 * max_cycles; /* a stall at rest (IDLE for ever) ends here too */
    while (r->state != LSM_INTERP_DONE && r->cycles - r->idle_cycles < max_cycles && r->cycles < hard)
        fz_step(r);
    if (r->state != LSM_INTERP_DONE) {
        /* stopped or crawling: keep stepping to tell which (a stall never ends; a crawl does, slowly) */
        const long limit = r->cycles + max_cycles * 4; /* bounded: a fuzzing run must stay fast */
        while (r->state != LSM_INTERP_DONE && r->cycles < limit)
            fz_step(r);
        if (r->state != LSM_INTERP_DONE && r->state != LSM_INTERP_RUN)
            fz_fatal("machine %s: not done after %ld cycles (%.3f s, bound %.3f s): a stall (state %d)", r->m->name,
                     r->cycles, r->cycles * r->m->cycle_s, bound_s, (int)r->state);
        if (r->state == LSM_INTERP_RUN) { /* still moving after 5 x the bound: an extreme crawl (or a stall) */
            fz_known(FZ_K_CRAWL, "machine %s: still running after %.3f s in motion, bound %.3f s", r->m->name,
                     (r->cycles - r->idle_cycles) * r->m->cycle_s, bound_s);
            return;
        }
        fz_known(FZ_K_CRAWL, "machine %s: %.3f s in motion against a bound of %.3f s", r->m->name,
                 (r->cycles - r->idle_cycles) * r->m->cycle_s, bound_s);
    }
    /* at rest after the end: three more cycles close the differences */
    for (int k = 0; k < 3; k++)
        fz_step(r);
    for (int a = 0; a < FZ_AXES; a++)
        if (r->q[0][a] != (double)end[a]) {
            fz_known(FZ_K_END, "machine %s: end axis %d %.17g != %.17g (diff %.3g)", r->m->name, a, r->q[0][a],
                     (double)end[a], r->q[0][a] - (double)end[a]);
            break;
        }
    fz_measure_report(&r->ms, r->m->name, r->span);
    if (getenv("FZ_VERBOSE"))
        fprintf(stderr, "fuzz: machine %s, %ld cycles (%ld at rest), end %g %g %g, bound %.3f s\n", r->m->name,
                r->cycles, r->idle_cycles, r->q[0][0], r->q[0][1], r->q[0][2], bound_s);
    if (r->pl.stats.plan_fallbacks)
        fz_known(FZ_K_FALLBACK, "machine %s: %u fallback pieces", r->m->name, (unsigned)r->pl.stats.plan_fallbacks);
}

#endif
