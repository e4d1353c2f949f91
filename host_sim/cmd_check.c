/*
 * lissom-sim check: every error and warning of a G-code program in one pass (the firmware's parser, gcode.h).
 *
 *   lissom-sim check PROGRAM [--machine MACHINE.json | --axes XYZ] [--json] [--blocks] [--start X,Y,Z[,A,B,C]]
 *
 * PROGRAM "-" reads standard input. Each refused line is reported as `PROGRAM:LINE:COLUMN: error: REASON 'WORD'`
 * and reading goes on (a refused line changes nothing, so later lines are checked as the machine would run them
 * without it). Warnings: text after the end of the program (ignored, as LinuxCNC does), no end of program (M2, M30
 * or a closing %), G28/G30 before any G28.1/G30.1 (they go to machine zero), G43 (the simulator has no tool table:
 * no length is applied). --machine (or --axes with the axis letters) refuses words for axes the machine lacks. Exit status: 0 when there is no error
 * (warnings allowed), 1 with errors, 2 on bad usage or an unreadable file.
 * --json prints {"errors": [...], "warnings": [...], "blocks": N, "events": N} instead, and with --blocks also the
 * motion blocks and machine functions themselves (mm, mm/s, rad; the Python rig reads its blocks from here, so
 * the dialect has one implementation).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "gcode.h"
#include "machine.h"
#include "pathrun.h"

#define CHECK_MAX_MSGS 100000 /* reported messages beyond this are only counted */

typedef struct {
    int line, column; /* column 0: none */
    int error;        /* 1 error, 0 warning */
    char text[160];
} check_msg;

typedef struct {
    check_msg *v;
    size_t n, cap, n_err, n_warn;
    FILE *blocks; /* --blocks --json: a temporary file holding the blocks' JSON */
    FILE *events;
    size_t n_blocks, n_events;
} check_list;

static void add_msg(check_list *l, int error, int line, int column, const char *text)
{
    if (error)
        l->n_err++;
    else
        l->n_warn++;
    if (l->n >= CHECK_MAX_MSGS)
        return;
    if (l->n == l->cap) {
        size_t nc = l->cap ? 2 * l->cap : 64;
        check_msg *nv = realloc(l->v, nc * sizeof *nv);
        if (!nv)
            return;
        l->v = nv;
        l->cap = nc;
    }
    check_msg *m = &l->v[l->n++];
    m->line = line;
    m->column = column;
    m->error = error;
    snprintf(m->text, sizeof m->text, "%s", text);
}

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        const unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(f, "\\%c", c);
        else if (c < 0x20)
            fprintf(f, "\\u%04x", c);
        else
            fputc(c, f);
    }
    fputc('"', f);
}

static void json_vec(FILE *f, const lsm_real *v, int n)
{
    fputc('[', f);
    for (int k = 0; k < n; k++) {
        if (k)
            fputs(", ", f);
        json_num(f, v[k]);
    }
    fputc(']', f);
}

static void put_block(check_list *l, const lsm_gcode_block *b)
{
    FILE *f = l->blocks;
    static const char *type[] = {"rapid", "linear", "arc"};
    fprintf(f, "%s\n    {\"line\": %u, \"type\": \"%s\", \"start\": ", l->n_blocks ? "," : "", (unsigned)b->line,
            type[b->type]);
    json_vec(f, b->start, LSM_GCODE_N_AXES);
    fputs(", \"end\": ", f);
    json_vec(f, b->end, LSM_GCODE_N_AXES);
    fputs(", \"feed_mm_s\": ", f);
    json_num(f, b->feed_mm_s);
    fputs(", \"feed_rot_rad_s\": ", f);
    json_num(f, b->feed_rot_rad_s);
    if (b->type == LSM_GCODE_BLOCK_ARC) {
        fprintf(f, ", \"plane\": %d, \"dir\": %d, \"turns\": %u, \"centre\": ", (int)b->plane, (int)b->dir,
                (unsigned)b->turns);
        json_vec(f, b->centre, 3);
        fputs(", \"radius_mm\": ", f);
        json_num(f, b->radius_mm);
        fputs(", \"angle_rad\": ", f);
        json_num(f, b->angle_rad);
    }
    fputc('}', f);
    l->n_blocks++;
}

static void put_event(check_list *l, const lsm_gcode_event *e, size_t before)
{
    FILE *f = l->events;
    fprintf(f,
            "%s\n    {\"line\": %u, \"event\": \"%s\", \"code\": \"%s\", \"before_block\": %zu, \"exact_stop\": %s, "
            "\"tool\": %d, \"value\": ",
            l->n_events ? "," : "", (unsigned)e->line, lsm_gcode_event_name(e->kind), lsm_gcode_event_code(e->kind),
            before, e->exact_stop ? "true" : "false", (int)e->tool);
    json_num(f, e->value);
    fputc('}', f);
    l->n_events++;
}

