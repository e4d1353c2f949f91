/*
 * test_gcode_fuzz.c: randomized properties of the G-code parser (firmware/gcode/gcode.c).
 *
 *   test_gcode_fuzz [seed] [count]      (default: seed 1, 20000 programs; a soak run passes more)
 *
 * Each program is ~20 lines drawn from a grammar of valid words (all G/M codes of the subset, arcs in
 * both forms and all planes, inch/mm, absolute/incremental, comments, N words), then mutated: random
 * bytes (including NUL, control and non-ASCII), deleted or duplicated characters, digit strings of
 * extreme length, and overlong lines. Properties checked on every line:
 *   1. streaming the program in random chunk sizes gives exactly the results of parsing it line by
 *      line with lsm_gcode_parse_line (status, column, blocks bit for bit, modal state);
 *   2. a status is LSM_OK or one of the G-code codes (-80 .. -97), with 1 <= column <= length + 1 and
 *      the line number of the line; an erroneous line emits no block and changes no state;
 *   3. blocks chain (each starts where the previous position was), every value is finite, and arcs
 *      are consistent: the radius is the start-centre distance, the end radius is within the
 *      LinuxCNC tolerance of it, and 0 < angle <= 2 pi (turns + 1).
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
#include "lsm_test_rng.h"

static uint64_t g_seed = 1;
static long g_count = 20000;

static uint64_t rng_state;
static int rint_(int n)
{
    return (int)(test_urand(&rng_state) * n);
}
static double rdouble(double lo, double hi)
{
    return lo + (hi - lo) * test_urand(&rng_state);
}

#define MAX_PROG 16384

static size_t append(char *buf, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(buf + n, MAX_PROG - n, fmt, ap);
    va_end(ap);
    if (k < 0)
        return n;
    n += (size_t)k;
    return n < MAX_PROG ? n : MAX_PROG - 1;
}

static size_t gen_line(char *buf, size_t n)
{
    static const char *const modal[] = {"G17", "G18", "G19", "G20", "G21", "G90", "G91", "G61", "G64", "G64 P0.02",
                                        "G94", "G40", "G49", "G54", "G80", "G0",  "G1",  "G2",  "G3"};
    static const char *const axes = "XYZABC";
    if (rint_(10) == 0)
        n = append(buf, n, "N%d ", rint_(1000));
    int kind = rint_(10);
    if (kind == 0) {
        n = append(buf, n, "%s", modal[rint_((int)(sizeof modal / sizeof modal[0]))]);
    } else if (kind <= 4) { /* straight move */
        n = append(buf, n, "G%d", rint_(2));
        int na = 1 + rint_(3);
        for (int i = 0; i < na; i++)
            n = append(buf, n, " %c%.3f", axes[rint_(6)], rdouble(-50, 50));
        if (rint_(3) == 0)
            n = append(buf, n, " F%d", rint_(3000));
    } else if (kind <= 7) { /* arc */
        static const char *const planes[] = {"", "G17 ", "G18 ", "G19 "};
        n = append(buf, n, "%sG%d", planes[rint_(4)], 2 + rint_(2));
        n = append(buf, n, " X%.3f Y%.3f", rdouble(-20, 20), rdouble(-20, 20));
        if (rint_(2))
            n = append(buf, n, " Z%.3f", rdouble(-20, 20));
        if (rint_(3) == 0)
            n = append(buf, n, " R%.3f", rdouble(-30, 30));
        else
            n = append(buf, n, " I%.3f J%.3f", rdouble(-20, 20), rdouble(-20, 20));
        if (rint_(2))
            n = append(buf, n, " K%.3f", rdouble(-20, 20));
        if (rint_(5) == 0)
            n = append(buf, n, " P%d", rint_(4));
        if (rint_(2))
            n = append(buf, n, " F%d", 1 + rint_(3000));
    } else if (kind == 8) {
        n = append(buf, n, "(comment %d) ; tail", rint_(100));
    } else {
        /* arcs that are valid wherever they start: incremental, in G17, then back to G90 */
        double r = rdouble(0.5, 20), t0 = rdouble(0, 6.3), phi = rdouble(-6.3, 6.3);
        double i = -r * cos(t0), j = -r * sin(t0);
        int form = rint_(3);
        if (form == 0) /* centre form, end on the circle */
            n = append(buf, n, "G17 G91 G%d X%.4f Y%.4f I%.4f J%.4f F600\n", phi > 0 ? 3 : 2, i + r * cos(t0 + phi),
                       j + r * sin(t0 + phi), i, j);
        else if (form == 1) /* full circle, maybe helical with turns */
            n = append(buf, n, "G17 G91 G%d X0 Y0 Z%.3f I%.4f J%.4f P%d F600\n", 2 + rint_(2), rdouble(-2, 2), i, j,
                       1 + rint_(3));
        else { /* radius form, R at least half the chord */
            double dx = rdouble(-10, 10), dy = rdouble(-10, 10), c = hypot(dx, dy);
            n = append(buf, n, "G17 G91 G%d X%.4f Y%.4f R%.4f F600\n", 2 + rint_(2), dx, dy,
                       (rint_(2) ? 1 : -1) * (0.5 * c + rdouble(0.01, 10)));
        }
        n = append(buf, n, "G90");
    }
    return append(buf, n, rint_(8) == 0 ? "\r\n" : "\n");
}

