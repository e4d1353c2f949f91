/*
 * test_co_sdo_split.c: the SDO server in the background (canopen.h, cfg.sdo_background: the protocol in the
 * background, every object access applied by the tick, the hand-off of request ring, access mailbox, response ring
 * and reset epoch) against the server in the tick (one context).
 *
 * A seeded client plays CANopen master: sessions of expedited and segmented uploads and downloads (sized and not),
 * and the failures: unknown objects and sub-indices, read-only and write-only objects, values out of range, wrong
 * sizes, toggle errors, out-of-sequence segments, block-transfer requests, client aborts, time-outs, malformed
 * frames, SDO in NMT STOPPED, NMT reset communication and reset node between transfers. Like a real client it sends
 * the next request of a transfer only after the response to the last one. The same script runs on two nodes:
 *   reference   the one-context node (the server inside lsm_canopen_rx / _process);
 *   injector    the split node with its background run at a seeded schedule between ticks: to idle, one step, or
 *               not at all for up to 3 ticks (an interrupt-heavy main loop);
 *   threads     (LSM_TEST_THREADS, the ThreadSanitizer build: ctest co_sdo_split_tsan) the tick in this thread, the
 *               background spinning in another, preempting each other anywhere.
 * Checks: the split node's SDO response frames equal the reference's, frame for frame and in order, and the objects
 * the script writes read the same at the end. Plus the split's own cases: a request in flight when an NMT stop or
 * reset arrives is dropped unanswered, a full request ring refuses at once with 0x05040005.
 * argv: [seed] [count] (count scripts per mode).
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "canopen.h"
#include "lsm_test_rng.h"

#if LSM_TEST_THREADS
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#endif

#define NODE_ID 5u
#define SDO_RX (0x600u + NODE_ID)
#define SDO_TX (0x580u + NODE_ID)
#define TXCAP 64u
#define PATHCAP 8u
#define MAX_STEPS 2048u
#define SDO_TIMEOUT_US 1000000000u /* 1000 s: only the script's time jumps reach it, never a slow background */
#define TIMEOUT_JUMP_US 1100000000u
#define WAIT_TICKS 64u /* injector: the longest a response may take (3 starved ticks + 2 of hand-off, with margin) */

static unsigned long long g_seed, g_count;

/* ---- the script ------------------------------------------------------------------------------------------ */

enum { S_REQ = 0, S_SEND = 1, S_WAIT = 2 }; /* expect one response / expect none / send nothing, expect one */

typedef struct step {
    lsm_can_frame f;
    uint8_t kind;
    uint32_t jump_us; /* time added before the step (a time-out) */
} step;

typedef struct script {
    step s[MAX_STEPS];
    size_t n;
} script;

static script g_script;

static void add(script *sc, uint32_t id, uint8_t dlc, const uint8_t *d, uint8_t kind, uint32_t jump_us)
{
    assert_true(sc->n < MAX_STEPS);
    step *st = &sc->s[sc->n++];
    memset(st, 0, sizeof *st);
    st->f.id = id;
    st->f.dlc = dlc;
    if (d != NULL)
        memcpy(st->f.data, d, dlc);
    st->kind = kind;
    st->jump_us = jump_us;
}

static void req(script *sc, const uint8_t d[8])
{
    add(sc, SDO_RX, 8u, d, S_REQ, 0u);
}

static void init_frame(uint8_t d[8], uint8_t cmd, uint16_t index, uint8_t sub)
{
    memset(d, 0, 8);
    d[0] = cmd;
    lsm_can_put_u16(&d[1], index);
    d[3] = sub;
}

static void exp_upload(script *sc, uint16_t index, uint8_t sub)
{
    uint8_t d[8];
    init_frame(d, 0x40u, index, sub);
    req(sc, d);
}

/* len 1..4; sized false: command 0x22 (the server takes the object's own size). */
static void exp_download(script *sc, uint16_t index, uint8_t sub, uint64_t v, size_t len, bool sized)
{
    uint8_t d[8];
    init_frame(d, sized ? (uint8_t)(0x23u | ((4u - len) << 2)) : 0x22u, index, sub);
    lsm_can_put_le(&d[4], v, len);
    req(sc, d);
}

