#include "co_od.h"

#include <string.h>

#include "can.h"

size_t lsm_co_od_type_size(uint8_t type)
{
    switch (type) {
    case LSM_CO_T_BOOL:
    case LSM_CO_T_I8:
    case LSM_CO_T_U8: return 1u;
    case LSM_CO_T_I16:
    case LSM_CO_T_U16: return 2u;
    case LSM_CO_T_I32:
    case LSM_CO_T_U32:
    case LSM_CO_T_REAL32: return 4u;
    case LSM_CO_T_I64:
    case LSM_CO_T_U64: return 8u;
    default: return 0u;
    }
}

bool lsm_co_od_type_signed(uint8_t type)
{
    return type == LSM_CO_T_I8 || type == LSM_CO_T_I16 || type == LSM_CO_T_I32 || type == LSM_CO_T_I64;
}

static bool type_known(uint8_t type)
{
    return lsm_co_od_type_size(type) != 0u || type == LSM_CO_T_VSTRING || type == LSM_CO_T_DOMAIN;
}

/* Instance number of `index` in entry e, or -1. */
static int instance_of(const lsm_co_od *od, const lsm_co_od_entry *e, uint16_t index)
{
    if (e->group == 0u)
        return e->index == index ? 0 : -1;
    const lsm_co_od_group *g = &od->cfg.groups[e->group];
    if (index < e->index)
        return -1;
    uint32_t d = (uint32_t)index - e->index;
    if (d > (uint32_t)g->index_step * (g->count - 1u)) /* beyond the last instance: no division needed */
        return -1;
    uint32_t k = d / g->index_step;
    return k * g->index_step == d ? (int)k : -1;
}

static uint16_t count_of(const lsm_co_od *od, const lsm_co_od_entry *e)
{
    return e->group == 0u ? 1u : od->cfg.groups[e->group].count;
}

static size_t storage_size(const lsm_co_od_entry *e)
{
    if (e->flags & LSM_CO_OD_STRPTR)
        return sizeof(const char *);
    if (e->type == LSM_CO_T_DOMAIN)
        return 0u; /* the hook owns the bytes */
    return e->size;
}

static bool entry_ok(const lsm_co_od *od, const lsm_co_od_entry *e)
{
    const lsm_co_od_config *c = &od->cfg;
    size_t ts = lsm_co_od_type_size(e->type);
    if (!type_known(e->type))
        return false;
    if ((e->flags & LSM_CO_OD_RW) == 0u)
        return false;
    if (e->group >= LSM_CO_OD_GROUPS)
        return false;
    if (e->group != 0u && (c->groups[e->group].count == 0u || c->groups[e->group].index_step == 0u))
        return false;
    if (ts != 0u && e->size != ts)
        return false;
    if (ts == 0u && e->size == 0u)
        return false;
    if ((e->flags & LSM_CO_OD_TPDO) && (!(e->flags & LSM_CO_OD_R) || ts == 0u))
        return false;
    if ((e->flags & LSM_CO_OD_RPDO) && (!(e->flags & LSM_CO_OD_W) || ts == 0u))
        return false;
    if (e->range != 0u) {
        if (ts == 0u || e->type == LSM_CO_T_REAL32 || c->ranges == NULL || e->range >= c->n_ranges)
            return false;
        if (c->ranges[e->range].min > c->ranges[e->range].max)
            return false;
        if (e->type == LSM_CO_T_U64 && c->ranges[e->range].min < 0)
            return false;
    }
    if ((e->flags & LSM_CO_OD_HOOK) && c->write_hook == NULL)
        return false;
    if (e->type == LSM_CO_T_VSTRING) {
        /* read-only string behind a pointer */
        if (!(e->flags & LSM_CO_OD_STRPTR) || (e->flags & (LSM_CO_OD_W | LSM_CO_OD_CONST)))
            return false;
    } else if (e->flags & LSM_CO_OD_STRPTR) {
        return false;
    }
    if (e->type == LSM_CO_T_DOMAIN) {
        if ((e->flags & LSM_CO_OD_RW) != LSM_CO_OD_W || !(e->flags & LSM_CO_OD_HOOK))
            return false;
    }
    if (e->flags & LSM_CO_OD_CONST) {
        if ((e->flags & (LSM_CO_OD_W | LSM_CO_OD_HOOK)) || ts == 0u || ts > 4u || !(e->flags & LSM_CO_OD_R))
            return false;
        return true; /* no storage */
    }
    size_t st = storage_size(e);
    if (st != 0u) {
        if (c->base == NULL)
            return false;
        uint64_t last = (uint64_t)e->arg + st;
        if (e->group != 0u)
            last += (uint64_t)c->groups[e->group].offset_step * (c->groups[e->group].count - 1u);
        if (last > c->base_size)
            return false;
    }
    return true;
}

