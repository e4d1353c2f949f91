/*
 * lissom-sim run: a G-code program through the look-ahead planner and interpolator on a machine.
 *
 *   lissom-sim run PROGRAM --machine MACHINE.json --out DIR [--json] [--planner lissom|vpop] [--override F]
 *                  [--capacity N] [--no-drive] [--no-csv] [--plots] [--progress | --no-progress]
 *
 * Prints duration, cycles, max_deviation, end_error and, per axis, max_axis_velocity, max_axis_acceleration and
 * max_axis_jerk, all measured from the setpoints with backward differences (Beudaert eq 6); see pathrun.h.
 * Writes DIR/setpoints.csv (t, then one column per machine axis), DIR/run.csv (the run CSV of docs/host_sim.md:
 * setpoints, actual positions and following error from the simulated drives, feed, and per-axis v, a, j),
 * DIR/summary.json (what --json prints), and with --plots the PNGs of hil/lissom_hil/plot.py. With --no-csv only
 * summary.json is written (the same summary), and the run keeps no setpoint: it measures them as they come, in
 * constant memory (sim_run_opts.summary_only); formatting run.csv costs about half the host time of a --no-drive
 * run (the benchmark against Klipper, docs/planner.md).
 * A progress bar (progress.h) goes to stderr: on a terminal once the run has taken 2 s of wall time, always with
 * --progress (one line per 10 % step when stderr is not a terminal), never with --no-progress. Stdout only
 * ever holds the summary.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "pathrun.h"
#include "progress.h"

static const char *unit_of(char axis)
{
    return (axis == 'A' || axis == 'B' || axis == 'C') ? "rad" : "mm";
}

/* The machine functions of the program (gcode.h events) with their source line and the machine time they ran at
 * (null with --planner vpop, which runs none); a pause (M0/M1) is followed by its resume (the simulator resumes at
 * once). */
static void print_events(FILE *f, const sim_run_result *r)
{
    fprintf(f, "  \"events\": [");
    for (size_t i = 0; i < r->n_mfuncs; i++) {
        const sim_run_mfunc *m = &r->mfuncs[i];
        const lsm_gcode_event_kind k = m->ev.kind;
        const bool pause = k == LSM_GCODE_EV_PAUSE || k == LSM_GCODE_EV_OPTIONAL_PAUSE;
        for (int rep = 0; rep < (pause ? 2 : 1); rep++) {
            fprintf(f, "%s\n    {\"line\": %u, \"event\": \"%s\", \"code\": \"%s\"", i || rep ? "," : "",
                    (unsigned)m->ev.line, rep ? "resume" : lsm_gcode_event_name(k),
                    k == LSM_GCODE_EV_END && m->ev.tool == 30 ? "M30" : lsm_gcode_event_code(k));
            if (k == LSM_GCODE_EV_SPINDLE_SPEED || k == LSM_GCODE_EV_SPINDLE_CW || k == LSM_GCODE_EV_SPINDLE_CCW)
                fprintf(f, ", \"rpm\": %.17g", (double)m->ev.value);
            if (k == LSM_GCODE_EV_DWELL)
                fprintf(f, ", \"seconds\": %.17g", (double)m->ev.value);
            if (k == LSM_GCODE_EV_TOOL_SELECT || k == LSM_GCODE_EV_TOOL_CHANGE)
                fprintf(f, ", \"tool\": %d", (int)m->ev.tool);
            if (k == LSM_GCODE_EV_TOOL_LENGTH)
                fprintf(f, ", \"h\": %d", (int)m->ev.tool);
            fprintf(f, ", \"exact_stop\": %s, \"t\": ", m->ev.exact_stop ? "true" : "false");
            json_num(f, m->t_s >= 0 ? m->t_s : (double)NAN);
            fprintf(f, "}");
        }
    }
    fprintf(f, "%s]\n", r->n_mfuncs ? "\n  " : "");
}