/* Warnings about what a line means on this simulator (not errors: LinuxCNC runs them). */
static void line_warnings(check_list *l, const lsm_gcode_result *r, bool homes_set[2])
{
    char buf[160];
    for (int k = 0; k < r->n_events; k++) {
        if (r->events[k].kind == LSM_GCODE_EV_TOOL_LENGTH) {
            snprintf(buf, sizeof buf, "G43 H%d: lissom-sim has no tool table; no tool length offset is applied",
                     (int)r->events[k].tool);
            add_msg(l, 0, (int)r->line, 0, buf);
        }
    }
    const int16_t nm = r->nonmodal;
    if (nm == 281 || nm == 301)
        homes_set[nm == 301] = true;
    if ((nm == 280 || nm == 300) && !homes_set[nm == 300]) {
        snprintf(buf, sizeof buf, "G%d goes to its stored position, machine zero here (no G%d.1 before it)", nm / 10,
                 nm / 10);
        add_msg(l, 0, (int)r->line, 0, buf);
    }
}

/* Reads the whole program; every line's errors and warnings go to l. Returns 0, or -1 if the parser cannot start. */
static int check_text(const char *text, size_t len, const lsm_gcode_options *go, const double *start, check_list *l)
{
    lsm_gcode g;
    if (lsm_gcode_init(&g, go) != LSM_OK)
        return -1;
    lsm_real start_r[LSM_GCODE_N_AXES];
    for (int k = 0; start && k < LSM_GCODE_N_AXES; k++)
        start_r[k] = (lsm_real)start[k];
    if (start && lsm_gcode_set_position(&g, start_r) != LSM_OK)
        return -1;
    bool ended = false, percent = false, homes_set[2] = {false, false};
    int ignored_first = 0;
    size_t ignored = 0, at = 0, line_start = 0;
    for (;;) {
        lsm_gcode_result r;
        size_t used = 0;
        const bool fin = at >= len;
        lsm_status st = fin ? lsm_gcode_finish(&g, &r) : lsm_gcode_feed(&g, text + at, len - at, &used, &r);
        at += used;
        if (r.complete) {
            const char *s = text + line_start;
            const size_t n = at - line_start;
            line_start = at;
            if (st != LSM_OK) {
                char why[128];
                add_msg(l, 1, (int)r.err.line, (int)r.err.column, lsm_gcode_error_text(&r.err, why, sizeof why));
            } else {
                if (r.ignored && ignored++ == 0)
                    ignored_first = (int)r.line;
                line_warnings(l, &r, homes_set);
                for (int k = 0; k < r.n_blocks; k++) {
                    if (l->blocks)
                        put_block(l, &r.blocks[k]);
                    else
                        l->n_blocks++;
                }
                for (int k = 0; k < r.n_events; k++) {
                    if (l->events)
                        put_event(l, &r.events[k], l->n_blocks - r.n_blocks + r.events[k].at_block);
                    else
                        l->n_events++;
                }
                ended = r.end_of_program;
                if (!percent && n > 0 && memchr(s, '%', n))
                    percent = true;
            }
        }
        if (fin)
            break;
    }
    char buf[160];
    if (ignored) {
        snprintf(buf, sizeof buf, "%zu line(s) after the end of the program are ignored", ignored);
        add_msg(l, 0, ignored_first, 0, buf);
    }
    if (!ended)
        add_msg(l, 0, (int)g.line_no, 0,
                percent ? "the program opens with % but does not close with %"
                        : "the program has no end (M2, M30 or %)");
    return 0;
}

static int parse_start(cli_args *a, double start[LSM_GCODE_N_AXES], bool *given)
{
    double v[LSM_GCODE_N_AXES] = {0};
    const int n = cli_num_list(a, "start", v, LSM_GCODE_N_AXES);
    if (n < 0)
        return -1;
    *given = n > 0;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        start[k] = k < n ? (k >= 3 ? v[k] * LSM_PI / 180.0 : v[k]) : 0.0;
    return 0;
}

