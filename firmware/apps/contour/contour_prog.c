/* contour_prog.c: the built-in contour program (see contour_prog.h). */
#include "contour_prog.h"

#include <string.h>

#include "lsm_math.h"

/* ---- the program ---- */

/* Items before the dense polyline. Start: (0, 0, 0). */
static const lsm_contour_item k_head[] = {
    {0, 0, {LSM_R(30.0), LSM_R(0.0), LSM_R(0.0)}, {0}, LSM_R(120.0), LSM_R(0.02)},
    /* G3 quarter circle, tangent to the line before it */
    {1, 1, {LSM_R(40.0), LSM_R(10.0), LSM_R(0.0)}, {LSM_R(30.0), LSM_R(10.0), LSM_R(0.0)}, LSM_R(120.0), LSM_R(0.02)},
    /* tangent line, then a corner of 146 degrees (clothoid pair) */
    {0, 0, {LSM_R(40.0), LSM_R(30.0), LSM_R(0.0)}, {0}, LSM_R(120.0), LSM_R(0.05)},
    {0, 0, {LSM_R(25.0), LSM_R(40.0), LSM_R(0.0)}, {0}, LSM_R(120.0), LSM_R(0.05)},
    /* G2 half circle R 5, entered at a corner (line/arc clothoids) */
    {1, -1, {LSM_R(15.0), LSM_R(40.0), LSM_R(0.0)}, {LSM_R(20.0), LSM_R(40.0), LSM_R(0.0)}, LSM_R(100.0), LSM_R(0.02)},
};
#define N_HEAD ((uint32_t)(sizeof k_head / sizeof k_head[0]))

/* Dense polyline: x from 15 down to 0 in 0.25 mm steps, y = 40 + sin(2 pi x' / 7.5), 60 points. */
#define N_DENSE 60u
#define DENSE_DX LSM_R(0.25)
#define DENSE_W LSM_R(0.20943951) /* 2 pi 0.25 / 7.5 per point */

/* Items after it. */
static const lsm_contour_item k_tail[] = {
    /* 3-D line down to Z -2 (corner with the polyline's end) */
    {0, 0, {LSM_R(0.0), LSM_R(20.0), LSM_R(-2.0)}, {0}, LSM_R(100.0), LSM_R(0.05)},
    /* G2 helical half turn R 5, Z -2 -> -3 */
    {1, -1, {LSM_R(0.0), LSM_R(10.0), LSM_R(-3.0)}, {LSM_R(0.0), LSM_R(15.0), LSM_R(0.0)}, LSM_R(100.0), LSM_R(0.05)},
    /* back to the origin: exact stop (end of program) */
    {0, 0, {LSM_R(0.0), LSM_R(0.0), LSM_R(0.0)}, {0}, LSM_R(80.0), LSM_R(0.0)},
};
#define N_TAIL ((uint32_t)(sizeof k_tail / sizeof k_tail[0]))

uint32_t lsm_contour_n_items(void)
{
    return N_HEAD + N_DENSE + N_TAIL;
}

void lsm_contour_item_get(uint32_t k, lsm_contour_item *it)
{
    if (k < N_HEAD) {
        *it = k_head[k];
        return;
    }
    k -= N_HEAD;
    if (k < N_DENSE) {
        memset(it, 0, sizeof *it);
        const lsm_real i = (lsm_real)(k + 1u);
        it->end[0] = LSM_R(15.0) - DENSE_DX * i;
        it->end[1] = LSM_R(40.0) + lsm_math_sinf(DENSE_W * i);
        it->feed_mm_s = LSM_R(100.0);
        it->tol_mm = LSM_R(0.02);
        return;
    }
    k -= N_DENSE;
    *it = k_tail[k < N_TAIL ? k : N_TAIL - 1u];
}

/* ---- running it ---- */

static uint32_t hash_u32(uint32_t h, uint32_t w)
{
    for (unsigned i = 0; i < 4u; i++) {
        h ^= (w >> (8u * i)) & 0xFFu;
        h *= 0x01000193u;
    }
    return h;
}

static uint32_t bits_of(lsm_real x)
{
    uint32_t w[(sizeof(lsm_real) + 3u) / 4u];
    uint32_t b = 0;
    memcpy(w, &x, sizeof x);
    for (unsigned i = 0; i < sizeof w / sizeof w[0]; i++)
        b ^= w[i];
    return b;
}

