#include "co_path.h"

#include <string.h>

#include "can.h"
#include "co_od.h"

lsm_status lsm_co_path_init(lsm_co_path *p, lsm_co_path_block *storage, size_t cap, uint8_t n_axes)
{
    if (p == NULL || storage == NULL)
        return LSM_E_NULL;
    if (cap == 0u || cap > 65535u)
        return LSM_E_ARG;
    if (n_axes < 1u || n_axes > LSM_MAX_AXES)
        return LSM_E_CO_AXES;
    memset(p, 0, sizeof *p);
    p->ring = storage;
    p->cap = (uint16_t)cap;
    p->capacity = (uint16_t)cap;
    p->free_slots = (uint16_t)cap;
    p->n_axes = n_axes;
    p->override_pct = 100u;
    p->state = LSM_CO_PATH_IDLE;
    p->standstill = true;
    return LSM_OK;
}

/* Plane axes: first and second axis of the arc's plane. */
static void plane_axes(uint8_t plane, uint8_t *a, uint8_t *b)
{
    switch (plane) {
    case 1:
        *a = 2u;
        *b = 0u;
        break; /* ZX */
    case 2:
        *a = 1u;
        *b = 2u;
        break; /* YZ */
    default:
        *a = 0u;
        *b = 1u;
        break; /* XY */
    }
}

uint32_t lsm_co_path_decode(const lsm_co_path *p, const uint8_t *data, size_t len, lsm_co_path_block *b)
{
    if (len < 16u)
        return LSM_CO_ABORT_LENGTH_LOW;
    uint8_t type = data[4], plane = data[5], n = data[6], flags = data[7];
    if (type < LSM_CO_PATH_LINE || type > LSM_CO_PATH_ARC_CCW || n != p->n_axes || plane > 2u || flags != 0u)
        return LSM_CO_ABORT_VALUE;
    bool arc = type != LSM_CO_PATH_LINE;
    uint8_t pa, pb;
    plane_axes(plane, &pa, &pb);
    if (arc && (pa >= n || pb >= n))
        return LSM_CO_ABORT_VALUE;
    if (!arc && plane != 0u)
        return LSM_CO_ABORT_VALUE;
    size_t expect = 16u + 4u * n + (arc ? 8u : 0u);
    if (len > expect)
        return LSM_CO_ABORT_LENGTH_HIGH;
    if (len < expect)
        return LSM_CO_ABORT_LENGTH_LOW;
    memset(b, 0, sizeof *b);
    b->seq = lsm_can_get_u32(&data[0]);
    b->type = type;
    b->plane = plane;
    b->feed_um_s = lsm_can_get_u32(&data[8]);
    b->tol_um = lsm_can_get_u32(&data[12]);
    if (b->feed_um_s == 0u || b->tol_um == 0u)
        return LSM_CO_ABORT_VALUE_LOW;
    for (size_t i = 0; i < n; i++)
        b->end[i] = (int32_t)lsm_can_get_u32(&data[16u + 4u * i]);
    if (arc) {
        b->centre[0] = (int32_t)lsm_can_get_u32(&data[16u + 4u * n]);
        b->centre[1] = (int32_t)lsm_can_get_u32(&data[20u + 4u * n]);
        if (b->end[pa] == b->centre[0] && b->end[pb] == b->centre[1])
            return LSM_CO_ABORT_VALUE; /* zero end radius */
    }
    return LSM_CO_ABORT_NONE;
}

/* Checks that need the previous block's end (after the sequence check: a retried block would fail them). */
static uint32_t check_continuity(const lsm_co_path *p, const lsm_co_path_block *b)
{
    if (!p->have_prev)
        return LSM_CO_ABORT_NONE;
    if (b->type != LSM_CO_PATH_LINE) {
        uint8_t pa, pb;
        plane_axes(b->plane, &pa, &pb);
        if (p->prev_end[pa] == b->centre[0] && p->prev_end[pb] == b->centre[1])
            return LSM_CO_ABORT_VALUE; /* zero start radius */
        return LSM_CO_ABORT_NONE;
    }
    for (size_t i = 0; i < p->n_axes; i++) {
        if (b->end[i] != p->prev_end[i])
            return LSM_CO_ABORT_NONE;
    }
    return LSM_CO_ABORT_VALUE; /* zero-length line */
}

static void set_free(lsm_co_path *p)
{
    p->free_slots = (uint16_t)(p->cap - p->count);
}

uint32_t lsm_co_path_write_block(lsm_co_path *p, const uint8_t *data, size_t len, lsm_status *st)
{
    lsm_status dummy;
    if (st == NULL)
        st = &dummy;
    if (p->state == LSM_CO_PATH_STOPPING) {
        *st = LSM_E_STATE;
        return LSM_CO_ABORT_DEVICE_STATE;
    }
    lsm_co_path_block b;
    uint32_t ab = lsm_co_path_decode(p, data, len, &b);
    if (ab) {
        p->n_refused++;
        *st = LSM_E_CO_BLOCK;
        return ab;
    }
    int32_t d = (int32_t)(b.seq - (p->last_seq + 1u));
    if (d < 0) {
        p->n_dup++;
        *st = LSM_E_CO_SEQ_DUP;
        return LSM_CO_ABORT_NONE;
    }
    if (d > 0) {
        p->n_gap++;
        *st = LSM_E_CO_SEQ_GAP;
        return LSM_CO_ABORT_VALUE_HIGH;
    }
    ab = check_continuity(p, &b);
    if (ab) {
        p->n_refused++;
        *st = LSM_E_CO_BLOCK;
        return ab;
    }
    if (p->count >= p->cap) {
        *st = LSM_E_FULL;
        return LSM_CO_ABORT_STORE;
    }
    uint32_t tail = (uint32_t)p->head + p->count;
    if (tail >= p->cap)
        tail -= p->cap;
    p->ring[tail] = b;
    p->count++;
    set_free(p);
    p->last_seq = b.seq;
    memcpy(p->prev_end, b.end, sizeof p->prev_end);
    p->have_prev = true;
    *st = LSM_OK;
    return LSM_CO_ABORT_NONE;
}

