/*
 * lissom-sim clothoid: evaluate a clothoid, or fit one to a line (firmware/path/clothoid.h).
 *   lissom-sim clothoid eval --x0 X --y0 Y --theta0 T --kappa0 K --c C --s S [--json]
 *       prints {"x","y","theta","kappa"}: the state at arc length S (eqs 1, 2, 11, 12).
 *   lissom-sim clothoid fit --x0 X --y0 Y --theta0 T --kappa0 K --line A,B,C [--json]
 *       the clothoid from that start state that ends on the line A x + B y + C = 0 at a right angle
 *       (paper section IV); prints {"c","s","x","y","theta","kappa","iterations"} (plus
 *       "evaluations", "residual_mm", "residual_rad").
 *   lissom-sim clothoid g2path --gcode FILE (--segments N | --tolerance T) [--amax A] [--jmax J] [--json]
 *       the section-V G2 path (firmware/path/g2path.h) of the contour made by the program's G1/G2/G3 blocks
 *       (rapids are skipped; the plane is that of its arcs, G17 if none): prints the report
 *       {"segments","deviation","deviation_polygon","kappa_max","sharpness_max","feed_limit_eq7_mm_s",
 *       "feed_limit_eq8_mm_s","feed_limit_eq7_mm_min","feed_limit_eq8_mm_min","end_gap","builds"} and,
 *       with --list, the clothoids. amax and jmax default to the paper's 50 mm/s^2 and 500 mm/s^3.
 *       host_sim/examples/shahzadeh_corner.ngc with --segments 6 reproduces the paper's example.
 * x0, y0, theta0, kappa0 default to 0; c and s (eval) and line (fit) are required. Units: mm, rad,
 * 1/mm, 1/mm^2. Bad input (missing or malformed numbers, NaN, inf, a degenerate line, no solution)
 * prints a message on stderr and exits with 1 (2 for usage errors).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "clothoid.h"
#include "commands.h"
#include "g2path.h"
#include "gcode.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: lissom-sim clothoid eval --x0 X --y0 Y --theta0 T --kappa0 K --c C --s S [--json]\n"
               "       lissom-sim clothoid fit --x0 X --y0 Y --theta0 T --kappa0 K --line A,B,C [--json]\n"
               "       lissom-sim clothoid g2path --gcode FILE (--segments N | --tolerance T) [--amax A] [--jmax J]"
               " [--list] [--json]\n");
}

static int read_start(cli_args *a, double v[4])
{
    static const char *names[4] = {"x0", "y0", "theta0", "kappa0"};
    for (int i = 0; i < 4; i++) {
        v[i] = 0.0;
        if (cli_num(a, names[i], &v[i]) < 0)
            return -1;
    }
    return 0;
}

static int clothoid_eval(cli_args *a)
{
    double v[4], c, s;
    if (read_start(a, v) || cli_num_req(a, "c", &c) || cli_num_req(a, "s", &s))
        return 2;
    const bool json = cli_flag(a, "json");
    if (cli_check_unused(a, "clothoid eval"))
        return 2;
    lsm_clothoid cl;
    lsm_status st = lsm_clothoid_init(&cl, v[0], v[1], v[2], v[3], c, 0.0);
    lsm_clothoid_state out;
    if (st == LSM_OK)
        st = lsm_clothoid_eval(&cl, s, &out);
    if (st != LSM_OK) {
        fprintf(stderr, "error: clothoid eval: %s (%d)\n", lsm_status_str(st), (int)st);
        return 1;
    }
    if (json) {
        printf("{\"x\": ");
        json_num(stdout, out.x_mm);
        printf(", \"y\": ");
        json_num(stdout, out.y_mm);
        printf(", \"theta\": ");
        json_num(stdout, out.theta_rad);
        printf(", \"kappa\": ");
        json_num(stdout, out.kappa_per_mm);
        printf("}\n");
    } else {
        printf("x %.17g mm\ny %.17g mm\ntheta %.17g rad\nkappa %.17g 1/mm\n", out.x_mm, out.y_mm, out.theta_rad,
               out.kappa_per_mm);
    }
    return 0;
}

static int clothoid_fit(cli_args *a)
{
    double v[4], line[3];
    if (read_start(a, v))
        return 2;
    const int n = cli_num_list(a, "line", line, 3);
    if (n < 0)
        return 2;
    if (n != 3) {
        fprintf(stderr, "error: clothoid fit: --line A,B,C (three numbers) is required\n");
        return 2;
    }
    const bool json = cli_flag(a, "json");
    if (cli_check_unused(a, "clothoid fit"))
        return 2;
    const lsm_clothoid_state start = {v[0], v[1], v[2], v[3]};
    lsm_clothoid_fit_result r;
    lsm_status st = lsm_clothoid_fit_line(&start, line[0], line[1], line[2], &r);
    if (st != LSM_OK) {
        fprintf(stderr, "error: clothoid fit: %s (%d)\n", lsm_status_str(st), (int)st);
        return 1;
    }
    if (json) {
        const struct {
            const char *k;
            double v;
        } f[] = {{"c", r.c_per_mm2},
                 {"s", r.s_mm},
                 {"x", r.end.x_mm},
                 {"y", r.end.y_mm},
                 {"theta", r.end.theta_rad},
                 {"kappa", r.end.kappa_per_mm},
                 {"residual_mm", r.residual_mm},
                 {"residual_rad", r.residual_rad}};
        printf("{");
        for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) {
            printf("%s\"%s\": ", i ? ", " : "", f[i].k);
            json_num(stdout, f[i].v);
        }
        printf(", \"iterations\": %d, \"evaluations\": %d}\n", r.iterations, r.evaluations);
    } else {
        printf("c %.17g 1/mm^2\ns %.17g mm\nend x %.17g y %.17g theta %.17g kappa %.17g\n"
               "iterations %d (evaluations %d), residual %.3g mm %.3g rad\n",
               r.c_per_mm2, r.s_mm, r.end.x_mm, r.end.y_mm, r.end.theta_rad, r.end.kappa_per_mm, r.iterations,
               r.evaluations, r.residual_mm, r.residual_rad);
    }
    return 0;
}

/* The contour: the program's feed blocks (G1/G2/G3) as lines and arcs; the plane of its arcs. */
static int g2_read(const char *path, lsm_geom **out, int *n_out, lsm_geom_plane *plane)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        fprintf(stderr, "error: clothoid g2path: cannot open '%s'\n", path);
        return -1;
    }
    lsm_gcode p;
    lsm_gcode_result res;
    lsm_gcode_init(&p, NULL);
    lsm_geom *g = NULL;
    int n = 0, cap = 0, rc = 0;
    *plane = LSM_GEOM_PLANE_XY;
    char *line = NULL;
    size_t lcap = 0;
    ssize_t len;
    while (rc == 0 && (len = getline(&line, &lcap, f)) >= 0) {
        lsm_status st = lsm_gcode_parse_line(&p, line, (size_t)len, &res);
        if (st != LSM_OK) {
            fprintf(stderr, "error: clothoid g2path: %s:%u:%u: %s (%d)\n", path, (unsigned)res.err.line,
                    (unsigned)res.err.column, lsm_status_str(st), (int)st);
            rc = -1;
            break;
        }
        for (int k = 0; k < res.n_blocks && rc == 0; k++) {
            const lsm_gcode_block *b = &res.blocks[k];
            if (b->type == LSM_GCODE_BLOCK_RAPID)
                continue;
            if (n == cap) {
                cap = cap ? 2 * cap : 16;
                lsm_geom *ng = realloc(g, (size_t)cap * sizeof *g);
                if (ng == NULL) {
                    rc = -1;
                    break;
                }
                g = ng;
            }
            lsm_status gs;
            if (b->type == LSM_GCODE_BLOCK_ARC) {
                gs = lsm_geom_arc_init(&g[n], b->start, b->end, b->centre, (lsm_geom_plane)b->plane, b->dir, b->turns);
                *plane = (lsm_geom_plane)b->plane;
            } else {
                gs = lsm_geom_line_init(&g[n], b->start, b->end);
            }
            if (gs != LSM_OK) {
                fprintf(stderr, "error: clothoid g2path: %s:%u: %s (%d)\n", path, (unsigned)b->line, lsm_status_str(gs),
                        (int)gs);
                rc = -1;
                break;
            }
            n++;
        }
        if (res.end_of_program)
            break;
    }
    free(line);
    fclose(f);
    if (rc == 0 && n == 0) {
        fprintf(stderr, "error: clothoid g2path: '%s' has no G1/G2/G3 block\n", path);
        rc = -1;
    }
    if (rc != 0) {
        free(g);
        return rc;
    }
    *out = g;
    *n_out = n;
    return 0;
}

