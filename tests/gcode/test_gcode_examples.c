/*
 * test_gcode_examples.c: every shipped example program (host_sim/examples, every .ngc file) goes through the G-code
 * parser without an error, ends with M2, and has the geometry make_examples.py meant it to have:
 *   - shahzadeh_corner: line 15.5, CCW arc R10 of 90 degrees about (15.5, 10), line 15.5;
 *   - trident: a closed G1 polyline of 612 chords whose length is the spline's 59.168013 mm (within
 *     5 um: chords stay within 1 um of the curve) and no chord longer than 0.1 mm;
 *   - circle_chords: 628 chords of 0.1 mm (within the 0.1 um print rounding);
 *   - pocket: 2 mm deep, six rings of four 90-degree R-form arcs with R >= 1 mm;
 *   - surface_finish: every point lies on z = 2 exp(-r^2/128) + 0.5 sin(2 pi x/40) cos(2 pi y/40).
 * Files are found from this file's path (__FILE__) or $LSM_EXAMPLES_DIR. Built for double and float
 * (float tolerances: a few ulps of 40 mm).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "gcode.h"

#define PI 3.14159265358979323846
#define EPS (LSM_REAL_IS_FLOAT ? 2e-5 : 1e-9)

static char g_dir[1024];

typedef struct {
    lsm_gcode_block b[4096];
    int n;
    bool ended;
    uint32_t lines;
} prog_t;

static prog_t g_prog;

static void find_dir(void)
{
    const char *env = getenv("LSM_EXAMPLES_DIR");
    if (env) {
        snprintf(g_dir, sizeof g_dir, "%s", env);
        return;
    }
    snprintf(g_dir, sizeof g_dir, "%s%s", LSM_REPO_DIR,
             "/host_sim/examples"); /* the repository (tests/CMakeLists.txt) */
}

static const prog_t *load(const char *name)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", g_dir, name);
    FILE *f = fopen(path, "rb");
    if (!f)
        print_error("cannot open %s\n", path);
    assert_non_null(f);
    prog_t *p = &g_prog;
    memset(p, 0, sizeof *p);
    static lsm_gcode gc;
    assert_int_equal(lsm_gcode_init(&gc, NULL), LSM_OK);
    char buf[4096];
    size_t n;
    lsm_gcode_result res;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) {
        size_t off = 0;
        while (off < n) {
            size_t used;
            lsm_status st = lsm_gcode_feed(&gc, buf + off, n - off, &used, &res);
            off += used;
            if (st != LSM_OK)
                print_error("%s:%u:%u: %s\n", name, (unsigned)res.err.line, (unsigned)res.err.column,
                            lsm_status_str(st));
            assert_int_equal(st, LSM_OK);
            for (int k = 0; k < res.n_blocks; k++) {
                assert_true(p->n < 4096);
                p->b[p->n++] = res.blocks[k];
            }
            if (res.complete)
                p->lines = res.line;
        }
    }
    fclose(f);
    assert_int_equal(lsm_gcode_finish(&gc, &res), LSM_OK);
    p->ended = res.end_of_program;
    assert_true(p->ended);
    for (int k = 1; k < p->n; k++)
        for (int a = 0; a < 6; a++)
            assert_true(p->b[k].start[a] == p->b[k - 1].end[a]);
    return p;
}

static double seg_len(const lsm_gcode_block *b)
{
    return sqrt(pow((double)(b->end[0] - b->start[0]), 2) + pow((double)(b->end[1] - b->start[1]), 2) +
                pow((double)(b->end[2] - b->start[2]), 2));
}

static void test_shahzadeh(void **state)
{
    (void)state;
    const prog_t *p = load("shahzadeh_corner.ngc");
    assert_int_equal(p->n, 3);
    assert_int_equal(p->b[0].type, LSM_GCODE_BLOCK_LINEAR);
    assert_true(fabs(seg_len(&p->b[0]) - 15.5) < EPS);
    assert_true(fabs((double)p->b[0].feed_mm_s - 50.0) < 1e-4); /* F3000 */
    const lsm_gcode_block *a = &p->b[1];
    assert_int_equal(a->type, LSM_GCODE_BLOCK_ARC);
    assert_int_equal(a->dir, 1);
    assert_true(fabs((double)a->radius_mm - 10) < EPS);
    assert_true(fabs((double)a->angle_rad - PI / 2) < EPS);
    assert_true(fabs((double)a->centre[0] - 15.5) < EPS && fabs((double)a->centre[1] - 10) < EPS);
    assert_true(fabs(seg_len(&p->b[2]) - 15.5) < EPS);
}