static void print_json(const check_list *l, const char *program, bool blocks)
{
    printf("{\n  \"program\": ");
    json_str(stdout, program);
    printf(",\n  \"errors\": %zu,\n  \"warnings\": %zu,\n  \"messages\": [", l->n_err, l->n_warn);
    for (size_t i = 0; i < l->n; i++) {
        const check_msg *m = &l->v[i];
        printf("%s\n    {\"severity\": \"%s\", \"line\": %d, \"column\": %d, \"text\": ", i ? "," : "",
               m->error ? "error" : "warning", m->line, m->column);
        json_str(stdout, m->text);
        printf("}");
    }
    printf("%s],\n  \"n_blocks\": %zu,\n  \"n_events\": %zu", l->n ? "\n  " : "", l->n_blocks, l->n_events);
    if (blocks) {
        char buf[65536];
        size_t k;
        printf(",\n  \"blocks\": [");
        fflush(stdout);
        rewind(l->blocks);
        while ((k = fread(buf, 1, sizeof buf, l->blocks)) > 0)
            fwrite(buf, 1, k, stdout);
        printf("%s],\n  \"events\": [", l->n_blocks ? "\n  " : "");
        rewind(l->events);
        while ((k = fread(buf, 1, sizeof buf, l->events)) > 0)
            fwrite(buf, 1, k, stdout);
        printf("%s]", l->n_events ? "\n  " : "");
    }
    printf("\n}\n");
}

static char *read_stdin(size_t *len)
{
    size_t cap = 1 << 16, n = 0, k;
    char *buf = malloc(cap + 1);
    while (buf && (k = fread(buf + n, 1, cap - n, stdin)) > 0) {
        n += k;
        if (n == cap) {
            char *nb = realloc(buf, 2 * cap + 1);
            if (!nb) {
                free(buf);
                return NULL;
            }
            buf = nb;
            cap *= 2;
        }
    }
    if (buf)
        buf[n] = '\0';
    *len = n;
    return buf;
}

int cmd_check(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    const char *machine = cli_opt(&a, "machine");
    const char *axes = cli_opt(&a, "axes");
    const bool json = cli_flag(&a, "json"), blocks = cli_flag(&a, "blocks");
    double start[LSM_GCODE_N_AXES];
    bool start_given = false;
    if (parse_start(&a, start, &start_given) != 0)
        return 2;
    const char *program = cli_positional(&a, 0);
    if (cli_check_unused(&a, "check"))
        return 2;
    if (!program || (blocks && !json)) {
        fprintf(stderr, "usage: lissom-sim check PROGRAM|- [--machine MACHINE.json | --axes XYZ] [--json [--blocks]] "
                        "[--start X,Y,Z[,A,B,C]]\n");
        return 2;
    }
    lsm_gcode_options go;
    lsm_gcode_default_options(&go);
    if (machine) {
        sim_machine m;
        char err[512];
        if (sim_machine_load_file(machine, &m, err, sizeof err) != SIM_MACHINE_OK) {
            fprintf(stderr, "error: %s\n", err);
            return 2;
        }
        go.axis_mask = m.axis_mask;
    }
    if (axes) { /* --axes XYZ: the machine's axes without a machine file */
        go.axis_mask = 0;
        for (const char *c = axes; *c; c++) {
            const char *at = strchr("XYZABC", *c);
            if (!at || !*c) {
                fprintf(stderr, "error: --axes takes letters of XYZABC, not '%c'\n", *c);
                return 2;
            }
            go.axis_mask |= (uint8_t)(1u << (at - "XYZABC"));
        }
        if (!go.axis_mask) {
            fprintf(stderr, "error: --axes is empty\n");
            return 2;
        }
    }
    size_t len = 0;
    char *text = strcmp(program, "-") == 0 ? read_stdin(&len) : sim_read_file(program, &len);
    if (!text) {
        fprintf(stderr, "error: cannot read %s\n", program);
        return 2;
    }
    check_list l = {0};
    if (blocks) {
        l.blocks = tmpfile();
        l.events = tmpfile();
        if (!l.blocks || !l.events) {
            fprintf(stderr, "error: cannot create a temporary file\n");
            free(text);
            return 2;
        }
    }
    if (check_text(text, len, &go, start_given ? start : NULL, &l) != 0) {
        fprintf(stderr, "error: bad --start position\n");
        free(text);
        return 2;
    }
    if (json) {
        print_json(&l, program, blocks);
    } else {
        for (size_t i = 0; i < l.n; i++) {
            const check_msg *m = &l.v[i];
            if (m->column > 0)
                printf("%s:%d:%d: %s: %s\n", program, m->line, m->column, m->error ? "error" : "warning", m->text);
            else
                printf("%s:%d: %s: %s\n", program, m->line, m->error ? "error" : "warning", m->text);
        }
        printf("%s: %zu error%s, %zu warning%s\n", program, l.n_err, l.n_err == 1 ? "" : "s", l.n_warn,
               l.n_warn == 1 ? "" : "s");
    }
    if (l.blocks)
        fclose(l.blocks);
    if (l.events)
        fclose(l.events);
    free(l.v);
    free(text);
    return l.n_err ? 1 : 0;
}
