/*
 * co_od_dump.c: prints the object dictionary a Lissom node serves, as JSON, for the EDS generator
 * (scripts/gen_eds.py) and its check (tests/py/test_eds.py). Host tool, not firmware.
 *
 *   co_od_dump <node_id> <n_axes>
 *
 * One object per (index, sub-index) actually served, every instance expanded, with the value it has
 * right after boot (its EDS DefaultValue), the CiA data type, the access and whether it is PDO-mappable.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>

#include "canopen.h"

static lsm_canopen node;
static lsm_can_frame tx[16];
static lsm_co_path_block blocks[32];

static const char *access_of(uint8_t flags)
{
    if (flags & LSM_CO_OD_CONST)
        return "const";
    if ((flags & LSM_CO_OD_RW) == LSM_CO_OD_RW)
        return "rw";
    return (flags & LSM_CO_OD_R) ? "ro" : "wo";
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: co_od_dump <node_id> <n_axes>\n");
        return 2;
    }
    lsm_canopen_config c = lsm_canopen_default_config();
    c.node_id = (uint8_t)strtoul(argv[1], NULL, 0);
    c.n_axes = (uint8_t)strtoul(argv[2], NULL, 0);
    c.tx_storage = tx;
    c.tx_cap = 16;
    c.path_storage = blocks;
    c.path_cap = 32;
    lsm_status st = lsm_canopen_init(&node, &c, 0);
    if (st != LSM_OK) {
        fprintf(stderr, "init: %s\n", lsm_status_str(st));
        return 1;
    }
    size_t n = 0;
    const lsm_co_od_entry *tab = lsm_canopen_od_table(&n);
    printf("{\"node_id\": %u, \"n_axes\": %u, \"n_rpdo\": %d, \"n_tpdo\": %d, \"vendor_id\": %" PRIu32
           ", \"product_code\": %" PRIu32 ", \"revision\": %" PRIu32 ", \"device_name\": \"%s\", \"objects\": [\n",
           c.node_id, c.n_axes, LSM_CO_N_RPDO, LSM_CO_N_TPDO, c.vendor_id, c.product_code, c.revision,
           node.device_name);
    bool first = true;
    for (size_t i = 0; i < n; i++) {
        const lsm_co_od_entry *e = &tab[i];
        const lsm_co_od_group *g = &node.od.cfg.groups[e->group];
        unsigned count = e->group ? g->count : 1u;
        for (unsigned k = 0; k < count; k++) {
            uint16_t index = (uint16_t)(e->index + (e->group ? k * g->index_step : 0u));
            lsm_co_od_ref ref;
            if (lsm_co_od_find(&node.od, index, e->sub, &ref) != 0u || ref.entry != e) {
                fprintf(stderr, "0x%04X:%u not found back\n", index, e->sub);
                return 1;
            }
            printf("%s  {\"index\": %u, \"sub\": %u, \"type\": %u, \"access\": \"%s\", \"pdo\": %s, \"group\": %u, "
                   "\"instance\": %u",
                   first ? "" : ",\n", index, e->sub, e->type, access_of(e->flags),
                   (e->flags & (LSM_CO_OD_TPDO | LSM_CO_OD_RPDO)) ? "true" : "false", e->group, k);
            first = false;
            if (e->range != 0u) {
                const lsm_co_od_range *r = &node.od.cfg.ranges[e->range];
                printf(", \"min\": %" PRId64 ", \"max\": %" PRId64, r->min, r->max);
            }
            if (e->flags & LSM_CO_OD_R) {
                uint8_t buf[80];
                size_t len = 0;
                if (lsm_co_od_read(&node.od, &ref, buf, sizeof buf, &len) != 0u) {
                    fprintf(stderr, "0x%04X:%u unreadable\n", index, e->sub);
                    return 1;
                }
                if (e->type == LSM_CO_T_VSTRING) {
                    printf(", \"default\": \"%.*s\"", (int)len, (const char *)buf);
                } else {
                    uint64_t raw = lsm_can_get_le(buf, len);
                    if (lsm_co_od_type_signed(e->type) && len < 8u && (raw >> (8u * len - 1u)) & 1u)
                        printf(", \"default\": %" PRId64, (int64_t)(raw | ~((1ull << (8u * len)) - 1u)));
                    else if (lsm_co_od_type_signed(e->type))
                        printf(", \"default\": %" PRId64, (int64_t)raw);
                    else
                        printf(", \"default\": %" PRIu64, raw);
                }
            }
            printf("}");
        }
    }
    printf("\n]}\n");
    return 0;
}