static void print_summary(FILE *f, const sim_run_opts *o, const sim_run_result *r, const char *program,
                          const char *machine)
{
    const sim_machine *m = o->machine;
    fprintf(f, "{\n  \"program\": \"%s\",\n  \"machine\": \"%s\",\n  \"planner\": \"%s\",\n", program, machine,
            sim_run_planner_name(o->planner));
    fprintf(f, "  \"duration\": ");
    json_num(f, r->duration_s);
    fprintf(f, ",\n  \"cycles\": %llu,\n  \"cycle_s\": ", (unsigned long long)r->cycles);
    json_num(f, r->cycle_s);
    fprintf(f, ",\n  \"max_deviation\": ");
    json_num(f, r->max_dev_mm);
    fprintf(f, ",\n  \"end_error\": ");
    json_num(f, r->end_error);
    fprintf(f, ",\n  \"program_blocks\": %zu,\n  \"program_held_max\": %zu,\n  \"program_length_mm\": ", r->prog_blocks,
            r->prog_held_max);
    json_num(f, r->prog_length_mm);
    static const char *keys[3] = {"max_axis_velocity", "max_axis_acceleration", "max_axis_jerk"};
    for (int kind = 0; kind < 3; kind++) {
        fprintf(f, ",\n  \"%s\": {", keys[kind]);
        for (int i = 0; i < r->n_axes; i++) {
            const int a = r->axis_index[i];
            const double v = kind == 0 ? r->max_v[a] : kind == 1 ? r->max_a[a] : r->max_j[a];
            fprintf(f, "%s\"%c\": ", i ? ", " : "", r->axis_name[i]);
            json_num(f, v);
        }
        fprintf(f, "}");
    }
    fprintf(f, ",\n  \"axes\": [");
    bool within = true;
    for (int i = 0; i < r->n_axes; i++) {
        const int a = r->axis_index[i];
        const sim_machine_axis *x = &m->axes[i];
        const bool ok = r->max_v[a] <= x->v_max_u_s * (1 + 1e-6) && r->max_a[a] <= x->a_max_u_s2 * (1 + 1e-6) &&
                        r->max_j[a] <= x->j_max_u_s3 * (1 + 1e-6);
        within = within && ok;
        fprintf(f, "%s\n    {\"name\": \"%c\", \"unit\": \"%s\", \"max_axis_velocity\": ", i ? "," : "", x->name,
                unit_of(x->name));
        json_num(f, r->max_v[a]);
        fprintf(f, ", \"max_axis_acceleration\": ");
        json_num(f, r->max_a[a]);
        fprintf(f, ", \"max_axis_jerk\": ");
        json_num(f, r->max_j[a]);
        fprintf(f, ", \"v_max\": ");
        json_num(f, x->v_max_u_s);
        fprintf(f, ", \"a_max\": ");
        json_num(f, x->a_max_u_s2);
        fprintf(f, ", \"j_max\": ");
        json_num(f, x->j_max_u_s3);
        fprintf(f, ", \"within_limits\": %s", ok ? "true" : "false");
        if (r->has_act) {
            fprintf(f, ", \"max_following_error\": ");
            json_num(f, r->max_follow_err[a]);
        }
        fprintf(f, "}");
    }
    fprintf(f, "\n  ],\n  \"within_limits\": %s,\n", within ? "true" : "false");
    if (r->intersample_jerk_max >= 0) {
        fprintf(f, "  \"intersample_jerk_ratio\": {\"max\": ");
        json_num(f, r->intersample_jerk_max);
        fprintf(f, ", \"p99\": ");
        json_num(f, r->intersample_jerk_p99);
        fprintf(f, "},\n");
    }
    if (r->cont_ratio[0] >= 0) {
        fprintf(f, "  \"continuous_ratio\": {\"v\": ");
        json_num(f, r->cont_ratio[0]);
        fprintf(f, ", \"a\": ");
        json_num(f, r->cont_ratio[1]);
        fprintf(f, ", \"j\": ");
        json_num(f, r->cont_ratio[2]);
        fprintf(f, "},\n");
    }
    fprintf(f,
            "  \"planner_stats\": {\"blocks_appended\": %u, \"corners_smoothed\": %u, \"corner_stops\": %u, "
            "\"pieces\": %u, \"replans\": %u, \"fallbacks\": %u, \"plan_errors\": %u, \"ramp_checks\": %u, "
            "\"block_bytes\": %u, \"append_ns_per_block\": ",
            r->stats.appended, r->stats.corners, r->stats.corner_stops, r->stats.pieces, r->replans,
            r->stats.plan_fallbacks, r->plan_errors, r->stats.checks, r->pl_block_bytes);
    json_num(f, r->plan_ns_per_block);
    fprintf(f, ", \"interp_ns_per_cycle\": ");
    json_num(f, r->interp_ns_per_cycle);
    fprintf(f, ", \"prepare_ns_per_piece\": ");
    json_num(f, r->prepare_ns_per_piece);
    fprintf(f, ", \"pieces_prepared\": %u, \"pieces_planned_in_cycle\": %u", r->prepared, r->tick_plans);
    fprintf(f, "},\n");
    print_events(f, r);
    fprintf(f, "}\n");
}

static void on_progress(void *ctx, sim_run_phase phase, double done, double machine_time_s)
{
    /* the drives run one axis after the other over the whole run: their machine time would jump back */
    if (phase == SIM_RUN_PHASE_DRIVES)
        sim_progress_update((sim_progress *)ctx, "drives", done, -1);
    else
        sim_progress_update((sim_progress *)ctx, "planning", done, machine_time_s);
}

