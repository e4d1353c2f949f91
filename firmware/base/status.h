/*
 * status.h: the one status enum of the Lissom core (lsm_status_*).
 *
 * 0 is success; every error is negative and documented. Bad-input errors (rejected at the entrance,
 * before anything is computed or stored) are kept apart from internal faults. Each module owns a
 * block of codes so that modules can grow without renumbering others:
 *    -1 ..  -19  generic input validation
 *   -20 ..  -39  S-curve and point-to-point moves (scurve.c, move.c, stepgen.c, fixstep.c)
 *   -40 ..  -59  clothoid geometry and corner smoothing
 *   -60 ..  -79  look-ahead planner and interpolator
 *   -80 ..  -99  G-code parser
 *  -100 .. -119  CANopen / CiA 402
 *  -120 .. -139  ports and host simulation
 *  -200 ..       internal faults (a bug, never caused by input)
 */
#ifndef LSM_STATUS_H
#define LSM_STATUS_H

typedef enum lsm_status {
    LSM_OK = 0,

    /* generic input validation */
    LSM_E_NULL = -1,        /* a required pointer is NULL */
    LSM_E_NAN = -2,         /* an input is NaN */
    LSM_E_INF = -3,         /* an input is +/-infinity */
    LSM_E_LIMIT = -4,       /* a limit (v, a, j or snap) is zero or negative */
    LSM_E_CYCLE = -5,       /* the control cycle is zero or negative */
    LSM_E_NEG_FEED = -6,    /* a feed (velocity) is negative */
    LSM_E_RANGE = -7,       /* a value is too large to represent (distance, cycle count, counts) */
    LSM_E_ZERO_LENGTH = -8, /* a move or block has zero length */
    LSM_E_FULL = -9,        /* a buffer is full; nothing was stored */
    LSM_E_EMPTY = -10,      /* a buffer is empty */
    LSM_E_ARG = -11,        /* an argument is out of its documented domain (enum, count, index) */
    LSM_E_TOLERANCE = -12,  /* a tolerance is zero or negative */
    LSM_E_STATE = -13,      /* the call is not valid in the object's current state */

    /* S-curve and moves */
    LSM_E_FEED_ABOVE_VMAX = -20, /* a start or end feed exceeds the cruise limit v_max */
    LSM_E_INFEASIBLE = -21,      /* the distance is too short to go from v0 to v1 within the limits */
    LSM_E_TOO_LONG = -22,        /* the move needs more cycles than a 32-bit cycle counter holds */

    /* clothoid geometry and corner smoothing (geom.c, clothoid.c, g2path.c, corner.c) */
    LSM_E_FIT_LINE = -40,    /* clothoid fit: the target line is degenerate (A = B = 0) */
    LSM_E_FIT_ON_LINE = -41, /* clothoid fit: the start point is on the target line (and not already normal to it) */
    LSM_E_FIT_NO_SOLUTION = -42, /* clothoid fit: no clothoid from the start state meets the line at a right angle
                                      within reach (no sign change of the distance over the search range) */
    LSM_E_NOT_CONVERGED = -43,   /* a Newton iteration (fit or corner) hit its iteration cap */
    LSM_E_COLLINEAR = -44,       /* corner: no corner at all, the blocks already join with equal tangent and
                                      curvature (G2); not a fault: join them directly, nothing to smooth */
    LSM_E_REVERSAL = -45,        /* corner: the path reverses exactly (tangents opposite); cannot be blended */
    LSM_E_NONPLANAR = -46,       /* corner/contour: an arc and the other block are not in one plane, or a helical arc */
    LSM_E_ROTARY = -47,          /* corner: a block at the corner moves rotary axes (A B C); not blended */
    LSM_E_CORNER_NO_SOLUTION = -48, /* corner: no transition fits within the trim limits (blocks too short or the
                                      geometry folds); stop at the corner instead */
    LSM_E_GAP = -49,                /* corner/contour: a block does not start where the previous one ends */
    LSM_E_ARC_GEOMETRY = -50,  /* arc: zero radius, start/end radii differ, or the plane basis is not orthonormal */
    LSM_E_TOL_UNREACHED = -51, /* G2 path: the tolerance is not reached with the segments the storage holds */

    /* look-ahead planner and interpolator (planner.c, interp.c) */
    LSM_E_PL_AXIS = -60,      /* planner: a block moves an axis the machine does not have (axis mask) */
    LSM_E_PL_FINISHED = -61,  /* planner: a block appended after lsm_planner_finish (end of program) */
    LSM_E_PL_CAPACITY = -62,  /* planner: block storage smaller than LSM_PLANNER_MIN_BLOCKS */
    LSM_E_PL_OVERRIDE = -63,  /* feed override outside 0 .. 2 (0 .. 200 %) */
    LSM_E_PL_OVR_LATER = -64, /* planner: feed override not applied yet: the machine cannot follow it from here (the
                                 plan stays as it was; the interpolator retries it) */

    /* G-code parser (gcode.c); every one comes with the line and column of the offending text */
    LSM_E_GC_UNKNOWN_WORD = -80,   /* a letter, G or M number outside the supported subset */
    LSM_E_GC_MISSING_ARG = -81,    /* a letter without a number after it (e.g. "X", "X-", "X.") */
    LSM_E_GC_SYNTAX = -82,         /* a character that cannot start a word, or N not first */
    LSM_E_GC_NUMBER_RANGE = -83,   /* a number or coordinate too large to represent (LSM_GCODE_MAX_ABS) */
    LSM_E_GC_LINE_TOO_LONG = -84,  /* a line longer than LSM_GCODE_MAX_LINE bytes */
    LSM_E_GC_BINARY = -85,         /* a control byte, or a non-ASCII byte outside a comment */
    LSM_E_GC_WORD_REPEATED = -86,  /* the same letter twice on a line (X1 X2, F1 F2) */
    LSM_E_GC_MODAL_CONFLICT = -87, /* two G (or M) words of one modal group on a line (G0 G1, G20 G21) */
    LSM_E_GC_NO_FEED = -88,        /* G1/G2/G3 while the feed is zero (no F word yet) */
    LSM_E_GC_ARC_MISMATCH = -89,   /* centre-form arc: start and end radii differ beyond tolerance */
    LSM_E_GC_ARC_RADIUS = -90,     /* radius-form arc: R too small for the chord, zero, or end == start */
    LSM_E_GC_ARC_CENTRE = -91,     /* centre-form arc: the centre is on the start or end point (zero radius) */
    LSM_E_GC_ARC_FORM = -92,    /* arc words incomplete or inconsistent (no I/J/K/R, both, wrong plane, no end word) */
    LSM_E_GC_UNUSED_WORD = -93, /* a word no command on the line uses (I without G2, X with G80) */
    LSM_E_GC_UNSUPPORTED = -94, /* a dialect feature outside the subset: # parameters, [expr], O-words */
    LSM_E_GC_COMMENT = -95,     /* an unclosed or nested "(" comment */
    LSM_E_GC_BAD_VALUE = -96,   /* a value outside its domain (negative F or G64 P, P turns not an integer >= 1, ...) */
    LSM_E_GC_NO_AXIS = -97,     /* an axis word for an axis the machine does not have */

    /* CANopen / CiA 402 (can.c, co_*.c, canopen.c, cia402.c) */
    LSM_E_CO_NODE_ID = -100,   /* a CANopen node id outside 1..127 */
    LSM_E_CO_OD = -101,        /* the object-dictionary table is inconsistent (type, size, offset, duplicate, hook) */
    LSM_E_CO_FRAME = -102,     /* a received frame is malformed (wrong DLC for its protocol, RTR, 29-bit id); ignored */
    LSM_E_CO_MAPPING = -103,   /* a PDO mapping is invalid (object not mappable, longer than 64 bits) */
    LSM_E_CO_AXES = -104,      /* the axis count is outside 1..LSM_MAX_AXES */
    LSM_E_CO_SEQ_GAP = -105,   /* a path block skips sequence numbers; it was not stored */
    LSM_E_CO_SEQ_DUP = -106,   /* a path block repeats an accepted sequence number; discarded, not applied twice */
    LSM_E_CO_BLOCK = -107,     /* a path block is malformed (length, type, plane, zero feed or tolerance, geometry) */
    LSM_E_CO_NMT_STATE = -108, /* the frame's service is not allowed in the present NMT state; ignored */
    LSM_E_CO_BUS_OFF = -109,   /* the CAN controller is bus-off: nothing is queued until it recovers */

    /* ports (firmware/port/lsm_port.h) */
    LSM_E_PORT_IO = -120,          /* the board's hardware or the OS reported an error (port) */
    LSM_E_PORT_UNSUPPORTED = -121, /* this board has no such facility, or the port leaves it blank */

    /* internal faults */
    LSM_E_INTERNAL = -200 /* an internal consistency check failed (a bug) */
} lsm_status;

/* A short, constant, human-readable name for a status code (never NULL). */
const char *lsm_status_str(lsm_status st);

#endif /* LSM_STATUS_H */
