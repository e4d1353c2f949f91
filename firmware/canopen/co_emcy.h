/*
 * co_emcy.h: EMCY producer, error register 0x1001 and pre-defined error field 0x1003 (CiA 301 §7.2.7).
 *
 * Model. An EMCY frame (COB-ID 0x80 + node id, 8 bytes) carries
 *     bytes 0-1  error code (CiA 301 Table 21, CiA 402 Table 4), little-endian
 *     byte  2    the error register 0x1001 after the event
 *     byte  3    `info`: the axis (0..5) for per-axis errors, 0xFF for the whole node        (manufacturer)
 *     bytes 4-7  `extra`: e.g. the path block sequence number or the count that overflowed  (manufacturer)
 * Two kinds of errors:
 *   - conditions (lsm_co_emcy_raise / lsm_co_emcy_clear): stay active until cleared, latch their error
 *     register bits; when the last one clears, an "error reset" EMCY (code 0x0000, register 0) is sent;
 *   - events (lsm_co_emcy_event): a one-shot frame (a malformed PDO, a recovered bus-off), not latched.
 * Raising a condition that is already active (same code and info) sends nothing: no EMCY storms.
 * Every frame sent is also pushed at the front of the 0x1003 history (newest at sub-index 1,
 * UNSIGNED32 = info << 16 | code; sub-index 0 = number of entries, writing 0 clears it).
 * EMCY frames are only sent in PRE-OPERATIONAL and OPERATIONAL (the caller passes can_send); errors raised
 * in STOPPED or during bus-off are latched and recorded but their frame is not sent.
 * Bit 0 (generic) of the error register is set whenever any condition is active.
 * Contexts: EMCY is the tick's (canopen.h, "Contexts"): every call here.
 */
#ifndef LSM_CO_EMCY_H
#define LSM_CO_EMCY_H

#include "can.h"

/* Compile-time settings (LSM_CO_EMCY_HISTORY, LSM_CO_EMCY_ACTIVE): lsm_config.h. */

/* Error register bits (0x1001). */
#define LSM_CO_ERREG_GENERIC 0x01u
#define LSM_CO_ERREG_CURRENT 0x02u
#define LSM_CO_ERREG_VOLTAGE 0x04u
#define LSM_CO_ERREG_TEMPERATURE 0x08u
#define LSM_CO_ERREG_COMM 0x10u
#define LSM_CO_ERREG_PROFILE 0x20u
#define LSM_CO_ERREG_MANUFACTURER 0x80u

/* Error codes the layer uses. */
#define LSM_CO_EMCY_NO_ERROR 0x0000u            /* error reset / no error */
#define LSM_CO_EMCY_SOFTWARE 0x6100u            /* internal software (the application reported a fault) */
#define LSM_CO_EMCY_COMM 0x8100u                /* communication, generic: latched while the controller is bus-off */
#define LSM_CO_EMCY_CAN_OVERRUN 0x8110u         /* CAN overrun: frames lost (TX queue full, port RX overrun) */
#define LSM_CO_EMCY_CAN_PASSIVE 0x8120u         /* CAN in error passive mode */
#define LSM_CO_EMCY_HEARTBEAT 0x8130u           /* life guard or heartbeat error */
#define LSM_CO_EMCY_BUS_OFF_RECOVERED 0x8140u   /* recovered from bus off */
#define LSM_CO_EMCY_PDO_LENGTH 0x8210u          /* PDO not processed due to length error */
#define LSM_CO_EMCY_PDO_LENGTH_EXCEEDED 0x8220u /* PDO length exceeded (processed, extra bytes ignored) */
#define LSM_CO_EMCY_SYNC_LENGTH 0x8240u         /* unexpected SYNC data length */
#define LSM_CO_EMCY_FOLLOWING_ERROR 0x8611u     /* CiA 402: following error */
#define LSM_CO_EMCY_EXTERNAL 0x9000u            /* external error: the E-stop input */
#define LSM_CO_EMCY_PATH_REJECTED 0xFF01u /* manufacturer: the planner refused a path block (extra = its sequence) */

typedef struct lsm_co_emcy_cond {
    uint16_t code;
    uint8_t reg; /* error register bits it latches */
    uint8_t info;
} lsm_co_emcy_cond;

typedef struct lsm_co_emcy {
    uint32_t cob_id;        /* 0x1014: 0x80 + node id */
    uint8_t error_register; /* 0x1001 */
    uint8_t n_history;      /* 0x1003 sub 0 */
    uint8_t n_active;
    uint8_t overflow; /* conditions that did not fit in `active` (their register bits stay latched) */
    uint8_t overflow_reg;
    uint32_t history[LSM_CO_EMCY_HISTORY]; /* 0x1003 sub 1.., newest first */
    lsm_co_emcy_cond active[LSM_CO_EMCY_ACTIVE];
    uint32_t sent;       /* EMCY frames queued (wraps) */
    uint32_t suppressed; /* frames not sent: NMT state, bus-off or full queue (wraps) */
} lsm_co_emcy;

/* Errors: LSM_E_NULL, LSM_E_CO_NODE_ID. Tick. */
lsm_status lsm_co_emcy_init(lsm_co_emcy *emcy, uint8_t node_id);

/* Raises a condition. Returns LSM_OK (also when already active), or the txq status. Tick. */
lsm_status lsm_co_emcy_raise(lsm_co_emcy *emcy, uint16_t code, uint8_t reg_bits, uint8_t info, uint32_t extra,
                             bool can_send, lsm_can_txq *txq);

/* Clears a condition; sends the error-reset EMCY when none is left. LSM_OK also when it was not active. Tick. */
lsm_status lsm_co_emcy_clear(lsm_co_emcy *emcy, uint16_t code, uint8_t info, bool can_send, lsm_can_txq *txq);

/* A one-shot event: one frame (register shows reg_bits for this frame only), recorded in 0x1003. Tick. */
lsm_status lsm_co_emcy_event(lsm_co_emcy *emcy, uint16_t code, uint8_t reg_bits, uint8_t info, uint32_t extra,
                             bool can_send, lsm_can_txq *txq);

/* Tick. */
bool lsm_co_emcy_is_active(const lsm_co_emcy *emcy, uint16_t code, uint8_t info);

/* 0x1003 sub 0 write: 0 clears the history; anything else is 0x06090030. Tick. */
uint32_t lsm_co_emcy_write_history_count(lsm_co_emcy *emcy, int64_t value);

#endif /* LSM_CO_EMCY_H */
