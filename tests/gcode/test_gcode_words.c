/*
 * test_gcode_words.c: the words CAM output uses (issue 15), built for double and float.
 *
 * Machine-function events (S, T, M6, M3-M5, M7-M9, G4, G43/G49, M0/M1, M2/M30) in LinuxCNC's order with
 * their line, position among the line's blocks and exact-stop flag; the post-processor preamble; centre-form
 * full circles without end words; work offsets (G54-G59, G10 L2/L20, G92/G92.1, G53); G28/G30 with stored
 * positions; G90.1; error texts that quote the word; refused lines that change nothing.
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
#define PI 3.14159265358979323846

static lsm_gcode g_p;

static void start(const lsm_gcode_options *opt)
{
    assert_int_equal(lsm_gcode_init(&g_p, opt), LSM_OK);
}

static lsm_status line(const char *text, lsm_gcode_result *res)
{
    return lsm_gcode_parse_line(&g_p, text, strlen(text), res);
}

static void ok(const char *text, lsm_gcode_result *res)
{
    lsm_status st = line(text, res);
    if (st != LSM_OK) {
        char msg[128];
        print_error("\"%s\": %s\n", text, lsm_gcode_error_text(&res->err, msg, sizeof msg));
    }
    assert_int_equal(st, LSM_OK);
}

static void expect_text(const char *text, lsm_status code, uint32_t col, const char *message)
{
    lsm_gcode_result res;
    lsm_status st = line(text, &res);
    char msg[128];
    lsm_gcode_error_text(&res.err, msg, sizeof msg);
    if (st != code || res.err.column != col || strcmp(msg, message) != 0)
        print_error("\"%s\": got %d col %u \"%s\", expected %d col %u \"%s\"\n", text, (int)st,
                    (unsigned)res.err.column, msg, (int)code, (unsigned)col, message);
    assert_int_equal(st, code);
    assert_int_equal(res.err.column, col);
    assert_string_equal(msg, message);
    assert_int_equal(res.n_blocks, 0);
    assert_int_equal(res.n_events, 0);
}

static void near(double got, double want)
{
    assert_true(fabs(got - want) <= TOL_MM * (1 + fabs(want)));
}

static void test_events_in_linuxcnc_order(void **state)
{
    (void)state;
    start(NULL);
    lsm_gcode_result r;
    ok("G0 X1", &r);
    /* every machine function on one line: S T M6 M3 M7 M8 G4 G43, the motion, then M0 */
    ok("N10 M8 G4 P0.5 M3 M6 T7 S12000 M7 G43 H7 G1 X5 F600 M0", &r);
    assert_int_equal(r.n_blocks, 1);
    static const lsm_gcode_event_kind want[] = {LSM_GCODE_EV_SPINDLE_SPEED, LSM_GCODE_EV_TOOL_SELECT,
                                                LSM_GCODE_EV_TOOL_CHANGE,   LSM_GCODE_EV_SPINDLE_CW,
                                                LSM_GCODE_EV_COOLANT_MIST,  LSM_GCODE_EV_COOLANT_FLOOD,
                                                LSM_GCODE_EV_DWELL,         LSM_GCODE_EV_TOOL_LENGTH,
                                                LSM_GCODE_EV_PAUSE};
    assert_int_equal(r.n_events, 9);
    for (int k = 0; k < 9; k++) {
        assert_int_equal(r.events[k].kind, want[k]);
        assert_int_equal(r.events[k].line, 2);
        assert_int_equal(r.events[k].at_block, k == 8 ? 1 : 0);
    }
    near(r.events[0].value, 12000);
    assert_true(r.events[0].exact_stop);
    assert_int_equal(r.events[1].tool, 7);
    assert_false(r.events[1].exact_stop); /* T only prepares */
    assert_int_equal(r.events[2].tool, 7);
    assert_true(r.events[2].exact_stop);
    near(r.events[3].value, 12000);
    near(r.events[6].value, 0.5);
    assert_int_equal(r.events[7].tool, 7);
    assert_false(r.events[7].exact_stop);
    assert_true(r.events[8].exact_stop);
    assert_int_equal(r.modal.spindle, 3);
    assert_true(r.modal.mist && r.modal.flood);
    assert_int_equal(r.modal.tool_loaded, 7);
    assert_true(r.modal.tool_length_on);
    /* M4 keeps the speed; M5, M9, G49 */
    ok("M4", &r);
    assert_int_equal(r.n_events, 1);
    assert_int_equal(r.events[0].kind, LSM_GCODE_EV_SPINDLE_CCW);
    near(r.events[0].value, 12000);
    ok("M5 M9 G49", &r);
    assert_int_equal(r.n_events, 3);
    assert_int_equal(r.events[0].kind, LSM_GCODE_EV_SPINDLE_STOP);
    assert_int_equal(r.events[1].kind, LSM_GCODE_EV_COOLANT_OFF);
    assert_int_equal(r.events[2].kind, LSM_GCODE_EV_TOOL_LENGTH_OFF);
    assert_false(r.modal.mist || r.modal.flood || r.modal.tool_length_on);
    /* G43 without H takes the loaded tool */
    ok("G43", &r);
    assert_int_equal(r.events[0].tool, 7);
}

