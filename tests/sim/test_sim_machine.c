/*
 * test_sim_machine.c: machine description files (host_sim/machine.c).
 *
 * - the shipped machines (host_sim/machines, every .json file) load, with the paper values converted to mm
 *   (Kombarov Table 1 Test 2, Beudaert Table 1) and each axis's drive is stable with the machine's
 *   cycle (a 1 mm step settles with bounded overshoot);
 * - rotary axes convert degrees to radians;
 * - bad files are rejected with the right status, and the message names the key and its line:column.
 * The machines directory is found from this file's path (__FILE__), or from $LSM_MACHINES_DIR.
 */
#define _POSIX_C_SOURCE 200809L /* opendir */
#include <dirent.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "machine.h"

#define PI 3.14159265358979323846

static char g_dir[1024];

static const char *machine_path(const char *file)
{
    static char path[1200];
    snprintf(path, sizeof path, "%s/%s", g_dir, file);
    return path;
}

static void find_dir(void)
{
    const char *env = getenv("LSM_MACHINES_DIR");
    if (env) {
        snprintf(g_dir, sizeof g_dir, "%s", env);
        return;
    }
    snprintf(g_dir, sizeof g_dir, "%s%s", LSM_REPO_DIR,
             "/host_sim/machines"); /* the repository (tests/CMakeLists.txt) */
}

static void assert_rel(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol * fabs(b)))
        print_error("%.17g vs %.17g\n", a, b);
    assert_true(fabs(a - b) <= tol * fabs(b));
}

/* 1 mm (or 1 mrad) step through the axis's drive at the machine's cycle. */
static void check_drive_stable(const sim_machine *m, const sim_machine_axis *a)
{
    sim_drive d;
    assert_int_equal(sim_drive_init(&d, &a->drive, m->cycle_s, 0.0), LSM_OK);
    const double step = a->rotary ? 1e-3 : 1.0;
    const int n = (int)(1.0 / m->cycle_s);
    double act = 0, peak = 0, settle = 0;
    for (int k = 0; k < n; k++) {
        assert_int_equal(sim_drive_step(&d, step, 0.0, &act), LSM_OK);
        if (act > peak)
            peak = act;
        if (fabs(act - step) > 0.02 * step)
            settle = (k + 1) * m->cycle_s;
    }
    printf("  %s %c: overshoot %.2f %%, settled (2 %%) after %.3f s, error after 1 s %.2e\n", m->name, a->name,
           100 * (peak - step) / step, settle, step - act);
    assert_true(peak - step < 0.1 * step);
    assert_true(settle < 0.4);
    assert_true(fabs(step - act) < 0.005 * step);
}

static void test_shipped_router(void **state)
{
    (void)state;
    sim_machine m;
    char err[256];
    sim_machine_status st = sim_machine_load_file(machine_path("router.json"), &m, err, sizeof err);
    if (st != SIM_MACHINE_OK)
        print_error("%s\n", err);
    assert_int_equal(st, SIM_MACHINE_OK);
    assert_string_equal(m.name, "router");
    assert_rel(m.cycle_s, 0.001, 0);
    assert_int_equal(m.lookahead_blocks, 64);
    assert_rel(m.blend_tol_mm, 0.02, 0);
    assert_int_equal(m.n_axes, 3);
    assert_int_equal(m.axis_mask, 0x07);
    const sim_machine_axis *x = sim_machine_axis_by_name(&m, 'x');
    assert_non_null(x);
    assert_int_equal(x->index, 0);
    assert_false(x->rotary);
    assert_rel(x->v_max_u_s, 250, 0);
    assert_rel(x->a_max_u_s2, 3000, 0);
    assert_rel(x->j_max_u_s3, 60000, 0);
    assert_rel(x->snap_max_u_s4, 1.18e7, 0);
    assert_rel(x->drive.encoder_counts_per_mm, 1000, 0);
    assert_rel(x->drive.load_mass_kg, 45, 0);
    const sim_machine_axis *z = sim_machine_axis_by_name(&m, 'Z');
    assert_rel(z->v_max_u_s, 100, 0);
    assert_rel(z->drive.load_mass_kg, 12, 0);
    assert_null(sim_machine_axis_by_name(&m, 'A'));
    for (int i = 0; i < m.n_axes; i++)
        check_drive_stable(&m, &m.axes[i]);
}

