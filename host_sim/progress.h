/*
 * progress.h: a progress bar on stderr for long lissom-sim runs (host only, sim_progress_*).
 *
 * Two styles, chosen by the caller:
 *   terminal  one line redrawn in place with '\r' at most every 0.1 s and cleared at the end:
 *               drives    [###########.........]  55 %  31.9 s machine time  1.4 s
 *   log       (stderr not a terminal, e.g. a CI log) one line per phase and per 10 % step:
 *               progress: drives    [###########.........]  55 %  31.9 s machine time
 * Nothing is drawn before `delay_s` of wall time has passed, so short runs stay quiet; `lissom-sim run` uses
 * 2 s on a terminal and 0 when --progress asks for the bar. A phase reported with done < 0 has no fraction
 * (e.g. plotting in a child process) and is drawn without a bar. Only ever writes to `out` (stderr), never to
 * stdout, so --json output stays clean.
 */
#ifndef LSM_SIM_PROGRESS_H
#define LSM_SIM_PROGRESS_H

#include <stdbool.h>
#include <stdio.h>

#define SIM_PROGRESS_BAR_CHARS 20

typedef struct sim_progress {
    FILE *out;
    bool enabled;       /* draw at all */
    bool terminal;      /* redraw in place (terminal) or one line per step (log) */
    double delay_s;     /* wall time before anything is drawn */
    double t0_s;        /* wall clock at init (monotonic) */
    double last_draw_s; /* wall clock of the last terminal redraw */
    const char *phase;  /* phase of the last line drawn (log style) */
    int last_step;      /* 10 % step of the last line drawn (log style), -1 none */
    int width;          /* characters of the last terminal line (to clear it) */
    bool shown;         /* something was drawn */
} sim_progress;

/* out: where to draw (stderr); enabled: draw at all; terminal: the style; delay_s >= 0. */
void sim_progress_init(sim_progress *p, FILE *out, bool enabled, bool terminal, double delay_s);

/* phase: a short name ("planning", "drives", ...; a string that outlives the call); done in [0, 1], or < 0
 * for a phase without a fraction; machine_time_s: how far the run has got in machine time (< 0: not shown). */
void sim_progress_update(sim_progress *p, const char *phase, double done, double machine_time_s);

/* Ends the display: clears the terminal line. Safe to call when nothing was drawn. */
void sim_progress_finish(sim_progress *p);

/* The line drawn for a state (no '\r', no newline), for tests: returns its length. */
int sim_progress_format(char *buf, size_t n, const char *phase, double done, double machine_time_s);

#endif /* LSM_SIM_PROGRESS_H */