/* Faults of a segmented transfer, at segment number `at` (-1: none). */
typedef struct seg_faults {
    int toggle_at;    /* this segment with the wrong toggle */
    int abort_at;     /* a client abort instead of this segment (then the segment anyway: out of sequence) */
    int timeout_at;   /* the client stalls before this segment until the server's time-out abort */
    int nmt_at;       /* an NMT stop and PRE-OPERATIONAL before this segment (the transfer is dropped) */
    int64_t announce; /* size announced at initiate (-1: the true size; -2: not indicated) */
} seg_faults;

static const seg_faults k_clean = {-1, -1, -1, -1, -1};

static void segment_faults(script *sc, const seg_faults *fl, int k, uint8_t *d0)
{
    if (k == fl->abort_at) {
        uint8_t a[8] = {0x80u, 0, 0, 0, 0x00, 0x00, 0x04, 0x05};
        add(sc, SDO_RX, 8u, a, S_SEND, 0u);
    }
    if (k == fl->timeout_at)
        add(sc, 0u, 0u, NULL, S_WAIT, TIMEOUT_JUMP_US);
    if (k == fl->nmt_at) {
        const uint8_t stop[2] = {0x02u, NODE_ID}, preop[2] = {0x80u, NODE_ID};
        add(sc, 0x000u, 2u, stop, S_SEND, 0u);
        add(sc, 0x000u, 2u, preop, S_SEND, 0u);
    }
    if (k == fl->toggle_at)
        *d0 ^= 0x10u;
}

static void seg_download(script *sc, uint16_t index, uint8_t sub, const uint8_t *data, size_t len, const seg_faults *fl)
{
    uint8_t d[8];
    init_frame(d, fl->announce == -2 ? 0x20u : 0x21u, index, sub);
    if (fl->announce != -2)
        lsm_can_put_u32(&d[4], (uint32_t)(fl->announce >= 0 ? (uint64_t)fl->announce : len));
    req(sc, d);
    size_t pos = 0;
    uint8_t t = 0;
    int k = 0;
    do {
        const size_t n = len - pos > 7u ? 7u : len - pos;
        const bool last = pos + n == len;
        memset(d, 0, sizeof d);
        d[0] = (uint8_t)(t | ((7u - n) << 1) | (last ? 1u : 0u));
        segment_faults(sc, fl, k, &d[0]);
        memcpy(&d[1], &data[pos], n);
        req(sc, d);
        pos += n;
        t ^= 0x10u;
        k++;
    } while (pos < len);
}

static void seg_upload(script *sc, uint16_t index, uint8_t sub, int segments, const seg_faults *fl)
{
    uint8_t d[8];
    init_frame(d, 0x40u, index, sub);
    req(sc, d);
    uint8_t t = 0;
    for (int k = 0; k < segments; k++) {
        memset(d, 0, sizeof d);
        d[0] = (uint8_t)(0x60u | t);
        segment_faults(sc, fl, k, &d[0]);
        req(sc, d);
        t ^= 0x10u;
    }
}

static void nmt(script *sc, uint8_t cmd)
{
    uint8_t d[2] = {cmd, NODE_ID};
    add(sc, 0x000u, 2u, d, S_SEND, 0u);
}

static uint32_t rnd(uint64_t *st, uint32_t n)
{
    return (uint32_t)(test_urand(st) * (double)n);
}

/* The readable objects a session picks from (some absent, some write-only). */
static const struct {
    uint16_t index;
    uint8_t sub;
} k_reads[] = {{0x1000, 0}, {0x1001, 0}, {0x1017, 0}, {0x6060, 0}, {0x607A, 0}, {0x687A, 0}, {0x6041, 0},
               {0x5F00, 1}, {0x5001, 0}, {0x1018, 2}, {0x1234, 0}, {0x1000, 5}, {0x5010, 0}, {0x1200, 1}};

