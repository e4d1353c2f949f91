/*
 * test_gcode.c: the G-code parser (firmware/gcode/gcode.c), built for double and float.
 *
 * Every word of the subset, modal behaviour, arcs in the I/J/K and R forms in all three planes,
 * inch and incremental modes, streaming in chunks of every size, and malformed input: each error
 * is checked for its code, line and column. Tolerances: 1e-9 mm (double) or 2e-4 mm (float, a few
 * ulps of coordinates up to ~100 mm) on positions, relative 1e-12 / 1e-6 on feeds.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "gcode.h"

#define TOL_MM (LSM_REAL_IS_FLOAT ? 2e-4 : 1e-9)
#define TOL_REL (LSM_REAL_IS_FLOAT ? 1e-6 : 1e-12)
#define PI 3.14159265358979323846

#define MAX_BLOCKS 2048
#define MAX_ERRS 16

typedef struct {
    lsm_gcode p;
    lsm_gcode_block blocks[MAX_BLOCKS];
    int n;
    lsm_gcode_error errs[MAX_ERRS];
    int n_err;
    uint32_t lines;
    bool ended;
    lsm_gcode_modal modal;
} run_t;

static run_t g_run, g_run2;

/* Parse a whole program through lsm_gcode_feed in chunks of `chunk` bytes (0 = all at once). */
static void run_prog_opt(run_t *r, const char *text, size_t len, size_t chunk, const lsm_gcode_options *opt)
{
    memset(r, 0, sizeof *r);
    assert_int_equal(lsm_gcode_init(&r->p, opt), LSM_OK);
    size_t off = 0;
    lsm_gcode_result res;
    while (off < len) {
        size_t n = chunk == 0 ? len - off : (chunk < len - off ? chunk : len - off);
        size_t sub = 0;
        while (sub < n) {
            size_t used = 0;
            lsm_status st = lsm_gcode_feed(&r->p, text + off + sub, n - sub, &used, &res);
            assert_true(used > 0 && used <= n - sub);
            sub += used;
            if (!res.complete) {
                assert_int_equal(st, LSM_OK);
                continue;
            }
            r->lines = res.line;
            assert_int_equal(st, res.status);
            if (st != LSM_OK) {
                assert_int_equal(res.n_blocks, 0);
                if (r->n_err < MAX_ERRS)
                    r->errs[r->n_err++] = res.err;
            }
            for (int k = 0; k < res.n_blocks; k++) {
                assert_true(r->n < MAX_BLOCKS);
                r->blocks[r->n++] = res.blocks[k];
            }
            r->ended = res.end_of_program;
            r->modal = res.modal;
        }
        off += n;
    }
    lsm_status st = lsm_gcode_finish(&r->p, &res);
    if (res.complete) {
        r->lines = res.line;
        if (st != LSM_OK && r->n_err < MAX_ERRS)
            r->errs[r->n_err++] = res.err;
        for (int k = 0; k < res.n_blocks; k++)
            r->blocks[r->n++] = res.blocks[k];
    }
    r->ended = res.end_of_program;
    r->modal = res.modal;
}

static void run_prog(run_t *r, const char *text)
{
    run_prog_opt(r, text, strlen(text), 0, NULL);
}

/* Parse one line on a fresh parser prepared by `setup` (a program of earlier lines). */
static lsm_status one_line(const char *setup, const char *line, lsm_gcode_result *res)
{
    static lsm_gcode p;
    assert_int_equal(lsm_gcode_init(&p, NULL), LSM_OK);
    lsm_gcode_result tmp;
    if (setup) {
        size_t off = 0, len = strlen(setup);
        while (off < len) {
            size_t used;
            lsm_status st = lsm_gcode_feed(&p, setup + off, len - off, &used, &tmp);
            assert_int_equal(st, LSM_OK); /* the setup itself must be valid */
            off += used;
        }
        assert_int_equal(lsm_gcode_finish(&p, &tmp), LSM_OK);
    }
    return lsm_gcode_parse_line(&p, line, strlen(line), res);
}

/* The line under test comes after the setup's lines: its physical line number is one more than the number of
 * line endings in the setup (blank and comment lines count). */
static uint32_t line_after(const char *setup)
{
    uint32_t n = 1;
    for (const char *c = setup; c && *c; c++)
        n += *c == '\n';
    return n;
}

static void expect_error(const char *setup, const char *line, lsm_status code, uint32_t column)
{
    lsm_gcode_result res;
    lsm_status st = one_line(setup, line, &res);
    const uint32_t want_line = line_after(setup);
    if (st != code || res.err.column != column || res.err.line != want_line) {
        print_error("line \"%s\": got %d (%s) at %u:%u, expected %d (%s) at %u:%u\n", line, (int)st, lsm_status_str(st),
                    (unsigned)res.err.line, (unsigned)res.err.column, (int)code, lsm_status_str(code),
                    (unsigned)want_line, (unsigned)column);
    }
    assert_int_equal(st, code);
    assert_int_equal(res.status, code);
    assert_int_equal(res.err.code, code);
    assert_int_equal(res.err.line, want_line);
    assert_int_equal(res.err.column, column);
    assert_int_equal(res.n_blocks, 0);
}

static void expect_ok(const char *setup, const char *line, lsm_gcode_result *res)
{
    lsm_status st = one_line(setup, line, res);
    if (st != LSM_OK)
        print_error("line \"%s\": %s at column %u\n", line, lsm_status_str(st), (unsigned)res->err.column);
    assert_int_equal(st, LSM_OK);
}

#define assert_near(a, b, tol) assert_true(fabs((double)(a) - (double)(b)) <= (tol))
#define assert_mm(a, b) assert_near(a, b, TOL_MM)
#define assert_rel(a, b) assert_true(fabs((double)(a) - (double)(b)) <= TOL_REL * fabs((double)(b)))

/* ---------------------------------------------------------------- words and modal state */

