#include "canopen.h"

#include <string.h>

/* ---- object dictionary table ---------------------------------------------------------------------- */

enum { G_NONE = 0, G_AXIS = 1, G_RPDO = 2, G_TPDO = 3 };
enum {
    R_NONE = 0,
    R_POS = 1,
    R_ABORT_OPT = 2,
    R_ERR_BEHAV = 3,
    R_OVERRIDE = 4,
    R_IP_INDEX = 5,
    R_MAP_COUNT = 6,
    R_COUNT
};

static const lsm_co_od_range k_ranges[R_COUNT] = {
    [R_NONE] = {0, 0},
    [R_POS] = {1, INT64_MAX}, /* limits and scales: zero is refused (0x06090032) */
    [R_ABORT_OPT] = {0, 3},   /* 0x6007 */
    [R_ERR_BEHAV] = {0, 2},   /* 0x1029 sub 1 */
    [R_OVERRIDE] = {0, 200},  /* 0x5001, percent */
    [R_IP_INDEX] = {-6, 0},   /* 0x60C2 sub 2: 1 µs .. 1 s units */
    [R_MAP_COUNT] = {0, LSM_CO_PDO_MAX_MAP},
};

#define R_ LSM_CO_OD_R
#define W_ LSM_CO_OD_W
#define RW_ LSM_CO_OD_RW
#define TP_ LSM_CO_OD_TPDO
#define RP_ LSM_CO_OD_RPDO
#define HK_ LSM_CO_OD_HOOK
#define CONST_ (LSM_CO_OD_R | LSM_CO_OD_CONST)

#define OFF(f) ((uint32_t)offsetof(lsm_canopen, f))
#define AX(f) OFF(axis[0].f)
#define ENT(idx, sub, t, sz, fl, grp, rng, arg)                      \
    {                                                                \
        (idx), (sub), (t), (fl), (grp), (rng), (sz), (uint32_t)(arg) \
    }
#define E_U8(i, s, fl, g, r, a) ENT(i, s, LSM_CO_T_U8, 1, fl, g, r, a)
#define E_I8(i, s, fl, g, r, a) ENT(i, s, LSM_CO_T_I8, 1, fl, g, r, a)
#define E_U16(i, s, fl, g, r, a) ENT(i, s, LSM_CO_T_U16, 2, fl, g, r, a)
#define E_I16(i, s, fl, g, r, a) ENT(i, s, LSM_CO_T_I16, 2, fl, g, r, a)
#define E_U32(i, s, fl, g, r, a) ENT(i, s, LSM_CO_T_U32, 4, fl, g, r, a)
#define E_I32(i, s, fl, g, r, a) ENT(i, s, LSM_CO_T_I32, 4, fl, g, r, a)
#define E_U64(i, s, fl, g, r, a) ENT(i, s, LSM_CO_T_U64, 8, fl, g, r, a)

#if LSM_CO_EMCY_HISTORY != 8
#error "the 0x1003 entries below list 8 sub-indices"
#endif
#if LSM_CO_HB_CONSUMERS != 2
#error "the 0x1016 entries below list 2 sub-indices"
#endif
#if LSM_CO_PDO_MAX_MAP != 8
#error "the PDO mapping entries below list 8 sub-indices"
#endif

/* NOLINTBEGIN(bugprone-macro-parentheses): arr names a member for offsetof, which takes no parentheses */
#define MAP_ENTRIES(idx, g, arr)                                                                                    \
    E_U8(idx, 0, RW_ | HK_, g, R_MAP_COUNT, OFF(arr[0].n_map)), E_U32(idx, 1, RW_ | HK_, g, 0, OFF(arr[0].map[0])), \
        E_U32(idx, 2, RW_ | HK_, g, 0, OFF(arr[0].map[1])), E_U32(idx, 3, RW_ | HK_, g, 0, OFF(arr[0].map[2])),     \
        E_U32(idx, 4, RW_ | HK_, g, 0, OFF(arr[0].map[3])), E_U32(idx, 5, RW_ | HK_, g, 0, OFF(arr[0].map[4])),     \
        E_U32(idx, 6, RW_ | HK_, g, 0, OFF(arr[0].map[5])), E_U32(idx, 7, RW_ | HK_, g, 0, OFF(arr[0].map[6])),     \
        E_U32(idx, 8, RW_ | HK_, g, 0, OFF(arr[0].map[7]))
/* NOLINTEND(bugprone-macro-parentheses) */