/* A write to one of the objects the end state compares, with values in and out of their ranges. */
static void random_write(script *sc, uint64_t *st)
{
    switch (rnd(st, 7)) {
    case 0: exp_download(sc, 0x1017, 0, rnd(st, 2000), 2, rnd(st, 2) != 0u); break;
    case 1: exp_download(sc, 0x607A, 0, (uint64_t)(int64_t)((int32_t)rnd(st, 200000) - 100000), 4, true); break;
    case 2: exp_download(sc, 0x687A, 0, rnd(st, 1000), 4, rnd(st, 2) != 0u); break;
    case 3: exp_download(sc, 0x5001, 0, rnd(st, 260), 1, true); break; /* 0..200 % */
    case 4: {
        static const int8_t modes[] = {1, 8, -1, 5, 0, 3};
        exp_download(sc, 0x6060, 0, (uint64_t)(uint8_t)modes[rnd(st, 6)], 1, true);
        break;
    }
    case 5: exp_download(sc, 0x6081, 0, rnd(st, 3), 4, true); break; /* 0 refused */
    default: exp_download(sc, 0x1000, 0, 1, 4, true); break;         /* read-only */
    }
}

static void random_segmented(script *sc, uint64_t *st)
{
    uint8_t data[32];
    for (size_t i = 0; i < sizeof data; i++)
        data[i] = (uint8_t)rnd(st, 256);
    seg_faults fl = k_clean;
    const uint32_t fault = rnd(st, 9);
    if (fault == 1)
        fl.toggle_at = 1;
    else if (fault == 2)
        fl.abort_at = 1;
    else if (fault == 3)
        fl.timeout_at = 1;
    else if (fault == 4)
        fl.announce = 12; /* more than the object */
    else if (fault == 5)
        fl.announce = -2; /* not indicated */
    else if (fault == 6)
        fl.announce = 9; /* one more than the bytes sent */
    else if (fault == 7)
        fl.nmt_at = 1;
    switch (rnd(st, 4)) {
    case 0: seg_download(sc, 0x2060, 0, data, 8, &fl); break;  /* UNSIGNED64: zero refused (range) */
    case 1: seg_download(sc, 0x5010, 0, data, 20, &fl); break; /* a path block of garbage: refused */
    case 2: seg_upload(sc, 0x1008, 0, 5, &fl); break;          /* the device name, 33 bytes: 5 segments */
    default: seg_upload(sc, 0x2060, 0, 2, &fl); break;         /* 8 bytes: 2 segments */
    }
}

static void random_misc(script *sc, uint64_t *st)
{
    uint8_t d[8];
    switch (rnd(st, 6)) {
    case 0: /* block download request: not supported */
        init_frame(d, 0xC2u, 0x2060, 0);
        req(sc, d);
        break;
    case 1: /* a segment with no transfer open */
        memset(d, 0, sizeof d);
        req(sc, d);
        break;
    case 2: /* malformed: DLC 7, ignored */
        init_frame(d, 0x40u, 0x1000, 0);
        add(sc, SDO_RX, 7u, d, S_SEND, 0u);
        break;
    case 3: /* NMT stopped: the request is ignored; back to PRE-OPERATIONAL */
        nmt(sc, 0x02u);
        init_frame(d, 0x40u, 0x1000, 0);
        add(sc, SDO_RX, 8u, d, S_SEND, 0u);
        nmt(sc, 0x80u);
        break;
    case 4: nmt(sc, 0x82u); break;  /* reset communication: 0x1017 back to its default */
    default: nmt(sc, 0x81u); break; /* reset node (at rest: at the next cycle) */
    }
}

static void make_script(script *sc, uint64_t seed, size_t sessions)
{
    uint64_t st = seed * 0x9E3779B97F4A7C15ull + 1u;
    sc->n = 0;
    for (size_t i = 0; i < sessions; i++) {
        const uint32_t what = rnd(&st, 10);
        if (what < 3) {
            const size_t k = rnd(&st, sizeof k_reads / sizeof k_reads[0]);
            exp_upload(sc, k_reads[k].index, k_reads[k].sub);
        } else if (what < 6) {
            random_write(sc, &st);
        } else if (what < 9) {
            random_segmented(sc, &st);
        } else {
            random_misc(sc, &st);
        }
    }
}

