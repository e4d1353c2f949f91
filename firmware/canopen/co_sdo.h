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
 * Two halves (issue 13: the SDO server runs in the background, the dictionary stays the tick's). The protocol
 * (lsm_co_sdo_request, lsm_co_sdo_complete, lsm_co_sdo_timeout) never touches the object dictionary: where a request
 * needs an object it returns an access (lsm_co_sdo_access: read, write, or the checks of a segmented download's
 * initiate) and waits. Whoever owns the dictionary applies it (lsm_co_sdo_access_apply, the same checks and abort
 * codes as before, in the same order) and hands the answer back (lsm_co_sdo_complete, which makes the response).
 * At most one access is outstanding; the server's buffer belongs to the side applying it until the answer is back
 * (a read fills it, a segmented write takes its bytes from it). canopen.h runs the protocol in the background and
 * the accesses in the tick, with a hand-off between them; lsm_co_sdo_rx / lsm_co_sdo_process run both halves at
 * once in one context (the unit tests, a node without a background).
 *
 * Time: now_us is a free-running 32-bit microsecond clock, compared wrap-safe. A deadline counts from the time of
 * the request that opened or continued the transfer (the frame's reception), not from when its access came back.
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

/* What a request asks of the object dictionary. */
typedef enum lsm_co_sdo_acc_kind {
    LSM_CO_SDO_ACC_NONE = 0,
    LSM_CO_SDO_ACC_READ = 1,      /* upload initiate: read the object into the server's buffer */
    LSM_CO_SDO_ACC_WRITE = 2,     /* last download segment: write len bytes of the server's buffer */
    LSM_CO_SDO_ACC_WRITE_EXP = 3, /* expedited download: writable?, then write exp[] (len bytes; 0 = size not
                                     indicated: the object's own size, at most 4) */
    LSM_CO_SDO_ACC_CHECK = 4      /* segmented download initiate: exists, writable, announced size len fits (sized) */
} lsm_co_sdo_acc_kind;

/* One access: the request part is written by the server, the answer part by lsm_co_sdo_access_apply. */
typedef struct lsm_co_sdo_access {
    uint8_t kind; /* lsm_co_sdo_acc_kind */
    uint8_t sub;
    uint16_t index;
    uint8_t sized;  /* CHECK, WRITE_EXP: the client indicated the size */
    uint8_t exp[4]; /* WRITE_EXP: the data bytes of the request */
    uint32_t len;   /* WRITE: bytes; WRITE_EXP: bytes indicated (0: not); CHECK: size announced */
    /* answer */
    uint32_t abort;   /* 0 or the CiA 301 abort code */
    uint32_t out_len; /* READ: bytes placed in the buffer */
} lsm_co_sdo_access;

/* What lsm_co_sdo_request asks its caller to do. */
typedef enum lsm_co_sdo_step {
    LSM_CO_SDO_STEP_NONE = 0,     /* nothing to send (a client abort) */
    LSM_CO_SDO_STEP_RESPOND = 1,  /* send *resp */
    LSM_CO_SDO_STEP_ACCESS = 2,   /* apply *acc (lsm_co_sdo_access_apply), then lsm_co_sdo_complete */
    LSM_CO_SDO_STEP_MALFORMED = 3 /* DLC != 8, RTR or 29-bit: ignored, counted */
} lsm_co_sdo_step;

typedef struct lsm_co_sdo {
    lsm_co_od *od;   /* for lsm_co_sdo_rx (one context) only; the protocol never reads it */
    uint8_t *buf;    /* caller storage for segmented transfers */
    uint16_t cap;    /* its size in bytes (>= 8) */
    uint16_t rx_id;  /* 0x600 + node id */
    uint16_t tx_id;  /* 0x580 + node id */
    uint8_t phase;   /* lsm_co_sdo_phase */
    uint8_t toggle;  /* expected toggle bit (0 or 0x10) */
    bool size_known; /* download: the client announced the size */
    uint16_t index;  /* object of the open transfer (or of the outstanding access) */
    uint8_t sub;
    uint8_t wait;         /* lsm_co_sdo_acc_kind of the outstanding access, NONE if none */
    uint8_t wait_d0;      /* WRITE: the segment response's command byte */
    bool wait_cancel;     /* the transfer was reset while its access was outstanding: answer nothing */
    uint32_t wait_us;     /* time of the request that is waiting for its access */
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
 * The server's context, before it serves.
 */
lsm_status lsm_co_sdo_init(lsm_co_sdo *sdo, lsm_co_od *od, uint8_t node_id, uint8_t *buf, size_t cap,
                           uint32_t timeout_us);

/* Drops an open transfer without answering (NMT reset, state change). An outstanding access stays outstanding (its
 * answer is still awaited by lsm_co_sdo_complete, which then answers nothing). The server's context. */
void lsm_co_sdo_reset(lsm_co_sdo *sdo);

/*
 * One context (protocol and dictionary together): serves one request frame (f->id must be rx_id; the caller
 * dispatches), applying its access at once. Queues at most one response in txq. Returns LSM_OK (answered, possibly
 * with an abort), LSM_E_CO_FRAME (DLC != 8 or RTR: ignored), LSM_E_FULL (the response found no room in txq; the
 * transfer state is kept as if it had been sent). The context that owns both the server and od.
 */
lsm_status lsm_co_sdo_rx(lsm_co_sdo *sdo, const lsm_can_frame *f, uint32_t now_us, lsm_can_txq *txq);

/* One context: aborts an open transfer whose next segment is overdue (0x05040000). Same context as lsm_co_sdo_rx. */
void lsm_co_sdo_process(lsm_co_sdo *sdo, uint32_t now_us, lsm_can_txq *txq);

/*
 * The protocol half: one request frame received at now_us. RESPOND: *resp is the answer. ACCESS: *acc is to be
 * applied by the dictionary's owner, then lsm_co_sdo_complete; until then the buffer is the applier's and no other
 * request may be given. NONE, MALFORMED: nothing to send. The server's context (the background in canopen.h).
 */
lsm_co_sdo_step lsm_co_sdo_request(lsm_co_sdo *sdo, const lsm_can_frame *f, uint32_t now_us, lsm_can_frame *resp,
                                   lsm_co_sdo_access *acc);

/* The answer of the outstanding access (acc as applied). True with *resp to send; false when there was no access
 * outstanding or the transfer was reset meanwhile (nothing to send). The server's context. */
bool lsm_co_sdo_complete(lsm_co_sdo *sdo, const lsm_co_sdo_access *acc, lsm_can_frame *resp);

/* True when an access is outstanding (lsm_co_sdo_request returned ACCESS and it has not been completed). */
bool lsm_co_sdo_waiting(const lsm_co_sdo *sdo);

/* The timeout of an open transfer: true with the abort 0x05040000 in *resp when its next segment is overdue at
 * now_us (never while an access is outstanding: that wait is the dictionary owner's, bounded). The server's
 * context. */
bool lsm_co_sdo_timeout(lsm_co_sdo *sdo, uint32_t now_us, lsm_can_frame *resp);

/* The dictionary half: applies acc to od (buf[cap]: the server's buffer, handed over with the access) and fills
 * its answer (abort, out_len). The context that owns od (the tick in canopen.h). */
void lsm_co_sdo_access_apply(lsm_co_od *od, lsm_co_sdo_access *acc, uint8_t *buf, size_t cap);

#endif /* LSM_CO_SDO_H */