static const lsm_co_od_entry k_od[] = {
    /* CiA 301 communication area */
    E_U32(0x1000, 0, R_, 0, 0, OFF(device_type)),
    E_U8(0x1001, 0, R_ | TP_, 0, 0, OFF(emcy.error_register)),
    E_U8(0x1003, 0, RW_ | HK_, 0, 0, OFF(emcy.n_history)),
    E_U32(0x1003, 1, R_, 0, 0, OFF(emcy.history[0])),
    E_U32(0x1003, 2, R_, 0, 0, OFF(emcy.history[1])),
    E_U32(0x1003, 3, R_, 0, 0, OFF(emcy.history[2])),
    E_U32(0x1003, 4, R_, 0, 0, OFF(emcy.history[3])),
    E_U32(0x1003, 5, R_, 0, 0, OFF(emcy.history[4])),
    E_U32(0x1003, 6, R_, 0, 0, OFF(emcy.history[5])),
    E_U32(0x1003, 7, R_, 0, 0, OFF(emcy.history[6])),
    E_U32(0x1003, 8, R_, 0, 0, OFF(emcy.history[7])),
    E_U32(0x1005, 0, RW_ | HK_, 0, 0, OFF(pdo.sync_cob_id)),
    E_U32(0x1006, 0, RW_, 0, 0, OFF(cycle_period_us)),
    ENT(0x1008, 0, LSM_CO_T_VSTRING, 64, R_ | LSM_CO_OD_STRPTR, 0, 0, OFF(device_name)),
    E_U32(0x1014, 0, R_, 0, 0, OFF(emcy.cob_id)),
    E_U8(0x1016, 0, CONST_, 0, 0, LSM_CO_HB_CONSUMERS),
    E_U32(0x1016, 1, RW_ | HK_, 0, 0, OFF(nmt.cons[0].param)),
    E_U32(0x1016, 2, RW_ | HK_, 0, 0, OFF(nmt.cons[1].param)),
    E_U16(0x1017, 0, RW_ | HK_, 0, 0, OFF(nmt.producer_ms)),
    E_U8(0x1018, 0, CONST_, 0, 0, 4),
    E_U32(0x1018, 1, R_, 0, 0, OFF(identity[0])),
    E_U32(0x1018, 2, R_, 0, 0, OFF(identity[1])),
    E_U32(0x1018, 3, R_, 0, 0, OFF(identity[2])),
    E_U32(0x1018, 4, R_, 0, 0, OFF(identity[3])),
    E_U8(0x1029, 0, CONST_, 0, 0, 1),
    E_U8(0x1029, 1, RW_, 0, R_ERR_BEHAV, OFF(comm_error_behaviour)),
    E_U8(0x1200, 0, CONST_, 0, 0, 2),
    E_U32(0x1200, 1, R_, 0, 0, OFF(sdo_cob_rx)),
    E_U32(0x1200, 2, R_, 0, 0, OFF(sdo_cob_tx)),
    /* RPDO k: 0x1400 + k, 0x1600 + k */
    E_U8(0x1400, 0, CONST_, G_RPDO, 0, 2),
    E_U32(0x1400, 1, RW_ | HK_, G_RPDO, 0, OFF(pdo.rpdo[0].cob_id)),
    E_U8(0x1400, 2, RW_ | HK_, G_RPDO, 0, OFF(pdo.rpdo[0].trans_type)),
    MAP_ENTRIES(0x1600, G_RPDO, pdo.rpdo),
    /* TPDO k: 0x1800 + k, 0x1A00 + k */
    E_U8(0x1800, 0, CONST_, G_TPDO, 0, 5),
    E_U32(0x1800, 1, RW_ | HK_, G_TPDO, 0, OFF(pdo.tpdo[0].cob_id)),
    E_U8(0x1800, 2, RW_ | HK_, G_TPDO, 0, OFF(pdo.tpdo[0].trans_type)),
    E_U16(0x1800, 3, RW_ | HK_, G_TPDO, 0, OFF(pdo.tpdo[0].inhibit_100us)),
    E_U16(0x1800, 5, RW_ | HK_, G_TPDO, 0, OFF(pdo.tpdo[0].event_ms)),
    MAP_ENTRIES(0x1A00, G_TPDO, pdo.tpdo),
    /* manufacturer, per axis k at index + 0x800·k */
    E_U32(0x2001, 0, RW_ | HK_, G_AXIS, R_POS, AX(counts_per_mm)),
    E_U64(0x2060, 0, RW_, G_AXIS, R_POS, AX(profile_jerk)),
    E_U64(0x2061, 0, RW_, G_AXIS, R_POS, AX(profile_snap)),
    /* manufacturer, path (co_path.h) */
    E_U8(0x5000, 0, RW_ | RP_ | HK_, 0, 0, OFF(path.command)),
    E_U8(0x5001, 0, RW_ | RP_, 0, R_OVERRIDE, OFF(path.override_pct)),
    E_U8(0x5002, 0, R_ | TP_, 0, 0, OFF(path.state)),
    E_U16(0x5003, 0, R_ | TP_, 0, 0, OFF(path.free_slots)),
    E_U32(0x5004, 0, RW_ | TP_ | HK_, 0, 0, OFF(path.last_seq)),
    E_U32(0x5005, 0, R_ | TP_, 0, 0, OFF(path.active_seq)),
    E_U32(0x5006, 0, R_ | TP_, 0, 0, OFF(path.feed_um_s)),
    E_U16(0x5007, 0, R_, 0, 0, OFF(path.capacity)),
    E_U8(0x5008, 0, CONST_, 0, 0, 4),
    E_U16(0x5008, 1, R_ | TP_, 0, 0, OFF(path.n_dup)),
    E_U16(0x5008, 2, R_ | TP_, 0, 0, OFF(path.n_gap)),
    E_U16(0x5008, 3, R_ | TP_, 0, 0, OFF(path.n_refused)),
    E_U16(0x5008, 4, R_ | TP_, 0, 0, OFF(path.n_underrun)),
    ENT(0x5010, 0, LSM_CO_T_DOMAIN, LSM_CO_PATH_BLOCK_MAX, W_ | HK_, 0, 0, 0),
    E_U8(0x5020, 0, R_ | TP_, 0, 0, OFF(machine_status)),
    /* manufacturer, the port's tick statistics (lsm_canopen_set_tick_stats) */
    E_U8(0x5F00, 0, CONST_, 0, 0, 10),
    E_U32(0x5F00, 1, R_, 0, 0, OFF(tick_stats.ticks)),
    E_U32(0x5F00, 2, R_, 0, 0, OFF(tick_stats.overruns)),
    E_U32(0x5F00, 3, R_, 0, 0, OFF(tick_stats.worst_instr)),
    E_U16(0x5F00, 4, R_, 0, 0, OFF(tick_stats.bg_load_permille)),
    E_U32(0x5F00, 5, R_, 0, 0, OFF(tick_stats.late_wakes)),
    E_U32(0x5F00, 6, R_, 0, 0, OFF(tick_stats.clock_ms)),
    E_U32(0x5F00, 7, R_, 0, 0, OFF(tick_stats.path_underruns)),
    E_U32(0x5F00, 8, R_, 0, 0, OFF(tick_stats.path_min_ahead)),
    E_U32(0x5F00, 9, R_, 0, 0, OFF(sdo_link.most_waiting)),
    E_U32(0x5F00, 10, R_, 0, 0, OFF(sdo_link.refused)),
    /* CiA 402, per axis k at index + 0x800·k */
    E_I16(0x6007, 0, RW_, G_AXIS, R_ABORT_OPT, AX(abort_option)),
    E_U16(0x603F, 0, R_ | TP_, G_AXIS, 0, AX(error_code)),
    E_U16(0x6040, 0, RW_ | RP_ | HK_, G_AXIS, 0, AX(controlword)),
    E_U16(0x6041, 0, R_ | TP_, G_AXIS, 0, AX(statusword)),
    E_I16(0x605A, 0, RW_ | HK_, G_AXIS, 0, AX(quick_stop_option)),
    E_I8(0x6060, 0, RW_ | RP_ | HK_, G_AXIS, 0, AX(mode)),
    E_I8(0x6061, 0, R_ | TP_, G_AXIS, 0, AX(mode_display)),
    E_I32(0x6062, 0, R_ | TP_, G_AXIS, 0, AX(pos_demand)),
    E_I32(0x6064, 0, R_ | TP_, G_AXIS, 0, AX(pos_actual)),
    E_U32(0x6065, 0, RW_, G_AXIS, 0, AX(fe_window)),
    E_U16(0x6066, 0, RW_, G_AXIS, 0, AX(fe_timeout_ms)),
    E_U32(0x6067, 0, RW_, G_AXIS, 0, AX(pos_window)),
    E_I32(0x606C, 0, R_ | TP_, G_AXIS, 0, AX(vel_actual)),
    E_I32(0x607A, 0, RW_ | RP_ | HK_, G_AXIS, 0, AX(target)),
    E_U32(0x6081, 0, RW_ | RP_, G_AXIS, R_POS, AX(profile_velocity)),
    E_U32(0x6083, 0, RW_ | RP_, G_AXIS, R_POS, AX(profile_accel)),
    E_U32(0x6084, 0, RW_ | RP_, G_AXIS, R_POS, AX(profile_decel)),
    E_U32(0x6085, 0, RW_, G_AXIS, R_POS, AX(quick_stop_decel)),
    E_I16(0x6086, 0, RW_ | HK_, G_AXIS, 0, AX(profile_type)),
    E_U8(0x60C2, 0, CONST_, G_AXIS, 0, 2),
    E_U8(0x60C2, 1, RW_, G_AXIS, 0, AX(ip_period_value)),
    E_I8(0x60C2, 2, RW_, G_AXIS, R_IP_INDEX, AX(ip_period_index)),
    E_I32(0x60F4, 0, R_ | TP_, G_AXIS, 0, AX(fe_actual)),
    E_U32(0x6502, 0, CONST_, G_AXIS, 0, LSM_CIA402_SUPPORTED_MODES),
};

