/*
 * lissom-sim: the host simulator's command-line front end.
 *
 * Each subcommand lives in its own file (cmd_<name>.c) and is listed in the table below.
 * Contract for every subcommand: on success it prints its result (JSON with --json) on stdout and
 * returns 0; on bad input it prints a message on stderr and returns non-zero.
 */
#include <stdio.h>
#include <string.h>

#include "commands.h"

typedef struct {
    const char *name;
    int (*run)(int argc, char **argv); /* argv[0] is the first argument after the subcommand */
    const char *help;
} subcommand;

static const subcommand k_commands[] = {
    {"version", cmd_version, "print the version"},
    {"scurve", cmd_scurve, "plan one sin^2 velocity change (Kombarov §4)"},
    {"move", cmd_move, "plan a synchronised point-to-point move on one or more axes"},
    {"demo", cmd_demo, "S-curve demo: prints a summary, writes CSV and a PNG plot of J, A, V, S"},
    {"bench", cmd_bench, "host benchmark of the S-curve planner and per-cycle evaluator"},
    {"experiment", cmd_experiment,
     "experiment kombarov: following error of trapezoid vs sin² vs constant jerk on the simulated drive"},
    {"clothoid", cmd_clothoid, "clothoid eval|fit: evaluate a clothoid or fit one to a line (Shahzadeh IV)"},
    {"smooth", cmd_smooth, "G2 corner smoothing of a G-code file with clothoid pairs within a tolerance"},
    {"bench-clothoid", cmd_bench_clothoid, "host benchmark: ns per corner smoothed and per clothoid step"},
    {"run", cmd_run, "run a G-code program through the look-ahead planner on a machine (setpoints, limits)"},
    {"bench-planner", cmd_bench_planner,
     "host benchmark: lissom planner vs the VPOp offline reference (durations, limits, ns)"},
    {"plot", cmd_plot, "draw the PNG plots of a run directory (feed, acceleration, jerk, error, XY path by feed)"},
    {"check", cmd_check, "list every error and warning of a G-code program (exit 1 if any error)"},
    {"stream", cmd_stream, "run a G-code program on a Lissom node over SocketCAN (path blocks, progress, hold)"},
    /* further subcommands register here, one line each */
};

static void usage(FILE *f)
{
    fprintf(f, "usage: lissom-sim <command> [options]\n\ncommands:\n");
    for (size_t i = 0; i < sizeof k_commands / sizeof k_commands[0]; i++)
        fprintf(f, "  %-10s %s\n", k_commands[i].name, k_commands[i].help);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "help") == 0) {
        usage(stdout);
        return 0;
    }
    for (size_t i = 0; i < sizeof k_commands / sizeof k_commands[0]; i++) {
        if (strcmp(argv[1], k_commands[i].name) == 0)
            return k_commands[i].run(argc - 2, argv + 2);
    }
    fprintf(stderr, "error: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return 2;
}
