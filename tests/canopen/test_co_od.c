/*
 * test_co_od.c: the object dictionary engine (co_od.c) on a small table of its own: lookup, every type's
 * little-endian encoding, access rights, length and range checks with their CiA abort codes, constants,
 * strings, the write hook, instance groups, and the init-time table checks (each rejection reason).
 * Also checks that the node's real table (canopen.c) passes init for every axis count.
 */
#include "co_test_util.h"

typedef struct obj {
    uint8_t u8;
    int8_t i8;
    uint16_t u16;
    int16_t i16;
    uint32_t u32;
    int32_t i32;
    uint64_t u64;
    int64_t i64;
    float r32;
    uint8_t flag;
    const char *name;
    uint32_t hooked;
    int32_t inst[3];
} obj;

enum { RG_NONE, RG_SMALL, RG_POS, RG_BIG, RG_N };
static const lsm_co_od_range k_rg[RG_N] = {{0, 0}, {-5, 10}, {1, INT64_MAX}, {0, 1000}};

#define O(f) ((uint32_t)offsetof(obj, f))
static const lsm_co_od_entry k_tab[] = {
    {0x2000, 0, LSM_CO_T_U8, LSM_CO_OD_RW, 0, 0, 1, O(u8)},
    {0x2001, 0, LSM_CO_T_I8, LSM_CO_OD_RW, 0, RG_SMALL, 1, O(i8)},
    {0x2002, 0, LSM_CO_T_U16, LSM_CO_OD_RW | LSM_CO_OD_TPDO, 0, 0, 2, O(u16)},
    {0x2003, 0, LSM_CO_T_I16, LSM_CO_OD_RW, 0, 0, 2, O(i16)},
    {0x2004, 0, LSM_CO_T_U32, LSM_CO_OD_R, 0, 0, 4, O(u32)},
    {0x2005, 0, LSM_CO_T_I32, LSM_CO_OD_RW, 0, 0, 4, O(i32)},
    {0x2006, 0, LSM_CO_T_U64, LSM_CO_OD_RW, 0, RG_POS, 8, O(u64)},
    {0x2007, 0, LSM_CO_T_I64, LSM_CO_OD_RW, 0, 0, 8, O(i64)},
    {0x2008, 0, LSM_CO_T_REAL32, LSM_CO_OD_RW, 0, 0, 4, O(r32)},
    {0x2009, 0, LSM_CO_T_BOOL, LSM_CO_OD_RW, 0, 0, 1, O(flag)},
    {0x200A, 0, LSM_CO_T_VSTRING, LSM_CO_OD_R | LSM_CO_OD_STRPTR, 0, 0, 8, O(name)},
    {0x200B, 0, LSM_CO_T_U8, LSM_CO_OD_R | LSM_CO_OD_CONST, 0, 0, 1, 3},
    {0x200B, 1, LSM_CO_T_U32, LSM_CO_OD_RW | LSM_CO_OD_HOOK, 0, RG_BIG, 4, O(hooked)},
    {0x200C, 0, LSM_CO_T_DOMAIN, LSM_CO_OD_W | LSM_CO_OD_HOOK, 0, 0, 16, 0},
    {0x3000, 0, LSM_CO_T_I32, LSM_CO_OD_RW, 1, 0, 4, O(inst[0])},
    {0x3000, 1, LSM_CO_T_U8, LSM_CO_OD_R | LSM_CO_OD_CONST, 1, 0, 1, 0x42},
};

static int hook_calls;
static int64_t hook_value;
static size_t hook_len;

static uint32_t hook(void *ctx, const lsm_co_od_ref *ref, const uint8_t *data, size_t len, int64_t v)
{
    (void)ctx;
    hook_calls++;
    hook_value = v;
    hook_len = len;
    if (ref->entry->type == LSM_CO_T_DOMAIN)
        return len == 3u ? 0u : LSM_CO_ABORT_VALUE;
    if (v == 13)
        return LSM_CO_ABORT_VALUE; /* an enumeration hole */
    lsm_co_od_store(ref, data);
    return 0u;
}