/* ---- the nodes and the client ------------------------------------------------------------------------------ */

enum { M_REFERENCE = 0, M_INJECTOR = 1, M_THREADS = 2 };

typedef struct run {
    lsm_canopen node;
    lsm_can_frame tx[TXCAP];
    lsm_co_path_block blocks[PATHCAP];
    lsm_can_frame resp[MAX_STEPS * 2u];
    size_t n_resp;
    uint32_t now_us, dt_us;
    int mode;
    uint64_t sched; /* the injector's generator */
    int starve;     /* injector: ticks left without a background step */
    unsigned long ticks;
#if LSM_TEST_THREADS
    atomic_uint clock_us; /* the tick's time for the background thread (published after rx, as ctl_app does) */
#endif
} run;

static run g_ref, g_split;

static void boot(run *r, int mode, uint64_t seed)
{
    memset(r, 0, sizeof *r);
    r->mode = mode;
    r->dt_us = mode == M_THREADS ? 1u : 1000u;
    r->sched = seed * 0xD1B54A32D192ED03ull + 7u;
    lsm_canopen_config c = lsm_canopen_default_config();
    c.node_id = NODE_ID;
    c.n_axes = 2;
    c.heartbeat_ms = 0u;
    c.tx_storage = r->tx;
    c.tx_cap = TXCAP;
    c.path_storage = r->blocks;
    c.path_cap = PATHCAP;
    c.device_name = "Lissom test node with a long name";
    c.sdo_timeout_us = SDO_TIMEOUT_US;
    c.sdo_background = mode != M_REFERENCE;
    assert_int_equal(lsm_canopen_init(&r->node, &c, 0u), LSM_OK);
}

/* The injector: the background's share between two ticks. */
static void inject_background(run *r)
{
    if (r->starve > 0) {
        r->starve--;
        return;
    }
    const uint32_t pick = rnd(&r->sched, 10);
    if (pick < 6) {
        while (lsm_canopen_sdo_background(&r->node, r->now_us)) {
        }
    } else if (pick < 9) {
        (void)lsm_canopen_sdo_background(&r->node, r->now_us);
    } else {
        r->starve = (int)rnd(&r->sched, 3);
    }
}

static void tick(run *r, const lsm_can_frame *f)
{
    r->now_us += r->dt_us;
    r->ticks++;
    if (f != NULL)
        (void)lsm_canopen_rx(&r->node, f, r->now_us);
#if LSM_TEST_THREADS
    atomic_store_explicit(&r->clock_us, r->now_us, memory_order_release);
#endif
    (void)lsm_canopen_process(&r->node, r->now_us);
    lsm_can_frame out;
    while (lsm_canopen_tx_pop(&r->node, &out)) {
        if (out.id == SDO_TX) {
            assert_true(r->n_resp < MAX_STEPS * 2u);
            r->resp[r->n_resp++] = out;
        }
    }
    if (r->mode == M_INJECTOR)
        inject_background(r);
}

static void run_script(run *r, const script *sc)
{
    for (size_t i = 0; i < sc->n; i++) {
        const step *st = &sc->s[i];
        r->now_us += st->jump_us;
        const size_t before = r->n_resp;
        tick(r, st->kind == S_WAIT ? NULL : &st->f);
        if (st->kind == S_SEND)
            continue;
        /* a client waits for the response before it sends anything else */
        const unsigned long bound = r->mode == M_THREADS ? 20000000ul : WAIT_TICKS;
        for (unsigned long w = 0; r->n_resp == before && w < bound; w++) {
#if LSM_TEST_THREADS
            if (r->mode == M_THREADS)
                sched_yield();
#endif
            tick(r, NULL);
        }
        if (r->n_resp == before) {
            fprintf(stderr, "step %zu (id 0x%03X, byte 0 0x%02X): no response\n", i, (unsigned)st->f.id, st->f.data[0]);
            fail();
        }
    }
    for (unsigned w = 0; w < 8u; w++) /* anything late (an unexpected frame) shows in the comparison */
        tick(r, NULL);
}

