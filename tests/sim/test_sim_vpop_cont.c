/*
 * test_sim_vpop_cont.c: the continuous-limit reference (`--planner vpop-cont`, pathrun.h SIM_RUN_VPOP_CONT): VPOp
 * whose every step is also checked between its samples (vpop.h: step_cont; pathrun.c: vp_cstep_segment), the motion
 * between the samples being their cubic B-spline (the step's discrete jerk held over the cycle).
 *
 * On the four shipped paths of `bench-planner` (the trident polyline on beudaert_table1, the circle of chords, the
 * pocket and the 3-D surface on the router):
 * - the reference holds the continuous limits: its largest axis velocity, acceleration and jerk over the limits on
 *   the continuous motion, measured independently of the step's check (pathrun.c vp_cont_verify: the B-spline
 *   resampled 32 times a cycle, backward differences of the exact positions; result cont_ratio), are <= 1 +
 *   CONT_TOL. CONT_TOL is the numerical bound of the check: it samples each block's part of a cycle at up to 18
 *   points, then refines around the largest by golden section, so a peak narrower than that can still pass by a
 *   little; measured: 1e-8 on the shipped paths, at most 1.1e-5 on the random programs of seeds 1-3 (2e-4 before
 *   the golden section). The rounding of the measure itself is below 1e-7 there.
 * - it also holds the discrete limits (eq 6) on its samples, ends exactly, and is no faster than plain VPOp.
 * - with the continuous check disabled (that is plain VPOp, `--planner vpop`: the same planner with step_cont NULL)
 *   the same measure finds the limit broken (continuous jerk > 1.5 J on every one of these paths), so the
 *   predicate above is able to fail.
 * - on a program of straight lines only (no curved block) the check is implied by the discrete bounds, so the
 *   reference is the plain VPOp motion, setpoint for setpoint.
 * - random programs on the router ([seed] [count] from argv; count programs, 3 by default): lines, arcs of random
 *   radius, rapids, G61/G64 switches, random feed: the same limits (discrete and continuous) and the exact end, and
 *   no faster than plain VPOp by more than one cycle (VPOp is a greedy heuristic, so a continuous check that changes
 *   a switching step may in principle end a little earlier; it has not on any seed tried).
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

#include "lsm_test_rng.h"
#include "pathrun.h"

static uint64_t g_seed = 20261127;
static long g_count = 3;

#define CONT_TOL 1e-4 /* the check's numerical bound (above); measured <= 1.1e-5 */

typedef struct cs_case {
    const char *program, *machine;
} cs_case;

static const cs_case k_cases[] = {
    {"host_sim/examples/trident.ngc", "host_sim/machines/beudaert_table1.json"},
    {"host_sim/examples/circle_chords.ngc", "host_sim/machines/router.json"},
    {"host_sim/examples/pocket.ngc", "host_sim/machines/router.json"},
    {"host_sim/examples/surface_finish.ngc", "host_sim/machines/router.json"},
};

static void repo_path(char *out, size_t n, const char *rel)
{
    snprintf(out, n, "%s/%s", LSM_REPO_DIR, rel);
}

/* Runs text on machine m with the planner; checks the discrete limits of the setpoints and the exact end. */
static void run_checked(const sim_machine *m, const char *text, size_t len, sim_run_planner planner, sim_run_result *r)
{
    sim_run_opts o;
    memset(&o, 0, sizeof o);
    o.machine = m;
    o.text = text;
    o.len = len;
    o.planner = planner;
    if (sim_run_program(&o, r) != 0) {
        fprintf(stderr, "%s: %s\n", sim_run_planner_name(planner), r->err);
        fail();
    }
    double qmax = 0;
    for (size_t i = 0; i < r->n * LSM_MAX_AXES; i++)
        qmax = fmax(qmax, fabs(r->q[i]));
    const double u = 8 * 2.220446049250313e-16 * (1 + qmax), dt = r->cycle_s;
    for (int i = 0; i < m->n_axes; i++) {
        const sim_machine_axis *x = &m->axes[i];
        assert_true(r->max_v[x->index] <= x->v_max_u_s * (1 + 1e-9) + 2 * u / dt);
        assert_true(r->max_a[x->index] <= x->a_max_u_s2 * (1 + 1e-9) + 4 * u / (dt * dt));
        assert_true(r->max_j[x->index] <= x->j_max_u_s3 * (1 + 1e-9) + 8 * u / (dt * dt * dt));
    }
    assert_true(r->end_error == 0);
}

/* The continuous limits hold (the predicate the reference must meet and plain VPOp must fail). */
static int holds_continuously(const sim_run_result *r)
{
    return r->cont_ratio[0] >= 0 && r->cont_ratio[0] <= 1 + CONT_TOL && r->cont_ratio[1] <= 1 + CONT_TOL &&
           r->cont_ratio[2] <= 1 + CONT_TOL;
}

