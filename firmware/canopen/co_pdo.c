#include "co_pdo.h"

#include <string.h>

static lsm_co_pdo_chan *chan(lsm_co_pdo *pdo, bool tx, size_t k)
{
    if (tx)
        return k < LSM_CO_N_TPDO ? &pdo->tpdo[k] : NULL;
    return k < LSM_CO_N_RPDO ? &pdo->rpdo[k] : NULL;
}

static uint32_t default_cob_id(bool tx, size_t k, uint8_t node_id)
{
    uint32_t id = LSM_CO_PDO_INVALID | (tx ? LSM_CO_PDO_NO_RTR : 0u); /* RPDO: bit 30 reserved */
    if (k < 4u)
        id |= (tx ? 0x180u : 0x200u) + 0x100u * (uint32_t)k + node_id;
    return id;
}

lsm_status lsm_co_pdo_init(lsm_co_pdo *pdo, lsm_co_od *od, uint8_t node_id)
{
    if (pdo == NULL || od == NULL)
        return LSM_E_NULL;
    if (node_id < 1u || node_id > 127u)
        return LSM_E_CO_NODE_ID;
    memset(pdo, 0, sizeof *pdo);
    pdo->od = od;
    pdo->node_id = node_id;
    pdo->sync_cob_id = 0x80u;
    for (size_t k = 0; k < LSM_CO_N_RPDO; k++) {
        pdo->rpdo[k].cob_id = default_cob_id(false, k, node_id);
        pdo->rpdo[k].trans_type = 255u;
    }
    for (size_t k = 0; k < LSM_CO_N_TPDO; k++) {
        pdo->tpdo[k].cob_id = default_cob_id(true, k, node_id);
        pdo->tpdo[k].trans_type = 255u;
    }
    return LSM_OK;
}

static bool valid(const lsm_co_pdo_chan *c)
{
    return (c->cob_id & LSM_CO_PDO_INVALID) == 0u;
}

/* CiA 301 Table 3: identifiers no PDO may use. */
static bool restricted_id(uint32_t id)
{
    return id == 0x000u || (id >= 0x001u && id <= 0x07Fu) || (id >= 0x101u && id <= 0x180u) ||
           (id >= 0x581u && id <= 0x5FFu) || (id >= 0x601u && id <= 0x67Fu) || (id >= 0x6E0u && id <= 0x6FFu) ||
           (id >= 0x701u && id <= 0x77Fu) || (id >= 0x780u && id <= 0x7FFu);
}

static bool trans_type_ok(uint32_t t)
{
    return t <= 240u || t == 254u || t == 255u;
}

/* Resolves mapping entry m for direction tx: table entry, instance and bytes. m == 0 is an empty entry. */
static uint32_t resolve(const lsm_co_pdo *pdo, bool tx, uint32_t m, uint16_t *entry, uint8_t *inst, uint8_t *bytes)
{
    *entry = 0u;
    *inst = 0u;
    *bytes = 0u;
    if (m == 0u)
        return LSM_CO_ABORT_NONE;
    lsm_co_od_ref ref;
    if (lsm_co_od_find(pdo->od, (uint16_t)(m >> 16), (uint8_t)(m >> 8), &ref) != 0u)
        return LSM_CO_ABORT_NOT_MAPPABLE;
    uint8_t need = tx ? LSM_CO_OD_TPDO : LSM_CO_OD_RPDO;
    if (!(ref.entry->flags & need))
        return LSM_CO_ABORT_NOT_MAPPABLE;
    if ((m & 0xFFu) != 8u * ref.entry->size)
        return LSM_CO_ABORT_NOT_MAPPABLE;
    *entry = (uint16_t)(ref.entry - pdo->od->cfg.table);
    *inst = ref.inst;
    *bytes = ref.entry->size;
    return LSM_CO_ABORT_NONE;
}

static void restart_chan(lsm_co_pdo_chan *c, uint32_t now_us)
{
    c->pending = false;
    c->sent_once = false;
    c->len_err = false;
    c->sync_count = 0u;
    c->inhibit_until_us = now_us;
    c->event_due_us = now_us + (uint32_t)c->event_ms * 1000u;
}

