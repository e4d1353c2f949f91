/*
 * lsm_atomic.h: the hand-off primitives between the two contexts of the firmware (docs/architecture.md):
 * the control cycle (tick: an interrupt on a board, a high-priority thread on a host) and the background (the
 * main loop). C11 atomics, so the same code is correct on the Cortex-M4F (32-bit loads and stores are single
 * instructions; acquire / release add a DMB) and on a multi-core host, and ThreadSanitizer understands it.
 *
 * Model. Every shared field has exactly one writer context. A single word goes over with a release store and an
 * acquire load. A group of words that must be read together (a request of the tick) is published with a
 * sequence counter (a sequence lock): the writer makes the counter odd, writes the fields (release stores),
 * makes it even again (release); a reader copies the fields (acquire loads) between two reads of the counter and
 * retries if it was odd or changed. The writer never waits, so the tick may write; only the background reads
 * such groups (it may retry: the tick always completes before the background runs again on a single core).
 *
 * Types: lsm_atomic_u32 (uint32_t), lsm_atomic_real (lsm_real; lock-free for float on the M4 and for double on
 * 64-bit hosts).
 */
#ifndef LSM_ATOMIC_H
#define LSM_ATOMIC_H

#include <stdatomic.h>
#include <stdint.h>

#include "lsm_config.h"

typedef _Atomic uint32_t lsm_atomic_u32;
typedef _Atomic lsm_real lsm_atomic_real;

/* Plain (relaxed) access to a shared field: no ordering, but no torn or undefined access. Any context. */
#define lsm_atomic_get(p) atomic_load_explicit((p), memory_order_relaxed)
#define lsm_atomic_put(p, v) atomic_store_explicit((p), (v), memory_order_relaxed)

#if LSM_HANDOFF_SINGLE_CORE
/* One core (lsm_config.h: the Cortex-M4F builds): the tick interrupts the background and never runs beside it, and
 * a core sees its own stores in program order, so only the compiler must keep the order of the accesses: a signal
 * fence, which emits no instruction (a DMB per release store cost the 3-axis cycle about 60 instructions). */
#define LSM_COMPILER_FENCE() atomic_signal_fence(memory_order_seq_cst)
#define lsm_atomic_get_acquire(p) lsm_fenced_get_u32(p)
#define lsm_atomic_put_release(p, v)                           \
    do {                                                       \
        LSM_COMPILER_FENCE();                                  \
        atomic_store_explicit((p), (v), memory_order_relaxed); \
    } while (0)
#define lsm_seq_put(p, v) atomic_store_explicit((p), (v), memory_order_relaxed)
#define lsm_seq_get(p) atomic_load_explicit((p), memory_order_relaxed)
static inline uint32_t lsm_fenced_get_u32(const lsm_atomic_u32 *p)
{
    const uint32_t v = atomic_load_explicit((lsm_atomic_u32 *)p, memory_order_relaxed);
    LSM_COMPILER_FENCE();
    return v;
}
#else
#define LSM_COMPILER_FENCE() ((void)0)
/* Publication of a single word: what the writer wrote before the release store is visible to the reader after
 * its acquire load of that word. */
#define lsm_atomic_get_acquire(p) atomic_load_explicit((p), memory_order_acquire)
#define lsm_atomic_put_release(p, v) atomic_store_explicit((p), (v), memory_order_release)
/* The fields of a sequence-locked group: release stores (each is ordered after the odd count) and acquire loads
 * (the count read after them sees the writer's odd count if any of them is newer). No standalone fence, which
 * ThreadSanitizer does not model (Boehm, "Can seqlocks get along with programming language memory models?",
 * 2012, the variant with ordered data accesses). */
#define lsm_seq_put(p, v) atomic_store_explicit((p), (v), memory_order_release)
#define lsm_seq_get(p) atomic_load_explicit((p), memory_order_acquire)
#endif

/* Sequence lock, writer side (one writer context). Wait-free. */
static inline void lsm_seq_write_begin(lsm_atomic_u32 *seq)
{
    lsm_atomic_put(seq, lsm_atomic_get(seq) + 1u); /* odd: being written */
    LSM_COMPILER_FENCE();
}

static inline void lsm_seq_write_end(lsm_atomic_u32 *seq)
{
    lsm_atomic_put_release(seq, lsm_atomic_get(seq) + 1u); /* even: every field written before it */
}

/* Sequence lock, reader side: begin returns the count to pass to retry; retry is true if the copy may be torn
 * (the writer was active or wrote meanwhile): copy again. The fields are read with lsm_seq_get. */
static inline uint32_t lsm_seq_read_begin(const lsm_atomic_u32 *seq)
{
    return lsm_atomic_get_acquire((lsm_atomic_u32 *)seq);
}

static inline int lsm_seq_read_retry(const lsm_atomic_u32 *seq, uint32_t begin)
{
    LSM_COMPILER_FENCE();
    return (begin & 1u) != 0u || atomic_load_explicit((lsm_atomic_u32 *)seq, memory_order_relaxed) != begin;
}

#endif /* LSM_ATOMIC_H */
