/* selftest_prog.c: the built-in self-test motion program (see selftest_prog.h). */
#include "selftest_prog.h"

#include <stdatomic.h>
#include <string.h>

#define CYCLE_S ((lsm_real)LSM_SELFTEST_CYCLE_US * LSM_R(1e-6))

enum { PART_SCURVE = 0, PART_MOVE = 1, N_PARTS = 2 };

static const char *const k_part_names[N_PARTS] = {"scurve", "move"};

/* Velocity changes: v0, v1 (mm/s), a_max, j_max, snap_max. The last one is invalid on purpose (a negative
 * limit), so the plan hash also covers the validation path. */
typedef struct sc_case {
    float v0, v1, a, j, snap;
} sc_case;

static const sc_case k_sc_cases[] = {
    {0.0f, 100.0f, 1000.0f, 20000.0f, 1.0e6f}, {100.0f, 30.0f, 500.0f, 10000.0f, 5.0e5f},
    {30.0f, 0.0f, 2000.0f, 1.0e5f, 1.0e7f},    {0.0f, 5.0f, 3000.0f, 5.0e4f, 2.0e6f},
    {12.5f, 250.0f, 4000.0f, 8.0e4f, 4.0e6f},  {1.0f, 2.0f, -1.0f, 1.0f, 1.0f},
};
#define N_SC_CASES ((uint32_t)(sizeof k_sc_cases / sizeof k_sc_cases[0]))

/* Point-to-point moves on 1, 3 and 6 axes (distances in mm or deg for A, B, C); the last request is
 * infeasible on purpose (far too short to reach its end feed). */
typedef struct mv_case {
    uint8_t n_axes;
    float d[LSM_MAX_AXES];
    float v0, v1; /* the same start/end feed on every axis */
} mv_case;

static const mv_case k_mv_cases[] = {
    {1, {42.0f}, 0.0f, 0.0f},
    {3, {100.0f, -40.0f, 5.0f}, 0.0f, 0.0f},
    {3, {0.5f, 0.2f, -0.1f}, 0.0f, 0.0f},
    {6, {20.0f, -20.0f, 3.0f, 90.0f, -45.0f, 0.0f}, 0.0f, 0.0f},
    {3, {0.001f, 0.001f, 0.001f}, 0.0f, 50.0f},
};
#define N_MV_CASES ((uint32_t)(sizeof k_mv_cases / sizeof k_mv_cases[0]))

/* Per-axis limits of the moves (v, a, j, snap): X Y Z A B C. */
static const lsm_axis_limits k_axis_lim[LSM_MAX_AXES] = {
    {200.0f, 2000.0f, 40000.0f, 2.0e6f}, {200.0f, 2000.0f, 40000.0f, 2.0e6f}, {50.0f, 800.0f, 10000.0f, 5.0e5f},
    {360.0f, 3000.0f, 60000.0f, 3.0e6f}, {360.0f, 3000.0f, 60000.0f, 3.0e6f}, {720.0f, 5000.0f, 1.0e5f, 5.0e6f},
};

uint32_t lsm_selftest_hash_u32(uint32_t h, uint32_t word)
{
    for (unsigned i = 0; i < 4u; i++) {
        h ^= (word >> (8u * i)) & 0xFFu;
        h *= 0x01000193u;
    }
    return h;
}

uint32_t lsm_selftest_bits(lsm_real x)
{
    uint32_t words[(sizeof(lsm_real) + 3u) / 4u];
    uint32_t b = 0;
    memcpy(words, &x, sizeof x);
    for (unsigned i = 0; i < sizeof words / sizeof words[0]; i++)
        b ^= words[i];
    return b;
}

static uint32_t hash_real(uint32_t h, lsm_real x)
{
    return lsm_selftest_hash_u32(h, lsm_selftest_bits(x));
}

void lsm_selftest_init(lsm_selftest *st)
{
    memset(st, 0, sizeof *st);
    st->n_parts = N_PARTS;
    for (unsigned p = 0; p < N_PARTS; p++) {
        st->result[p].name = k_part_names[p];
        st->result[p].plan_hash = LSM_SELFTEST_HASH_INIT;
        st->result[p].cycle_hash = LSM_SELFTEST_HASH_INIT;
    }
}

static uint32_t part_items(uint32_t part)
{
    return part == PART_SCURVE ? N_SC_CASES : N_MV_CASES;
}

