/*
 * gcode.c: streaming RS274/NGC subset parser (see gcode.h for the dialect, units and rules).
 *
 * Each line goes through three steps, all on the stack:
 *   1. a byte check (control bytes anywhere, non-ASCII outside comments -> LSM_E_GC_BINARY);
 *   2. a scan into a word table (one slot per letter, one per modal group), which reports the
 *      lexical errors left to right;
 *   3. execution on a copy of the modal state, in RS274/NGC order (F, units, plane, distance,
 *      path control, motion, stop), committed only if the whole line succeeds (gcode_exec.c).
 */

#include "gcode_int.h"


typedef struct {
    int16_t group;
    int16_t code10; /* G number times ten */
} gc_gdef;

static const gc_gdef k_gcodes[] = {
    {GRP_MOTION, 0},     {GRP_MOTION, 10},    {GRP_MOTION, 20},    {GRP_MOTION, 30},    {GRP_MOTION, 800},
    {GRP_PLANE, 170},    {GRP_PLANE, 180},    {GRP_PLANE, 190},    {GRP_DISTANCE, 900}, {GRP_DISTANCE, 910},
    {GRP_ARCDIST, 901},  {GRP_ARCDIST, 911},  {GRP_UNITS, 200},    {GRP_UNITS, 210},    {GRP_PATH, 610},
    {GRP_PATH, 640},     {GRP_FEEDMODE, 940}, {GRP_COMP, 400},     {GRP_TOOL_LEN, 430}, {GRP_TOOL_LEN, 490},
    {GRP_WCS, 540},      {GRP_WCS, 550},      {GRP_WCS, 560},      {GRP_WCS, 570},      {GRP_WCS, 580},
    {GRP_WCS, 590},      {GRP_NONMODAL, 40},  {GRP_NONMODAL, 100}, {GRP_NONMODAL, 280}, {GRP_NONMODAL, 281},
    {GRP_NONMODAL, 300}, {GRP_NONMODAL, 301}, {GRP_NONMODAL, 530}, {GRP_NONMODAL, 920}, {GRP_NONMODAL, 921},
    {GRP_NONMODAL, 922},
};

/* LinuxCNC words that this subset knows but does not run: refused with the reason. */
typedef struct {
    int16_t code10;
    const char *reason;
} gc_unsup;

static const gc_unsup k_unsup_g[] = {
    {50, "unsupported: splines (G5)"},
    {51, "unsupported: splines (G5.1)"},
    {52, "unsupported: NURBS (G5.2)"},
    {70, "unsupported: lathe diameter mode"},
    {80, "unsupported: lathe radius mode"},
    {330, "unsupported: spindle-synchronized motion"},
    {331, "unsupported: rigid tapping"},
    {382, "unsupported: probing"},
    {383, "unsupported: probing"},
    {384, "unsupported: probing"},
    {385, "unsupported: probing"},
    {410, "unsupported: cutter compensation"},
    {411, "unsupported: cutter compensation"},
    {420, "unsupported: cutter compensation"},
    {421, "unsupported: cutter compensation"},
    {431, "unsupported: dynamic tool length offset"},
    {432, "unsupported: additive tool length offset"},
    {520, "unsupported: local offsets (G52)"},
    {591, "unsupported: coordinate systems G59.1-G59.3"},
    {592, "unsupported: coordinate systems G59.1-G59.3"},
    {593, "unsupported: coordinate systems G59.1-G59.3"},
    {730, "unsupported: canned cycles"},
    {760, "unsupported: threading cycle"},
    {810, "unsupported: canned cycles"},
    {820, "unsupported: canned cycles"},
    {830, "unsupported: canned cycles"},
    {840, "unsupported: canned cycles"},
    {850, "unsupported: canned cycles"},
    {860, "unsupported: canned cycles"},
    {870, "unsupported: canned cycles"},
    {880, "unsupported: canned cycles"},
    {890, "unsupported: canned cycles"},
    {923, "unsupported: restoring G92 offsets (G92.3)"},
    {930, "unsupported: inverse-time feed"},
    {950, "unsupported: feed per revolution"},
    {960, "unsupported: constant surface speed"},
    {970, "unsupported: constant surface speed"},
    {980, "unsupported: canned cycle return mode"},
    {990, "unsupported: canned cycle return mode"},
};

