/*
 * co_od.h: the CANopen object dictionary (CiA 301 §7.4): typed objects addressed by (index, sub-index).
 *
 * Model. The dictionary is a table of entries, one per (index, sub-index), each with a CiA data type, an
 * access mask and the place of its value. The table is meant to be `static const` (it lives in flash on
 * an MCU and costs no RAM): instead of a pointer, an entry stores the byte offset of its value from a base
 * object that the caller owns (for the node, the lsm_canopen struct; see canopen.c). Constant values (the
 * sub-index 0 "number of entries" of records, supported-modes bit masks) are stored in the entry itself.
 *
 * Instance groups. Objects that repeat (the CiA 402 objects of each axis at index + 0x800·k, CiA 402 §6;
 * the RPDO/TPDO parameter records at index + k) are one entry with a group number g = 1..3: instance k
 * (k < groups[g].count) answers at index + k·index_step and keeps its value at offset + k·offset_step.
 *
 * Writes. lsm_co_od_write checks, in this order, and answers with the CiA 301 abort code of the first
 * failure (Table 22 of CiA 301 v4.2): writable (0x06010002), length (0x06070012 too long, 0x06070013 too
 * short), value range from the entry's range (0x06090031 above max, 0x06090032 below min), BOOLEAN 0/1 and
 * REAL32 finite (0x06090030). Entries flagged LSM_CO_OD_HOOK then go to the dictionary's write hook, which
 * validates what the table cannot express (enumerations, device state) and stores the value itself; other
 * entries are stored at once. RPDO reception goes through the same path, so a value that an SDO write
 * would refuse is never applied by a PDO either.
 *
 * Byte order: values travel little-endian (CiA 301 §7.1.2); storage is the native C type of the entry
 * (uint8_t for BOOLEAN, int16_t for INTEGER16, float for REAL32, ...), accessed with memcpy.
 * No allocation, no globals: the dictionary is a small struct that points to the caller's table and base.
 * Contexts: the dictionary belongs to the tick (the control cycle; canopen.h, "Contexts"): every value it
 * addresses is written by the tick only. The background's SDO server never calls it: it posts accesses that the tick
 * applies (co_sdo.h, lsm_co_sdo_access_apply). Each call below names its context.
 */
#ifndef LSM_CO_OD_H
#define LSM_CO_OD_H

#include "lsm_config.h"
#include "status.h"

/* CiA 301 data types; the values are the CiA data-type indices (an EDS writes them as DataType=0x0007). */
typedef enum lsm_co_type {
    LSM_CO_T_BOOL = 0x01,    /* BOOLEAN, 1 byte, 0 or 1 */
    LSM_CO_T_I8 = 0x02,      /* INTEGER8 */
    LSM_CO_T_I16 = 0x03,     /* INTEGER16 */
    LSM_CO_T_I32 = 0x04,     /* INTEGER32 */
    LSM_CO_T_U8 = 0x05,      /* UNSIGNED8 */
    LSM_CO_T_U16 = 0x06,     /* UNSIGNED16 */
    LSM_CO_T_U32 = 0x07,     /* UNSIGNED32 */
    LSM_CO_T_REAL32 = 0x08,  /* REAL32 (IEEE 754 single) */
    LSM_CO_T_VSTRING = 0x09, /* VISIBLE_STRING, read-only here (see LSM_CO_OD_STRPTR) */
    LSM_CO_T_DOMAIN = 0x0F,  /* DOMAIN: opaque bytes, write-only through the hook here */
    LSM_CO_T_I64 = 0x15,     /* INTEGER64 */
    LSM_CO_T_U64 = 0x1B      /* UNSIGNED64 */
} lsm_co_type;

/* Entry flags. */
#define LSM_CO_OD_R 0x01u /* readable (SDO upload, TPDO) */
#define LSM_CO_OD_W 0x02u /* writable (SDO download, RPDO) */
#define LSM_CO_OD_RW 0x03u
#define LSM_CO_OD_CONST 0x04u  /* read-only constant: the value is entry.arg (numeric, <= 32 bits) */
#define LSM_CO_OD_TPDO 0x08u   /* may be mapped into a TPDO (needs R) */
#define LSM_CO_OD_RPDO 0x10u   /* may be mapped into an RPDO (needs W) */
#define LSM_CO_OD_HOOK 0x20u   /* writes go to the write hook, which validates and stores */
#define LSM_CO_OD_STRPTR 0x40u /* VISIBLE_STRING: the storage holds a `const char *` (NUL-terminated, may be NULL) */

