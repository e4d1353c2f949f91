/*
 * gcode.h: a streaming RS274/NGC subset parser, LinuxCNC dialect (lsm_gcode_*).
 *
 * Model. A program is a sequence of lines; each line is parsed as a whole and either applies
 * completely (modal state updated, zero or one motion block emitted) or not at all (an error with
 * its code, line and column; the parser state is left as it was before the line). The parser holds
 * no pointers and allocates nothing: the caller owns the `lsm_gcode` object (about 0.4 kB with the
 * default LSM_GCODE_MAX_LINE) and feeds it bytes, one line or any chunk at a time. It runs on the
 * MCU as well as on the host (no stdio, no strtod, no locale).
 *
 * Accepted words (letters are case-insensitive; spaces and tabs are ignored everywhere outside
 * comments, as in RS274/NGC, so "G 0 1 X 1 0" is G01 X10):
 *   G0 rapid, G1 linear, G2 clockwise arc, G3 counter-clockwise arc, G80 motion off   (group 1)
 *   G17 XY, G18 ZX, G19 YZ plane (group 2); G90 absolute, G91 incremental (group 3);
 *   G20 inch, G21 mm (group 6); G61 exact stop, G64 [P tol] blending (group 13).
 *   Accepted and without effect, because they only restate this parser's fixed defaults:
 *   G40 (no cutter compensation), G49 (no tool length offset), G54 (first work offset, zero),
 *   G94 (feed in units per minute).
 *   M2, M30 end of program. F feed. N line number (first word only). X Y Z A B C axes.
 *   I J K arc centre offsets (always relative to the start point, i.e. G91.1 semantics).
 *   R arc radius. P: blend tolerance with G64, number of turns with G2/G3.
 *   Comments "( ... )" (not nested) and "; ..." to end of line; a '/' first on a line deletes it
 *   when the block-delete switch is on (ignored otherwise); a line holding only '%' delimits the
 *   program (the second one ends it like M2).
 *   Everything else is an error: other letters and G/M numbers (LSM_E_GC_UNKNOWN_WORD), parameters
 *   '#', expressions '[', O-words, '<', '@', '^' (LSM_E_GC_UNSUPPORTED).
 *
 * Units. Whatever the G-code units, everything leaving the parser is in mm, mm/s and rad:
 *   X Y Z, I J K, R and G64 P are multiplied by 25.4 under G20; F (units/min) becomes mm/s;
 *   A B C are degrees in the G-code (never scaled by G20) and leave the parser in radians.
 *   The numbers on a line are read in the units in force after that line's G20/G21. F is
 *   converted when it is read, so a later G20/G21 does not change the physical feed.
 *   For a block that moves only rotary axes LinuxCNC reads F as degrees/min; that value is given
 *   separately as feed_rot_rad_s.
 *
 * Arcs (RS274/NGC rules as in LinuxCNC). In the active plane with in-plane coordinates (u, v) and
 * normal w -- G17: (X, Y; Z), G18: (Z, X; Y), G19: (Y, Z; X) -- G3 turns counter-clockwise about
 * +w and G2 clockwise. Offsets I J K give the centre relative to the start (G17: I J, G18: I K,
 * G19: J K; the third one is an error). Centre form: the start and end radii r1, r2 must satisfy
 * |r1 - r2| <= LSM_GCODE_ARC_ABS_TOL_MM and |r1 - r2| / max(r1, r2) <= LSM_GCODE_ARC_REL_TOL
 * (LinuxCNC's spiral tolerances); end == start is a full circle. Radius form: R > 0 gives the
 * arc of at most 180 degrees, R < 0 the one over 180 degrees; end == start is an error, and the chord
 * may exceed the diameter by at most LSM_GCODE_ARC_RADIUS_TOL_MM (then it is a half circle).
 * P n (integer >= 1, default 1) adds n - 1 full turns. Axes other than u, v move linearly with
 * the arc angle (helix along w, and A B C). At least one of the u, v axis words must be given.
 *
 * Incremental mode (G91) applies to axis words only; I J K are always incremental.
 * Zero-length G0/G1 moves (end == start on every axis) emit no block.
 * Lines after the end of the program are consumed and ignored (LinuxCNC does not read them).
 */
#ifndef LSM_GCODE_H
#define LSM_GCODE_H

#include "lsm_config.h"
#include "status.h"

