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
    if (sdo->wait != LSM_CO_SDO_ACC_NONE)
        sdo->wait_cancel = true;
}

/* ---- protocol half: frames in, responses or accesses out, no dictionary --------------------------------- */

static lsm_co_sdo_step respond(const lsm_co_sdo *sdo, const uint8_t d[8], lsm_can_frame *resp)
{
    resp->id = sdo->tx_id;
    resp->dlc = 8u;
    resp->flags = 0u;
    memcpy(resp->data, d, 8);
    return LSM_CO_SDO_STEP_RESPOND;
}

static lsm_co_sdo_step respond_abort(lsm_co_sdo *sdo, uint16_t index, uint8_t sub, uint32_t code, lsm_can_frame *resp)
{
    uint8_t d[8];
    d[0] = 0x80u;
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
    lsm_can_put_u32(&d[4], code);
    sdo->phase = LSM_CO_SDO_IDLE;
    sdo->aborts_sent++;
    sdo->last_abort = code;
    return respond(sdo, d, resp);
}

/* The answer of an access that names (index, sub): 0x60 / expedited upload and the like. */
static lsm_co_sdo_step respond_obj(const lsm_co_sdo *sdo, uint8_t d0, uint16_t index, uint8_t sub, lsm_can_frame *resp)
{
    uint8_t d[8] = {d0, 0, 0, 0, 0, 0, 0, 0};
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
    return respond(sdo, d, resp);
}

static lsm_co_sdo_step ask(lsm_co_sdo *sdo, uint8_t kind, uint16_t index, uint8_t sub, uint32_t now_us,
                           lsm_co_sdo_access *acc)
{
    acc->kind = kind;
    acc->index = index;
    acc->sub = sub;
    acc->abort = 0u;
    acc->out_len = 0u;
    sdo->wait = kind;
    sdo->wait_cancel = false;
    sdo->wait_us = now_us;
    return LSM_CO_SDO_STEP_ACCESS;
}

static lsm_co_sdo_step initiate_download(lsm_co_sdo *sdo, const uint8_t *r, uint32_t now_us, lsm_co_sdo_access *acc)
{
    const uint16_t index = lsm_can_get_u16(&r[1]);
    const uint8_t sub = r[3];
    const bool sized = (r[0] & 0x01u) != 0u;
    acc->sized = sized ? 1u : 0u;
    if ((r[0] & 0x02u) != 0u) { /* expedited: the open transfer (if any) stays as it is, as before the split */
        acc->len = sized ? 4u - ((r[0] >> 2) & 0x03u) : 0u;
        memcpy(acc->exp, &r[4], 4);
        return ask(sdo, LSM_CO_SDO_ACC_WRITE_EXP, index, sub, now_us, acc);
    }
    acc->len = sized ? lsm_can_get_u32(&r[4]) : 0u;
    return ask(sdo, LSM_CO_SDO_ACC_CHECK, index, sub, now_us, acc);
}

static lsm_co_sdo_step download_segment(lsm_co_sdo *sdo, const uint8_t *r, uint32_t now_us, lsm_can_frame *resp,
                                        lsm_co_sdo_access *acc)
{
    /* out of sequence: name the open transfer's object, or 0:0 when none is open */
    const uint16_t index = sdo->phase != LSM_CO_SDO_IDLE ? sdo->index : 0u;
    const uint8_t sub = sdo->phase != LSM_CO_SDO_IDLE ? sdo->sub : 0u;
    if (sdo->phase != LSM_CO_SDO_DOWNLOAD)
        return respond_abort(sdo, index, sub, LSM_CO_ABORT_CMD, resp);
    if ((r[0] & 0x10u) != sdo->toggle)
        return respond_abort(sdo, index, sub, LSM_CO_ABORT_TOGGLE, resp);
    const size_t n = 7u - ((r[0] >> 1) & 0x07u);
    const bool last = (r[0] & 0x01u) != 0u;
    if ((size_t)sdo->pos + n > sdo->cap)
        return respond_abort(sdo, index, sub, LSM_CO_ABORT_NO_MEM, resp);
    if (sdo->size_known && (size_t)sdo->pos + n > sdo->size)
        return respond_abort(sdo, index, sub, LSM_CO_ABORT_LENGTH, resp);
    memcpy(&sdo->buf[sdo->pos], &r[1], n);
    sdo->pos = (uint16_t)(sdo->pos + n);
    const uint8_t d0 = (uint8_t)(0x20u | sdo->toggle);
    sdo->toggle ^= 0x10u;
    sdo->deadline_us = now_us + sdo->timeout_us;
    if (!last)
        return respond_obj(sdo, d0, 0u, 0u, resp);
    if (sdo->size_known && sdo->pos != sdo->size)
        return respond_abort(sdo, index, sub, LSM_CO_ABORT_LENGTH, resp);
    acc->len = sdo->pos;
    sdo->wait_d0 = d0;
    return ask(sdo, LSM_CO_SDO_ACC_WRITE, index, sub, now_us, acc);
}

