/*
 * gcode.h: a streaming RS274/NGC subset parser, LinuxCNC dialect (lsm_gcode_*).
 *
 * Model. A program is a sequence of lines; each line is parsed as a whole and either applies
 * completely (modal state and offsets updated, up to two motion blocks and its machine-function events
 * emitted) or not at all (an error with
 * its code, line and column; the parser state is left as it was before the line). The parser holds
 * no pointers and allocates nothing: the caller owns the `lsm_gcode` object (580 B float, 848 B double, with the
 * default LSM_GCODE_MAX_LINE) and feeds it bytes, one line or any chunk at a time. It runs on the
 * MCU as well as on the host (no stdio, no strtod, no locale).
 *
 * Accepted words (letters are case-insensitive; spaces and tabs are ignored everywhere outside
 * comments, as in RS274/NGC, so "G 0 1 X 1 0" is G01 X10). docs/gcode.md gives each word with the
 * section of the LinuxCNC G-code reference it follows.
 *   Motion (group 1): G0 rapid, G1 linear, G2 clockwise arc, G3 counter-clockwise arc, G80 motion off
 *   (G80 next to another motion code on the same line is dropped: the other one wins, as in LinuxCNC).
 *   G17 XY, G18 ZX, G19 YZ plane; G90 / G91 absolute / incremental; G90.1 / G91.1 absolute / incremental
 *   arc centres; G20 inch, G21 mm; G61 exact stop, G64 [P tol] blending; G40, G94 (the only cutter
 *   compensation and feed modes: accepted, no effect); G43 [H n] / G49 tool length offset (passed to the
 *   caller as events; the parser keeps no tool table); G54..G59 work offsets; G4 P dwell (s);
 *   G10 L2 / L20 P0..6 set work offsets; G28 / G30 [axes] go home through an intermediate point, G28.1 /
 *   G30.1 store the home positions; G53 machine coordinates for this line; G92 / G92.1 / G92.2 offsets.
 *   M0 pause, M1 optional pause, M2 / M30 end; M3 / M4 / M5 spindle; M6 tool change; M7 / M8 / M9 coolant.
 *   F feed, S spindle speed (rpm), T tool, H tool length offset number, L with G10, N line number (first
 *   word only). X Y Z A B C axes; I J K arc centre; R arc radius; P: G4 seconds, G10 system, G64
 *   tolerance, G2/G3 turns.
 *   Comments "( ... )" (not nested) and "; ..." to end of line; a '/' first on a line deletes it
 *   when the block-delete switch is on (ignored otherwise); a line holding only '%' delimits the
 *   program (the second one ends it like M2).
 *   Everything else is an error naming the word: other letters and G/M numbers (LSM_E_GC_UNKNOWN_WORD),
 *   known features outside the subset (LSM_E_GC_UNSUPPORTED with a reason: parameters '#', expressions
 *   '[', O-words, canned cycles, cutter compensation, ...).
 *
 * Machine functions. S, T, M6, M3/M4/M5, M7/M8/M9, G4, G43/G49, M0/M1 and M2/M30 come out as events, in
 * the order LinuxCNC executes them (S, T, M6, M3-M5, M7-M9, G4, G43/G49, then the line's motion, then
 * M0/M1, M2/M30), each with its line and with `at_block`, the number of the line's motion blocks before
 * it. `exact_stop` says the machine must be at rest on the end of the motion before it when the event
 * runs (LinuxCNC's task waits for motion to finish before it issues spindle, coolant, tool change, dwell
 * and pause commands). The caller runs them (the simulator logs them in summary.json).
 *
 * Coordinates. Blocks are in machine coordinates: program coordinates plus the work offset in use
 * (G54..G59, set by G10 L2/L20) plus the G92 offset. A G53 line's axis words are machine coordinates.
 * G28/G30 positions are machine coordinates (zero until G28.1/G30.1 store them).
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
 * the arc angle (helix along w, and A B C). A centre-form arc needs no end word (then it is a full
 * circle: "G2 I5"); a radius-form arc needs at least one of the u, v axis words.
 *
 * Incremental mode (G91) applies to axis words only; I J K are incremental (G91.1, the default) or
 * absolute program coordinates (G90.1).
 * Zero-length G0/G1 moves (end == start on every axis) emit no block.
 * Lines after the end of the program are consumed and ignored (LinuxCNC does not read them).
 */
#ifndef LSM_GCODE_H
#define LSM_GCODE_H

#include "lsm_config.h"
#include "status.h"

/* Compile-time settings (LSM_GCODE_MAX_LINE, LSM_GCODE_MAX_ABS, LSM_GCODE_ARC_ABS_TOL_MM, LSM_GCODE_ARC_REL_TOL,
 * LSM_GCODE_ARC_RADIUS_TOL_MM, LSM_GCODE_MAX_BLOCKS, LSM_GCODE_MAX_EVENTS, LSM_GCODE_MAX_TOOL, LSM_GCODE_MAX_TURNS):
 * lsm_config.h. */