lsm_status lsm_co_od_init(lsm_co_od *od, const lsm_co_od_config *cfg)
{
    if (od == NULL || cfg == NULL || cfg->table == NULL)
        return LSM_E_NULL;
    if (cfg->n_entries == 0u)
        return LSM_E_CO_OD;
    od->cfg = *cfg;
    for (size_t i = 0; i < cfg->n_entries; i++) {
        if (!entry_ok(od, &cfg->table[i]))
            return LSM_E_CO_OD;
    }
    /* no (index, sub) may be served twice, counting every instance of grouped entries */
    for (size_t i = 0; i < cfg->n_entries; i++) {
        const lsm_co_od_entry *a = &cfg->table[i];
        uint16_t na = count_of(od, a);
        uint16_t step = a->group ? cfg->groups[a->group].index_step : 0u;
        for (uint16_t k = 0; k < na; k++) {
            uint32_t idx = (uint32_t)a->index + (uint32_t)k * step;
            if (idx > 0xFFFFu)
                return LSM_E_CO_OD;
            for (size_t j = i + 1u; j < cfg->n_entries; j++) {
                const lsm_co_od_entry *b = &cfg->table[j];
                if (b->sub == a->sub && instance_of(od, b, (uint16_t)idx) >= 0)
                    return LSM_E_CO_OD;
            }
        }
    }
    return LSM_OK;
}

static void make_ref(const lsm_co_od *od, const lsm_co_od_entry *e, uint16_t inst, lsm_co_od_ref *ref)
{
    ref->entry = e;
    ref->inst = (uint8_t)inst;
    ref->sub = e->sub;
    if (e->group == 0u) {
        ref->index = e->index;
    } else {
        const lsm_co_od_group *g = &od->cfg.groups[e->group];
        ref->index = (uint16_t)(e->index + inst * g->index_step);
    }
    if ((e->flags & LSM_CO_OD_CONST) || storage_size(e) == 0u) {
        ref->ptr = NULL;
    } else {
        size_t off = e->arg;
        if (e->group != 0u)
            off += (size_t)od->cfg.groups[e->group].offset_step * inst;
        ref->ptr = (uint8_t *)od->cfg.base + off;
    }
}

uint32_t lsm_co_od_find(const lsm_co_od *od, uint16_t index, uint8_t sub, lsm_co_od_ref *ref)
{
    /* the sub-index first (a byte compare), the index (a division for instance groups) only where it matches:
     * PDO mapping looks up every mapped object, and a node reset maps the default PDOs again */
    for (size_t i = 0; i < od->cfg.n_entries; i++) {
        const lsm_co_od_entry *e = &od->cfg.table[i];
        if (e->sub != sub)
            continue;
        int k = instance_of(od, e, index);
        if (k < 0)
            continue;
        make_ref(od, e, (uint16_t)k, ref);
        return LSM_CO_ABORT_NONE;
    }
    for (size_t i = 0; i < od->cfg.n_entries; i++) { /* not found: is it the sub-index or the object? */
        if (instance_of(od, &od->cfg.table[i], index) >= 0)
            return LSM_CO_ABORT_NO_SUB;
    }
    return LSM_CO_ABORT_NO_OBJECT;
}

