/*
 * cia402.h: one CiA 402 axis: the drive state machine, Profile Position and Cyclic Synchronous Position
 * hand-shakes, and the objects of the axis (CiA 402-2 §6-§12). The motion itself is not computed here:
 * the application polls this module for set-points and stop requests and reports back the positions.
 *
 * State machine (controlword 0x6040 -> statusword 0x6041, CiA 402-2 Figure 6 / Table 6):
 *
 *   NOT READY TO SWITCH ON --1 (automatic, at init)--> SWITCH ON DISABLED
 *   SWITCH ON DISABLED --2 shutdown (xxxx x110)--> READY TO SWITCH ON
 *   READY TO SWITCH ON --3 switch on (0111)--> SWITCHED ON            (1111 does 3 then 4)
 *   SWITCHED ON --4 enable operation (1111)--> OPERATION ENABLED
 *   OPERATION ENABLED --5 disable operation (0111)--> SWITCHED ON         } after a jerk-limited stop with
 *   OPERATION ENABLED --8 shutdown--> READY TO SWITCH ON                   } the profile deceleration 0x6084
 *   OPERATION ENABLED --9 disable voltage (xxxx xx0x)--> SWITCH ON DISABLED  after a quick stop (0x6085)
 *   SWITCHED ON --6 shutdown--> READY TO SWITCH ON;  --10 disable voltage / quick stop--> SWITCH ON DISABLED
 *   READY TO SWITCH ON --7 disable voltage / quick stop--> SWITCH ON DISABLED
 *   OPERATION ENABLED --11 quick stop (xxxx x01x)--> QUICK STOP ACTIVE  (stop per 0x605A:
 *       1 slow-down ramp then 12, 2 quick-stop ramp then 12, 5 slow-down ramp and stay, 6 quick-stop ramp and stay)
 *   QUICK STOP ACTIVE --12 (after the stop, options 1/2; or disable voltage)--> SWITCH ON DISABLED
 *   QUICK STOP ACTIVE --16 enable operation (options 5/6)--> OPERATION ENABLED
 *   any --13 fault--> FAULT REACTION ACTIVE --14 (at standstill)--> FAULT --15 fault reset (bit 7 rising)--> SOD
 *
 * Every way out of motion waits for the application to report standstill (lsm_cia402_update): the
 * statusword keeps OPERATION ENABLED (resp. QUICK STOP ACTIVE, FAULT REACTION ACTIVE) until then, and
 * bit 14 (manufacturer) says a stop is in progress. Stop options that would let the axis coast (0x605A 0,
 * 3, 4, 7, 8) are refused: motion always stops with limited jerk.
 *
 * Statusword: bits 0-3, 5, 6 give the state (as in the diagram), bit 4 voltage enabled (RTSO, SO, OE,
 * QSA), bit 9 remote (always 1), bit 10 target reached, bit 11 internal limit active (a relative set-point
 * overflowed 32 bits), bit 12 PP: set-point acknowledge / CSP: following the command value, bit 13 following
 * error, bit 14 stop in progress.
 *
 * Modes of operation 0x6060 (display 0x6061; the display switches when the axis is at rest):
 *   0 no mode (no motion), 1 Profile Position (PP), 8 Cyclic Synchronous Position (CSP),
 *   -1 coordinated path (manufacturer-specific: the axis follows co_path.h's planner).
 *
 * Profile Position (CiA 402-2 §12). Controlword bit 4 new set-point (rising edge), bit 5 change set
 * immediately, bit 6 relative (to the previous target), bit 8 halt, bit 9 change on set-point (blend).
 * At the rising edge the set-point is captured with the profile values of that moment: target 0x607A,
 * profile velocity 0x6081, acceleration 0x6083, deceleration 0x6084, motion profile type 0x6086
 * (0 linear ramp = trapezoidal acceleration with a constant-jerk ramp, 1 sin² ramp), jerk 0x2060 and snap
 * 0x2061 (manufacturer). The buffer holds an active and one next set-point:
 *   bit 5 = 1 (single set-point): the new set-point replaces everything at once (REPLACE for the application);
 *   bit 5 = 0 (set of set-points): it becomes active if none is, else it waits as next; with both taken the
 *                edge is ignored (not acknowledged) and counted.
 * Set-point acknowledge (statusword bit 12) rises when a set-point is taken, and falls when bit 4 is 0 and
 * the next slot is free (CiA 402-2 Figure 41/42). Target reached (bit 10): no set-point left, standstill
 * and |target - actual| <= position window 0x6067; with halt: standstill.
 *
 * Cyclic Synchronous Position (CiA 402-2 §16): every write of 0x607A (normally by a synchronous RPDO,
 * applied at SYNC) is passed to the application unchanged (lsm_cia402_csp_fetch), which interpolates over
 * the SYNC period (0x60C2 = value·10^index s). Bit 12 = 1 while the axis follows.
 *
 * Following error 0x60F4 = demand 0x6062 - actual 0x6064. Beyond the window 0x6065 (0xFFFFFFFF = off) for
 * longer than 0x6066 ms: bit 13 and fault 0x8611 (fault reaction: emergency stop).
 *
 * Units: positions in counts (0x2001 counts per mm: 1000 means 1 count = 1 µm), velocity counts/s,
 * acceleration counts/s², jerk counts/s³, snap counts/s⁴, time in ms on the bus and µs in the API.
 * Contexts: the axes are the tick's (canopen.h, "Contexts"): every call here, the object writes included (an SDO write
 * of the controlword or a target is applied by the tick, as an access the background's SDO server posted; co_sdo.h).
 */