static const gc_unsup k_unsup_m[] = {
    {190, "unsupported: spindle orientation"},
    {480, "unsupported: override control"},
    {490, "unsupported: override control"},
    {500, "unsupported: override control"},
    {510, "unsupported: override control"},
    {520, "unsupported: override control"},
    {530, "unsupported: override control"},
    {600, "unsupported: pallet change"},
    {610, "unsupported: setting the current tool (M61)"},
    {620, "unsupported: digital outputs"},
    {630, "unsupported: digital outputs"},
    {640, "unsupported: digital outputs"},
    {650, "unsupported: digital outputs"},
    {660, "unsupported: waiting on inputs"},
    {670, "unsupported: analog outputs"},
    {680, "unsupported: analog outputs"},
    {700, "unsupported: saving modal state"},
    {710, "unsupported: saving modal state"},
    {720, "unsupported: saving modal state"},
    {730, "unsupported: saving modal state"},
    {980, "unsupported: subroutines (M98)"},
    {990, "unsupported: subroutines (M99)"},
};


static lsm_real pow10_r(unsigned k)
{
    static const lsm_real k_pow10[GC_MAX_SIG_DIGITS + 1] = {LSM_R(1e0),  LSM_R(1e1),  LSM_R(1e2),  LSM_R(1e3),
                                                            LSM_R(1e4),  LSM_R(1e5),  LSM_R(1e6),  LSM_R(1e7),
                                                            LSM_R(1e8),  LSM_R(1e9),  LSM_R(1e10), LSM_R(1e11),
                                                            LSM_R(1e12), LSM_R(1e13), LSM_R(1e14), LSM_R(1e15),
                                                            LSM_R(1e16), LSM_R(1e17), LSM_R(1e18)};
    return k_pow10[k];
}

static bool is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r';
}

static uint32_t skip_blanks(const char *s, uint32_t n, uint32_t i)
{
    while (i < n && is_blank(s[i]))
        i++;
    return i;
}

/* Step 1: bytes. Control bytes (other than tab and CR) are junk everywhere; bytes >= 0x80 are
 * accepted inside comments only (UTF-8 text in comments is common in CAM output). */
static lsm_status check_bytes(const char *s, uint32_t n, lsm_gcode_result *res)
{
    bool in_paren = false, in_semi = false;
    for (uint32_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F)
            return fail(res, LSM_E_GC_BINARY, i + 1);
        if (c >= 0x80 && !in_paren && !in_semi)
            return fail(res, LSM_E_GC_BINARY, i + 1);
        if (!in_semi) {
            if (c == '(')
                in_paren = true;
            else if (c == ')')
                in_paren = false;
            else if (c == ';' && !in_paren)
                in_semi = true;
        }
    }
    return LSM_OK;
}

/* Reads the number after a letter (blanks allowed anywhere inside, as in RS274/NGC). */
static lsm_status read_number(const char *s, uint32_t n, uint32_t *pi, uint32_t col, gc_num *out, lsm_gcode_result *res)
{
    uint32_t i = skip_blanks(s, n, *pi);
    if (i < n && s[i] == '#')
        return fail_r(res, LSM_E_GC_UNSUPPORTED, i + 1, "unsupported: parameters");
    if (i < n && s[i] == '[')
        return fail_r(res, LSM_E_GC_UNSUPPORTED, i + 1, "unsupported: expressions");
    bool neg = false, any = false, dot = false, overflow = false;
    uint64_t m = 0;
    unsigned sig = 0, frac = 0;
    if (i < n && (s[i] == '+' || s[i] == '-')) {
        neg = s[i] == '-';
        i = skip_blanks(s, n, i + 1);
    }
    for (; i < n; i++) {
        char c = s[i];
        if (c >= '0' && c <= '9') {
            unsigned d = (unsigned)(c - '0');
            any = true;
            if (dot) {
                if (sig < GC_MAX_SIG_DIGITS && frac < GC_MAX_SIG_DIGITS) {
                    m = m * 10u + d;
                    frac++;
                    if (m != 0)
                        sig++;
                } /* further fraction digits are below the type's resolution: dropped */
            } else if (sig < GC_MAX_SIG_DIGITS) {
                m = m * 10u + d;
                if (m != 0)
                    sig++;
            } else {
                overflow = true;
            }
        } else if (c == '.' && !dot) {
            dot = true;
        } else if (!is_blank(c)) {
            break;
        }
    }
    *pi = i;
    if (!any)
        return fail(res, LSM_E_GC_MISSING_ARG, col);
    if (overflow)
        return fail(res, LSM_E_GC_NUMBER_RANGE, col);
    lsm_real v = (lsm_real)m / pow10_r(frac);
    if (v > (lsm_real)LSM_GCODE_MAX_ABS)
        return fail(res, LSM_E_GC_NUMBER_RANGE, col);
    out->mant = m;
    out->frac = (uint8_t)frac;
    out->neg = neg;
    out->value = neg ? -v : v;
    return LSM_OK;
}

