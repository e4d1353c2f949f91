/*
 * co_nmt.h: NMT slave state machine, heartbeat producer and heartbeat consumers (CiA 301 §7.2.8, §7.3.2).
 *
 * Model. States and the value they send in a heartbeat (CiA 301 Table 52):
 *
 *     power-on --> INITIALISATION (0x00) --boot-up msg--> PRE-OPERATIONAL (0x7F)
 *                       ^   reset node (0x81) / reset communication (0x82) from any state
 *     PRE-OPERATIONAL --start (0x01)--> OPERATIONAL (0x05) --enter pre-op (0x80)--> PRE-OPERATIONAL
 *     any of the three --stop (0x02)--> STOPPED (0x04) --start / enter pre-op--> ...
 *
 * NMT commands arrive on COB-ID 0x000 with 2 data bytes: command, node id (0 = every node). A frame with
 * another DLC is malformed and ignored. This module only decodes the command; the node (canopen.c) applies
 * it, because a reset must first bring the motion to a jerk-limited stop.
 *
 * Heartbeat producer (0x1017, period in ms, 0 = off): one frame 0x700 + node id with the state byte every
 * period, the first one a period after boot-up (the boot-up frame itself is the state 0x00 heartbeat).
 * Heartbeat consumers (0x1016 sub 1..LSM_CO_HB_CONSUMERS, UNSIGNED32 = node id << 16 | time in ms):
 * monitoring of a node starts with its first heartbeat; when no heartbeat arrives for longer than the
 * consumer time (now - last > time, wrap-safe) the consumer is LOST and lsm_co_nmt_process reports it once.
 * A heartbeat after a loss reports RESUMED. Frames with a DLC other than 1 are malformed and do not count.
 * CiA 301 forbids two consumer entries with the same node id and a non-zero time: refused with 0x06040043.
 * Time: now_us is a free-running 32-bit microsecond clock, compared wrap-safe.
 * Contexts: NMT and heartbeats are the tick's (canopen.h, "Contexts"): every call here. An NMT state change that
 * drops SDO transfers reaches the background's SDO server through the node's SDO epoch (canopen.h).
 */
#ifndef LSM_CO_NMT_H
#define LSM_CO_NMT_H

#include "can.h"
#include "co_od.h"

/* Compile-time settings (LSM_CO_HB_CONSUMERS): lsm_config.h. */

typedef enum lsm_co_nmt_state {
    LSM_CO_NMT_INITIALISING = 0x00,
    LSM_CO_NMT_STOPPED = 0x04,
    LSM_CO_NMT_OPERATIONAL = 0x05,
    LSM_CO_NMT_PRE_OPERATIONAL = 0x7F
} lsm_co_nmt_state;

typedef enum lsm_co_nmt_cmd {
    LSM_CO_NMT_CMD_NONE = 0x00,
    LSM_CO_NMT_CMD_START = 0x01,
    LSM_CO_NMT_CMD_STOP = 0x02,
    LSM_CO_NMT_CMD_PRE_OPERATIONAL = 0x80,
    LSM_CO_NMT_CMD_RESET_NODE = 0x81,
    LSM_CO_NMT_CMD_RESET_COMM = 0x82
} lsm_co_nmt_cmd;

typedef enum lsm_co_hb_status {
    LSM_CO_HB_OFF = 0,     /* entry disabled (node id 0 or time 0) */
    LSM_CO_HB_WAITING = 1, /* configured, no heartbeat seen yet: not monitored */
    LSM_CO_HB_ACTIVE = 2,  /* heartbeats arrive in time */
    LSM_CO_HB_LOST = 3     /* timed out */
} lsm_co_hb_status;

typedef struct lsm_co_hb_consumer {
    uint32_t param;       /* 0x1016 value: node id << 16 | time ms */
    uint32_t last_us;     /* arrival of the last heartbeat */
    uint8_t status;       /* lsm_co_hb_status */
    uint8_t remote_state; /* state byte of the last heartbeat */
} lsm_co_hb_consumer;

typedef struct lsm_co_nmt {
    uint8_t node_id;
    uint8_t state;        /* lsm_co_nmt_state */
    uint16_t producer_ms; /* 0x1017 */
    uint32_t next_hb_us;  /* when the next heartbeat is due */
    uint32_t malformed;   /* NMT or heartbeat frames with a wrong DLC (wraps) */
    lsm_co_hb_consumer cons[LSM_CO_HB_CONSUMERS];
} lsm_co_nmt;

/* State INITIALISING, producer period producer_ms, every consumer off. Errors: LSM_E_NULL, LSM_E_CO_NODE_ID. Tick. */
lsm_status lsm_co_nmt_init(lsm_co_nmt *nmt, uint8_t node_id, uint16_t producer_ms);

/* Sends the boot-up frame (0x700 + id, one byte 0x00), enters PRE-OPERATIONAL, restarts the heartbeat
 * timer and re-arms every configured consumer (WAITING). Returns the txq push status. Tick. */
lsm_status lsm_co_nmt_boot(lsm_co_nmt *nmt, uint32_t now_us, lsm_can_txq *txq);

/* Decodes an NMT command frame (id 0x000). Returns the command when it addresses this node and is known,
 * else LSM_CO_NMT_CMD_NONE; *st is LSM_E_CO_FRAME for a malformed frame (DLC != 2, RTR), else LSM_OK. Tick. */
lsm_co_nmt_cmd lsm_co_nmt_decode(lsm_co_nmt *nmt, const lsm_can_frame *f, lsm_status *st);

/* Sets the state (the node calls it after deciding how to apply a command). Tick. */
void lsm_co_nmt_set_state(lsm_co_nmt *nmt, lsm_co_nmt_state state);

/* 0x1017 write: new period (0 = off); the next heartbeat is due one period from now. Tick. */
void lsm_co_nmt_set_producer(lsm_co_nmt *nmt, uint16_t period_ms, uint32_t now_us);

/* 0x1016 sub (i + 1) write. Returns 0 or an abort code (0x06090030 bits 24..31 set or node id > 127,
 * 0x06040043 same node id as another active entry). The entry restarts in WAITING. Tick. */
uint32_t lsm_co_nmt_set_consumer(lsm_co_nmt *nmt, size_t i, uint32_t param);

/* True if f->id is 0x700 + the node id of an enabled consumer entry. Tick. */
bool lsm_co_nmt_is_consumed(const lsm_co_nmt *nmt, uint32_t id);

/* Serves a heartbeat frame from a monitored node. Returns a bit mask of the consumer entries that were
 * LOST and are ACTIVE again (bit i = entry i); *st is LSM_E_CO_FRAME for a DLC other than 1. Tick. */
uint32_t lsm_co_nmt_rx_heartbeat(lsm_co_nmt *nmt, const lsm_can_frame *f, uint32_t now_us, lsm_status *st);

/* Sends the heartbeat when due and checks the consumers. Returns a bit mask of the entries that timed out
 * in this call (each loss is reported once). Tick. */
uint32_t lsm_co_nmt_process(lsm_co_nmt *nmt, uint32_t now_us, lsm_can_txq *txq);

#endif /* LSM_CO_NMT_H */