/* Work offsets G54..G59 (G10 L2/L20 P1..P6): fixed by the language, not a setting. */
#define LSM_GCODE_N_WCS 6

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
    lsm_gcode_units units; /* units of the G-code input; the outputs are always mm */
    lsm_gcode_distance distance;
    lsm_gcode_blend blend;
    lsm_real blend_tol_mm;   /* G64 P converted to mm; 0 = no P given (use the machine default) */
    lsm_real feed_mm_s;      /* last F, in mm/s; 0 until an F word is read */
    lsm_real feed_rot_rad_s; /* the same F read as deg/min (for rotary-only moves), in rad/s */
    bool arc_absolute;       /* G90.1: I J K are absolute program coordinates (default G91.1) */
    uint8_t wcs;             /* work offset in use: 1 (G54) .. 6 (G59) */
    uint8_t spindle;         /* 3 (M3), 4 (M4), 5 (M5: stopped, the state at start) */
    bool mist, flood;        /* M7, M8 (M9 clears both) */
    bool tool_length_on;     /* G43 in force (G49 at start) */
    int32_t tool_length_h;   /* its H number (-1 without G43) */
    int32_t tool_selected;   /* last T (-1: none yet) */
    int32_t tool_loaded;     /* tool of the last M6 (0 at start: no tool) */
    lsm_real speed_rpm;      /* last S (0 at start) */
} lsm_gcode_modal;

/* Machine functions (see the header comment). */
typedef enum lsm_gcode_event_kind {
    LSM_GCODE_EV_SPINDLE_SPEED = 1, /* S: value = rpm */
    LSM_GCODE_EV_TOOL_SELECT,       /* T: tool = T (prepare; no stop) */
    LSM_GCODE_EV_TOOL_CHANGE,       /* M6: tool = the selected tool */
    LSM_GCODE_EV_SPINDLE_CW,        /* M3: value = rpm in force */
    LSM_GCODE_EV_SPINDLE_CCW,       /* M4: value = rpm in force */
    LSM_GCODE_EV_SPINDLE_STOP,      /* M5 (also at M2/M30 if the spindle turns) */
    LSM_GCODE_EV_COOLANT_MIST,      /* M7 */
    LSM_GCODE_EV_COOLANT_FLOOD,     /* M8 */
    LSM_GCODE_EV_COOLANT_OFF,       /* M9 (also at M2/M30 if coolant is on) */
    LSM_GCODE_EV_DWELL,             /* G4: value = seconds */
    LSM_GCODE_EV_TOOL_LENGTH,       /* G43: tool = H (the caller applies the length; no stop) */
    LSM_GCODE_EV_TOOL_LENGTH_OFF,   /* G49 (no stop) */
    LSM_GCODE_EV_PAUSE,             /* M0: stop and wait for the operator's resume */
    LSM_GCODE_EV_OPTIONAL_PAUSE,    /* M1: as M0 when opt.optional_stop is set (else no event) */
    LSM_GCODE_EV_END                /* M2 / M30 or the closing '%': tool = 2, 30 or 0 */
} lsm_gcode_event_kind;

typedef struct lsm_gcode_event {
    lsm_gcode_event_kind kind;
    uint32_t line;    /* physical source line (1-based) */
    uint8_t at_block; /* motion blocks of this line that come before it */
    bool exact_stop;  /* the machine must be at rest at the end of the motion before it */
    int32_t tool;     /* T, H, or the M number of an end */
    lsm_real value;   /* rpm (S, M3, M4) or seconds (G4) */
} lsm_gcode_event;

typedef enum lsm_gcode_block_type {
    LSM_GCODE_BLOCK_RAPID = 0, /* G0: straight line at the machine's rapid rate (feed_mm_s = 0) */
    LSM_GCODE_BLOCK_LINEAR,    /* G1: straight line at feed_mm_s */
    LSM_GCODE_BLOCK_ARC        /* G2/G3: circular or helical arc at feed_mm_s */
} lsm_gcode_block_type;

typedef struct lsm_gcode_block {
    lsm_gcode_block_type type;
    uint32_t line;                    /* physical source line (1-based) */
    lsm_real start[LSM_GCODE_N_AXES]; /* X Y Z mm, A B C rad */
    lsm_real end[LSM_GCODE_N_AXES];
    lsm_real feed_mm_s;      /* programmed feed (0 for rapids) */
    lsm_real feed_rot_rad_s; /* programmed F read as deg/min, in rad/s (0 for rapids) */
    /* arcs only (zero otherwise): */
    lsm_gcode_plane plane;
    int8_t dir;             /* +1 counter-clockwise (G3), -1 clockwise (G2) about +normal */
    uint32_t turns;         /* additional full turns (P - 1) */
    lsm_real centre[3];     /* X Y Z of the centre, mm; its normal coordinate = start's */
    lsm_real radius_mm;     /* distance start-centre in the plane */
    lsm_real radius_end_mm; /* distance end-centre in the plane (within tolerance of radius_mm) */
    lsm_real angle_rad;     /* swept angle > 0, including the full turns */
    lsm_real helix_mm;      /* displacement along the plane normal (end - start) */
} lsm_gcode_block;

