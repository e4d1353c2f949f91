#include "cli.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void cli_init(cli_args *a, int argc, char **argv)
{
    a->argc = argc;
    a->argv = argv;
    memset(a->used, 0, sizeof a->used);
}

static int find(cli_args *a, const char *name)
{
    for (int i = 0; i < a->argc && i < 256; i++) {
        const char *s = a->argv[i];
        if (s[0] == '-' && s[1] == '-' && strcmp(s + 2, name) == 0)
            return i;
    }
    return -1;
}

const char *cli_opt(cli_args *a, const char *name)
{
    int i = find(a, name);
    if (i < 0)
        return NULL;
    a->used[i] = 1;
    if (i + 1 >= a->argc) {
        fprintf(stderr, "error: option --%s needs a value\n", name);
        return "";
    }
    a->used[i + 1] = 1;
    return a->argv[i + 1];
}

bool cli_flag(cli_args *a, const char *name)
{
    int i = find(a, name);
    if (i < 0)
        return false;
    a->used[i] = 1;
    return true;
}

int cli_parse_number(const char *s, double *out)
{
    if (s == NULL || *s == '\0')
        return -1;
    errno = 0;
    char *end = NULL;
    double v = strtod(s, &end);
    if (end == s || *end != '\0')
        return -1;
    if (errno == ERANGE && isfinite(v) && v != 0.0)
        return -1;
    *out = v; /* ERANGE overflow gives +/-HUGE_VAL (inf): left to the firmware to reject */
    return 0;
}

int cli_num(cli_args *a, const char *name, double *out)
{
    const char *s = cli_opt(a, name);
    if (s == NULL)
        return 1;
    if (cli_parse_number(s, out) != 0) {
        fprintf(stderr, "error: --%s: '%s' is not a number\n", name, s);
        return -1;
    }
    return 0;
}

int cli_num_req(cli_args *a, const char *name, double *out)
{
    int r = cli_num(a, name, out);
    if (r == 1) {
        fprintf(stderr, "error: missing required option --%s\n", name);
        return -1;
    }
    return r;
}

int cli_num_list(cli_args *a, const char *name, double *out, int max)
{
    const char *s = cli_opt(a, name);
    if (s == NULL)
        return 0;
    char buf[1024];
    size_t len = strlen(s);
    if (len == 0 || len >= sizeof buf) {
        fprintf(stderr, "error: --%s: bad list\n", name);
        return -1;
    }
    memcpy(buf, s, len + 1);
    int n = 0;
    char *p = buf;
    for (;;) {
        char *comma = strchr(p, ',');
        if (comma)
            *comma = '\0';
        if (n >= max) {
            fprintf(stderr, "error: --%s: at most %d values\n", name, max);
            return -1;
        }
        if (cli_parse_number(p, &out[n]) != 0) {
            fprintf(stderr, "error: --%s: '%s' is not a number\n", name, p);
            return -1;
        }
        n++;
        if (!comma)
            break;
        p = comma + 1;
    }
    return n;
}

const char *cli_positional(cli_args *a, int k)
{
    /* call after every option was read: what is left unused and not "--x" is positional */
    for (int i = 0; i < a->argc && i < 256; i++) {
        const char *s = a->argv[i];
        if (a->used[i] || (s[0] == '-' && s[1] == '-'))
            continue;
        if (k-- == 0) {
            a->used[i] = 1;
            return s;
        }
    }
    return NULL;
}

int cli_check_unused(cli_args *a, const char *cmd)
{
    int bad = 0;
    for (int i = 0; i < a->argc && i < 256; i++) {
        if (!a->used[i]) {
            fprintf(stderr, "error: %s: unknown or unexpected argument '%s'\n", cmd, a->argv[i]);
            bad = 1;
        }
    }
    return bad ? -1 : 0;
}

void json_num(FILE *f, double x)
{
    if (!isfinite(x))
        fputs("null", f);
    else
        fprintf(f, "%.17g", x);
}

int cli_mkdirs(const char *dir)
{
    char path[4096];
    if (snprintf(path, sizeof path, "%s", dir) >= (int)sizeof path) {
        fprintf(stderr, "error: path too long: %s\n", dir);
        return -1;
    }
    for (char *p = path + 1; *p; p++) {
        if (*p == '/') {
            *p = '\0';
            mkdir(path, 0755);
            *p = '/';
        }
    }
    if (mkdir(path, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "error: cannot create %s\n", dir);
        return -1;
    }
    return 0;
}

FILE *cli_open_out(const char *dir, const char *name, char *path, size_t n)
{
    if (cli_mkdirs(dir) != 0)
        return NULL;
    if (snprintf(path, n, "%s/%s", dir, name) >= (int)n) {
        fprintf(stderr, "error: path too long: %s/%s\n", dir, name);
        return NULL;
    }
    FILE *f = fopen(path, "w");
    if (!f)
        fprintf(stderr, "error: cannot write %s\n", path);
    return f;
}

/* Where the plotter is, in this order: an installed tree (<exe>/../share/lissom/python, the interpreter $LISSOM_PYTHON
 * or python3 on PATH); a build in the source tree (<repo>/build/bin/lissom-sim: <repo>/hil, the interpreter
 * $LISSOM_PYTHON or <repo>/.venv/bin/python); else python3 (or $LISSOM_PYTHON) with a pip-installed lissom_hil. */