const lsm_co_od_entry *lsm_canopen_od_table(size_t *n_entries)
{
    if (n_entries != NULL)
        *n_entries = sizeof k_od / sizeof k_od[0];
    return k_od;
}

/* ---- helpers ------------------------------------------------------------------------------------- */

static bool emcy_can_send(const lsm_canopen *n)
{
    return !n->bus_off && (n->nmt.state == LSM_CO_NMT_PRE_OPERATIONAL || n->nmt.state == LSM_CO_NMT_OPERATIONAL);
}

static void emcy_raise(lsm_canopen *n, uint16_t code, uint8_t reg, uint8_t info, uint32_t extra)
{
    (void)lsm_co_emcy_raise(&n->emcy, code, reg, info, extra, emcy_can_send(n), &n->txq);
}

static void emcy_clear(lsm_canopen *n, uint16_t code, uint8_t info)
{
    (void)lsm_co_emcy_clear(&n->emcy, code, info, emcy_can_send(n), &n->txq);
}

static void emcy_event(lsm_canopen *n, uint16_t code, uint8_t reg, uint8_t info, uint32_t extra)
{
    (void)lsm_co_emcy_event(&n->emcy, code, reg, info, extra, emcy_can_send(n), &n->txq);
}

bool lsm_canopen_axes_ready_for_path(const lsm_canopen *n)
{
    for (size_t k = 0; k < n->n_axes; k++) {
        if (n->axis[k].mode_display != LSM_CIA402_MODE_PATH || !lsm_cia402_motion_allowed(&n->axis[k]))
            return false;
    }
    return true;
}

static uint32_t od_hook(void *ctx, const lsm_co_od_ref *ref, const uint8_t *data, size_t len, int64_t v)
{
    lsm_canopen *n = (lsm_canopen *)ctx;
    const lsm_co_od_entry *e = ref->entry;
    switch (e->group) {
    case G_AXIS: return lsm_cia402_od_write(&n->axis[ref->inst], e->index, e->sub, v, n->now_us);
    case G_RPDO:
    case G_TPDO: {
        bool tx = e->group == G_TPDO;
        if (e->index == 0x1400u || e->index == 0x1800u)
            return lsm_co_pdo_write_comm(&n->pdo, tx, ref->inst, e->sub, (uint32_t)v, n->now_us);
        return lsm_co_pdo_write_map(&n->pdo, tx, ref->inst, e->sub, (uint32_t)v);
    }
    default: break;
    }
    switch (e->index) {
    case 0x1003: return lsm_co_emcy_write_history_count(&n->emcy, v);
    case 0x1005: return lsm_co_pdo_write_sync_id(&n->pdo, (uint32_t)v);
    case 0x1016: return lsm_co_nmt_set_consumer(&n->nmt, (size_t)e->sub - 1u, (uint32_t)v);
    case 0x1017: lsm_co_nmt_set_producer(&n->nmt, (uint16_t)v, n->now_us); return LSM_CO_ABORT_NONE;
    case 0x5000: return lsm_co_path_command(&n->path, v, lsm_canopen_axes_ready_for_path(n));
    case 0x5004: return lsm_co_path_resync(&n->path, (uint32_t)v);
    case 0x5010: return lsm_co_path_write_block(&n->path, data, len, NULL);
    default: return LSM_CO_ABORT_GENERAL; /* an entry flagged HOOK that nobody serves: a table bug */
    }
}

#define MAP(idx, sub, bits) (((uint32_t)(idx) << 16) | ((uint32_t)(sub) << 8) | (uint32_t)(bits))
#define AXIDX(base, k) ((uint16_t)((base) + 0x800u * (k)))

/* Default PDOs (docs/canopen.md). Objects of axes the node does not have are left out. */
static lsm_status default_pdos(lsm_canopen *n)
{
    uint32_t m[LSM_CO_PDO_MAX_MAP];
    size_t c;
    lsm_status st;
    uint8_t na = n->n_axes;

    /* RPDO1: controlword of axis 0, at once */
    m[0] = MAP(0x6040, 0, 16);
    if ((st = lsm_co_pdo_configure(&n->pdo, false, 0, 255u, m, 1, true)) != LSM_OK)
        return st;
    /* RPDO2: CSP targets of axes 0, 1, applied at SYNC */
    c = 0;
    for (uint8_t k = 0; k < 2u && k < na; k++)
        m[c++] = MAP(AXIDX(0x607A, k), 0, 32);
    if ((st = lsm_co_pdo_configure(&n->pdo, false, 1, 1u, m, c, c != 0u)) != LSM_OK)
        return st;
    /* RPDO3: CSP targets of axes 2, 3, applied at SYNC */
    c = 0;
    for (uint8_t k = 2; k < 4u && k < na; k++)
        m[c++] = MAP(AXIDX(0x607A, k), 0, 32);
    if ((st = lsm_co_pdo_configure(&n->pdo, false, 2, 1u, m, c, c != 0u)) != LSM_OK)
        return st;
    /* RPDO4: controlwords of axes 1..3, at once */
    c = 0;
    for (uint8_t k = 1; k < 4u && k < na; k++)
        m[c++] = MAP(AXIDX(0x6040, k), 0, 16);
    if ((st = lsm_co_pdo_configure(&n->pdo, false, 3, 255u, m, c, c != 0u)) != LSM_OK)
        return st;
    /* TPDO1: statusword and mode display of axis 0, on change and at least every 50 ms (a master such as
     * python-canopen's BaseNode402 treats a TPDO it has seen twice as periodic and waits for the next one) */
    m[0] = MAP(0x6041, 0, 16);
    m[1] = MAP(0x6061, 0, 8);
    if ((st = lsm_co_pdo_configure(&n->pdo, true, 0, 255u, m, 2, true)) != LSM_OK)
        return st;
    if (lsm_co_pdo_write_comm(&n->pdo, true, 0, 5u, 50u, n->now_us) != 0u)
        return LSM_E_INTERNAL;
    /* TPDO2: path state, free slots, last accepted sequence, at each SYNC */
    m[0] = MAP(0x5002, 0, 8);
    m[1] = MAP(0x5003, 0, 16);
    m[2] = MAP(0x5004, 0, 32);
    if ((st = lsm_co_pdo_configure(&n->pdo, true, 1, 1u, m, 3, true)) != LSM_OK)
        return st;
    /* TPDO3: position actual of axes 0, 1, at each SYNC */
    c = 0;
    for (uint8_t k = 0; k < 2u && k < na; k++)
        m[c++] = MAP(AXIDX(0x6064, k), 0, 32);
    if ((st = lsm_co_pdo_configure(&n->pdo, true, 2, 1u, m, c, true)) != LSM_OK)
        return st;
    /* TPDO4: position actual of axis 2, executing block sequence, at each SYNC */
    c = 0;
    if (na > 2u)
        m[c++] = MAP(AXIDX(0x6064, 2), 0, 32);
    m[c++] = MAP(0x5005, 0, 32);
    return lsm_co_pdo_configure(&n->pdo, true, 3, 1u, m, c, true);
}