static lsm_co_sdo_step upload_segment(lsm_co_sdo *sdo, const uint8_t *r, uint32_t now_us, lsm_can_frame *resp)
{
    /* out of sequence: name the open transfer's object, or 0:0 when none is open */
    const uint16_t index = sdo->phase != LSM_CO_SDO_IDLE ? sdo->index : 0u;
    const uint8_t sub = sdo->phase != LSM_CO_SDO_IDLE ? sdo->sub : 0u;
    if (sdo->phase != LSM_CO_SDO_UPLOAD)
        return respond_abort(sdo, index, sub, LSM_CO_ABORT_CMD, resp);
    if ((r[0] & 0x10u) != sdo->toggle)
        return respond_abort(sdo, index, sub, LSM_CO_ABORT_TOGGLE, resp);
    const size_t left = sdo->size - sdo->pos;
    const size_t n = left > 7u ? 7u : left;
    const bool last = left <= 7u;
    uint8_t d[8] = {0};
    d[0] = (uint8_t)(sdo->toggle | ((7u - n) << 1) | (last ? 1u : 0u));
    memcpy(&d[1], &sdo->buf[sdo->pos], n);
    sdo->pos = (uint16_t)(sdo->pos + n);
    sdo->toggle ^= 0x10u;
    sdo->deadline_us = now_us + sdo->timeout_us;
    if (last)
        sdo->phase = LSM_CO_SDO_IDLE;
    return respond(sdo, d, resp);
}

lsm_co_sdo_step lsm_co_sdo_request(lsm_co_sdo *sdo, const lsm_can_frame *f, uint32_t now_us, lsm_can_frame *resp,
                                   lsm_co_sdo_access *acc)
{
    if (f->dlc != 8u || (f->flags & (LSM_CAN_FLAG_RTR | LSM_CAN_FLAG_EXT))) {
        sdo->malformed++;
        return LSM_CO_SDO_STEP_MALFORMED;
    }
    if (sdo->wait != LSM_CO_SDO_ACC_NONE)
        return LSM_CO_SDO_STEP_NONE; /* the caller broke the contract (a request while an access is out): ignored */
    const uint8_t *r = f->data;
    switch (r[0] >> 5) {
    case 0: return download_segment(sdo, r, now_us, resp, acc);
    case 1: return initiate_download(sdo, r, now_us, acc);
    case 2: return ask(sdo, LSM_CO_SDO_ACC_READ, lsm_can_get_u16(&r[1]), r[3], now_us, acc);
    case 3: return upload_segment(sdo, r, now_us, resp);
    case 4:
        sdo->phase = LSM_CO_SDO_IDLE; /* abort from the client: drop, no answer */
        return LSM_CO_SDO_STEP_NONE;
    default: return respond_abort(sdo, lsm_can_get_u16(&r[1]), r[3], LSM_CO_ABORT_CMD, resp);
    }
}

/* Upload initiate answered: expedited up to 4 bytes, else the segmented transfer opens on the buffer. */
static void upload_opened(lsm_co_sdo *sdo, const lsm_co_sdo_access *acc, lsm_can_frame *resp)
{
    const uint32_t len = acc->out_len;
    uint8_t d[8] = {0};
    lsm_can_put_u16(&d[1], acc->index);
    d[3] = acc->sub;
    if (len >= 1u && len <= 4u) {
        d[0] = (uint8_t)(0x43u | ((4u - len) << 2));
        memcpy(&d[4], sdo->buf, len);
        sdo->phase = LSM_CO_SDO_IDLE;
    } else {
        d[0] = 0x41u;
        lsm_can_put_u32(&d[4], len);
        sdo->phase = LSM_CO_SDO_UPLOAD;
        sdo->index = acc->index;
        sdo->sub = acc->sub;
        sdo->size = len;
        sdo->pos = 0u;
        sdo->toggle = 0u;
        sdo->deadline_us = sdo->wait_us + sdo->timeout_us;
    }
    (void)respond(sdo, d, resp);
}

bool lsm_co_sdo_complete(lsm_co_sdo *sdo, const lsm_co_sdo_access *acc, lsm_can_frame *resp)
{
    const uint8_t kind = sdo->wait;
    const bool cancelled = sdo->wait_cancel;
    sdo->wait = LSM_CO_SDO_ACC_NONE;
    sdo->wait_cancel = false;
    if (kind == LSM_CO_SDO_ACC_NONE || cancelled)
        return false;
    if (acc->abort != 0u) {
        (void)respond_abort(sdo, acc->index, acc->sub, acc->abort, resp);
        return true;
    }
    switch (kind) {
    case LSM_CO_SDO_ACC_READ: upload_opened(sdo, acc, resp); break;
    case LSM_CO_SDO_ACC_WRITE:
        sdo->phase = LSM_CO_SDO_IDLE;
        (void)respond_obj(sdo, sdo->wait_d0, 0u, 0u, resp);
        break;
    case LSM_CO_SDO_ACC_CHECK:
        sdo->phase = LSM_CO_SDO_DOWNLOAD;
        sdo->index = acc->index;
        sdo->sub = acc->sub;
        sdo->size_known = acc->sized != 0u;
        sdo->size = acc->len;
        sdo->pos = 0u;
        sdo->toggle = 0u;
        sdo->deadline_us = sdo->wait_us + sdo->timeout_us;
        (void)respond_obj(sdo, 0x60u, acc->index, acc->sub, resp);
        break;
    default: (void)respond_obj(sdo, 0x60u, acc->index, acc->sub, resp); break; /* WRITE_EXP */
    }
    return true;
}