/* Integer value of a parsed number times ten (G61.1 -> 611), or -1 if it has more than one
 * significant decimal or is negative. */
static int32_t code_times_ten(const gc_num *x)
{
    if (x->neg && x->mant != 0)
        return -1;
    if (x->frac == 0)
        return (int32_t)(x->mant * 10u);
    uint64_t m = x->mant;
    for (unsigned k = 1; k < x->frac; k++) {
        if (m % 10u != 0)
            return -1;
        m /= 10u;
    }
    return (int32_t)m;
}


/* Reason for a G or M number this subset knows but refuses (NULL: unknown). */
static const char *unsupported_reason(const gc_unsup *t, size_t n, int32_t code)
{
    for (size_t k = 0; k < n; k++)
        if (t[k].code10 == code)
            return t[k].reason;
    return NULL;
}

static lsm_status scan_g(gc_words *w, int32_t code, uint32_t col, lsm_gcode_result *res)
{
    int grp = -1;
    for (size_t k = 0; k < sizeof k_gcodes / sizeof k_gcodes[0]; k++) {
        if (k_gcodes[k].code10 == code) {
            grp = k_gcodes[k].group;
            break;
        }
    }
    if (grp < 0) {
        const char *why = unsupported_reason(k_unsup_g, sizeof k_unsup_g / sizeof k_unsup_g[0], code);
        return why ? fail_r(res, LSM_E_GC_UNSUPPORTED, col, why) : fail(res, LSM_E_GC_UNKNOWN_WORD, col);
    }
    if (w->g[grp] >= 0) {
        /* G80 next to another motion code: the other one wins (LinuxCNC accepts the preamble
         * "G0 G17 G40 G49 G80 G90") */
        if (grp == GRP_MOTION && code == 800 && w->g[grp] != 800)
            return LSM_OK;
        if (!(grp == GRP_MOTION && w->g[grp] == 800 && code != 800))
            return fail_r(res, LSM_E_GC_MODAL_CONFLICT, col, "two G words of one modal group");
    }
    w->g[grp] = (int16_t)code;
    w->gcol[grp] = col;
    return LSM_OK;
}

static lsm_status scan_m(gc_words *w, int32_t code, uint32_t col, lsm_gcode_result *res)
{
    int grp;
    switch (code) {
    case 0:
    case 10:
    case 20:
    case 300: grp = MG_STOP; break;
    case 60: grp = MG_TOOL; break;
    case 30:
    case 40:
    case 50: grp = MG_SPINDLE; break;
    case 70: grp = MG_MIST; break;
    case 80: grp = MG_FLOOD; break;
    case 90: grp = MG_COOL_OFF; break;
    default: {
        const char *why = unsupported_reason(k_unsup_m, sizeof k_unsup_m / sizeof k_unsup_m[0], code);
        if (!why && code >= 1000 && code <= 1990)
            why = "unsupported: user M-codes (M100-M199)";
        return why ? fail_r(res, LSM_E_GC_UNSUPPORTED, col, why) : fail(res, LSM_E_GC_UNKNOWN_WORD, col);
    }
    }
    /* M7 and M8 may share a line; M9 with either is a conflict (one coolant group) */
    const bool cool_clash = (grp == MG_COOL_OFF && (w->m[MG_MIST] >= 0 || w->m[MG_FLOOD] >= 0)) ||
                            ((grp == MG_MIST || grp == MG_FLOOD) && w->m[MG_COOL_OFF] >= 0);
    if (w->m[grp] >= 0 || cool_clash)
        return fail_r(res, LSM_E_GC_MODAL_CONFLICT, col, "two M words of one modal group");
    w->m[grp] = (int16_t)code;
    w->mcol[grp] = col;
    return LSM_OK;
}