/* ---- SDO: the server in the tick, or in the background with the hand-off of canopen.h ----------------- */

#define SDO_Q LSM_CANOPEN_SDO_QUEUE
_Static_assert((LSM_CANOPEN_SDO_QUEUE & (LSM_CANOPEN_SDO_QUEUE - 1u)) == 0u, "the SDO rings' size: a power of two");

static lsm_status sdo_init(lsm_canopen *n)
{
    return lsm_co_sdo_init(&n->sdo, &n->od, n->cfg.node_id, n->sdo_buf, sizeof n->sdo_buf, n->cfg.sdo_timeout_us);
}

/* The SDO server back to idle with its defaults (reset communication, reset node, boot): in the tick's own server at
 * once; with the background server through the epoch (it drops its transfer, and what is in flight is dropped). */
static lsm_status sdo_restart(lsm_canopen *n)
{
    if (!n->sdo_link.enabled)
        return sdo_init(n);
    lsm_atomic_put_release(&n->sdo_link.epoch, lsm_atomic_get(&n->sdo_link.epoch) + 1u);
    return LSM_OK;
}

/* An open transfer dropped without an answer (NMT stopped). */
static void sdo_reset(lsm_canopen *n)
{
    if (n->sdo_link.enabled)
        (void)sdo_restart(n);
    else
        lsm_co_sdo_reset(&n->sdo);
}

/* Tick: an SDO request for the background server. A full ring refuses it at once with 0x05040005 (a client abort,
 * which needs no answer, is just dropped), so the tick never waits. */
static lsm_status sdo_push(lsm_canopen *n, const lsm_can_frame *f, uint32_t now_us)
{
    lsm_canopen_sdo_link *l = &n->sdo_link;
    if (f->dlc != 8u)
        return LSM_E_CO_FRAME; /* malformed: no answer, as the server itself would do */
    const uint32_t head = lsm_atomic_get(&l->req_head);
    const uint32_t waiting = head - lsm_atomic_get_acquire(&l->req_tail);
    if (waiting >= SDO_Q) {
        l->refused++;
        const uint8_t ccs = (uint8_t)(f->data[0] >> 5);
        if (ccs == 4u)
            return LSM_E_FULL;
        const bool names = ccs == 1u || ccs == 2u; /* initiate requests name their object; segments do not */
        lsm_can_frame a;
        a.id = n->sdo_cob_tx;
        a.dlc = 8u;
        a.flags = 0u;
        a.data[0] = 0x80u;
        lsm_can_put_u16(&a.data[1], names ? lsm_can_get_u16(&f->data[1]) : 0u);
        a.data[3] = names ? f->data[3] : 0u;
        lsm_can_put_u32(&a.data[4], LSM_CO_ABORT_NO_MEM);
        (void)lsm_can_txq_push(&n->txq, &a);
        return LSM_E_FULL;
    }
    lsm_canopen_sdo_req *r = &l->req[head % SDO_Q];
    r->f = *f;
    r->rx_us = now_us;
    r->epoch = lsm_atomic_get(&l->epoch);
    lsm_atomic_put_release(&l->req_head, head + 1u);
    if (waiting + 1u > l->most_waiting)
        l->most_waiting = waiting + 1u;
    return LSM_OK;
}

/* Tick: the server's object access (at most one is outstanding), then its responses into the TX queue. True when
 * something was done. */
static bool sdo_tick(lsm_canopen *n)
{
    lsm_canopen_sdo_link *l = &n->sdo_link;
    const uint32_t epoch = lsm_atomic_get(&l->epoch);
    const uint32_t done = lsm_atomic_get(&l->acc_done);
    bool did = false;
    if (lsm_atomic_get_acquire(&l->acc_posted) != done) {
        if (l->acc_epoch == epoch) {
            lsm_co_sdo_access_apply(&n->od, &l->acc, n->sdo_buf, sizeof n->sdo_buf);
        } else { /* posted before an SDO reset: not applied */
            l->acc.abort = LSM_CO_ABORT_DEVICE_STATE;
            l->acc.out_len = 0u;
            l->stale++;
        }
        lsm_atomic_put_release(&l->acc_done, done + 1u);
        did = true;
    }
    uint32_t tail = lsm_atomic_get(&l->res_tail);
    const uint32_t head = lsm_atomic_get_acquire(&l->res_head);
    while (tail != head) {
        const lsm_canopen_sdo_res *r = &l->res[tail % SDO_Q];
        if (r->epoch != epoch)
            l->stale++;
        else if (!n->bus_off)                       /* bus-off: nothing is queued */
            (void)lsm_can_txq_push(&n->txq, &r->f); /* full: dropped and counted, the client times out (as before) */
        tail++;
        lsm_atomic_put_release(&l->res_tail, tail);
        did = true;
    }
    return did;
}

/* Background: responses the ring can take now. */
static uint32_t sdo_res_room(lsm_canopen_sdo_link *l)
{
    return SDO_Q - (lsm_atomic_get(&l->res_head) - lsm_atomic_get_acquire(&l->res_tail));
}

