/*
 * co_pdo.h: SYNC consumer, receive and transmit PDOs with configurable mapping (CiA 301 §7.2.2, §7.2.5,
 * §7.5.2.35-38 for the objects 0x1005, 0x1400, 0x1600, 0x1800, 0x1A00).
 *
 * Model. A PDO is one CAN frame whose bytes are the values of up to LSM_CO_PDO_MAX_MAP mapped objects,
 * packed little-endian in mapping order, whole bytes only (a mapping entry is index << 16 | sub << 8 | bits,
 * and bits must equal the object's size). The PDO exists when bit 31 of its COB-ID is 0.
 *
 *   RPDO k (0x1400 + k / 0x1600 + k): received on its COB-ID (default 0x200 + 0x100·k + node id, k < 4).
 *     transmission type 0..240: synchronous, the data is kept and applied at the next SYNC;
 *     254, 255: applied at once. Each mapped value is written through lsm_co_od_write, i.e. with the same
 *     checks and hooks as an SDO write; a value that is refused is skipped (the others are applied) and counted.
 *     DLC shorter than the mapping: not processed, EMCY 0x8210. Longer: processed, extra bytes ignored,
 *     EMCY 0x8220. Either EMCY is sent once per RPDO until a frame of the right length arrives again.
 *   TPDO k (0x1800 + k / 0x1A00 + k): sent on its COB-ID (default 0x180 + 0x100·k + node id).
 *     0: at a SYNC, if the mapped data changed since the last transmission (acyclic synchronous);
 *     1..240: at every n-th SYNC (n = type), e.g. telemetry at each SYNC with type 1;
 *     254, 255: when the mapped data changed (checked in lsm_co_pdo_process), at most once per inhibit time
 *     (sub 3, 100 µs units), and at least every event time (sub 5, ms, 0 = no timer). The first check after
 *     the PDO becomes valid or the node enters OPERATIONAL sends at once.
 *   Types 241..253 (reserved, RTR-only) are refused with 0x06090030: this layer has no RTR.
 *
 * Changing a mapping follows CiA 301: make the PDO not valid (COB-ID bit 31 = 1), write sub 0 = 0, write
 * the entries, write sub 0 = n (checked now: entries exist, are mappable in that direction, total <= 64 bits),
 * make the PDO valid. Abort codes: 0x08000022 (mapping or inhibit time changed while the PDO is valid, or an
 * entry written while sub 0 != 0), 0x06040041 (object missing, not mappable, or bit length != its size),
 * 0x06040042 (more than 64 bits), 0x06090031 (sub 0 > LSM_CO_PDO_MAX_MAP), 0x06090030 (COB-ID with bit 29
 * (29-bit id), a CAN-ID restricted by CiA 301 Table 3, or a new CAN-ID while the PDO is valid).
 *
 * SYNC (COB-ID 0x1005, default 0x80): this node consumes SYNC and never produces it (bit 30 = 1 refused).
 * The SYNC counter (0x1019) is not supported: a SYNC with DLC != 0 is malformed, not processed, EMCY 0x8240.
 *
 * PDOs only run in NMT OPERATIONAL; the node calls these functions accordingly.
 * Time: now_us is a free-running 32-bit microsecond clock, compared wrap-safe.
 * Contexts: PDOs are the tick's (SYNC and PDO timing are the control cycle's work; canopen.h, "Contexts"): every call
 * here, including the mapping hooks an SDO write reaches (the tick applies the background server's accesses).
 */
#ifndef LSM_CO_PDO_H
#define LSM_CO_PDO_H

#include "can.h"
#include "co_od.h"

/* Compile-time settings (LSM_CO_N_RPDO, LSM_CO_N_TPDO, LSM_CO_PDO_MAX_MAP): lsm_config.h. */

#define LSM_CO_PDO_INVALID 0x80000000u /* COB-ID bit 31: the PDO does not exist */
#define LSM_CO_PDO_NO_RTR 0x40000000u  /* COB-ID bit 30: no RTR allowed (always so here) */
#define LSM_CO_PDO_EXT 0x20000000u     /* COB-ID bit 29: 29-bit id (refused) */

