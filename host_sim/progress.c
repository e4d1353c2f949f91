/* progress.c: progress bar on stderr for long runs (see progress.h). */
#include "progress.h"

#include <math.h>
#include <string.h>
#include <time.h>

static double wall_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void sim_progress_init(sim_progress *p, FILE *out, bool enabled, bool terminal, double delay_s)
{
    memset(p, 0, sizeof *p);
    p->out = out;
    p->enabled = enabled && out != NULL;
    p->terminal = terminal;
    p->delay_s = delay_s > 0 ? delay_s : 0;
    p->t0_s = wall_s();
    p->last_draw_s = -1e300;
    p->last_step = -1;
}

int sim_progress_format(char *buf, size_t n, const char *phase, double done, double machine_time_s)
{
    char bar[SIM_PROGRESS_BAR_CHARS + 1];
    int len;
    if (done >= 0) {
        const double f = done > 1 ? 1 : done;
        const int full = (int)floor(f * SIM_PROGRESS_BAR_CHARS + 1e-9);
        for (int i = 0; i < SIM_PROGRESS_BAR_CHARS; i++)
            bar[i] = i < full ? '#' : '.';
        bar[SIM_PROGRESS_BAR_CHARS] = '\0';
        len = snprintf(buf, n, "%-9s [%s] %3d %%", phase, bar, (int)floor(100 * f + 1e-9));
    } else {
        len = snprintf(buf, n, "%-9s ...", phase);
    }
    if (machine_time_s >= 0 && len >= 0 && (size_t)len < n)
        len += snprintf(buf + len, n - (size_t)len, "  %.1f s machine time", machine_time_s);
    return len;
}

void sim_progress_update(sim_progress *p, const char *phase, double done, double machine_time_s)
{
    if (!p || !p->enabled || !phase)
        return;
    const double now = wall_s();
    if (now - p->t0_s < p->delay_s)
        return;
    char line[160];
    sim_progress_format(line, sizeof line, phase, done, machine_time_s);
    const bool same_phase = p->phase != NULL && strcmp(phase, p->phase) == 0;
    if (p->terminal) {
        /* at most 10 redraws per second, but always on a phase change */
        if (same_phase && now - p->last_draw_s < 0.1)
            return;
        const size_t used = strlen(line);
        snprintf(line + used, sizeof line - used, "  %.1f s", now - p->t0_s);
        const int len = (int)strlen(line);
        if (len > p->width)
            p->width = len;
        fprintf(p->out, "\r%-*s", p->width, line); /* pads over a longer previous line */
        p->last_draw_s = now;
    } else {
        const int step = done >= 0 ? (int)floor(10 * (done > 1 ? 1 : done) + 1e-9) : 0;
        if (same_phase && step <= p->last_step)
            return;
        fprintf(p->out, "progress: %s\n", line);
        p->last_step = step;
    }
    p->phase = phase;
    p->shown = true;
    fflush(p->out);
}

void sim_progress_finish(sim_progress *p)
{
    if (!p || !p->enabled || !p->shown)
        return;
    if (p->terminal) {
        fprintf(p->out, "\r%*s\r", p->width, "");
        fflush(p->out);
    }
    p->shown = false;
}