/* Background: a response to the tick (room checked by the caller). */
static void sdo_respond(lsm_canopen_sdo_link *l, const lsm_can_frame *f)
{
    const uint32_t head = lsm_atomic_get(&l->res_head);
    lsm_canopen_sdo_res *r = &l->res[head % SDO_Q];
    r->f = *f;
    r->epoch = l->bg_epoch;
    lsm_atomic_put_release(&l->res_head, head + 1u);
}

/* Background: the answer of the outstanding access, if it is back. False while it is still out. */
static bool sdo_take_answer(lsm_canopen *n)
{
    lsm_canopen_sdo_link *l = &n->sdo_link;
    if (lsm_atomic_get_acquire(&l->acc_done) != lsm_atomic_get(&l->acc_posted))
        return false;
    lsm_can_frame resp;
    if (lsm_co_sdo_complete(&n->sdo, &l->acc, &resp) && l->acc_epoch == l->bg_epoch)
        sdo_respond(l, &resp);
    return true;
}

/* Background: the next waiting request. False when there is none. */
static bool sdo_serve_one(lsm_canopen *n)
{
    lsm_canopen_sdo_link *l = &n->sdo_link;
    const uint32_t tail = lsm_atomic_get(&l->req_tail);
    if (lsm_atomic_get_acquire(&l->req_head) == tail)
        return false;
    const lsm_canopen_sdo_req rq = l->req[tail % SDO_Q];
    lsm_atomic_put_release(&l->req_tail, tail + 1u);
    if (rq.epoch != l->bg_epoch) {
        if ((int32_t)(rq.epoch - l->bg_epoch) < 0) {
            l->bg_dropped++; /* received before an SDO reset the server has already seen */
            return true;
        }
        l->bg_epoch = rq.epoch;
        lsm_co_sdo_reset(&n->sdo);
    }
    lsm_can_frame resp;
    const lsm_co_sdo_step st = lsm_co_sdo_request(&n->sdo, &rq.f, rq.rx_us, &resp, &l->acc);
    if (st == LSM_CO_SDO_STEP_RESPOND) {
        sdo_respond(l, &resp);
    } else if (st == LSM_CO_SDO_STEP_ACCESS) {
        l->acc_epoch = l->bg_epoch;
        lsm_atomic_put_release(&l->acc_posted, lsm_atomic_get(&l->acc_posted) + 1u);
    }
    return true;
}

bool lsm_canopen_sdo_background(lsm_canopen *n, uint32_t now_us)
{
    if (n == NULL || !n->sdo_link.enabled)
        return false;
    lsm_canopen_sdo_link *l = &n->sdo_link;
    bool did = false;
    const uint32_t epoch = lsm_atomic_get_acquire(&l->epoch);
    if (epoch != l->bg_epoch) {
        l->bg_epoch = epoch;
        lsm_co_sdo_reset(&n->sdo);
        did = true;
    }
    if (lsm_co_sdo_waiting(&n->sdo)) {
        if (!sdo_take_answer(n))
            return did;
        did = true;
    }
    while (!lsm_co_sdo_waiting(&n->sdo) && sdo_res_room(l) > 0u && sdo_serve_one(n))
        did = true;
    /* the timeout after the requests: a segment received before now_us is served first, as when the tick served
     * the requests before its timeout check */
    lsm_can_frame resp;
    if (!lsm_co_sdo_waiting(&n->sdo) && sdo_res_room(l) > 0u && lsm_co_sdo_timeout(&n->sdo, now_us, &resp)) {
        sdo_respond(l, &resp);
        did = true;
    }
    return did;
}

void lsm_canopen_sdo_sync(lsm_canopen *n, uint32_t now_us)
{
    if (n == NULL || !n->sdo_link.enabled)
        return;
    /* each round serves a request or an access; what a burst of received frames needs is bounded by the rings */
    for (unsigned i = 0; i < 8u * SDO_Q; i++) {
        const bool bg = lsm_canopen_sdo_background(n, now_us);
        if (!sdo_tick(n) && !bg)
            return;
    }
}

void lsm_canopen_sdo_stats(lsm_canopen *n, uint32_t *waiting, uint32_t *most_waiting, uint32_t *refused)
{
    if (n == NULL)
        return;
    lsm_canopen_sdo_link *l = &n->sdo_link;
    if (waiting != NULL)
        *waiting = lsm_atomic_get(&l->req_head) - lsm_atomic_get_acquire(&l->req_tail);
    if (most_waiting != NULL)
        *most_waiting = l->most_waiting;
    if (refused != NULL)
        *refused = l->refused;
}

/* Communication objects to their defaults (the part of a reset communication). */
static lsm_status comm_defaults(lsm_canopen *n)
{
    const lsm_canopen_config *cfg = &n->cfg;
    lsm_status st;
    n->device_type = LSM_CANOPEN_DEVICE_TYPE;
    n->cycle_period_us = 0u;
    n->device_name = cfg->device_name != NULL ? cfg->device_name : "Lissom motion controller";
    n->identity[0] = cfg->vendor_id;
    n->identity[1] = cfg->product_code;
    n->identity[2] = cfg->revision;
    n->identity[3] = cfg->serial;
    n->sdo_cob_rx = 0x600u + cfg->node_id;
    n->sdo_cob_tx = 0x580u + cfg->node_id;
    n->comm_error_behaviour = 0u;
    if ((st = sdo_restart(n)) != LSM_OK)
        return st;
    if ((st = lsm_co_nmt_init(&n->nmt, cfg->node_id, cfg->heartbeat_ms)) != LSM_OK)
        return st;
    if (cfg->master_node_id != 0u && cfg->master_timeout_ms != 0u) {
        uint32_t param = ((uint32_t)cfg->master_node_id << 16) | cfg->master_timeout_ms;
        if (lsm_co_nmt_set_consumer(&n->nmt, 0, param) != 0u)
            return LSM_E_ARG;
    }
    n->emcy.cob_id = 0x80u + cfg->node_id;
    if (n->pdo_boot_valid) { /* the defaults as default_pdos built them at init, timers restarted */
        n->pdo = n->pdo_boot;
        lsm_co_pdo_restart(&n->pdo, n->now_us);
        return LSM_OK;
    }
    if ((st = lsm_co_pdo_init(&n->pdo, &n->od, cfg->node_id)) != LSM_OK)
        return st;
    if ((st = default_pdos(n)) != LSM_OK)
        return st;
    /* kept for the resets: mapping the defaults again looks up ~30 objects in the dictionary, ~40 k instructions
     * on the M4 inside a control tick, for the same result */
    n->pdo_boot = n->pdo;
    n->pdo_boot_valid = true;
    return LSM_OK;
}