static void test_defaults_and_init(void **state)
{
    (void)state;
    lsm_gcode p;
    assert_int_equal(lsm_gcode_init(NULL, NULL), LSM_E_NULL);
    lsm_gcode_options o;
    lsm_gcode_default_options(&o);
    assert_int_equal(o.axis_mask, 0x3F);
    o.axis_mask = 0;
    assert_int_equal(lsm_gcode_init(&p, &o), LSM_E_ARG);
    o.axis_mask = 0x40;
    assert_int_equal(lsm_gcode_init(&p, &o), LSM_E_ARG);
    lsm_gcode_default_options(&o);
    o.units = (lsm_gcode_units)22;
    assert_int_equal(lsm_gcode_init(&p, &o), LSM_E_ARG);
    assert_int_equal(lsm_gcode_init(&p, NULL), LSM_OK);
    const lsm_gcode_modal *m = lsm_gcode_modal_state(&p);
    assert_int_equal(m->motion, LSM_GCODE_MOTION_NONE);
    assert_int_equal(m->plane, LSM_GCODE_PLANE_XY);
    assert_int_equal(m->units, LSM_GCODE_UNITS_MM);
    assert_int_equal(m->distance, LSM_GCODE_ABSOLUTE);
    assert_int_equal(m->blend, LSM_GCODE_BLEND);
    assert_true(m->blend_tol_mm == 0 && m->feed_mm_s == 0);

    lsm_real pos[6] = {1, 2, 3, 0.5, 0, 0};
    assert_int_equal(lsm_gcode_set_position(&p, pos), LSM_OK);
    assert_true(lsm_gcode_position(&p)[2] == 3);
    pos[1] = (lsm_real)NAN;
    assert_int_equal(lsm_gcode_set_position(&p, pos), LSM_E_NAN);
    pos[1] = (lsm_real)INFINITY;
    assert_int_equal(lsm_gcode_set_position(&p, pos), LSM_E_INF);
    pos[1] = (lsm_real)2e6;
    assert_int_equal(lsm_gcode_set_position(&p, pos), LSM_E_RANGE);
    assert_true(lsm_gcode_position(&p)[1] == 2); /* unchanged by the rejected calls */
    assert_int_equal(lsm_gcode_set_position(&p, NULL), LSM_E_NULL);
}

static void test_linear_rapid_feed(void **state)
{
    (void)state;
    run_t *r = &g_run;
    run_prog(r, "G21 G90 G17\n"
                "G0 X10 Y5\n"
                "G1 Z-1 F600\n"
                "X20\n"      /* modal G1 */
                "X20\n"      /* zero length: no block */
                "G1 F1200\n" /* no axis words: no block, feed changes */
                "Y15 A90\n"
                "M2\n");
    assert_int_equal(r->n_err, 0);
    assert_int_equal(r->n, 4);
    assert_true(r->ended);
    const lsm_gcode_block *b = r->blocks;
    assert_int_equal(b[0].type, LSM_GCODE_BLOCK_RAPID);
    assert_int_equal(b[0].line, 2);
    assert_mm(b[0].end[0], 10);
    assert_mm(b[0].end[1], 5);
    assert_true(b[0].feed_mm_s == 0);
    assert_int_equal(b[1].type, LSM_GCODE_BLOCK_LINEAR);
    assert_rel(b[1].feed_mm_s, 10.0); /* 600 mm/min */
    assert_rel(b[1].feed_rot_rad_s, 10.0 * PI / 180.0);
    assert_mm(b[1].start[0], 10);
    assert_mm(b[1].end[2], -1);
    assert_int_equal(b[2].line, 4);
    assert_mm(b[2].end[0], 20);
    assert_mm(b[2].end[1], 5);
    assert_mm(b[2].end[2], -1);
    assert_int_equal(b[3].line, 7);
    assert_rel(b[3].feed_mm_s, 20.0);
    assert_mm(b[3].end[1], 15);
    assert_mm(b[3].end[3], PI / 2); /* A leaves in radians */
    for (int k = 1; k < r->n; k++)
        for (int a = 0; a < 6; a++)
            assert_true(r->blocks[k].start[a] == r->blocks[k - 1].end[a]);
}

static void test_incremental(void **state)
{
    (void)state;
    run_t *r = &g_run;
    run_prog(r, "G91 G1 F60 X1 Y2\nX1\nY-3 C-45\nG90 X0\n");
    assert_int_equal(r->n_err, 0);
    assert_int_equal(r->n, 4);
    assert_mm(r->blocks[0].end[0], 1);
    assert_mm(r->blocks[0].end[1], 2);
    assert_mm(r->blocks[1].end[0], 2);
    assert_mm(r->blocks[2].end[1], -1);
    assert_mm(r->blocks[2].end[5], -PI / 4);
    assert_mm(r->blocks[3].end[0], 0);
    assert_mm(r->blocks[3].end[1], -1);
    assert_int_equal(r->modal.distance, LSM_GCODE_ABSOLUTE);
    assert_false(r->ended);
}

static void test_inch(void **state)
{
    (void)state;
    run_t *r = &g_run;
    /* F is read in the line's final units; A is degrees whatever the units. */
    run_prog(r, "G20 G1 X1 F10\nG91 Y-0.5 A180\nG64 P0.001\nG21 G90 X10\n");
    assert_int_equal(r->n_err, 0);
    assert_int_equal(r->n, 3);
    assert_mm(r->blocks[0].end[0], 25.4);
    assert_rel(r->blocks[0].feed_mm_s, 25.4 * 10 / 60.0);
    assert_rel(r->blocks[0].feed_rot_rad_s, 10.0 / 60.0 * PI / 180.0);
    assert_mm(r->blocks[1].end[1], -12.7);
    assert_mm(r->blocks[1].end[3], PI);
    assert_int_equal(r->modal.blend, LSM_GCODE_BLEND);
    assert_rel(r->modal.blend_tol_mm, 0.0254);
    assert_mm(r->blocks[2].end[0], 10);
    assert_int_equal(r->modal.units, LSM_GCODE_UNITS_MM);
    /* the feed keeps its physical value after G21 */
    assert_rel(r->blocks[2].feed_mm_s, 25.4 * 10 / 60.0);

    /* start in inches by option */
    lsm_gcode_options o;
    lsm_gcode_default_options(&o);
    o.units = LSM_GCODE_UNITS_INCH;
    const char *prog = "G1 X2 F1\n";
    run_prog_opt(r, prog, strlen(prog), 0, &o);
    assert_int_equal(r->n, 1);
    assert_mm(r->blocks[0].end[0], 50.8);
}