static void test_end_stops_spindle_and_coolant(void **state)
{
    (void)state;
    start(NULL);
    lsm_gcode_result r;
    ok("M3 S1000 M8", &r);
    ok("G0 X10 M30", &r);
    assert_int_equal(r.n_events, 3);
    assert_int_equal(r.events[0].kind, LSM_GCODE_EV_SPINDLE_STOP);
    assert_int_equal(r.events[1].kind, LSM_GCODE_EV_COOLANT_OFF);
    assert_int_equal(r.events[2].kind, LSM_GCODE_EV_END);
    assert_int_equal(r.events[2].tool, 30);
    assert_int_equal(r.events[2].at_block, 1);
    assert_true(r.end_of_program);
    ok("G0 X20", &r); /* after the end: read and ignored, flagged */
    assert_true(r.ignored);
    assert_int_equal(r.n_blocks, 0);
    ok("   ", &r);
    assert_false(r.ignored);
    /* the closing '%' ends like M2 */
    start(NULL);
    ok("%", &r);
    ok("M3 S100", &r);
    ok("%", &r);
    assert_int_equal(r.n_events, 2);
    assert_int_equal(r.events[0].kind, LSM_GCODE_EV_SPINDLE_STOP);
    assert_int_equal(r.events[1].kind, LSM_GCODE_EV_END);
}

static void test_pauses_and_dwell(void **state)
{
    (void)state;
    lsm_gcode_options o;
    lsm_gcode_default_options(&o);
    start(&o);
    lsm_gcode_result r;
    ok("M1", &r);
    assert_int_equal(r.n_events, 1);
    assert_int_equal(r.events[0].kind, LSM_GCODE_EV_OPTIONAL_PAUSE);
    o.optional_stop = false;
    start(&o);
    ok("M1", &r);
    assert_int_equal(r.n_events, 0);
    ok("G4 P2", &r);
    assert_int_equal(r.events[0].kind, LSM_GCODE_EV_DWELL);
    near(r.events[0].value, 2);
    ok("G20 G4 P1.5", &r); /* seconds in inch mode too */
    near(r.events[0].value, 1.5);
    expect_text("G4", LSM_E_GC_MISSING_ARG, 1, "G4 needs P (seconds) 'G4'");
    expect_text("G4 P-1", LSM_E_GC_BAD_VALUE, 4, "negative dwell 'P-1'");
    expect_text("G4 P1 G64 P0.1", LSM_E_GC_WORD_REPEATED, 11, "word repeated on one line 'P0.1'");
    expect_text("M0 M1", LSM_E_GC_MODAL_CONFLICT, 4, "two M words of one modal group 'M1'");
    expect_text("M7 M9", LSM_E_GC_MODAL_CONFLICT, 4, "two M words of one modal group 'M9'");
    expect_text("M3 M5", LSM_E_GC_MODAL_CONFLICT, 4, "two M words of one modal group 'M5'");
    expect_text("S-100", LSM_E_GC_BAD_VALUE, 1, "negative spindle speed 'S-100'");
    expect_text("T1.5", LSM_E_GC_BAD_VALUE, 1, "tool number must be an integer 0..99999 'T1.5'");
    expect_text("H2", LSM_E_GC_UNUSED_WORD, 1, "H without G43 'H2'");
}