uint32_t lsm_co_od_ref_at(const lsm_co_od *od, size_t entry, uint8_t inst, lsm_co_od_ref *ref)
{
    if (entry >= od->cfg.n_entries)
        return LSM_CO_ABORT_NO_OBJECT;
    const lsm_co_od_entry *e = &od->cfg.table[entry];
    if (inst >= count_of(od, e))
        return LSM_CO_ABORT_NO_OBJECT;
    make_ref(od, e, inst, ref);
    return LSM_CO_ABORT_NONE;
}

static const char *string_of(const lsm_co_od_ref *ref)
{
    const char *s;
    memcpy(&s, ref->ptr, sizeof s);
    return s;
}

size_t lsm_co_od_read_size(const lsm_co_od_ref *ref)
{
    const lsm_co_od_entry *e = ref->entry;
    if (e->type == LSM_CO_T_VSTRING) {
        const char *s = string_of(ref);
        size_t n = 0;
        if (s != NULL) {
            while (n < e->size && s[n] != '\0')
                n++;
        }
        return n;
    }
    return lsm_co_od_type_size(e->type);
}

/* The value's bit pattern, zero-extended. */
static uint64_t raw_of(const lsm_co_od_ref *ref)
{
    const lsm_co_od_entry *e = ref->entry;
    if (e->flags & LSM_CO_OD_CONST)
        return e->arg;
    switch (e->size) {
    case 1: {
        uint8_t v;
        memcpy(&v, ref->ptr, 1);
        return v;
    }
    case 2: {
        uint16_t v;
        memcpy(&v, ref->ptr, 2);
        return v;
    }
    case 4: {
        uint32_t v;
        memcpy(&v, ref->ptr, 4);
        return v;
    }
    default: {
        uint64_t v;
        memcpy(&v, ref->ptr, 8);
        return v;
    }
    }
}

uint32_t lsm_co_od_read(const lsm_co_od *od, const lsm_co_od_ref *ref, uint8_t *buf, size_t cap, size_t *len)
{
    (void)od;
    const lsm_co_od_entry *e = ref->entry;
    if (!(e->flags & LSM_CO_OD_R))
        return LSM_CO_ABORT_WRITE_ONLY;
    size_t n = lsm_co_od_read_size(ref);
    if (n > cap)
        return LSM_CO_ABORT_NO_MEM;
    if (e->type == LSM_CO_T_VSTRING) {
        if (n)
            memcpy(buf, string_of(ref), n);
    } else {
        lsm_can_put_le(buf, raw_of(ref), n);
    }
    *len = n;
    return LSM_CO_ABORT_NONE;
}

void lsm_co_od_store(const lsm_co_od_ref *ref, const uint8_t *data)
{
    if (ref->ptr == NULL)
        return; /* a constant or an entry without storage (its hook handles writes): nothing to store */
    uint64_t raw = lsm_can_get_le(data, ref->entry->size);
    switch (ref->entry->size) {
    case 1: {
        uint8_t v = (uint8_t)raw;
        memcpy(ref->ptr, &v, 1);
        break;
    }
    case 2: {
        uint16_t v = (uint16_t)raw;
        memcpy(ref->ptr, &v, 2);
        break;
    }
    case 4: {
        uint32_t v = (uint32_t)raw;
        memcpy(ref->ptr, &v, 4);
        break;
    }
    default: memcpy(ref->ptr, &raw, 8); break;
    }
}

static int64_t sign_extend(uint64_t raw, size_t n)
{
    if (n >= 8u)
        return (int64_t)raw;
    uint64_t sign = (uint64_t)1 << (8u * n - 1u);
    if (raw & sign)
        return (int64_t)(raw | ~((sign << 1) - 1u));
    return (int64_t)raw;
}