static obj g_obj;

static lsm_co_od_config base_cfg(const lsm_co_od_entry *tab, size_t n)
{
    lsm_co_od_config c;
    memset(&c, 0, sizeof c);
    c.table = tab;
    c.n_entries = n;
    c.ranges = k_rg;
    c.n_ranges = RG_N;
    c.groups[1].count = 3;
    c.groups[1].index_step = 0x10;
    c.groups[1].offset_step = sizeof(int32_t);
    c.base = &g_obj;
    c.base_size = sizeof g_obj;
    c.write_hook = hook;
    return c;
}

static lsm_co_od g_od;

static int setup(void **state)
{
    (void)state;
    memset(&g_obj, 0, sizeof g_obj);
    g_obj.name = "Lissom-OD-name";
    hook_calls = 0;
    lsm_co_od_config c = base_cfg(k_tab, sizeof k_tab / sizeof k_tab[0]);
    assert_int_equal(lsm_co_od_init(&g_od, &c), LSM_OK);
    return 0;
}

static uint32_t wr(uint16_t idx, uint8_t sub, uint64_t raw, size_t len)
{
    lsm_co_od_ref ref;
    uint32_t ab = lsm_co_od_find(&g_od, idx, sub, &ref);
    if (ab)
        return ab;
    uint8_t b[8];
    lsm_can_put_le(b, raw, len);
    return lsm_co_od_write(&g_od, &ref, b, len);
}

static uint64_t rd(uint16_t idx, uint8_t sub, size_t *len)
{
    lsm_co_od_ref ref;
    assert_int_equal(lsm_co_od_find(&g_od, idx, sub, &ref), 0);
    uint8_t b[16];
    assert_int_equal(lsm_co_od_read(&g_od, &ref, b, sizeof b, len), 0);
    return lsm_can_get_le(b, *len > 8 ? 8 : *len);
}

static void test_find(void **state)
{
    (void)state;
    lsm_co_od_ref ref;
    assert_int_equal(lsm_co_od_find(&g_od, 0x2000, 0, &ref), 0);
    assert_ptr_equal(ref.ptr, &g_obj.u8);
    assert_int_equal(lsm_co_od_find(&g_od, 0x2100, 0, &ref), LSM_CO_ABORT_NO_OBJECT);
    assert_int_equal(lsm_co_od_find(&g_od, 0x2000, 1, &ref), LSM_CO_ABORT_NO_SUB);
    assert_int_equal(lsm_co_od_find(&g_od, 0x200B, 2, &ref), LSM_CO_ABORT_NO_SUB);
    /* groups: instance k at 0x3000 + 0x10 k, value k at inst[k] */
    assert_int_equal(lsm_co_od_find(&g_od, 0x3020, 0, &ref), 0);
    assert_int_equal(ref.inst, 2);
    assert_ptr_equal(ref.ptr, &g_obj.inst[2]);
    assert_int_equal(lsm_co_od_find(&g_od, 0x3030, 0, &ref), LSM_CO_ABORT_NO_OBJECT); /* count is 3 */
    assert_int_equal(lsm_co_od_find(&g_od, 0x3008, 0, &ref), LSM_CO_ABORT_NO_OBJECT); /* not on the step */
    assert_int_equal(lsm_co_od_find(&g_od, 0x3010, 1, &ref), 0);
    assert_null(ref.ptr);
    size_t n;
    assert_int_equal(rd(0x3010, 1, &n), 0x42);
}

