#include "co_sdo.h"

#include <string.h>

lsm_status lsm_co_sdo_init(lsm_co_sdo *sdo, lsm_co_od *od, uint8_t node_id, uint8_t *buf, size_t cap,
                           uint32_t timeout_us)
{
    if (sdo == NULL || od == NULL || buf == NULL)
        return LSM_E_NULL;
    if (node_id < 1u || node_id > 127u)
        return LSM_E_CO_NODE_ID;
    if (cap < 8u || cap > 65535u)
        return LSM_E_ARG;
    memset(sdo, 0, sizeof *sdo);
    sdo->od = od;
    sdo->buf = buf;
    sdo->cap = (uint16_t)cap;
    sdo->rx_id = (uint16_t)(0x600u + node_id);
    sdo->tx_id = (uint16_t)(0x580u + node_id);
    sdo->timeout_us = timeout_us ? timeout_us : LSM_CO_SDO_TIMEOUT_US;
    return LSM_OK;
}

void lsm_co_sdo_reset(lsm_co_sdo *sdo)
{
    sdo->phase = LSM_CO_SDO_IDLE;
}

static lsm_status send(lsm_co_sdo *sdo, const uint8_t d[8], lsm_can_txq *txq)
{
    lsm_can_frame f;
    f.id = sdo->tx_id;
    f.dlc = 8u;
    f.flags = 0u;
    memcpy(f.data, d, 8);
    return lsm_can_txq_push(txq, &f);
}

static lsm_status send_abort(lsm_co_sdo *sdo, uint16_t index, uint8_t sub, uint32_t code, lsm_can_txq *txq)
{
    uint8_t d[8];
    d[0] = 0x80u;
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
    lsm_can_put_u32(&d[4], code);
    sdo->phase = LSM_CO_SDO_IDLE;
    sdo->aborts_sent++;
    sdo->last_abort = code;
    return send(sdo, d, txq);
}

static lsm_status initiate_download(lsm_co_sdo *sdo, const uint8_t *r, uint32_t now_us, lsm_can_txq *txq)
{
    uint16_t index = lsm_can_get_u16(&r[1]);
    uint8_t sub = r[3];
    bool expedited = (r[0] & 0x02u) != 0u;
    bool sized = (r[0] & 0x01u) != 0u;
    lsm_co_od_ref ref;
    uint32_t ab = lsm_co_od_find(sdo->od, index, sub, &ref);
    if (ab)
        return send_abort(sdo, index, sub, ab, txq);
    if (!(ref.entry->flags & LSM_CO_OD_W))
        return send_abort(sdo, index, sub, LSM_CO_ABORT_READ_ONLY, txq);
    size_t ts = lsm_co_od_type_size(ref.entry->type);
    if (expedited) {
        size_t len;
        if (sized)
            len = 4u - ((r[0] >> 2) & 0x03u);
        else
            len = (ts != 0u && ts < 4u) ? ts : 4u; /* size not indicated: the object's own size */
        ab = lsm_co_od_write(sdo->od, &ref, &r[4], len);
        if (ab)
            return send_abort(sdo, index, sub, ab, txq);
    } else {
        uint32_t size = sized ? lsm_can_get_u32(&r[4]) : 0u;
        if (sized) {
            /* refuse at once what can never fit, instead of after all the segments */
            size_t maxlen = ts != 0u ? ts : ref.entry->size;
            if (size > maxlen)
                return send_abort(sdo, index, sub, LSM_CO_ABORT_LENGTH_HIGH, txq);
            if (ts != 0u && size < ts)
                return send_abort(sdo, index, sub, LSM_CO_ABORT_LENGTH_LOW, txq);
            if (size > sdo->cap)
                return send_abort(sdo, index, sub, LSM_CO_ABORT_NO_MEM, txq);
        }
        sdo->phase = LSM_CO_SDO_DOWNLOAD;
        sdo->ref = ref;
        sdo->size_known = sized;
        sdo->size = size;
        sdo->pos = 0u;
        sdo->toggle = 0u;
        sdo->deadline_us = now_us + sdo->timeout_us;
    }
    uint8_t d[8] = {0x60u, 0, 0, 0, 0, 0, 0, 0};
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
    return send(sdo, d, txq);
}

static lsm_status download_segment(lsm_co_sdo *sdo, const uint8_t *r, uint32_t now_us, lsm_can_txq *txq)
{
    /* out of sequence: name the open transfer's object, or 0:0 when none is open */
    uint16_t index = sdo->phase != LSM_CO_SDO_IDLE ? sdo->ref.index : 0u;
    uint8_t sub = sdo->phase != LSM_CO_SDO_IDLE ? sdo->ref.sub : 0u;
    if (sdo->phase != LSM_CO_SDO_DOWNLOAD)
        return send_abort(sdo, index, sub, LSM_CO_ABORT_CMD, txq);
    if ((r[0] & 0x10u) != sdo->toggle)
        return send_abort(sdo, index, sub, LSM_CO_ABORT_TOGGLE, txq);
    size_t n = 7u - ((r[0] >> 1) & 0x07u);
    bool last = (r[0] & 0x01u) != 0u;
    if ((size_t)sdo->pos + n > sdo->cap)
        return send_abort(sdo, index, sub, LSM_CO_ABORT_NO_MEM, txq);
    if (sdo->size_known && (size_t)sdo->pos + n > sdo->size)
        return send_abort(sdo, index, sub, LSM_CO_ABORT_LENGTH, txq);
    memcpy(&sdo->buf[sdo->pos], &r[1], n);
    sdo->pos = (uint16_t)(sdo->pos + n);
    uint8_t d[8] = {(uint8_t)(0x20u | sdo->toggle), 0, 0, 0, 0, 0, 0, 0};
    sdo->toggle ^= 0x10u;
    sdo->deadline_us = now_us + sdo->timeout_us;
    if (last) {
        if (sdo->size_known && sdo->pos != sdo->size)
            return send_abort(sdo, index, sub, LSM_CO_ABORT_LENGTH, txq);
        uint32_t ab = lsm_co_od_write(sdo->od, &sdo->ref, sdo->buf, sdo->pos);
        if (ab)
            return send_abort(sdo, index, sub, ab, txq);
        sdo->phase = LSM_CO_SDO_IDLE;
    }
    return send(sdo, d, txq);
}