static void flush(lsm_co_path *p)
{
    p->head = 0u;
    p->count = 0u;
    set_free(p);
    p->have_prev = false;
    p->epoch++;
}

uint32_t lsm_co_path_command(lsm_co_path *p, int64_t cmd, bool axes_ready)
{
    switch (cmd) {
    case LSM_CO_PATH_CMD_NOP: break;
    case LSM_CO_PATH_CMD_START:
        if (p->state == LSM_CO_PATH_RUNNING)
            break;
        if (p->state != LSM_CO_PATH_IDLE || !axes_ready)
            return LSM_CO_ABORT_DEVICE_STATE;
        p->state = LSM_CO_PATH_RUNNING;
        p->standstill = false; /* moving until the application reports rest */
        break;
    case LSM_CO_PATH_CMD_HOLD:
        if (p->state == LSM_CO_PATH_IDLE || p->state == LSM_CO_PATH_STOPPING)
            return LSM_CO_ABORT_DEVICE_STATE;
        if (p->state == LSM_CO_PATH_RUNNING) {
            p->state = p->standstill ? LSM_CO_PATH_HELD : LSM_CO_PATH_HOLDING;
            p->quick = false;
        }
        break;
    case LSM_CO_PATH_CMD_RESUME:
        if (p->state == LSM_CO_PATH_RUNNING)
            break;
        if ((p->state != LSM_CO_PATH_HOLDING && p->state != LSM_CO_PATH_HELD) || !axes_ready)
            return LSM_CO_ABORT_DEVICE_STATE;
        p->state = LSM_CO_PATH_RUNNING;
        p->standstill = false;
        break;
    case LSM_CO_PATH_CMD_CLEAR:
        flush(p);
        p->quick = true;
        p->state = p->standstill ? LSM_CO_PATH_IDLE : LSM_CO_PATH_STOPPING;
        break;
    default: return LSM_CO_ABORT_VALUE;
    }
    p->command = (uint8_t)cmd;
    return LSM_CO_ABORT_NONE;
}

uint32_t lsm_co_path_resync(lsm_co_path *p, uint32_t last_seq)
{
    if (p->state != LSM_CO_PATH_IDLE || p->count != 0u)
        return LSM_CO_ABORT_DEVICE_STATE;
    p->last_seq = last_seq;
    p->have_prev = false;
    return LSM_CO_ABORT_NONE;
}

void lsm_co_path_hold(lsm_co_path *p, bool quick)
{
    if (p->state == LSM_CO_PATH_RUNNING) {
        p->state = p->standstill ? LSM_CO_PATH_HELD : LSM_CO_PATH_HOLDING;
        p->quick = quick;
    } else if (p->state == LSM_CO_PATH_HOLDING && quick) {
        p->quick = true; /* a feed hold in progress becomes a quick stop */
    }
}

lsm_co_path_motion lsm_co_path_get_motion(const lsm_co_path *p)
{
    switch (p->state) {
    case LSM_CO_PATH_RUNNING: return LSM_CO_PATH_MOTION_RUN;
    case LSM_CO_PATH_HOLDING: return p->quick ? LSM_CO_PATH_MOTION_QUICK : LSM_CO_PATH_MOTION_HOLD;
    case LSM_CO_PATH_HELD: return LSM_CO_PATH_MOTION_HOLD;
    case LSM_CO_PATH_STOPPING: return LSM_CO_PATH_MOTION_QUICK;
    default: return LSM_CO_PATH_MOTION_IDLE;
    }
}

size_t lsm_co_path_count(const lsm_co_path *p)
{
    return p->count;
}

bool lsm_co_path_peek(const lsm_co_path *p, size_t i, lsm_co_path_block *b)
{
    if (i >= p->count)
        return false;
    size_t k = p->head + i;
    if (k >= p->cap)
        k -= p->cap;
    *b = p->ring[k];
    return true;
}

lsm_status lsm_co_path_pop(lsm_co_path *p, lsm_co_path_block *b)
{
    if (p->count == 0u)
        return LSM_E_EMPTY;
    if (b != NULL)
        *b = p->ring[p->head];
    p->head = (uint16_t)(p->head + 1u == p->cap ? 0u : p->head + 1u);
    p->count--;
    set_free(p);
    return LSM_OK;
}

void lsm_co_path_update(lsm_co_path *p, const lsm_co_path_report *r)
{
    p->active_seq = r->active_seq;
    p->feed_um_s = r->feed_um_s;
    p->standstill = r->standstill;
    if (r->starved && !p->starved && p->state == LSM_CO_PATH_RUNNING)
        p->n_underrun++;
    p->starved = r->starved;
    if (r->standstill) {
        if (p->state == LSM_CO_PATH_HOLDING)
            p->state = LSM_CO_PATH_HELD;
        else if (p->state == LSM_CO_PATH_STOPPING)
            p->state = LSM_CO_PATH_IDLE;
    }
}

void lsm_co_path_reject(lsm_co_path *p, uint32_t seq)
{
    flush(p);
    p->reject_pending = true;
    p->reject_seq = seq;
    p->quick = true;
    p->state = p->standstill ? LSM_CO_PATH_IDLE : LSM_CO_PATH_STOPPING;
}