/* The objects the script writes (and a few it only reads), through the dictionary: tick. */
static const struct {
    uint16_t index;
    uint8_t sub;
} k_state[] = {{0x1017, 0}, {0x607A, 0}, {0x687A, 0}, {0x5001, 0}, {0x6060, 0}, {0x6061, 0},
               {0x6081, 0}, {0x2060, 0}, {0x6041, 0}, {0x5003, 0}, {0x5004, 0}, {0x1001, 0}};

static void check_same(const char *what, unsigned long long seed)
{
    bool same = g_split.n_resp == g_ref.n_resp;
    size_t i = 0;
    for (; same && i < g_ref.n_resp; i++)
        same = g_split.resp[i].dlc == g_ref.resp[i].dlc && memcmp(g_split.resp[i].data, g_ref.resp[i].data, 8) == 0;
    if (!same) {
        fprintf(stderr, "%s, script seed %llu: responses differ at %zu (%zu vs %zu responses)\n", what, seed,
                i == 0 ? 0 : i - 1, g_split.n_resp, g_ref.n_resp);
        fail();
    }
    for (size_t k = 0; k < sizeof k_state / sizeof k_state[0]; k++) {
        int64_t a = 0, b = 0;
        const uint32_t ea = lsm_co_od_get_int(&g_ref.node.od, k_state[k].index, k_state[k].sub, &a);
        const uint32_t eb = lsm_co_od_get_int(&g_split.node.od, k_state[k].index, k_state[k].sub, &b);
        if (ea != eb || a != b) {
            fprintf(stderr, "%s, script seed %llu: 0x%04X:%u reads %lld vs %lld\n", what, seed, k_state[k].index,
                    k_state[k].sub, (long long)b, (long long)a);
            fail();
        }
    }
    assert_int_equal(lsm_canopen_nmt_state(&g_split.node), lsm_canopen_nmt_state(&g_ref.node));
}

/* The reference itself answers what the script asks (so the comparison compares something). */
static void test_reference_answers(void **state)
{
    (void)state;
    make_script(&g_script, g_seed, 400);
    boot(&g_ref, M_REFERENCE, g_seed);
    run_script(&g_ref, &g_script);
    size_t aborts = 0, segments = 0, expedited = 0;
    for (size_t i = 0; i < g_ref.n_resp; i++) {
        const uint8_t c = g_ref.resp[i].data[0];
        aborts += c == 0x80u;
        segments += (c & 0xE0u) == 0x20u || (c & 0xE0u) == 0x00u;
        expedited += (c & 0xE3u) == 0x43u;
    }
    assert_true(aborts > 20u);
    assert_true(segments > 20u);
    assert_true(expedited > 20u);
}

static void test_injector(void **state)
{
    (void)state;
    for (unsigned long long c = 0; c < g_count; c++) {
        const unsigned long long seed = g_seed + c;
        make_script(&g_script, seed, 400);
        boot(&g_ref, M_REFERENCE, seed);
        run_script(&g_ref, &g_script);
        boot(&g_split, M_INJECTOR, seed);
        run_script(&g_split, &g_script);
        check_same("injector", seed);
    }
}

#if LSM_TEST_THREADS
static atomic_bool g_stop;
static atomic_ulong g_bg_steps; /* background calls that did something */

static void *background_thread(void *arg)
{
    run *r = arg;
    uint32_t now_us = 0;
    /* the clock is read only now and then (a main loop's time may be old; it is never ahead of the tick's), so that
     * its acquire does not order the rings' slots: those must be ordered by the rings' own counts */
    for (unsigned k = 0; !atomic_load_explicit(&g_stop, memory_order_relaxed); k++) {
        if (k % 64u == 0u)
            now_us = atomic_load_explicit(&r->clock_us, memory_order_acquire);
        if (lsm_canopen_sdo_background(&r->node, now_us))
            atomic_fetch_add(&g_bg_steps, 1u);
        else
            sched_yield();
    }
    return NULL;
}

