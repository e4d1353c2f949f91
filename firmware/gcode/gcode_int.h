/*
 * gcode_int.h: private to the gcode component (gcode.c: bytes, words, the line loop and the public calls;
 * gcode_exec.c: step 3, executing a line's word table). The word table, its letters and modal groups, and the
 * error helpers both use.
 */
#ifndef LSM_GCODE_INT_H
#define LSM_GCODE_INT_H

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

static inline lsm_status fail_r(lsm_gcode_result *res, lsm_status code, uint32_t col, const char *reason)
{
    res->status = code;
    res->err.code = code;
    res->err.line = res->line;
    res->err.column = col;
    res->err.reason = reason;
    return code;
}

static inline lsm_status fail(lsm_gcode_result *res, lsm_status code, uint32_t col)
{
    return fail_r(res, code, col, NULL);
}

/* Smallest column among the letters in `mask` that are present (0 if none). */
static inline uint32_t first_col(const gc_words *w, uint32_t mask)
{
    uint32_t best = 0;
    for (int k = 0; k < 26; k++) {
        if ((w->seen & mask & (1u << k)) && (best == 0 || w->col[k] < best))
            best = w->col[k];
    }
    return best;
}

/* True if the number is a non-negative integer; *out gets it. */
static inline bool as_uint(const gc_num *x, uint32_t *out)
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

static inline void push_event(lsm_gcode_result *res, lsm_gcode_event_kind kind, bool stop, int32_t tool, lsm_real value)
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

/* Step 3: executes the word table w of one line on a copy of the state and commits it on success (gcode_exec.c). */
lsm_status lsm_gc_execute(lsm_gcode *p, const gc_words *w, lsm_gcode_result *res);

#endif