/* Compile-time settings (LSM_GCODE_MAX_LINE, LSM_GCODE_MAX_ABS, LSM_GCODE_ARC_ABS_TOL_MM, LSM_GCODE_ARC_REL_TOL,
 * LSM_GCODE_ARC_RADIUS_TOL_MM, LSM_GCODE_MAX_BLOCKS, LSM_GCODE_MAX_TURNS): lsm_config.h. */

/* Axis indices into every position array: X Y Z in mm, A B C in rad. */
enum { LSM_GCODE_X = 0, LSM_GCODE_Y, LSM_GCODE_Z, LSM_GCODE_A, LSM_GCODE_B, LSM_GCODE_C };
#define LSM_GCODE_N_AXES 6
#define LSM_GCODE_ALL_AXES 0x3Fu

typedef enum lsm_gcode_motion {
    LSM_GCODE_MOTION_NONE = 0, /* G80 (and the state at start: axis words need a G0..G3 first) */
    LSM_GCODE_MOTION_RAPID,    /* G0 */
    LSM_GCODE_MOTION_LINEAR,   /* G1 */
    LSM_GCODE_MOTION_CW,       /* G2 */
    LSM_GCODE_MOTION_CCW       /* G3 */
} lsm_gcode_motion;

typedef enum lsm_gcode_plane {
    LSM_GCODE_PLANE_XY = 17, /* G17: u = X, v = Y, normal Z */
    LSM_GCODE_PLANE_ZX = 18, /* G18: u = Z, v = X, normal Y */
    LSM_GCODE_PLANE_YZ = 19  /* G19: u = Y, v = Z, normal X */
} lsm_gcode_plane;

typedef enum lsm_gcode_units { LSM_GCODE_UNITS_MM = 21, LSM_GCODE_UNITS_INCH = 20 } lsm_gcode_units;
typedef enum lsm_gcode_distance { LSM_GCODE_ABSOLUTE = 90, LSM_GCODE_INCREMENTAL = 91 } lsm_gcode_distance;
typedef enum lsm_gcode_blend {
    LSM_GCODE_EXACT_STOP = 61, /* G61: stop at the end of every block */
    LSM_GCODE_BLEND = 64       /* G64: blend, within blend_tol_mm if > 0, else the machine default */
} lsm_gcode_blend;

/* The modal state (as it is after a line). */
typedef struct lsm_gcode_modal {
    lsm_gcode_motion motion;
    lsm_gcode_plane plane;
    lsm_gcode_units units;       /* units of the G-code input; the outputs are always mm */
    lsm_gcode_distance distance;
    lsm_gcode_blend blend;
    lsm_real blend_tol_mm;       /* G64 P converted to mm; 0 = no P given (use the machine default) */
    lsm_real feed_mm_s;          /* last F, in mm/s; 0 until an F word is read */
    lsm_real feed_rot_rad_s;     /* the same F read as deg/min (for rotary-only moves), in rad/s */
} lsm_gcode_modal;

typedef enum lsm_gcode_block_type {
    LSM_GCODE_BLOCK_RAPID = 0,   /* G0: straight line at the machine's rapid rate (feed_mm_s = 0) */
    LSM_GCODE_BLOCK_LINEAR,      /* G1: straight line at feed_mm_s */
    LSM_GCODE_BLOCK_ARC          /* G2/G3: circular or helical arc at feed_mm_s */
} lsm_gcode_block_type;

typedef struct lsm_gcode_block {
    lsm_gcode_block_type type;
    uint32_t line;                    /* physical source line (1-based) */
    lsm_real start[LSM_GCODE_N_AXES]; /* X Y Z mm, A B C rad */
    lsm_real end[LSM_GCODE_N_AXES];
    lsm_real feed_mm_s;               /* programmed feed (0 for rapids) */
    lsm_real feed_rot_rad_s;          /* programmed F read as deg/min, in rad/s (0 for rapids) */
    /* arcs only (zero otherwise): */
    lsm_gcode_plane plane;
    int8_t dir;                       /* +1 counter-clockwise (G3), -1 clockwise (G2) about +normal */
    uint32_t turns;                   /* additional full turns (P - 1) */
    lsm_real centre[3];               /* X Y Z of the centre, mm; its normal coordinate = start's */
    lsm_real radius_mm;               /* distance start-centre in the plane */
    lsm_real radius_end_mm;           /* distance end-centre in the plane (within tolerance of radius_mm) */
    lsm_real angle_rad;               /* swept angle > 0, including the full turns */
    lsm_real helix_mm;                /* displacement along the plane normal (end - start) */
} lsm_gcode_block;

