/*
 * gcode.c: streaming RS274/NGC subset parser (see gcode.h for the dialect, units and rules).
 *
 * Each line goes through three steps, all on the stack:
 *   1. a byte check (control bytes anywhere, non-ASCII outside comments -> LSM_E_GC_BINARY);
 *   2. a scan into a word table (one slot per letter, one per modal group), which reports the
 *      lexical errors left to right;
 *   3. execution on a copy of the modal state, in RS274/NGC order (F, units, plane, distance,
 *      path control, motion, stop), committed only if the whole line succeeds.
 */
#include "gcode.h"

#include "lsm_math.h"

#define GC_PI ((lsm_real)LSM_PI)
#define GC_DEG2RAD ((lsm_real)(LSM_PI / 180.0))
#define GC_MM_PER_INCH LSM_R(25.4)
#define GC_MAX_SIG_DIGITS 18

/* Modal groups of the G words on one line (LinuxCNC's groups; G53 is in the non-modal group 0). */
enum {
    GRP_MOTION = 0, /* G0 G1 G2 G3 G80 */
    GRP_PLANE,      /* G17 G18 G19 */
    GRP_DISTANCE,   /* G90 G91 */
    GRP_ARCDIST,    /* G90.1 G91.1 */
    GRP_UNITS,      /* G20 G21 */
    GRP_PATH,       /* G61 G64 */
    GRP_FEEDMODE,   /* G94 (no effect) */
    GRP_COMP,       /* G40 (no effect) */
    GRP_TOOL_LEN,   /* G43 G49 */
    GRP_WCS,        /* G54 .. G59 */
    GRP_NONMODAL,   /* G4 G10 G28 G28.1 G30 G30.1 G53 G92 G92.1 G92.2 */
    GRP_COUNT
};

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

/* A parsed number: value plus its exact decimal form (for G/M/N/P integer checks). */
typedef struct {
    uint64_t mant;
    uint8_t frac; /* digits after the point that were kept */
    bool neg;
    lsm_real value;
} gc_num;

#define LETTER(c) ((c) - 'A')
#define BIT(c) (1u << LETTER(c))
#define AXIS_BITS (BIT('X') | BIT('Y') | BIT('Z') | BIT('A') | BIT('B') | BIT('C'))
#define ARC_BITS (BIT('I') | BIT('J') | BIT('K') | BIT('R'))
#define KNOWN_BITS                                                                                                  \
    (BIT('G') | BIT('M') | BIT('N') | BIT('F') | AXIS_BITS | ARC_BITS | BIT('P') | BIT('S') | BIT('T') | BIT('H') | \
     BIT('L'))

/* M words of a line, by LinuxCNC modal group. */
enum { MG_STOP = 0, MG_TOOL, MG_SPINDLE, MG_MIST, MG_FLOOD, MG_COOL_OFF, MG_COUNT };

typedef struct {
    uint32_t seen; /* bit per letter A..Z (G and M excluded) */
    uint32_t n_words;
    lsm_real val[26];
    uint32_t col[26];
    gc_num pnum, lnum; /* P and L as parsed (integer checks) */
    int16_t g[GRP_COUNT];
    uint32_t gcol[GRP_COUNT];
    int16_t m[MG_COUNT]; /* M number times ten, or -1 */
    uint32_t mcol[MG_COUNT];
} gc_words;

static const char k_axis_letters[LSM_GCODE_N_AXES] = {'X', 'Y', 'Z', 'A', 'B', 'C'};

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

static lsm_status fail_r(lsm_gcode_result *res, lsm_status code, uint32_t col, const char *reason)
{
    res->status = code;
    res->err.code = code;
    res->err.line = res->line;
    res->err.column = col;
    res->err.reason = reason;
    return code;
}