static void test_path_control_modal(void **state)
{
    (void)state;
    lsm_gcode_result res;
    expect_ok(NULL, "G61", &res);
    assert_int_equal(res.modal.blend, LSM_GCODE_EXACT_STOP);
    expect_ok("G64 P0.05\n", "G1", &res);
    assert_int_equal(res.modal.blend, LSM_GCODE_BLEND);
    assert_rel(res.modal.blend_tol_mm, 0.05);
    assert_int_equal(res.modal.motion, LSM_GCODE_MOTION_LINEAR);
    expect_ok("G64 P0.05\nG61\n", "G64", &res); /* G64 without P: machine default */
    assert_true(res.modal.blend_tol_mm == 0);
    expect_ok(NULL, "G18", &res);
    assert_int_equal(res.modal.plane, LSM_GCODE_PLANE_ZX);
    expect_ok(NULL, "G19 G91", &res);
    assert_int_equal(res.modal.plane, LSM_GCODE_PLANE_YZ);
    assert_int_equal(res.modal.distance, LSM_GCODE_INCREMENTAL);
    /* accepted no-ops */
    expect_ok(NULL, "G17 G21 G90 G94 G40 G49 G54 G80", &res);
    assert_int_equal(res.modal.motion, LSM_GCODE_MOTION_NONE);
    /* G-number spellings */
    expect_ok(NULL, "G01 F100 X1", &res);
    assert_int_equal(res.n_blocks, 1);
    expect_ok(NULL, "G1.0 F100 X1", &res);
    assert_int_equal(res.n_blocks, 1);
    expect_ok(NULL, "g00x1", &res); /* lower case, no spaces */
    assert_int_equal(res.n_blocks, 1);
    assert_int_equal(res.blocks[0].type, LSM_GCODE_BLOCK_RAPID);
}

static void test_comments_numbers_lines(void **state)
{
    (void)state;
    lsm_gcode_result res;
    expect_ok(NULL, "N120 G1 (move x) F100 X1 ; trailing", &res);
    assert_true(res.has_n);
    assert_int_equal(res.n, 120);
    assert_int_equal(res.n_blocks, 1);
    expect_ok(NULL, "(only a comment) ; and another", &res);
    expect_ok(NULL, "G1 F100 X1 (caf\xC3\xA9 \xE2\x80\x94 UTF-8 in a comment)", &res);
    assert_int_equal(res.n_blocks, 1);
    expect_ok(NULL, "G1 F100 X1 ; \xC3\xA9 here too", &res);
    /* blanks inside numbers and between letter and number (RS274/NGC ignores them) */
    expect_ok(NULL, "G 1 F 1 0 0 X - 1 2 . 5", &res);
    assert_mm(res.blocks[0].end[0], -12.5);
    expect_ok(NULL, "G1 F100 X.5 Y-.25 Z+3.", &res);
    assert_mm(res.blocks[0].end[0], 0.5);
    assert_mm(res.blocks[0].end[1], -0.25);
    assert_mm(res.blocks[0].end[2], 3);
    /* leading zeros and many digits */
    expect_ok(NULL, "G1 F100 X000012.500000000000000000000001", &res);
    assert_mm(res.blocks[0].end[0], 12.5);
    expect_ok(NULL, "G1 F100 X0.000000000000000000000000001", &res);
    assert_mm(res.blocks[0].end[0], 0);
    /* empty, blank, CR */
    expect_ok(NULL, "", &res);
    expect_ok(NULL, " \t \r", &res);
    expect_ok(NULL, "G1 F100 X3\r\n", &res);
    assert_int_equal(res.n_blocks, 1);
}

static void test_block_delete_percent_end(void **state)
{
    (void)state;
    run_t *r = &g_run;
    const char *prog = "%\n(title)\n/G1 F100 X5\nG1 F100 X1\n%\nG1 X99\nnot even G-code \x01\n";
    run_prog(r, prog); /* switch off: '/' is ignored and the line runs */
    assert_int_equal(r->n_err, 0);
    assert_int_equal(r->n, 2);
    assert_true(r->ended);
    assert_int_equal(r->lines, 7);
    lsm_gcode_options o;
    lsm_gcode_default_options(&o);
    o.block_delete = true;
    run_prog_opt(r, prog, strlen(prog), 0, &o);
    assert_int_equal(r->n_err, 0);
    assert_int_equal(r->n, 1);
    assert_mm(r->blocks[0].end[0], 1);
    /* M30 ends; what follows is not read */
    run_prog(r, "G0 X1\nM30\nG0 X2\n#junk\n");
    assert_int_equal(r->n_err, 0);
    assert_int_equal(r->n, 1);
    assert_true(r->ended);
    /* M2 on a motion line: the motion happens, then the program ends */
    run_prog(r, "G0 X1 M2\nG0 X3\n");
    assert_int_equal(r->n, 1);
    assert_true(r->ended);
    /* a '%' after content ends the program as well */
    run_prog(r, "G0 X1\n%\nG0 X5\n");
    assert_int_equal(r->n, 1);
    assert_true(r->ended);
    run_prog(r, "G0 X1\n");
    assert_false(r->ended);
}

/* ---------------------------------------------------------------- arcs */

static void check_on_circle(const lsm_gcode_block *b)
{
    int iu = 0, iv = 1;
    if (b->plane == LSM_GCODE_PLANE_ZX) {
        iu = 2;
        iv = 0;
    } else if (b->plane == LSM_GCODE_PLANE_YZ) {
        iu = 1;
        iv = 2;
    }
    double rs = hypot((double)(b->start[iu] - b->centre[iu]), (double)(b->start[iv] - b->centre[iv]));
    double re = hypot((double)(b->end[iu] - b->centre[iu]), (double)(b->end[iv] - b->centre[iv]));
    assert_mm(rs, b->radius_mm);
    assert_mm(re, b->radius_end_mm);
}

