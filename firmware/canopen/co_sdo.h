/*
 * co_sdo.h: the CANopen SDO server (CiA 301 §7.2.4): expedited and segmented upload and download.
 *
 * Model. One server channel: requests arrive on COB-ID 0x600 + node id, responses leave on 0x580 + node id,
 * always 8 data bytes. Byte 0 of a request is the command specifier (ccs in bits 7..5):
 *   ccs 1 initiate download  (e = expedited, s = size indicated, n = unused bytes)  -> 0x60
 *   ccs 0 download segment   (t = toggle, n = unused bytes, c = last)              -> 0x20 | t
 *   ccs 2 initiate upload                                                          -> 0x43|n<<2 (expedited)
 *                                                                                     or 0x41 + size (segmented)
 *   ccs 3 upload segment     (t = toggle)                                          -> t | n<<1 | c, 7 data bytes
 *   ccs 4 abort transfer     (from the client: the server drops the transfer, sends nothing)
 * Anything else (block transfer ccs 5/6, or 7) is answered with abort 0x05040001.
 *
 * Atomicity. A segmented download is collected in the caller's buffer and written to the object
 * dictionary only when the last segment has arrived, through the same checks as an expedited write
 * (lsm_co_od_write): a transfer is either applied whole or not at all. This is what makes a path block
 * (co_path.h) all-or-nothing. An upload reads the object once at the initiate request, so the client
 * gets one consistent snapshot even when the value changes during the transfer.
 *
 * Errors answered with an abort frame (0x80, index, sub-index, code): every code of co_od.h's list that
 * the dictionary produces, plus 0x05030000 (toggle bit not alternated), 0x05040001 (unknown or
 * out-of-sequence command), 0x05040005 (object larger than the buffer), 0x06070010 (the bytes received
 * differ from the size announced at initiate), 0x05040000 (no segment for timeout_us: the server
 * aborts and returns to idle; lsm_co_sdo_process checks it). A request frame whose DLC is not 8 is
 * malformed: it is ignored without an answer (there is nothing reliable to answer to) and counted.
 * A new initiate request while a transfer is open silently replaces it (the client gave up on it).
 *
 * Time: now_us is a free-running 32-bit microsecond clock, compared wrap-safe.
 */
#ifndef LSM_CO_SDO_H
#define LSM_CO_SDO_H

#include "can.h"
#include "co_od.h"

/* Compile-time settings (LSM_CO_SDO_TIMEOUT_US): lsm_config.h. */

typedef enum lsm_co_sdo_phase {
    LSM_CO_SDO_IDLE = 0,
    LSM_CO_SDO_DOWNLOAD = 1, /* segmented download open */
    LSM_CO_SDO_UPLOAD = 2    /* segmented upload open */
} lsm_co_sdo_phase;

typedef struct lsm_co_sdo {
    lsm_co_od *od;
    uint8_t *buf;         /* caller storage for segmented transfers */
    uint16_t cap;         /* its size in bytes (>= 8) */
    uint16_t rx_id;       /* 0x600 + node id */
    uint16_t tx_id;       /* 0x580 + node id */
    uint8_t phase;        /* lsm_co_sdo_phase */
    uint8_t toggle;       /* expected toggle bit (0 or 0x10) */
    bool size_known;      /* download: the client announced the size */
    lsm_co_od_ref ref;    /* object of the open transfer */
    uint32_t size;        /* download: announced size; upload: total bytes */
    uint16_t pos;         /* bytes received (download) or sent (upload) */
    uint32_t deadline_us; /* the open transfer aborts when now passes it */
    uint32_t timeout_us;
    uint32_t malformed;   /* request frames with DLC != 8 (wraps) */
    uint32_t aborts_sent; /* abort frames sent (wraps) */
    uint32_t last_abort;  /* code of the last abort sent, 0 if none yet */
} lsm_co_sdo;

/*
 * Binds a server to od for node_id (1..127) with buf[cap] for segmented transfers (cap >= 8 so that every
 * numeric object fits; an object longer than cap is refused with 0x05040005). timeout_us 0 selects
 * LSM_CO_SDO_TIMEOUT_US. Errors: LSM_E_NULL, LSM_E_CO_NODE_ID, LSM_E_ARG (cap < 8 or > 65535).
 */
lsm_status lsm_co_sdo_init(lsm_co_sdo *sdo, lsm_co_od *od, uint8_t node_id, uint8_t *buf, size_t cap,
                           uint32_t timeout_us);

/* Drops an open transfer without answering (NMT reset, state change). */
void lsm_co_sdo_reset(lsm_co_sdo *sdo);

/*
 * Serves one request frame (f->id must be rx_id; the caller dispatches). Queues at most one response in
 * txq. Returns LSM_OK (answered, possibly with an abort), LSM_E_CO_FRAME (DLC != 8 or RTR: ignored),
 * LSM_E_FULL (the response found no room in txq; the transfer state is kept as if it had been sent).
 */
lsm_status lsm_co_sdo_rx(lsm_co_sdo *sdo, const lsm_can_frame *f, uint32_t now_us, lsm_can_txq *txq);

/* Aborts an open transfer whose next segment is overdue (0x05040000). */
void lsm_co_sdo_process(lsm_co_sdo *sdo, uint32_t now_us, lsm_can_txq *txq);

#endif /* LSM_CO_SDO_H */
