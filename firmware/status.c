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
    case LSM_E_INTERNAL: return "internal fault";
    }
    return "unknown status";
}