static void test_arc_ijk_xy(void **state)
{
    (void)state;
    lsm_gcode_result res;
    /* from (0,0): centre (10,0), end (10,10): G2 is a quarter, G3 three quarters */
    expect_ok("F600\n", "G2 X10 Y10 I10 J0", &res);
    assert_int_equal(res.n_blocks, 1);
    const lsm_gcode_block *b = &res.blocks[0];
    assert_int_equal(b->type, LSM_GCODE_BLOCK_ARC);
    assert_int_equal(b->plane, LSM_GCODE_PLANE_XY);
    assert_int_equal(b->dir, -1);
    assert_int_equal(b->turns, 0);
    assert_mm(b->centre[0], 10);
    assert_mm(b->centre[1], 0);
    assert_mm(b->centre[2], 0);
    assert_mm(b->radius_mm, 10);
    assert_mm(b->angle_rad, PI / 2);
    assert_mm(b->helix_mm, 0);
    assert_rel(b->feed_mm_s, 10);
    check_on_circle(b);
    expect_ok("F600\n", "G3 X10 Y10 I10", &res); /* J omitted = 0 */
    assert_int_equal(res.blocks[0].dir, 1);
    assert_mm(res.blocks[0].angle_rad, 3 * PI / 2);
    /* modal arc: the next line with only axis words and offsets is G3 again */
    expect_ok("F600\nG3 X10 Y10 I10\n", "X0 Y0 I0 J-10", &res);
    assert_int_equal(res.n_blocks, 1);
    assert_int_equal(res.blocks[0].dir, 1);
    assert_mm(res.blocks[0].centre[0], 10);
    assert_mm(res.blocks[0].centre[1], 0);
    assert_mm(res.blocks[0].angle_rad, PI / 2);
    /* helix: Z and A move with the arc */
    expect_ok("F600\nG0 X5 Y0 Z1\n", "G17 G3 X-5 Y0 Z-2 A30 I-5", &res);
    b = &res.blocks[0];
    assert_mm(b->angle_rad, PI);
    assert_mm(b->helix_mm, -3);
    assert_mm(b->centre[2], 1); /* normal coordinate of the centre = start's */
    assert_mm(b->end[3], PI / 6);
    /* inch and incremental: I J are always relative and are scaled */
    expect_ok("F10 G20 G91\n", "G2 X1 Y-1 I0 J-1", &res);
    b = &res.blocks[0];
    assert_mm(b->end[0], 25.4);
    assert_mm(b->end[1], -25.4);
    assert_mm(b->centre[0], 0);
    assert_mm(b->centre[1], -25.4);
    assert_mm(b->radius_mm, 25.4);
    assert_mm(b->angle_rad, PI / 2);
    /* within LinuxCNC's tolerance the radius difference is accepted and reported */
    expect_ok("F600\n", "G2 X10 Y0 I5.001", &res);
    assert_mm(res.blocks[0].radius_mm, 5.001);
    assert_mm(res.blocks[0].radius_end_mm, 4.999);
}

static void test_arc_full_circle_turns(void **state)
{
    (void)state;
    lsm_gcode_result res;
    expect_ok("F600 G0 X10 Y0\n", "G3 X10 Y0 I-10", &res);
    assert_mm(res.blocks[0].angle_rad, 2 * PI);
    assert_int_equal(res.blocks[0].turns, 0);
    expect_ok("F600 G0 X10 Y0\n", "G2 X10 I-10 P3", &res);
    assert_mm(res.blocks[0].angle_rad, 6 * PI);
    assert_int_equal(res.blocks[0].turns, 2);
    assert_int_equal(res.blocks[0].dir, -1);
    /* partial arc plus one full turn, helical (a thread-milling pass) */
    expect_ok("F600 G0 X10 Y0\n", "G3 X0 Y10 Z-4 I-10 P2", &res);
    assert_mm(res.blocks[0].angle_rad, 2 * PI + PI / 2);
    assert_mm(res.blocks[0].helix_mm, -4);
    /* incremental full circle */
    expect_ok("F600 G91\n", "G2 X0 Y0 I3 J4", &res);
    assert_mm(res.blocks[0].radius_mm, 5);
    assert_mm(res.blocks[0].angle_rad, 2 * PI);
}

static void test_arc_radius_form(void **state)
{
    (void)state;
    lsm_gcode_result res;
    const double s2 = sqrt(2.0);
    /* chord (0,0)->(2,0), |R| = sqrt 2: the centre is (1, +-1) */
    struct {
        const char *line;
        double cy, angle;
        int dir;
    } k[] = {
        {"G3 X2 Y0 R1.41421356237309505", 1, PI / 2, 1},       /* CCW short: centre left of the chord */
        {"G3 X2 Y0 R-1.41421356237309505", -1, 3 * PI / 2, 1}, /* CCW long */
        {"G2 X2 Y0 R1.41421356237309505", -1, PI / 2, -1},     /* CW short: centre right */
        {"G2 X2 Y0 R-1.41421356237309505", 1, 3 * PI / 2, -1}, /* CW long */
    };
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++) {
        expect_ok("F600\n", k[i].line, &res);
        const lsm_gcode_block *b = &res.blocks[0];
        assert_int_equal(b->dir, k[i].dir);
        assert_mm(b->centre[0], 1);
        assert_mm(b->centre[1], k[i].cy);
        assert_mm(b->radius_mm, s2);
        assert_mm(b->angle_rad, k[i].angle);
        check_on_circle(b);
    }
    /* exact half circle, and a chord longer than the diameter by less than the tolerance */
    expect_ok("F600\n", "G2 X10 R5", &res);
    assert_mm(res.blocks[0].centre[0], 5);
    assert_mm(res.blocks[0].centre[1], 0);
    assert_mm(res.blocks[0].angle_rad, PI);
    expect_ok("F600\n", "G2 X10.002 R5", &res);
    assert_mm(res.blocks[0].centre[0], 5.001);
    assert_near(res.blocks[0].angle_rad, PI, LSM_REAL_IS_FLOAT ? 1e-3 : 1e-6);
    /* R in inches */
    expect_ok("F1 G20\n", "G3 X2 R1", &res);
    assert_mm(res.blocks[0].radius_mm, 25.4);
    assert_mm(res.blocks[0].centre[0], 25.4);
}

static void test_arc_planes(void **state)
{
    (void)state;
    lsm_gcode_result res;
    /* G18: plane (Z, X), normal Y; offsets I (X) and K (Z). From (0,0,0) to X10 Z10 with the
     * centre at X10: G3 turns from Z to X about +Y. The start is at angle atan2(x-cx, z-cz) =
     * atan2(-10, 0) = -90 deg, the end at atan2(0, 10) = 0: G3 is a quarter turn. */
    expect_ok("F600\n", "G18 G3 X10 Z10 I10 Y-2", &res);
    const lsm_gcode_block *b = &res.blocks[0];
    assert_int_equal(b->plane, LSM_GCODE_PLANE_ZX);
    assert_int_equal(b->dir, 1);
    assert_mm(b->centre[0], 10);
    assert_mm(b->centre[1], 0);
    assert_mm(b->centre[2], 0);
    assert_mm(b->angle_rad, PI / 2);
    assert_mm(b->helix_mm, -2);
    check_on_circle(b);
    expect_ok("F600\n", "G18 G2 X10 Z10 K0 I10", &res);
    assert_mm(res.blocks[0].angle_rad, 3 * PI / 2);
    /* G19: plane (Y, Z), normal X; offsets J (Y) and K (Z) */
    expect_ok("F600\n", "G19 G3 Y10 Z10 J10 X4", &res);
    b = &res.blocks[0];
    assert_int_equal(b->plane, LSM_GCODE_PLANE_YZ);
    /* start at angle atan2(z-cz, y-cy) = atan2(0, -10) = 180 deg, end atan2(10, 0) = 90: G3 = 270 */
    assert_mm(b->angle_rad, 3 * PI / 2);
    assert_mm(b->centre[1], 10);
    assert_mm(b->centre[0], 0);
    assert_mm(b->helix_mm, 4);
    check_on_circle(b);
    expect_ok("F600\n", "G19 G2 Y10 Z10 R10", &res);
    assert_mm(res.blocks[0].angle_rad, PI / 2);
    check_on_circle(&res.blocks[0]);
}