static void test_preamble_and_g80(void **state)
{
    (void)state;
    start(NULL);
    lsm_gcode_result r;
    ok("G00 G17 G21 G40 G49 G80 G90", &r);
    assert_int_equal(r.modal.motion, LSM_GCODE_MOTION_RAPID);
    ok("G90 G94 G91.1 G40 G49 G17 G54 G64 P0.01", &r);
    ok("G80 G1 X1 F100", &r); /* G80 first, then a motion code: the motion code wins */
    assert_int_equal(r.n_blocks, 1);
    assert_int_equal(r.blocks[0].type, LSM_GCODE_BLOCK_LINEAR);
    ok("G80", &r);
    assert_int_equal(r.modal.motion, LSM_GCODE_MOTION_NONE);
    expect_text("G0 G1 X1", LSM_E_GC_MODAL_CONFLICT, 4, "two G words of one modal group 'G1'");
}

static void test_full_circle_without_end_words(void **state)
{
    (void)state;
    start(NULL);
    lsm_gcode_result r;
    ok("G0 X1 Y2", &r);
    ok("G2 I.5 J.5 F300", &r); /* LinuxCNC's 3dtest.ngc */
    assert_int_equal(r.n_blocks, 1);
    const lsm_gcode_block *b = &r.blocks[0];
    assert_int_equal(b->type, LSM_GCODE_BLOCK_ARC);
    near(b->angle_rad, 2 * PI);
    near(b->centre[0], 1.5);
    near(b->centre[1], 2.5);
    near(b->end[0], 1);
    near(b->end[1], 2);
    ok("G3 I1 Z-1 P2", &r); /* a helix of two turns, no in-plane end word */
    near(r.blocks[0].angle_rad, 4 * PI);
    near(r.blocks[0].helix_mm, -1);
    expect_text("G2 R2", LSM_E_GC_ARC_FORM, 1, "radius-form arc without an end word in its plane 'G2'");
    /* G90.1: absolute centres */
    ok("G90.1 G2 X3 Y1 I2 J1.5", &r);
    near(r.blocks[0].centre[0], 2);
    near(r.blocks[0].centre[1], 1.5);
}

static void test_work_offsets(void **state)
{
    (void)state;
    start(NULL);
    lsm_gcode_result r;
    ok("G10 L2 P1 X100 Y50", &r); /* G54 origin */
    ok("G10 L2 P2 X-10", &r);     /* G55 origin */
    ok("G0 X1 Y1", &r);
    near(r.blocks[0].end[0], 101);
    near(r.blocks[0].end[1], 51);
    ok("G55 X1", &r);
    near(r.blocks[0].end[0], -9);
    near(r.blocks[0].end[1], 51); /* Y stays: not programmed */
    ok("G53 X0 Y0", &r);          /* machine coordinates, this line only */
    near(r.blocks[0].end[0], 0);
    near(r.blocks[0].end[1], 0);
    ok("X2", &r);
    near(r.blocks[0].end[0], -8);
    /* G10 L20: the current point gets X5 in G56 */
    ok("G10 L20 P3 X5", &r);
    ok("G56 X6", &r);
    near(r.blocks[0].end[0], -7);
    /* G92: the current point becomes X0; G92.1 clears it */
    ok("G92 X0", &r);
    ok("X1", &r);
    near(r.blocks[0].end[0], -6);
    ok("G92.1", &r);
    ok("X1", &r);
    near(r.blocks[0].end[0], -12);
    /* P0: the system in use; inch values */
    ok("G20 G10 L2 P0 X1", &r);
    ok("G21 X0", &r);
    near(r.blocks[0].end[0], 25.4);
    expect_text("G10 L2 P7 X1", LSM_E_GC_UNSUPPORTED, 8, "unsupported: coordinate systems G59.1-G59.3 (P7)");
    expect_text("G10 L1 P1 Z1", LSM_E_GC_UNSUPPORTED, 5, "unsupported: tool table (G10 L1/L10/L11) (L1)");
    expect_text("G10 L2 P1 R30", LSM_E_GC_UNSUPPORTED, 11, "unsupported: coordinate system rotation (R) (R30)");
    expect_text("G10 P1 X1", LSM_E_GC_MISSING_ARG, 1, "G10 needs L2 or L20 'G10'");
    expect_text("G92", LSM_E_GC_MISSING_ARG, 1, "G92 needs at least one axis word 'G92'");
    expect_text("G91 G53 X1", LSM_E_GC_BAD_VALUE, 5, "G53 in incremental mode (G91) 'G53'");
    expect_text("G10 L2 P1 G1 X1", LSM_E_GC_MODAL_CONFLICT, 11, "two commands use the axis words 'G1'");
}