static void test_shipped_paths(void **state)
{
    (void)state;
    for (size_t c = 0; c < sizeof k_cases / sizeof k_cases[0]; c++) {
        char pp[1024], mp[1024], err[256];
        repo_path(pp, sizeof pp, k_cases[c].program);
        repo_path(mp, sizeof mp, k_cases[c].machine);
        sim_machine m;
        assert_int_equal(sim_machine_load_file(mp, &m, err, sizeof err), SIM_MACHINE_OK);
        size_t len = 0;
        char *text = sim_read_file(pp, &len);
        assert_non_null(text);
        sim_run_result plain, cs;
        run_checked(&m, text, len, SIM_RUN_VPOP, &plain);
        run_checked(&m, text, len, SIM_RUN_VPOP_CONT, &cs);
        printf("  %s: vpop %.3f s (continuous v/a/j %.3f/%.3f/%.3f), vpop-cont %.3f s (%.3f/%.3f/%.6f)\n",
               k_cases[c].program, plain.duration_s, plain.cont_ratio[0], plain.cont_ratio[1], plain.cont_ratio[2],
               cs.duration_s, cs.cont_ratio[0], cs.cont_ratio[1], cs.cont_ratio[2]);
        assert_true(holds_continuously(&cs));
        assert_false(holds_continuously(&plain)); /* the check disabled: the limit breaks */
        assert_true(plain.cont_ratio[2] > 1.5);
        assert_true(cs.duration_s >= plain.duration_s);
        sim_run_free(&plain);
        sim_run_free(&cs);
        free(text);
    }
}

/* Lines only (one stop at the corner between them: G61): the check is implied by the discrete bounds. */
static void test_lines_same_as_vpop(void **state)
{
    (void)state;
    char mp[1024], err[256];
    repo_path(mp, sizeof mp, "host_sim/machines/router.json");
    sim_machine m;
    assert_int_equal(sim_machine_load_file(mp, &m, err, sizeof err), SIM_MACHINE_OK);
    static const char text[] = "G21 G90 G61\nG1 X40 Y10 F6000\nG1 X45 Y-20 Z3\nG1 X0 Y0 Z0 F3000\n";
    sim_run_result plain, cs;
    run_checked(&m, text, strlen(text), SIM_RUN_VPOP, &plain);
    run_checked(&m, text, strlen(text), SIM_RUN_VPOP_CONT, &cs);
    printf("  lines: vpop %.3f s, vpop-cont %.3f s (continuous j %.6f)\n", plain.duration_s, cs.duration_s,
           cs.cont_ratio[2]);
    assert_int_equal(plain.n, cs.n);
    assert_memory_equal(plain.q, cs.q, plain.n * LSM_MAX_AXES * sizeof *plain.q);
    assert_true(holds_continuously(&cs));
    sim_run_free(&plain);
    sim_run_free(&cs);
}

static void test_random_programs(void **state)
{
    (void)state;
    char mp[1024], err[256];
    repo_path(mp, sizeof mp, "host_sim/machines/router.json");
    sim_machine m;
    assert_int_equal(sim_machine_load_file(mp, &m, err, sizeof err), SIM_MACHINE_OK);
    uint64_t rng = g_seed * 6364136223846793005ull + 1442695040888963407ull;
    for (long c = 0; c < g_count; c++) {
        char text[4096];
        int at =
            snprintf(text, sizeof text, "G21 G90 G17 G64 P0.01\nG0 X0 Y0 Z0\nG1 F%.0f\n", test_logu(&rng, 600, 9000));
        for (int i = 0; i < 10; i++) {
            const double x = 40 * test_urand(&rng), y = 40 * test_urand(&rng), z = 3 * test_urand(&rng);
            const double u = test_urand(&rng);
            if (u < 0.1)
                at += snprintf(text + at, sizeof text - (size_t)at, "%s\n", test_urand(&rng) < 0.5 ? "G61" : "G64");
            if (u < 0.35)
                at += snprintf(text + at, sizeof text - (size_t)at, "G%d X%.3f Y%.3f R%.3f\n",
                               test_urand(&rng) < 0.5 ? 2 : 3, x, y, test_logu(&rng, 22, 60));
            else if (u < 0.45)
                at += snprintf(text + at, sizeof text - (size_t)at, "G0 X%.3f Y%.3f Z%.3f\nG1\n", x, y, z + 3);
            else
                at += snprintf(text + at, sizeof text - (size_t)at, "G1 X%.3f Y%.3f Z%.3f\n", x, y, z);
        }
        snprintf(text + at, sizeof text - (size_t)at, "M30\n");
        sim_run_result plain, cs;
        run_checked(&m, text, strlen(text), SIM_RUN_VPOP, &plain);
        run_checked(&m, text, strlen(text), SIM_RUN_VPOP_CONT, &cs);
        printf("  random program %ld: vpop %.3f s (continuous j %.3f), vpop-cont %.3f s (%.3f/%.3f/%.6f)\n", c,
               plain.duration_s, plain.cont_ratio[2], cs.duration_s, cs.cont_ratio[0], cs.cont_ratio[1],
               cs.cont_ratio[2]);
        if (!holds_continuously(&cs) || cs.duration_s < plain.duration_s - cs.cycle_s - 1e-9)
            fprintf(stderr, "%s", text);
        assert_true(holds_continuously(&cs));
        assert_true(cs.duration_s >= plain.duration_s - cs.cycle_s - 1e-9);
        sim_run_free(&plain);
        sim_run_free(&cs);
    }
}

int main(int argc, char **argv)
{
    g_seed = (uint64_t)test_arg_u(argc, argv, 1, g_seed);
    g_count = (long)test_arg_u(argc, argv, 2, (unsigned long long)g_count);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lines_same_as_vpop),
        cmocka_unit_test(test_random_programs),
        cmocka_unit_test(test_shipped_paths),
    };
    return test_seed_finish(argv[0], g_seed, (unsigned long long)g_count, cmocka_run_group_tests(tests, NULL, NULL));
}