/* Characters that start something this subset refuses, with the reason (NULL: none). */
static const char *unsupported_char(char c)
{
    switch (c) {
    case '#': return "unsupported: parameters";
    case '[': return "unsupported: expressions";
    case '<': return "unsupported: named parameters";
    case '@':
    case '^': return "unsupported: polar coordinates";
    case 'O': return "unsupported: O-words (subroutines, loops, conditionals)";
    case 'U':
    case 'V':
    case 'W': return "unsupported: U V W axes";
    case 'D': return "unsupported: cutter compensation (D)";
    default: return NULL;
    }
}

/* Skips a "( ... )" comment starting at i; returns the index after it. */
static lsm_status skip_comment(const char *s, uint32_t n, uint32_t *pi, lsm_gcode_result *res)
{
    uint32_t j = *pi + 1;
    while (j < n && s[j] != ')') {
        if (s[j] == '(')
            return fail_r(res, LSM_E_GC_COMMENT, j + 1, "nested comment");
        j++;
    }
    if (j >= n)
        return fail_r(res, LSM_E_GC_COMMENT, *pi + 1, "unclosed comment");
    *pi = j + 1;
    return LSM_OK;
}

/* Checks of a letter word's value that need no context; records N. */
static lsm_status check_word(const lsm_gcode *p, gc_words *w, char c, const gc_num *num, uint32_t col,
                             lsm_gcode_result *res)
{
    uint32_t u;
    if (c == 'N') {
        if (w->n_words != 0)
            return fail_r(res, LSM_E_GC_SYNTAX, col, "N must be the first word of a line");
        if (!as_uint(num, &u))
            return fail_r(res, LSM_E_GC_BAD_VALUE, col, "N must be a non-negative integer");
        res->has_n = true;
        res->n = u;
    } else if (c == 'F' || c == 'S') {
        if (num->value < 0)
            return fail_r(res, LSM_E_GC_BAD_VALUE, col, c == 'F' ? "negative feed" : "negative spindle speed");
    } else if (c == 'T' || c == 'H') {
        if (!as_uint(num, &u) || u > LSM_GCODE_MAX_TOOL)
            return fail_r(res, LSM_E_GC_BAD_VALUE, col, "tool number must be an integer 0..99999");
    } else if (AXIS_BITS & BIT(c)) {
        for (unsigned k = 0; k < LSM_GCODE_N_AXES; k++) {
            if (k_axis_letters[k] == c && !(p->opt.axis_mask & (1u << k)))
                return fail_r(res, LSM_E_GC_NO_AXIS, col, "the machine has no such axis");
        }
    }
    return LSM_OK;
}

/* Step 2: the word table. */
static lsm_status scan_words(const lsm_gcode *p, const char *s, uint32_t n, uint32_t i, gc_words *w,
                             lsm_gcode_result *res)
{
    for (int g = 0; g < GRP_COUNT; g++)
        w->g[g] = -1;
    for (int g = 0; g < MG_COUNT; g++)
        w->m[g] = -1;
    for (;;) {
        i = skip_blanks(s, n, i);
        if (i >= n)
            return LSM_OK;
        char c = s[i];
        uint32_t col = i + 1;
        if (c == ';')
            return LSM_OK;
        if (c == '(') {
            lsm_status st = skip_comment(s, n, &i, res);
            if (st != LSM_OK)
                return st;
            continue;
        }
        if (c == ')')
            return fail_r(res, LSM_E_GC_COMMENT, col, "')' without '('");
        if (c >= 'a' && c <= 'z')
            c = (char)(c - 'a' + 'A');
        const char *why = unsupported_char(c);
        if (why)
            return fail_r(res, LSM_E_GC_UNSUPPORTED, col, why);
        if (c < 'A' || c > 'Z')
            return fail(res, LSM_E_GC_SYNTAX, col);
        if (!(KNOWN_BITS & BIT(c)))
            return fail(res, LSM_E_GC_UNKNOWN_WORD, col);
        i++;
        gc_num num;
        lsm_status st = read_number(s, n, &i, col, &num, res);
        if (st != LSM_OK)
            return st;
        if (c == 'G' || c == 'M') {
            int32_t code = code_times_ten(&num);
            st = c == 'G' ? scan_g(w, code, col, res) : scan_m(w, code, col, res);
            if (st != LSM_OK)
                return st;
            w->n_words++;
            continue;
        }
        if (w->seen & BIT(c))
            return fail_r(res, LSM_E_GC_WORD_REPEATED, col, "word repeated on one line");
        st = check_word(p, w, c, &num, col, res);
        if (st != LSM_OK)
            return st;
        w->seen |= BIT(c);
        w->val[LETTER(c)] = num.value;
        w->col[LETTER(c)] = col;
        if (c == 'P')
            w->pnum = num;
        else if (c == 'L')
            w->lnum = num;
        w->n_words++;
    }
}