static int write_csvs(const char *out, const sim_run_result *r, sim_progress *prog)
{
    char path[4200];
    FILE *f = cli_open_out(out, "setpoints.csv", path, sizeof path);
    if (!f)
        return -1;
    fprintf(f, "t");
    for (int i = 0; i < r->n_axes; i++)
        fprintf(f, ",%c", r->axis_name[i]);
    fprintf(f, "\n");
    for (size_t k = 0; k < r->n; k++) {
        fprintf(f, "%.9g", (double)(k + 1) * r->cycle_s);
        for (int i = 0; i < r->n_axes; i++)
            fprintf(f, ",%.17g", r->q[k * LSM_MAX_AXES + r->axis_index[i]]);
        fprintf(f, "\n");
    }
    fclose(f);
    f = cli_open_out(out, "run.csv", path, sizeof path);
    if (!f)
        return -1;
    fprintf(f, "t_s,feed_mm_s,block");
    for (int i = 0; i < r->n_axes; i++) {
        const char c = r->axis_name[i];
        const char *u = unit_of(c);
        fprintf(f, ",%c_set_%s", c, u);
        if (r->act)
            fprintf(f, ",%c_act_%s,%c_err_%s", c, u, c, u);
        fprintf(f, ",%c_v_%s_s,%c_a_%s_s2,%c_j_%s_s3", c, u, c, u, c, u);
    }
    fprintf(f, "\n");
    const double dt = r->cycle_s;
    for (size_t k = 0; k < r->n; k++) {
        if ((k & 0xFFF) == 0)
            sim_progress_update(prog, "CSV", (double)k / (double)r->n, (double)k * dt);
        fprintf(f, "%.9g,%.9g,%u", (double)(k + 1) * dt, r->feed[k], r->line[k]);
        for (int i = 0; i < r->n_axes; i++) {
            const int a = r->axis_index[i];
            const double q0 = r->q[k * LSM_MAX_AXES + a];
            const double q1 = k >= 1 ? r->q[(k - 1) * LSM_MAX_AXES + a] : r->start[a];
            const double q2 = k >= 2 ? r->q[(k - 2) * LSM_MAX_AXES + a] : r->start[a];
            const double q3 = k >= 3 ? r->q[(k - 3) * LSM_MAX_AXES + a] : r->start[a];
            fprintf(f, ",%.12g", q0);
            if (r->act)
                fprintf(f, ",%.12g,%.9g", r->act[k * LSM_MAX_AXES + a], q0 - r->act[k * LSM_MAX_AXES + a]);
            fprintf(f, ",%.9g,%.9g,%.9g", (q0 - q1) / dt, (q0 - 2 * q1 + q2) / (dt * dt),
                    (q0 - 3 * q1 + 3 * q2 - q3) / (dt * dt * dt));
        }
        fprintf(f, "\n");
    }
    fclose(f);
    return 0;
}

/* python -m lissom_hil.plot run DIR/run.csv --out DIR --machine M (the project's venv, or $LISSOM_PYTHON) */
static int plot_run(const char *out, const char *machine)
{
    char args[12000];
    snprintf(args, sizeof args, "run '%s/run.csv' --out '%s' --machine '%s' >/dev/null", out, out, machine);
    return cli_plot(args);
}

