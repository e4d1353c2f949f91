/*
 * lissom-sim smooth: G2 corner smoothing of a G-code program (firmware/path/corner.h).
 *   lissom-sim smooth --gcode FILE --tolerance EPS [--amax A] [--jmax J] [--json]
 *
 * Reads the program with the G-code parser (firmware/gcode/gcode.h), turns G1/G2/G3 blocks into path
 * elements (firmware/path/geom.h) and smooths every corner between two consecutive feed blocks with a
 * clothoid pair within EPS (mm). Each block may lose at most half its length to each of its two
 * corners. A corner is not blended (status "stop": the machine stops there) next to a rapid (G0),
 * under G61, when a block moves A B C, when it is not planar, for an exact reversal, or when no
 * transition fits; "joined" means there was nothing to smooth (already G2).
 * The tolerance comes from --tolerance (G64 P in the file is not used; G61 is).
 *
 * Output (--json): per corner {"index","line","status", and when smoothed: "deviation",
 * "vertex_deviation","path_deviation","deviation_sampled","kappa_max","sharpness_max","trim_before",
 * "trim_after","angle_deg","iterations","scales","limited","feed_limit_eq7_mm_s","feed_limit_eq8_mm_s"};
 * overall "max_deviation" (as the firmware computed it), "max_deviation_sampled" (an independent
 * dense check here: 2000 samples per clothoid, exact distances to the programmed blocks),
 * "max_curvature_jump" (1/mm, largest |difference of curvature vectors| over every joint the machine
 * passes without stopping, after smoothing), "max_curvature_jump_rel", "max_position_gap",
 * "max_tangent_jump_rad", "kappa_max" (whole path, arcs included), "sharpness_max", and the feed limits
 * of eq 7 sqrt(amax/kappa_max) and eq 8 cbrt(jmax/sharpness_max), in mm/s and mm/min (null when
 * unbounded). amax and jmax default to the paper's machine, 50 mm/s^2 and 500 mm/s^3.
 * Exit: 0 ok; 1 bad file, G-code error or bad tolerance; 2 usage.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "corner.h"
#include "gcode.h"
#include "geom.h"
#include "simprog.h"

typedef struct {
    lsm_geom g;
    uint32_t line;
    int feed;     /* G1/G2/G3 (not a rapid) */
    int stop_end; /* G61 in force: stop at the end of this block */
    int rotary;   /* an arc that moves A B C (its geometry ignores them) */
} sm_block;

typedef struct {
    int status; /* 0 smoothed, 1 joined, 2 stop */
    const char *reason;
    lsm_corner_result r;
    double dev_sampled;
} sm_corner;

/* ---- reader: G-code file -> blocks (the one place that knows the input format) ---- */

static int sm_read_gcode(const char *path, sm_block **out, int *n_out)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        fprintf(stderr, "error: smooth: cannot open '%s'\n", path);
        return -1;
    }
    lsm_gcode p;
    lsm_gcode_result res;
    lsm_gcode_init(&p, NULL);
    sm_block *b = NULL;
    int n = 0, cap = 0;
    char *line = NULL;
    size_t lcap = 0;
    ssize_t len;
    int rc = 0;
    while ((len = getline(&line, &lcap, f)) >= 0) {
        lsm_status st = lsm_gcode_parse_line(&p, line, (size_t)len, &res);
        if (st != LSM_OK) {
            fprintf(stderr, "error: smooth: %s:%u:%u: %s (%d)\n", path, (unsigned)res.err.line,
                    (unsigned)res.err.column, lsm_status_str(st), (int)st);
            rc = -1;
            break;
        }
        for (int k = 0; k < res.n_blocks; k++) {
            const lsm_gcode_block *gb = &res.blocks[k];
            if (n == cap) {
                cap = cap ? 2 * cap : 64;
                sm_block *nb = realloc(b, (size_t)cap * sizeof *b);
                if (nb == NULL) {
                    fprintf(stderr, "error: smooth: out of memory\n");
                    rc = -1;
                    break;
                }
                b = nb;
            }
            sm_block *s = &b[n];
            memset(s, 0, sizeof *s);
            s->line = gb->line;
            s->feed = gb->type != LSM_GCODE_BLOCK_RAPID;
            s->stop_end = res.modal.blend == LSM_GCODE_EXACT_STOP;
            lsm_status gs;
            if (gb->type == LSM_GCODE_BLOCK_ARC) {
                gs = lsm_geom_arc_init(&s->g, gb->start, gb->end, gb->centre, (lsm_geom_plane)gb->plane, gb->dir,
                                       gb->turns);
                s->rotary = gb->start[3] != gb->end[3] || gb->start[4] != gb->end[4] || gb->start[5] != gb->end[5];
            } else {
                gs = lsm_geom_line_init(&s->g, gb->start, gb->end);
            }
            if (gs != LSM_OK) {
                fprintf(stderr, "error: smooth: %s:%u: block geometry: %s (%d)\n", path, (unsigned)gb->line,
                        lsm_status_str(gs), (int)gs);
                rc = -1;
                break;
            }
            n++;
        }
        if (rc != 0 || res.end_of_program)
            break;
    }
    free(line);
    fclose(f);
    if (rc != 0) {
        free(b);
        return rc;
    }
    *out = b;
    *n_out = n;
    return 0;
}