/* ---------------------------------------------------------------- streaming */

static void test_streaming_chunks(void **state)
{
    (void)state;
    static char prog[20000];
    size_t len = 0;
    len += (size_t)snprintf(prog + len, sizeof prog - len, "%%\r\nG21 G90 G64 P0.01 (setup)\r\nG0 X0 Y0\r\nF1500\r\n");
    for (int i = 0; i < 200; i++) {
        double a = 2 * PI * i / 200.0;
        len += (size_t)snprintf(prog + len, sizeof prog - len, "N%d G1 X%.4f Y%.4f ; chord %d\n", i + 10, 20 * cos(a),
                                20 * sin(a), i);
    }
    len += (size_t)snprintf(prog + len, sizeof prog - len, "G1 X20 Y0\nG2 X20 Y0 I-20 J0\nG3 X0 Y0 R10\nM30\n");
    run_prog_opt(&g_run, prog, len, 0, NULL);
    assert_int_equal(g_run.n_err, 0);
    assert_int_equal(g_run.n, 203); /* 200 chords (the first from the origin), G1, G2, G3 */
    assert_true(g_run.ended);
    const size_t chunks[] = {1, 2, 3, 7, 64, 255, 256, 257, 1000};
    for (size_t c = 0; c < sizeof chunks / sizeof chunks[0]; c++) {
        run_prog_opt(&g_run2, prog, len, chunks[c], NULL);
        assert_int_equal(g_run2.n_err, 0);
        assert_int_equal(g_run2.n, g_run.n);
        assert_int_equal(g_run2.lines, g_run.lines);
        assert_true(g_run2.ended);
        assert_memory_equal(g_run2.blocks, g_run.blocks, sizeof(lsm_gcode_block) * (size_t)g_run.n);
    }
    /* a last line without a line ending is parsed by finish() */
    run_prog_opt(&g_run2, "G0 X1\nG0 X2", 11, 4, NULL);
    assert_int_equal(g_run2.n, 2);
    assert_int_equal(g_run2.lines, 2);
    /* parse_line refuses to interleave with an unfinished streamed line */
    lsm_gcode p;
    lsm_gcode_result res;
    size_t used;
    lsm_gcode_init(&p, NULL);
    assert_int_equal(lsm_gcode_feed(&p, "G0 X", 4, &used, &res), LSM_OK);
    assert_false(res.complete);
    assert_int_equal(lsm_gcode_parse_line(&p, "G0 X1", 5, &res), LSM_E_STATE);
    assert_int_equal(lsm_gcode_feed(&p, "5\n", 2, &used, &res), LSM_OK);
    assert_true(res.complete);
    assert_mm(res.blocks[0].end[0], 5);
    assert_int_equal(lsm_gcode_feed(NULL, "x", 1, &used, &res), LSM_E_NULL);
    assert_int_equal(lsm_gcode_feed(&p, NULL, 1, &used, &res), LSM_E_NULL);
    assert_int_equal(lsm_gcode_parse_line(&p, "G0\nX1", 5, &res), LSM_E_GC_SYNTAX);
    assert_int_equal(res.err.column, 3);
}

/* ---------------------------------------------------------------- malformed input */

static void test_err_unknown_missing_syntax(void **state)
{
    (void)state;
    expect_error(NULL, "G1 X1 Q5", LSM_E_GC_UNKNOWN_WORD, 7);
    expect_error(NULL, "G4.5 P1", LSM_E_GC_UNKNOWN_WORD, 1);
    expect_error(NULL, "G0 X1 M47", LSM_E_GC_UNKNOWN_WORD, 7);
    expect_error(NULL, "G61.1", LSM_E_GC_UNKNOWN_WORD, 1);
    expect_error(NULL, "G1.5 X1", LSM_E_GC_UNKNOWN_WORD, 1);
    expect_error(NULL, "G-1 X1", LSM_E_GC_UNKNOWN_WORD, 1);
    expect_error(NULL, "E1", LSM_E_GC_UNKNOWN_WORD, 1);
    expect_error(NULL, "G1 X1e3", LSM_E_GC_UNKNOWN_WORD, 6); /* no exponents in G-code */
    expect_error(NULL, "G1 X", LSM_E_GC_MISSING_ARG, 4);
    expect_error(NULL, "G1 X- Y2", LSM_E_GC_MISSING_ARG, 4);
    expect_error(NULL, "G1 X. Y2", LSM_E_GC_MISSING_ARG, 4);
    expect_error(NULL, "G X1", LSM_E_GC_MISSING_ARG, 1);
    expect_error(NULL, "G1 X1 = 2", LSM_E_GC_SYNTAX, 7);
    expect_error(NULL, "G1 X1.2.3", LSM_E_GC_SYNTAX, 8);
    expect_error(NULL, "12 G1", LSM_E_GC_SYNTAX, 1);
    expect_error(NULL, "G1 N5", LSM_E_GC_SYNTAX, 4);
    expect_error(NULL, "G0 X1 %", LSM_E_GC_SYNTAX, 7);
    expect_error(NULL, "% G0", LSM_E_GC_SYNTAX, 3);
    expect_error(NULL, "#1=5", LSM_E_GC_UNSUPPORTED, 1);
    expect_error(NULL, "G1 X[1+2]", LSM_E_GC_UNSUPPORTED, 5);
    expect_error(NULL, "O100 sub", LSM_E_GC_UNSUPPORTED, 1);
    expect_error(NULL, "G1 (unclosed", LSM_E_GC_COMMENT, 4);
    expect_error(NULL, "G1 (a (b) )", LSM_E_GC_COMMENT, 7);
    expect_error(NULL, "G0 X1 )", LSM_E_GC_COMMENT, 7);
}

