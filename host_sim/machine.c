/*
 * machine.c: machine description file loader (see machine.h and docs/machine_file.md).
 */
#include "machine.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "json.h"

#define MAX_TOKS 4096
#define DEG2RAD (3.14159265358979323846 / 180.0)

typedef struct {
    const char *text;
    size_t len;
    const char *source;
    const sim_json_tok *t;
    char *err;
    size_t errlen;
} ctx;

static sim_machine_status fail(const ctx *c, int tok, sim_machine_status st, const char *fmt, ...)
{
    if (c->err && c->errlen > 0) {
        int line = 0, col = 0;
        size_t at = 0;
        if (tok >= 0) {
            at = c->t[tok].start;
            if (c->t[tok].type == SIM_JSON_STRING && at > 0)
                at--; /* point at the opening quote */
        }
        sim_json_line_col(c->text, c->len, at, &line, &col);
        int n = snprintf(c->err, c->errlen, "%s:%d:%d: ", c->source, line, col);
        if (n < 0)
            n = 0;
        if ((size_t)n < c->errlen) {
            va_list ap;
            va_start(ap, fmt);
            vsnprintf(c->err + n, c->errlen - (size_t)n, fmt, ap);
            va_end(ap);
        }
    }
    return st;
}

/* Keys allowed in an object; reports the first unknown key. */
static sim_machine_status check_keys(const ctx *c, int obj, const char *where, const char *const *allowed,
                                     size_t n_allowed)
{
    for (int k = obj + 1, i = 0; i < c->t[obj].size; i++, k = c->t[k + 1].next) {
        bool ok = sim_json_string_eq(c->text, &c->t[k], "comment");
        for (size_t a = 0; a < n_allowed && !ok; a++)
            ok = sim_json_string_eq(c->text, &c->t[k], allowed[a]);
        if (!ok) {
            char key[96];
            if (sim_json_string(c->text, &c->t[k], key, sizeof key) < 0)
                snprintf(key, sizeof key, "(long key)");
            return fail(c, k, SIM_MACHINE_E_UNKNOWN_KEY, "%sunknown key \"%s\"", where, key);
        }
        if (sim_json_string_eq(c->text, &c->t[k], "comment") && c->t[k + 1].type != SIM_JSON_STRING)
            return fail(c, k + 1, SIM_MACHINE_E_TYPE, "%s\"comment\" must be a string", where);
    }
    return SIM_MACHINE_OK;
}

/* A number member: required or optional (then *found tells), > 0 (or >= 0 if allow_zero). */
static sim_machine_status get_num(const ctx *c, int obj, const char *where, const char *key, bool required,
                                  bool allow_zero, double *out, bool *found)
{
    int v = sim_json_find(c->text, c->t, obj, key);
    if (found)
        *found = v >= 0;
    if (v < 0) {
        if (required)
            return fail(c, obj, SIM_MACHINE_E_MISSING_KEY, "%smissing key \"%s\"", where, key);
        return SIM_MACHINE_OK;
    }
    if (c->t[v].type != SIM_JSON_NUMBER)
        return fail(c, v, SIM_MACHINE_E_TYPE, "%s\"%s\" must be a number, not %s", where, key,
                    sim_json_type_name(c->t[v].type));
    double x;
    sim_json_number(c->text, &c->t[v], &x);
    if (x < 0 || (!allow_zero && x == 0))
        return fail(c, v, SIM_MACHINE_E_VALUE, "%s\"%s\" must be %s (got %g)", where, key, allow_zero ? ">= 0" : "> 0",
                    x);
    *out = x;
    return SIM_MACHINE_OK;
}

