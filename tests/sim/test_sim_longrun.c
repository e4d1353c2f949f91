/*
 * test_sim_longrun.c: long jobs and stalls in the simulator's run loop (host_sim/pathrun.c, issue 12).
 *
 * - a job longer than the former 3,600 s cap of machine time (G1 X100 at F1: 6,000 s) runs to its end;
 * - a feed hold that nothing resumes is a stall: the run ends with "stalled" about 10 s of machine time after the
 *   machine came to rest, not at a fixed cap;
 * - a hold with a resume pending is waiting, not stalled, however long the wait; so is a dwell (G4 P30);
 * - summary_only (run --no-csv) keeps no setpoint (constant memory) and measures the same numbers as a run that
 *   keeps them: axis v, a, j, deviation, end error and, with the drives, the following error.
 * The machine has a 50 ms cycle so that hours of machine time stay a few hundred thousand cycles.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "machine.h"
#include "pathrun.h"

static const char k_machine[] =
    "{\"format\": \"lissom-machine-1\", \"name\": \"slow\", \"cycle_s\": 0.05, \"lookahead_blocks\": 16, "
    "\"blend_tol_mm\": 0.02, \"axes\": ["
    "{\"name\": \"X\", \"v_max_mm_s\": 50, \"a_max_mm_s2\": 100, \"j_max_mm_s3\": 1000, \"snap_max_mm_s4\": 20000, "
    "\"counts_per_mm\": 1000},"
    "{\"name\": \"Y\", \"v_max_mm_s\": 50, \"a_max_mm_s2\": 100, \"j_max_mm_s3\": 1000, \"snap_max_mm_s4\": 20000, "
    "\"counts_per_mm\": 1000}]}";

static void load(sim_machine *m)
{
    char err[256];
    assert_int_equal(sim_machine_load_text(k_machine, strlen(k_machine), "test", m, err, sizeof err), SIM_MACHINE_OK);
}

static int run_opts(const char *prog, const sim_run_event *ev, size_t n_ev, bool drives, bool summary_only,
                    sim_run_result *r)
{
    static sim_machine m;
    load(&m);
    sim_run_opts o;
    memset(&o, 0, sizeof o);
    o.machine = &m;
    o.text = prog;
    o.len = strlen(prog);
    o.planner = SIM_RUN_LISSOM;
    o.events = ev;
    o.n_events = n_ev;
    o.drives = drives;
    o.summary_only = summary_only;
    memset(r, 0, sizeof *r);
    return sim_run_program(&o, r);
}

static int run(const char *prog, const sim_run_event *ev, size_t n_ev, sim_run_result *r)
{
    return run_opts(prog, ev, n_ev, false, false, r);
}

static void test_long_job(void **state)
{
    (void)state;
    sim_run_result r;
    const int rc = run("G21 G90 G64\nG1 X100 F1\nM2\n", NULL, 0, &r);
    print_message("G1 X100 F1: rc %d, %.1f s of machine time, end error %g mm %s\n", rc, r.duration_s, r.end_error,
                  rc ? r.err : "");
    assert_int_equal(rc, 0);
    assert_true(r.duration_s > 6000.0 && r.duration_s < 6010.0);
    assert_true(r.end_error == 0.0);
    sim_run_free(&r);
}

static void test_hold_without_resume_stalls(void **state)
{
    (void)state;
    sim_run_result r;
    const sim_run_event ev[1] = {{100, 1, 0.0}}; /* hold at 5 s, nothing resumes */
    const int rc = run("G21 G90 G64\nG1 X100 F60\nM2\n", ev, 1, &r);
    print_message("hold, no resume: rc %d: %s\n", rc, r.err);
    assert_int_not_equal(rc, 0);
    assert_non_null(strstr(r.err, "stalled"));
    assert_non_null(strstr(r.err, "held"));
    /* at rest within a second or so of the hold, then 10 s without progress */
    double at = -1;
    const char *p = strstr(r.err, "(at ");
    assert_non_null(p);
    at = strtod(p + 4, NULL);
    assert_true(at > 15.0 && at < 20.0);
    sim_run_free(&r);
}

static void test_long_hold_with_resume_waits(void **state)
{
    (void)state;
    sim_run_result r;
    const sim_run_event ev[2] = {{100, 1, 0.0}, {100 + 20 * 3600, 2, 0.0}}; /* held for an hour, then resumed */
    const int rc = run("G21 G90 G64\nG1 X100 F60\nM2\n", ev, 2, &r);
    print_message("hold for an hour, then resume: rc %d, %.1f s %s\n", rc, r.duration_s, rc ? r.err : "");
    assert_int_equal(rc, 0);
    assert_true(r.duration_s > 3600.0 + 100.0);
    assert_true(r.end_error == 0.0);
    sim_run_free(&r);
}

static void test_long_dwell_waits(void **state)
{
    (void)state;
    sim_run_result r;
    const int rc = run("G21 G90 G64\nG1 X10 F600\nG4 P30\nG1 X20\nM2\n", NULL, 0, &r);
    print_message("G4 P30 between two moves: rc %d, %.1f s %s\n", rc, r.duration_s, rc ? r.err : "");
    assert_int_equal(rc, 0);
    assert_true(r.duration_s > 30.0);
    sim_run_free(&r);
}

static void test_summary_only_same_numbers(void **state)
{
    (void)state;
    static const char prog[] = "G21 G90 G64 P0.05\nG1 X20 F1200\nG1 Y10\nG3 X10 Y20 R10\nG1 X0.5 Y20.3\nG1 X0 Y0\nM2\n";
    for (int drives = 0; drives < 2; drives++) {
        sim_run_result a, b;
        assert_int_equal(run_opts(prog, NULL, 0, drives, false, &a), 0);
        assert_int_equal(run_opts(prog, NULL, 0, drives, true, &b), 0);
        assert_true(a.n > 100 && a.q != NULL);
        assert_true(b.n == 0 && b.q == NULL && b.feed == NULL && b.line == NULL && b.act == NULL);
        assert_true(a.has_act == (drives != 0) && b.has_act == (drives != 0));
        assert_true(a.cycles == b.cycles && a.duration_s == b.duration_s);
        assert_true(a.max_dev_mm == b.max_dev_mm && a.end_error == b.end_error && a.max_dev_mm > 0);
        for (int k = 0; k < LSM_MAX_AXES; k++) {
            assert_true(a.max_v[k] == b.max_v[k] && a.max_a[k] == b.max_a[k] && a.max_j[k] == b.max_j[k]);
            assert_true(a.max_follow_err[k] == b.max_follow_err[k]);
        }
        assert_true(a.max_j[0] > 0 && (drives == 0 || a.max_follow_err[0] > 0));
        sim_run_free(&a);
        sim_run_free(&b);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_long_job),
        cmocka_unit_test(test_hold_without_resume_stalls),
        cmocka_unit_test(test_long_hold_with_resume_waits),
        cmocka_unit_test(test_long_dwell_waits),
        cmocka_unit_test(test_summary_only_same_numbers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