void lsm_co_pdo_restart(lsm_co_pdo *pdo, uint32_t now_us)
{
    for (size_t k = 0; k < LSM_CO_N_RPDO; k++)
        restart_chan(&pdo->rpdo[k], now_us);
    for (size_t k = 0; k < LSM_CO_N_TPDO; k++)
        restart_chan(&pdo->tpdo[k], now_us);
}

uint32_t lsm_co_pdo_write_comm(lsm_co_pdo *pdo, bool tx, size_t k, uint8_t sub, uint32_t value, uint32_t now_us)
{
    lsm_co_pdo_chan *c = chan(pdo, tx, k);
    if (c == NULL)
        return LSM_CO_ABORT_NO_OBJECT;
    switch (sub) {
    case 1: {
        if (value & LSM_CO_PDO_EXT)
            return LSM_CO_ABORT_VALUE;
        bool now_valid = (value & LSM_CO_PDO_INVALID) == 0u;
        uint32_t id = value & 0x7FFu;
        if ((value & 0x1FFFF800u) != 0u)
            return LSM_CO_ABORT_VALUE; /* bits 11..28 must be 0 for an 11-bit id */
        if (now_valid && restricted_id(id))
            return LSM_CO_ABORT_VALUE;
        if (now_valid && valid(c) && id != (c->cob_id & 0x7FFu))
            return LSM_CO_ABORT_VALUE; /* CiA 301: the id may not change while the PDO exists */
        bool was_valid = valid(c);
        c->cob_id = value | (tx ? LSM_CO_PDO_NO_RTR : 0u);
        if (now_valid && !was_valid)
            restart_chan(c, now_us);
        return LSM_CO_ABORT_NONE;
    }
    case 2:
        if (!trans_type_ok(value))
            return LSM_CO_ABORT_VALUE;
        c->trans_type = (uint8_t)value;
        c->sync_count = 0u;
        c->pending = false;
        return LSM_CO_ABORT_NONE;
    case 3:
        if (!tx)
            return LSM_CO_ABORT_NO_SUB;
        if (valid(c))
            return LSM_CO_ABORT_DEVICE_STATE;
        c->inhibit_100us = (uint16_t)value;
        return LSM_CO_ABORT_NONE;
    case 5:
        c->event_ms = (uint16_t)value;
        c->event_due_us = now_us + value * 1000u;
        return LSM_CO_ABORT_NONE;
    default: return LSM_CO_ABORT_NO_SUB;
    }
}

uint32_t lsm_co_pdo_write_map(lsm_co_pdo *pdo, bool tx, size_t k, uint8_t sub, uint32_t value)
{
    lsm_co_pdo_chan *c = chan(pdo, tx, k);
    if (c == NULL)
        return LSM_CO_ABORT_NO_OBJECT;
    if (valid(c))
        return LSM_CO_ABORT_DEVICE_STATE;
    if (sub == 0u) {
        if (value > LSM_CO_PDO_MAX_MAP)
            return LSM_CO_ABORT_VALUE_HIGH;
        uint32_t bits = 0u;
        for (size_t i = 0; i < value; i++) {
            uint16_t e;
            uint8_t inst, bytes;
            if (c->map[i] == 0u)
                return LSM_CO_ABORT_NOT_MAPPABLE;
            uint32_t ab = resolve(pdo, tx, c->map[i], &e, &inst, &bytes);
            if (ab)
                return ab;
            bits += 8u * bytes;
        }
        if (bits > 64u)
            return LSM_CO_ABORT_PDO_LENGTH;
        c->n_map = (uint8_t)value;
        c->dlc = (uint8_t)(bits / 8u);
        return LSM_CO_ABORT_NONE;
    }
    if (sub > LSM_CO_PDO_MAX_MAP)
        return LSM_CO_ABORT_NO_SUB;
    if (c->n_map != 0u)
        return LSM_CO_ABORT_DEVICE_STATE;
    uint16_t e;
    uint8_t inst, bytes;
    uint32_t ab = resolve(pdo, tx, value, &e, &inst, &bytes);
    if (ab)
        return ab;
    c->map[sub - 1u] = value;
    c->map_entry[sub - 1u] = e;
    c->map_inst[sub - 1u] = inst;
    return LSM_CO_ABORT_NONE;
}