static void apply_estop_level(lsm_canopen *n)
{
    for (size_t k = 0; k < n->n_axes; k++) {
        lsm_cia402_set_fault_hold(&n->axis[k], n->estop);
        if (n->estop)
            lsm_cia402_fault(&n->axis[k], LSM_CO_EMCY_EXTERNAL, false);
    }
    if (n->estop)
        lsm_co_path_hold(&n->path, true);
}

/* validated: the node's dictionary as lsm_co_od_init checked it before (an NMT reset node): kept as it is, since the
 * table is constant and its check (every entry against every other) costs ~200 k instructions on the M4, more
 * than a control tick may take. NULL: check it (lsm_canopen_init). */
static lsm_status build(lsm_canopen *n, uint32_t now_us, const lsm_co_od *validated)
{
    const lsm_canopen_config *cfg = &n->cfg;
    lsm_status st;
    lsm_co_od_config oc;
    memset(&oc, 0, sizeof oc);
    oc.table = k_od;
    oc.n_entries = sizeof k_od / sizeof k_od[0];
    oc.ranges = k_ranges;
    oc.n_ranges = R_COUNT;
    oc.groups[G_AXIS].count = cfg->n_axes;
    oc.groups[G_AXIS].index_step = 0x800u;
    oc.groups[G_AXIS].offset_step = (uint32_t)sizeof(lsm_cia402);
    oc.groups[G_RPDO].count = LSM_CO_N_RPDO;
    oc.groups[G_RPDO].index_step = 1u;
    oc.groups[G_RPDO].offset_step = (uint32_t)sizeof(lsm_co_pdo_chan);
    oc.groups[G_TPDO].count = LSM_CO_N_TPDO;
    oc.groups[G_TPDO].index_step = 1u;
    oc.groups[G_TPDO].offset_step = (uint32_t)sizeof(lsm_co_pdo_chan);
    oc.base = n;
    oc.base_size = sizeof *n;
    oc.write_hook = od_hook;
    oc.hook_ctx = n;
    if (validated != NULL)
        n->od = *validated;
    else if ((st = lsm_co_od_init(&n->od, &oc)) != LSM_OK)
        return st;
    if ((st = lsm_co_emcy_init(&n->emcy, cfg->node_id)) != LSM_OK)
        return st;
    for (size_t k = 0; k < LSM_MAX_AXES; k++) {
        if ((st = lsm_cia402_init(&n->axis[k])) != LSM_OK)
            return st;
    }
    if ((st = lsm_co_path_init(&n->path, cfg->path_storage, cfg->path_cap, cfg->n_axes)) != LSM_OK)
        return st;
    if ((st = comm_defaults(n)) != LSM_OK)
        return st;
    n->now_us = now_us;
    n->pending_reset = 0u;
    (void)lsm_co_nmt_boot(&n->nmt, now_us, &n->txq);
    apply_estop_level(n);
    if (n->estop)
        emcy_raise(n, LSM_CO_EMCY_EXTERNAL, LSM_CO_ERREG_GENERIC, 0xFFu, 0u);
    return LSM_OK;
}

lsm_canopen_config lsm_canopen_default_config(void)
{
    lsm_canopen_config c;
    memset(&c, 0, sizeof c);
    c.node_id = 1u;
    c.n_axes = 1u;
    c.heartbeat_ms = 100u;
    c.vendor_id = 0u;
    c.product_code = 0x4C534D31u; /* "LSM1" */
    c.revision = 0x00010000u;
    return c;
}

lsm_status lsm_canopen_init(lsm_canopen *n, const lsm_canopen_config *cfg, uint32_t now_us)
{
    if (n == NULL || cfg == NULL || cfg->tx_storage == NULL || cfg->path_storage == NULL)
        return LSM_E_NULL;
    if (cfg->node_id < 1u || cfg->node_id > 127u)
        return LSM_E_CO_NODE_ID;
    if (cfg->n_axes < 1u || cfg->n_axes > LSM_MAX_AXES)
        return LSM_E_CO_AXES;
    memset(n, 0, sizeof *n);
    n->cfg = *cfg;
    n->node_id = cfg->node_id;
    n->n_axes = cfg->n_axes;
    lsm_status st = lsm_can_txq_init(&n->txq, cfg->tx_storage, cfg->tx_cap);
    if (st != LSM_OK)
        return st;
    n->sdo_link.enabled = cfg->sdo_background;
    if (cfg->sdo_background && (st = sdo_init(n)) != LSM_OK) /* once: then it is the background's */
        return st;
    return build(n, now_us, NULL);
}

/* ---- NMT ----------------------------------------------------------------------------------------- */

/* A running path holds when some axis may not follow it: a feed hold if the only reason is a halt bit,
 * a quick stop along the path otherwise. */
static void couple_path(lsm_canopen *n)
{
    bool ready = true, quick = false;
    for (size_t k = 0; k < n->n_axes; k++) {
        const lsm_cia402 *ax = &n->axis[k];
        if (ax->mode_display == LSM_CIA402_MODE_PATH && lsm_cia402_motion_allowed(ax))
            continue;
        ready = false;
        if (ax->mode_display != LSM_CIA402_MODE_PATH || lsm_cia402_stop_request(ax, NULL) != LSM_CIA402_STOP_HALT)
            quick = true;
    }
    if (!ready)
        lsm_co_path_hold(&n->path, quick);
}

static void comm_lost_axes(lsm_canopen *n)
{
    for (size_t k = 0; k < n->n_axes; k++)
        lsm_cia402_comm_lost(&n->axis[k]);
    couple_path(n);
}

static void set_nmt_state(lsm_canopen *n, lsm_co_nmt_state s)
{
    uint8_t old = n->nmt.state;
    if (old == s)
        return;
    lsm_co_nmt_set_state(&n->nmt, s);
    if (old == LSM_CO_NMT_OPERATIONAL)
        comm_lost_axes(n); /* the master's PDOs no longer reach the axes: 0x6007 */
    if (s == LSM_CO_NMT_OPERATIONAL)
        lsm_co_pdo_restart(&n->pdo, n->now_us);
    if (s == LSM_CO_NMT_STOPPED)
        sdo_reset(n);
}

static void reset_comm(lsm_canopen *n)
{
    set_nmt_state(n, LSM_CO_NMT_INITIALISING);
    if (comm_defaults(n) != LSM_OK)
        return; /* cannot fail: the same configuration succeeded at init */
    (void)lsm_co_nmt_boot(&n->nmt, n->now_us, &n->txq);
}

static bool all_at_rest(const lsm_canopen *n)
{
    for (size_t k = 0; k < n->n_axes; k++) {
        if (!n->axis[k].standstill)
            return false;
    }
    return n->path.standstill;
}