static lsm_status fail(lsm_gcode_result *res, lsm_status code, uint32_t col)
{
    return fail_r(res, code, col, NULL);
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

/* True if the number is a non-negative integer; *out gets it. */
static bool as_uint(const gc_num *x, uint32_t *out)
{
    if (x->neg && x->mant != 0)
        return false;
    uint64_t m = x->mant;
    for (unsigned k = 0; k < x->frac; k++) {
        if (m % 10u != 0)
            return false;
        m /= 10u;
    }
    if (m > 0xFFFFFFFFu)
        return false;
    *out = (uint32_t)m;
    return true;
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

/* Smallest column among the letters in `mask` that are present (0 if none). */
static uint32_t first_col(const gc_words *w, uint32_t mask)
{
    uint32_t best = 0;
    for (int k = 0; k < 26; k++) {
        if ((w->seen & mask & (1u << k)) && (best == 0 || w->col[k] < best))
            best = w->col[k];
    }
    return best;
}

static lsm_real hypot_r(lsm_real a, lsm_real b)
{
    return lsm_sqrt(a * a + b * b);
}

/* Arc geometry in the plane (u, v) with normal w. */
static lsm_status make_arc(const gc_words *w, const lsm_gcode_modal *m, const lsm_real s[LSM_GCODE_N_AXES],
                           const lsm_real e[LSM_GCODE_N_AXES], const lsm_real off[LSM_GCODE_N_AXES], lsm_real lin,
                           uint32_t turns, uint32_t mcol, lsm_gcode_block *b, lsm_gcode_result *res)
{
    int iu, iv, iw;
    char lu, lv, lbad; /* offset letters along u and v, and the one that is not allowed */
    switch (m->plane) {
    case LSM_GCODE_PLANE_ZX:
        iu = LSM_GCODE_Z;
        iv = LSM_GCODE_X;
        iw = LSM_GCODE_Y;
        lu = 'K';
        lv = 'I';
        lbad = 'J';
        break;
    case LSM_GCODE_PLANE_YZ:
        iu = LSM_GCODE_Y;
        iv = LSM_GCODE_Z;
        iw = LSM_GCODE_X;
        lu = 'J';
        lv = 'K';
        lbad = 'I';
        break;
    case LSM_GCODE_PLANE_XY:
    default:
        iu = LSM_GCODE_X;
        iv = LSM_GCODE_Y;
        iw = LSM_GCODE_Z;
        lu = 'I';
        lv = 'J';
        lbad = 'K';
        break;
    }
    const int dir = m->motion == LSM_GCODE_MOTION_CCW ? 1 : -1;
    const bool has_r = (w->seen & BIT('R')) != 0;
    const uint32_t ijk = w->seen & (BIT('I') | BIT('J') | BIT('K'));

    /* form (LinuxCNC: end words are optional in the centre form, whose end = start is a full circle) */
    if (!has_r && !ijk)
        return fail_r(res, LSM_E_GC_ARC_FORM, mcol, "arc needs I J K (centre) or R (radius)");
    if (has_r && ijk) {
        uint32_t cr = w->col[LETTER('R')], ci = first_col(w, ijk);
        return fail_r(res, LSM_E_GC_ARC_FORM, cr > ci ? cr : ci, "arc with both R and I J K");
    }
    if (has_r && !(w->seen & (BIT(k_axis_letters[iu]) | BIT(k_axis_letters[iv]))))
        return fail_r(res, LSM_E_GC_ARC_FORM, mcol, "radius-form arc without an end word in its plane");
    if (ijk & BIT(lbad))
        return fail_r(res, LSM_E_GC_ARC_FORM, w->col[LETTER(lbad)], "centre offset off the arc's plane");
    if (m->feed_mm_s <= 0)
        return fail_r(res, LSM_E_GC_NO_FEED, mcol, "feed move with no feed (F) before");

    /* same-point threshold: a few ulps of the coordinates */
    const lsm_real scale = LSM_R(1.0) + lsm_fabs(s[iu]) + lsm_fabs(s[iv]);
    const lsm_real same_eps = scale * (LSM_REAL_IS_FLOAT ? (lsm_real)4e-7 : (lsm_real)1e-12);
    const lsm_real du = e[iu] - s[iu], dv = e[iv] - s[iv];
    const lsm_real chord = hypot_r(du, dv);
    const bool same = chord <= same_eps;
    const lsm_real rtol = (lsm_real)LSM_GCODE_ARC_RADIUS_TOL_MM;
    lsm_real cu, cv;

    if (has_r) {
        const lsm_real r = w->val[LETTER('R')] * lin;
        const lsm_real ar = lsm_fabs(r);
        const uint32_t rcol = w->col[LETTER('R')];
        if (same)
            return fail_r(res, LSM_E_GC_ARC_RADIUS, rcol, "radius-form arc ending on its start");
        if (ar < rtol)
            return fail_r(res, LSM_E_GC_ARC_RADIUS, rcol, "arc radius too small");
        lsm_real half = chord * LSM_R(0.5);
        if (half - ar > rtol)
            return fail_r(res, LSM_E_GC_ARC_RADIUS, rcol, "arc radius shorter than half the chord");
        lsm_real h2 = ar * ar - half * half;
        lsm_real h = h2 > 0 ? lsm_sqrt(h2) : LSM_R(0.0);
        /* the centre is left of the chord for a counter-clockwise arc of at most 180 degrees */
        lsm_real side = (lsm_real)(dir * (r > 0 ? 1 : -1));
        cu = s[iu] + LSM_R(0.5) * du + side * h * (-dv / chord);
        cv = s[iv] + LSM_R(0.5) * dv + side * h * (du / chord);
    } else {
        lsm_real ou = (w->seen & BIT(lu)) ? w->val[LETTER(lu)] * lin : LSM_R(0.0);
        lsm_real ov = (w->seen & BIT(lv)) ? w->val[LETTER(lv)] * lin : LSM_R(0.0);
        if (m->arc_absolute) { /* G90.1: program coordinates of the centre (a missing one: the start's) */
            cu = (w->seen & BIT(lu)) ? ou + off[iu] : s[iu];
            cv = (w->seen & BIT(lv)) ? ov + off[iv] : s[iv];
        } else {
            cu = s[iu] + ou;
            cv = s[iv] + ov;
        }
        lsm_real r1 = hypot_r(s[iu] - cu, s[iv] - cv);
        lsm_real r2 = hypot_r(e[iu] - cu, e[iv] - cv);
        if (r1 < rtol || r2 < rtol)
            return fail_r(res, LSM_E_GC_ARC_CENTRE, first_col(w, ijk), "arc centre on its start or end point");
        lsm_real err = lsm_fabs(r1 - r2);
        lsm_real rmax = r1 > r2 ? r1 : r2;
        if (err > (lsm_real)LSM_GCODE_ARC_ABS_TOL_MM || err > (lsm_real)LSM_GCODE_ARC_REL_TOL * rmax)
            return fail_r(res, LSM_E_GC_ARC_MISMATCH, mcol, "arc start and end radii differ");
    }

    lsm_real ts = lsm_atan2(s[iv] - cv, s[iu] - cu);
    lsm_real te = lsm_atan2(e[iv] - cv, e[iu] - cu);
    lsm_real d = dir > 0 ? te - ts : ts - te;
    if (same) {
        d = 2 * GC_PI;
    } else {
        while (d <= 0)
            d += 2 * GC_PI;
        while (d > 2 * GC_PI)
            d -= 2 * GC_PI;
    }
    b->type = LSM_GCODE_BLOCK_ARC;
    b->plane = m->plane;
    b->dir = (int8_t)dir;
    b->turns = turns - 1u;
    b->centre[iu] = cu;
    b->centre[iv] = cv;
    b->centre[iw] = s[iw];
    b->radius_mm = hypot_r(s[iu] - cu, s[iv] - cv);
    b->radius_end_mm = hypot_r(e[iu] - cu, e[iv] - cv);
    b->angle_rad = d + 2 * GC_PI * (lsm_real)(turns - 1u);
    b->helix_mm = e[iw] - s[iw];
    return LSM_OK;
}

/* Step 3: execute the word table on a copy of the state, in LinuxCNC's order of execution; commit on
 * success. */

/* Offsets that a line may change (committed with the modal state). */
typedef struct {
    lsm_real wcs[LSM_GCODE_N_WCS][LSM_GCODE_N_AXES];
    lsm_real g92[LSM_GCODE_N_AXES];
    lsm_real home[2][LSM_GCODE_N_AXES];
} gc_offsets;

typedef struct {
    lsm_gcode_modal m;
    gc_offsets o;
    lsm_real lin;                   /* mm per G-code length unit on this line */
    lsm_real end[LSM_GCODE_N_AXES]; /* where the line's motion ends (machine coordinates) */
} gc_exec;

static void push_event(lsm_gcode_result *res, lsm_gcode_event_kind kind, bool stop, int32_t tool, lsm_real value)
{
    if (res->n_events >= LSM_GCODE_MAX_EVENTS)
        return; /* cannot happen: a line has at most 11 (see LSM_GCODE_MAX_EVENTS) */
    lsm_gcode_event *e = &res->events[res->n_events++];
    e->kind = kind;
    e->line = res->line;
    e->at_block = res->n_blocks;
    e->exact_stop = stop;
    e->tool = tool;
    e->value = value;
}

/* Offset from program to machine coordinates of axis k (work offset in use plus G92). */
static lsm_real offset_of(const gc_exec *x, int k)
{
    return x->o.wcs[x->m.wcs - 1][k] + x->o.g92[k];
}

/* The value of axis word k in mm (X Y Z) or rad (A B C). */
static lsm_real axis_value(const gc_words *w, const gc_exec *x, int k)
{
    return w->val[LETTER(k_axis_letters[k])] * (k >= LSM_GCODE_A ? GC_DEG2RAD : x->lin);
}

/* Units, F and S, then the machine functions before the motion: S, T, M6, M3-M5, M7-M9, G4. */
static lsm_status exec_functions(const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    lsm_gcode_modal *m = &x->m;
    /* units first: every number on the line is read in the line's final units */
    if (w->g[GRP_UNITS] >= 0)
        m->units = w->g[GRP_UNITS] == 200 ? LSM_GCODE_UNITS_INCH : LSM_GCODE_UNITS_MM;
    x->lin = m->units == LSM_GCODE_UNITS_INCH ? GC_MM_PER_INCH : LSM_R(1.0);
    if (w->seen & BIT('F')) {
        lsm_real f = w->val[LETTER('F')];
        m->feed_mm_s = f * x->lin / LSM_R(60.0);
        m->feed_rot_rad_s = f / LSM_R(60.0) * GC_DEG2RAD;
    }
    if (w->seen & BIT('S')) {
        m->speed_rpm = w->val[LETTER('S')];
        push_event(res, LSM_GCODE_EV_SPINDLE_SPEED, true, 0, m->speed_rpm);
    }
    if (w->seen & BIT('T')) {
        m->tool_selected = (int32_t)w->val[LETTER('T')];
        push_event(res, LSM_GCODE_EV_TOOL_SELECT, false, m->tool_selected, 0);
    }
    if (w->m[MG_TOOL] >= 0) {
        m->tool_loaded = m->tool_selected >= 0 ? m->tool_selected : 0;
        push_event(res, LSM_GCODE_EV_TOOL_CHANGE, true, m->tool_loaded, 0);
    }
    if (w->m[MG_SPINDLE] >= 0) {
        const int16_t c = w->m[MG_SPINDLE];
        m->spindle = (uint8_t)(c / 10);
        push_event(res,
                   c == 30   ? LSM_GCODE_EV_SPINDLE_CW
                   : c == 40 ? LSM_GCODE_EV_SPINDLE_CCW
                             : LSM_GCODE_EV_SPINDLE_STOP,
                   true, 0, c == 50 ? LSM_R(0.0) : m->speed_rpm);
    }
    if (w->m[MG_MIST] >= 0) {
        m->mist = true;
        push_event(res, LSM_GCODE_EV_COOLANT_MIST, true, 0, 0);
    }
    if (w->m[MG_FLOOD] >= 0) {
        m->flood = true;
        push_event(res, LSM_GCODE_EV_COOLANT_FLOOD, true, 0, 0);
    }
    if (w->m[MG_COOL_OFF] >= 0) {
        m->mist = m->flood = false;
        push_event(res, LSM_GCODE_EV_COOLANT_OFF, true, 0, 0);
    }
    if (w->g[GRP_NONMODAL] == 40) {
        if (!(w->seen & BIT('P')))
            return fail_r(res, LSM_E_GC_MISSING_ARG, w->gcol[GRP_NONMODAL], "G4 needs P (seconds)");
        const lsm_real t = w->val[LETTER('P')];
        if (t < 0)
            return fail_r(res, LSM_E_GC_BAD_VALUE, w->col[LETTER('P')], "negative dwell");
        push_event(res, LSM_GCODE_EV_DWELL, true, 0, t);
    }
    return LSM_OK;
}

/* Plane, distance modes, tool length offset, work offset selection, path control and motion mode. */
static lsm_status exec_modes(const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    lsm_gcode_modal *m = &x->m;
    if (w->g[GRP_PLANE] >= 0)
        m->plane = (lsm_gcode_plane)(w->g[GRP_PLANE] / 10);
    if (w->g[GRP_DISTANCE] >= 0)
        m->distance = w->g[GRP_DISTANCE] == 900 ? LSM_GCODE_ABSOLUTE : LSM_GCODE_INCREMENTAL;
    if (w->g[GRP_ARCDIST] >= 0)
        m->arc_absolute = w->g[GRP_ARCDIST] == 901;
    if (w->g[GRP_TOOL_LEN] == 430) {
        m->tool_length_on = true;
        m->tool_length_h = (w->seen & BIT('H')) ? (int32_t)w->val[LETTER('H')] : m->tool_loaded;
        push_event(res, LSM_GCODE_EV_TOOL_LENGTH, false, m->tool_length_h, 0);
    } else if (w->g[GRP_TOOL_LEN] == 490) {
        m->tool_length_on = false;
        m->tool_length_h = -1;
        push_event(res, LSM_GCODE_EV_TOOL_LENGTH_OFF, false, 0, 0);
    }
    if ((w->seen & BIT('H')) && w->g[GRP_TOOL_LEN] != 430)
        return fail_r(res, LSM_E_GC_UNUSED_WORD, w->col[LETTER('H')], "H without G43");
    if (w->g[GRP_WCS] >= 0)
        m->wcs = (uint8_t)((w->g[GRP_WCS] - 530) / 10);
    if (w->g[GRP_PATH] == 610) {
        m->blend = LSM_GCODE_EXACT_STOP;
        m->blend_tol_mm = 0;
    }
    if (w->g[GRP_MOTION] >= 0) {
        switch (w->g[GRP_MOTION]) {
        case 0: m->motion = LSM_GCODE_MOTION_RAPID; break;
        case 10: m->motion = LSM_GCODE_MOTION_LINEAR; break;
        case 20: m->motion = LSM_GCODE_MOTION_CW; break;
        case 30: m->motion = LSM_GCODE_MOTION_CCW; break;
        default: m->motion = LSM_GCODE_MOTION_NONE; break;
        }
    }
    return LSM_OK;
}

/* Who uses P on this line: G4, G10, G64 or an arc's turns; more than one is an error. */
static lsm_status exec_p(const gc_words *w, gc_exec *x, bool arc_cmd, uint32_t *turns, lsm_gcode_result *res)
{
    const bool g64 = w->g[GRP_PATH] == 640;
    const int16_t nm = w->g[GRP_NONMODAL];
    const uint32_t pcol = w->col[LETTER('P')];
    *turns = 1;
    if (w->seen & BIT('P')) {
        if (g64 && arc_cmd)
            return fail_r(res, LSM_E_GC_ARC_FORM, pcol, "P of both G64 and an arc");
        const int users = (int)g64 + (int)arc_cmd + (int)(nm == 40) + (int)(nm == 100);
        if (users == 0)
            return fail_r(res, LSM_E_GC_UNUSED_WORD, pcol, "P without G4, G10, G64 or an arc");
        if (users > 1)
            return fail_r(res, LSM_E_GC_MODAL_CONFLICT, pcol, "P used by two commands");
        if (arc_cmd) {
            if (!as_uint(&w->pnum, turns) || *turns < 1 || *turns > LSM_GCODE_MAX_TURNS)
                return fail_r(res, LSM_E_GC_BAD_VALUE, pcol, "arc turns P must be an integer 1..1000");
        } else if (g64 && w->val[LETTER('P')] < 0) {
            return fail_r(res, LSM_E_GC_BAD_VALUE, pcol, "negative blend tolerance");
        }
    }
    if (g64) {
        x->m.blend = LSM_GCODE_BLEND;
        x->m.blend_tol_mm = (w->seen & BIT('P')) ? w->val[LETTER('P')] * x->lin : LSM_R(0.0);
    }
    return LSM_OK;
}

/* G10 L2 / L20: set the origin of work offset P (0: the one in use). Values are absolute machine
 * coordinates (L2) or make the current point have these coordinates (L20), in G90 and G91 alike. */
static lsm_status exec_g10(const lsm_gcode *p, const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    const uint32_t col = w->gcol[GRP_NONMODAL];
    uint32_t l = 0, sys = 0;
    if (!(w->seen & BIT('L')))
        return fail_r(res, LSM_E_GC_MISSING_ARG, col, "G10 needs L2 or L20");
    if (!as_uint(&w->lnum, &l) || (l != 2 && l != 20)) {
        const bool tool = l == 1 || l == 10 || l == 11;
        return fail_r(res, tool ? LSM_E_GC_UNSUPPORTED : LSM_E_GC_BAD_VALUE, w->col[LETTER('L')],
                      tool ? "unsupported: tool table (G10 L1/L10/L11)" : "G10 needs L2 or L20");
    }
    if (!(w->seen & BIT('P')))
        return fail_r(res, LSM_E_GC_MISSING_ARG, col, "G10 needs P (coordinate system 0..6)");
    if (!as_uint(&w->pnum, &sys) || sys > 9)
        return fail_r(res, LSM_E_GC_BAD_VALUE, w->col[LETTER('P')], "coordinate system P must be 0..9");
    if (sys > LSM_GCODE_N_WCS)
        return fail_r(res, LSM_E_GC_UNSUPPORTED, w->col[LETTER('P')], "unsupported: coordinate systems G59.1-G59.3");
    if (w->seen & BIT('R'))
        return fail_r(res, LSM_E_GC_UNSUPPORTED, w->col[LETTER('R')], "unsupported: coordinate system rotation (R)");
    const unsigned idx = sys == 0 ? (unsigned)x->m.wcs - 1u : sys - 1u;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        if (!(w->seen & BIT(k_axis_letters[k])))
            continue;
        const lsm_real v = axis_value(w, x, k);
        x->o.wcs[idx][k] = l == 2 ? v : p->pos[k] - x->o.g92[k] - v;
    }
    return LSM_OK;
}

/* G92 (the current point gets the given coordinates), G92.1 / G92.2 (offsets cleared). */
static lsm_status exec_g92(const lsm_gcode *p, const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    if (w->g[GRP_NONMODAL] != 920) {
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            x->o.g92[k] = 0;
        return LSM_OK;
    }
    if (!(w->seen & AXIS_BITS))
        return fail_r(res, LSM_E_GC_MISSING_ARG, w->gcol[GRP_NONMODAL], "G92 needs at least one axis word");
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        if (w->seen & BIT(k_axis_letters[k]))
            x->o.g92[k] = p->pos[k] - x->o.wcs[x->m.wcs - 1][k] - axis_value(w, x, k);
    return LSM_OK;
}

/* End point of the axis words as a move (G0-G3, G28/G30 intermediate point); G53: machine coordinates. */
static lsm_status exec_end(const lsm_gcode *p, const gc_words *w, gc_exec *x, bool g53, lsm_gcode_result *res)
{
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        char L = k_axis_letters[k];
        x->end[k] = p->pos[k];
        if (!(w->seen & BIT(L)))
            continue;
        const bool rotary = k >= LSM_GCODE_A;
        const lsm_real v = axis_value(w, x, k);
        if (x->m.distance == LSM_GCODE_INCREMENTAL) {
            x->end[k] = p->pos[k] + v;
        } else {
            const lsm_real off = g53 ? LSM_R(0.0) : offset_of(x, k);
            x->end[k] = off != 0 ? v + off : v;
        }
        lsm_real lim = (lsm_real)LSM_GCODE_MAX_ABS * (rotary ? GC_DEG2RAD : LSM_R(1.0));
        if (lsm_fabs(x->end[k]) > lim)
            return fail_r(res, LSM_E_GC_NUMBER_RANGE, w->col[LETTER(L)], "coordinate out of range");
    }
    return LSM_OK;
}