static void test_home_positions(void **state)
{
    (void)state;
    start(NULL);
    lsm_gcode_result r;
    ok("G0 X10 Y20 Z30", &r);
    ok("G28.1", &r); /* stores (10, 20, 30) */
    ok("G0 X0 Y0 Z0", &r);
    ok("G28", &r); /* straight home */
    assert_int_equal(r.n_blocks, 1);
    near(r.blocks[0].end[0], 10);
    near(r.blocks[0].end[2], 30);
    ok("G0 X1 Y2 Z3", &r);
    ok("G91 G28 Z0", &r); /* Z only, through the (incremental, zero) intermediate point */
    assert_int_equal(r.n_blocks, 1);
    near(r.blocks[0].end[0], 1);
    near(r.blocks[0].end[1], 2);
    near(r.blocks[0].end[2], 30);
    assert_int_equal(r.modal.motion, LSM_GCODE_MOTION_RAPID); /* G28 keeps the motion mode */
    ok("G90 G30 X5", &r);                                     /* intermediate X5, then X to G30's zero */
    assert_int_equal(r.n_blocks, 2);
    near(r.blocks[0].end[0], 5);
    near(r.blocks[1].start[0], 5);
    near(r.blocks[1].end[0], 0);
    near(r.blocks[1].end[2], 30);
    assert_int_equal(r.blocks[1].type, LSM_GCODE_BLOCK_RAPID);
    /* G30.1 stores G30's position; G28's stays */
    ok("G0 X7 Y8 Z9", &r);
    ok("G30.1", &r);
    ok("G0 X0 Y0 Z0", &r);
    ok("G30", &r);
    near(r.blocks[0].end[0], 7);
    near(r.blocks[0].end[2], 9);
    ok("G28", &r);
    near(r.blocks[0].end[0], 10);
    assert_int_equal(r.nonmodal, 280);
    expect_text("G28.1 X1", LSM_E_GC_UNUSED_WORD, 7, "axis words with G28.1, G30.1 or G92.1 'X1'");
}

static void test_every_work_offset(void **state)
{
    (void)state;
    start(NULL);
    lsm_gcode_result r;
    static const char *sel[6] = {"G54", "G55", "G56", "G57", "G58", "G59"};
    char text[48];
    for (int k = 0; k < 6; k++) {
        snprintf(text, sizeof text, "G10 L2 P%d Y%d", k + 1, 10 * (k + 1));
        ok(text, &r);
    }
    for (int k = 0; k < 6; k++) {
        snprintf(text, sizeof text, "%s G0 Y1", sel[k]);
        ok(text, &r);
        assert_int_equal(r.modal.wcs, k + 1);
        near(r.blocks[0].end[1], 10 * (k + 1) + 1);
    }
    ok("G92 Y0", &r); /* G92.2 clears like G92.1 */
    ok("G0 Y1", &r);
    near(r.blocks[0].end[1], 62);
    ok("G92.2", &r);
    ok("G0 Y3", &r);
    assert_int_equal(r.n_blocks, 1);
    near(r.blocks[0].end[1], 63);
}