/* The tick in this thread, the background in another. */
static void test_threads(void **state)
{
    (void)state;
    unsigned long ticks = 0;
    atomic_store(&g_bg_steps, 0u);
    for (unsigned long long c = 0; c < g_count; c++) {
        const unsigned long long seed = g_seed + c;
        make_script(&g_script, seed, 200);
        boot(&g_ref, M_REFERENCE, seed);
        g_ref.dt_us = 1u;
        run_script(&g_ref, &g_script);
        boot(&g_split, M_THREADS, seed);
        atomic_store(&g_stop, false);
        pthread_t th;
        assert_int_equal(pthread_create(&th, NULL, background_thread, &g_split), 0);
        run_script(&g_split, &g_script);
        atomic_store(&g_stop, true);
        assert_int_equal(pthread_join(th, NULL), 0);
        check_same("threads", seed);
        ticks += g_split.ticks;
    }
    /* the background thread served the sessions while the tick ran on */
    printf("threads: %lu ticks, %lu background steps that did something\n", ticks, atomic_load(&g_bg_steps));
    assert_true(atomic_load(&g_bg_steps) > 100u);
}
#endif

/* ---- the split's own cases ------------------------------------------------------------------------------------ */

static lsm_can_frame upload_req(uint16_t index)
{
    lsm_can_frame f;
    memset(&f, 0, sizeof f);
    f.id = SDO_RX;
    f.dlc = 8u;
    init_frame(f.data, 0x40u, index, 0);
    return f;
}

static size_t drain_sdo(run *r)
{
    size_t n = 0;
    lsm_can_frame out;
    while (lsm_canopen_tx_pop(&r->node, &out)) {
        if (out.id == SDO_TX)
            r->resp[n++] = out;
    }
    return n;
}

/* An NMT stop while a request waits for the background, or while its access waits for the tick: no answer, and
 * the next transfer after the node is back is served normally. */
static void test_reset_drops_in_flight(void **state)
{
    (void)state;
    boot(&g_split, M_INJECTOR, 1);
    run *r = &g_split;
    (void)drain_sdo(r);
    const lsm_can_frame f = upload_req(0x1000);
    const uint8_t stop[2] = {0x02u, NODE_ID}, preop[2] = {0x80u, NODE_ID};
    lsm_can_frame nf;
    memset(&nf, 0, sizeof nf);
    nf.dlc = 2u;
    for (int where = 0; where < 2; where++) {
        assert_int_equal(lsm_canopen_rx(&r->node, &f, 1000u), LSM_OK);
        if (where == 1)
            assert_true(lsm_canopen_sdo_background(&r->node, 1000u)); /* its access is posted */
        memcpy(nf.data, stop, 2);
        assert_int_equal(lsm_canopen_rx(&r->node, &nf, 1000u), LSM_OK);
        for (int k = 0; k < 4; k++) {
            (void)lsm_canopen_process(&r->node, 2000u);
            (void)lsm_canopen_sdo_background(&r->node, 2000u);
        }
        assert_int_equal(drain_sdo(r), 0u);
        memcpy(nf.data, preop, 2);
        assert_int_equal(lsm_canopen_rx(&r->node, &nf, 3000u), LSM_OK);
    }
    assert_true(r->node.sdo_link.stale + r->node.sdo_link.bg_dropped >= 1u);
    assert_int_equal(lsm_canopen_rx(&r->node, &f, 4000u), LSM_OK);
    for (int k = 0; k < 3; k++) {
        (void)lsm_canopen_sdo_background(&r->node, 4000u);
        (void)lsm_canopen_process(&r->node, 4000u);
    }
    assert_int_equal(drain_sdo(r), 1u);
    assert_int_equal(r->resp[0].data[0], 0x43u);
    assert_int_equal(lsm_can_get_u32(&r->resp[0].data[4]), LSM_CANOPEN_DEVICE_TYPE);
}