/* ---- independent deviation check (dense sampling, exact distances, double) ---- */

/* lsm_geom_eval in double whatever lsm_real is (the checks here compute in double; a float core's results are
 * widened exactly). */
static void sm_eval(const lsm_geom *g, double s, double pos[LSM_MAX_AXES], double tan[3], double curv[3])
{
    lsm_real p[LSM_MAX_AXES] = {0}, t[3] = {0}, c[3] = {0};
    lsm_geom_eval(g, (lsm_real)s, p, t, c);
    for (int i = 0; i < LSM_MAX_AXES; i++) {
        if (pos)
            pos[i] = p[i];
        if (i < 3 && tan)
            tan[i] = t[i];
        if (i < 3 && curv)
            curv[i] = c[i];
    }
}


typedef struct {
    const lsm_corner_result *r;
    const lsm_geom *b1, *b2;
    double v[3];
} sm_check;

/* which 0: -(distance to the corner point)^2 ; 1: distance to the programmed path */
static double sm_f(const sm_check *c, int which, double t)
{
    const double L = c->r->trans[0].len;
    double p[LSM_MAX_AXES];
    if (t <= L)
        sm_eval(&c->r->trans[0], t, p, NULL, NULL);
    else
        sm_eval(&c->r->trans[1], t - L, p, NULL, NULL);
    if (which == 0) {
        double d2 = 0.0;
        for (int i = 0; i < 3; i++)
            d2 += (p[i] - c->v[i]) * (p[i] - c->v[i]);
        return -d2;
    }
    const double a = sim_prog_distance(c->b1, p), b = sim_prog_distance(c->b2, p);
    return a < b ? a : b;
}

static double sm_sampled_deviation(const lsm_geom *b1, const lsm_geom *b2, const lsm_corner_result *r)
{
    sm_check c = {r, b1, b2, {0, 0, 0}};
    double pv[LSM_MAX_AXES];
    sm_eval(b1, b1->len, pv, NULL, NULL);
    memcpy(c.v, pv, sizeof c.v);
    const int n = 2000;
    const double T = r->trans[0].len + r->trans[1].len, h = T / n;
    double res[2];
    for (int w = 0; w < 2; w++) {
        double best = -HUGE_VAL;
        int arg = 0;
        for (int i = 0; i <= n; i++) {
            const double f = sm_f(&c, w, h * i);
            if (f > best) {
                best = f;
                arg = i;
            }
        }
        double a = h * (arg > 0 ? arg - 1 : 0), b = h * (arg < n ? arg + 1 : n);
        const double g = 0.6180339887498949;
        for (int k = 0; k < 60; k++) {
            const double x1 = b - g * (b - a), x2 = a + g * (b - a);
            const double f1 = sm_f(&c, w, x1), f2 = sm_f(&c, w, x2);
            if (f1 > best)
                best = f1;
            if (f2 > best)
                best = f2;
            if (f1 >= f2)
                b = x2;
            else
                a = x1;
        }
        res[w] = best;
    }
    const double vd = sqrt(-res[0]), pd = res[1];
    return vd > pd ? vd : pd;
}

/* ---- joints of the smoothed path ---- */

typedef struct {
    double gap, tan, curv, curv_rel;
    uint32_t worst_line;
} sm_joint;

/* The relative jump is taken against the larger of the two curvatures and `scale` (the corner's
 * kappa_max), so that rounding at a line's zero curvature does not count as a 100 % jump. */