void lsm_contour_config(lsm_planner_config *cfg, uint8_t axis_mask)
{
    lsm_planner_default_config(cfg);
    cfg->cycle_s = (lsm_real)LSM_CONTOUR_CYCLE_US * LSM_R(1e-6);
    cfg->axis_mask = axis_mask;
    for (int i = 3; i < LSM_MAX_AXES; i++) { /* A B C (rad) */
        cfg->axis[i].v_max = LSM_R(6.0);
        cfg->axis[i].a_max = LSM_R(60.0);
        cfg->axis[i].j_max = LSM_R(1200.0);
        cfg->axis[i].snap_max = LSM_R(2.4e5);
    }
}

lsm_status lsm_contour_init(lsm_contour *c)
{
    memset(c, 0, sizeof *c);
    c->hash = LSM_CONTOUR_HASH_INIT;
    c->err = LSM_OK;
    lsm_planner_config cfg;
    lsm_contour_config(&cfg, 0x07u);
    const lsm_real start[LSM_MAX_AXES] = {0};
    lsm_status st = lsm_planner_init(&c->pl, &cfg, c->blk, LSM_CONTOUR_BLOCKS, start);
    if (st == LSM_OK)
        st = lsm_interp_init(&c->ip, &c->pl);
    if (st != LSM_OK) {
        c->err = st;
        c->result = LSM_CONTOUR_ERROR;
    }
    return st;
}

static lsm_contour_result fail(lsm_contour *c, lsm_status st)
{
    c->err = st;
    c->err_item = c->next_item;
    c->result = LSM_CONTOUR_ERROR;
    return LSM_CONTOUR_ERROR;
}

static void add_sample(lsm_contour *c)
{
    if (c->n_samples >= LSM_CONTOUR_MAX_SAMPLES)
        return;
    lsm_contour_sample *s = &c->sample[c->n_samples++];
    s->cycle = c->cycles;
    for (int i = 0; i < 3; i++)
        s->p[i] = c->pos[i];
}

lsm_contour_result lsm_contour_cycle(lsm_contour *c)
{
    if (lsm_contour_background(c) != LSM_CONTOUR_RUNNING)
        return (lsm_contour_result)c->result;
    return lsm_contour_step(c);
}

lsm_contour_result lsm_contour_background(lsm_contour *c)
{
    if (c->result != LSM_CONTOUR_RUNNING)
        return (lsm_contour_result)c->result;
    /* 1. feed: one item per cycle */
    if (c->next_item < lsm_contour_n_items()) {
        if (lsm_planner_free(&c->pl) >= 3u) {
            lsm_contour_item it;
            lsm_contour_item_get(c->next_item, &it);
            lsm_planner_move mv;
            memset(&mv, 0, sizeof mv);
            mv.feed_mm_s = it.feed_mm_s;
            mv.tol_mm = it.tol_mm;
            mv.seq = c->next_item + 1u;
            lsm_status st;
            if (it.arc) {
                st = lsm_planner_append_arc(&c->pl, it.end, it.centre, LSM_GEOM_PLANE_XY, it.dir, 0u, &mv);
            } else {
                lsm_real end[LSM_MAX_AXES] = {0};
                for (int i = 0; i < 3; i++)
                    end[i] = it.end[i];
                st = lsm_planner_append_line(&c->pl, end, &mv);
            }
            if (st == LSM_OK) {
                c->next_item++;
                c->appends++;
            } else if (st == LSM_E_FULL) {
                c->full_retries++; /* points held for fitting need room: run and retry */
            } else {
                return fail(c, st);
            }
        }
    } else if (!c->finished) {
        const lsm_status st = lsm_planner_finish(&c->pl);
        if (st == LSM_OK)
            c->finished = 1;
        else if (st != LSM_E_FULL)
            return fail(c, st);
    }
    /* 2. background planning (lsm_interp_prepare) */
    (void)lsm_interp_prepare(&c->ip);
    return LSM_CONTOUR_RUNNING;
}

lsm_contour_result lsm_contour_step(lsm_contour *c)
{
    if (c->result != LSM_CONTOUR_RUNNING)
        return (lsm_contour_result)c->result;
    /* 3. one interpolator cycle */
    const lsm_interp_state s = lsm_interp_step(&c->ip, c->pos);
    for (int i = 0; i < LSM_MAX_AXES; i++)
        c->hash = hash_u32(c->hash, bits_of(c->pos[i]));
    const lsm_pblock *b = lsm_planner_block(&c->pl, c->ip.blk);
    const unsigned kind = b != NULL ? (unsigned)b->g.kind : 0u;
    c->kind_cycles[kind < 4u ? kind : 0u]++;
    const lsm_real f = lsm_interp_feed(&c->ip);
    if (f > c->feed_max_mm_s)
        c->feed_max_mm_s = f;
    const bool done = s == LSM_INTERP_DONE && c->finished;
    if (c->cycles % LSM_CONTOUR_SAMPLE_EVERY == 0u || done)
        add_sample(c);
    c->cycles++;
    if (done) {
        c->result = LSM_CONTOUR_DONE;
        return LSM_CONTOUR_DONE;
    }
    if (c->cycles >= LSM_CONTOUR_MAX_CYCLES)
        return fail(c, LSM_E_INTERNAL);
    return LSM_CONTOUR_RUNNING;
}