static void test_types_roundtrip(void **state)
{
    (void)state;
    size_t n;
    assert_int_equal(wr(0x2000, 0, 0xAB, 1), 0);
    assert_int_equal(g_obj.u8, 0xAB);
    assert_int_equal(wr(0x2001, 0, 0xFB, 1), 0); /* -5 */
    assert_int_equal(g_obj.i8, -5);
    assert_int_equal(wr(0x2002, 0, 0xBEEF, 2), 0);
    assert_int_equal(g_obj.u16, 0xBEEF);
    assert_int_equal(wr(0x2003, 0, 0x8000, 2), 0);
    assert_int_equal(g_obj.i16, -32768);
    assert_int_equal(wr(0x2005, 0, 0xFFFFFFFFu, 4), 0);
    assert_int_equal(g_obj.i32, -1);
    assert_int_equal(wr(0x2006, 0, 0x7EDCBA9876543210ull, 8), 0);
    assert_true(g_obj.u64 == 0x7EDCBA9876543210ull);
    assert_int_equal(wr(0x2007, 0, 0x8000000000000001ull, 8), 0);
    assert_true(g_obj.i64 == INT64_MIN + 1);
    float f = 1.5f;
    uint32_t fb;
    memcpy(&fb, &f, 4);
    assert_int_equal(wr(0x2008, 0, fb, 4), 0);
    assert_true(g_obj.r32 == 1.5f);
    /* read back, little-endian */
    g_obj.u32 = 0x11223344u;
    assert_int_equal(rd(0x2004, 0, &n), 0x11223344u);
    assert_int_equal(n, 4);
    assert_int_equal(rd(0x2003, 0, &n), 0x8000);
    assert_int_equal(n, 2);
    assert_true(rd(0x2006, 0, &n) == 0x7EDCBA9876543210ull);
    assert_int_equal(n, 8);
    int64_t v;
    assert_int_equal(lsm_co_od_get_int(&g_od, 0x2003, 0, &v), 0);
    assert_int_equal(v, -32768);
    assert_int_equal(lsm_co_od_get_int(&g_od, 0x2001, 0, &v), 0);
    assert_int_equal(v, -5);
}

static void test_access_and_length(void **state)
{
    (void)state;
    assert_int_equal(wr(0x2004, 0, 1, 4), LSM_CO_ABORT_READ_ONLY);
    assert_int_equal(wr(0x200B, 0, 1, 1), LSM_CO_ABORT_READ_ONLY); /* const */
    assert_int_equal(wr(0x200A, 0, 1, 1), LSM_CO_ABORT_READ_ONLY); /* string */
    lsm_co_od_ref ref;
    uint8_t b[8];
    size_t n;
    assert_int_equal(lsm_co_od_find(&g_od, 0x200C, 0, &ref), 0);
    assert_int_equal(lsm_co_od_read(&g_od, &ref, b, sizeof b, &n), LSM_CO_ABORT_WRITE_ONLY);
    assert_int_equal(wr(0x2002, 0, 1, 4), LSM_CO_ABORT_LENGTH_HIGH);
    assert_int_equal(wr(0x2002, 0, 1, 1), LSM_CO_ABORT_LENGTH_LOW);
    assert_int_equal(wr(0x2006, 0, 1, 4), LSM_CO_ABORT_LENGTH_LOW);
    /* a read into a too small buffer */
    assert_int_equal(lsm_co_od_find(&g_od, 0x2006, 0, &ref), 0);
    assert_int_equal(lsm_co_od_read(&g_od, &ref, b, 4, &n), LSM_CO_ABORT_NO_MEM);
    /* nothing was stored by any refused write */
    assert_int_equal(g_obj.u16, 0);
    assert_true(g_obj.u64 == 0);
}

