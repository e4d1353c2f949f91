#include "status.h"

const char *lsm_status_str(lsm_status st)
{
    switch (st) {
    case LSM_OK: return "ok";
    case LSM_E_NULL: return "null pointer";
    case LSM_E_NAN: return "input is NaN";
    case LSM_E_INF: return "input is infinite";
    case LSM_E_LIMIT: return "limit is zero or negative";
    case LSM_E_CYCLE: return "control cycle is zero or negative";
    case LSM_E_NEG_FEED: return "feed is negative";
    case LSM_E_RANGE: return "value too large to represent";
    case LSM_E_ZERO_LENGTH: return "zero-length move";
    case LSM_E_FULL: return "buffer full";
    case LSM_E_EMPTY: return "buffer empty";
    case LSM_E_ARG: return "argument out of range";
    case LSM_E_TOLERANCE: return "tolerance is zero or negative";
    case LSM_E_STATE: return "invalid in current state";
    case LSM_E_FEED_ABOVE_VMAX: return "start or end feed above v_max";
    case LSM_E_INFEASIBLE: return "distance too short for the requested feeds within the limits";
    case LSM_E_TOO_LONG: return "move too long for the cycle counter";
    case LSM_E_FIT_LINE: return "clothoid fit: degenerate line (A = B = 0)";
    case LSM_E_FIT_ON_LINE: return "clothoid fit: start point on the line";
    case LSM_E_FIT_NO_SOLUTION: return "clothoid fit: no solution within reach";
    case LSM_E_NOT_CONVERGED: return "iteration did not converge";
    case LSM_E_COLLINEAR: return "no corner: blocks already join G2 (nothing to smooth)";
    case LSM_E_REVERSAL: return "corner is an exact reversal";
    case LSM_E_NONPLANAR: return "corner or contour not planar (or helical arc)";
    case LSM_E_ROTARY: return "rotary axes move at the corner";
    case LSM_E_CORNER_NO_SOLUTION: return "no corner transition within the trim limits";
    case LSM_E_GAP: return "blocks do not connect";
    case LSM_E_ARC_GEOMETRY: return "inconsistent arc geometry";
    case LSM_E_TOL_UNREACHED: return "tolerance not reached within the segment capacity";
    case LSM_E_PL_AXIS: return "planner: block moves an axis the machine does not have";
    case LSM_E_PL_FINISHED: return "planner: block appended after the end of the program";
    case LSM_E_PL_CAPACITY: return "planner: block storage too small";
    case LSM_E_PL_OVERRIDE: return "feed override outside 0 .. 200 %";
    case LSM_E_PL_OVR_LATER: return "feed override not applied yet (the machine cannot follow it from here)";
    case LSM_E_GC_UNKNOWN_WORD: return "G-code: unknown word";
    case LSM_E_GC_MISSING_ARG: return "G-code: word without a number";
    case LSM_E_GC_SYNTAX: return "G-code: syntax error";
    case LSM_E_GC_NUMBER_RANGE: return "G-code: number too large to represent";
    case LSM_E_GC_LINE_TOO_LONG: return "G-code: line too long";
    case LSM_E_GC_BINARY: return "G-code: binary or non-printable byte";
    case LSM_E_GC_WORD_REPEATED: return "G-code: word repeated on one line";
    case LSM_E_GC_MODAL_CONFLICT: return "G-code: two words of one modal group";
    case LSM_E_GC_NO_FEED: return "G-code: feed move with zero feed (no F)";
    case LSM_E_GC_ARC_MISMATCH: return "G-code: arc start and end radii differ";
    case LSM_E_GC_ARC_RADIUS: return "G-code: bad arc radius (R form)";
    case LSM_E_GC_ARC_CENTRE: return "G-code: arc centre on its start or end point";
    case LSM_E_GC_ARC_FORM: return "G-code: arc words incomplete or inconsistent";
    case LSM_E_GC_UNUSED_WORD: return "G-code: word not used by any command";
    case LSM_E_GC_UNSUPPORTED: return "G-code: unsupported dialect feature";
    case LSM_E_GC_COMMENT: return "G-code: unclosed or nested comment";
    case LSM_E_GC_BAD_VALUE: return "G-code: value out of range for its word";
    case LSM_E_GC_NO_AXIS: return "G-code: axis not present on this machine";
    case LSM_E_CO_NODE_ID: return "CANopen: node id outside 1..127";
    case LSM_E_CO_OD: return "CANopen: inconsistent object dictionary table";
    case LSM_E_CO_FRAME: return "CANopen: malformed frame ignored";
    case LSM_E_CO_MAPPING: return "CANopen: invalid PDO mapping";
    case LSM_E_CO_AXES: return "CANopen: axis count outside 1..LSM_MAX_AXES";
    case LSM_E_CO_SEQ_GAP: return "CANopen: path block sequence gap";
    case LSM_E_CO_SEQ_DUP: return "CANopen: duplicate path block discarded";
    case LSM_E_CO_BLOCK: return "CANopen: malformed path block";
    case LSM_E_CO_NMT_STATE: return "CANopen: service not allowed in this NMT state";
    case LSM_E_CO_BUS_OFF: return "CANopen: bus-off";
    case LSM_E_PORT_IO: return "port: hardware or OS error";
    case LSM_E_PORT_UNSUPPORTED: return "port: not supported by this board";
    case LSM_E_INTERNAL: return "internal fault";
    }
    return "unknown status";
}