static sim_machine_status get_str(const ctx *c, int obj, const char *where, const char *key, bool required, char *buf,
                                  size_t bufsize, int *tok)
{
    int v = sim_json_find(c->text, c->t, obj, key);
    if (tok)
        *tok = v;
    if (v < 0) {
        if (required)
            return fail(c, obj, SIM_MACHINE_E_MISSING_KEY, "%smissing key \"%s\"", where, key);
        buf[0] = '\0';
        return SIM_MACHINE_OK;
    }
    if (c->t[v].type != SIM_JSON_STRING)
        return fail(c, v, SIM_MACHINE_E_TYPE, "%s\"%s\" must be a string, not %s", where, key,
                    sim_json_type_name(c->t[v].type));
    if (sim_json_string(c->text, &c->t[v], buf, bufsize) < 0)
        return fail(c, v, SIM_MACHINE_E_VALUE, "%s\"%s\" is longer than %zu bytes", where, key, bufsize - 5);
    return SIM_MACHINE_OK;
}

typedef struct {
    const char *key;
    size_t offset; /* into sim_drive_params */
    bool allow_zero;
} drive_key;

#define DK(f, z)                             \
    {                                        \
#f, offsetof(sim_drive_params, f), z \
    }
static const drive_key k_drive_keys[] = {
    DK(kv_1_s, false),        DK(vff_gain, true),       DK(aff_gain, true),        DK(vel_kp_A_s_m, false),
    DK(vel_ti_s, true),       DK(current_tau_s, false), DK(current_max_A, false),  DK(force_const_N_A, false),
    DK(motor_mass_kg, false), DK(load_mass_kg, false),  DK(stiffness_N_m, false),  DK(damping_N_s_m, true),
    DK(viscous_N_s_m, true),  DK(coulomb_N, true),      DK(servo_period_s, false),
};
#define N_DRIVE_KEYS (sizeof k_drive_keys / sizeof k_drive_keys[0])

static sim_machine_status load_drive(const ctx *c, int obj, const char *where, sim_drive_params *d)
{
    if (c->t[obj].type != SIM_JSON_OBJECT)
        return fail(c, obj, SIM_MACHINE_E_TYPE, "%s\"drive\" must be an object, not %s", where,
                    sim_json_type_name(c->t[obj].type));
    const char *allowed[N_DRIVE_KEYS];
    for (size_t i = 0; i < N_DRIVE_KEYS; i++)
        allowed[i] = k_drive_keys[i].key;
    char w[64];
    snprintf(w, sizeof w, "%sdrive: ", where);
    sim_machine_status st = check_keys(c, obj, w, allowed, N_DRIVE_KEYS);
    if (st != SIM_MACHINE_OK)
        return st;
    for (size_t i = 0; i < N_DRIVE_KEYS; i++) {
        double *field = (double *)(void *)((char *)d + k_drive_keys[i].offset);
        st = get_num(c, obj, w, k_drive_keys[i].key, false, k_drive_keys[i].allow_zero, field, NULL);
        if (st != SIM_MACHINE_OK)
            return st;
    }
    return SIM_MACHINE_OK;
}

static const char *const k_linear_keys[] = {"name",           "v_max_mm_s",    "a_max_mm_s2", "j_max_mm_s3",
                                            "snap_max_mm_s4", "counts_per_mm", "drive"};
static const char *const k_rotary_keys[] = {"name",         "v_max_deg_s",     "a_max_deg_s2",
                                            "j_max_deg_s3", "snap_max_deg_s4", "counts_per_deg",
                                            "drive"};