static void mutate(char *buf, size_t *len)
{
    int kinds = rint_(4); /* number of mutations */
    for (int m = 0; m<kinds && * len> 2 && *len < MAX_PROG - 600; m++) {
        size_t at = (size_t)rint_((int)*len);
        switch (rint_(6)) {
        case 0: buf[at] = (char)rint_(256); break; /* any byte */
        case 1:
            memmove(buf + at, buf + at + 1, *len - at - 1);
            (*len)--;
            break; /* delete */
        case 2:
            memmove(buf + at + 1, buf + at, *len - at);
            (*len)++;
            break;                                                                /* duplicate */
        case 3: buf[at] = "XYZ.-+()#;%/ \tGMIJKRPFN0123456789"[rint_(34)]; break; /* syntax chars */
        case 4: {                                                                 /* a very long digit string */
            size_t k = (size_t)(10 + rint_(40));
            memmove(buf + at + k, buf + at, *len - at);
            for (size_t i = 0; i < k; i++)
                buf[at + i] = (char)('0' + rint_(10));
            *len += k;
            break;
        }
        default: { /* an overlong line */
            size_t k = LSM_GCODE_MAX_LINE + (size_t)rint_(20) - 10;
            memmove(buf + at + k, buf + at, *len - at);
            memset(buf + at, ' ', k);
            *len += k;
            break;
        }
        }
    }
}

typedef struct {
    lsm_gcode_result r[512];
    int n;
} results;

static results g_a, g_b;
static lsm_gcode g_pa, g_pb;

static void by_lines(const char *buf, size_t len, results *out)
{
    lsm_gcode_init(&g_pa, NULL);
    out->n = 0;
    size_t i = 0;
    while (i < len && out->n < 512) {
        size_t j = i;
        while (j < len && buf[j] != '\n')
            j++;
        size_t l = j - i + (j < len ? 1 : 0);
        lsm_status st = lsm_gcode_parse_line(&g_pa, buf + i, l, &out->r[out->n]);
        assert_int_equal(st, out->r[out->n].status);
        out->n++;
        i = j + 1;
    }
}

static void streamed(const char *buf, size_t len, results *out)
{
    lsm_gcode_init(&g_pb, NULL);
    out->n = 0;
    size_t off = 0;
    lsm_gcode_result res;
    while (off < len) {
        size_t chunk = 1 + (size_t)rint_(rint_(2) ? 8 : 700);
        if (chunk > len - off)
            chunk = len - off;
        size_t sub = 0;
        while (sub < chunk) {
            size_t used;
            lsm_status st = lsm_gcode_feed(&g_pb, buf + off + sub, chunk - sub, &used, &res);
            sub += used;
            if (res.complete && out->n < 512) {
                assert_int_equal(st, res.status);
                out->r[out->n++] = res;
            }
        }
        off += chunk;
    }
    lsm_status fst = lsm_gcode_finish(&g_pb, &res);
    assert_int_equal(fst, res.complete ? res.status : LSM_OK);
    if (res.complete && out->n < 512)
        out->r[out->n++] = res;
}

static bool finite_block(const lsm_gcode_block *b)
{
    const lsm_real *v[] = {b->start, b->end};
    for (int k = 0; k < 2; k++)
        for (int a = 0; a < 6; a++)
            if (!isfinite((double)v[k][a]))
                return false;
    return isfinite((double)b->radius_mm) && isfinite((double)b->angle_rad) && isfinite((double)b->centre[0]) &&
           isfinite((double)b->centre[1]) && isfinite((double)b->centre[2]) && isfinite((double)b->feed_mm_s);
}