static void test_ranges(void **state)
{
    (void)state;
    assert_int_equal(wr(0x2001, 0, 11, 1), LSM_CO_ABORT_VALUE_HIGH);
    assert_int_equal(wr(0x2001, 0, (uint8_t)-6, 1), LSM_CO_ABORT_VALUE_LOW);
    assert_int_equal(wr(0x2001, 0, 10, 1), 0);
    assert_int_equal(wr(0x2001, 0, (uint8_t)-5, 1), 0);
    /* UNSIGNED64 compares unsigned: 0 is below min 1, 2^63 is above INT64_MAX */
    assert_int_equal(wr(0x2006, 0, 0, 8), LSM_CO_ABORT_VALUE_LOW);
    assert_int_equal(wr(0x2006, 0, 0x8000000000000000ull, 8), LSM_CO_ABORT_VALUE_HIGH);
    /* BOOLEAN only 0/1 */
    assert_int_equal(wr(0x2009, 0, 2, 1), LSM_CO_ABORT_VALUE);
    assert_int_equal(wr(0x2009, 0, 1, 1), 0);
    /* REAL32 NaN and infinity refused */
    assert_int_equal(wr(0x2008, 0, 0x7FC00000u, 4), LSM_CO_ABORT_VALUE);
    assert_int_equal(wr(0x2008, 0, 0xFF800000u, 4), LSM_CO_ABORT_VALUE);
    /* set_int: values that do not fit the type */
    assert_int_equal(lsm_co_od_set_int(&g_od, 0x2000, 0, 256), LSM_CO_ABORT_VALUE_HIGH);
    assert_int_equal(lsm_co_od_set_int(&g_od, 0x2000, 0, -1), LSM_CO_ABORT_VALUE_LOW);
    assert_int_equal(lsm_co_od_set_int(&g_od, 0x2003, 0, 40000), LSM_CO_ABORT_VALUE_HIGH);
    assert_int_equal(lsm_co_od_set_int(&g_od, 0x2003, 0, -1234), 0);
    assert_int_equal(g_obj.i16, -1234);
}

static void test_hook(void **state)
{
    (void)state;
    assert_int_equal(wr(0x200B, 1, 12, 4), 0);
    assert_int_equal(hook_calls, 1);
    assert_int_equal(hook_value, 12);
    assert_int_equal(g_obj.hooked, 12);
    assert_int_equal(wr(0x200B, 1, 13, 4), LSM_CO_ABORT_VALUE); /* the hook refuses */
    assert_int_equal(g_obj.hooked, 12);
    assert_int_equal(wr(0x200B, 1, 1001, 4), LSM_CO_ABORT_VALUE_HIGH); /* range checked before the hook */
    assert_int_equal(hook_calls, 2);
    /* domain: length checked against the maximum, then the hook */
    lsm_co_od_ref ref;
    uint8_t b[20] = {1, 2, 3};
    assert_int_equal(lsm_co_od_find(&g_od, 0x200C, 0, &ref), 0);
    assert_int_equal(lsm_co_od_write(&g_od, &ref, b, 3), 0);
    assert_int_equal(hook_len, 3);
    assert_int_equal(lsm_co_od_write(&g_od, &ref, b, 17), LSM_CO_ABORT_LENGTH_HIGH);
    assert_int_equal(lsm_co_od_write(&g_od, &ref, b, 4), LSM_CO_ABORT_VALUE);
}

static void test_string(void **state)
{
    (void)state;
    lsm_co_od_ref ref;
    uint8_t b[16];
    size_t n;
    assert_int_equal(lsm_co_od_find(&g_od, 0x200A, 0, &ref), 0);
    assert_int_equal(lsm_co_od_read(&g_od, &ref, b, sizeof b, &n), 0);
    assert_int_equal(n, 8); /* truncated to the entry's maximum */
    assert_memory_equal(b, "Lissom-O", 8);
    g_obj.name = "ab";
    assert_int_equal(lsm_co_od_read(&g_od, &ref, b, sizeof b, &n), 0);
    assert_int_equal(n, 2);
    g_obj.name = NULL;
    assert_int_equal(lsm_co_od_read(&g_od, &ref, b, sizeof b, &n), 0);
    assert_int_equal(n, 0);
}

/* Each malformed table is refused at init. */
static void expect_bad(lsm_co_od_entry e, const char *why)
{
    lsm_co_od_entry t[3] = {k_tab[0], k_tab[14], e};
    lsm_co_od_config c = base_cfg(t, 3);
    lsm_co_od od;
    if (lsm_co_od_init(&od, &c) != LSM_E_CO_OD)
        fail_msg("table accepted: %s", why);
}

