#include "co_nmt.h"

#include <string.h>

lsm_status lsm_co_nmt_init(lsm_co_nmt *nmt, uint8_t node_id, uint16_t producer_ms)
{
    if (nmt == NULL)
        return LSM_E_NULL;
    if (node_id < 1u || node_id > 127u)
        return LSM_E_CO_NODE_ID;
    memset(nmt, 0, sizeof *nmt);
    nmt->node_id = node_id;
    nmt->state = LSM_CO_NMT_INITIALISING;
    nmt->producer_ms = producer_ms;
    return LSM_OK;
}

static uint8_t cons_node(uint32_t param)
{
    return (uint8_t)((param >> 16) & 0xFFu);
}

static uint32_t cons_time_us(uint32_t param)
{
    return (param & 0xFFFFu) * 1000u;
}

static bool cons_enabled(uint32_t param)
{
    return cons_node(param) != 0u && (param & 0xFFFFu) != 0u;
}

lsm_status lsm_co_nmt_boot(lsm_co_nmt *nmt, uint32_t now_us, lsm_can_txq *txq)
{
    lsm_can_frame f = {0};
    f.id = 0x700u + nmt->node_id;
    f.dlc = 1u;
    f.data[0] = LSM_CO_NMT_INITIALISING;
    nmt->state = LSM_CO_NMT_PRE_OPERATIONAL;
    nmt->next_hb_us = now_us + (uint32_t)nmt->producer_ms * 1000u;
    for (size_t i = 0; i < LSM_CO_HB_CONSUMERS; i++)
        nmt->cons[i].status = cons_enabled(nmt->cons[i].param) ? LSM_CO_HB_WAITING : LSM_CO_HB_OFF;
    return lsm_can_txq_push(txq, &f);
}

lsm_co_nmt_cmd lsm_co_nmt_decode(lsm_co_nmt *nmt, const lsm_can_frame *f, lsm_status *st)
{
    *st = LSM_OK;
    if (f->dlc != 2u || (f->flags & (LSM_CAN_FLAG_RTR | LSM_CAN_FLAG_EXT))) {
        nmt->malformed++;
        *st = LSM_E_CO_FRAME;
        return LSM_CO_NMT_CMD_NONE;
    }
    if (f->data[1] != 0u && f->data[1] != nmt->node_id)
        return LSM_CO_NMT_CMD_NONE;
    switch (f->data[0]) {
    case LSM_CO_NMT_CMD_START:
    case LSM_CO_NMT_CMD_STOP:
    case LSM_CO_NMT_CMD_PRE_OPERATIONAL:
    case LSM_CO_NMT_CMD_RESET_NODE:
    case LSM_CO_NMT_CMD_RESET_COMM: return (lsm_co_nmt_cmd)f->data[0];
    default: return LSM_CO_NMT_CMD_NONE; /* unknown command specifier: CiA 301 says ignore */
    }
}

void lsm_co_nmt_set_state(lsm_co_nmt *nmt, lsm_co_nmt_state state)
{
    nmt->state = (uint8_t)state;
}

void lsm_co_nmt_set_producer(lsm_co_nmt *nmt, uint16_t period_ms, uint32_t now_us)
{
    nmt->producer_ms = period_ms;
    nmt->next_hb_us = now_us + (uint32_t)period_ms * 1000u;
}

uint32_t lsm_co_nmt_set_consumer(lsm_co_nmt *nmt, size_t i, uint32_t param)
{
    if (i >= LSM_CO_HB_CONSUMERS)
        return LSM_CO_ABORT_NO_SUB;
    if ((param >> 24) != 0u || cons_node(param) > 127u)
        return LSM_CO_ABORT_VALUE;
    if (cons_enabled(param)) {
        for (size_t j = 0; j < LSM_CO_HB_CONSUMERS; j++) {
            if (j != i && cons_enabled(nmt->cons[j].param) && cons_node(nmt->cons[j].param) == cons_node(param))
                return LSM_CO_ABORT_PARAM_INCOMPAT;
        }
    }
    nmt->cons[i].param = param;
    nmt->cons[i].status = cons_enabled(param) ? LSM_CO_HB_WAITING : LSM_CO_HB_OFF;
    return 0u;
}

bool lsm_co_nmt_is_consumed(const lsm_co_nmt *nmt, uint32_t id)
{
    if (id <= 0x700u || id > 0x77Fu)
        return false;
    for (size_t i = 0; i < LSM_CO_HB_CONSUMERS; i++) {
        if (cons_enabled(nmt->cons[i].param) && 0x700u + cons_node(nmt->cons[i].param) == id)
            return true;
    }
    return false;
}

uint32_t lsm_co_nmt_rx_heartbeat(lsm_co_nmt *nmt, const lsm_can_frame *f, uint32_t now_us, lsm_status *st)
{
    *st = LSM_OK;
    if (f->dlc != 1u || (f->flags & (LSM_CAN_FLAG_RTR | LSM_CAN_FLAG_EXT))) {
        nmt->malformed++;
        *st = LSM_E_CO_FRAME;
        return 0u;
    }
    uint32_t resumed = 0u;
    for (size_t i = 0; i < LSM_CO_HB_CONSUMERS; i++) {
        lsm_co_hb_consumer *c = &nmt->cons[i];
        if (!cons_enabled(c->param) || 0x700u + cons_node(c->param) != f->id)
            continue;
        if (c->status == LSM_CO_HB_LOST)
            resumed |= 1u << i;
        c->status = LSM_CO_HB_ACTIVE;
        c->last_us = now_us;
        c->remote_state = f->data[0];
    }
    return resumed;
}

uint32_t lsm_co_nmt_process(lsm_co_nmt *nmt, uint32_t now_us, lsm_can_txq *txq)
{
    if (nmt->state != LSM_CO_NMT_INITIALISING && nmt->producer_ms != 0u && (int32_t)(now_us - nmt->next_hb_us) >= 0) {
        lsm_can_frame f = {0};
        f.id = 0x700u + nmt->node_id;
        f.dlc = 1u;
        f.data[0] = nmt->state;
        (void)lsm_can_txq_push(txq, &f);
        uint32_t period_us = (uint32_t)nmt->producer_ms * 1000u;
        nmt->next_hb_us += period_us;
        if ((int32_t)(now_us - nmt->next_hb_us) >= 0) /* called late: do not send a burst */
            nmt->next_hb_us = now_us + period_us;
    }
    uint32_t lost = 0u;
    for (size_t i = 0; i < LSM_CO_HB_CONSUMERS; i++) {
        lsm_co_hb_consumer *c = &nmt->cons[i];
        if (c->status != LSM_CO_HB_ACTIVE)
            continue;
        if ((int32_t)(now_us - c->last_us) > (int32_t)cons_time_us(c->param)) {
            c->status = LSM_CO_HB_LOST;
            lost |= 1u << i;
        }
    }
    return lost;
}