/* Appends a straight block from `from` to `to` unless they are equal. */
static void emit_line(lsm_gcode_result *res, lsm_gcode_block_type type, const lsm_real from[LSM_GCODE_N_AXES],
                      const lsm_real to[LSM_GCODE_N_AXES], const lsm_gcode_modal *m)
{
    bool moves = false;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        if (to[k] != from[k])
            moves = true;
    if (!moves || res->n_blocks >= LSM_GCODE_MAX_BLOCKS)
        return;
    lsm_gcode_block b = {0};
    b.type = type;
    b.line = res->line;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        b.start[k] = from[k];
        b.end[k] = to[k];
    }
    if (type != LSM_GCODE_BLOCK_RAPID) {
        b.feed_mm_s = m->feed_mm_s;
        b.feed_rot_rad_s = m->feed_rot_rad_s;
    }
    res->blocks[res->n_blocks++] = b;
}

/* G28 / G30: rapid to the intermediate point of the axis words, then the given axes (all without
 * axis words) rapid to the stored position. */
static void exec_home(const lsm_gcode *p, const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    const lsm_real *home = x->o.home[w->g[GRP_NONMODAL] == 300 ? 1 : 0];
    const bool any = (w->seen & AXIS_BITS) != 0;
    lsm_real fin[LSM_GCODE_N_AXES];
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        const bool present = (p->opt.axis_mask & (1u << k)) != 0;
        fin[k] = present && (!any || (w->seen & BIT(k_axis_letters[k]))) ? home[k] : x->end[k];
    }
    emit_line(res, LSM_GCODE_BLOCK_RAPID, p->pos, x->end, &x->m);
    emit_line(res, LSM_GCODE_BLOCK_RAPID, x->end, fin, &x->m);
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        x->end[k] = fin[k];
}