static void test_init_checks(void **state)
{
    (void)state;
    expect_bad((lsm_co_od_entry){0x2100, 0, 0x0A, LSM_CO_OD_R, 0, 0, 1, 0}, "unknown type");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U16, LSM_CO_OD_R, 0, 0, 4, 0}, "size != type size");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U16, 0, 0, 0, 2, 0}, "no access");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U32, LSM_CO_OD_R, 0, 0, 4, sizeof(obj) - 2}, "outside base");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U32, LSM_CO_OD_RW | LSM_CO_OD_CONST, 0, 0, 4, 1},
               "writable const");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U64, LSM_CO_OD_R | LSM_CO_OD_CONST, 0, 0, 8, 1}, "64-bit const");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U8, LSM_CO_OD_R | LSM_CO_OD_RPDO, 0, 0, 1, 0}, "RPDO without W");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U8, LSM_CO_OD_W | LSM_CO_OD_TPDO, 0, 0, 1, 0}, "TPDO without R");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U8, LSM_CO_OD_RW, 0, RG_N, 1, 0}, "range index");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_REAL32, LSM_CO_OD_RW, 0, RG_SMALL, 4, 0}, "range on REAL32");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U64, LSM_CO_OD_RW, 0, RG_SMALL, 8, 0}, "U64 range min < 0");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_U8, LSM_CO_OD_RW, 2, 0, 1, 0}, "empty group");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_VSTRING, LSM_CO_OD_R, 0, 0, 8, 0}, "string without STRPTR");
    expect_bad((lsm_co_od_entry){0x2100, 0, LSM_CO_T_DOMAIN, LSM_CO_OD_RW | LSM_CO_OD_HOOK, 0, 0, 8, 0},
               "readable domain");
    expect_bad((lsm_co_od_entry){0x2000, 0, LSM_CO_T_U8, LSM_CO_OD_R, 0, 0, 1, 0}, "duplicate");
    expect_bad((lsm_co_od_entry){0x2FF0, 0, LSM_CO_T_I32, LSM_CO_OD_RW, 1, 0, 4, O(inst[0])},
               "instance 1 of a group entry collides with 0x3000:00");
    expect_bad((lsm_co_od_entry){0x3000, 0, LSM_CO_T_I32, LSM_CO_OD_RW, 0, 0, 4, O(i32)},
               "single entry collides with instance 0 of a group");
    /* a hook flag without a hook */
    lsm_co_od_entry t[1] = {k_tab[12]};
    lsm_co_od_config c = base_cfg(t, 1);
    c.write_hook = NULL;
    lsm_co_od od;
    assert_int_equal(lsm_co_od_init(&od, &c), LSM_E_CO_OD);
    assert_int_equal(lsm_co_od_init(NULL, &c), LSM_E_NULL);
}

/* The node's own table passes its checks for every axis count, and answers the mandatory objects. */
static void test_node_table(void **state)
{
    (void)state;
    static test_node tn;
    for (uint8_t na = 1; na <= LSM_MAX_AXES; na++) {
        assert_int_equal(tn_init(&tn, na, PATHCAP), LSM_OK);
        int64_t v;
        assert_int_equal(lsm_co_od_get_int(&tn.node.od, 0x1000, 0, &v), 0);
        assert_int_equal(v, LSM_CANOPEN_DEVICE_TYPE);
        assert_int_equal(lsm_co_od_get_int(&tn.node.od, 0x1018, 0, &v), 0);
        assert_int_equal(v, 4);
        assert_int_equal(lsm_co_od_get_int(&tn.node.od, (uint16_t)(0x6041 + 0x800 * (na - 1)), 0, &v), 0);
        /* the first axis the node does not have */
        assert_int_equal(lsm_co_od_get_int(&tn.node.od, (uint16_t)(0x6041 + 0x800 * na), 0, &v),
                         LSM_CO_ABORT_NO_OBJECT);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_find, setup),
        cmocka_unit_test_setup(test_types_roundtrip, setup),
        cmocka_unit_test_setup(test_access_and_length, setup),
        cmocka_unit_test_setup(test_ranges, setup),
        cmocka_unit_test_setup(test_hook, setup),
        cmocka_unit_test_setup(test_string, setup),
        cmocka_unit_test_setup(test_init_checks, setup),
        cmocka_unit_test(test_node_table),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