static void test_shipped_papers(void **state)
{
    (void)state;
    sim_machine m;
    char err[256];
    sim_machine_status st = sim_machine_load_file(machine_path("kombarov_table1.json"), &m, err, sizeof err);
    if (st != SIM_MACHINE_OK)
        print_error("%s\n", err);
    assert_int_equal(st, SIM_MACHINE_OK);
    assert_rel(m.cycle_s, 0.001, 0);
    for (int i = 0; i < m.n_axes; i++) {
        /* Test 2: A 1.57 m/s^2, J 16 m/s^3, DJ 560 m/s^4, dF 13.2 m/min = 0.22 m/s */
        assert_rel(m.axes[i].a_max_u_s2, 1.57e3, 1e-15);
        assert_rel(m.axes[i].j_max_u_s3, 16e3, 1e-15);
        assert_rel(m.axes[i].snap_max_u_s4, 560e3, 1e-15);
        assert_rel(m.axes[i].v_max_u_s, 13.2e3 / 60.0, 1e-15);
        /* the sin^2 jerk rise of Table 1: dt1J = pi J / (2 DJ) = 0.044 s after flooring to the cycle */
        double dt1j = PI * m.axes[i].j_max_u_s3 / (2 * m.axes[i].snap_max_u_s4);
        assert_int_equal((int)floor(dt1j / m.cycle_s + 1e-9), 44);
        check_drive_stable(&m, &m.axes[i]);
    }
    assert_rel(m.axes[0].drive.vff_gain, 1.0, 0);
    assert_rel(m.axes[0].drive.aff_gain, 1.0, 0);

    st = sim_machine_load_file(machine_path("beudaert_table1.json"), &m, err, sizeof err);
    if (st != SIM_MACHINE_OK)
        print_error("%s\n", err);
    assert_int_equal(st, SIM_MACHINE_OK);
    assert_rel(m.cycle_s, 0.006, 0);
    const sim_machine_axis *x = sim_machine_axis_by_name(&m, 'X'), *y = sim_machine_axis_by_name(&m, 'Y'),
                           *z = sim_machine_axis_by_name(&m, 'Z');
    assert_non_null(x);
    assert_non_null(y);
    assert_non_null(z);
    /* Table 1: 30 m/min; 2.5, 3, 2.1 m/s^2; 5, 5, 50 m/s^3 */
    assert_rel(x->v_max_u_s, 30e3 / 60.0, 1e-15);
    assert_rel(y->v_max_u_s, 30e3 / 60.0, 1e-15);
    assert_rel(x->a_max_u_s2, 2500, 1e-15);
    assert_rel(y->a_max_u_s2, 3000, 1e-15);
    assert_rel(z->a_max_u_s2, 2100, 1e-15);
    assert_rel(x->j_max_u_s3, 5000, 1e-15);
    assert_rel(y->j_max_u_s3, 5000, 1e-15);
    assert_rel(z->j_max_u_s3, 50000, 1e-15);
    /* snap lets a sin^2 jerk ramp take one 6 ms cycle: pi J / (2 dt) */
    assert_rel(x->snap_max_u_s4, PI * 5000 / (2 * 0.006), 1e-3);
    assert_rel(z->snap_max_u_s4, PI * 50000 / (2 * 0.006), 1e-3);
    for (int i = 0; i < m.n_axes; i++)
        check_drive_stable(&m, &m.axes[i]);
}

/* Every .json file in host_sim/machines loads, and every drive in it is stable; the chosen Kombarov case is the axis
 * docs/machine_file.md describes (Table 1 Test 2 limits, 45 Hz resonance with zeta 0.02, kv 40 /s, no feed-forward). */
static void test_shipped_all(void **state)
{
    (void)state;
    DIR *dir = opendir(g_dir);
    assert_non_null(dir);
    int n = 0;
    bool positioning = false;
    for (struct dirent *e = readdir(dir); e; e = readdir(dir)) {
        const size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".json") != 0)
            continue;
        sim_machine m;
        char err[256];
        const sim_machine_status st = sim_machine_load_file(machine_path(e->d_name), &m, err, sizeof err);
        if (st != SIM_MACHINE_OK)
            print_error("%s: %s\n", e->d_name, err);
        assert_int_equal(st, SIM_MACHINE_OK);
        for (int i = 0; i < m.n_axes; i++)
            check_drive_stable(&m, &m.axes[i]);
        n++;
        if (strcmp(e->d_name, "kombarov_positioning.json") == 0) {
            positioning = true;
            assert_int_equal(m.n_axes, 1);
            const sim_machine_axis *x = sim_machine_axis_by_name(&m, 'X');
            assert_non_null(x);
            assert_rel(x->v_max_u_s, 220, 0);
            assert_rel(x->a_max_u_s2, 1570, 0);
            assert_rel(x->j_max_u_s3, 16000, 0);
            assert_rel(x->snap_max_u_s4, 560000, 0);
            assert_rel(x->drive.kv_1_s, 40, 0);
            assert_true(x->drive.vff_gain == 0 && x->drive.aff_gain == 0);
            sim_drive_modes md;
            sim_drive_modes_analytic(&x->drive, &md);
            assert_rel(md.f_res_hz, 45.0, 2e-3);
            assert_rel(md.zeta_res, 0.02, 2e-3);
        }
    }
    closedir(dir);
    printf("  %d machine files\n", n);
    assert_true(n >= 4);
    assert_true(positioning);
}