typedef struct lsm_co_pdo_chan {
    uint32_t cob_id;                        /* sub 1 */
    uint8_t trans_type;                     /* sub 2 */
    uint8_t n_map;                          /* mapping sub 0 */
    uint8_t dlc;                            /* bytes of the current mapping */
    uint8_t sync_count;                     /* TPDO: SYNCs since the last transmission */
    uint16_t inhibit_100us;                 /* TPDO sub 3 */
    uint16_t event_ms;                      /* sub 5 (TPDO event timer) */
    uint32_t map[LSM_CO_PDO_MAX_MAP];       /* mapping sub 1.. */
    uint16_t map_entry[LSM_CO_PDO_MAX_MAP]; /* resolved: table entry number */
    uint8_t map_inst[LSM_CO_PDO_MAX_MAP];   /* resolved: instance */
    uint8_t buf[8];                         /* RPDO: data waiting for SYNC; TPDO: data of the last transmission */
    bool pending;                           /* RPDO: buf waits for SYNC */
    bool sent_once;                         /* TPDO: buf is valid */
    bool len_err;                           /* RPDO: a length EMCY was sent and not yet followed by a good frame */
    uint32_t inhibit_until_us;
    uint32_t event_due_us;
} lsm_co_pdo_chan;

/* What an RPDO reception produced, for the node's EMCY. */
typedef enum lsm_co_pdo_rx_result {
    LSM_CO_PDO_RX_OK = 0,
    LSM_CO_PDO_RX_SHORT = 1, /* not processed: send EMCY 0x8210 */
    LSM_CO_PDO_RX_LONG = 2,  /* processed: send EMCY 0x8220 */
    LSM_CO_PDO_RX_QUIET = 3  /* a length error already reported: nothing to send */
} lsm_co_pdo_rx_result;

typedef struct lsm_co_pdo {
    lsm_co_od *od;
    uint32_t sync_cob_id;      /* 0x1005 */
    uint32_t syncs;            /* SYNCs processed (wraps) */
    uint32_t rx_refused;       /* mapped values refused by the dictionary (wraps) */
    uint32_t rx_length_errors; /* RPDOs with a wrong DLC (wraps) */
    uint8_t node_id;
    lsm_co_pdo_chan rpdo[LSM_CO_N_RPDO];
    lsm_co_pdo_chan tpdo[LSM_CO_N_TPDO];
} lsm_co_pdo;

/* Every PDO not valid with its default COB-ID, type 255, no mapping; SYNC COB-ID 0x80.
 * Errors: LSM_E_NULL, LSM_E_CO_NODE_ID. Tick. */
lsm_status lsm_co_pdo_init(lsm_co_pdo *pdo, lsm_co_od *od, uint8_t node_id);

/*
 * Application default configuration of one PDO (tx: TPDO, else RPDO; k its number): the mapping maps[0..n-1],
 * the transmission type, and whether it is valid with its default COB-ID. Goes through the same checks as the
 * SDO procedure. Errors: LSM_E_ARG (k, n or type out of range), LSM_E_CO_MAPPING (an entry is refused).
 * Tick.
 */
lsm_status lsm_co_pdo_configure(lsm_co_pdo *pdo, bool tx, size_t k, uint8_t trans_type, const uint32_t *maps, size_t n,
                                bool valid);

/* OD hook parts: communication record (sub 1, 2, 3, 5), mapping record (sub 0..8), 0x1005. Abort or 0. Tick. */
uint32_t lsm_co_pdo_write_comm(lsm_co_pdo *pdo, bool tx, size_t k, uint8_t sub, uint32_t value, uint32_t now_us);
uint32_t lsm_co_pdo_write_map(lsm_co_pdo *pdo, bool tx, size_t k, uint8_t sub, uint32_t value);
uint32_t lsm_co_pdo_write_sync_id(lsm_co_pdo *pdo, uint32_t value);

/* Number of the valid RPDO listening on id, or -1. Tick. */
int lsm_co_pdo_rpdo_of(const lsm_co_pdo *pdo, uint32_t id);

/* True if id is the SYNC COB-ID. Tick. */
bool lsm_co_pdo_is_sync(const lsm_co_pdo *pdo, uint32_t id);

/* Serves one frame of RPDO k. Tick. */
lsm_co_pdo_rx_result lsm_co_pdo_rx(lsm_co_pdo *pdo, size_t k, const lsm_can_frame *f);

/* A SYNC frame: LSM_E_CO_FRAME if its DLC is not 0 (nothing done), else sends the synchronous TPDOs due,
 * then applies the synchronous RPDOs received since the last SYNC. Tick. */
lsm_status lsm_co_pdo_sync(lsm_co_pdo *pdo, const lsm_can_frame *f, uint32_t now_us, lsm_can_txq *txq);

/* Event-driven TPDOs (types 254/255): change of mapped data, inhibit time, event timer. Tick. */
void lsm_co_pdo_process(lsm_co_pdo *pdo, uint32_t now_us, lsm_can_txq *txq);

/* Forgets runtime state (pending synchronous RPDO data, last TPDO data, counters): the node calls it when
 * it enters OPERATIONAL so that every event TPDO is sent once at the start. Tick. */
void lsm_co_pdo_restart(lsm_co_pdo *pdo, uint32_t now_us);

#endif /* LSM_CO_PDO_H */
