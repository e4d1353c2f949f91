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
    LSM_E_NULL = -1,            /* a required pointer is NULL */
    LSM_E_NAN = -2,             /* an input is NaN */
    LSM_E_INF = -3,             /* an input is +/-infinity */
    LSM_E_LIMIT = -4,           /* a limit (v, a, j or snap) is zero or negative */
    LSM_E_CYCLE = -5,           /* the control cycle is zero or negative */
    LSM_E_NEG_FEED = -6,        /* a feed (velocity) is negative */
    LSM_E_RANGE = -7,           /* a value is too large to represent (distance, cycle count, counts) */
    LSM_E_ZERO_LENGTH = -8,     /* a move or block has zero length */
    LSM_E_FULL = -9,            /* a buffer is full; nothing was stored */
    LSM_E_EMPTY = -10,          /* a buffer is empty */
    LSM_E_ARG = -11,            /* an argument is out of its documented domain (enum, count, index) */
    LSM_E_TOLERANCE = -12,      /* a tolerance is zero or negative */
    LSM_E_STATE = -13,          /* the call is not valid in the object's current state */

    /* S-curve and moves */
    LSM_E_FEED_ABOVE_VMAX = -20,  /* a start or end feed exceeds the cruise limit v_max */
    LSM_E_INFEASIBLE = -21,       /* the distance is too short to go from v0 to v1 within the limits */
    LSM_E_TOO_LONG = -22,         /* the move needs more cycles than a 32-bit cycle counter holds */

    /* internal faults */
    LSM_E_INTERNAL = -200         /* an internal consistency check failed (a bug) */
} lsm_status;

/* A short, constant, human-readable name for a status code (never NULL). */
const char *lsm_status_str(lsm_status st);

#endif /* LSM_STATUS_H */