/* Non-modal commands that use axis words, and G28.1 / G30.1. Returns through *moved whether the line's axis
 * words were consumed. */
static lsm_status exec_nonmodal(const lsm_gcode *p, const gc_words *w, gc_exec *x, bool *used_axes,
                                lsm_gcode_result *res)
{
    const int16_t nm = w->g[GRP_NONMODAL];
    const bool has_axis = (w->seen & AXIS_BITS) != 0;
    *used_axes = nm == 100 || nm == 280 || nm == 300 || nm == 920;
    if (*used_axes && has_axis && w->g[GRP_MOTION] >= 0 && w->g[GRP_MOTION] != 800)
        return fail_r(res, LSM_E_GC_MODAL_CONFLICT, w->gcol[GRP_MOTION], "two commands use the axis words");
    if ((w->seen & BIT('L')) && nm != 100)
        return fail_r(res, LSM_E_GC_UNUSED_WORD, w->col[LETTER('L')], "L without G10");
    if ((nm == 281 || nm == 301 || nm == 921 || nm == 922) && has_axis)
        return fail_r(res, LSM_E_GC_UNUSED_WORD, first_col(w, AXIS_BITS), "axis words with G28.1, G30.1 or G92.1");
    switch (nm) {
    case 100: return exec_g10(p, w, x, res);
    case 920:
    case 921:
    case 922: return exec_g92(p, w, x, res);
    case 281:
    case 301:
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            x->o.home[nm == 301 ? 1 : 0][k] = p->pos[k];
        return LSM_OK;
    case 280:
    case 300: {
        lsm_status st = exec_end(p, w, x, false, res);
        if (st != LSM_OK)
            return st;
        exec_home(p, w, x, res);
        return LSM_OK;
    }
    default: return LSM_OK;
    }
}