static lsm_status initiate_upload(lsm_co_sdo *sdo, const uint8_t *r, uint32_t now_us, lsm_can_txq *txq)
{
    uint16_t index = lsm_can_get_u16(&r[1]);
    uint8_t sub = r[3];
    lsm_co_od_ref ref;
    uint32_t ab = lsm_co_od_find(sdo->od, index, sub, &ref);
    if (ab)
        return send_abort(sdo, index, sub, ab, txq);
    size_t len = 0;
    ab = lsm_co_od_read(sdo->od, &ref, sdo->buf, sdo->cap, &len);
    if (ab)
        return send_abort(sdo, index, sub, ab, txq);
    uint8_t d[8] = {0};
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
    if (len >= 1u && len <= 4u) {
        d[0] = (uint8_t)(0x43u | ((4u - len) << 2));
        memcpy(&d[4], sdo->buf, len);
        sdo->phase = LSM_CO_SDO_IDLE;
    } else {
        d[0] = 0x41u;
        lsm_can_put_u32(&d[4], (uint32_t)len);
        sdo->phase = LSM_CO_SDO_UPLOAD;
        sdo->ref = ref;
        sdo->size = (uint32_t)len;
        sdo->pos = 0u;
        sdo->toggle = 0u;
        sdo->deadline_us = now_us + sdo->timeout_us;
    }
    return send(sdo, d, txq);
}

static lsm_status upload_segment(lsm_co_sdo *sdo, const uint8_t *r, uint32_t now_us, lsm_can_txq *txq)
{
    /* out of sequence: name the open transfer's object, or 0:0 when none is open */
    uint16_t index = sdo->phase != LSM_CO_SDO_IDLE ? sdo->ref.index : 0u;
    uint8_t sub = sdo->phase != LSM_CO_SDO_IDLE ? sdo->ref.sub : 0u;
    if (sdo->phase != LSM_CO_SDO_UPLOAD)
        return send_abort(sdo, index, sub, LSM_CO_ABORT_CMD, txq);
    if ((r[0] & 0x10u) != sdo->toggle)
        return send_abort(sdo, index, sub, LSM_CO_ABORT_TOGGLE, txq);
    size_t left = sdo->size - sdo->pos;
    size_t n = left > 7u ? 7u : left;
    bool last = left <= 7u;
    uint8_t d[8] = {0};
    d[0] = (uint8_t)(sdo->toggle | ((7u - n) << 1) | (last ? 1u : 0u));
    memcpy(&d[1], &sdo->buf[sdo->pos], n);
    sdo->pos = (uint16_t)(sdo->pos + n);
    sdo->toggle ^= 0x10u;
    sdo->deadline_us = now_us + sdo->timeout_us;
    if (last)
        sdo->phase = LSM_CO_SDO_IDLE;
    return send(sdo, d, txq);
}

lsm_status lsm_co_sdo_rx(lsm_co_sdo *sdo, const lsm_can_frame *f, uint32_t now_us, lsm_can_txq *txq)
{
    if (f->dlc != 8u || (f->flags & (LSM_CAN_FLAG_RTR | LSM_CAN_FLAG_EXT))) {
        sdo->malformed++;
        return LSM_E_CO_FRAME;
    }
    const uint8_t *r = f->data;
    switch (r[0] >> 5) {
    case 0: return download_segment(sdo, r, now_us, txq);
    case 1: return initiate_download(sdo, r, now_us, txq);
    case 2: return initiate_upload(sdo, r, now_us, txq);
    case 3: return upload_segment(sdo, r, now_us, txq);
    case 4:
        sdo->phase = LSM_CO_SDO_IDLE; /* abort from the client: drop, no answer */
        return LSM_OK;
    default: return send_abort(sdo, lsm_can_get_u16(&r[1]), r[3], LSM_CO_ABORT_CMD, txq);
    }
}

void lsm_co_sdo_process(lsm_co_sdo *sdo, uint32_t now_us, lsm_can_txq *txq)
{
    if (sdo->phase == LSM_CO_SDO_IDLE)
        return;
    if ((int32_t)(now_us - sdo->deadline_us) > 0)
        (void)send_abort(sdo, sdo->ref.index, sdo->ref.sub, LSM_CO_ABORT_TIMEOUT, txq);
}