/* Number of instance groups including group 0 (single objects). */
#define LSM_CO_OD_GROUPS 4

/* CiA 301 SDO abort codes (0 = success). Every code the layer can produce is listed here. */
#define LSM_CO_ABORT_NONE 0x00000000u
#define LSM_CO_ABORT_TOGGLE 0x05030000u         /* toggle bit not alternated */
#define LSM_CO_ABORT_TIMEOUT 0x05040000u        /* SDO protocol timed out */
#define LSM_CO_ABORT_CMD 0x05040001u            /* client/server command specifier not valid or unknown */
#define LSM_CO_ABORT_NO_MEM 0x05040005u         /* out of memory (object larger than the SDO buffer) */
#define LSM_CO_ABORT_UNSUPPORTED 0x06010000u    /* unsupported access to an object */
#define LSM_CO_ABORT_WRITE_ONLY 0x06010001u     /* attempt to read a write-only object */
#define LSM_CO_ABORT_READ_ONLY 0x06010002u      /* attempt to write a read-only object */
#define LSM_CO_ABORT_NO_OBJECT 0x06020000u      /* object does not exist in the object dictionary */
#define LSM_CO_ABORT_NOT_MAPPABLE 0x06040041u   /* object cannot be mapped to the PDO */
#define LSM_CO_ABORT_PDO_LENGTH 0x06040042u     /* number and length of mapped objects exceed the PDO length */
#define LSM_CO_ABORT_PARAM_INCOMPAT 0x06040043u /* general parameter incompatibility */
#define LSM_CO_ABORT_LENGTH 0x06070010u       /* data type does not match, length of service parameter does not match */
#define LSM_CO_ABORT_LENGTH_HIGH 0x06070012u  /* ... length of service parameter too high */
#define LSM_CO_ABORT_LENGTH_LOW 0x06070013u   /* ... length of service parameter too low */
#define LSM_CO_ABORT_NO_SUB 0x06090011u       /* sub-index does not exist */
#define LSM_CO_ABORT_VALUE 0x06090030u        /* invalid value for parameter (download only) */
#define LSM_CO_ABORT_VALUE_HIGH 0x06090031u   /* value of parameter written too high */
#define LSM_CO_ABORT_VALUE_LOW 0x06090032u    /* value of parameter written too low */
#define LSM_CO_ABORT_GENERAL 0x08000000u      /* general error */
#define LSM_CO_ABORT_STORE 0x08000020u        /* data cannot be transferred or stored to the application */
#define LSM_CO_ABORT_DEVICE_STATE 0x08000022u /* ... because of the present device state */

/* One object (index, sub-index). 12 bytes; tables are meant to be static const. */
typedef struct lsm_co_od_entry {
    uint16_t index; /* index of instance 0 */
    uint8_t sub;    /* sub-index */
    uint8_t type;   /* lsm_co_type */
    uint8_t flags;  /* LSM_CO_OD_* */
    uint8_t group;  /* 0 = single object, 1..3 = instance group */
    uint8_t range;  /* 0 = no range check, else index into the range table */
    uint8_t size;   /* bytes: the type's size; for strings and domains the maximum length (1..255) */
    uint32_t arg;   /* byte offset of instance 0's value from the base; for CONST the value itself */
} lsm_co_od_entry;

/* Inclusive value range of numeric entries (UNSIGNED64 values compare as unsigned; then min >= 0). */
typedef struct lsm_co_od_range {
    int64_t min;
    int64_t max;
} lsm_co_od_range;

/* An instance group: `count` instances, `index_step` apart in the dictionary, `offset_step` bytes apart. */
typedef struct lsm_co_od_group {
    uint16_t count;
    uint16_t index_step;
    uint32_t offset_step;
} lsm_co_od_group;

/* A resolved object: the entry, the instance, and where its value lives. */
typedef struct lsm_co_od_ref {
    const lsm_co_od_entry *entry;
    void *ptr;      /* storage of this instance; NULL for CONST entries */
    uint16_t index; /* index as addressed */
    uint8_t sub;
    uint8_t inst; /* instance number within the entry's group (0 for group 0) */
} lsm_co_od_ref;