static void reset_node_now(lsm_canopen *n)
{
    bool estop = n->estop, bus_off = n->bus_off;
    uint32_t malformed = n->malformed, now_us = n->now_us;
    lsm_canopen_config cfg = n->cfg;
    lsm_can_txq txq = n->txq;
    lsm_canopen_tick_stats ts = n->tick_stats;
    const lsm_co_od od = n->od;
    const lsm_co_pdo pdo_boot = n->pdo_boot;
    const bool pdo_boot_valid = n->pdo_boot_valid;
    memset(n, 0, offsetof(lsm_canopen, sdo_link)); /* the SDO server and its hand-off stay (sdo_restart) */
    n->tick_stats = ts;
    n->pdo_boot = pdo_boot;
    n->pdo_boot_valid = pdo_boot_valid;
    n->cfg = cfg;
    n->node_id = cfg.node_id;
    n->n_axes = cfg.n_axes;
    n->txq = txq;
    n->estop = estop;
    n->bus_off = bus_off;
    n->malformed = malformed;
    (void)build(n, now_us, &od);
}

static void nmt_command(lsm_canopen *n, lsm_co_nmt_cmd cmd)
{
    switch (cmd) {
    case LSM_CO_NMT_CMD_START: set_nmt_state(n, LSM_CO_NMT_OPERATIONAL); break;
    case LSM_CO_NMT_CMD_STOP: set_nmt_state(n, LSM_CO_NMT_STOPPED); break;
    case LSM_CO_NMT_CMD_PRE_OPERATIONAL: set_nmt_state(n, LSM_CO_NMT_PRE_OPERATIONAL); break;
    case LSM_CO_NMT_CMD_RESET_COMM: reset_comm(n); break;
    case LSM_CO_NMT_CMD_RESET_NODE:
        /* stop every motion with limited jerk first; lsm_canopen_process resets at rest */
        for (size_t k = 0; k < n->n_axes; k++) {
            lsm_cia402 *ax = &n->axis[k];
            if (ax->state == LSM_CIA402_OPERATION_ENABLED) {
                int16_t keep = ax->abort_option;
                ax->abort_option = 3; /* quick stop command */
                lsm_cia402_comm_lost(ax);
                ax->abort_option = keep;
            }
        }
        lsm_co_path_hold(&n->path, true);
        n->pending_reset = (uint8_t)cmd;
        break;
    default: break;
    }
}

/* ---- reception ----------------------------------------------------------------------------------- */

static void comm_error(lsm_canopen *n)
{
    switch (n->comm_error_behaviour) {
    case 0:
        if (n->nmt.state == LSM_CO_NMT_OPERATIONAL)
            set_nmt_state(n, LSM_CO_NMT_PRE_OPERATIONAL);
        break;
    case 2: set_nmt_state(n, LSM_CO_NMT_STOPPED); break;
    default: break;
    }
    comm_lost_axes(n);
}

lsm_status lsm_canopen_rx(lsm_canopen *n, const lsm_can_frame *f, uint32_t now_us)
{
    if (n == NULL || f == NULL)
        return LSM_E_NULL;
    n->now_us = now_us;
    if ((f->flags & (LSM_CAN_FLAG_EXT | LSM_CAN_FLAG_RTR)) || f->dlc > 8u || f->id > LSM_CAN_STD_ID_MAX) {
        n->malformed++;
        return LSM_E_CO_FRAME; /* CANopen uses neither 29-bit ids nor remote frames here */
    }
    lsm_status st = LSM_OK;
    uint8_t state = n->nmt.state;
    bool op = state == LSM_CO_NMT_OPERATIONAL;
    bool sdo_ok = op || state == LSM_CO_NMT_PRE_OPERATIONAL;

    if (f->id == 0u) {
        lsm_co_nmt_cmd cmd = lsm_co_nmt_decode(&n->nmt, f, &st);
        nmt_command(n, cmd);
    } else if (lsm_co_nmt_is_consumed(&n->nmt, f->id)) {
        uint32_t back = lsm_co_nmt_rx_heartbeat(&n->nmt, f, now_us, &st);
        for (size_t i = 0; i < LSM_CO_HB_CONSUMERS; i++) {
            if (back & (1u << i))
                emcy_clear(n, LSM_CO_EMCY_HEARTBEAT, (uint8_t)(n->nmt.cons[i].param >> 16));
        }
    } else if (f->id == n->sdo_cob_rx) {
        if (!sdo_ok)
            st = LSM_E_CO_NMT_STATE;
        else if (n->sdo_link.enabled)
            st = sdo_push(n, f, now_us);
        else if (lsm_co_sdo_rx(&n->sdo, f, now_us, &n->txq) == LSM_E_CO_FRAME)
            st = LSM_E_CO_FRAME; /* LSM_E_FULL: the response was dropped and counted; the client will time out */
    } else if (lsm_co_pdo_is_sync(&n->pdo, f->id)) {
        if (op) {
            st = lsm_co_pdo_sync(&n->pdo, f, now_us, &n->txq);
            if (st == LSM_E_CO_FRAME)
                emcy_event(n, LSM_CO_EMCY_SYNC_LENGTH, LSM_CO_ERREG_COMM, 0u, f->dlc);
        } else if (state == LSM_CO_NMT_STOPPED) {
            st = LSM_E_CO_NMT_STATE;
        }
    } else {
        int k = lsm_co_pdo_rpdo_of(&n->pdo, f->id);
        if (k >= 0) {
            if (!op) {
                st = LSM_E_CO_NMT_STATE;
            } else {
                lsm_co_pdo_rx_result r = lsm_co_pdo_rx(&n->pdo, (size_t)k, f);
                if (r != LSM_CO_PDO_RX_OK)
                    st = LSM_E_CO_FRAME;
                if (r == LSM_CO_PDO_RX_SHORT)
                    emcy_event(n, LSM_CO_EMCY_PDO_LENGTH, LSM_CO_ERREG_COMM, (uint8_t)k, f->dlc);
                else if (r == LSM_CO_PDO_RX_LONG)
                    emcy_event(n, LSM_CO_EMCY_PDO_LENGTH_EXCEEDED, LSM_CO_ERREG_COMM, (uint8_t)k, f->dlc);
            }
        }
    }
    if (st == LSM_E_CO_FRAME)
        n->malformed++;
    if (n->bus_off)
        lsm_can_txq_clear(&n->txq);
    return st;
}

/* ---- process ------------------------------------------------------------------------------------- */