static sim_machine_status load_axis(const ctx *c, int obj, int idx, double cycle_s, sim_machine_axis *a)
{
    char where[32];
    snprintf(where, sizeof where, "axes[%d]: ", idx);
    if (c->t[obj].type != SIM_JSON_OBJECT)
        return fail(c, obj, SIM_MACHINE_E_TYPE, "%san axis must be an object, not %s", where,
                    sim_json_type_name(c->t[obj].type));
    char name[8];
    int name_tok;
    sim_machine_status st = get_str(c, obj, where, "name", true, name, sizeof name, &name_tok);
    if (st != SIM_MACHINE_OK)
        return st;
    static const char k_names[] = "XYZABC";
    const char *pos = name[0] ? strchr(k_names, name[0]) : NULL;
    if (!pos || name[1] != '\0')
        return fail(c, name_tok, SIM_MACHINE_E_AXES, "%saxis name \"%s\" is not one of X Y Z A B C", where, name);
    *a = (sim_machine_axis){0};
    a->name = name[0];
    a->index = (int)(pos - k_names);
    a->rotary = a->index >= 3;
    const char *const *keys = a->rotary ? k_rotary_keys : k_linear_keys;
    /* a linear key on a rotary axis (or the reverse) gets a pointed message */
    const char *const *other = a->rotary ? k_linear_keys : k_rotary_keys;
    for (int k = obj + 1, i = 0; i < c->t[obj].size; i++, k = c->t[k + 1].next) {
        for (size_t o = 1; o < 6; o++) {
            if (sim_json_string_eq(c->text, &c->t[k], other[o]))
                return fail(c, k, SIM_MACHINE_E_UNKNOWN_KEY, "%sunknown key \"%s\": axis %c is %s, use \"%s\"", where,
                            other[o], a->name, a->rotary ? "rotary" : "linear", keys[o]);
        }
    }
    st = check_keys(c, obj, where, keys, 7);
    if (st != SIM_MACHINE_OK)
        return st;
    double *dst[5] = {&a->v_max_u_s, &a->a_max_u_s2, &a->j_max_u_s3, &a->snap_max_u_s4, &a->counts_per_u};
    for (int i = 0; i < 5; i++) {
        st = get_num(c, obj, where, keys[i + 1], true, false, dst[i], NULL);
        if (st != SIM_MACHINE_OK)
            return st;
    }
    if (a->rotary) {
        for (int i = 0; i < 4; i++)
            *dst[i] *= DEG2RAD;
        a->counts_per_u /= DEG2RAD; /* counts per degree -> counts per rad */
    }
    sim_drive_params_default(&a->drive, a->rotary);
    int dv = sim_json_find(c->text, c->t, obj, "drive");
    if (dv >= 0) {
        st = load_drive(c, dv, where, &a->drive);
        if (st != SIM_MACHINE_OK)
            return st;
    }
    a->drive.rotary = a->rotary;
    a->drive.encoder_counts_per_mm = a->counts_per_u;
    const char *bad = NULL;
    lsm_status ds = sim_drive_validate(&a->drive, cycle_s, &bad);
    if (ds != LSM_OK) {
        int at = dv >= 0 ? dv : obj;
        if (dv >= 0 && bad) {
            int f = sim_json_find(c->text, c->t, dv, bad);
            if (f >= 0)
                at = f;
        }
        if (bad && strcmp(bad, "servo_period_s") == 0)
            return fail(c, at, SIM_MACHINE_E_DRIVE,
                        "%sdrive: \"servo_period_s\" %g s is not valid (%s): it must be at least %g s and must not "
                        "exceed the cycle, the current time constant, or 0.5/(2 pi f_res)",
                        where, a->drive.servo_period_s, lsm_status_str(ds), SIM_DRIVE_MIN_SERVO_PERIOD_S);
        return fail(c, at, SIM_MACHINE_E_DRIVE, "%sdrive: \"%s\" is not valid (%s)", where, bad ? bad : "?",
                    lsm_status_str(ds));
    }
    /* valid numbers can still make an unstable loop: a small step must settle */
    sim_drive_step_stats ss;
    /* 1 mm (1 mrad), or 100 counts if that is more: the 2 % band must span a few counts */
    const double step = fmax(a->rotary ? 1e-3 : 1.0, 100.0 / a->counts_per_u);
    if (sim_drive_step_test(&a->drive, cycle_s, step, 2.0, &ss) != LSM_OK || !ss.settled) {
        sim_drive_modes md;
        sim_drive_modes_analytic(&a->drive, &md);
        return fail(c, dv >= 0 ? dv : obj, SIM_MACHINE_E_DRIVE,
                    "%sdrive: the position loop does not settle (a %g %s step still has an error of %.3g after "
                    "1.5 s): lower vel_kp_A_s_m or kv_1_s, or raise the resonance (now %.1f Hz)",
                    where, step, a->rotary ? "rad" : "mm", ss.max_error, md.f_res_hz);
    }
    return SIM_MACHINE_OK;
}

static const char *const k_top_keys[] = {"format",           "name",         "description", "cycle_s",
                                         "lookahead_blocks", "blend_tol_mm", "axes"};