int cli_plot(const char *args)
{
    char exe[3000];
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0)
        return -1;
    exe[n] = '\0';
    char *slash = strrchr(exe, '/'); /* exe = <prefix>/bin */
    if (!slash)
        return -1;
    *slash = '\0';
    const char *env = getenv("LISSOM_PYTHON");
    char pypath[3300] = "", py[3300];
    struct stat st;
    snprintf(py, sizeof py, "%s", env && *env ? env : "python3");
    char probe[3300];
    snprintf(probe, sizeof probe, "%s/../share/lissom/python/lissom_hil/plot.py", exe);
    if (stat(probe, &st) == 0) {
        snprintf(pypath, sizeof pypath, "%s/../share/lissom/python", exe);
    } else {
        char repo[3000];
        snprintf(repo, sizeof repo, "%s", exe);
        for (int up = 0; up < 2; up++) { /* <repo>/build/bin -> <repo> */
            char *s2 = strrchr(repo, '/');
            if (s2)
                *s2 = '\0';
        }
        snprintf(probe, sizeof probe, "%s/hil/lissom_hil/plot.py", repo);
        if (stat(probe, &st) == 0) {
            snprintf(pypath, sizeof pypath, "%s/hil", repo);
            snprintf(probe, sizeof probe, "%s/.venv/bin/python", repo);
            if (!(env && *env) && stat(probe, &st) == 0)
                snprintf(py, sizeof py, "%s", probe);
        }
    }
    if (strchr(py, '\'') || strchr(pypath, '\''))
        return -1;
    char cmd[16384];
    int w;
    if (pypath[0])
        w = snprintf(cmd, sizeof cmd, "PYTHONPATH='%s'${PYTHONPATH:+:$PYTHONPATH} '%s' -m lissom_hil.plot %s", pypath,
                     py, args);
    else
        w = snprintf(cmd, sizeof cmd, "'%s' -m lissom_hil.plot %s", py, args);
    if (w >= (int)sizeof cmd)
        return -1;
    const int rc = system(cmd);
    return rc == -1 ? -1 : (WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + (WIFSIGNALED(rc) ? WTERMSIG(rc) : 0));
}

/* ---------------------------------------------------------------------------------------------------------- */
/* validation of options where they enter                                                                      */

int cli_check_range(const char *name, double v, double lo, double hi)
{
    if (isfinite(v) && v >= lo && v <= hi)
        return 0;
    fprintf(stderr, "error: --%s %g is out of range: it must be a number in [%g, %g] (docs/host_sim.md)\n", name, v, lo,
            hi);
    return -1;
}

int cli_check_cycle(const char *name, double v)
{
    if (isfinite(v) && v > 0 && v <= CLI_CYCLE_MAX_S)
        return 0;
    fprintf(stderr, "error: --%s %g is out of range: the control cycle must be in (0, %g] s\n", name, v,
            CLI_CYCLE_MAX_S);
    return -1;
}

int cli_check_regular_file(const char *what, const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        fprintf(stderr, "error: %s '%s' cannot be read: %s\n", what, path, strerror(errno));
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        fprintf(stderr, "error: %s '%s' is %s, not a regular file\n", what, path,
                S_ISDIR(st.st_mode) ? "a directory" : "a special file");
        return -1;
    }
    return 0;
}

int cli_check_out_dir(const char *name, const char *dir)
{
    if (cli_mkdirs(dir) != 0)
        return -1; /* "cannot create DIR" printed */
    char probe[4200];
    if (snprintf(probe, sizeof probe, "%s/.lissom-write-check-%ld", dir, (long)getpid()) >= (int)sizeof probe) {
        fprintf(stderr, "error: --%s: path too long: %s\n", name, dir);
        return -1;
    }
    const int fd = open(probe, O_WRONLY | O_CREAT | O_EXCL, 0644);
    if (fd < 0) {
        fprintf(stderr, "error: --%s '%s' is not writable: %s\n", name, dir, strerror(errno));
        return -1;
    }
    close(fd);
    unlink(probe);
    return 0;
}

int cli_check_out_file(const char *name, const char *path)
{
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        fprintf(stderr, "error: --%s '%s' is a directory\n", name, path);
        return -1;
    }
    const bool existed = stat(path, &st) == 0;
    FILE *f = fopen(path, "a"); /* "a": an existing file is left as it is until the command writes it */
    if (!f) {
        fprintf(stderr, "error: --%s '%s' cannot be written: %s\n", name, path, strerror(errno));
        return -1;
    }
    fclose(f);
    if (!existed)
        unlink(path);
    return 0;
}

int cli_check_sample_rows(const char *name, double rows, double cycle_s)
{
    if (rows <= (double)CLI_SAMPLES_MAX_ROWS)
        return 0;
    fprintf(stderr,
            "error: --%s: the profile has %.0f cycles of %g s, more than the %u rows --%s writes at most; "
            "use a longer --cycle\n",
            name, rows, cycle_s, CLI_SAMPLES_MAX_ROWS, name);
    return -1;
}