/* ---------------------------------------------------------------- bad files */

#define TOP                                                                                            \
    "\"format\": \"lissom-machine-1\", \"name\": \"t\", \"cycle_s\": 0.001, \"lookahead_blocks\": 8, " \
    "\"blend_tol_mm\": 0.01"
#define AXIS_X                                                                                                      \
    "{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": 1e4, \"snap_max_mm_s4\": 1e6, " \
    "\"counts_per_mm\": 100}"

static void expect_bad(const char *text, sim_machine_status code, const char *needle1, const char *needle2)
{
    sim_machine m;
    memset(&m, 0x5A, sizeof m);
    sim_machine before = m;
    char err[512];
    sim_machine_status st = sim_machine_load_text(text, strlen(text), "t.json", &m, err, sizeof err);
    if (st != code || (needle1 && !strstr(err, needle1)) || (needle2 && !strstr(err, needle2)))
        print_error("text %s\n -> %d (%s): %s\n", text, (int)st, sim_machine_status_str(st), err);
    assert_int_equal(st, code);
    if (needle1)
        assert_non_null(strstr(err, needle1));
    if (needle2)
        assert_non_null(strstr(err, needle2));
    assert_memory_equal(&m, &before, sizeof m); /* untouched on error */
}

static void test_good_minimal_and_rotary(void **state)
{
    (void)state;
    const char *text = "{" TOP ", \"comment\": \"c\", \"axes\": [" AXIS_X ", "
                       "{\"name\": \"A\", \"v_max_deg_s\": 90, \"a_max_deg_s2\": 180, \"j_max_deg_s3\": 3600, "
                       "\"snap_max_deg_s4\": 360000, \"counts_per_deg\": 100, \"comment\": \"rotary table\", "
                       "\"drive\": {\"kv_1_s\": 30}}]}";
    sim_machine m;
    char err[256];
    sim_machine_status st = sim_machine_load_text(text, strlen(text), "t.json", &m, err, sizeof err);
    if (st)
        print_error("%s\n", err);
    assert_int_equal(st, SIM_MACHINE_OK);
    assert_int_equal(m.n_axes, 2);
    assert_int_equal(m.axis_mask, 0x09);
    const sim_machine_axis *a = sim_machine_axis_by_name(&m, 'A');
    assert_true(a->rotary);
    assert_int_equal(a->index, 3);
    assert_rel(a->v_max_u_s, PI / 2, 1e-15);
    assert_rel(a->a_max_u_s2, PI, 1e-15);
    assert_rel(a->j_max_u_s3, 20 * PI, 1e-15);
    assert_rel(a->snap_max_u_s4, 2000 * PI, 1e-15);
    assert_rel(a->counts_per_u, 100 * 180 / PI, 1e-15);
    assert_true(a->drive.rotary);
    assert_rel(a->drive.kv_1_s, 30, 0);
    sim_drive_params def;
    sim_drive_params_default(&def, true);
    assert_rel(a->drive.load_mass_kg, def.load_mass_kg, 0); /* unspecified: the rotary default */
    assert_string_equal(m.description, "");
}