/* Copies the offending word at the error's column into err.word: a letter and its number (blanks
 * removed, upper case), "#..." / "[...]" / "<...>", or the single character; "0xNN" for a binary byte. */
static void describe_word(lsm_gcode_result *res, const char *s, uint32_t n)
{
    lsm_gcode_error *e = &res->err;
    char *out = e->word;
    const uint32_t cap = 20u; /* then "..." and the NUL: sizeof e->word >= 24 */
    uint32_t k = 0, i = e->column ? e->column - 1u : 0u;
    out[0] = '\0';
    if (i >= n)
        return;
    const unsigned char c0 = (unsigned char)s[i];
    if (c0 < 0x20 || c0 >= 0x7F) {
        static const char hex[] = "0123456789ABCDEF";
        out[0] = '0', out[1] = 'x', out[2] = hex[c0 >> 4], out[3] = hex[c0 & 15u], out[4] = '\0';
        return;
    }
    char close = c0 == '[' ? ']' : c0 == '<' ? '>' : 0;
    const bool letter = (c0 >= 'A' && c0 <= 'Z') || (c0 >= 'a' && c0 <= 'z');
    out[k++] = (char)(c0 >= 'a' && c0 <= 'z' ? c0 - 'a' + 'A' : c0);
    for (i++; i < n && k < cap; i++) {
        const char c = s[i];
        if (close) {
            if (!is_blank(c))
                out[k++] = c;
            if (c == close)
                break;
        } else if (letter || c0 == '#') {
            if (c0 == '#' && c == '<')
                close = '>';
            if (is_blank(c))
                continue;
            if (!((c >= '0' && c <= '9') || c == '.' || c == '+' || c == '-' || c == '<'))
                break;
            out[k++] = c;
        } else {
            break;
        }
    }
    if (k == cap && i < n && i + 1 < n && !is_blank(s[i]) && !(s[i] == close)) {
        out[k++] = '.', out[k++] = '.', out[k++] = '.';
    }
    out[k] = '\0';
}

/* Parses one line (no line ending) and fills res; the line number is already in res->line. */
static lsm_status parse_words(lsm_gcode *p, const char *s, uint32_t n, lsm_gcode_result *res)
{
    lsm_status st = check_bytes(s, n, res);
    if (st != LSM_OK)
        return st;
    uint32_t i = skip_blanks(s, n, 0);
    if (i >= n)
        return LSM_OK;
    const bool first_line = !p->seen_content;
    p->seen_content = true;
    if (s[i] == '%') {
        uint32_t j = skip_blanks(s, n, i + 1);
        if (j < n)
            return fail_r(res, LSM_E_GC_SYNTAX, j + 1, "text after '%'");
        if (first_line && !p->percent_open) {
            p->percent_open = true;
        } else {
            if (p->modal.spindle != 5)
                push_event(res, LSM_GCODE_EV_SPINDLE_STOP, true, 0, 0);
            if (p->modal.mist || p->modal.flood)
                push_event(res, LSM_GCODE_EV_COOLANT_OFF, true, 0, 0);
            p->modal.spindle = 5;
            p->modal.mist = p->modal.flood = false;
            push_event(res, LSM_GCODE_EV_END, true, 0, 0);
            p->ended = true;
        }
        return LSM_OK;
    }
    if (s[i] == '/') {
        if (p->opt.block_delete) {
            res->deleted = true;
            return LSM_OK;
        }
        i++;
    }
    gc_words w = {0};
    st = scan_words(p, s, n, i, &w, res);
    if (st != LSM_OK)
        return st;
    return lsm_gc_execute(p, &w, res);
}