bool lsm_contour_end_exact(const lsm_contour *c)
{
    lsm_contour_item last;
    lsm_contour_item_get(lsm_contour_n_items() - 1u, &last);
    for (int i = 0; i < LSM_MAX_AXES; i++)
        if (c->pos[i] != (i < 3 ? last.end[i] : LSM_R(0.0)))
            return false;
    return true;
}

/* ---- report (own formatting: no stdio on the MCU) ---- */

typedef struct line_buf {
    char s[160];
    unsigned n;
} line_buf;

static void lb_str(line_buf *l, const char *s)
{
    while (*s != '\0' && l->n + 1u < sizeof l->s)
        l->s[l->n++] = *s++;
    l->s[l->n] = '\0';
}

static void lb_u32(line_buf *l, uint32_t v)
{
    char t[11];
    unsigned k = 0;
    do {
        t[k++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    char r[11];
    for (unsigned i = 0; i < k; i++)
        r[i] = t[k - 1u - i];
    r[k] = '\0';
    lb_str(l, r);
}

static void lb_i32(line_buf *l, int32_t v)
{
    if (v < 0) {
        lb_str(l, "-");
        lb_u32(l, 0u - (uint32_t)v);
    } else {
        lb_u32(l, (uint32_t)v);
    }
}

static void lb_hex(line_buf *l, uint32_t v)
{
    char t[11] = "0x";
    for (unsigned i = 0; i < 8u; i++)
        t[2u + i] = "0123456789abcdef"[(v >> (28u - 4u * i)) & 0xFu];
    t[10] = '\0';
    lb_str(l, t);
}

static void lb_kv(line_buf *l, const char *key, uint32_t v)
{
    lb_str(l, " ");
    lb_str(l, key);
    lb_str(l, "=");
    lb_u32(l, v);
}

void lsm_contour_report(const lsm_contour *c, void (*put)(const char *line, void *ctx), void *ctx)
{
    line_buf l = {{0}, 0};
    lb_str(&l, "contour result=");
    lb_u32(&l, c->result);
    lb_str(&l, " err=");
    lb_i32(&l, (int32_t)c->err);
    lb_kv(&l, "err_item", c->err_item);
    lb_kv(&l, "cycles", c->cycles);
    lb_kv(&l, "appends", c->appends);
    lb_kv(&l, "full_retries", c->full_retries);
    lb_str(&l, " checksum=");
    lb_hex(&l, c->hash);
    lb_str(&l, " end=");
    for (int i = 0; i < 3; i++) {
        if (i > 0)
            lb_str(&l, ",");
        lb_hex(&l, bits_of(c->pos[i]));
    }
    lb_kv(&l, "end_exact", lsm_contour_end_exact(c) ? 1u : 0u);
    put(l.s, ctx);

    l.n = 0;
    lb_str(&l, "contour_stats");
    lb_kv(&l, "corners", c->pl.stats.corners);
    lb_kv(&l, "corner_stops", c->pl.stats.corner_stops);
    lb_kv(&l, "pieces", c->pl.stats.pieces);
    lb_kv(&l, "fallbacks", c->pl.stats.plan_fallbacks);
    lb_kv(&l, "plan_errors", c->ip.plan_errors);
    lb_kv(&l, "replans", c->ip.replans);
    lb_kv(&l, "line_cycles", c->kind_cycles[LSM_GEOM_LINE]);
    lb_kv(&l, "arc_cycles", c->kind_cycles[LSM_GEOM_ARC]);
    lb_kv(&l, "clothoid_cycles", c->kind_cycles[LSM_GEOM_CLOTHOID]);
    lb_kv(&l, "feed_max_mm_s", (uint32_t)(c->feed_max_mm_s + LSM_R(0.5)));
    put(l.s, ctx);

    for (uint32_t k = 0; k < c->n_samples; k++) {
        const lsm_contour_sample *s = &c->sample[k];
        l.n = 0;
        lb_str(&l, "contour_sample ");
        lb_u32(&l, s->cycle);
        for (int i = 0; i < 3; i++) {
            lb_str(&l, " ");
            lb_hex(&l, bits_of(s->p[i]));
        }
        put(l.s, ctx);
    }
}
