#include "co_emcy.h"

#include <string.h>

#include "co_od.h"

lsm_status lsm_co_emcy_init(lsm_co_emcy *emcy, uint8_t node_id)
{
    if (emcy == NULL)
        return LSM_E_NULL;
    if (node_id < 1u || node_id > 127u)
        return LSM_E_CO_NODE_ID;
    memset(emcy, 0, sizeof *emcy);
    emcy->cob_id = 0x80u + node_id;
    return LSM_OK;
}

static void recompute(lsm_co_emcy *emcy)
{
    uint8_t reg = emcy->overflow_reg;
    for (size_t i = 0; i < emcy->n_active; i++)
        reg |= emcy->active[i].reg;
    if (emcy->n_active != 0u || emcy->overflow != 0u)
        reg |= LSM_CO_ERREG_GENERIC;
    emcy->error_register = reg;
}

static void push_history(lsm_co_emcy *emcy, uint16_t code, uint8_t info)
{
    size_t n = emcy->n_history < LSM_CO_EMCY_HISTORY ? emcy->n_history : LSM_CO_EMCY_HISTORY - 1u;
    memmove(&emcy->history[1], &emcy->history[0], n * sizeof emcy->history[0]);
    emcy->history[0] = ((uint32_t)info << 16) | code;
    if (emcy->n_history < LSM_CO_EMCY_HISTORY)
        emcy->n_history++;
}

static lsm_status send(lsm_co_emcy *emcy, uint16_t code, uint8_t reg, uint8_t info, uint32_t extra, bool can_send,
                       lsm_can_txq *txq)
{
    if (code != LSM_CO_EMCY_NO_ERROR)
        push_history(emcy, code, info);
    if (!can_send) {
        emcy->suppressed++;
        return LSM_OK;
    }
    lsm_can_frame f = {0};
    f.id = emcy->cob_id & 0x7FFu;
    f.dlc = 8u;
    lsm_can_put_u16(&f.data[0], code);
    f.data[2] = reg;
    f.data[3] = info;
    lsm_can_put_u32(&f.data[4], extra);
    lsm_status st = lsm_can_txq_push(txq, &f);
    if (st == LSM_OK)
        emcy->sent++;
    else
        emcy->suppressed++;
    return st;
}

static int find(const lsm_co_emcy *emcy, uint16_t code, uint8_t info)
{
    for (size_t i = 0; i < emcy->n_active; i++) {
        if (emcy->active[i].code == code && emcy->active[i].info == info)
            return (int)i;
    }
    return -1;
}

bool lsm_co_emcy_is_active(const lsm_co_emcy *emcy, uint16_t code, uint8_t info)
{
    return find(emcy, code, info) >= 0;
}

lsm_status lsm_co_emcy_raise(lsm_co_emcy *emcy, uint16_t code, uint8_t reg_bits, uint8_t info, uint32_t extra,
                             bool can_send, lsm_can_txq *txq)
{
    if (find(emcy, code, info) >= 0)
        return LSM_OK;
    if (emcy->n_active < LSM_CO_EMCY_ACTIVE) {
        lsm_co_emcy_cond *c = &emcy->active[emcy->n_active++];
        c->code = code;
        c->reg = reg_bits;
        c->info = info;
    } else {
        /* cannot track it: keep its bits latched until every condition is gone */
        if (emcy->overflow < 255u)
            emcy->overflow++;
        emcy->overflow_reg |= reg_bits;
    }
    recompute(emcy);
    return send(emcy, code, emcy->error_register, info, extra, can_send, txq);
}

lsm_status lsm_co_emcy_clear(lsm_co_emcy *emcy, uint16_t code, uint8_t info, bool can_send, lsm_can_txq *txq)
{
    int i = find(emcy, code, info);
    if (i < 0)
        return LSM_OK;
    emcy->n_active--;
    memmove(&emcy->active[i], &emcy->active[i + 1], (emcy->n_active - (size_t)i) * sizeof emcy->active[0]);
    if (emcy->n_active == 0u) {
        emcy->overflow = 0u;
        emcy->overflow_reg = 0u;
    }
    recompute(emcy);
    if (emcy->n_active == 0u)
        return send(emcy, LSM_CO_EMCY_NO_ERROR, emcy->error_register, 0u, 0u, can_send, txq);
    return LSM_OK;
}

lsm_status lsm_co_emcy_event(lsm_co_emcy *emcy, uint16_t code, uint8_t reg_bits, uint8_t info, uint32_t extra,
                             bool can_send, lsm_can_txq *txq)
{
    return send(emcy, code, (uint8_t)(emcy->error_register | reg_bits | LSM_CO_ERREG_GENERIC), info, extra, can_send,
                txq);
}

uint32_t lsm_co_emcy_write_history_count(lsm_co_emcy *emcy, int64_t value)
{
    if (value != 0)
        return LSM_CO_ABORT_VALUE;
    emcy->n_history = 0u;
    memset(emcy->history, 0, sizeof emcy->history);
    return LSM_CO_ABORT_NONE;
}