/* Where an error is (line and column are 1-based; column counts bytes). */
typedef struct lsm_gcode_error {
    lsm_status code;
    uint32_t line;
    uint32_t column;
} lsm_gcode_error;

/* What one line produced. */
typedef struct lsm_gcode_result {
    bool complete;          /* a line was completed (feed/finish); always true from parse_line */
    uint32_t line;          /* physical line number (1-based) */
    lsm_status status;      /* LSM_OK or the error of this line */
    lsm_gcode_error err;    /* valid when status != LSM_OK */
    bool has_n;             /* the line had an N word ... */
    uint32_t n;             /* ... with this value */
    bool deleted;           /* skipped by block delete ('/' with the switch on) */
    uint8_t n_blocks;       /* motion blocks produced (0 .. LSM_GCODE_MAX_BLOCKS) */
    lsm_gcode_block blocks[LSM_GCODE_MAX_BLOCKS];
    lsm_gcode_modal modal;  /* modal state after the line */
    bool end_of_program;    /* M2, M30 or the closing '%' was read (on this or an earlier line) */
} lsm_gcode_result;

typedef struct lsm_gcode_options {
    uint8_t axis_mask;      /* bit k set: axis k (X=0 .. C=5) exists; words for others are errors */
    bool block_delete;      /* the block-delete switch: skip lines that start with '/' */
    lsm_gcode_units units;  /* units at program start (RS274/NGC leaves it to the machine) */
} lsm_gcode_options;

/* Parser state: caller-owned, initialise with lsm_gcode_init. Fields are private. */
typedef struct lsm_gcode {
    lsm_gcode_options opt;
    lsm_gcode_modal modal;
    lsm_real pos[LSM_GCODE_N_AXES]; /* current programmed position, mm / rad */
    uint32_t line_no;               /* lines completed so far */
    bool ended;
    bool percent_open;
    bool seen_content;              /* a non-blank line was seen (for the opening '%') */
    bool overflow;                  /* the current line exceeded LSM_GCODE_MAX_LINE */
    bool pending;                   /* bytes of an unfinished line are buffered */
    uint16_t len;
    char buf[LSM_GCODE_MAX_LINE + 1]; /* +1: room for the '\r' of a full-length line */
} lsm_gcode;

/* Defaults: all six axes, block delete off, mm. */
void lsm_gcode_default_options(lsm_gcode_options *opt);

/* Initialise (opt may be NULL for the defaults). Modal state at start: G80 G17 G90 G64 (no P),
 * units from opt, F 0, position 0. Errors: LSM_E_NULL, LSM_E_ARG (axis_mask 0 or above 0x3F,
 * units not 20/21). */
lsm_status lsm_gcode_init(lsm_gcode *p, const lsm_gcode_options *opt);

/* Set the current position (X Y Z mm, A B C rad), e.g. the machine position at program start.
 * Errors: LSM_E_NULL, LSM_E_NAN, LSM_E_INF, LSM_E_RANGE (beyond LSM_GCODE_MAX_ABS). */
lsm_status lsm_gcode_set_position(lsm_gcode *p, const lsm_real pos[LSM_GCODE_N_AXES]);

/* Streaming input. Consumes bytes of `data` up to and including the first '\n' (or all of them)
 * and sets *used to the count consumed. When a line was completed, res->complete is true and the
 * return value is the line's status (res holds its blocks, modal state or error); otherwise
 * res->complete is false and the return value is LSM_OK. Call again with the rest of the data.
 * A line longer than LSM_GCODE_MAX_LINE is consumed to its end and reported once, at its end.
 * "\r\n" and "\n" end lines; '\r' elsewhere counts as a blank. */
lsm_status lsm_gcode_feed(lsm_gcode *p, const char *data, size_t len, size_t *used, lsm_gcode_result *res);

/* End of input: parses a final line that had no line ending, if any (res->complete tells). */
lsm_status lsm_gcode_finish(lsm_gcode *p, lsm_gcode_result *res);

/* Convenience: parse exactly one line (a trailing "\n" or "\r\n" is allowed; any other '\n' is an
 * error, LSM_E_GC_SYNTAX). Must not be mixed with an unfinished lsm_gcode_feed line (LSM_E_STATE). */
lsm_status lsm_gcode_parse_line(lsm_gcode *p, const char *line, size_t len, lsm_gcode_result *res);

/* Current modal state and position (for a caller that wants them without a result). */
const lsm_gcode_modal *lsm_gcode_modal_state(const lsm_gcode *p);
const lsm_real *lsm_gcode_position(const lsm_gcode *p);

#endif /* LSM_GCODE_H */