#ifndef LSM_CIA402_H
#define LSM_CIA402_H

#include "lsm_config.h"
#include "status.h"

typedef enum lsm_cia402_state {
    LSM_CIA402_NOT_READY = 0, /* NOT READY TO SWITCH ON */
    LSM_CIA402_SWITCH_ON_DISABLED = 1,
    LSM_CIA402_READY_TO_SWITCH_ON = 2,
    LSM_CIA402_SWITCHED_ON = 3,
    LSM_CIA402_OPERATION_ENABLED = 4,
    LSM_CIA402_QUICK_STOP_ACTIVE = 5,
    LSM_CIA402_FAULT_REACTION_ACTIVE = 6,
    LSM_CIA402_FAULT = 7
} lsm_cia402_state;

#define LSM_CIA402_MODE_NONE 0
#define LSM_CIA402_MODE_PP 1
#define LSM_CIA402_MODE_CSP 8
#define LSM_CIA402_MODE_PATH (-1)

/* 0x6502 supported drive modes: PP (bit 0), CSP (bit 7), path (bit 16, manufacturer). */
#define LSM_CIA402_SUPPORTED_MODES 0x00010081u

/* Controlword bits. */
#define LSM_CIA402_CW_SWITCH_ON 0x0001u
#define LSM_CIA402_CW_ENABLE_VOLTAGE 0x0002u
#define LSM_CIA402_CW_QUICK_STOP 0x0004u /* active low */
#define LSM_CIA402_CW_ENABLE_OPERATION 0x0008u
#define LSM_CIA402_CW_NEW_SETPOINT 0x0010u
#define LSM_CIA402_CW_IMMEDIATE 0x0020u
#define LSM_CIA402_CW_RELATIVE 0x0040u
#define LSM_CIA402_CW_FAULT_RESET 0x0080u
#define LSM_CIA402_CW_HALT 0x0100u
#define LSM_CIA402_CW_CHANGE_ON_SETPOINT 0x0200u

/* Statusword bits. */
#define LSM_CIA402_SW_READY 0x0001u
#define LSM_CIA402_SW_SWITCHED_ON 0x0002u
#define LSM_CIA402_SW_OP_ENABLED 0x0004u
#define LSM_CIA402_SW_FAULT 0x0008u
#define LSM_CIA402_SW_VOLTAGE 0x0010u
#define LSM_CIA402_SW_QUICK_STOP 0x0020u /* 0 = quick stop active */
#define LSM_CIA402_SW_SOD 0x0040u
#define LSM_CIA402_SW_WARNING 0x0080u
#define LSM_CIA402_SW_REMOTE 0x0200u
#define LSM_CIA402_SW_TARGET_REACHED 0x0400u
#define LSM_CIA402_SW_LIMIT 0x0800u
#define LSM_CIA402_SW_ACK 0x1000u /* PP: set-point acknowledge; CSP: following the command */
#define LSM_CIA402_SW_FOLLOWING_ERROR 0x2000u
#define LSM_CIA402_SW_STOPPING 0x4000u /* manufacturer: a stop is in progress */