static void sm_joint_check(const lsm_geom *a, const lsm_geom *b, sm_joint *j, uint32_t line, double scale)
{
    double pa[LSM_MAX_AXES], pb[LSM_MAX_AXES], ta[3], tb[3], ca[3], cb[3];
    sm_eval(a, a->len, pa, ta, ca);
    sm_eval(b, 0.0, pb, tb, cb);
    double g2 = 0.0, c2 = 0.0, na = 0.0, nb = 0.0, dt = 0.0;
    for (int i = 0; i < 3; i++) {
        g2 += (pa[i] - pb[i]) * (pa[i] - pb[i]);
        c2 += (ca[i] - cb[i]) * (ca[i] - cb[i]);
        na += ca[i] * ca[i];
        nb += cb[i] * cb[i];
        dt += (ta[i] - tb[i]) * (ta[i] - tb[i]);
    }
    const double gap = sqrt(g2), cj = sqrt(c2);
    const double cmax = sqrt(na > nb ? na : nb);
    if (cmax > scale)
        scale = cmax;
    const double tj = 2.0 * asin(fmin(1.0, 0.5 * sqrt(dt)));
    const double rel = scale > 0.0 ? cj / scale : 0.0;
    if (gap > j->gap)
        j->gap = gap;
    if (tj > j->tan)
        j->tan = tj;
    if (cj > j->curv)
        j->curv = cj;
    if (rel > j->curv_rel) {
        j->curv_rel = rel;
        j->worst_line = line;
    }
}

static void sm_num(const char *key, double v, int *first)
{
    printf("%s\"%s\": ", *first ? "" : ", ", key);
    json_num(stdout, v);
    *first = 0;
}

/* The run's options. */
typedef struct {
    const char *path;
    double eps, amax, jmax;
    bool json;
} sm_opts;

/* What the whole program came to. */
typedef struct {
    int n_smooth, n_join, n_stop;
    double max_dev, max_dev_s, kmax, cmax;
    sm_joint jt;
} sm_totals;

/* Options; returns 0, or the exit code of a usage (2) or value (1) error. */
static int sm_parse(int argc, char **argv, sm_opts *o)
{
    cli_args a;
    cli_init(&a, argc, argv);
    o->path = cli_opt(&a, "gcode");
    o->amax = 50.0;
    o->jmax = 500.0;
    if (cli_num_req(&a, "tolerance", &o->eps) || cli_num(&a, "amax", &o->amax) < 0 || cli_num(&a, "jmax", &o->jmax) < 0)
        return 2;
    o->json = cli_flag(&a, "json");
    if (cli_check_unused(&a, "smooth"))
        return 2;
    if (o->path == NULL || *o->path == '\0') {
        fprintf(stderr, "error: smooth: --gcode FILE is required\n");
        return 2;
    }
    if (!(isfinite(o->eps) && o->eps > 0.0)) {
        fprintf(stderr, "error: smooth: --tolerance must be a finite number > 0\n");
        return 1;
    }
    if (!(isfinite(o->amax) && o->amax > 0.0 && isfinite(o->jmax) && o->jmax > 0.0)) {
        fprintf(stderr, "error: smooth: --amax and --jmax must be finite numbers > 0\n");
        return 1;
    }
    if (cli_check_range("amax", o->amax, CLI_LIMIT_MIN, CLI_ACC_MAX) ||
        cli_check_range("jmax", o->jmax, CLI_LIMIT_MIN, CLI_JERK_MAX) || cli_check_regular_file("--gcode", o->path))
        return 1;
    return 0;
}

/* The corner between blocks p and q: smoothed (status 0), joined (1: nothing to smooth) or a stop (2, reason). */
static void sm_smooth_one(const sm_block *p, const sm_block *q, const lsm_corner_params *prm, sm_corner *k,
                          sm_totals *t)
{
    if (!p->feed || !q->feed) {
        k->status = 2;
        k->reason = "rapid";
    } else if (p->stop_end) {
        k->status = 2;
        k->reason = "G61 exact stop";
    } else if (p->rotary || q->rotary) {
        k->status = 2;
        k->reason = lsm_status_str(LSM_E_ROTARY);
    } else {
        lsm_status st = lsm_corner_smooth(&p->g, &q->g, prm, &k->r);
        if (st == LSM_OK) {
            k->status = 0;
            k->dev_sampled = sm_sampled_deviation(&p->g, &q->g, &k->r);
            if (k->r.deviation_mm > t->max_dev)
                t->max_dev = k->r.deviation_mm;
            if (k->dev_sampled > t->max_dev_s)
                t->max_dev_s = k->dev_sampled;
            if (k->r.kappa_max_per_mm > t->kmax)
                t->kmax = k->r.kappa_max_per_mm;
            if (k->r.sharpness_max_per_mm2 > t->cmax)
                t->cmax = k->r.sharpness_max_per_mm2;
        } else if (st == LSM_E_COLLINEAR) {
            k->status = 1;
        } else {
            k->status = 2;
            k->reason = lsm_status_str(st);
        }
    }
    t->n_smooth += k->status == 0;
    t->n_join += k->status == 1;
    t->n_stop += k->status == 2;
}

