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

/* Modal groups of the G words on one line. */
enum {
    GRP_MOTION = 0, /* G0 G1 G2 G3 G80 */
    GRP_PLANE,      /* G17 G18 G19 */
    GRP_DISTANCE,   /* G90 G91 */
    GRP_UNITS,      /* G20 G21 */
    GRP_PATH,       /* G61 G64 */
    GRP_FEEDMODE,   /* G94 (no effect) */
    GRP_COMP,       /* G40 (no effect) */
    GRP_TOOL_LEN,   /* G49 (no effect) */
    GRP_WCS,        /* G54 (no effect) */
    GRP_COUNT
};

typedef struct {
    int16_t group;
    int16_t code10; /* G number times ten */
} gc_gdef;

static const gc_gdef k_gcodes[] = {
    {GRP_MOTION, 0},    {GRP_MOTION, 10},   {GRP_MOTION, 20},  {GRP_MOTION, 30},  {GRP_MOTION, 800},
    {GRP_PLANE, 170},   {GRP_PLANE, 180},   {GRP_PLANE, 190},  {GRP_DISTANCE, 900}, {GRP_DISTANCE, 910},
    {GRP_UNITS, 200},   {GRP_UNITS, 210},   {GRP_PATH, 610},   {GRP_PATH, 640},   {GRP_FEEDMODE, 940},
    {GRP_COMP, 400},    {GRP_TOOL_LEN, 490}, {GRP_WCS, 540},
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

typedef struct {
    uint32_t seen; /* bit per letter A..Z (G and M excluded) */
    uint32_t n_words;
    lsm_real val[26];
    uint32_t col[26];
    gc_num pnum; /* P as parsed (integer check for turns) */
    gc_num nnum; /* N as parsed */
    int16_t g[GRP_COUNT];
    uint32_t gcol[GRP_COUNT];
    int16_t m_stop; /* 20 or 300, or -1 */
    uint32_t mcol;
} gc_words;

static const char k_axis_letters[LSM_GCODE_N_AXES] = {'X', 'Y', 'Z', 'A', 'B', 'C'};

static lsm_real pow10_r(unsigned k)
{
    static const lsm_real k_pow10[GC_MAX_SIG_DIGITS + 1] = {
        LSM_R(1e0),  LSM_R(1e1),  LSM_R(1e2),  LSM_R(1e3),  LSM_R(1e4),  LSM_R(1e5),  LSM_R(1e6),
        LSM_R(1e7),  LSM_R(1e8),  LSM_R(1e9),  LSM_R(1e10), LSM_R(1e11), LSM_R(1e12), LSM_R(1e13),
        LSM_R(1e14), LSM_R(1e15), LSM_R(1e16), LSM_R(1e17), LSM_R(1e18)};
    return k_pow10[k];
}

static bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

static uint32_t skip_blanks(const char *s, uint32_t n, uint32_t i)
{
    while (i < n && is_blank(s[i]))
        i++;
    return i;
}

static lsm_status fail(lsm_gcode_result *res, lsm_status code, uint32_t col)
{
    res->status = code;
    res->err.code = code;
    res->err.line = res->line;
    res->err.column = col;
    return code;
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
static lsm_status read_number(const char *s, uint32_t n, uint32_t *pi, uint32_t col, gc_num *out,
                              lsm_gcode_result *res)
{
    uint32_t i = skip_blanks(s, n, *pi);
    if (i < n && (s[i] == '#' || s[i] == '['))
        return fail(res, LSM_E_GC_UNSUPPORTED, i + 1); /* parameters and expressions */
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

/* Step 2: the word table. */
static lsm_status scan_words(const lsm_gcode *p, const char *s, uint32_t n, uint32_t i, gc_words *w,
                             lsm_gcode_result *res)
{
    for (int g = 0; g < GRP_COUNT; g++)
        w->g[g] = -1;
    w->m_stop = -1;
    for (;;) {
        i = skip_blanks(s, n, i);
        if (i >= n)
            return LSM_OK;
        char c = s[i];
        uint32_t col = i + 1;
        if (c == ';')
            return LSM_OK;
        if (c == '(') {
            uint32_t j = i + 1;
            while (j < n && s[j] != ')') {
                if (s[j] == '(')
                    return fail(res, LSM_E_GC_COMMENT, j + 1);
                j++;
            }
            if (j >= n)
                return fail(res, LSM_E_GC_COMMENT, col);
            i = j + 1;
            continue;
        }
        if (c == ')')
            return fail(res, LSM_E_GC_COMMENT, col);
        if (c == '#' || c == '[' || c == '<' || c == '@' || c == '^')
            return fail(res, LSM_E_GC_UNSUPPORTED, col);
        if (c >= 'a' && c <= 'z')
            c = (char)(c - 'a' + 'A');
        if (c < 'A' || c > 'Z')
            return fail(res, LSM_E_GC_SYNTAX, col);
        if (c == 'O')
            return fail(res, LSM_E_GC_UNSUPPORTED, col);
        const uint32_t known = BIT('G') | BIT('M') | BIT('N') | BIT('F') | AXIS_BITS | ARC_BITS | BIT('P');
        if (!(known & BIT(c)))
            return fail(res, LSM_E_GC_UNKNOWN_WORD, col);
        i++;
        gc_num num;
        lsm_status st = read_number(s, n, &i, col, &num, res);
        if (st != LSM_OK)
            return st;
        if (c == 'G' || c == 'M') {
            int32_t code = code_times_ten(&num);
            if (c == 'G') {
                int grp = -1;
                for (size_t k = 0; k < sizeof k_gcodes / sizeof k_gcodes[0]; k++) {
                    if (k_gcodes[k].code10 == code) {
                        grp = k_gcodes[k].group;
                        break;
                    }
                }
                if (grp < 0)
                    return fail(res, LSM_E_GC_UNKNOWN_WORD, col);
                if (w->g[grp] >= 0)
                    return fail(res, LSM_E_GC_MODAL_CONFLICT, col);
                w->g[grp] = (int16_t)code;
                w->gcol[grp] = col;
            } else {
                if (code != 20 && code != 300)
                    return fail(res, LSM_E_GC_UNKNOWN_WORD, col);
                if (w->m_stop >= 0)
                    return fail(res, LSM_E_GC_MODAL_CONFLICT, col);
                w->m_stop = (int16_t)code;
                w->mcol = col;
            }
            w->n_words++;
            continue;
        }
        if (w->seen & BIT(c))
            return fail(res, LSM_E_GC_WORD_REPEATED, col);
        if (c == 'N') {
            uint32_t nv;
            if (w->n_words != 0)
                return fail(res, LSM_E_GC_SYNTAX, col);
            if (!as_uint(&num, &nv))
                return fail(res, LSM_E_GC_BAD_VALUE, col);
            w->nnum = num;
            res->has_n = true;
            res->n = nv;
        } else if (c == 'F') {
            if (num.value < 0)
                return fail(res, LSM_E_GC_BAD_VALUE, col);
        } else if (c == 'P') {
            w->pnum = num;
        } else if (AXIS_BITS & BIT(c)) {
            for (unsigned k = 0; k < LSM_GCODE_N_AXES; k++) {
                if (k_axis_letters[k] == c && !(p->opt.axis_mask & (1u << k)))
                    return fail(res, LSM_E_GC_NO_AXIS, col);
            }
        }
        w->seen |= BIT(c);
        w->val[LETTER(c)] = num.value;
        w->col[LETTER(c)] = col;
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

static lsm_real hypot_r(lsm_real a, lsm_real b) { return lsm_sqrt(a * a + b * b); }

/* Arc geometry in the plane (u, v) with normal w. */
static lsm_status make_arc(const gc_words *w, const lsm_gcode_modal *m, const lsm_real s[LSM_GCODE_N_AXES],
                           const lsm_real e[LSM_GCODE_N_AXES], lsm_real lin, uint32_t turns, uint32_t mcol,
                           lsm_gcode_block *b, lsm_gcode_result *res)
{
    int iu, iv, iw;
    char lu, lv, lbad; /* offset letters along u and v, and the one that is not allowed */
    switch (m->plane) {
    case LSM_GCODE_PLANE_ZX: iu = LSM_GCODE_Z; iv = LSM_GCODE_X; iw = LSM_GCODE_Y; lu = 'K'; lv = 'I'; lbad = 'J'; break;
    case LSM_GCODE_PLANE_YZ: iu = LSM_GCODE_Y; iv = LSM_GCODE_Z; iw = LSM_GCODE_X; lu = 'J'; lv = 'K'; lbad = 'I'; break;
    case LSM_GCODE_PLANE_XY:
    default: iu = LSM_GCODE_X; iv = LSM_GCODE_Y; iw = LSM_GCODE_Z; lu = 'I'; lv = 'J'; lbad = 'K'; break;
    }
    const int dir = m->motion == LSM_GCODE_MOTION_CCW ? 1 : -1;
    const bool has_r = (w->seen & BIT('R')) != 0;
    const uint32_t ijk = w->seen & (BIT('I') | BIT('J') | BIT('K'));

    /* form */
    if (!(w->seen & (BIT(k_axis_letters[iu]) | BIT(k_axis_letters[iv]))))
        return fail(res, LSM_E_GC_ARC_FORM, mcol);
    if (!has_r && !ijk)
        return fail(res, LSM_E_GC_ARC_FORM, mcol);
    if (has_r && ijk) {
        uint32_t cr = w->col[LETTER('R')], ci = first_col(w, ijk);
        return fail(res, LSM_E_GC_ARC_FORM, cr > ci ? cr : ci);
    }
    if (ijk & BIT(lbad))
        return fail(res, LSM_E_GC_ARC_FORM, w->col[LETTER(lbad)]);
    if (m->feed_mm_s <= 0)
        return fail(res, LSM_E_GC_NO_FEED, mcol);

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
        if (same || ar < rtol)
            return fail(res, LSM_E_GC_ARC_RADIUS, rcol);
        lsm_real half = chord * LSM_R(0.5);
        if (half - ar > rtol)
            return fail(res, LSM_E_GC_ARC_RADIUS, rcol);
        lsm_real h2 = ar * ar - half * half;
        lsm_real h = h2 > 0 ? lsm_sqrt(h2) : LSM_R(0.0);
        /* the centre is left of the chord for a counter-clockwise arc of at most 180 degrees */
        lsm_real side = (lsm_real)(dir * (r > 0 ? 1 : -1));
        cu = s[iu] + LSM_R(0.5) * du + side * h * (-dv / chord);
        cv = s[iv] + LSM_R(0.5) * dv + side * h * (du / chord);
    } else {
        lsm_real ou = (w->seen & BIT(lu)) ? w->val[LETTER(lu)] * lin : LSM_R(0.0);
        lsm_real ov = (w->seen & BIT(lv)) ? w->val[LETTER(lv)] * lin : LSM_R(0.0);
        cu = s[iu] + ou;
        cv = s[iv] + ov;
        lsm_real r1 = hypot_r(s[iu] - cu, s[iv] - cv);
        lsm_real r2 = hypot_r(e[iu] - cu, e[iv] - cv);
        if (r1 < rtol || r2 < rtol)
            return fail(res, LSM_E_GC_ARC_CENTRE, first_col(w, ijk));
        lsm_real err = lsm_fabs(r1 - r2);
        lsm_real rmax = r1 > r2 ? r1 : r2;
        if (err > (lsm_real)LSM_GCODE_ARC_ABS_TOL_MM || err > (lsm_real)LSM_GCODE_ARC_REL_TOL * rmax)
            return fail(res, LSM_E_GC_ARC_MISMATCH, mcol);
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

/* Step 3a: the modal words that do not move (units, feed, plane, distance mode) into m; returns the line's linear
 * unit (mm per unit). */
static lsm_real exec_modal(const gc_words *w, lsm_gcode_modal *m)
{
    /* units first: every number on the line is read in the line's final units */
    if (w->g[GRP_UNITS] >= 0)
        m->units = w->g[GRP_UNITS] == 200 ? LSM_GCODE_UNITS_INCH : LSM_GCODE_UNITS_MM;
    const lsm_real lin = m->units == LSM_GCODE_UNITS_INCH ? GC_MM_PER_INCH : LSM_R(1.0);

    if (w->seen & BIT('F')) {
        lsm_real f = w->val[LETTER('F')];
        m->feed_mm_s = f * lin / LSM_R(60.0);
        m->feed_rot_rad_s = f / LSM_R(60.0) * GC_DEG2RAD;
    }
    if (w->g[GRP_PLANE] >= 0)
        m->plane = (lsm_gcode_plane)(w->g[GRP_PLANE] / 10);
    if (w->g[GRP_DISTANCE] >= 0)
        m->distance = w->g[GRP_DISTANCE] == 900 ? LSM_GCODE_ABSOLUTE : LSM_GCODE_INCREMENTAL;
    return lin;
}

/* Step 3b: the end point of the line's motion (axis words in the line's units and distance mode), each within
 * LSM_GCODE_MAX_ABS. */
static lsm_status exec_end_point(const lsm_gcode *p, const gc_words *w, const lsm_gcode_modal *m, lsm_real lin,
                                 lsm_real end[LSM_GCODE_N_AXES], lsm_gcode_result *res)
{
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        char L = k_axis_letters[k];
        if (!(w->seen & BIT(L)))
            continue;
        const bool rotary = k >= LSM_GCODE_A;
        lsm_real v = w->val[LETTER(L)] * (rotary ? GC_DEG2RAD : lin);
        end[k] = m->distance == LSM_GCODE_ABSOLUTE ? v : p->pos[k] + v;
        lsm_real lim = (lsm_real)LSM_GCODE_MAX_ABS * (rotary ? GC_DEG2RAD : LSM_R(1.0));
        if (lsm_fabs(end[k]) > lim)
            return fail(res, LSM_E_GC_NUMBER_RANGE, w->col[LETTER(L)]);
    }
    return LSM_OK;
}

/* Step 3: execute the word table on a copy of the state; commit on success. */
static lsm_status execute(lsm_gcode *p, const gc_words *w, lsm_gcode_result *res)
{
    lsm_gcode_modal m = p->modal;
    lsm_real end[LSM_GCODE_N_AXES];
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        end[k] = p->pos[k];
    const lsm_real lin = exec_modal(w, &m);

    const bool has_p = (w->seen & BIT('P')) != 0;
    const bool g64 = w->g[GRP_PATH] == 640;
    if (w->g[GRP_PATH] == 610) {
        m.blend = LSM_GCODE_EXACT_STOP;
        m.blend_tol_mm = 0;
    }

    /* motion */
    const bool explicit_motion = w->g[GRP_MOTION] >= 0;
    if (explicit_motion) {
        switch (w->g[GRP_MOTION]) {
        case 0: m.motion = LSM_GCODE_MOTION_RAPID; break;
        case 10: m.motion = LSM_GCODE_MOTION_LINEAR; break;
        case 20: m.motion = LSM_GCODE_MOTION_CW; break;
        case 30: m.motion = LSM_GCODE_MOTION_CCW; break;
        default: m.motion = LSM_GCODE_MOTION_NONE; break;
        }
    }
    const bool has_axis = (w->seen & AXIS_BITS) != 0;
    const bool is_arc_mode = m.motion == LSM_GCODE_MOTION_CW || m.motion == LSM_GCODE_MOTION_CCW;
    const bool arc_cmd = is_arc_mode && (explicit_motion || has_axis);
    const bool line_cmd = (m.motion == LSM_GCODE_MOTION_RAPID || m.motion == LSM_GCODE_MOTION_LINEAR) && has_axis;
    const uint32_t axis_col = first_col(w, AXIS_BITS);
    const uint32_t mcol = explicit_motion ? w->gcol[GRP_MOTION] : axis_col;

    if (has_axis && m.motion == LSM_GCODE_MOTION_NONE)
        return fail(res, LSM_E_GC_UNUSED_WORD, axis_col);
    if ((w->seen & ARC_BITS) && !arc_cmd)
        return fail(res, LSM_E_GC_UNUSED_WORD, first_col(w, ARC_BITS));
    uint32_t turns = 1;
    if (has_p) {
        uint32_t pcol = w->col[LETTER('P')];
        if (g64 && arc_cmd)
            return fail(res, LSM_E_GC_ARC_FORM, pcol);
        if (!g64 && !arc_cmd)
            return fail(res, LSM_E_GC_UNUSED_WORD, pcol);
        if (arc_cmd) {
            if (!as_uint(&w->pnum, &turns) || turns < 1 || turns > LSM_GCODE_MAX_TURNS)
                return fail(res, LSM_E_GC_BAD_VALUE, pcol);
        } else if (w->val[LETTER('P')] < 0) {
            return fail(res, LSM_E_GC_BAD_VALUE, pcol);
        }
    }
    if (g64) {
        m.blend = LSM_GCODE_BLEND;
        m.blend_tol_mm = has_p ? w->val[LETTER('P')] * lin : LSM_R(0.0);
    }

    lsm_status est = exec_end_point(p, w, &m, lin, end, res);
    if (est != LSM_OK)
        return est;

    lsm_gcode_block b = {0};
    bool emit = false;
    if (line_cmd) {
        if (m.motion == LSM_GCODE_MOTION_LINEAR && m.feed_mm_s <= 0)
            return fail(res, LSM_E_GC_NO_FEED, mcol);
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            if (end[k] != p->pos[k])
                emit = true;
        b.type = m.motion == LSM_GCODE_MOTION_RAPID ? LSM_GCODE_BLOCK_RAPID : LSM_GCODE_BLOCK_LINEAR;
    } else if (arc_cmd) {
        lsm_status st = make_arc(w, &m, p->pos, end, lin, turns, mcol, &b, res);
        if (st != LSM_OK)
            return st;
        emit = true;
    }
    if (emit) {
        b.line = res->line;
        for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
            b.start[k] = p->pos[k];
            b.end[k] = end[k];
        }
        if (b.type != LSM_GCODE_BLOCK_RAPID) {
            b.feed_mm_s = m.feed_mm_s;
            b.feed_rot_rad_s = m.feed_rot_rad_s;
        }
        res->blocks[0] = b;
        res->n_blocks = 1;
    }

    /* commit */
    p->modal = m;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        p->pos[k] = end[k];
    if (w->m_stop >= 0)
        p->ended = true;
    return LSM_OK;
}

/* Parses one line (no line ending) and fills res; the line number is already in res->line. */
static lsm_status parse(lsm_gcode *p, const char *s, uint32_t n, lsm_gcode_result *res)
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
            return fail(res, LSM_E_GC_SYNTAX, j + 1);
        if (first_line && !p->percent_open)
            p->percent_open = true;
        else
            p->ended = true;
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

static void result_begin(lsm_gcode *p, lsm_gcode_result *res)
{
    *res = (lsm_gcode_result){0};
    res->complete = true;
    res->line = ++p->line_no;
    res->status = LSM_OK;
}

static lsm_status result_end(lsm_gcode *p, lsm_gcode_result *res, lsm_status st)
{
    if (st != LSM_OK)
        res->n_blocks = 0;
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
    if (was_ended)
        return result_end(p, res, LSM_OK);
    if (n > 0 && p->buf[n - 1] == '\r')
        n--;
    if (overflow || n > LSM_GCODE_MAX_LINE)
        return result_end(p, res, fail(res, LSM_E_GC_LINE_TOO_LONG, LSM_GCODE_MAX_LINE + 1));
    return result_end(p, res, parse(p, p->buf, n, res));
}

void lsm_gcode_default_options(lsm_gcode_options *opt)
{
    if (!opt)
        return;
    opt->axis_mask = LSM_GCODE_ALL_AXES;
    opt->block_delete = false;
    opt->units = LSM_GCODE_UNITS_MM;
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
    if (was_ended)
        return result_end(p, res, LSM_OK);
    if (len > 0 && line[len - 1] == '\n')
        len--;
    if (len > 0 && line[len - 1] == '\r')
        len--;
    if (len > LSM_GCODE_MAX_LINE)
        return result_end(p, res, fail(res, LSM_E_GC_LINE_TOO_LONG, LSM_GCODE_MAX_LINE + 1));
    for (size_t i = 0; i < len; i++)
        if (line[i] == '\n')
            return result_end(p, res, fail(res, LSM_E_GC_SYNTAX, (uint32_t)i + 1));
    return result_end(p, res, parse(p, line, (uint32_t)len, res));
}

const lsm_gcode_modal *lsm_gcode_modal_state(const lsm_gcode *p) { return p ? &p->modal : NULL; }

const lsm_real *lsm_gcode_position(const lsm_gcode *p) { return p ? p->pos : NULL; }