/* How the application must stop the axis (strongest first: EMERGENCY > QUICK > SLOW > HALT). */
typedef enum lsm_cia402_stop {
    LSM_CIA402_STOP_NONE = 0,     /* motion allowed */
    LSM_CIA402_STOP_HALT = 1,     /* halt bit: stop with decel (0x6084), stay enabled, resume when released */
    LSM_CIA402_STOP_SLOW = 2,     /* disable operation / shutdown, quick stop options 1/5: decel 0x6084 */
    LSM_CIA402_STOP_QUICK = 3,    /* quick stop options 2/6, disable voltage, lost connection: decel 0x6085 */
    LSM_CIA402_STOP_EMERGENCY = 4 /* fault reaction (E-stop, following error, application fault): the fastest
                                       jerk-limited stop the machine can do; decel 0x6085 is a lower bound */
} lsm_cia402_stop;

typedef struct lsm_cia402_stop_req {
    uint8_t kind;   /* lsm_cia402_stop */
    uint32_t decel; /* counts/s² */
    uint64_t jerk;  /* counts/s³ (0x2060) */
} lsm_cia402_stop_req;

/* One Profile Position set-point, captured at the new-set-point edge. */
typedef struct lsm_cia402_setpoint {
    int32_t target;       /* absolute counts (relative set-points already added to the previous target) */
    uint32_t velocity;    /* counts/s, 0x6081 */
    uint32_t accel;       /* counts/s², 0x6083 */
    uint32_t decel;       /* counts/s², 0x6084 */
    uint64_t jerk;        /* counts/s³, 0x2060 */
    uint64_t snap;        /* counts/s⁴, 0x2061 */
    int16_t profile_type; /* 0x6086: 0 linear (trapezoidal acceleration), 1 sin² */
    bool blend;           /* bit 9: pass this target without stopping when a next set-point exists */
    uint16_t id;          /* running number of accepted set-points */
} lsm_cia402_setpoint;

typedef enum lsm_cia402_sp_event {
    LSM_CIA402_SP_NONE = 0,   /* nothing new */
    LSM_CIA402_SP_START = 1,  /* no move was running: start one to sp */
    LSM_CIA402_SP_REPLACE = 2 /* abandon the running move and go to sp from the present state
                                   (change set immediately, or resume after halt) */
} lsm_cia402_sp_event;

/* What the application reports each cycle. */
typedef struct lsm_cia402_feedback {
    int32_t demand;   /* counts: position the profile generator commands now (0x6062) */
    int32_t actual;   /* counts: measured position (0x6064) */
    int32_t velocity; /* counts/s (0x606C) */
    bool standstill;  /* the commanded motion is at rest (no move running, v = a = 0) */
} lsm_cia402_feedback;

#define LSM_CIA402_EVENTS 4

/* Per-axis EMCY events for the node: raise (code) or clear (code). */
typedef struct lsm_cia402_event {
    uint16_t code;
    bool raise;
} lsm_cia402_event;