/* A full request ring refuses at once (the tick never waits): abort 0x05040005 naming the object, LSM_E_FULL; the
 * requests already queued are all answered. */
static void test_full_ring_refuses(void **state)
{
    (void)state;
    boot(&g_split, M_INJECTOR, 1);
    run *r = &g_split;
    (void)drain_sdo(r);
    for (unsigned i = 0; i < LSM_CANOPEN_SDO_QUEUE; i++) {
        const lsm_can_frame f = upload_req(0x1000);
        assert_int_equal(lsm_canopen_rx(&r->node, &f, 1000u), LSM_OK);
    }
    const lsm_can_frame f = upload_req(0x1017);
    assert_int_equal(lsm_canopen_rx(&r->node, &f, 1000u), LSM_E_FULL);
    assert_int_equal(drain_sdo(r), 1u);
    assert_int_equal(r->resp[0].data[0], 0x80u);
    assert_int_equal(lsm_can_get_u16(&r->resp[0].data[1]), 0x1017);
    assert_int_equal(lsm_can_get_u32(&r->resp[0].data[4]), LSM_CO_ABORT_NO_MEM);
    uint32_t waiting = 0, most = 0, refused = 0;
    lsm_canopen_sdo_stats(&r->node, &waiting, &most, &refused);
    assert_int_equal(waiting, LSM_CANOPEN_SDO_QUEUE);
    assert_int_equal(most, LSM_CANOPEN_SDO_QUEUE);
    assert_int_equal(refused, 1u);
    size_t answered = 0;
    for (unsigned k = 0; k < 4u * LSM_CANOPEN_SDO_QUEUE; k++) {
        (void)lsm_canopen_sdo_background(&r->node, 2000u);
        (void)lsm_canopen_process(&r->node, 2000u);
        const size_t n = drain_sdo(r);
        for (size_t i = 0; i < n; i++)
            assert_int_equal(r->resp[i].data[0], 0x43u);
        answered += n;
    }
    assert_int_equal(answered, LSM_CANOPEN_SDO_QUEUE);
    lsm_canopen_sdo_stats(&r->node, &waiting, NULL, NULL);
    assert_int_equal(waiting, 0u);
}

/* The tick applies at most one object access per cycle, whatever the background asks. */
static void test_one_access_per_tick(void **state)
{
    (void)state;
    boot(&g_split, M_INJECTOR, 1);
    run *r = &g_split;
    (void)drain_sdo(r);
    for (unsigned i = 0; i < 4u; i++) {
        const lsm_can_frame f = upload_req(0x1000);
        assert_int_equal(lsm_canopen_rx(&r->node, &f, 1000u), LSM_OK);
    }
    for (unsigned k = 0; k < 4u; k++) {
        while (lsm_canopen_sdo_background(&r->node, 1000u)) {
        }
        const uint32_t before = lsm_atomic_get(&r->node.sdo_link.acc_done);
        (void)lsm_canopen_process(&r->node, 1000u);
        assert_int_equal(lsm_atomic_get(&r->node.sdo_link.acc_done) - before, 1u);
    }
}

int main(int argc, char **argv)
{
    g_seed = test_arg_u(argc, argv, 1, 1u);
    g_count = test_arg_u(argc, argv, 2, 12u);
    const struct CMUnitTest tests[] =
    { cmocka_unit_test(test_reference_answers),
      cmocka_unit_test(test_injector),
#if LSM_TEST_THREADS
      cmocka_unit_test(test_threads),
#endif
      cmocka_unit_test(test_reset_drops_in_flight),
      cmocka_unit_test(test_full_ring_refuses),
      cmocka_unit_test(test_one_access_per_tick),
    };
    const int rc = cmocka_run_group_tests(tests, NULL, NULL);
    return test_seed_finish(argv[0], g_seed, g_count, rc);
}