/* The smoothed path: every block trimmed by its corners (and the arcs' curvature counted). Returns 0 or 1 (error
 * printed). */
static int sm_trim_blocks(sm_block *b, int n, const sm_corner *c, sm_totals *t)
{
    for (int i = 0; i < n; i++) {
        lsm_geom g = b[i].g;
        const double tb = (i > 0 && c[i - 1].status == 0) ? c[i - 1].r.trim2_mm : 0.0;
        const double ta = (i + 1 < n && c[i].status == 0) ? c[i].r.trim1_mm : 0.0;
        if (lsm_geom_trim_start(&g, tb) != LSM_OK || lsm_geom_trim_end(&g, ta) != LSM_OK) {
            fprintf(stderr, "error: smooth: block at line %u: trims exceed its length\n", (unsigned)b[i].line);
            return 1;
        }
        b[i].g = g;
        if (g.kind == LSM_GEOM_ARC && b[i].feed) {
            const double ka = lsm_geom_kappa(&g, 0.0);
            if (ka > t->kmax)
                t->kmax = ka;
        }
    }
    return 0;
}

/* Every joint the machine passes without stopping, after smoothing. */
static void sm_check_joints(const sm_block *b, int n, const sm_corner *c, sm_joint *jt)
{
    for (int i = 0; i + 1 < n; i++) {
        if (c[i].status == 0) {
            sm_joint_check(&b[i].g, &c[i].r.trans[0], jt, b[i + 1].line, c[i].r.kappa_max_per_mm);
            sm_joint_check(&c[i].r.trans[0], &c[i].r.trans[1], jt, b[i + 1].line, c[i].r.kappa_max_per_mm);
            sm_joint_check(&c[i].r.trans[1], &b[i + 1].g, jt, b[i + 1].line, c[i].r.kappa_max_per_mm);
        } else if (c[i].status == 1) {
            sm_joint_check(&b[i].g, &b[i + 1].g, jt, b[i + 1].line, 0.0);
        }
    }
}

static void sm_print_corner_json(const sm_opts *o, const sm_corner *k, int i, uint32_t line)
{
    static const char *names[3] = {"smoothed", "joined", "stop"};
    printf("%s{\"index\": %d, \"line\": %u, \"status\": \"%s\"", i ? ", " : "", i, (unsigned)line, names[k->status]);
    if (k->status == 2)
        printf(", \"reason\": \"%s\"", k->reason);
    if (k->status == 0) {
        const lsm_corner_result *r = &k->r;
        int f = 0;
        sm_num("deviation", r->deviation_mm, &f);
        sm_num("vertex_deviation", r->vertex_dev_mm, &f);
        sm_num("path_deviation", r->path_dev_mm, &f);
        sm_num("deviation_sampled", k->dev_sampled, &f);
        sm_num("kappa_max", r->kappa_max_per_mm, &f);
        sm_num("sharpness_max", r->sharpness_max_per_mm2, &f);
        sm_num("trim_before", r->trim1_mm, &f);
        sm_num("trim_after", r->trim2_mm, &f);
        sm_num("angle_deg", r->delta_rad * 180.0 / LSM_PI, &f);
        sm_num("feed_limit_eq7_mm_s", r->kappa_max_per_mm > 0 ? sqrt(o->amax / r->kappa_max_per_mm) : HUGE_VAL, &f);
        sm_num("feed_limit_eq8_mm_s",
               r->sharpness_max_per_mm2 > 0 ? cbrt(o->jmax / r->sharpness_max_per_mm2) : HUGE_VAL, &f);
        printf(", \"iterations\": %u, \"scales\": %u, \"limited\": %s, \"closed_form\": %s", (unsigned)r->iterations,
               (unsigned)r->scales, r->limited ? "true" : "false", r->closed_form ? "true" : "false");
    }
    printf("}");
}