int cmd_run(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    const char *machine = cli_opt(&a, "machine");
    const char *out = cli_opt(&a, "out");
    const char *planner = cli_opt(&a, "planner");
    const bool json = cli_flag(&a, "json");
    const bool no_drive = cli_flag(&a, "no-drive");
    const bool no_csv = cli_flag(&a, "no-csv");
    const bool plots = cli_flag(&a, "plots");
    const bool progress_on = cli_flag(&a, "progress"), progress_off = cli_flag(&a, "no-progress");
    double ovr = 1.0, capacity = 0;
    if (cli_num(&a, "override", &ovr) < 0 || cli_num(&a, "capacity", &capacity) < 0)
        return 2;
    const char *program = cli_positional(&a, 0);
    if (cli_check_unused(&a, "run"))
        return 2;
    if (!program || !machine) {
        fprintf(stderr, "usage: lissom-sim run PROGRAM --machine MACHINE.json --out DIR [--json] "
                        "[--planner lissom|vpop] [--override F] [--capacity N] [--no-drive] [--no-csv] "
                        "[--plots] [--progress | --no-progress]\n");
        return 2;
    }
    if (plots && no_csv) {
        fprintf(stderr, "error: --plots draws from run.csv: it cannot go with --no-csv\n");
        return 2;
    }
    if (progress_on && progress_off) {
        fprintf(stderr, "error: --progress and --no-progress exclude each other\n");
        return 2;
    }
    /* the run directory goes into a shell command for the plots: refuse what would break its quoting */
    if (plots && ((out && strchr(out, '\'')) || strchr(machine, '\''))) {
        fprintf(stderr, "error: --plots: paths with a single quote (') are not supported\n");
        return 2;
    }
    if (!out)
        out = "out/run";
    sim_run_opts o;
    memset(&o, 0, sizeof o);
    if (planner == NULL || strcmp(planner, "lissom") == 0)
        o.planner = SIM_RUN_LISSOM;
    else if (strcmp(planner, "vpop") == 0)
        o.planner = SIM_RUN_VPOP;
    else if (strcmp(planner, "vpop-cont") == 0)
        o.planner = SIM_RUN_VPOP_CONT;
    else {
        fprintf(stderr, "error: --planner must be lissom, vpop or vpop-cont\n");
        return 2;
    }
    if (!(ovr > 0 && ovr <= 2)) {
        fprintf(stderr, "error: --override must be in (0, 2]\n");
        return 2;
    }
    if (!(capacity >= 0 && capacity < 1e7)) {
        fprintf(stderr, "error: --capacity out of range\n");
        return 2;
    }
    if (cli_check_regular_file("program", program) || cli_check_regular_file("machine file", machine) ||
        cli_check_out_dir("out", out))
        return 2;
    sim_machine m;
    char err[512];
    if (sim_machine_load_file(machine, &m, err, sizeof err) != SIM_MACHINE_OK) {
        fprintf(stderr, "error: %s\n", err);
        return 1;
    }
    /* --no-csv with the Lissom planner: the program is read in chunks as it runs (constant memory, pathrun.h) */
    const bool stream = no_csv && o.planner == SIM_RUN_LISSOM;
    size_t len = 0;
    char *text = stream ? NULL : sim_read_file(program, &len);
    if (!stream && !text) {
        fprintf(stderr, "error: cannot read %s\n", program);
        return 1;
    }
    o.machine = &m;
    o.text = text;
    o.len = len;
    o.path = program;
    o.capacity = (uint32_t)capacity;
    o.drives = !no_drive;
    o.summary_only = no_csv; /* constant memory: nothing is kept for CSVs */
    const bool terminal = isatty(2) != 0;
    sim_progress prog;
    sim_progress_init(&prog, stderr, progress_on || (terminal && !progress_off), terminal, progress_on ? 0 : 2.0);
    o.progress = on_progress;
    o.progress_ctx = &prog;
    sim_run_event ev = {0, 3, ovr};
    if (ovr != 1.0) {
        o.events = &ev;
        o.n_events = 1;
    }
    sim_run_result r;
    if (sim_run_program(&o, &r) != 0) {
        sim_progress_finish(&prog);
        fprintf(stderr, "error: %s\n", r.err);
        sim_run_free(&r);
        free(text);
        return 1;
    }
    int rc = 0;
    char path[4200];
    FILE *f = NULL;
    if (!no_csv && write_csvs(out, &r, &prog) != 0)
        rc = 1; /* its message is printed; the summary is not tried (one message, not two) */
    else
        f = cli_open_out(out, "summary.json", path, sizeof path);
    if (f) {
        print_summary(f, &o, &r, program, machine);
        fclose(f);
    } else {
        rc = 1;
    }
    sim_progress_finish(&prog);
    if (json) {
        print_summary(stdout, &o, &r, program, machine);
    } else {
        printf("%s on %s (%s): %.4f s, %llu cycles, max deviation %.6f mm, end error %.3g\n", program, m.name,
               sim_run_planner_name(o.planner), r.duration_s, (unsigned long long)r.cycles, r.max_dev_mm, r.end_error);
        for (int i = 0; i < r.n_axes; i++) {
            const int ax = r.axis_index[i];
            printf("  %c: v %.6g / %.6g  a %.6g / %.6g  j %.6g / %.6g\n", r.axis_name[i], r.max_v[ax],
                   m.axes[i].v_max_u_s, r.max_a[ax], m.axes[i].a_max_u_s2, r.max_j[ax], m.axes[i].j_max_u_s3);
        }
        if (no_csv)
            printf("  wrote %s/summary.json\n", out);
        else
            printf("  wrote %s/setpoints.csv, %s/run.csv, %s/summary.json\n", out, out, out);
    }
    if (plots) {
        fflush(stdout);
        sim_progress_update(&prog, "plots", -1, -1);
        const int prc = plot_run(out, machine);
        sim_progress_finish(&prog);
        if (prc != 0) {
            fprintf(stderr,
                    "error: --plots: plotting failed (python -m lissom_hil.plot, status %d; see docs/host_sim.md: "
                    "the plotter needs Python 3 with lissom_hil, numpy and matplotlib)\n",
                    prc);
            rc = 1;
        }
    }
    sim_run_free(&r);
    free(text);
    return rc;
}