static lsm_status parse(lsm_gcode *p, const char *s, uint32_t n, lsm_gcode_result *res)
{
    lsm_status st = parse_words(p, s, n, res);
    if (st != LSM_OK)
        describe_word(res, s, n);
    return st;
}

/* A line after the end of the program: read and ignored; flagged when it holds more than blanks, comments and
 * the closing '%'. */
static void mark_ignored(lsm_gcode_result *res, const char *s, size_t n)
{
    bool paren = false;
    for (size_t i = 0; i < n; i++) {
        const char c = s[i];
        if (c == ';' && !paren)
            return;
        if (c == '(' || c == ')')
            paren = c == '(';
        else if (!paren && !is_blank(c) && c != '\n' && c != '%')
            res->ignored = true;
    }
}

static void result_begin(lsm_gcode *p, lsm_gcode_result *res)
{
    *res = (lsm_gcode_result){0};
    res->complete = true;
    res->line = ++p->line_no;
    res->status = LSM_OK;
    res->nonmodal = -1;
}

static lsm_status result_end(lsm_gcode *p, lsm_gcode_result *res, lsm_status st)
{
    if (st != LSM_OK) {
        res->n_blocks = 0;
        res->n_events = 0;
    }
    res->status = st;
    res->modal = p->modal;
    res->end_of_program = p->ended;
    return st;
}

/* Completes the buffered line. */
static lsm_status complete_line(lsm_gcode *p, lsm_gcode_result *res)
{
    const bool was_ended = p->ended;
    result_begin(p, res);
    uint32_t n = p->len;
    bool overflow = p->overflow;
    p->len = 0;
    p->overflow = false;
    p->pending = false;
    if (was_ended) {
        mark_ignored(res, p->buf, overflow ? 1u : n);
        return result_end(p, res, LSM_OK);
    }
    if (n > 0 && p->buf[n - 1] == '\r')
        n--;
    if (overflow || n > LSM_GCODE_MAX_LINE)
        return result_end(p, res, fail_r(res, LSM_E_GC_LINE_TOO_LONG, LSM_GCODE_MAX_LINE + 1, "line too long"));
    return result_end(p, res, parse(p, p->buf, n, res));
}

void lsm_gcode_default_options(lsm_gcode_options *opt)
{
    if (!opt)
        return;
    opt->axis_mask = LSM_GCODE_ALL_AXES;
    opt->block_delete = false;
    opt->units = LSM_GCODE_UNITS_MM;
    opt->optional_stop = true;
}

lsm_status lsm_gcode_init(lsm_gcode *p, const lsm_gcode_options *opt)
{
    if (!p)
        return LSM_E_NULL;
    lsm_gcode_options o;
    if (opt)
        o = *opt;
    else
        lsm_gcode_default_options(&o);
    if (o.axis_mask == 0 || (o.axis_mask & ~LSM_GCODE_ALL_AXES) != 0)
        return LSM_E_ARG;
    if (o.units != LSM_GCODE_UNITS_MM && o.units != LSM_GCODE_UNITS_INCH)
        return LSM_E_ARG;
    *p = (lsm_gcode){0};
    p->opt = o;
    p->modal.motion = LSM_GCODE_MOTION_NONE;
    p->modal.plane = LSM_GCODE_PLANE_XY;
    p->modal.units = o.units;
    p->modal.distance = LSM_GCODE_ABSOLUTE;
    p->modal.blend = LSM_GCODE_BLEND;
    p->modal.blend_tol_mm = 0;
    p->modal.feed_mm_s = 0;
    p->modal.feed_rot_rad_s = 0;
    p->modal.wcs = 1;
    p->modal.spindle = 5;
    p->modal.tool_length_h = -1;
    p->modal.tool_selected = -1;
    return LSM_OK;
}

