#include "can.h"

lsm_status lsm_can_txq_init(lsm_can_txq *q, lsm_can_frame *storage, size_t cap)
{
    if (q == NULL || storage == NULL)
        return LSM_E_NULL;
    if (cap == 0u || cap > 65535u)
        return LSM_E_ARG;
    q->buf = storage;
    q->cap = (uint16_t)cap;
    q->head = 0u;
    q->count = 0u;
    q->dropped = 0u;
    return LSM_OK;
}

lsm_status lsm_can_txq_push(lsm_can_txq *q, const lsm_can_frame *f)
{
    if (q->count >= q->cap) {
        q->dropped++;
        return LSM_E_FULL;
    }
    uint32_t tail = (uint32_t)q->head + q->count;
    if (tail >= q->cap)
        tail -= q->cap;
    q->buf[tail] = *f;
    q->count++;
    return LSM_OK;
}

bool lsm_can_txq_pop(lsm_can_txq *q, lsm_can_frame *out)
{
    if (q->count == 0u)
        return false;
    *out = q->buf[q->head];
    q->head = (uint16_t)(q->head + 1u == q->cap ? 0u : q->head + 1u);
    q->count--;
    return true;
}

size_t lsm_can_txq_count(const lsm_can_txq *q)
{
    return q->count;
}

void lsm_can_txq_clear(lsm_can_txq *q)
{
    q->head = 0u;
    q->count = 0u;
}

uint16_t lsm_can_get_u16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (uint16_t)(p[1] << 8));
}

uint32_t lsm_can_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

void lsm_can_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

void lsm_can_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

uint64_t lsm_can_get_le(const uint8_t *p, size_t n)
{
    uint64_t v = 0u;
    for (size_t i = n; i > 0u; i--)
        v = (v << 8) | p[i - 1u];
    return v;
}

void lsm_can_put_le(uint8_t *p, uint64_t v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        p[i] = (uint8_t)v;
        v >>= 8;
    }
}
