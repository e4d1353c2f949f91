/*
 * can.h: the classic CAN frame of the core, a small transmit queue, and little-endian byte helpers.
 *
 * Model. The CANopen layer (canopen.h and the co_*.h modules) never touches a CAN controller: the port
 * hands it received frames (lsm_canopen_rx) and drains the frames it produced from a FIFO queue
 * (lsm_canopen_tx_pop). The queue lives in caller-owned storage (an array of lsm_can_frame), so its RAM
 * is chosen by the application: 16 frames (256 bytes) is plenty for one node at a 1 ms cycle.
 * When the queue is full a new frame is dropped (never an older one), the drop is counted, and the
 * node reports the overrun with an EMCY (0x8110) once room is back.
 *
 * The port interface (firmware/port/lsm_port.h) uses this same frame type, so a port passes frames through
 * unchanged. CANopen (CiA 301) uses 11-bit identifiers only: the layer ignores
 * frames with LSM_CAN_FLAG_EXT or LSM_CAN_FLAG_RTR.
 *
 * CANopen transmits every multi-byte number little-endian (CiA 301 §7.1.2): the lsm_can_get_* /
 * lsm_can_put_* helpers convert without caring about the host's byte order or alignment.
 * Units: none (bytes, identifiers).
 * Contexts: a frame is plain data; a TX queue belongs to one context (the node's to the tick: canopen.h). The SDO
 * server in the background hands its responses to the tick through a ring (canopen.h), never through the queue.
 */
#ifndef LSM_CAN_H
#define LSM_CAN_H

#include "lsm_config.h"
#include "status.h"

#define LSM_CAN_MAX_DLC 8u             /* classic CAN: at most 8 data bytes */
#define LSM_CAN_STD_ID_MAX 0x7FFu      /* largest 11-bit identifier */
#define LSM_CAN_EXT_ID_MAX 0x1FFFFFFFu /* largest 29-bit identifier */
#define LSM_CAN_FLAG_EXT 0x01u         /* flags: the id is a 29-bit extended identifier */
#define LSM_CAN_FLAG_RTR 0x02u         /* flags: remote transmission request (no data bytes) */

/* One classic CAN frame. */
typedef struct lsm_can_frame {
    uint32_t id;     /* identifier: <= LSM_CAN_STD_ID_MAX (CANopen), or 29 bits with LSM_CAN_FLAG_EXT */
    uint8_t dlc;     /* number of data bytes, 0..8 */
    uint8_t flags;   /* LSM_CAN_FLAG_* */
    uint8_t data[8]; /* data bytes; only the first dlc are meaningful */
} lsm_can_frame;

/* A FIFO of frames in caller-owned storage. Fields are read-only for the caller. */
typedef struct lsm_can_txq {
    lsm_can_frame *buf; /* storage, cap frames */
    uint16_t cap;       /* capacity in frames, 1..65535 */
    uint16_t head;      /* index of the oldest frame */
    uint16_t count;     /* frames queued */
    uint32_t dropped;   /* frames refused because the queue was full (wraps) */
} lsm_can_txq;

/* Binds the queue to storage[cap]. Errors: LSM_E_NULL, LSM_E_ARG (cap 0 or > 65535). The queue's owner (the tick
 * for the node's TX queue), before use. */
lsm_status lsm_can_txq_init(lsm_can_txq *q, lsm_can_frame *storage, size_t cap);

/* Appends a copy of *f. LSM_E_FULL when no room (nothing stored, `dropped` counts it). The queue's owner (the tick
 * for the node's TX queue), as every txq call below. */
lsm_status lsm_can_txq_push(lsm_can_txq *q, const lsm_can_frame *f);

/* Removes the oldest frame into *out. Returns false when the queue is empty (*out untouched). The queue's owner. */
bool lsm_can_txq_pop(lsm_can_txq *q, lsm_can_frame *out);

/* Frames queued. The queue's owner. */
size_t lsm_can_txq_count(const lsm_can_txq *q);

/* Drops every queued frame (e.g. at bus-off: stale frames must not go out after recovery). The queue's owner. */
void lsm_can_txq_clear(lsm_can_txq *q);

/* Little-endian access to p[0..n-1]; no alignment needed. Any context (pure). */
uint16_t lsm_can_get_u16(const uint8_t *p);
uint32_t lsm_can_get_u32(const uint8_t *p);
void lsm_can_put_u16(uint8_t *p, uint16_t v);
void lsm_can_put_u32(uint8_t *p, uint32_t v);
/* n = 1..8 bytes, zero-extended / truncated. Any context (pure). */
uint64_t lsm_can_get_le(const uint8_t *p, size_t n);
void lsm_can_put_le(uint8_t *p, uint64_t v, size_t n);

#endif /* LSM_CAN_H */