static void check_arc(const lsm_gcode_block *b)
{
    int iu = 0, iv = 1;
    if (b->plane == LSM_GCODE_PLANE_ZX) {
        iu = 2;
        iv = 0;
    } else if (b->plane == LSM_GCODE_PLANE_YZ) {
        iu = 1;
        iv = 2;
    }
    const double tol = LSM_REAL_IS_FLOAT ? 1e-4 : 1e-9;
    double r1 = hypot((double)(b->start[iu] - b->centre[iu]), (double)(b->start[iv] - b->centre[iv]));
    double r2 = hypot((double)(b->end[iu] - b->centre[iu]), (double)(b->end[iv] - b->centre[iv]));
    assert_true(fabs(r1 - (double)b->radius_mm) <= tol * (1 + r1));
    assert_true(fabs(r2 - (double)b->radius_end_mm) <= tol * (1 + r2));
    double d = fabs(r1 - r2);
    assert_true(d <= LSM_GCODE_ARC_ABS_TOL_MM + LSM_GCODE_ARC_RADIUS_TOL_MM + tol * (1 + r1));
    assert_true(b->angle_rad > 0);
    assert_true((double)b->angle_rad <= 2 * 3.14159265358979323846 * (b->turns + 1) + 1e-4);
    assert_true(b->dir == 1 || b->dir == -1);
}

static void test_fuzz(void **state)
{
    (void)state;
    static char buf[MAX_PROG];
    rng_state = 0x9E3779B97F4A7C15ull ^ (g_seed * 0x2545F4914F6CDD1Dull);
    long lines = 0, errors = 0, blocks = 0, arcs = 0;
    for (long prog = 0; prog < g_count; prog++) {
        size_t len = 0;
        int nl = 5 + rint_(25);
        for (int i = 0; i < nl && len < MAX_PROG - 1200; i++)
            len = gen_line(buf, len);
        if (rint_(3))
            mutate(buf, &len);
        by_lines(buf, len, &g_a);
        streamed(buf, len, &g_b);
        assert_int_equal(g_a.n, g_b.n);
        lsm_real pos[6] = {0};
        lsm_gcode_modal prev;
        lsm_gcode_init(&g_pa, NULL);
        prev = *lsm_gcode_modal_state(&g_pa);
        for (int k = 0; k < g_a.n; k++) {
            const lsm_gcode_result *a = &g_a.r[k], *b = &g_b.r[k];
            lines++;
            assert_int_equal(a->line, (uint32_t)(k + 1));
            assert_int_equal(b->line, a->line);
            assert_int_equal(a->status, b->status);
            assert_int_equal(a->n_blocks, b->n_blocks);
            assert_memory_equal(&a->modal, &b->modal, sizeof a->modal);
            assert_int_equal(a->end_of_program, b->end_of_program);
            if (a->n_blocks)
                assert_memory_equal(a->blocks, b->blocks, sizeof(lsm_gcode_block) * a->n_blocks);
            if (a->status != LSM_OK) {
                errors++;
                assert_true(a->status <= -80 && a->status >= -97);
                assert_int_equal(a->err.code, a->status);
                assert_int_equal(b->err.column, a->err.column);
                assert_int_equal(a->err.line, a->line);
                assert_true(a->err.column >= 1 && a->err.column <= LSM_GCODE_MAX_LINE + 1);
                assert_int_equal(a->n_blocks, 0);
                assert_memory_equal(&a->modal, &prev, sizeof prev); /* nothing changed */
            }
            for (int j = 0; j < a->n_blocks; j++) {
                const lsm_gcode_block *blk = &a->blocks[j];
                blocks++;
                assert_true(finite_block(blk));
                for (int x = 0; x < 6; x++)
                    assert_true(blk->start[x] == pos[x]);
                for (int x = 0; x < 6; x++)
                    pos[x] = blk->end[x];
                if (blk->type == LSM_GCODE_BLOCK_ARC) {
                    arcs++;
                    check_arc(blk);
                }
                if (blk->type != LSM_GCODE_BLOCK_RAPID)
                    assert_true(blk->feed_mm_s > 0);
            }
            prev = a->modal;
        }
    }
    printf("seed %llu: %ld programs, %ld lines, %ld errors, %ld blocks (%ld arcs)\n", (unsigned long long)g_seed,
           g_count, lines, errors, blocks, arcs);
    assert_true(errors > 0 && arcs > 0 && blocks > errors / 10); /* the generator exercises both sides */
}

int main(int argc, char **argv)
{
    g_seed = (uint64_t)test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_fuzz)};
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count,
                            cmocka_run_group_tests_name(LSM_REAL_IS_FLOAT ? "gcode_fuzz_float" : "gcode_fuzz", tests,
                                                        NULL, NULL));
}