uint32_t lsm_co_pdo_write_sync_id(lsm_co_pdo *pdo, uint32_t value)
{
    if (value & (0x40000000u | LSM_CO_PDO_EXT | 0x1FFFF800u))
        return LSM_CO_ABORT_VALUE; /* we never produce SYNC; 11-bit ids only */
    pdo->sync_cob_id = value;
    return LSM_CO_ABORT_NONE;
}

lsm_status lsm_co_pdo_configure(lsm_co_pdo *pdo, bool tx, size_t k, uint8_t trans_type, const uint32_t *maps, size_t n,
                                bool valid_now)
{
    lsm_co_pdo_chan *c = chan(pdo, tx, k);
    if (c == NULL || n > LSM_CO_PDO_MAX_MAP || !trans_type_ok(trans_type) || (n != 0u && maps == NULL))
        return LSM_E_ARG;
    c->cob_id |= LSM_CO_PDO_INVALID;
    c->trans_type = trans_type;
    if (lsm_co_pdo_write_map(pdo, tx, k, 0u, 0u) != 0u)
        return LSM_E_CO_MAPPING;
    for (size_t i = 0; i < LSM_CO_PDO_MAX_MAP; i++) {
        if (lsm_co_pdo_write_map(pdo, tx, k, (uint8_t)(i + 1u), i < n ? maps[i] : 0u) != 0u)
            return LSM_E_CO_MAPPING;
    }
    if (lsm_co_pdo_write_map(pdo, tx, k, 0u, (uint32_t)n) != 0u)
        return LSM_E_CO_MAPPING;
    if (valid_now) {
        uint32_t id = default_cob_id(tx, k, pdo->node_id) & ~LSM_CO_PDO_INVALID;
        if (lsm_co_pdo_write_comm(pdo, tx, k, 1u, id, 0u) != 0u)
            return LSM_E_ARG; /* PDO 5 and above have no default COB-ID */
    }
    return LSM_OK;
}

int lsm_co_pdo_rpdo_of(const lsm_co_pdo *pdo, uint32_t id)
{
    for (size_t k = 0; k < LSM_CO_N_RPDO; k++) {
        const lsm_co_pdo_chan *c = &pdo->rpdo[k];
        if (valid(c) && (c->cob_id & 0x7FFu) == id)
            return (int)k;
    }
    return -1;
}

bool lsm_co_pdo_is_sync(const lsm_co_pdo *pdo, uint32_t id)
{
    return (pdo->sync_cob_id & 0x7FFu) == id;
}

static void apply(lsm_co_pdo *pdo, const lsm_co_pdo_chan *c, const uint8_t *data)
{
    size_t off = 0;
    for (size_t i = 0; i < c->n_map; i++) {
        lsm_co_od_ref ref;
        if (lsm_co_od_ref_at(pdo->od, c->map_entry[i], c->map_inst[i], &ref) != 0u) {
            pdo->rx_refused++;
            continue;
        }
        size_t n = ref.entry->size;
        if (lsm_co_od_write(pdo->od, &ref, &data[off], n) != 0u)
            pdo->rx_refused++;
        off += n;
    }
}