lsm_status lsm_gcode_set_position(lsm_gcode *p, const lsm_real pos[LSM_GCODE_N_AXES])
{
    if (!p || !pos)
        return LSM_E_NULL;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        int f = lsm_check_finite(pos[k]);
        if (f != 0)
            return (lsm_status)f;
        lsm_real lim = (lsm_real)LSM_GCODE_MAX_ABS * (k >= LSM_GCODE_A ? GC_DEG2RAD : LSM_R(1.0));
        if (lsm_fabs(pos[k]) > lim)
            return LSM_E_RANGE;
    }
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        p->pos[k] = pos[k];
    return LSM_OK;
}

lsm_status lsm_gcode_feed(lsm_gcode *p, const char *data, size_t len, size_t *used, lsm_gcode_result *res)
{
    if (!p || !used || !res || (!data && len > 0))
        return LSM_E_NULL;
    *res = (lsm_gcode_result){0};
    for (size_t i = 0; i < len; i++) {
        char c = data[i];
        if (c == '\n') {
            *used = i + 1;
            return complete_line(p, res);
        }
        /* one byte of slack holds the '\r' of a "\r\n" after a full-length line */
        if (p->len < LSM_GCODE_MAX_LINE + 1)
            p->buf[p->len++] = c;
        else
            p->overflow = true;
        p->pending = true;
    }
    *used = len;
    res->modal = p->modal;
    res->end_of_program = p->ended;
    return LSM_OK;
}

lsm_status lsm_gcode_finish(lsm_gcode *p, lsm_gcode_result *res)
{
    if (!p || !res)
        return LSM_E_NULL;
    if (!p->pending) {
        *res = (lsm_gcode_result){0};
        res->modal = p->modal;
        res->end_of_program = p->ended;
        return LSM_OK;
    }
    return complete_line(p, res);
}

lsm_status lsm_gcode_parse_line(lsm_gcode *p, const char *line, size_t len, lsm_gcode_result *res)
{
    if (!p || !res || (!line && len > 0))
        return LSM_E_NULL;
    if (p->pending)
        return LSM_E_STATE;
    const bool was_ended = p->ended;
    result_begin(p, res);
    if (was_ended) {
        mark_ignored(res, line, len);
        return result_end(p, res, LSM_OK);
    }
    if (len > 0 && line[len - 1] == '\n')
        len--;
    if (len > 0 && line[len - 1] == '\r')
        len--;
    if (len > LSM_GCODE_MAX_LINE)
        return result_end(p, res, fail_r(res, LSM_E_GC_LINE_TOO_LONG, LSM_GCODE_MAX_LINE + 1, "line too long"));
    for (size_t i = 0; i < len; i++)
        if (line[i] == '\n')
            return result_end(p, res, fail_r(res, LSM_E_GC_SYNTAX, (uint32_t)i + 1, "line ending inside the line"));
    return result_end(p, res, parse(p, line, (uint32_t)len, res));
}

const lsm_gcode_modal *lsm_gcode_modal_state(const lsm_gcode *p)
{
    return p ? &p->modal : NULL;
}

const lsm_real *lsm_gcode_position(const lsm_gcode *p)
{
    return p ? p->pos : NULL;
}

/* Default reason of each error code (a stage may give a more precise one). */
static const char *default_reason(lsm_status code)
{
    switch (code) {
    case LSM_E_GC_UNKNOWN_WORD: return "unknown word";
    case LSM_E_GC_MISSING_ARG: return "word without a number";
    case LSM_E_GC_SYNTAX: return "syntax error at";
    case LSM_E_GC_NUMBER_RANGE: return "number too large";
    case LSM_E_GC_LINE_TOO_LONG: return "line too long";
    case LSM_E_GC_BINARY: return "binary or non-printable byte";
    case LSM_E_GC_WORD_REPEATED: return "word repeated on one line";
    case LSM_E_GC_MODAL_CONFLICT: return "two words of one modal group";
    case LSM_E_GC_NO_FEED: return "feed move with no feed (F) before";
    case LSM_E_GC_ARC_MISMATCH: return "arc start and end radii differ";
    case LSM_E_GC_ARC_RADIUS: return "bad arc radius";
    case LSM_E_GC_ARC_CENTRE: return "arc centre on its start or end point";
    case LSM_E_GC_ARC_FORM: return "arc words incomplete or inconsistent";
    case LSM_E_GC_UNUSED_WORD: return "word not used by any command";
    case LSM_E_GC_UNSUPPORTED: return "unsupported";
    case LSM_E_GC_COMMENT: return "bad comment";
    case LSM_E_GC_BAD_VALUE: return "value out of range";
    case LSM_E_GC_NO_AXIS: return "the machine has no such axis";
    default: return "error";
    }
}

