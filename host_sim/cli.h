/*
 * cli.h: small helpers shared by the lissom-sim subcommands (host only; may use stdio).
 *
 * Options are GNU-style `--name value` pairs or bare flags (`--json`). Numbers are parsed strictly:
 * the whole token must be a number (strtod), otherwise the command fails with a message on stderr.
 * NaN and inf are passed through to the firmware so that its own validation reports them.
 */
#ifndef LSM_SIM_CLI_H
#define LSM_SIM_CLI_H

#include <stdbool.h>
#include <stdio.h>

typedef struct cli_args {
    int argc;
    char **argv;
    unsigned char used[256]; /* which argv entries were consumed (for unknown-option errors) */
} cli_args;

void cli_init(cli_args *a, int argc, char **argv);
/* Value of --name, or NULL if absent. Marks the option and its value as used. */
const char *cli_opt(cli_args *a, const char *name);
/* true if the bare flag --name is present. */
bool cli_flag(cli_args *a, const char *name);
/* Parse --name as a number. Returns 0 ok, 1 absent (out left untouched), -1 malformed (message printed). */
int cli_num(cli_args *a, const char *name, double *out);
/* Like cli_num but the option is required (-1 with a message when absent). */
int cli_num_req(cli_args *a, const char *name, double *out);
/* Parse a comma-separated list of numbers. Returns the count (>= 1), 0 if absent, -1 malformed. */
int cli_num_list(cli_args *a, const char *name, double *out, int max);
/* Positional argument k (0-based): call after all options were read; it is the k-th argument
 * left unused that does not start with "--". */
const char *cli_positional(cli_args *a, int k);
/* Reports any argument that was not consumed; returns -1 if there is one, else 0. */
int cli_check_unused(cli_args *a, const char *cmd);
/* Strict number parse of a token (whole token, allows nan/inf spellings). */
int cli_parse_number(const char *s, double *out);

/* ---- validation where an option enters (every message names the option and the offending value) ----
 * The sane ranges of lissom-sim's options (docs/host_sim.md, "Option ranges"). Units are any consistent set
 * (mm and s by convention); the bounds are wide enough for m or mm, and narrow enough that every quantity the
 * firmware derives from them (durations, cycle counts, distances) stays finite in float and in double. */
#define CLI_CYCLE_MAX_S 0.1           /* the machine-file bound: a 100 ms cycle is already far slower than any drive */
#define CLI_LIMIT_MIN 1e-6            /* below this a limit is a typo (or a unit mix-up), and durations overflow */
#define CLI_VEL_MAX 1e6               /* mm/s: 1 km/s */
#define CLI_ACC_MAX 1e9               /* mm/s^2: 1e5 g */
#define CLI_JERK_MAX 1e12             /* mm/s^3 */
#define CLI_SNAP_MAX 1e15             /* mm/s^4 */
#define CLI_DISTANCE_MAX 1e7          /* mm: 10 km, |distance| */
#define CLI_SAMPLES_MAX_ROWS 2000000u /* --samples: rows (cycles) written at most, about 100 MB of CSV */

/* v in [lo, hi] (finite). Otherwise prints "error: --NAME VALUE is out of range: ..." and returns -1. */
int cli_check_range(const char *name, double v, double lo, double hi);
/* The control cycle: 0 < v <= CLI_CYCLE_MAX_S. */
int cli_check_cycle(const char *name, double v);
/* path names an existing regular file (not a directory, not missing); what says what it is ("program"). */
int cli_check_regular_file(const char *what, const char *path);
/* dir can be created (mkdir -p) and a file can be created in it: checked before a run, one message. */
int cli_check_out_dir(const char *name, const char *dir);
/* A --samples FILE can be created (it is created empty; the command writes it later). */
int cli_check_out_file(const char *name, const char *path);
/* rows <= CLI_SAMPLES_MAX_ROWS, else a message naming the row count and the cycle. */
int cli_check_sample_rows(const char *name, double rows, double cycle_s);

/* mkdir -p: creates dir and its parents (0 ok, -1 with a message on stderr). */
int cli_mkdirs(const char *dir);
/* Opens dir/name for writing, creating dir; the full path goes to path (size n). NULL with a message. */
FILE *cli_open_out(const char *dir, const char *name, char *path, size_t n);
/* Runs `python -m lissom_hil.plot ARGS` (ARGS quoted by the caller): from an installed tree
 * (<prefix>/share/lissom/python with python3 or $LISSOM_PYTHON), from the source tree of a build in it (<repo>/hil with
 * <repo>/.venv or $LISSOM_PYTHON), else python3 with a pip-installed lissom_hil. Returns system()'s status. */
int cli_plot(const char *args);

/* JSON output helpers: numbers are printed with 17 significant digits (round-trip exact in double);
 * NaN and inf (never expected) are printed as null. */
void json_num(FILE *f, double x);

#endif