lsm_co_pdo_rx_result lsm_co_pdo_rx(lsm_co_pdo *pdo, size_t k, const lsm_can_frame *f)
{
    lsm_co_pdo_chan *c = &pdo->rpdo[k];
    lsm_co_pdo_rx_result res = LSM_CO_PDO_RX_OK;
    if (f->dlc < c->dlc || (f->flags & LSM_CAN_FLAG_RTR)) {
        pdo->rx_length_errors++;
        res = c->len_err ? LSM_CO_PDO_RX_QUIET : LSM_CO_PDO_RX_SHORT;
        c->len_err = true;
        return res;
    }
    if (f->dlc > c->dlc) {
        pdo->rx_length_errors++;
        res = c->len_err ? LSM_CO_PDO_RX_QUIET : LSM_CO_PDO_RX_LONG;
        c->len_err = true;
    } else {
        c->len_err = false;
    }
    if (c->trans_type <= 240u) {
        memcpy(c->buf, f->data, c->dlc);
        c->pending = true;
    } else {
        apply(pdo, c, f->data);
    }
    return res;
}

/* Samples the mapped objects of TPDO c into data. */
static void sample(lsm_co_pdo *pdo, const lsm_co_pdo_chan *c, uint8_t *data)
{
    size_t off = 0;
    memset(data, 0, 8);
    for (size_t i = 0; i < c->n_map; i++) {
        lsm_co_od_ref ref;
        size_t n = 0;
        if (lsm_co_od_ref_at(pdo->od, c->map_entry[i], c->map_inst[i], &ref) == 0u)
            (void)lsm_co_od_read(pdo->od, &ref, &data[off], 8u - off, &n);
        off += c->map_entry[i] < pdo->od->cfg.n_entries ? pdo->od->cfg.table[c->map_entry[i]].size : 0u;
    }
}

static void transmit(lsm_co_pdo_chan *c, const uint8_t *data, uint32_t now_us, lsm_can_txq *txq)
{
    lsm_can_frame f = {0};
    f.id = c->cob_id & 0x7FFu;
    f.dlc = c->dlc;
    memcpy(f.data, data, 8);
    (void)lsm_can_txq_push(txq, &f);
    memcpy(c->buf, data, 8);
    c->sent_once = true;
    c->inhibit_until_us = now_us + (uint32_t)c->inhibit_100us * 100u;
    c->event_due_us = now_us + (uint32_t)c->event_ms * 1000u;
}

lsm_status lsm_co_pdo_sync(lsm_co_pdo *pdo, const lsm_can_frame *f, uint32_t now_us, lsm_can_txq *txq)
{
    if (f->dlc != 0u || (f->flags & LSM_CAN_FLAG_RTR))
        return LSM_E_CO_FRAME;
    pdo->syncs++;
    for (size_t k = 0; k < LSM_CO_N_TPDO; k++) {
        lsm_co_pdo_chan *c = &pdo->tpdo[k];
        if (!valid(c) || c->trans_type > 240u)
            continue;
        uint8_t data[8];
        if (c->trans_type == 0u) {
            sample(pdo, c, data);
            if (!c->sent_once || memcmp(data, c->buf, c->dlc) != 0)
                transmit(c, data, now_us, txq);
            continue;
        }
        if (++c->sync_count >= c->trans_type) {
            c->sync_count = 0u;
            sample(pdo, c, data);
            transmit(c, data, now_us, txq);
        }
    }
    for (size_t k = 0; k < LSM_CO_N_RPDO; k++) {
        lsm_co_pdo_chan *c = &pdo->rpdo[k];
        if (c->pending && valid(c) && c->trans_type <= 240u)
            apply(pdo, c, c->buf);
        c->pending = false;
    }
    return LSM_OK;
}

void lsm_co_pdo_process(lsm_co_pdo *pdo, uint32_t now_us, lsm_can_txq *txq)
{
    for (size_t k = 0; k < LSM_CO_N_TPDO; k++) {
        lsm_co_pdo_chan *c = &pdo->tpdo[k];
        if (!valid(c) || c->trans_type < 254u)
            continue;
        if ((int32_t)(now_us - c->inhibit_until_us) < 0)
            continue;
        uint8_t data[8];
        sample(pdo, c, data);
        bool changed = !c->sent_once || memcmp(data, c->buf, c->dlc) != 0;
        bool timer = c->event_ms != 0u && (int32_t)(now_us - c->event_due_us) >= 0;
        if (changed || timer)
            transmit(c, data, now_us, txq);
    }
}