static void test_err_range_and_long_lines(void **state)
{
    (void)state;
    expect_error(NULL, "G1 X12345678901234567890 F100", LSM_E_GC_NUMBER_RANGE, 4);
    expect_error(NULL, "G0 X2000000", LSM_E_GC_NUMBER_RANGE, 4);
    expect_error(NULL, "G0 Y-1000000.5", LSM_E_GC_NUMBER_RANGE, 4);
    expect_error(NULL, "F99999999", LSM_E_GC_NUMBER_RANGE, 1);
    expect_error(NULL, "G20 G0 X100000", LSM_E_GC_NUMBER_RANGE, 8);        /* 2.54e6 mm after conversion */
    expect_error("G91 G0 X900000\n", "X900000", LSM_E_GC_NUMBER_RANGE, 1); /* accumulated */
    lsm_gcode_result res;
    expect_ok(NULL, "G0 X1000000", &res); /* the limit itself is representable */

    /* lines: exactly the maximum is fine (also with CRLF), one more is an error at column max+1 */
    static char line[LSM_GCODE_MAX_LINE + 64];
    memset(line, ' ', sizeof line);
    memcpy(line, "G0 X1", 5);
    line[LSM_GCODE_MAX_LINE] = '\0';
    expect_ok(NULL, line, &res);
    assert_int_equal(res.n_blocks, 1);
    line[LSM_GCODE_MAX_LINE] = 'Y';
    line[LSM_GCODE_MAX_LINE + 1] = '\0';
    expect_error(NULL, line, LSM_E_GC_LINE_TOO_LONG, LSM_GCODE_MAX_LINE + 1);

    /* streamed: the long line is reported once with its line number, the next line still works */
    static char prog[3 * LSM_GCODE_MAX_LINE];
    size_t n = 0;
    n += (size_t)snprintf(prog, sizeof prog, "G0 X1\r\n");
    memcpy(prog + n, "G0 X2", 5);
    memset(prog + n + 5, ' ', LSM_GCODE_MAX_LINE - 5);
    n += LSM_GCODE_MAX_LINE;
    n += (size_t)snprintf(prog + n, sizeof prog - n, "\r\n(");
    memset(prog + n, 'x', LSM_GCODE_MAX_LINE + 10);
    n += LSM_GCODE_MAX_LINE + 10;
    n += (size_t)snprintf(prog + n, sizeof prog - n, ")\nG0 X3\n");
    for (size_t chunk = 0; chunk < 9; chunk += 4) {
        run_prog_opt(&g_run, prog, n, chunk, NULL);
        assert_int_equal(g_run.n_err, 1);
        assert_int_equal(g_run.errs[0].code, LSM_E_GC_LINE_TOO_LONG);
        assert_int_equal(g_run.errs[0].line, 3);
        assert_int_equal(g_run.errs[0].column, LSM_GCODE_MAX_LINE + 1);
        assert_int_equal(g_run.n, 3);
        assert_mm(g_run.blocks[2].end[0], 3);
        assert_int_equal(g_run.blocks[2].line, 4);
    }
}

static void test_err_binary(void **state)
{
    (void)state;
    expect_error(NULL, "G1 X1\x01", LSM_E_GC_BINARY, 6);
    expect_error(NULL, "G0 X\x7f", LSM_E_GC_BINARY, 5);
    expect_error(NULL, "G0 X1 \xC3\xA9", LSM_E_GC_BINARY, 7);
    expect_error(NULL, "\xFF\xFE G0", LSM_E_GC_BINARY, 1);
    expect_error(NULL, "G0 (ok \x1b[31m)", LSM_E_GC_BINARY, 8); /* control bytes not even in comments */
    /* an embedded NUL byte, through parse_line with an explicit length */
    lsm_gcode p;
    lsm_gcode_result res;
    lsm_gcode_init(&p, NULL);
    assert_int_equal(lsm_gcode_parse_line(&p, "G0 X1\0Y2", 8, &res), LSM_E_GC_BINARY);
    assert_int_equal(res.err.column, 6);
    assert_int_equal(res.err.line, 1);
    /* a chunk of random-looking binary in a stream: reported with its line number, and the parser
     * recovers on the next line */
    static const char junk[] = "G0 X1\n\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\nG0 X2\n";
    run_prog_opt(&g_run, junk, sizeof junk - 1, 3, NULL);
    assert_true(g_run.n_err >= 2);
    assert_int_equal(g_run.errs[0].code, LSM_E_GC_BINARY);
    assert_int_equal(g_run.errs[0].line, 2);
    assert_int_equal(g_run.errs[0].column, 1);
    assert_int_equal(g_run.errs[1].code, LSM_E_GC_BINARY);
    assert_int_equal(g_run.errs[1].line, 3);
    assert_int_equal(g_run.n, 2);
    assert_mm(g_run.blocks[1].end[0], 2);
}

static void test_err_repeat_modal_feed(void **state)
{
    (void)state;
    expect_error(NULL, "G1 X1 X2", LSM_E_GC_WORD_REPEATED, 7);
    expect_error(NULL, "F1 G1 F2", LSM_E_GC_WORD_REPEATED, 7);
    expect_error(NULL, "N1 N2", LSM_E_GC_WORD_REPEATED, 4);
    expect_error(NULL, "G0 G1 X1", LSM_E_GC_MODAL_CONFLICT, 4);
    expect_error(NULL, "G1 G1 X1", LSM_E_GC_MODAL_CONFLICT, 4);
    expect_error(NULL, "G20 G21", LSM_E_GC_MODAL_CONFLICT, 5);
    expect_error(NULL, "G90 X1 G91", LSM_E_GC_MODAL_CONFLICT, 8);
    expect_error(NULL, "G17 G18", LSM_E_GC_MODAL_CONFLICT, 5);
    expect_error(NULL, "G61 G64", LSM_E_GC_MODAL_CONFLICT, 5);
    expect_error(NULL, "M2 M30", LSM_E_GC_MODAL_CONFLICT, 4);
    expect_error(NULL, "G0 X1 G1", LSM_E_GC_MODAL_CONFLICT, 7);
    expect_error(NULL, "G1 X10", LSM_E_GC_NO_FEED, 1);
    expect_error("G1 F0\n", "Y10", LSM_E_GC_NO_FEED, 1);
    expect_error(NULL, "G2 X10 Y0 I5", LSM_E_GC_NO_FEED, 1);
    expect_error("F100 G3 X0 Y0 I1\nF0\n", "  X5 Y5 I2.5 J2.5", LSM_E_GC_NO_FEED, 3);
    /* rapids need no feed; G1 alone sets the mode without moving */
    lsm_gcode_result res;
    expect_ok(NULL, "G0 X10", &res);
    expect_ok(NULL, "G1", &res);
    assert_int_equal(res.modal.motion, LSM_GCODE_MOTION_LINEAR);
}