/* The motion of the line (G0-G3 with the modal motion mode). */
static lsm_status exec_motion(const lsm_gcode *p, const gc_words *w, gc_exec *x, uint32_t turns, lsm_gcode_result *res)
{
    const lsm_gcode_modal *m = &x->m;
    const bool explicit_motion = w->g[GRP_MOTION] >= 0;
    const bool has_axis = (w->seen & AXIS_BITS) != 0;
    const bool is_arc_mode = m->motion == LSM_GCODE_MOTION_CW || m->motion == LSM_GCODE_MOTION_CCW;
    const bool g53 = w->g[GRP_NONMODAL] == 530;
    const uint32_t mcol = explicit_motion ? w->gcol[GRP_MOTION] : first_col(w, AXIS_BITS);
    if (g53 && (is_arc_mode || m->motion == LSM_GCODE_MOTION_NONE))
        return fail_r(res, LSM_E_GC_UNUSED_WORD, w->gcol[GRP_NONMODAL], "G53 needs G0 or G1");
    if (g53 && m->distance == LSM_GCODE_INCREMENTAL)
        return fail_r(res, LSM_E_GC_BAD_VALUE, w->gcol[GRP_NONMODAL], "G53 in incremental mode (G91)");
    lsm_status st = exec_end(p, w, x, g53, res);
    if (st != LSM_OK)
        return st;
    if (is_arc_mode && (explicit_motion || has_axis)) {
        lsm_gcode_block b = {0};
        lsm_real off[LSM_GCODE_N_AXES];
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            off[k] = offset_of(x, k);
        st = make_arc(w, m, p->pos, x->end, off, x->lin, turns, mcol, &b, res);
        if (st != LSM_OK)
            return st;
        b.line = res->line;
        for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
            b.start[k] = p->pos[k];
            b.end[k] = x->end[k];
        }
        b.feed_mm_s = m->feed_mm_s;
        b.feed_rot_rad_s = m->feed_rot_rad_s;
        res->blocks[res->n_blocks++] = b;
    } else if ((m->motion == LSM_GCODE_MOTION_RAPID || m->motion == LSM_GCODE_MOTION_LINEAR) && has_axis) {
        if (m->motion == LSM_GCODE_MOTION_LINEAR && m->feed_mm_s <= 0)
            return fail_r(res, LSM_E_GC_NO_FEED, mcol, "feed move with no feed (F) before");
        emit_line(res, m->motion == LSM_GCODE_MOTION_RAPID ? LSM_GCODE_BLOCK_RAPID : LSM_GCODE_BLOCK_LINEAR, p->pos,
                  x->end, m);
    }
    return LSM_OK;
}