/* Plans item (part, item) into slot sl; returns the status; sets sl->n_cycles. */
static lsm_status plan_into(lsm_selftest_slot *sl, uint32_t part, uint32_t item, uint32_t *hash)
{
    lsm_status rc;
    sl->n_cycles = 0;
    if (part == PART_SCURVE) {
        const sc_case *c = &k_sc_cases[item];
        const lsm_scurve_limits lim = {c->a, c->j, c->snap};
        rc = lsm_scurve_plan(&sl->sc, &lim, CYCLE_S, c->v0, c->v1, LSM_SCURVE_RULE_STRICT, NULL);
        if (rc == LSM_OK) {
            sl->n_cycles = lsm_scurve_total_cycles(&sl->sc.iv) + 1u; /* t = 0 .. tp inclusive */
            *hash = hash_real(*hash, sl->sc.jp_mm_s3);
        }
    } else {
        const mv_case *c = &k_mv_cases[item];
        lsm_move_request req;
        memset(&req, 0, sizeof req);
        req.n_axes = c->n_axes;
        req.cycle_s = CYCLE_S;
        req.rule = LSM_SCURVE_RULE_STRICT;
        for (unsigned a = 0; a < c->n_axes; a++) {
            req.distance_mm[a] = c->d[a];
            req.v0_mm_s[a] = c->v0;
            req.v1_mm_s[a] = c->v1;
            req.lim[a] = k_axis_lim[a];
        }
        rc = lsm_move_plan(&sl->mv, &req);
        if (rc == LSM_OK)
            rc = lsm_stepgen_init(&sl->gen, &sl->mv, NULL);
        if (rc == LSM_OK) {
            sl->n_cycles = lsm_move_total_cycles(&sl->mv); /* stepgen emits cycles 1 .. total */
            for (unsigned a = 0; a < sl->mv.n_axes; a++) {
                *hash = hash_real(*hash, sl->mv.axis[a].jp_acc_mm_s3);
                *hash = hash_real(*hash, sl->mv.axis[a].jp_dec_mm_s3);
            }
        }
    }
    *hash = lsm_selftest_hash_u32(*hash, (uint32_t)(int32_t)rc);
    *hash = lsm_selftest_hash_u32(*hash, sl->n_cycles);
    return rc;
}

lsm_selftest_plan_result lsm_selftest_plan(lsm_selftest *st)
{
    while (st->plan_part < N_PARTS && st->plan_item >= part_items(st->plan_part)) {
        st->plan_part++;
        st->plan_item = 0;
    }
    if (st->plan_part >= N_PARTS) {
        st->all_planned = 1;
        return LSM_SELFTEST_ALL_PLANNED;
    }
    lsm_selftest_slot *sl = &st->slot[st->plan_idx % 2u];
    if (sl->full)
        return LSM_SELFTEST_SLOTS_BUSY;
    lsm_selftest_part *r = &st->result[st->plan_part];
    const lsm_status rc = plan_into(sl, st->plan_part, st->plan_item, &r->plan_hash);
    r->n_plans++;
    if (rc == LSM_OK && sl->n_cycles > 0u) {
        sl->part = (uint8_t)st->plan_part;
        sl->item = (uint16_t)st->plan_item;
        atomic_signal_fence(memory_order_release); /* the slot is complete before the tick can see it */
        sl->full = 1;
        st->plan_idx++;
    }
    st->plan_item++;
    return LSM_SELFTEST_PLANNED;
}

static void record(lsm_selftest *st, const lsm_selftest_slot *sl, unsigned axis, const lsm_real *v, unsigned n)
{
    if (st->n_samples >= LSM_SELFTEST_MAX_SAMPLES) {
        st->samples_lost++;
        return;
    }
    lsm_selftest_sample *s = &st->sample[st->n_samples++];
    s->part = sl->part;
    s->axis = (uint8_t)axis;
    s->item = sl->item;
    s->cycle = st->cycle;
    for (unsigned i = 0; i < 4u; i++)
        s->v[i] = i < n ? v[i] : 0;
}

lsm_selftest_tick_result lsm_selftest_tick(lsm_selftest *st)
{
    if (st->finished)
        return LSM_SELFTEST_DONE;
    lsm_selftest_slot *sl = &st->slot[st->eval_idx % 2u];
    const bool planned_all = st->all_planned != 0u; /* read before `full`: the planner sets them in the
                                                        opposite order, so a last slot is never missed */
    atomic_signal_fence(memory_order_acquire);
    if (!sl->full) {
        if (planned_all) {
            st->finished = 1;
            return LSM_SELFTEST_DONE;
        }
        st->idle_ticks++;
        return LSM_SELFTEST_IDLE;
    }
    atomic_signal_fence(memory_order_acquire);
    lsm_selftest_part *r = &st->result[sl->part];
    const bool sample = st->cycle % LSM_SELFTEST_SAMPLE_EVERY == 0u || st->cycle + 1u == sl->n_cycles;
    if (sl->part == PART_SCURVE) {
        lsm_kin k;
        lsm_scurve_eval(&sl->sc, (lsm_real)st->cycle * CYCLE_S, &k);
        const lsm_real v[4] = {k.j_mm_s3, k.a_mm_s2, k.v_mm_s, k.s_mm};
        for (unsigned i = 0; i < 4u; i++)
            r->cycle_hash = hash_real(r->cycle_hash, v[i]);
        if (sample)
            record(st, sl, 0, v, 4);
    } else {
        lsm_real pos[LSM_MAX_AXES];
        const bool running = lsm_stepgen_next(&sl->gen, pos);
        for (unsigned a = 0; a < sl->mv.n_axes; a++) {
            r->cycle_hash = hash_real(r->cycle_hash, pos[a]);
            if (sample)
                record(st, sl, a, &pos[a], 1);
        }
        /* the evaluator must report its end exactly at the last cycle */
        r->cycle_hash = lsm_selftest_hash_u32(r->cycle_hash, running == (st->cycle + 1u < sl->n_cycles));
    }
    r->n_cycles++;
    if (++st->cycle >= sl->n_cycles) {
        st->cycle = 0;
        atomic_signal_fence(memory_order_release);
        sl->full = 0;
        st->eval_idx++;
    }
    return LSM_SELFTEST_CYCLE;
}