bool lsm_co_sdo_waiting(const lsm_co_sdo *sdo)
{
    return sdo->wait != LSM_CO_SDO_ACC_NONE;
}

bool lsm_co_sdo_timeout(lsm_co_sdo *sdo, uint32_t now_us, lsm_can_frame *resp)
{
    if (sdo->phase == LSM_CO_SDO_IDLE || sdo->wait != LSM_CO_SDO_ACC_NONE)
        return false;
    if ((int32_t)(now_us - sdo->deadline_us) <= 0)
        return false;
    (void)respond_abort(sdo, sdo->index, sdo->sub, LSM_CO_ABORT_TIMEOUT, resp);
    return true;
}

/* ---- dictionary half ---------------------------------------------------------------------------------- */

/* Segmented download initiate: what can never fit is refused at once, instead of after all the segments. */
static uint32_t check_download(const lsm_co_sdo_access *acc, const lsm_co_od_ref *ref, size_t cap)
{
    if (acc->sized == 0u)
        return LSM_CO_ABORT_NONE;
    const size_t ts = lsm_co_od_type_size(ref->entry->type);
    const size_t maxlen = ts != 0u ? ts : ref->entry->size;
    if (acc->len > maxlen)
        return LSM_CO_ABORT_LENGTH_HIGH;
    if (ts != 0u && acc->len < ts)
        return LSM_CO_ABORT_LENGTH_LOW;
    if (acc->len > cap)
        return LSM_CO_ABORT_NO_MEM;
    return LSM_CO_ABORT_NONE;
}

static uint32_t apply(lsm_co_od *od, lsm_co_sdo_access *acc, uint8_t *buf, size_t cap)
{
    lsm_co_od_ref ref;
    uint32_t ab = lsm_co_od_find(od, acc->index, acc->sub, &ref);
    if (ab)
        return ab;
    if (acc->kind == LSM_CO_SDO_ACC_READ) {
        size_t len = 0;
        ab = lsm_co_od_read(od, &ref, buf, cap, &len);
        acc->out_len = (uint32_t)len;
        return ab;
    }
    if (acc->kind == LSM_CO_SDO_ACC_WRITE)
        return lsm_co_od_write(od, &ref, buf, acc->len);
    if (!(ref.entry->flags & LSM_CO_OD_W))
        return LSM_CO_ABORT_READ_ONLY;
    if (acc->kind == LSM_CO_SDO_ACC_CHECK)
        return check_download(acc, &ref, cap);
    size_t len = acc->len; /* WRITE_EXP */
    if (acc->sized == 0u) {
        const size_t ts = lsm_co_od_type_size(ref.entry->type);
        len = (ts != 0u && ts < 4u) ? ts : 4u; /* size not indicated: the object's own size */
    }
    return lsm_co_od_write(od, &ref, acc->exp, len);
}

void lsm_co_sdo_access_apply(lsm_co_od *od, lsm_co_sdo_access *acc, uint8_t *buf, size_t cap)
{
    acc->out_len = 0u;
    acc->abort = apply(od, acc, buf, cap);
}

/* ---- one context: both halves at once ------------------------------------------------------------------ */

lsm_status lsm_co_sdo_rx(lsm_co_sdo *sdo, const lsm_can_frame *f, uint32_t now_us, lsm_can_txq *txq)
{
    lsm_can_frame resp;
    lsm_co_sdo_access acc;
    memset(&acc, 0, sizeof acc);
    lsm_co_sdo_step step = lsm_co_sdo_request(sdo, f, now_us, &resp, &acc);
    if (step == LSM_CO_SDO_STEP_MALFORMED)
        return LSM_E_CO_FRAME;
    if (step == LSM_CO_SDO_STEP_ACCESS) {
        lsm_co_sdo_access_apply(sdo->od, &acc, sdo->buf, sdo->cap);
        step = lsm_co_sdo_complete(sdo, &acc, &resp) ? LSM_CO_SDO_STEP_RESPOND : LSM_CO_SDO_STEP_NONE;
    }
    if (step == LSM_CO_SDO_STEP_RESPOND)
        return lsm_can_txq_push(txq, &resp);
    return LSM_OK;
}

void lsm_co_sdo_process(lsm_co_sdo *sdo, uint32_t now_us, lsm_can_txq *txq)
{
    lsm_can_frame resp;
    if (lsm_co_sdo_timeout(sdo, now_us, &resp))
        (void)lsm_can_txq_push(txq, &resp);
}