static int clothoid_g2path(cli_args *a)
{
    const char *path = cli_opt(a, "gcode");
    double nseg = 0, tol = 0, amax = 50.0, jmax = 500.0;
    const int hs = cli_num(a, "segments", &nseg), ht = cli_num(a, "tolerance", &tol);
    if (hs < 0 || ht < 0 || cli_num(a, "amax", &amax) < 0 || cli_num(a, "jmax", &jmax) < 0)
        return 2;
    const bool list = cli_flag(a, "list");
    const bool json = cli_flag(a, "json");
    if (cli_check_unused(a, "clothoid g2path"))
        return 2;
    if (path == NULL || *path == '\0' || (hs == 0) == (ht == 0)) {
        fprintf(stderr, "error: clothoid g2path: --gcode FILE and one of --segments N, --tolerance T are required\n");
        return 2;
    }
    if (hs == 0 && !(nseg >= 1 && nseg <= 1e6 && nseg == (double)(int)nseg)) {
        fprintf(stderr, "error: clothoid g2path: --segments must be an integer 1..1000000\n");
        return 1;
    }
    if (cli_check_range("amax", amax, CLI_LIMIT_MIN, CLI_ACC_MAX) ||
        cli_check_range("jmax", jmax, CLI_LIMIT_MIN, CLI_JERK_MAX) || cli_check_regular_file("--gcode", path))
        return 1;
    lsm_geom *c = NULL;
    int n = 0;
    lsm_geom_plane plane;
    if (g2_read(path, &c, &n, &plane) != 0)
        return 1;
    const int cap = hs == 0 ? (int)nseg : 100000;
    lsm_clothoid *out = malloc((size_t)cap * sizeof *out);
    if (out == NULL) {
        free(c);
        return 1;
    }
    lsm_g2path_report r;
    lsm_status st = hs == 0 ? lsm_g2path_build(c, n, plane, (int)nseg, amax, jmax, out, cap, &r)
                            : lsm_g2path_auto(c, n, plane, tol, amax, jmax, out, cap, &r);
    if (st != LSM_OK) {
        fprintf(stderr, "error: clothoid g2path: %s (%d)\n", lsm_status_str(st), (int)st);
        free(c);
        free(out);
        return 1;
    }
    const struct {
        const char *k;
        double v;
    } f[] = {{"deviation", r.dev_mm},
             {"deviation_polygon", r.dev_chord_mm},
             {"kappa_max", r.kappa_max_per_mm},
             {"sharpness_max", r.sharpness_max_per_mm2},
             {"feed_limit_eq7_mm_s", r.feed_acc_mm_s},
             {"feed_limit_eq8_mm_s", r.feed_jerk_mm_s},
             {"feed_limit_eq7_mm_min", 60.0 * r.feed_acc_mm_s},
             {"feed_limit_eq8_mm_min", 60.0 * r.feed_jerk_mm_s},
             {"end_gap", r.end_gap_mm}};
    if (json) {
        printf("{\"segments\": %d, \"builds\": %d, \"newton_iterations_max\": %d", r.n_segments, r.builds,
               r.iterations_max);
        for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) {
            printf(", \"%s\": ", f[i].k);
            json_num(stdout, f[i].v);
        }
        if (list) {
            printf(", \"clothoids\": [");
            for (int i = 0; i < r.n_segments; i++) {
                const lsm_clothoid *q = &out[i];
                printf("%s[%.17g, %.17g, %.17g, %.17g, %.17g, %.17g]", i ? ", " : "", q->x0_mm, q->y0_mm, q->theta0_rad,
                       q->kappa0_per_mm, q->c_per_mm2, q->len_mm);
            }
            printf("]");
        }
        printf("}\n");
    } else {
        printf("%d segments (%d builds): deviation %.6g mm (from the polygon %.6g mm), kappa_max %.6g 1/mm, "
               "c_max %.6g 1/mm^2\nfeed limits: eq 7 %.1f mm/min, eq 8 %.1f mm/min\n",
               r.n_segments, r.builds, r.dev_mm, r.dev_chord_mm, r.kappa_max_per_mm, r.sharpness_max_per_mm2,
               60.0 * r.feed_acc_mm_s, 60.0 * r.feed_jerk_mm_s);
        if (list)
            for (int i = 0; i < r.n_segments; i++)
                printf("  %3d  x0 %.6f y0 %.6f theta0 %.6f kappa0 %.6f c %.6g s %.6f\n", i, out[i].x0_mm, out[i].y0_mm,
                       out[i].theta0_rad, out[i].kappa0_per_mm, out[i].c_per_mm2, out[i].len_mm);
    }
    free(c);
    free(out);
    return 0;
}

int cmd_clothoid(int argc, char **argv)
{
    if (argc < 1) {
        usage(stderr);
        return 2;
    }
    if (strcmp(argv[0], "--help") == 0 || strcmp(argv[0], "help") == 0) {
        usage(stdout);
        return 0;
    }
    cli_args a;
    cli_init(&a, argc - 1, argv + 1);
    if (strcmp(argv[0], "eval") == 0)
        return clothoid_eval(&a);
    if (strcmp(argv[0], "fit") == 0)
        return clothoid_fit(&a);
    if (strcmp(argv[0], "g2path") == 0)
        return clothoid_g2path(&a);
    fprintf(stderr, "error: clothoid: unknown action '%s'\n", argv[0]);
    usage(stderr);
    return 2;
}