static sim_machine_status load_impl(const char *text, size_t len, const char *source, sim_machine *out, char *err,
                                    size_t errlen, sim_json_tok *toks)
{
    ctx c =
        {.text = text, .len = len, .source = source ? source : "(machine)", .t = toks, .err = err, .errlen = errlen};
    if (err && errlen)
        err[0] = '\0';
    if (!text || !out)
        return fail(&c, -1, SIM_MACHINE_E_IO, "no input");
    sim_json_error je;
    int n = sim_json_parse(text, len, toks, MAX_TOKS, &je);
    if (n < 0) {
        if (err && errlen)
            snprintf(err, errlen, "%s:%d:%d: invalid JSON: %s", c.source, je.line, je.column, je.msg);
        return SIM_MACHINE_E_JSON;
    }
    if (toks[0].type != SIM_JSON_OBJECT)
        return fail(&c, 0, SIM_MACHINE_E_TYPE, "the top level must be an object, not %s",
                    sim_json_type_name(toks[0].type));
    sim_machine m = {0};
    char fmt[64];
    int ftok;
    sim_machine_status st = get_str(&c, 0, "", "format", false, fmt, sizeof fmt, &ftok);
    if (st != SIM_MACHINE_OK)
        return st == SIM_MACHINE_E_TYPE ? SIM_MACHINE_E_FORMAT : st;
    if (ftok < 0)
        return fail(&c, 0, SIM_MACHINE_E_FORMAT, "missing key \"format\" (expected \"%s\")", SIM_MACHINE_FORMAT);
    if (strcmp(fmt, SIM_MACHINE_FORMAT) != 0)
        return fail(&c, ftok, SIM_MACHINE_E_FORMAT, "unsupported format \"%s\" (expected \"%s\")", fmt,
                    SIM_MACHINE_FORMAT);
    st = check_keys(&c, 0, "", k_top_keys, sizeof k_top_keys / sizeof k_top_keys[0]);
    if (st != SIM_MACHINE_OK)
        return st;
    if ((st = get_str(&c, 0, "", "name", true, m.name, sizeof m.name, NULL)) != SIM_MACHINE_OK)
        return st;
    if ((st = get_str(&c, 0, "", "description", false, m.description, sizeof m.description, NULL)) != SIM_MACHINE_OK)
        return st;
    if ((st = get_num(&c, 0, "", "cycle_s", true, false, &m.cycle_s, NULL)) != SIM_MACHINE_OK)
        return st;
    if (m.cycle_s > 0.1)
        return fail(&c, sim_json_find(text, toks, 0, "cycle_s"), SIM_MACHINE_E_VALUE,
                    "\"cycle_s\" must be at most 0.1 s (got %g)", m.cycle_s);
    double la;
    if ((st = get_num(&c, 0, "", "lookahead_blocks", true, false, &la, NULL)) != SIM_MACHINE_OK)
        return st;
    if (la != floor(la) || la > 100000)
        return fail(&c, sim_json_find(text, toks, 0, "lookahead_blocks"), SIM_MACHINE_E_VALUE,
                    "\"lookahead_blocks\" must be an integer from 1 to 100000 (got %g)", la);
    m.lookahead_blocks = (int)la;
    if ((st = get_num(&c, 0, "", "blend_tol_mm", true, false, &m.blend_tol_mm, NULL)) != SIM_MACHINE_OK)
        return st;
    if (m.blend_tol_mm > 10)
        return fail(&c, sim_json_find(text, toks, 0, "blend_tol_mm"), SIM_MACHINE_E_VALUE,
                    "\"blend_tol_mm\" must be at most 10 mm (got %g)", m.blend_tol_mm);

    int ax = sim_json_find(text, toks, 0, "axes");
    if (ax < 0)
        return fail(&c, 0, SIM_MACHINE_E_MISSING_KEY, "missing key \"axes\"");
    if (toks[ax].type != SIM_JSON_ARRAY)
        return fail(&c, ax, SIM_MACHINE_E_TYPE, "\"axes\" must be an array, not %s", sim_json_type_name(toks[ax].type));
    if (toks[ax].size < 1 || toks[ax].size > SIM_MACHINE_MAX_AXES)
        return fail(&c, ax, SIM_MACHINE_E_AXES, "\"axes\" must have 1 to %d entries (has %d)", SIM_MACHINE_MAX_AXES,
                    toks[ax].size);
    for (int e = ax + 1, i = 0; i < toks[ax].size; i++, e = toks[e].next) {
        st = load_axis(&c, e, i, m.cycle_s, &m.axes[i]);
        if (st != SIM_MACHINE_OK)
            return st;
        if (m.axis_mask & (1u << m.axes[i].index))
            return fail(&c, sim_json_find(text, toks, e, "name"), SIM_MACHINE_E_AXES, "axes[%d]: axis %c is repeated",
                        i, m.axes[i].name);
        m.axis_mask |= (uint8_t)(1u << m.axes[i].index);
        m.n_axes++;
    }
    *out = m;
    return SIM_MACHINE_OK;
}