/* Where an error is (line and column are 1-based; column counts bytes). */
typedef struct lsm_gcode_error {
    lsm_status code;
    uint32_t line;
    uint32_t column;
    const char *reason; /* what is wrong, e.g. "unknown word", "unsupported: parameters" (static text) */
    char word[24];      /* the offending word as written (blanks removed, letter upper case), e.g. "Q7"; a word
                             longer than 20 characters ends in "..." */
} lsm_gcode_error;

/* What one line produced. */
typedef struct lsm_gcode_result {
    bool complete;       /* a line was completed (feed/finish); always true from parse_line */
    uint32_t line;       /* physical line number (1-based) */
    lsm_status status;   /* LSM_OK or the error of this line */
    lsm_gcode_error err; /* valid when status != LSM_OK */
    bool has_n;          /* the line had an N word ... */
    uint32_t n;          /* ... with this value */
    bool deleted;        /* skipped by block delete ('/' with the switch on) */
    uint8_t n_blocks;    /* motion blocks produced (0 .. LSM_GCODE_MAX_BLOCKS) */
    lsm_gcode_block blocks[LSM_GCODE_MAX_BLOCKS];
    uint8_t n_events; /* machine-function events of the line, in execution order */
    lsm_gcode_event events[LSM_GCODE_MAX_EVENTS];
    lsm_gcode_modal modal; /* modal state after the line */
    bool end_of_program;   /* M2, M30 or the closing '%' was read (on this or an earlier line) */
    bool ignored;          /* a non-blank line after the end of the program (read and ignored) */
    int16_t nonmodal;      /* the line's non-modal G code times ten (G4: 40, G28.1: 281, ...), -1 if none */
} lsm_gcode_result;

typedef struct lsm_gcode_options {
    uint8_t axis_mask;     /* bit k set: axis k (X=0 .. C=5) exists; words for others are errors */
    bool block_delete;     /* the block-delete switch: skip lines that start with '/' */
    lsm_gcode_units units; /* units at program start (RS274/NGC leaves it to the machine) */
    bool optional_stop;    /* the optional-stop switch: M1 pauses when set (default), is ignored otherwise */
} lsm_gcode_options;

/* Parser state: caller-owned, initialise with lsm_gcode_init. Fields are private. */
typedef struct lsm_gcode {
    lsm_gcode_options opt;
    lsm_gcode_modal modal;
    lsm_real pos[LSM_GCODE_N_AXES];                  /* current position in machine coordinates, mm / rad */
    lsm_real wcs[LSM_GCODE_N_WCS][LSM_GCODE_N_AXES]; /* G54..G59 origins (machine coordinates) */
    lsm_real g92[LSM_GCODE_N_AXES];                  /* G92 offset */
    lsm_real home[2][LSM_GCODE_N_AXES];              /* G28 and G30 positions (machine coordinates) */
    uint32_t line_no;                                /* lines completed so far */
    bool ended;
    bool percent_open;
    bool seen_content; /* a non-blank line was seen (for the opening '%') */
    bool overflow;     /* the current line exceeded LSM_GCODE_MAX_LINE */
    bool pending;      /* bytes of an unfinished line are buffered */
    uint16_t len;
    char buf[LSM_GCODE_MAX_LINE + 1]; /* +1: room for the '\r' of a full-length line */
} lsm_gcode;

/* Defaults: all six axes, block delete off, mm, optional stop on. */
void lsm_gcode_default_options(lsm_gcode_options *opt);

/* Initialise (opt may be NULL for the defaults). Modal state at start: G80 G17 G90 G91.1 G64 (no P)
 * G40 G49 G54 G94 M5 M9, units from opt, F 0, S 0, no tool, position, offsets and homes 0. Errors: LSM_E_NULL, LSM_E_ARG (axis_mask 0 or above 0x3F,
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

/* Error text: reason and word, e.g. "unknown word 'Q7'", "unsupported: parameters (#2)",
 * "line longer than 256 bytes". Writes at most n bytes, NUL-terminated; returns buf. Any context. */
const char *lsm_gcode_error_text(const lsm_gcode_error *e, char *buf, size_t n);

/* Name and code of an event kind: "spindle_cw" and "M3", ... ("?" for others). Any context. */
const char *lsm_gcode_event_name(lsm_gcode_event_kind kind);
const char *lsm_gcode_event_code(lsm_gcode_event_kind kind);

/* Current modal state and position (for a caller that wants them without a result). */
const lsm_gcode_modal *lsm_gcode_modal_state(const lsm_gcode *p);
const lsm_real *lsm_gcode_position(const lsm_gcode *p);

#endif /* LSM_GCODE_H */
