/* simprog.c: the program of a simulator run, whole or windowed (see simprog.h). */
#include "simprog.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "arc_centre.h"

/* Windowed: the held blocks (elements) are moved down once this many lie before the first one still needed, and
 * at least as many as are still held (each block is moved O(1) times on average). */
#define SIM_PROG_TRIM_MIN 1024u

/* ---------------------------------------------------------------------------------------------------------- */
/* the text: a buffer, or a file in chunks                                                                      */

/* The unread bytes (*data, *n): 0 when there are none left, -1 on a read error. */
static int src_peek(sim_prog *p, const char **data, size_t *n)
{
    if (p->text) {
        *data = p->text + p->at;
        *n = p->len - p->at;
        return 0;
    }
    if (p->bat == p->blen) {
        p->blen = fread(p->buf, 1, SIM_PROG_CHUNK, p->f);
        p->bat = 0;
        if (p->blen == 0 && ferror(p->f))
            return -1;
    }
    *data = p->buf + p->bat;
    *n = p->blen - p->bat;
    return 0;
}

static void src_used(sim_prog *p, size_t n)
{
    if (p->text)
        p->at += n;
    else
        p->bat += n;
}

static int src_rewind(sim_prog *p)
{
    p->at = 0;
    p->bat = p->blen = 0;
    if (p->f && fseek(p->f, 0, SEEK_SET) != 0)
        return -1;
    return 0;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* what a line adds                                                                                             */

static int grow(void **v, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return 0;
    size_t nc = *cap ? *cap : 256;
    while (nc < need)
        nc *= 2;
    void *nv = realloc(*v, nc * size);
    if (!nv)
        return -1;
    *v = nv;
    *cap = nc;
    return 0;
}

/* The path element of block b (its X Y Z part), if it has one (a rotary-only move has none). */
static int add_element(sim_prog *p, const lsm_gcode_block *b)
{
    lsm_geom gg;
    lsm_status st;
    if (b->type == LSM_GCODE_BLOCK_ARC) {
        st = lsm_geom_arc_init(&gg, b->start, b->end, b->centre, (lsm_geom_plane)b->plane, b->dir, b->turns);
    } else {
        lsm_real a[LSM_MAX_AXES], e[LSM_MAX_AXES];
        for (int k = 0; k < LSM_MAX_AXES; k++) {
            a[k] = k < 3 ? b->start[k] : 0;
            e[k] = k < 3 ? b->end[k] : 0;
        }
        st = lsm_geom_line_init(&gg, a, e);
    }
    if (st != LSM_OK)
        return 0;
    const double s = p->s_next;
    p->s_next += gg.len;
    if (p->counting) {
        p->np++;
        return 0;
    }
    const size_t held = p->np - p->e0;
    if (grow((void **)&p->path, &p->pcap, held + 1, sizeof *p->path))
        return -1;
    p->path[held] = (sim_prog_elem){gg, s, b->line};
    p->np++;
    return 0;
}

static int add_block(sim_prog *p, const lsm_gcode_block *b, const lsm_gcode_modal *modal)
{
    if (p->n == 0)
        for (int i = 0; i < LSM_MAX_AXES; i++)
            p->start[i] = b->start[i];
    p->last_line = b->line;
    if (!p->counting) {
        if (grow((void **)&p->v, &p->cap, p->n - p->v0 + 1, sizeof *p->v))
            return -1;
        sim_prog_block *q = &p->v[p->n - p->v0];
        q->b = *b;
        if (modal->blend == LSM_GCODE_EXACT_STOP)
            q->tol_mm = 0;
        else
            q->tol_mm = modal->blend_tol_mm > 0 ? modal->blend_tol_mm : p->blend_default_mm;
    }
    p->n++;
    return add_element(p, b);
}

/* Keeps a line's machine functions; one that needs an exact stop makes the block before it end with one. The end
 * of the program (M2/M30) is the planner's own final stop. */
static int add_events(sim_prog *p, const lsm_gcode_result *res)
{
    if (p->counting)
        return 0;
    for (int k = 0; k < res->n_events; k++) {
        if (grow((void **)&p->ev, &p->cap_ev, p->n_ev + 1, sizeof *p->ev))
            return -1;
        const lsm_gcode_event *e = &res->events[k];
        const size_t before = p->n - (size_t)res->n_blocks + (size_t)e->at_block; /* the line's blocks are in */
        p->ev[p->n_ev++] = (sim_run_mfunc){*e, before, -1.0};
        if (e->exact_stop && e->kind != LSM_GCODE_EV_END && before > p->v0 && before <= p->n)
            p->v[before - 1 - p->v0].tol_mm = 0;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* the parse                                                                                                    */

static void note_error(sim_prog *p, char *err, size_t errlen)
{
    if (p->n_errors++ == 0) {
        char why[128];
        snprintf(err, errlen, "G-code line %u column %u: %s", (unsigned)p->res->err.line, (unsigned)p->res->err.column,
                 lsm_gcode_error_text(&p->res->err, why, sizeof why));
    }
}

/* Parses one more line (or the end of the input). Returns 1 while there is more, 0 when done, -1 on an error of
 * its own (err set); a refused line is counted (note_error) and the parse goes on. */
static int parse_step(sim_prog *p, char *err, size_t errlen)
{
    const char *data;
    size_t n, used = 0;
    if (src_peek(p, &data, &n) != 0) {
        snprintf(err, errlen, "cannot read the program");
        return -1;
    }
    const bool fin = n == 0;
    const lsm_status st = fin ? lsm_gcode_finish(p->g, p->res) : lsm_gcode_feed(p->g, data, n, &used, p->res);
    src_used(p, used);
    if (p->res->complete && st != LSM_OK) {
        note_error(p, err, errlen);
    } else if (p->res->complete) {
        for (int k = 0; k < p->res->n_blocks; k++)
            if (add_block(p, &p->res->blocks[k], &p->res->modal) != 0)
                goto oom;
        if (add_events(p, p->res) != 0)
            goto oom;
        if (p->res->end_of_program)
            return 0;
    }
    return fin ? 0 : 1;
oom:
    snprintf(err, errlen, "out of memory");
    return -1;
}

static void note_held(sim_prog *p)
{
    const size_t held = (p->n - p->v0) + (p->np - p->e0);
    if (held > p->held_max)
        p->held_max = held;
}

/* From the start: the parser and the input rewound, nothing held. */
static int restart(sim_prog *p, char *err, size_t errlen)
{
    lsm_gcode_options go;
    lsm_gcode_default_options(&go);
    go.axis_mask = p->axis_mask;
    if (lsm_gcode_init(p->g, &go) != LSM_OK) {
        snprintf(err, errlen, "G-code parser init failed");
        return -1;
    }
    if (src_rewind(p) != 0) {
        snprintf(err, errlen, "cannot read the program");
        return -1;
    }
    p->v0 = p->n = p->e0 = p->np = 0;
    p->s_next = 0;
    p->done = false;
    return 0;
}

/* Parses to the end: the totals (and, whole, every block). */
static int parse_all(sim_prog *p, char *err, size_t errlen)
{
    int rc;
    while ((rc = parse_step(p, err, errlen)) == 1)
        ;
    if (rc < 0)
        return -1;
    if (p->n_errors > 1) {
        const size_t used = strlen(err);
        snprintf(err + used, errlen - used, " (and %zu more: lissom-sim check lists them)", p->n_errors - 1);
    }
    if (p->n_errors)
        return -1;
    const lsm_real *pos = lsm_gcode_position(p->g);
    for (int i = 0; i < LSM_MAX_AXES; i++)
        p->end[i] = pos[i];
    p->total = p->n;
    p->length_mm = p->s_next;
    p->done = true;
    return 0;
}

int sim_prog_open(sim_prog *p, const char *text, size_t len, const char *path, bool windowed, uint8_t axis_mask,
                  double blend_default_mm, char *err, size_t errlen)
{
    memset(p, 0, sizeof *p);
    p->windowed = windowed;
    p->text = text;
    p->len = len;
    p->axis_mask = axis_mask;
    p->blend_default_mm = blend_default_mm;
    p->g = malloc(sizeof *p->g);
    p->res = malloc(sizeof *p->res);
    if (!text) {
        p->f = path ? fopen(path, "rb") : NULL;
        p->buf = malloc(SIM_PROG_CHUNK);
        if (!p->f) {
            snprintf(err, errlen, "cannot read %s", path ? path : "(no program)");
            goto fail;
        }
    }
    if (!p->g || !p->res || (!text && !p->buf)) {
        snprintf(err, errlen, "out of memory");
        goto fail;
    }
    p->counting = windowed;
    if (restart(p, err, errlen) != 0 || parse_all(p, err, errlen) != 0)
        goto fail;
    if (!windowed)
        goto ok;
    /* the run's pass: from the start again, parsed as the run needs it */
    p->counting = false;
    if (restart(p, err, errlen) != 0)
        goto fail;
ok:
    note_held(p);
    return 0;
fail:
    sim_prog_free(p);
    return -1;
}

int sim_prog_need(sim_prog *p, size_t k, char *err, size_t errlen)
{
    while (!p->done && p->n <= k) {
        const size_t errors = p->n_errors;
        const int rc = parse_step(p, err, errlen);
        if (rc < 0)
            return -1;
        if (p->n_errors != errors || p->n > p->total) {
            snprintf(err, errlen, "the program changed while it ran (line %u)", (unsigned)p->last_line);
            return -1;
        }
        if (rc == 0)
            p->done = true;
    }
    note_held(p);
    return 0;
}

void sim_prog_trim(sim_prog *p, size_t keep_block, size_t keep_elem)
{
    if (!p->windowed)
        return;
    if (keep_block > p->n)
        keep_block = p->n;
    if (keep_elem > p->np)
        keep_elem = p->np;
    const size_t db = keep_block > p->v0 ? keep_block - p->v0 : 0;
    if (db >= SIM_PROG_TRIM_MIN && db >= p->n - keep_block) {
        memmove(p->v, p->v + db, (p->n - keep_block) * sizeof *p->v);
        p->v0 = keep_block;
    }
    const size_t de = keep_elem > p->e0 ? keep_elem - p->e0 : 0;
    if (de >= SIM_PROG_TRIM_MIN && de >= p->np - keep_elem) {
        const size_t rest = p->np - keep_elem;
        memmove(p->path, p->path + de, rest * sizeof *p->path);
        p->e0 = keep_elem;
    }
}

void sim_prog_free(sim_prog *p)
{
    free(p->v);
    free(p->ev);
    free(p->path);
    free(p->g);
    free(p->res);
    free(p->buf);
    if (p->f)
        fclose(p->f);
    memset(p, 0, sizeof *p);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* deviation                                                                                                    */

static double dist3(const double x[3], const lsm_real q[3])
{
    return sqrt((x[0] - q[0]) * (x[0] - q[0]) + (x[1] - q[1]) * (x[1] - q[1]) + (x[2] - q[2]) * (x[2] - q[2]));
}

static double dist_line(const lsm_geom *g, const double x[3])
{
    const lsm_real *p0 = g->u.line.p0, *d = g->u.line.dir;
    double t = (x[0] - p0[0]) * d[0] + (x[1] - p0[1]) * d[1] + (x[2] - p0[2]) * d[2];
    if (t < 0)
        t = 0;
    if (t > g->len)
        t = g->len;
    double r = 0;
    for (int i = 0; i < 3; i++) {
        const double e = x[i] - (p0[i] + d[i] * t);
        r += e * e;
    }
    return sqrt(r);
}

/* Distance (X Y Z) from x to one arc (or helix): every turn's nearest angle, and the ends. */
static double dist_arc(const lsm_geom *g, const double x[3])
{
    const lsm_geom_arc *a = &g->u.arc;
    double n[3] = {a->e1[1] * a->e2[2] - a->e1[2] * a->e2[1], a->e1[2] * a->e2[0] - a->e1[0] * a->e2[2],
                   a->e1[0] * a->e2[1] - a->e1[1] * a->e2[0]};
    double ac[3];
    sim_arc_centre_d(a, ac);
    double d[3] = {x[0] - ac[0], x[1] - ac[1], x[2] - ac[2]};
    const double u = d[0] * a->e1[0] + d[1] * a->e1[1] + d[2] * a->e1[2];
    const double w = d[0] * a->e2[0] + d[1] * a->e2[1] + d[2] * a->e2[2];
    const double phi = atan2(w, u);
    const double sg = a->sweep_rad < 0 ? -1.0 : 1.0, sw = fabs(a->sweep_rad);
    double rel = fmod(sg * (phi - a->phi0_rad), 2 * LSM_PI);
    if (rel < 0)
        rel += 2 * LSM_PI;
    double best = INFINITY;
    for (double t = rel; t <= sw + 1e-12; t += 2 * LSM_PI) {
        const double ph = a->phi0_rad + sg * t, f = t / sw;
        double q[3];
        for (int i = 0; i < 3; i++)
            q[i] = ac[i] + a->radius_mm * (cos(ph) * a->e1[i] + sin(ph) * a->e2[i]) + n[i] * a->axial_mm * f;
        const double r =
            sqrt((x[0] - q[0]) * (x[0] - q[0]) + (x[1] - q[1]) * (x[1] - q[1]) + (x[2] - q[2]) * (x[2] - q[2]));
        if (r < best)
            best = r;
    }
    lsm_real e0[LSM_MAX_AXES] = {0}, e1[LSM_MAX_AXES] = {0};
    lsm_geom_eval(g, 0, e0, NULL, NULL);
    lsm_geom_eval(g, g->len, e1, NULL, NULL);
    const double r0 = dist3(x, e0), r1 = dist3(x, e1);
    if (r0 < best)
        best = r0;
    return r1 < best ? r1 : best;
}

double sim_prog_distance(const lsm_geom *g, const double x[3])
{
    return g->kind == LSM_GEOM_LINE ? dist_line(g, x) : dist_arc(g, x);
}

static double elem_s0(const sim_prog *p, size_t i)
{
    return i < p->np ? p->path[i - p->e0].s0 : p->s_next;
}

double sim_prog_deviation(const sim_prog *p, const double x[3], uint32_t line, double reach_mm, size_t *lo_out)
{
    if (p->np == 0) {
        *lo_out = 0;
        return 0;
    }
    /* the last element whose line is <= line */
    size_t lo = p->e0, hi = p->np;
    while (hi - lo > 1) {
        const size_t mid = (lo + hi) / 2;
        if (p->path[mid - p->e0].line <= line)
            lo = mid;
        else
            hi = mid;
    }
    const size_t e = lo;
    if (p->e0 > 0 && p->path[0].line > line)
        return -1; /* its element is gone */
    const double s_lo = elem_s0(p, e) - reach_mm, s_hi = elem_s0(p, e + 1) + reach_mm;
    const size_t back = 2 * LSM_ARCFIT_MAX + 4;
    size_t a = e, b = e;
    while (a > p->e0 && (elem_s0(p, a) > s_lo || e - a < back))
        a--;
    if (a == p->e0 && a > 0 && (elem_s0(p, a) > s_lo || e - a < back))
        return -1; /* it would look further back than is held */
    while (b + 1 < p->np && elem_s0(p, b + 1) < s_hi)
        b++;
    double best = INFINITY;
    for (size_t i = a; i <= b; i++) {
        const double d = sim_prog_distance(&p->path[i - p->e0].g, x);
        if (d < best)
            best = d;
    }
    *lo_out = a;
    return best;
}