static void test_trident(void **state)
{
    (void)state;
    const prog_t *p = load("trident.ngc");
    assert_int_equal(p->n, 613); /* G0 to the start + 612 chords */
    assert_int_equal(p->b[0].type, LSM_GCODE_BLOCK_RAPID);
    double len = 0, longest = 0;
    for (int k = 1; k < p->n; k++) {
        assert_int_equal(p->b[k].type, LSM_GCODE_BLOCK_LINEAR);
        assert_true(fabs((double)p->b[k].feed_mm_s - 2500.0 / 60) < 1e-4);
        double l = seg_len(&p->b[k]);
        len += l;
        if (l > longest)
            longest = l;
    }
    printf("trident polyline: %.6f mm (spline 59.168013), longest chord %.4f mm\n", len, longest);
    assert_true(fabs(len - 59.168013) < 0.005);
    assert_true(longest <= 0.1 + 1e-4);
    /* closed: back at (10, 0) */
    assert_true(fabs((double)p->b[p->n - 1].end[0] - 10) < EPS && fabs((double)p->b[p->n - 1].end[1]) < EPS);
}

static void test_circle(void **state)
{
    (void)state;
    const prog_t *p = load("circle_chords.ngc");
    assert_int_equal(p->n, 629);
    const double r = 0.05 / sin(PI / 628);
    for (int k = 1; k < p->n; k++) {
        assert_true(fabs(seg_len(&p->b[k]) - 0.1) < 1.5e-4);
        double rr = hypot((double)p->b[k].end[0], (double)p->b[k].end[1]);
        assert_true(fabs(rr - r) < 1e-4);
    }
}

static void test_pocket(void **state)
{
    (void)state;
    const prog_t *p = load("pocket.ngc");
    int arcs = 0;
    double zmin = 1e9;
    for (int k = 0; k < p->n; k++) {
        const lsm_gcode_block *b = &p->b[k];
        const double x = (double)b->end[0], y = (double)b->end[1], z = (double)b->end[2];
        if (z < zmin)
            zmin = z;
        if (b->type == LSM_GCODE_BLOCK_ARC) {
            arcs++;
            assert_int_equal(b->dir, 1);
            assert_true((double)b->radius_mm >= 1 - EPS);
            assert_true(fabs((double)b->angle_rad - PI / 2) < 1e-6);
            assert_true(fabs(z + 2) < EPS); /* at depth */
        }
        /* inside the 40 x 30 pocket */
        assert_true(x >= -EPS && x <= 40 + EPS && y >= -EPS && y <= 30 + EPS);
    }
    assert_int_equal(arcs, 24);
    assert_true(fabs(zmin + 2) < EPS);
    assert_int_equal(p->n, 58);
}

static void test_surface(void **state)
{
    (void)state;
    const prog_t *p = load("surface_finish.ngc");
    int on = 0;
    double worst = 0;
    for (int k = 0; k < p->n; k++) {
        const lsm_gcode_block *b = &p->b[k];
        if (b->type != LSM_GCODE_BLOCK_LINEAR || b->end[2] > 5)
            continue;
        double x = b->end[0], y = b->end[1];
        double z = 2 * exp(-((x - 20) * (x - 20) + (y - 20) * (y - 20)) / 128.0) +
                   0.5 * sin(2 * PI * x / 40) * cos(2 * PI * y / 40);
        double e = fabs(z - (double)b->end[2]);
        if (e > worst)
            worst = e;
        on++;
    }
    assert_int_equal(on, 41 * 80 + 40 + 1); /* 41 passes of 80 moves, 40 step-overs, the first plunge */
    assert_true(worst < 5e-5 + EPS);
}

int main(void)
{
    find_dir();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shahzadeh), cmocka_unit_test(test_trident), cmocka_unit_test(test_circle),
        cmocka_unit_test(test_pocket),    cmocka_unit_test(test_surface),
    };
    return cmocka_run_group_tests_name(LSM_REAL_IS_FLOAT ? "gcode_examples_float" : "gcode_examples", tests, NULL,
                                       NULL);
}