uint32_t lsm_co_od_write(lsm_co_od *od, const lsm_co_od_ref *ref, const uint8_t *data, size_t len)
{
    const lsm_co_od_entry *e = ref->entry;
    if (!(e->flags & LSM_CO_OD_W))
        return LSM_CO_ABORT_READ_ONLY;
    size_t ts = lsm_co_od_type_size(e->type);
    int64_t value = 0;
    if (ts != 0u) {
        if (len > ts)
            return LSM_CO_ABORT_LENGTH_HIGH;
        if (len < ts)
            return LSM_CO_ABORT_LENGTH_LOW;
        uint64_t raw = lsm_can_get_le(data, ts);
        value = lsm_co_od_type_signed(e->type) ? sign_extend(raw, ts) : (int64_t)raw;
        if (e->type == LSM_CO_T_BOOL && raw > 1u)
            return LSM_CO_ABORT_VALUE;
        if (e->type == LSM_CO_T_REAL32 && ((raw >> 23) & 0xFFu) == 0xFFu)
            return LSM_CO_ABORT_VALUE; /* NaN or infinity */
        if (e->range != 0u) {
            const lsm_co_od_range *r = &od->cfg.ranges[e->range];
            if (e->type == LSM_CO_T_U64) {
                if (raw > (uint64_t)r->max)
                    return LSM_CO_ABORT_VALUE_HIGH;
                if (raw < (uint64_t)r->min)
                    return LSM_CO_ABORT_VALUE_LOW;
            } else {
                if (value > r->max)
                    return LSM_CO_ABORT_VALUE_HIGH;
                if (value < r->min)
                    return LSM_CO_ABORT_VALUE_LOW;
            }
        }
    } else if (len > e->size) {
        return LSM_CO_ABORT_LENGTH_HIGH;
    }
    if (e->flags & LSM_CO_OD_HOOK)
        return od->cfg.write_hook(od->cfg.hook_ctx, ref, data, len, value);
    lsm_co_od_store(ref, data);
    return LSM_CO_ABORT_NONE;
}

uint32_t lsm_co_od_get_int(const lsm_co_od *od, uint16_t index, uint8_t sub, int64_t *value)
{
    lsm_co_od_ref ref;
    uint32_t ab = lsm_co_od_find(od, index, sub, &ref);
    if (ab)
        return ab;
    size_t ts = lsm_co_od_type_size(ref.entry->type);
    if (ts == 0u)
        return LSM_CO_ABORT_LENGTH;
    uint8_t buf[8];
    size_t n = 0;
    ab = lsm_co_od_read(od, &ref, buf, sizeof buf, &n);
    if (ab)
        return ab;
    uint64_t raw = lsm_can_get_le(buf, n);
    *value = lsm_co_od_type_signed(ref.entry->type) ? sign_extend(raw, n) : (int64_t)raw;
    return LSM_CO_ABORT_NONE;
}

uint32_t lsm_co_od_set_int(lsm_co_od *od, uint16_t index, uint8_t sub, int64_t value)
{
    lsm_co_od_ref ref;
    uint32_t ab = lsm_co_od_find(od, index, sub, &ref);
    if (ab)
        return ab;
    size_t ts = lsm_co_od_type_size(ref.entry->type);
    if (ts == 0u)
        return LSM_CO_ABORT_LENGTH;
    /* a value that does not fit the type is out of range, not silently truncated */
    if (lsm_co_od_type_signed(ref.entry->type)) {
        if (ts < 8u) {
            int64_t lim = (int64_t)1 << (8u * ts - 1u);
            if (value >= lim)
                return LSM_CO_ABORT_VALUE_HIGH;
            if (value < -lim)
                return LSM_CO_ABORT_VALUE_LOW;
        }
    } else if (ref.entry->type != LSM_CO_T_U64 && ref.entry->type != LSM_CO_T_REAL32) {
        if (value < 0)
            return LSM_CO_ABORT_VALUE_LOW;
        if (ts < 8u && (uint64_t)value >= ((uint64_t)1 << (8u * ts)))
            return LSM_CO_ABORT_VALUE_HIGH;
    }
    uint8_t buf[8];
    lsm_can_put_le(buf, (uint64_t)value, ts);
    return lsm_co_od_write(od, &ref, buf, ts);
}
