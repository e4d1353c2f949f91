/*
 * cmd_plot.c: lissom-sim plot RUN_DIR [--machine MACHINE.json] [--out DIR]
 *
 * Draws the PNG plots of a finished `lissom-sim run` (feed, acceleration, jerk and following error against time,
 * and the XY path coloured by feed) from RUN_DIR/run.csv, with the machine's limits as dashed lines when
 * --machine is given. Output goes to --out (default RUN_DIR). The drawing is hil/lissom_hil/plot.py
 * (matplotlib, the project's venv); this command only checks its arguments and calls it.
 */
#include "cli.h"
#include "commands.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

/* Paths are passed to the shell inside single quotes: refuse the one character that would end the quoting. */
static bool quotable(const char *s)
{
    return strchr(s, '\'') == NULL;
}

int cmd_plot(int argc, char **argv)
{
    cli_args a;
    cli_init(&a, argc, argv);
    const char *machine = cli_opt(&a, "machine");
    const char *out = cli_opt(&a, "out");
    const char *dir = cli_positional(&a, 0);
    if (!dir) {
        fprintf(stderr, "usage: lissom-sim plot RUN_DIR [--machine MACHINE.json] [--out DIR]\n");
        return 2;
    }
    if (cli_check_unused(&a, "plot") != 0)
        return 2;
    if (!out)
        out = dir;
    if (!quotable(dir) || !quotable(out) || (machine && !quotable(machine))) {
        fprintf(stderr, "error: paths with a single quote (') are not supported\n");
        return 2;
    }
    char csv[4096];
    struct stat st;
    if (snprintf(csv, sizeof csv, "%s/run.csv", dir) >= (int)sizeof csv || stat(csv, &st) != 0 ||
        !S_ISREG(st.st_mode)) {
        fprintf(stderr, "error: %s/run.csv not found (write it with lissom-sim run ... --out %s)\n", dir, dir);
        return 1;
    }
    if (machine && (stat(machine, &st) != 0 || !S_ISREG(st.st_mode))) {
        fprintf(stderr, "error: machine file %s not found\n", machine);
        return 1;
    }
    if (cli_mkdirs(out) != 0)
        return 1;
    char args[12800];
    int n;
    if (machine)
        n = snprintf(args, sizeof args, "run '%s' --out '%s' --machine '%s'", csv, out, machine);
    else
        n = snprintf(args, sizeof args, "run '%s' --out '%s'", csv, out);
    if (n >= (int)sizeof args) {
        fprintf(stderr, "error: paths too long\n");
        return 2;
    }
    const int rc = cli_plot(args);
    if (rc != 0) {
        fprintf(stderr, "error: plotting failed (python -m lissom_hil.plot, status %d)\n", rc);
        return 1;
    }
    return 0;
}