static void test_bad_files(void **state)
{
    (void)state;
    char big[4096];
    /* syntax: the JSON layer reports line and column */
    expect_bad("{" TOP ",\n \"axes\": [" AXIS_X ",]}", SIM_MACHINE_E_JSON, "t.json:2:", "trailing comma");
    expect_bad("{" TOP ", \"axes\": [" AXIS_X "]} // c", SIM_MACHINE_E_JSON, "extra data", NULL);
    expect_bad("[1, 2]", SIM_MACHINE_E_TYPE, "top level must be an object", NULL);
    /* format */
    expect_bad("{\"name\": \"t\"}", SIM_MACHINE_E_FORMAT, "missing key \"format\"", NULL);
    expect_bad("{\"format\": \"lissom-machine-2\"}", SIM_MACHINE_E_FORMAT, "lissom-machine-2", NULL);
    expect_bad("{\"format\": 1}", SIM_MACHINE_E_FORMAT, NULL, NULL);
    /* unknown keys, with line:column of the key */
    expect_bad("{" TOP ",\n  \"cycle_ms\": 1, \"axes\": [" AXIS_X "]}", SIM_MACHINE_E_UNKNOWN_KEY,
               "t.json:2:3: unknown key \"cycle_ms\"", NULL);
    expect_bad("{" TOP ", \"axes\": [{\"name\": \"X\", \"v_mx_mm_s\": 1}]}", SIM_MACHINE_E_UNKNOWN_KEY,
               "axes[0]: unknown key \"v_mx_mm_s\"", NULL);
    expect_bad("{" TOP ", \"axes\": [" AXIS_X ", {\"name\": \"B\", \"v_max_mm_s\": 1}]}", SIM_MACHINE_E_UNKNOWN_KEY,
               "axes[1]: unknown key \"v_max_mm_s\"", "use \"v_max_deg_s\"");
    expect_bad("{" TOP ", \"axes\": [{\"name\": \"Y\", \"counts_per_deg\": 1}]}", SIM_MACHINE_E_UNKNOWN_KEY,
               "axis Y is linear", NULL);
    snprintf(big, sizeof big,
             "{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": "
             "1e4, \"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100, \"drive\": {\"mass_kg\": 3}}]}");
    expect_bad(big, SIM_MACHINE_E_UNKNOWN_KEY, "axes[0]: drive: unknown key \"mass_kg\"", NULL);
    snprintf(big, sizeof big,
             "{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": "
             "1e4, \"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100, \"drive\": {\"encoder_counts_per_mm\": 3}}]}");
    expect_bad(big, SIM_MACHINE_E_UNKNOWN_KEY, "encoder_counts_per_mm", NULL);
    /* missing keys */
    expect_bad("{\"format\": \"lissom-machine-1\", \"name\": \"t\", \"lookahead_blocks\": 8, \"blend_tol_mm\": 0.01, "
               "\"axes\": [" AXIS_X "]}",
               SIM_MACHINE_E_MISSING_KEY, "missing key \"cycle_s\"", NULL);
    expect_bad("{" TOP "}", SIM_MACHINE_E_MISSING_KEY, "missing key \"axes\"", NULL);
    expect_bad("{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, "
               "\"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100}]}",
               SIM_MACHINE_E_MISSING_KEY, "axes[0]: missing key \"j_max_mm_s3\"", NULL);
    expect_bad("{" TOP ", \"axes\": [{\"v_max_mm_s\": 100}]}", SIM_MACHINE_E_MISSING_KEY, "missing key \"name\"", NULL);
    /* types */
    expect_bad("{\"format\": \"lissom-machine-1\", \"name\": \"t\", \"cycle_s\": \"0.001\", \"lookahead_blocks\": 8, "
               "\"blend_tol_mm\": 0.01, \"axes\": [" AXIS_X "]}",
               SIM_MACHINE_E_TYPE, "\"cycle_s\" must be a number, not string", NULL);
    expect_bad("{" TOP ", \"axes\": {}}", SIM_MACHINE_E_TYPE, "\"axes\" must be an array", NULL);
    expect_bad("{" TOP ", \"axes\": [7]}", SIM_MACHINE_E_TYPE, "axes[0]: an axis must be an object", NULL);
    expect_bad("{" TOP ", \"comment\": 5, \"axes\": [" AXIS_X "]}", SIM_MACHINE_E_TYPE, "\"comment\" must be a string",
               NULL);
    snprintf(big, sizeof big,
             "{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": "
             "1e4, \"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100, \"drive\": [1]}]}");
    expect_bad(big, SIM_MACHINE_E_TYPE, "\"drive\" must be an object", NULL);
    /* values */
    expect_bad("{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 0, \"j_max_mm_s3\": 1e4, "
               "\"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100}]}",
               SIM_MACHINE_E_VALUE, "\"a_max_mm_s2\" must be > 0", NULL);
    expect_bad("{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": -100, \"a_max_mm_s2\": 1, \"j_max_mm_s3\": 1e4, "
               "\"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100}]}",
               SIM_MACHINE_E_VALUE, "\"v_max_mm_s\" must be > 0 (got -100)", NULL);
    expect_bad("{\"format\": \"lissom-machine-1\", \"name\": \"t\", \"cycle_s\": 0.5, \"lookahead_blocks\": 8, "
               "\"blend_tol_mm\": 0.01, \"axes\": [" AXIS_X "]}",
               SIM_MACHINE_E_VALUE, "\"cycle_s\" must be at most 0.1 s", NULL);
    expect_bad("{\"format\": \"lissom-machine-1\", \"name\": \"t\", \"cycle_s\": 0.001, \"lookahead_blocks\": 8.5, "
               "\"blend_tol_mm\": 0.01, \"axes\": [" AXIS_X "]}",
               SIM_MACHINE_E_VALUE, "lookahead_blocks", NULL);
    expect_bad("{\"format\": \"lissom-machine-1\", \"name\": \"t\", \"cycle_s\": 0.001, \"lookahead_blocks\": 8, "
               "\"blend_tol_mm\": 0, \"axes\": [" AXIS_X "]}",
               SIM_MACHINE_E_VALUE, "blend_tol_mm", NULL);
    /* axes */
    expect_bad("{" TOP ", \"axes\": []}", SIM_MACHINE_E_AXES, "1 to 6 entries", NULL);
    expect_bad("{" TOP ", \"axes\": [" AXIS_X "," AXIS_X "]}", SIM_MACHINE_E_AXES, "axes[1]: axis X is repeated", NULL);
    expect_bad("{" TOP ", \"axes\": [{\"name\": \"Q\"}]}", SIM_MACHINE_E_AXES, "\"Q\" is not one of", NULL);
    expect_bad("{" TOP ", \"axes\": [{\"name\": \"XY\"}]}", SIM_MACHINE_E_AXES, NULL, NULL);
    expect_bad("{" TOP ", \"axes\": [1,2,3,4,5,6,7]}", SIM_MACHINE_E_AXES, "has 7", NULL);
    /* drive: a value the drive model rejects, with the field named at its position */
    snprintf(big, sizeof big,
             "{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": "
             "1e4, \"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100,\n \"drive\": {\"stiffness_N_m\": 1e11}}]}");
    expect_bad(big, SIM_MACHINE_E_DRIVE, "t.json:2:", "\"servo_period_s\" 6.25e-05 s is not valid");
    /* a servo period far below any drive's (fuzz_machine: 1e-50 s overflowed the substep count, and 1e-9 s made the
     * settling test run for minutes): refused up front, the value named */
    snprintf(big, sizeof big,
             "{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": "
             "1e4, \"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100, \"drive\": {\"servo_period_s\": 1e-50}}]}");
    expect_bad(big, SIM_MACHINE_E_DRIVE, "\"servo_period_s\" 1e-50 s is not valid", "at least 1e-06 s");
    snprintf(big, sizeof big,
             "{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": "
             "1e4, \"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100, \"drive\": {\"vff_gain\": 3}}]}");
    expect_bad(big, SIM_MACHINE_E_DRIVE, "\"vff_gain\" is not valid", NULL);
    snprintf(big, sizeof big,
             "{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": "
             "1e4, \"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100, \"drive\": {\"kv_1_s\": 0}}]}");
    expect_bad(big, SIM_MACHINE_E_VALUE, "drive: \"kv_1_s\" must be > 0", NULL);
    /* valid numbers, unstable loop: a 12 Hz resonance under the default 40 Hz velocity loop */
    snprintf(big, sizeof big,
             "{" TOP ", \"axes\": [{\"name\": \"X\", \"v_max_mm_s\": 100, \"a_max_mm_s2\": 1000, \"j_max_mm_s3\": "
             "1e4, \"snap_max_mm_s4\": 1e6, \"counts_per_mm\": 100, \"drive\": {\"stiffness_N_m\": 64000, "
             "\"damping_N_s_m\": 50}}]}");
    expect_bad(big, SIM_MACHINE_E_DRIVE, "does not settle", "resonance (now 12.");
    /* files */
    sim_machine m;
    char err[256];
    assert_int_equal(sim_machine_load_file("/nonexistent/dir/m.json", &m, err, sizeof err), SIM_MACHINE_E_IO);
    assert_non_null(strstr(err, "cannot open"));
    assert_int_equal(sim_machine_load_file(NULL, &m, err, sizeof err), SIM_MACHINE_E_IO);
    for (int s = 0; s >= -9; s--)
        assert_non_null(sim_machine_status_str((sim_machine_status)s));
}

int main(void)
{
    find_dir();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shipped_router), cmocka_unit_test(test_shipped_papers),
        cmocka_unit_test(test_shipped_all),    cmocka_unit_test(test_good_minimal_and_rotary),
        cmocka_unit_test(test_bad_files),
    };
    return cmocka_run_group_tests_name("sim_machine", tests, NULL, NULL);
}