typedef struct lsm_cia402 {
    /* object values (instance k at index + 0x800·k) */
    uint16_t controlword;      /* 0x6040 */
    uint16_t statusword;       /* 0x6041 */
    uint16_t error_code;       /* 0x603F: code of the present fault, 0 if none */
    int16_t abort_option;      /* 0x6007: on lost connection 0 none, 1 fault, 2 disable voltage, 3 quick stop */
    int16_t quick_stop_option; /* 0x605A: 1, 2, 5, 6 */
    int16_t profile_type;      /* 0x6086: 0 linear, 1 sin² */
    int8_t mode;               /* 0x6060 */
    int8_t mode_display;       /* 0x6061 */
    uint8_t ip_period_value;   /* 0x60C2 sub 1 */
    int8_t ip_period_index;    /* 0x60C2 sub 2: period = value · 10^index s */
    uint16_t fe_timeout_ms;    /* 0x6066 */
    int32_t target;            /* 0x607A */
    int32_t pos_demand;        /* 0x6062 */
    int32_t pos_actual;        /* 0x6064 */
    int32_t vel_actual;        /* 0x606C */
    int32_t fe_actual;         /* 0x60F4 */
    uint32_t fe_window;        /* 0x6065, 0xFFFFFFFF = monitoring off */
    uint32_t pos_window;       /* 0x6067 */
    uint32_t profile_velocity; /* 0x6081 */
    uint32_t profile_accel;    /* 0x6083 */
    uint32_t profile_decel;    /* 0x6084 */
    uint32_t quick_stop_decel; /* 0x6085 */
    uint32_t counts_per_mm;    /* 0x2001 */
    uint64_t profile_jerk;     /* 0x2060 */
    uint64_t profile_snap;     /* 0x2061 */
    /* runtime */
    uint8_t state;        /* lsm_cia402_state */
    uint8_t pending;      /* state to enter at standstill, or 0xFF */
    uint8_t pending_stop; /* stop kind of the pending transition */
    uint8_t n_events;
    bool standstill;
    bool fault_hold;     /* a fault reset is refused while set (E-stop input active) */
    bool fault_reported; /* the present fault has an EMCY to clear at reset */
    bool have_active, have_next, fresh, replace, ack, limit;
    bool csp_new;
    bool fe_over;
    uint32_t fe_since_us;
    uint16_t sp_count;
    uint16_t sp_ignored; /* new-set-point edges ignored because the buffer was full (wraps) */
    int32_t last_target; /* reference of relative set-points */
    lsm_cia402_setpoint sp_active, sp_next;
    lsm_cia402_event events[LSM_CIA402_EVENTS];
} lsm_cia402;

/* Defaults (documented in docs/canopen.md), state SWITCH ON DISABLED. Errors: LSM_E_NULL. Tick. */
lsm_status lsm_cia402_init(lsm_cia402 *ax);

/* OD hook for the axis objects; `index` is the instance-0 index (0x6040, 0x2001, ...). Stores the value
 * after its checks. Returns 0 or the abort code (0x06090030 unsupported enumeration value, 0x08000022
 * scaling changed while the axis is powered, 0x06020000 an index this module does not serve).
 * now_us is the time of the write (not used by the present objects). Tick. */
uint32_t lsm_cia402_od_write(lsm_cia402 *ax, uint16_t index, uint8_t sub, int64_t value, uint32_t now_us);

/* Application side, each cycle. Tick (canopen.h: the node is the tick's), as every call here. */
void lsm_cia402_update(lsm_cia402 *ax, const lsm_cia402_feedback *fb, uint32_t now_us);
lsm_cia402_sp_event lsm_cia402_pp_fetch(lsm_cia402 *ax, lsm_cia402_setpoint *sp);
bool lsm_cia402_pp_peek_next(const lsm_cia402 *ax, lsm_cia402_setpoint *sp);
void lsm_cia402_pp_done(lsm_cia402 *ax);
bool lsm_cia402_csp_fetch(lsm_cia402 *ax, int32_t *target);
lsm_cia402_stop lsm_cia402_stop_request(const lsm_cia402 *ax, lsm_cia402_stop_req *req);
bool lsm_cia402_motion_allowed(const lsm_cia402 *ax);
bool lsm_cia402_power_enabled(const lsm_cia402 *ax); /* drive-enable output: OE, QSA, FRA */
bool lsm_cia402_in_position(const lsm_cia402 *ax);   /* in-position output */
lsm_cia402_state lsm_cia402_get_state(const lsm_cia402 *ax);

/* Faults and node events. lsm_cia402_fault: fault reaction with `code` in 0x603F (first fault wins);
 * report = true queues an EMCY raise now and a clear at the fault reset. Tick. */
void lsm_cia402_fault(lsm_cia402 *ax, uint16_t code, bool report);
void lsm_cia402_set_fault_hold(lsm_cia402 *ax, bool hold);
/* Lost connection (master heartbeat, bus-off, leaving OPERATIONAL): the 0x6007 action; fault code 0x8130. Tick. */
void lsm_cia402_comm_lost(lsm_cia402 *ax);
/* Pops one EMCY event; false when none. Tick. */
bool lsm_cia402_take_event(lsm_cia402 *ax, lsm_cia402_event *ev);

#endif /* LSM_CIA402_H */