static void test_err_arcs(void **state)
{
    (void)state;
    /* centre form: radii 5.1 and 4.9 differ by 0.2 mm > 0.028 */
    expect_error("F100\n", "G2 X10 Y0 I5.1", LSM_E_GC_ARC_MISMATCH, 1);
    /* 0.02 mm is below the absolute tolerance but above 0.1 % of a 5 mm radius */
    expect_error("F100\n", "G2 X10 Y0 I5.01", LSM_E_GC_ARC_MISMATCH, 1);
    /* modal arc: the column is the first axis word's */
    expect_error("F100 G2 X10 Y0 I5\n", "   X0 Y0 I-4", LSM_E_GC_ARC_MISMATCH, 4);
    /* radius form: chord 30 > diameter 20; end == start; zero radius */
    expect_error("F100\n", "G2 X30 Y0 R10", LSM_E_GC_ARC_RADIUS, 11);
    expect_error("F100\n", "G2 X10.01 R5", LSM_E_GC_ARC_RADIUS, 11);
    expect_error("F100\n", "G2 X0 Y0 R5", LSM_E_GC_ARC_RADIUS, 10);
    expect_error("F100\n", "G3 X1 R0", LSM_E_GC_ARC_RADIUS, 7);
    /* centre on the start or on the end */
    expect_error("F100\n", "G2 X10 Y0 I0 J0", LSM_E_GC_ARC_CENTRE, 11);
    expect_error("F100\n", "G2 X10 Y0 I10", LSM_E_GC_ARC_CENTRE, 11);
    /* form: no offsets nor R, both, an offset outside the plane, no end point word in the plane */
    expect_error("F100\n", "G2 X10 Y0", LSM_E_GC_ARC_FORM, 1);
    expect_error("F100\n", "G2 X10 I5 R5", LSM_E_GC_ARC_FORM, 11);
    expect_error("F100\n", "G2 X10 R5 I5", LSM_E_GC_ARC_FORM, 11);
    expect_error("F100\n", "G17 G2 X10 I5 K1", LSM_E_GC_ARC_FORM, 15);
    expect_error("F100\n", "G18 G2 X10 I5 J1", LSM_E_GC_ARC_FORM, 15);
    expect_error("F100\n", "G19 G2 Y10 J5 I1", LSM_E_GC_ARC_FORM, 15);
    expect_error("F100\n", "G2 R5", LSM_E_GC_ARC_FORM, 1); /* R form needs an end word (centre form does not) */
    expect_error("F100\n", "G2 Z5 R5", LSM_E_GC_ARC_FORM, 1);
    expect_error("F100\n", "G2", LSM_E_GC_ARC_FORM, 1);
    expect_error("F100\n", "G64 P0.1 G2 X10 I5", LSM_E_GC_ARC_FORM, 5);
    /* P turns */
    expect_error("F100\n", "G2 X0 I5 P0", LSM_E_GC_BAD_VALUE, 10);
    expect_error("F100\n", "G2 X0 I5 P1.5", LSM_E_GC_BAD_VALUE, 10);
    expect_error("F100\n", "G2 X0 I5 P-2", LSM_E_GC_BAD_VALUE, 10);
    expect_error("F100\n", "G2 X0 I5 P1001", LSM_E_GC_BAD_VALUE, 10);
}

static void test_err_unused_values_axes(void **state)
{
    (void)state;
    expect_error(NULL, "X10", LSM_E_GC_UNUSED_WORD, 1); /* no motion mode yet (G80) */
    expect_error(NULL, "G80 X10", LSM_E_GC_UNUSED_WORD, 5);
    expect_error(NULL, "G1 F100 X10 I5", LSM_E_GC_UNUSED_WORD, 13);
    expect_error(NULL, "G0 R5 X1", LSM_E_GC_UNUSED_WORD, 4);
    expect_error(NULL, "P5", LSM_E_GC_UNUSED_WORD, 1);
    expect_error(NULL, "G61 P5", LSM_E_GC_UNUSED_WORD, 5);
    expect_error("G2 F100 X0 Y0 I1\n", "I5 J5", LSM_E_GC_UNUSED_WORD, 1); /* modal arc, no axis word */
    expect_error(NULL, "F-100", LSM_E_GC_BAD_VALUE, 1);
    expect_error(NULL, "G64 P-0.1", LSM_E_GC_BAD_VALUE, 5);
    expect_error(NULL, "N-5 G0", LSM_E_GC_BAD_VALUE, 1);
    expect_error(NULL, "N1.5 G0", LSM_E_GC_BAD_VALUE, 1);
    lsm_gcode_result res;
    expect_ok(NULL, "N0010.00 G0 X1", &res);
    assert_int_equal(res.n, 10);

    /* axes the machine lacks */
    lsm_gcode_options o;
    lsm_gcode_default_options(&o);
    o.axis_mask = 0x07; /* X Y Z */
    lsm_gcode p;
    assert_int_equal(lsm_gcode_init(&p, &o), LSM_OK);
    assert_int_equal(lsm_gcode_parse_line(&p, "G0 X1 A10", 9, &res), LSM_E_GC_NO_AXIS);
    assert_int_equal(res.err.column, 7);
    assert_int_equal(lsm_gcode_parse_line(&p, "G0 X1 Z2", 8, &res), LSM_OK);
    o.axis_mask = 0x03; /* X Y */
    assert_int_equal(lsm_gcode_init(&p, &o), LSM_OK);
    assert_int_equal(lsm_gcode_parse_line(&p, "G0 z2", 5, &res), LSM_E_GC_NO_AXIS);
    assert_int_equal(res.err.column, 4);
}