sim_machine_status sim_machine_load_text(const char *text, size_t len, const char *source, sim_machine *out, char *err,
                                         size_t errlen)
{
    sim_json_tok *toks = malloc(MAX_TOKS * sizeof *toks);
    if (!toks) {
        if (err && errlen)
            snprintf(err, errlen, "%s: out of memory", source ? source : "(machine)");
        return SIM_MACHINE_E_IO;
    }
    sim_machine_status st = load_impl(text, len, source, out, err, errlen, toks);
    free(toks);
    return st;
}

sim_machine_status sim_machine_load_file(const char *path, sim_machine *m, char *err, size_t errlen)
{
    if (err && errlen)
        err[0] = '\0';
    if (!path || !m) {
        if (err && errlen)
            snprintf(err, errlen, "no file name");
        return SIM_MACHINE_E_IO;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        if (err && errlen)
            snprintf(err, errlen, "%s: cannot open", path);
        return SIM_MACHINE_E_IO;
    }
    char *buf = malloc(SIM_MACHINE_MAX_FILE_BYTES + 1);
    if (!buf) {
        fclose(f);
        if (err && errlen)
            snprintf(err, errlen, "%s: out of memory", path);
        return SIM_MACHINE_E_IO;
    }
    size_t n = fread(buf, 1, SIM_MACHINE_MAX_FILE_BYTES + 1, f);
    bool bad = ferror(f) != 0;
    fclose(f);
    if (bad || n > SIM_MACHINE_MAX_FILE_BYTES) {
        free(buf);
        if (err && errlen)
            snprintf(err, errlen, "%s: %s", path, bad ? "read error" : "larger than 1 MiB");
        return SIM_MACHINE_E_IO;
    }
    sim_machine_status st = sim_machine_load_text(buf, n, path, m, err, errlen);
    free(buf);
    return st;
}

const sim_machine_axis *sim_machine_axis_by_name(const sim_machine *m, char name)
{
    if (!m)
        return NULL;
    if (name >= 'a' && name <= 'z')
        name = (char)(name - 'a' + 'A');
    for (int i = 0; i < m->n_axes; i++)
        if (m->axes[i].name == name)
            return &m->axes[i];
    return NULL;
}

const char *sim_machine_status_str(sim_machine_status st)
{
    switch (st) {
    case SIM_MACHINE_OK: return "ok";
    case SIM_MACHINE_E_IO: return "cannot read the file";
    case SIM_MACHINE_E_JSON: return "invalid JSON";
    case SIM_MACHINE_E_FORMAT: return "missing or unsupported format";
    case SIM_MACHINE_E_UNKNOWN_KEY: return "unknown key";
    case SIM_MACHINE_E_MISSING_KEY: return "missing key";
    case SIM_MACHINE_E_TYPE: return "wrong value type";
    case SIM_MACHINE_E_VALUE: return "value out of range";
    case SIM_MACHINE_E_AXES: return "bad axes";
    case SIM_MACHINE_E_DRIVE: return "invalid drive parameters";
    }
    return "unknown status";
}