/*
 * The write hook, for LSM_CO_OD_HOOK entries. Called after the generic checks with the received bytes
 * (little-endian, len already checked against the entry) and, for numeric types, the decoded value
 * (sign-extended; UNSIGNED64 as its bit pattern). Returns 0 after storing the value (lsm_co_od_store does
 * the default store), or an abort code and leaves everything unchanged.
 */
typedef uint32_t (*lsm_co_od_write_fn)(void *ctx, const lsm_co_od_ref *ref, const uint8_t *data, size_t len,
                                       int64_t value);

typedef struct lsm_co_od_config {
    const lsm_co_od_entry *table; /* the entries, any order */
    size_t n_entries;
    const lsm_co_od_range
        *ranges; /* range table; ranges[0] is unused (range 0 = none); may be NULL if no entry has a range */
    size_t n_ranges;
    lsm_co_od_group groups[LSM_CO_OD_GROUPS]; /* groups[0] unused */
    void *base;                               /* the object whose bytes the offsets address */
    size_t base_size;                         /* sizeof(*base): every value must lie inside */
    lsm_co_od_write_fn write_hook;            /* required if any entry has LSM_CO_OD_HOOK, else may be NULL */
    void *hook_ctx;
} lsm_co_od_config;

typedef struct lsm_co_od {
    lsm_co_od_config cfg;
} lsm_co_od;

/*
 * Checks the table once and binds it. Errors: LSM_E_NULL, LSM_E_CO_OD (unknown type, size that does not
 * match the type, value outside base, CONST that is writable or wider than 32 bits, PDO flag without the
 * matching access, range on a non-numeric entry or min > max, group without instances, HOOK entry without
 * a hook, a (index, sub-index) served twice, DOMAIN that is not a write-only hooked entry).
 * Before the tick and the background run (lsm_canopen_init).
 */
lsm_status lsm_co_od_init(lsm_co_od *od, const lsm_co_od_config *cfg);

/* Bytes of a numeric type (1, 2, 4 or 8), 0 for strings, domains and unknown types. Any context (pure). */
size_t lsm_co_od_type_size(uint8_t type);

/* True for the signed integer types. Any context (pure). */
bool lsm_co_od_type_signed(uint8_t type);

/* Finds (index, sub). Returns 0 with *ref filled, LSM_CO_ABORT_NO_OBJECT or LSM_CO_ABORT_NO_SUB. Tick. */
uint32_t lsm_co_od_find(const lsm_co_od *od, uint16_t index, uint8_t sub, lsm_co_od_ref *ref);

/* Builds the reference of instance `inst` of table entry number `entry` (as cached by PDO mappings).
 * Returns 0, or LSM_CO_ABORT_NO_OBJECT when entry or inst is out of range. Tick. */
uint32_t lsm_co_od_ref_at(const lsm_co_od *od, size_t entry, uint8_t inst, lsm_co_od_ref *ref);

/* Bytes a read of ref yields now (the type size; the current length for strings). Tick. */
size_t lsm_co_od_read_size(const lsm_co_od_ref *ref);

/* Reads the value into buf (little-endian). 0, LSM_CO_ABORT_WRITE_ONLY or LSM_CO_ABORT_NO_MEM (cap too small). Tick. */
uint32_t lsm_co_od_read(const lsm_co_od *od, const lsm_co_od_ref *ref, uint8_t *buf, size_t cap, size_t *len);

/* Writes len little-endian bytes with every check described above. Returns 0 or the abort code. Tick. */
uint32_t lsm_co_od_write(lsm_co_od *od, const lsm_co_od_ref *ref, const uint8_t *data, size_t len);

/* The default store of a numeric value (for hooks): copies data (the entry's size) into ref's storage. Tick. */
void lsm_co_od_store(const lsm_co_od_ref *ref, const uint8_t *data);

/* Convenience for applications and tests: read / write a numeric object by address, as int64
 * (UNSIGNED64 as its bit pattern). Same checks and abort codes as the SDO path. Tick. */
uint32_t lsm_co_od_get_int(const lsm_co_od *od, uint16_t index, uint8_t sub, int64_t *value);
uint32_t lsm_co_od_set_int(lsm_co_od *od, uint16_t index, uint8_t sub, int64_t value);

#endif /* LSM_CO_OD_H */