static size_t append_text(char *buf, size_t at, size_t n, const char *t)
{
    while (*t && at + 1 < n)
        buf[at++] = *t++;
    buf[at] = '\0';
    return at;
}

const char *lsm_gcode_error_text(const lsm_gcode_error *e, char *buf, size_t n)
{
    if (!buf || n == 0)
        return buf;
    buf[0] = '\0';
    if (!e)
        return buf;
    size_t at = append_text(buf, 0, n, e->reason ? e->reason : default_reason(e->code));
    if (e->code == LSM_E_GC_LINE_TOO_LONG) {
        at = append_text(buf, at, n, " (more than ");
        char num[12];
        unsigned v = LSM_GCODE_MAX_LINE, k = sizeof num - 1;
        num[k] = '\0';
        do {
            num[--k] = (char)('0' + v % 10u);
            v /= 10u;
        } while (v && k);
        at = append_text(buf, at, n, num + k);
        append_text(buf, at, n, " bytes)");
        return buf;
    }
    if (e->word[0] == '\0')
        return buf;
    const bool paren = e->code == LSM_E_GC_UNSUPPORTED;
    at = append_text(buf, at, n, paren ? " (" : " '");
    at = append_text(buf, at, n, e->word);
    append_text(buf, at, n, paren ? ")" : "'");
    return buf;
}

const char *lsm_gcode_event_name(lsm_gcode_event_kind kind)
{
    switch (kind) {
    case LSM_GCODE_EV_SPINDLE_SPEED: return "spindle_speed";
    case LSM_GCODE_EV_TOOL_SELECT: return "tool_select";
    case LSM_GCODE_EV_TOOL_CHANGE: return "tool_change";
    case LSM_GCODE_EV_SPINDLE_CW: return "spindle_cw";
    case LSM_GCODE_EV_SPINDLE_CCW: return "spindle_ccw";
    case LSM_GCODE_EV_SPINDLE_STOP: return "spindle_stop";
    case LSM_GCODE_EV_COOLANT_MIST: return "coolant_mist";
    case LSM_GCODE_EV_COOLANT_FLOOD: return "coolant_flood";
    case LSM_GCODE_EV_COOLANT_OFF: return "coolant_off";
    case LSM_GCODE_EV_DWELL: return "dwell";
    case LSM_GCODE_EV_TOOL_LENGTH: return "tool_length_offset";
    case LSM_GCODE_EV_TOOL_LENGTH_OFF: return "tool_length_offset_cancel";
    case LSM_GCODE_EV_PAUSE: return "pause";
    case LSM_GCODE_EV_OPTIONAL_PAUSE: return "optional_pause";
    case LSM_GCODE_EV_END: return "end";
    default: return "?";
    }
}

const char *lsm_gcode_event_code(lsm_gcode_event_kind kind)
{
    switch (kind) {
    case LSM_GCODE_EV_SPINDLE_SPEED: return "S";
    case LSM_GCODE_EV_TOOL_SELECT: return "T";
    case LSM_GCODE_EV_TOOL_CHANGE: return "M6";
    case LSM_GCODE_EV_SPINDLE_CW: return "M3";
    case LSM_GCODE_EV_SPINDLE_CCW: return "M4";
    case LSM_GCODE_EV_SPINDLE_STOP: return "M5";
    case LSM_GCODE_EV_COOLANT_MIST: return "M7";
    case LSM_GCODE_EV_COOLANT_FLOOD: return "M8";
    case LSM_GCODE_EV_COOLANT_OFF: return "M9";
    case LSM_GCODE_EV_DWELL: return "G4";
    case LSM_GCODE_EV_TOOL_LENGTH: return "G43";
    case LSM_GCODE_EV_TOOL_LENGTH_OFF: return "G49";
    case LSM_GCODE_EV_PAUSE: return "M0";
    case LSM_GCODE_EV_OPTIONAL_PAUSE: return "M1";
    case LSM_GCODE_EV_END: return "M2";
    default: return "?";
    }
}