static void test_errors_are_atomic(void **state)
{
    (void)state;
    run_t *r = &g_run;
    /* line 3 fails late (after units, distance, F and motion were decoded): none of it applies */
    run_prog(r, "G0 X1 Y1\nG1 F600 X2\nG20 G91 F1 G2 X5 Y5 I40 G64 P0.1\nX3\n");
    assert_int_equal(r->n_err, 1);
    assert_int_equal(r->errs[0].code, LSM_E_GC_ARC_FORM);
    assert_int_equal(r->errs[0].line, 3);
    assert_int_equal(r->n, 3);
    assert_mm(r->blocks[2].end[0], 3); /* absolute mm, G1, from X2 */
    assert_mm(r->blocks[2].start[0], 2);
    assert_int_equal(r->blocks[2].type, LSM_GCODE_BLOCK_LINEAR);
    assert_rel(r->blocks[2].feed_mm_s, 10);
    assert_int_equal(r->modal.units, LSM_GCODE_UNITS_MM);
    assert_int_equal(r->modal.distance, LSM_GCODE_ABSOLUTE);
    assert_true(r->modal.blend_tol_mm == 0);
    /* error positions across a multi-line program */
    const char *prog = "G0 X0\n\n(comment)\n  G1 X1 Y2 X3\n";
    run_prog_opt(r, prog, strlen(prog), 5, NULL);
    assert_int_equal(r->n_err, 1);
    assert_int_equal(r->errs[0].line, 4);
    assert_int_equal(r->errs[0].column, 12);
    assert_int_equal(r->errs[0].code, LSM_E_GC_WORD_REPEATED);
}

/* The malformed inputs the issue lists, one per line of one program streamed in chunks of several sizes: each
 * is reported with its exact code, physical line and column, changes nothing, and the parser goes on with the
 * next line (the last line still moves from where the first one left the machine). */
static void test_err_issue_cases_in_one_program(void **state)
{
    (void)state;
    static char prog[2048];
    size_t n = 0;
    n += (size_t)snprintf(prog + n, sizeof prog - n,
                          "G21 G90 G17 F600\n"         /* 1 ok */
                          "G1 X1 Q5\n"                 /* 2 unknown word Q, column 7 */
                          "G1 X\n"                     /* 3 missing argument, column 4 */
                          "G2 X30 Y0 R10\n"            /* 4 chord 30 > diameter 20, column 11 (R) */
                          "G2 X10 Y0 I0 J0\n"          /* 5 centre on the start, column 11 (I) */
                          "G2 X10 Y0 I5.1\n"           /* 6 radii 5.1 / 4.9 differ, column 1 (G2) */
                          "G1 X12345678901234567890\n" /* 7 number too large, column 4 */
                          "G1 X2");                    /* 8 overlong: column LSM_GCODE_MAX_LINE + 1 */
    memset(prog + n, ' ', LSM_GCODE_MAX_LINE + 40);
    n += LSM_GCODE_MAX_LINE + 40;
    static const char junk[] = "Y1\n\x89PNG\x1a\x00\x7f\xff\n" /* 9 binary junk, column 1 */
                               "G1 X3\n";                      /* 10 ok */
    memcpy(prog + n, junk, sizeof junk - 1);
    n += sizeof junk - 1;
    static const struct {
        lsm_status code;
        uint32_t line, column;
    } want[] = {
        {LSM_E_GC_UNKNOWN_WORD, 2, 7},
        {LSM_E_GC_MISSING_ARG, 3, 4},
        {LSM_E_GC_ARC_RADIUS, 4, 11},
        {LSM_E_GC_ARC_CENTRE, 5, 11},
        {LSM_E_GC_ARC_MISMATCH, 6, 1},
        {LSM_E_GC_NUMBER_RANGE, 7, 4},
        {LSM_E_GC_LINE_TOO_LONG, 8, LSM_GCODE_MAX_LINE + 1},
        {LSM_E_GC_BINARY, 9, 1},
    };
    static const size_t chunks[] = {0, 1, 3, 7, 64, 1000};
    for (size_t c = 0; c < sizeof chunks / sizeof chunks[0]; c++) {
        run_prog_opt(&g_run, prog, n, chunks[c], NULL);
        assert_int_equal(g_run.n_err, (int)(sizeof want / sizeof want[0]));
        for (size_t k = 0; k < sizeof want / sizeof want[0]; k++) {
            if (g_run.errs[k].code != want[k].code || g_run.errs[k].line != want[k].line ||
                g_run.errs[k].column != want[k].column)
                print_error("chunk %zu, error %zu: got %d at %u:%u, expected %d at %u:%u\n", chunks[c], k,
                            (int)g_run.errs[k].code, (unsigned)g_run.errs[k].line, (unsigned)g_run.errs[k].column,
                            (int)want[k].code, (unsigned)want[k].line, (unsigned)want[k].column);
            assert_int_equal(g_run.errs[k].code, want[k].code);
            assert_int_equal(g_run.errs[k].line, want[k].line);
            assert_int_equal(g_run.errs[k].column, want[k].column);
        }
        assert_int_equal(g_run.n, 1); /* only line 10 moved, from the origin */
        assert_int_equal(g_run.blocks[0].line, 10);
        assert_mm(g_run.blocks[0].start[0], 0);
        assert_mm(g_run.blocks[0].end[0], 3);
        assert_int_equal(g_run.lines, 10);
    }
}

static void test_status_strings(void **state)
{
    (void)state;
    for (int c = -80; c >= -97; c--) {
        const char *s = lsm_status_str((lsm_status)c);
        assert_non_null(s);
        assert_true(strncmp(s, "G-code:", 7) == 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_and_init),
        cmocka_unit_test(test_linear_rapid_feed),
        cmocka_unit_test(test_incremental),
        cmocka_unit_test(test_inch),
        cmocka_unit_test(test_path_control_modal),
        cmocka_unit_test(test_comments_numbers_lines),
        cmocka_unit_test(test_block_delete_percent_end),
        cmocka_unit_test(test_arc_ijk_xy),
        cmocka_unit_test(test_arc_full_circle_turns),
        cmocka_unit_test(test_arc_radius_form),
        cmocka_unit_test(test_arc_planes),
        cmocka_unit_test(test_streaming_chunks),
        cmocka_unit_test(test_err_unknown_missing_syntax),
        cmocka_unit_test(test_err_range_and_long_lines),
        cmocka_unit_test(test_err_binary),
        cmocka_unit_test(test_err_repeat_modal_feed),
        cmocka_unit_test(test_err_arcs),
        cmocka_unit_test(test_err_unused_values_axes),
        cmocka_unit_test(test_errors_are_atomic),
        cmocka_unit_test(test_err_issue_cases_in_one_program),
        cmocka_unit_test(test_status_strings),
    };
    return cmocka_run_group_tests_name(LSM_REAL_IS_FLOAT ? "gcode_float" : "gcode", tests, NULL, NULL);
}