/* After the motion: M0 / M1, M2 / M30 (which also stop the spindle and the coolant, as in LinuxCNC). */
static void exec_stop(const lsm_gcode *p, const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    const int16_t c = w->m[MG_STOP];
    if (c == 0)
        push_event(res, LSM_GCODE_EV_PAUSE, true, 0, 0);
    else if (c == 10 && p->opt.optional_stop)
        push_event(res, LSM_GCODE_EV_OPTIONAL_PAUSE, true, 0, 0);
    else if (c == 20 || c == 300) {
        if (x->m.spindle != 5)
            push_event(res, LSM_GCODE_EV_SPINDLE_STOP, true, 0, 0);
        if (x->m.mist || x->m.flood)
            push_event(res, LSM_GCODE_EV_COOLANT_OFF, true, 0, 0);
        x->m.spindle = 5;
        x->m.mist = x->m.flood = false;
        push_event(res, LSM_GCODE_EV_END, true, c / 10, 0);
    }
}

static lsm_status execute(lsm_gcode *p, const gc_words *w, lsm_gcode_result *res)
{
    gc_exec x;
    x.m = p->modal;
    for (int s = 0; s < LSM_GCODE_N_WCS; s++)
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            x.o.wcs[s][k] = p->wcs[s][k];
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        x.o.g92[k] = p->g92[k];
        x.o.home[0][k] = p->home[0][k];
        x.o.home[1][k] = p->home[1][k];
        x.end[k] = p->pos[k];
    }
    lsm_status st = exec_functions(w, &x, res);
    if (st == LSM_OK)
        st = exec_modes(w, &x, res);
    if (st != LSM_OK)
        return st;
    const bool has_axis = (w->seen & AXIS_BITS) != 0;
    const int16_t nm = w->g[GRP_NONMODAL];
    const bool nm_axes = nm == 100 || nm == 280 || nm == 300 || nm == 920;
    const bool is_arc_mode = x.m.motion == LSM_GCODE_MOTION_CW || x.m.motion == LSM_GCODE_MOTION_CCW;
    const bool arc_cmd = !nm_axes && is_arc_mode && (w->g[GRP_MOTION] >= 0 || has_axis);
    if (has_axis && !nm_axes && x.m.motion == LSM_GCODE_MOTION_NONE)
        return fail_r(res, LSM_E_GC_UNUSED_WORD, first_col(w, AXIS_BITS), "axis words without a motion mode (G80)");
    if ((w->seen & ARC_BITS) && !arc_cmd) {
        const bool g10_r = nm == 100 && (w->seen & ARC_BITS) == BIT('R');
        if (!g10_r)
            return fail_r(res, LSM_E_GC_UNUSED_WORD, first_col(w, ARC_BITS), "I J K R without G2 or G3");
    }
    uint32_t turns;
    st = exec_p(w, &x, arc_cmd, &turns, res);
    if (st != LSM_OK)
        return st;
    bool used_axes;
    st = exec_nonmodal(p, w, &x, &used_axes, res);
    if (st == LSM_OK && !used_axes)
        st = exec_motion(p, w, &x, turns, res);
    if (st != LSM_OK)
        return st;
    exec_stop(p, w, &x, res);
    res->nonmodal = w->g[GRP_NONMODAL];

    /* commit */
    p->modal = x.m;
    for (int s = 0; s < LSM_GCODE_N_WCS; s++)
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            p->wcs[s][k] = x.o.wcs[s][k];
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        p->g92[k] = x.o.g92[k];
        p->home[0][k] = x.o.home[0][k];
        p->home[1][k] = x.o.home[1][k];
        p->pos[k] = x.end[k];
    }
    if (w->m[MG_STOP] == 20 || w->m[MG_STOP] == 300)
        p->ended = true;
    return LSM_OK;
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
    return execute(p, &w, res);
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
