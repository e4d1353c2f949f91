/*
 * test_sim_progress.c: the progress bar of long lissom-sim runs (host_sim/progress.c).
 *
 * - the line: phase, a 20-character bar, the percentage (floored, clamped to 100), the machine time;
 * - log style (stderr not a terminal): one line per phase and per 10 % step, nothing in between, a line again
 *   on a phase change; a phase without a fraction is drawn as "...";
 * - terminal style: redrawn in place with '\r', padded over a longer earlier line, cleared at the end;
 * - nothing at all when disabled, or before the delay has passed (short runs stay quiet).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "progress.h"

static void test_format(void **state)
{
    (void)state;
    char buf[160];
    int n = sim_progress_format(buf, sizeof buf, "planning", 0.0, 0.0);
    assert_string_equal(buf, "planning  [....................]   0 %  0.0 s machine time");
    assert_int_equal(n, (int)strlen(buf));
    sim_progress_format(buf, sizeof buf, "drives", 0.449, -1);
    assert_string_equal(buf, "drives    [########............]  44 %");
    sim_progress_format(buf, sizeof buf, "CSV", 1.7, 58.6);
    assert_string_equal(buf, "CSV       [####################] 100 %  58.6 s machine time");
    sim_progress_format(buf, sizeof buf, "plots", -1, -1);
    assert_string_equal(buf, "plots     ...");
    /* a short buffer is truncated, not overrun */
    char small[8];
    memset(small, 'x', sizeof small);
    sim_progress_format(small, sizeof small, "planning", 0.5, 3.0);
    assert_int_equal(strlen(small), 7);
}

/* Everything drawn to a temporary file, read back. */
static char *drawn(FILE *f)
{
    static char text[8192];
    fflush(f);
    rewind(f);
    const size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = '\0';
    fclose(f);
    return text;
}

static int count(const char *s, const char *what)
{
    int n = 0;
    for (const char *p = strstr(s, what); p; p = strstr(p + 1, what))
        n++;
    return n;
}

static void test_log_style(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    sim_progress p;
    sim_progress_init(&p, f, true, false, 0);
    static const double done[] = {0, 0.01, 0.05, 0.099, 0.1, 0.15, 0.31, 0.32, 0.95, 1.0};
    for (size_t k = 0; k < sizeof done / sizeof done[0]; k++)
        sim_progress_update(&p, "planning", done[k], 0.5 * (double)k);
    char phase[] = "drives"; /* a phase name that is not the same literal: compared by content */
    sim_progress_update(&p, phase, 0.0, -1);
    sim_progress_update(&p, "drives", 0.05, -1);
    sim_progress_update(&p, "plots", -1, -1);
    sim_progress_finish(&p);
    const char *t = drawn(f);
    /* planning: 0, 10, 31, 95, 100 %; drives: 0 %; plots */
    assert_int_equal(count(t, "\n"), 7);
    assert_int_equal(count(t, "progress: planning"), 5);
    assert_non_null(strstr(t, "progress: planning  [##..................]  10 %  2.0 s machine time\n"));
    assert_non_null(strstr(t, "progress: planning  [######..............]  31 %  3.0 s machine time\n"));
    assert_non_null(strstr(t, "progress: planning  [####################] 100 %  4.5 s machine time\n"));
    assert_int_equal(count(t, "progress: drives"), 1);
    assert_non_null(strstr(t, "progress: plots     ...\n"));
    assert_null(strchr(t, '\r'));
}

static void test_terminal_style(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    sim_progress p;
    sim_progress_init(&p, f, true, true, 0);
    sim_progress_update(&p, "planning", 0.25, 12.0);
    sim_progress_update(&p, "planning", 0.26, 12.5); /* within 0.1 s of the last redraw: skipped */
    sim_progress_update(&p, "drives", 0.5, -1);      /* a new phase: drawn at once, padded */
    sim_progress_finish(&p);
    const char *t = drawn(f);
    assert_null(strchr(t, '\n'));
    assert_int_equal(count(t, "\r"), 4); /* two redraws, and the clearing \r ... \r */
    assert_non_null(strstr(t, "\rplanning  [#####...............]  25 %  12.0 s machine time  "));
    assert_null(strstr(t, " 26 %"));
    const char *d = strstr(t, "\rdrives    [##########..........]  50 %  ");
    assert_non_null(d);
    /* the drives line is as wide as the longer planning line before it (padded with spaces), and the end
     * clears that width */
    const char *first_end = strchr(t + 1, '\r');
    const char *second_end = strchr(d + 1, '\r');
    assert_int_equal(second_end - d, first_end - t);
    const char *last = strrchr(t, '\r');
    assert_int_equal(last - second_end, first_end - t);
    for (const char *c = second_end + 1; c < last; c++)
        assert_int_equal(*c, ' ');
}

static void test_quiet(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    sim_progress p;
    sim_progress_init(&p, f, false, true, 0); /* disabled */
    sim_progress_update(&p, "planning", 0.5, 1.0);
    sim_progress_finish(&p);
    sim_progress_init(&p, f, true, false, 3600); /* enabled, but the run is shorter than the delay */
    sim_progress_update(&p, "planning", 0.5, 1.0);
    sim_progress_update(&p, "drives", 1.0, 1.0);
    sim_progress_finish(&p);
    sim_progress_init(&p, NULL, true, false, 0); /* nowhere to draw */
    sim_progress_update(&p, "planning", 0.5, 1.0);
    sim_progress_finish(&p);
    sim_progress_update(NULL, "planning", 0.5, 1.0);
    sim_progress_finish(NULL);
    assert_string_equal(drawn(f), "");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_format),
        cmocka_unit_test(test_log_style),
        cmocka_unit_test(test_terminal_style),
        cmocka_unit_test(test_quiet),
    };
    return cmocka_run_group_tests_name("sim_progress", tests, NULL, NULL);
}