static void sm_print_json(const sm_opts *o, const sm_block *b, int n, const sm_corner *c, const sm_totals *t, double f7,
                          double f8)
{
    int first = 1;
    printf("{");
    sm_num("tolerance", o->eps, &first);
    printf(", \"blocks\": %d, \"smoothed\": %d, \"joined\": %d, \"stops\": %d, \"corners\": [", n, t->n_smooth,
           t->n_join, t->n_stop);
    for (int i = 0; i + 1 < n; i++)
        sm_print_corner_json(o, &c[i], i, b[i + 1].line);
    printf("]");
    sm_num("max_deviation", t->max_dev, &first);
    sm_num("max_deviation_sampled", t->max_dev_s, &first);
    sm_num("max_curvature_jump", t->jt.curv, &first);
    sm_num("max_curvature_jump_rel", t->jt.curv_rel, &first);
    sm_num("max_position_gap", t->jt.gap, &first);
    sm_num("max_tangent_jump_rad", t->jt.tan, &first);
    sm_num("kappa_max", t->kmax, &first);
    sm_num("sharpness_max", t->cmax, &first);
    sm_num("amax", o->amax, &first);
    sm_num("jmax", o->jmax, &first);
    sm_num("feed_limit_eq7_mm_s", f7, &first);
    sm_num("feed_limit_eq8_mm_s", f8, &first);
    sm_num("feed_limit_mm_s", f7 < f8 ? f7 : f8, &first);
    sm_num("feed_limit_eq7_mm_min", 60.0 * f7, &first);
    sm_num("feed_limit_eq8_mm_min", 60.0 * f8, &first);
    printf("}\n");
}

static void sm_print_text(const sm_opts *o, const sm_block *b, int n, const sm_corner *c, const sm_totals *t, double f7,
                          double f8)
{
    printf("%d blocks, %d corners: %d smoothed, %d joined, %d stops (tolerance %g mm)\n", n, n > 0 ? n - 1 : 0,
           t->n_smooth, t->n_join, t->n_stop, o->eps);
    for (int i = 0; i + 1 < n; i++) {
        const sm_corner *k = &c[i];
        if (k->status == 0)
            printf("  line %4u  %7.2f deg  dev %.6f mm (sampled %.6f)  kappa_max %.5g/mm  c_max %.5g/mm^2%s\n",
                   (unsigned)b[i + 1].line, k->r.delta_rad * 180.0 / LSM_PI, k->r.deviation_mm, k->dev_sampled,
                   k->r.kappa_max_per_mm, k->r.sharpness_max_per_mm2, k->r.limited ? "  (trim-limited)" : "");
        else if (k->status == 2)
            printf("  line %4u  stop: %s\n", (unsigned)b[i + 1].line, k->reason);
    }
    const sm_joint *jt = &t->jt;
    printf("max deviation %.6g mm (sampled %.6g), max curvature jump %.3g 1/mm (relative %.3g, at line %u; gap %.3g mm,"
           " tangent %.3g rad)\n",
           t->max_dev, t->max_dev_s, jt->curv, jt->curv_rel, (unsigned)jt->worst_line, jt->gap, jt->tan);
    printf("kappa_max %.6g 1/mm, c_max %.6g 1/mm^2: feed limits eq 7 %.1f mm/min, eq 8 %.1f mm/min\n", t->kmax, t->cmax,
           60.0 * f7, 60.0 * f8);
}

int cmd_smooth(int argc, char **argv)
{
    sm_opts o;
    const int pr = sm_parse(argc, argv, &o);
    if (pr != 0)
        return pr;
    sm_block *b = NULL;
    int n = 0;
    if (sm_read_gcode(o.path, &b, &n) != 0)
        return 1;
    sm_corner *c = n > 1 ? calloc((size_t)(n - 1), sizeof *c) : NULL;
    if (n > 1 && c == NULL) {
        free(b);
        fprintf(stderr, "error: smooth: out of memory\n");
        return 1;
    }
    const lsm_corner_params prm = {o.eps, 0.0, 0.0};
    sm_totals t = {0, 0, 0, 0.0, 0.0, 0.0, 0.0, {0, 0, 0, 0, 0}};
    for (int i = 0; i + 1 < n; i++)
        sm_smooth_one(&b[i], &b[i + 1], &prm, &c[i], &t);
    if (sm_trim_blocks(b, n, c, &t) != 0) {
        free(b);
        free(c);
        return 1;
    }
    sm_check_joints(b, n, c, &t.jt);
    const double f7 = t.kmax > 0.0 ? sqrt(o.amax / t.kmax) : HUGE_VAL;
    const double f8 = t.cmax > 0.0 ? cbrt(o.jmax / t.cmax) : HUGE_VAL;
    if (o.json)
        sm_print_json(&o, b, n, c, &t, f7, f8);
    else
        sm_print_text(&o, b, n, c, &t, f7, f8);
    free(b);
    free(c);
    return 0;
}