static void test_error_texts(void **state)
{
    (void)state;
    start(NULL);
    expect_text("G1 X1 Q7", LSM_E_GC_UNKNOWN_WORD, 7, "unknown word 'Q7'");
    expect_text("G1 X#2", LSM_E_GC_UNSUPPORTED, 5, "unsupported: parameters (#2)");
    expect_text("#<depth> = 3", LSM_E_GC_UNSUPPORTED, 1, "unsupported: parameters (#<depth>)");
    expect_text("G1 X[1+2]", LSM_E_GC_UNSUPPORTED, 5, "unsupported: expressions ([1+2])");
    expect_text("o100 sub", LSM_E_GC_UNSUPPORTED, 1, "unsupported: O-words (subroutines, loops, conditionals) (O100)");
    expect_text("G41 D1", LSM_E_GC_UNSUPPORTED, 1, "unsupported: cutter compensation (G41)");
    expect_text("G81 X1 Y1 Z-1 R1", LSM_E_GC_UNSUPPORTED, 1, "unsupported: canned cycles (G81)");
    expect_text("G93", LSM_E_GC_UNSUPPORTED, 1, "unsupported: inverse-time feed (G93)");
    expect_text("M98 P100", LSM_E_GC_UNSUPPORTED, 1, "unsupported: subroutines (M98) (M98)");
    expect_text("g 1 x 1 0 . 5 q 7", LSM_E_GC_UNKNOWN_WORD, 15, "unknown word 'Q7'");
    expect_text("G1 X", LSM_E_GC_MISSING_ARG, 4, "word without a number 'X'");
    expect_text("G1 X1 X2", LSM_E_GC_WORD_REPEATED, 7, "word repeated on one line 'X2'");
    expect_text("G1 X1", LSM_E_GC_NO_FEED, 1, "feed move with no feed (F) before 'G1'");
    expect_text("G0 X1 \x01", LSM_E_GC_BINARY, 7, "binary or non-printable byte '0x01'");
    expect_text("G0 X1 (note", LSM_E_GC_COMMENT, 7, "unclosed comment '('");
    expect_text("G1 X1 = 2", LSM_E_GC_SYNTAX, 7, "syntax error at '='");
    char buf[8];
    lsm_gcode_error e = {0};
    e.code = LSM_E_GC_UNKNOWN_WORD;
    strcpy(e.word, "Q7");
    assert_string_equal(lsm_gcode_error_text(&e, buf, sizeof buf), "unknown"); /* truncated, terminated */
    assert_string_equal(lsm_gcode_event_name(LSM_GCODE_EV_DWELL), "dwell");
    assert_string_equal(lsm_gcode_event_code(LSM_GCODE_EV_TOOL_CHANGE), "M6");
}

static void test_refused_line_changes_nothing(void **state)
{
    (void)state;
    start(NULL);
    lsm_gcode_result r;
    ok("G10 L2 P1 X100 M3 S500", &r);
    const lsm_gcode_modal before = r.modal;
    /* each of these has an error after words that would change state */
    expect_text("G10 L2 P1 X7 Q1", LSM_E_GC_UNKNOWN_WORD, 14, "unknown word 'Q1'");
    expect_text("M5 S10 G55 G28.1 Q1", LSM_E_GC_UNKNOWN_WORD, 18, "unknown word 'Q1'");
    expect_text("G92 X5 F-1", LSM_E_GC_BAD_VALUE, 8, "negative feed 'F-1'");
    ok("G0 X1", &r);
    near(r.blocks[0].end[0], 101);
    assert_int_equal(r.modal.spindle, before.spindle);
    near(r.modal.speed_rpm, 500);
    assert_int_equal(r.modal.wcs, 1);
    ok("G28", &r); /* the stored position is still machine zero */
    near(r.blocks[0].end[0], 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_events_in_linuxcnc_order),
        cmocka_unit_test(test_end_stops_spindle_and_coolant),
        cmocka_unit_test(test_pauses_and_dwell),
        cmocka_unit_test(test_preamble_and_g80),
        cmocka_unit_test(test_full_circle_without_end_words),
        cmocka_unit_test(test_work_offsets),
        cmocka_unit_test(test_home_positions),
        cmocka_unit_test(test_every_work_offset),
        cmocka_unit_test(test_error_texts),
        cmocka_unit_test(test_refused_line_changes_nothing),
    };
    return cmocka_run_group_tests_name(LSM_REAL_IS_FLOAT ? "gcode_words_float" : "gcode_words", tests, NULL, NULL);
}