static void update_machine_status(lsm_canopen *n)
{
    uint8_t s = 0u;
    if (n->estop)
        s |= 0x01u;
    for (size_t i = 0; i < LSM_CO_HB_CONSUMERS; i++) {
        if (n->nmt.cons[i].status == LSM_CO_HB_LOST)
            s |= 0x02u;
    }
    if (n->bus_off)
        s |= 0x04u;
    n->machine_status = s;
}

lsm_status lsm_canopen_process(lsm_canopen *n, uint32_t now_us)
{
    if (n == NULL)
        return LSM_E_NULL;
    n->now_us = now_us;
    if (n->pending_reset != 0u && all_at_rest(n)) {
        reset_node_now(n);
        return LSM_OK;
    }
    if (n->sdo_link.enabled)
        (void)sdo_tick(n);
    else
        lsm_co_sdo_process(&n->sdo, now_us, &n->txq);
    uint32_t lost = lsm_co_nmt_process(&n->nmt, now_us, &n->txq);
    if (lost != 0u) {
        for (size_t i = 0; i < LSM_CO_HB_CONSUMERS; i++) {
            if (lost & (1u << i))
                emcy_raise(n, LSM_CO_EMCY_HEARTBEAT, LSM_CO_ERREG_COMM, (uint8_t)(n->nmt.cons[i].param >> 16), 0u);
        }
        comm_error(n);
    }
    for (size_t k = 0; k < n->n_axes; k++) {
        lsm_cia402_event ev;
        while (lsm_cia402_take_event(&n->axis[k], &ev)) {
            if (ev.raise)
                emcy_raise(n, ev.code, LSM_CO_ERREG_PROFILE, (uint8_t)k, 0u);
            else
                emcy_clear(n, ev.code, (uint8_t)k);
        }
    }
    couple_path(n);
    if (n->path.reject_pending) {
        n->path.reject_pending = false;
        emcy_event(n, LSM_CO_EMCY_PATH_REJECTED, LSM_CO_ERREG_MANUFACTURER, 0xFFu, n->path.reject_seq);
    }
    if (n->txq.dropped != n->tx_dropped_seen && n->txq.count < n->txq.cap) {
        n->tx_dropped_seen = n->txq.dropped;
        emcy_event(n, LSM_CO_EMCY_CAN_OVERRUN, LSM_CO_ERREG_COMM, 0u, n->txq.dropped);
    }
    if (n->nmt.state == LSM_CO_NMT_OPERATIONAL)
        lsm_co_pdo_process(&n->pdo, now_us, &n->txq);
    update_machine_status(n);
    if (n->bus_off) {
        lsm_can_txq_clear(&n->txq);
        return LSM_E_CO_BUS_OFF;
    }
    return LSM_OK;
}

bool lsm_canopen_tx_pop(lsm_canopen *n, lsm_can_frame *out)
{
    if (n == NULL || out == NULL)
        return false;
    return lsm_can_txq_pop(&n->txq, out);
}

void lsm_canopen_bus_event(lsm_canopen *n, lsm_can_bus_event ev, uint32_t now_us)
{
    if (n == NULL)
        return;
    n->now_us = now_us;
    switch (ev) {
    case LSM_CAN_BUS_OFF:
        if (!n->bus_off) {
            n->bus_off = true;
            lsm_can_txq_clear(&n->txq);
            emcy_raise(n, LSM_CO_EMCY_COMM, LSM_CO_ERREG_COMM, 0u, 0u); /* latched, not sendable */
            comm_error(n);
        }
        break;
    case LSM_CAN_BUS_OK:
        n->error_passive = false;
        if (n->bus_off) {
            n->bus_off = false;
            n->tx_dropped_seen = n->txq.dropped;
            emcy_event(n, LSM_CO_EMCY_BUS_OFF_RECOVERED, LSM_CO_ERREG_COMM, 0u, 0u);
            emcy_clear(n, LSM_CO_EMCY_COMM, 0u);
        }
        break;
    case LSM_CAN_BUS_ERROR_PASSIVE:
        if (!n->error_passive && !n->bus_off) {
            n->error_passive = true;
            emcy_event(n, LSM_CO_EMCY_CAN_PASSIVE, LSM_CO_ERREG_COMM, 0u, 0u);
        }
        break;
    case LSM_CAN_BUS_RX_OVERRUN: emcy_event(n, LSM_CO_EMCY_CAN_OVERRUN, LSM_CO_ERREG_COMM, 1u, 0u); break;
    default: break;
    }
    update_machine_status(n);
    if (n->bus_off)
        lsm_can_txq_clear(&n->txq);
}

void lsm_canopen_estop(lsm_canopen *n, bool active, uint32_t now_us)
{
    if (n == NULL || active == n->estop)
        return;
    n->now_us = now_us;
    n->estop = active;
    apply_estop_level(n);
    if (active)
        emcy_raise(n, LSM_CO_EMCY_EXTERNAL, LSM_CO_ERREG_GENERIC, 0xFFu, 0u);
    else
        emcy_clear(n, LSM_CO_EMCY_EXTERNAL, 0xFFu);
    update_machine_status(n);
}

lsm_status lsm_canopen_axis_fault(lsm_canopen *n, size_t k, uint16_t code)
{
    if (n == NULL)
        return LSM_E_NULL;
    if (k >= n->n_axes)
        return LSM_E_ARG;
    lsm_cia402_fault(&n->axis[k], code, true);
    return LSM_OK;
}

lsm_cia402 *lsm_canopen_axis(lsm_canopen *n, size_t k)
{
    return (n != NULL && k < n->n_axes) ? &n->axis[k] : NULL;
}

lsm_co_path *lsm_canopen_path(lsm_canopen *n)
{
    return n != NULL ? &n->path : NULL;
}

lsm_co_od *lsm_canopen_od(lsm_canopen *n)
{
    return n != NULL ? &n->od : NULL;
}

lsm_co_nmt_state lsm_canopen_nmt_state(const lsm_canopen *n)
{
    return (lsm_co_nmt_state)n->nmt.state;
}

uint32_t lsm_canopen_sync_count(const lsm_canopen *n)
{
    return n->pdo.syncs;
}

bool lsm_canopen_drive_enable(const lsm_canopen *n)
{
    for (size_t k = 0; k < n->n_axes; k++) {
        if (lsm_cia402_power_enabled(&n->axis[k]))
            return true;
    }
    return false;
}

bool lsm_canopen_in_position(const lsm_canopen *n)
{
    for (size_t k = 0; k < n->n_axes; k++) {
        if (!lsm_cia402_in_position(&n->axis[k]))
            return false;
    }
    return true;
}

void lsm_canopen_set_tick_stats(lsm_canopen *node, const lsm_canopen_tick_stats *stats)
{
    if (node != NULL && stats != NULL)
        node->tick_stats = *stats;
}
