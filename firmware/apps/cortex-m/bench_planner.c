/*
 * bench_planner.c: instruction counts of the look-ahead planner and the interpolator (part of lissom-bench.elf,
 * method in bench_main.c: SysTick x 40 under -icount shift=0). Every figure uses a 128-block look-ahead.
 *
 * Per control cycle (lsm_interp_step, with lsm_interp_prepare called between cycles and not counted), for 1, 3
 * and 6 configured axes, classified by the kind of block the path cursor is on after the cycle (line, arc,
 * clothoid):
 *   interp_<kind>_<n>ax           every cycle: mean, and the largest single cycle
 *   interp_<kind>_<n>ax_noplan    the cycles that did not plan a piece themselves (lsm_planner_plan_piece inside
 *                                 the cycle: none was prepared): mean and largest, with where the largest was
 * Programs: 1 axis: X lines (collinear joins and reversals); 3 axes: the contour program (contour_prog.h: lines,
 * arcs, a helix, a dense polyline fitted with arcs, clothoid corners); 6 axes: the same contour with A B C
 * configured (they do not move: arcs and corner blends are X Y Z only) for arcs and clothoids, and lines that move
 * all six axes for lines. Each cycle is read on its own (+-40 instructions); the means average over every cycle.
 *
 * Per appended block (lsm_planner_append_line / _arc, which includes corner smoothing, arc fitting of dense
 * polylines and the backward pass of the look-ahead), over a "realistic" program: four rounds of a dense
 * polyline (0.1-0.5 mm segments on an R 20 curve, tol 0.01), a zigzag of 1.5 mm segments (corners of 0.8 rad,
 * tol 0.02) and half circles R 2 joined by lines at 0.3 rad corners; the buffer is kept full (append whenever
 * three slots are free) while the interpolator runs. Breakdown by wrapping the calls from the planner into other
 * modules (linker --wrap, see CMakeLists.txt): lsm_corner_smooth, lsm_arcfit_fit; the rest is validation, block
 * set-up (bounds, coefficients) and the backward pass. Built with BENCH_RAMP_WRAP (lissom-bench-ramp.elf) it also
 * times the ramp sizing and phase evaluation inside the appends. Also: one full backward pass over the full
 * buffer (full_pass = 1, lsm_planner_update), lsm_planner_plan_piece per piece (the forward step, which
 * lsm_interp_prepare calls between cycles), and lsm_clothoid_step alone.
 * Short timed windows start after dither() so that they sample every phase of the 40-instruction SysTick count.
 */
#include <string.h>

#include "arcfit.h"
#include "bench_planner.h"
#include "cm_board.h"
#include "cm_out.h"
#include "contour_prog.h"
#include "corner.h"
#include "interp.h"
#include "lsm_math.h"
#include "planner.h"

#define NBLK 128u
#define MAX_CYCLES 200000u

static lsm_pblock g_store[NBLK];
static lsm_planner g_pl;
static lsm_interp g_ip;

static inline uint32_t now(void)
{
    return CM_SYST_CVR;
}

static inline uint32_t since(uint32_t t0)
{
    return (t0 - CM_SYST_CVR) & CM_SYST_MAX_RELOAD;
}

/* ---- wrapped calls between modules (the wrappers' own reads add about 10 instructions per call) ---- */

typedef struct wstat {
    uint32_t calls;
    uint32_t counts;
    uint32_t max_counts;
} wstat;

static wstat g_w_corner, g_w_fit, g_w_piece;
static wstat g_w_size, g_w_phase;
static volatile bool g_w_ramp_on;
/* inside lsm_planner_plan_piece: its ramp verifications (planner stats), and in lissom-bench-ramp.elf its ramp
 * sizing and phase evaluation (g_w_psize, g_w_pphase) */
static volatile bool g_in_piece;
static uint32_t g_piece_checks;
#ifdef BENCH_RAMP_WRAP
static wstat g_w_psize, g_w_pphase;
#endif

/* The wrappers. Without link-time optimisation they are the linker's __wrap_X (-Wl,--wrap=X). With it
 * (BENCH_LTO_TRAMPOLINES, LSM_ARM_LTO), the calls inside the link-time unit are redirected to __wrap_X after the link
 * (scripts/arm_lto_wrap.py), and there a caller may keep values in the call-clobbered registers that X does not
 * touch (GCC's -fipa-ra knows X's clobbers): __wrap_X is then a trampoline that keeps every register but the
 * result's (r0; none for void) across the C wrapper bench_w_X, re-pushing the arguments passed on the stack. */
#ifdef BENCH_LTO_TRAMPOLINES
#define WRAP(x) bench_w_##x
#define TRAMPOLINE(x, save, pre, post)                                                           \
    __attribute__((naked)) void __wrap_##x(void);                                                \
    __attribute__((naked)) void __wrap_##x(void)                                                 \
    {                                                                                            \
        __asm volatile("push {" save ", r12, lr}\n\t"                                            \
                       "vpush {s0-s15}\n\t" pre "bl bench_w_" #x "\n\t" post "vpop {s0-s15}\n\t" \
                       "pop {" save ", r12, pc}\n\t");                                           \
    }
#define R0_OUT "r1-r4"   /* result in r0: keep r1-r3 (r4: 8-byte alignment, and scratch) */
#define VOID_OUT "r0-r5" /* no result: keep r0-r3 too (r4, r5: alignment) */
/* two words of arguments on the stack: at sp + 88 / + 92 after the pushes of R0_OUT (24 B) and s0-s15 (64 B) */
#define PUSH_TWO_STACK_ARGS "ldr r4, [sp, #88]\n\tldr r12, [sp, #92]\n\tpush {r4, r12}\n\t"
#define POP_TWO_STACK_ARGS "add sp, #8\n\t"
#else
#define WRAP(x) __wrap_##x
#endif

static void wadd(wstat *w, uint32_t c)
{
    w->calls++;
    w->counts += c;
    if (c > w->max_counts)
        w->max_counts = c;
}

lsm_status __real_lsm_corner_smooth(const lsm_geom *b1, const lsm_geom *b2, const lsm_corner_params *p,
                                    lsm_corner_result *out);
lsm_status WRAP(lsm_corner_smooth)(const lsm_geom *b1, const lsm_geom *b2, const lsm_corner_params *p,
                                   lsm_corner_result *out);
lsm_status WRAP(lsm_corner_smooth)(const lsm_geom *b1, const lsm_geom *b2, const lsm_corner_params *p,
                                   lsm_corner_result *out)
{
    const uint32_t t0 = now();
    const lsm_status r = __real_lsm_corner_smooth(b1, b2, p, out);
    wadd(&g_w_corner, since(t0));
    return r;
}

bool __real_lsm_arcfit_fit(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real tol_mm,
                           const lsm_arcfit_plane *plane_n, lsm_geom *g, lsm_arcfit_result *res);
bool WRAP(lsm_arcfit_fit)(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real tol_mm,
                          const lsm_arcfit_plane *plane_n, lsm_geom *g, lsm_arcfit_result *res);
bool WRAP(lsm_arcfit_fit)(const lsm_real p0[3], const lsm_arcfit_pt *q, int n, lsm_real tol_mm,
                          const lsm_arcfit_plane *plane_n, lsm_geom *g, lsm_arcfit_result *res)
{
    const uint32_t t0 = now();
    const bool r = __real_lsm_arcfit_fit(p0, q, n, tol_mm, plane_n, g, res);
    wadd(&g_w_fit, since(t0));
    return r;
}

lsm_status __real_lsm_planner_plan_piece(lsm_planner *pl, uint32_t blk, lsm_real off_mm, lsm_real v0_mm_s,
                                         lsm_piece_mode mode, lsm_piece *out);
lsm_status WRAP(lsm_planner_plan_piece)(lsm_planner *pl, uint32_t blk, lsm_real off_mm, lsm_real v0_mm_s,
                                        lsm_piece_mode mode, lsm_piece *out);
lsm_status WRAP(lsm_planner_plan_piece)(lsm_planner *pl, uint32_t blk, lsm_real off_mm, lsm_real v0_mm_s,
                                        lsm_piece_mode mode, lsm_piece *out)
{
    const uint32_t ch0 = pl->stats.checks;
    g_in_piece = true;
    const uint32_t t0 = now();
    const lsm_status r = __real_lsm_planner_plan_piece(pl, blk, off_mm, v0_mm_s, mode, out);
    wadd(&g_w_piece, since(t0));
    g_in_piece = false;
    g_piece_checks += pl->stats.checks - ch0;
    return r;
}

#ifdef BENCH_LTO_TRAMPOLINES
TRAMPOLINE(lsm_corner_smooth, R0_OUT, "", "")
TRAMPOLINE(lsm_arcfit_fit, R0_OUT, PUSH_TWO_STACK_ARGS, POP_TWO_STACK_ARGS) /* g, res on the stack */
TRAMPOLINE(lsm_planner_plan_piece, R0_OUT, "", "")
#endif

#ifdef BENCH_RAMP_WRAP
/* Only in lissom-bench-ramp.elf (these wrappers would add instructions to every figure of lissom-bench.elf):
 * ramp work of the planner, sizing (lsm_scurve_strict_intervals) and phase evaluation (lsm_phase_end /
 * lsm_phase_advance, used by the ramp verification), timed while g_w_ramp_on is set (inside the appends). */
bool __real_lsm_scurve_strict_intervals(const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real dv_mm_s,
                                        lsm_scurve_intervals *out);
bool WRAP(lsm_scurve_strict_intervals)(const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real dv_mm_s,
                                       lsm_scurve_intervals *out);
bool WRAP(lsm_scurve_strict_intervals)(const lsm_scurve_limits *lim, lsm_real cycle_s, lsm_real dv_mm_s,
                                       lsm_scurve_intervals *out)
{
    if (!g_w_ramp_on && !g_in_piece)
        return __real_lsm_scurve_strict_intervals(lim, cycle_s, dv_mm_s, out);
    const uint32_t t0 = now();
    const bool r = __real_lsm_scurve_strict_intervals(lim, cycle_s, dv_mm_s, out);
    wadd(g_in_piece ? &g_w_psize : &g_w_size, since(t0));
    return r;
}

void __real_lsm_phase_end(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_kin *out);
void WRAP(lsm_phase_end)(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_kin *out);
void WRAP(lsm_phase_end)(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_kin *out)
{
    if (!g_w_ramp_on && !g_in_piece) {
        __real_lsm_phase_end(ph, cycle_s, start, out);
        return;
    }
    const uint32_t t0 = now();
    __real_lsm_phase_end(ph, cycle_s, start, out);
    wadd(g_in_piece ? &g_w_pphase : &g_w_phase, since(t0));
}

void __real_lsm_phase_advance(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_real tau_s,
                              lsm_kin *out);
void WRAP(lsm_phase_advance)(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_real tau_s, lsm_kin *out);
void WRAP(lsm_phase_advance)(const lsm_phase *ph, lsm_real cycle_s, const lsm_kin *start, lsm_real tau_s, lsm_kin *out)
{
    if (!g_w_ramp_on && !g_in_piece) {
        __real_lsm_phase_advance(ph, cycle_s, start, tau_s, out);
        return;
    }
    const uint32_t t0 = now();
    __real_lsm_phase_advance(ph, cycle_s, start, tau_s, out);
    wadd(g_in_piece ? &g_w_pphase : &g_w_phase, since(t0));
}
#ifdef BENCH_LTO_TRAMPOLINES
TRAMPOLINE(lsm_scurve_strict_intervals, R0_OUT, "", "")
TRAMPOLINE(lsm_phase_end, VOID_OUT, "", "")
TRAMPOLINE(lsm_phase_advance, VOID_OUT, "", "")
#endif
#endif

/* ---- programs ---- */

typedef struct bitem {
    uint8_t arc;
    int8_t dir;
    lsm_real end[LSM_MAX_AXES];
    lsm_real centre[3];
    lsm_real feed, tol;
} bitem;

typedef struct gen {
    uint32_t k;    /* next item */
    lsm_real p[3]; /* end of the previous item */
    lsm_real h;    /* heading (dense program) */
} gen;

typedef bool (*gen_fn)(gen *g, bitem *it);

static bool gen_contour(gen *g, bitem *it)
{
    if (g->k >= lsm_contour_n_items())
        return false;
    lsm_contour_item ci;
    lsm_contour_item_get(g->k++, &ci);
    memset(it, 0, sizeof *it);
    it->arc = ci.arc;
    it->dir = ci.dir;
    for (int i = 0; i < 3; i++) {
        it->end[i] = ci.end[i];
        it->centre[i] = ci.centre[i];
    }
    it->feed = ci.feed_mm_s;
    it->tol = ci.tol_mm;
    return true;
}

/* X only: collinear runs and reversals, 3 times. */
static bool gen_line1(gen *g, bitem *it)
{
    static const float k_x[8] = {10.0f, 25.0f, 40.0f, 20.0f, 0.5f, 30.0f, 60.0f, 0.0f};
    if (g->k >= 24u)
        return false;
    memset(it, 0, sizeof *it);
    it->end[0] = k_x[g->k++ % 8u];
    it->feed = LSM_R(150.0);
    it->tol = LSM_R(0.02);
    return true;
}

/* All six axes move (mm, rad): corners with rotary axes stop. */
static bool gen_line6(gen *g, bitem *it)
{
    static const float k_p[6][LSM_MAX_AXES] = {
        {20.0f, 5.0f, -2.0f, 0.5f, -0.2f, 1.0f},   {35.0f, 20.0f, -4.0f, 0.8f, 0.1f, 2.5f},
        {10.0f, 30.0f, -1.0f, 0.2f, 0.3f, 3.0f},   {-5.0f, 10.0f, 0.0f, -0.4f, 0.0f, 1.5f},
        {15.0f, -10.0f, -3.0f, 0.0f, -0.3f, 0.5f}, {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    };
    if (g->k >= 12u)
        return false;
    memset(it, 0, sizeof *it);
    for (int i = 0; i < LSM_MAX_AXES; i++)
        it->end[i] = k_p[g->k % 6u][i];
    g->k++;
    it->feed = LSM_R(100.0);
    it->tol = LSM_R(0.02);
    return true;
}

/* The append benchmark's program (see the top of this file); 4 rounds of 136 items. */
#define DENSE_N 100u
#define ZIG_N 20u
#define ARC_N 16u
#define ROUND_N (DENSE_N + ZIG_N + ARC_N)
static bool gen_dense(gen *g, bitem *it)
{
    if (g->k >= 4u * ROUND_N)
        return false;
    const uint32_t j = g->k % ROUND_N;
    g->k++;
    memset(it, 0, sizeof *it);
    it->feed = LSM_R(100.0);
    if (j < DENSE_N) { /* polyline on an R 20 curve, segments 0.1 .. 0.5 mm */
        const lsm_real s = LSM_R(0.1) + LSM_R(0.1) * (lsm_real)(j % 5u);
        g->h += s / LSM_R(20.0);
        g->p[0] += s * lsm_cos(g->h);
        g->p[1] += s * lsm_sin(g->h);
        it->tol = LSM_R(0.01);
    } else if (j < DENSE_N + ZIG_N) { /* zigzag: corners of 0.8 rad */
        const lsm_real h = g->h + ((j & 1u) ? LSM_R(0.4) : LSM_R(-0.4));
        g->p[0] += LSM_R(1.5) * lsm_cos(h);
        g->p[1] += LSM_R(1.5) * lsm_sin(h);
        it->tol = LSM_R(0.02);
    } else if ((j - DENSE_N - ZIG_N) % 2u == 0u) { /* half circle R 2, alternately left (G3) and right (G2) */
        const int left = ((j - DENSE_N - ZIG_N) / 2u) % 2u == 0u;
        const lsm_real nx = -lsm_sin(g->h) * (left ? LSM_R(1.0) : LSM_R(-1.0));
        const lsm_real ny = lsm_cos(g->h) * (left ? LSM_R(1.0) : LSM_R(-1.0));
        it->arc = 1;
        it->dir = (int8_t)(left ? 1 : -1);
        it->centre[0] = g->p[0] + LSM_R(2.0) * nx;
        it->centre[1] = g->p[1] + LSM_R(2.0) * ny;
        it->centre[2] = g->p[2];
        g->p[0] += LSM_R(4.0) * nx;
        g->p[1] += LSM_R(4.0) * ny;
        g->h += LSM_R(3.14159265);
        it->tol = LSM_R(0.02);
    } else { /* a 3 mm line, 0.3 rad off the arc's end tangent */
        g->h += LSM_R(0.3);
        g->p[0] += LSM_R(3.0) * lsm_cos(g->h);
        g->p[1] += LSM_R(3.0) * lsm_sin(g->h);
        it->tol = LSM_R(0.02);
    }
    for (int i = 0; i < 3; i++)
        it->end[i] = g->p[i];
    return true;
}

static lsm_status append_item(const bitem *it)
{
    lsm_planner_move mv;
    memset(&mv, 0, sizeof mv);
    mv.feed_mm_s = it->feed;
    mv.tol_mm = it->tol;
    if (it->arc)
        return lsm_planner_append_arc(&g_pl, it->end, it->centre, LSM_GEOM_PLANE_XY, it->dir, 0u, &mv);
    return lsm_planner_append_line(&g_pl, it->end, &mv);
}

/* ---- timed calls ---- */

typedef lsm_interp_state (*step_fn)(lsm_interp *ip, lsm_real pos[LSM_MAX_AXES]);

__attribute__((noinline)) static lsm_interp_state empty_step(lsm_interp *ip, lsm_real pos[LSM_MAX_AXES])
{
    __asm__ volatile("" ::"r"(ip), "r"(pos) : "memory");
    return LSM_INTERP_RUN;
}

__attribute__((noinline)) static uint32_t timed_step(step_fn fn, lsm_real pos[LSM_MAX_AXES], lsm_interp_state *s)
{
    const uint32_t t0 = now();
    *s = fn(&g_ip, pos);
    return since(t0);
}

typedef lsm_status (*append_fn)(const bitem *it);

__attribute__((noinline)) static lsm_status empty_append(const bitem *it)
{
    __asm__ volatile("" ::"r"(it) : "memory");
    return LSM_OK;
}

__attribute__((noinline)) static uint32_t timed_append(append_fn fn, const bitem *it, lsm_status *st)
{
    const uint32_t t0 = now();
    *st = fn(it);
    return since(t0);
}

static uint32_t g_step_ovh_x100, g_append_ovh_x100; /* harness instructions per timed call, x100 */

/* A delay of 2 (i % 20) instructions before a short timed window, so that the window starts at every phase of
 * the 40-instruction SysTick count: without it a loop whose length is a multiple of 40 reads the same phase
 * every time and the mean of the per-call readings is biased (0 or 40 instead of the true 6). */
static void dither(uint32_t i)
{
    uint32_t n = i % 20u;
    if (n != 0u)
        __asm__ volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n)::"cc");
}

static void calibrate_overheads(void)
{
    lsm_real pos[LSM_MAX_AXES];
    lsm_interp_state s;
    lsm_status st;
    bitem it;
    memset(&it, 0, sizeof it);
    uint32_t c1 = 0, c2 = 0;
    const uint32_t n = 20000u;
    for (uint32_t i = 0; i < n; i++) {
        dither(i);
        c1 += timed_step(empty_step, pos, &s);
        dither(i * 7u);
        c2 += timed_append(empty_append, &it, &st);
    }
    g_step_ovh_x100 = (uint32_t)(((uint64_t)c1 * 40u * 100u + n / 2u) / n);
    g_append_ovh_x100 = (uint32_t)(((uint64_t)c2 * 40u * 100u + n / 2u) / n);
    cm_out_str("overhead timed_step ");
    cm_out_fixed((int32_t)g_step_ovh_x100, 2);
    cm_out_str(" timed_append ");
    cm_out_fixed((int32_t)g_append_ovh_x100, 2);
    cm_out_str(" (subtracted below)\n");
}

/* ---- statistics ---- */

typedef struct kstat {
    uint32_t n, n_noplan;
    uint64_t counts, counts_noplan;
    uint32_t max_counts, max_noplan;
    uint8_t max_noplan_entry; /* the largest cycle without planning entered a new block (1), started a new piece (2),
                                 both (3) */
} kstat;

static uint32_t mean_x100(uint64_t counts, uint32_t n, uint32_t ovh_x100)
{
    if (n == 0u)
        return 0u;
    const uint64_t x = (counts * 40u * 100u + n / 2u) / n;
    return x > ovh_x100 ? (uint32_t)(x - ovh_x100) : 0u;
}

static int32_t max_insns(uint32_t counts, uint32_t ovh_x100)
{
    return (int32_t)(counts * 40u) - (int32_t)(ovh_x100 / 100u);
}

static void out_line(const char *name, uint32_t x100, const char *unit, uint32_t calls, int32_t max, const char *extra)
{
    cm_out_str("bench ");
    cm_out_str(name);
    cm_out_char(' ');
    cm_out_fixed((int32_t)x100, 2);
    cm_out_char(' ');
    cm_out_str(unit);
    cm_out_str(" calls=");
    cm_out_u32(calls);
    if (max >= 0) {
        cm_out_str(" max=");
        cm_out_i32(max);
    }
    if (extra != NULL) {
        cm_out_char(' ');
        cm_out_str(extra);
    }
    cm_out_char('\n');
}

static void out_kind(const char *kind, unsigned n_axes, const kstat *k)
{
    char name[40];
    char *p = name;
    const char *parts[3] = {"interp_", kind, "_"};
    for (unsigned i = 0; i < 3u; i++)
        for (const char *s = parts[i]; *s != '\0'; s++)
            *p++ = *s;
    *p++ = (char)('0' + n_axes);
    *p++ = 'a';
    *p++ = 'x';
    *p = '\0';
    out_line(name, mean_x100(k->counts, k->n, g_step_ovh_x100), "cycle", k->n,
             max_insns(k->max_counts, g_step_ovh_x100), k->n > k->n_noplan ? "max_at=piece_planned" : "max_at=no_plan");
    const char *suffix = "_noplan";
    for (const char *s = suffix; *s != '\0'; s++)
        *p++ = *s;
    *p = '\0';
    out_line(name, mean_x100(k->counts_noplan, k->n_noplan, g_step_ovh_x100), "cycle", k->n_noplan,
             max_insns(k->max_noplan, g_step_ovh_x100),
             k->max_noplan_entry == 3u   ? "max_at=block_entry_and_piece"
             : k->max_noplan_entry == 2u ? "max_at=piece_switch"
             : k->max_noplan_entry == 1u ? "max_at=block_entry"
                                         : "max_at=inside_block");
}

typedef struct astat {
    uint32_t n;
    uint64_t counts, corner_counts, fit_counts, size_counts, phase_counts;
    uint32_t max_counts, max_corner, max_fit;
    uint32_t bp_nodes, checks;
    uint64_t cat_counts[3]; /* per kind of item: dense polyline point, zigzag line, arc or line after it */
    uint32_t cat_n[3], cat_max[3];
    uint32_t full_pass_counts; /* one full backward pass over a full buffer */
    uint32_t full_pass_blocks;
} astat;

/* Runs a program through the planner (NBLK blocks) and the interpolator; times every cycle into ks[kind] and,
 * if as != NULL, every accepted append. Returns false on an error (printed). */
static bool run(const char *name, gen_fn next, uint8_t axis_mask, kstat ks[4], astat *as)
{
    lsm_planner_config cfg;
    lsm_contour_config(&cfg, axis_mask);
    const lsm_real start[LSM_MAX_AXES] = {0};
    if (lsm_planner_init(&g_pl, &cfg, g_store, NBLK, start) != LSM_OK || lsm_interp_init(&g_ip, &g_pl) != LSM_OK) {
        cm_out_str("bench setup failed: ");
        cm_out_str(name);
        cm_out_char('\n');
        return false;
    }
    gen g;
    memset(&g, 0, sizeof g);
    bitem it;
    bool have = next(&g, &it), finished = false;
    lsm_real pos[LSM_MAX_AXES];
    for (uint32_t cyc = 0; cyc < MAX_CYCLES; cyc++) {
        while (have && lsm_planner_free(&g_pl) >= 3u) {
            const uint32_t bp0 = g_pl.stats.bp_nodes, ch0 = g_pl.stats.checks;
            const uint32_t cc0 = g_w_corner.counts, fc0 = g_w_fit.counts;
            const uint32_t sz0 = g_w_size.counts, ph0 = g_w_phase.counts;
            g_w_ramp_on = as != NULL;
            lsm_status st;
            dither(g.k * 7u);
            const uint32_t c = timed_append(append_item, &it, &st);
            g_w_ramp_on = false;
            if (st == LSM_E_FULL)
                break;
            if (st != LSM_OK) {
                cm_out_str("bench append failed: ");
                cm_out_str(name);
                cm_out_str(" status ");
                cm_out_i32((int32_t)st);
                cm_out_char('\n');
                return false;
            }
            if (as != NULL) {
                const uint32_t j = (g.k - 1u) % ROUND_N; /* the dense program's item kind */
                const unsigned cat = j < DENSE_N ? 0u : j < DENSE_N + ZIG_N ? 1u : 2u;
                as->cat_counts[cat] += c;
                as->cat_n[cat]++;
                if (c > as->cat_max[cat])
                    as->cat_max[cat] = c;
                as->n++;
                as->counts += c;
                as->corner_counts += g_w_corner.counts - cc0;
                as->fit_counts += g_w_fit.counts - fc0;
                as->size_counts += g_w_size.counts - sz0;
                as->phase_counts += g_w_phase.counts - ph0;
                as->bp_nodes += g_pl.stats.bp_nodes - bp0;
                as->checks += g_pl.stats.checks - ch0;
                if (c > as->max_counts) {
                    as->max_counts = c;
                    as->max_corner = g_w_corner.counts - cc0;
                    as->max_fit = g_w_fit.counts - fc0;
                }
            }
            have = next(&g, &it);
        }
        if (as != NULL && as->full_pass_counts == 0u && lsm_planner_free(&g_pl) < 3u) {
            /* one full backward pass over the full buffer (recomputes the same W values) */
            g_pl.full_pass = 1;
            const uint32_t t0 = now();
            lsm_planner_update(&g_pl);
            as->full_pass_counts = since(t0);
            as->full_pass_blocks = lsm_planner_count(&g_pl);
        }
        if (!have && !finished && lsm_planner_finish(&g_pl) == LSM_OK)
            finished = true;
        (void)lsm_interp_prepare(&g_ip); /* background planning (not part of the cycle's count) */
        const uint32_t pieces0 = g_w_piece.calls, blk0 = g_ip.blk, serial0 = g_ip.serial;
        lsm_interp_state s;
        dither(cyc);
        const uint32_t c = timed_step(lsm_interp_step, pos, &s);
        if (ks != NULL) {
            const lsm_pblock *b = lsm_planner_block(&g_pl, g_ip.blk);
            kstat *k = &ks[b != NULL && b->g.kind < 4u ? b->g.kind : 0u];
            k->n++;
            k->counts += c;
            if (c > k->max_counts)
                k->max_counts = c;
            if (g_w_piece.calls == pieces0) {
                k->n_noplan++;
                k->counts_noplan += c;
                if (c > k->max_noplan) {
                    k->max_noplan = c;
                    k->max_noplan_entry = (uint8_t)((g_ip.blk != blk0 ? 1u : 0u) | (g_ip.serial != serial0 ? 2u : 0u));
                }
            }
        }
        if (s == LSM_INTERP_DONE && finished) {
            if (g_pl.stats.plan_fallbacks != 0u || g_ip.plan_errors != 0u) {
                cm_out_str("bench note: ");
                cm_out_str(name);
                cm_out_str(" had fallback plans or planning errors\n");
            }
            return true;
        }
    }
    cm_out_str("bench run did not finish: ");
    cm_out_str(name);
    cm_out_char('\n');
    return false;
}

/* lsm_clothoid_step alone (what a clothoid cycle adds to a line cycle): 0.1 mm steps along a 5 mm clothoid
 * (curvature 0 -> 0.4 /mm), restarted at its end; anchored every 64 steps. */
static lsm_clothoid_stepper g_cst;
static lsm_clothoid g_cseg;

__attribute__((noinline)) static uint32_t timed_clothoid_step(void)
{
    const uint32_t t0 = now();
    (void)lsm_clothoid_step(&g_cst, LSM_R(0.1), NULL);
    return since(t0);
}

__attribute__((noinline)) static uint32_t timed_nothing(void)
{
    const uint32_t t0 = now();
    __asm__ volatile("" ::: "memory");
    return since(t0);
}

static void bench_clothoid_step(void)
{
    (void)lsm_clothoid_init(&g_cseg, LSM_R(0.0), LSM_R(0.0), LSM_R(0.3), LSM_R(0.0), LSM_R(0.08), LSM_R(5.0));
    uint32_t c = 0, c0 = 0, n = 0;
    for (uint32_t rep = 0; rep < 40u; rep++) {
        (void)lsm_clothoid_stepper_init(&g_cst, &g_cseg, LSM_R(0.0), 64u);
        for (uint32_t k = 0; k < 50u; k++, n++) {
            dither(n);
            c += timed_clothoid_step();
            dither(n * 7u);
            c0 += timed_nothing();
        }
    }
    out_line("clothoid_step", c > c0 ? mean_x100(c - c0, n, 0u) : 0u, "call", n, -1, NULL);
}

static bool bench_cycles(void)
{
    bool ok = true;
    kstat ks[4];

    memset(ks, 0, sizeof ks);
    ok = run("line_1ax", gen_line1, 0x01u, ks, NULL) && ok;
    out_kind("line", 1, &ks[LSM_GEOM_LINE]);

    memset(ks, 0, sizeof ks);
    ok = run("contour_3ax", gen_contour, 0x07u, ks, NULL) && ok;
    out_kind("line", 3, &ks[LSM_GEOM_LINE]);
    out_kind("arc", 3, &ks[LSM_GEOM_ARC]);
    out_kind("clothoid", 3, &ks[LSM_GEOM_CLOTHOID]);

    memset(ks, 0, sizeof ks);
    ok = run("line_6ax", gen_line6, 0x3Fu, ks, NULL) && ok;
    out_kind("line", 6, &ks[LSM_GEOM_LINE]);
    memset(ks, 0, sizeof ks);
    ok = run("contour_6ax", gen_contour, 0x3Fu, ks, NULL) && ok;
    out_kind("arc", 6, &ks[LSM_GEOM_ARC]);
    out_kind("clothoid", 6, &ks[LSM_GEOM_CLOTHOID]);

    return ok;
}

static bool bench_append(void)
{
    bool ok = true;
    kstat ks[4];
    /* appends over the dense program; per-call figures of the wrapped calls from this run only */
    memset(&g_w_corner, 0, sizeof g_w_corner);
    memset(&g_w_fit, 0, sizeof g_w_fit);
    memset(&g_w_piece, 0, sizeof g_w_piece);
    g_piece_checks = 0;
#ifdef BENCH_RAMP_WRAP
    memset(&g_w_psize, 0, sizeof g_w_psize);
    memset(&g_w_pphase, 0, sizeof g_w_pphase);
#endif
    astat as;
    memset(&as, 0, sizeof as);
    memset(ks, 0, sizeof ks);
    ok = run("append_dense", gen_dense, 0x07u, ks, &as) && ok;
    const uint32_t mean = mean_x100(as.counts, as.n, g_append_ovh_x100);
    const uint32_t corner = mean_x100(as.corner_counts, as.n, 0u);
    const uint32_t fit = mean_x100(as.fit_counts, as.n, 0u);
    char where[64];
    {
        /* breakdown of the worst append: corner smoothing, arc fitting (instructions) */
        char *p = where;
        const char *k1 = "max_at=corner:";
        while (*k1)
            *p++ = *k1++;
        uint32_t v = as.max_corner * 40u, d = 1000000000u;
        bool lead = false;
        for (; d > 0u; d /= 10u) {
            const uint32_t q = (v / d) % 10u;
            if (q || lead || d == 1u) {
                *p++ = (char)('0' + q);
                lead = true;
            }
        }
        const char *k2 = ",fit:";
        while (*k2)
            *p++ = *k2++;
        v = as.max_fit * 40u;
        lead = false;
        for (d = 1000000000u; d > 0u; d /= 10u) {
            const uint32_t q = (v / d) % 10u;
            if (q || lead || d == 1u) {
                *p++ = (char)('0' + q);
                lead = true;
            }
        }
        *p = '\0';
    }
    out_line("planner_append", mean, "block", as.n, max_insns(as.max_counts, g_append_ovh_x100), where);
    static const char *const k_cat[3] = {"planner_append_dense_point", "planner_append_zigzag_line",
                                         "planner_append_arc_or_line"};
    for (unsigned i = 0; i < 3u; i++)
        out_line(k_cat[i], mean_x100(as.cat_counts[i], as.cat_n[i], g_append_ovh_x100), "block", as.cat_n[i],
                 max_insns(as.cat_max[i], g_append_ovh_x100), NULL);
    out_line("planner_append_corner_smoothing", corner, "block", as.n, -1, NULL);
    out_line("planner_append_arc_fit", fit, "block", as.n, -1, NULL);
    out_line("planner_append_rest", mean > corner + fit ? mean - corner - fit : 0u, "block", as.n, -1,
             "what=validation,block_setup,backward_pass");
#ifdef BENCH_RAMP_WRAP
    /* inside the rest: ramp sizing and phase evaluation (the backward pass's ramps and their verification) */
    out_line("planner_append_ramp_sizing", mean_x100(as.size_counts, as.n, 0u), "block", as.n, -1, NULL);
    out_line("planner_append_phase_eval", mean_x100(as.phase_counts, as.n, 0u), "block", as.n, -1, NULL);
    out_line("scurve_strict_intervals_in_append", mean_x100(g_w_size.counts, g_w_size.calls, 0u), "call",
             g_w_size.calls, (int32_t)(g_w_size.max_counts * 40u), NULL);
    out_line("phase_eval_in_append", mean_x100(g_w_phase.counts, g_w_phase.calls, 0u), "call", g_w_phase.calls,
             (int32_t)(g_w_phase.max_counts * 40u), NULL);
#endif
    out_line("corner_smooth", mean_x100(g_w_corner.counts, g_w_corner.calls, 0u), "call", g_w_corner.calls,
             (int32_t)(g_w_corner.max_counts * 40u), NULL);
    out_line("arcfit_fit", mean_x100(g_w_fit.counts, g_w_fit.calls, 0u), "call", g_w_fit.calls,
             (int32_t)(g_w_fit.max_counts * 40u), NULL);
    out_line("planner_plan_piece", mean_x100(g_w_piece.counts, g_w_piece.calls, 0u), "piece", g_w_piece.calls,
             (int32_t)(g_w_piece.max_counts * 40u), NULL);
    /* where a piece's instructions go: its ramp verifications (planner stats), and in lissom-bench-ramp.elf the
     * ramp sizing and phase evaluation inside it, per piece and per call */
    out_line("planner_plan_piece_checks", g_w_piece.calls ? g_piece_checks * 100u / g_w_piece.calls : 0u, "piece",
             g_w_piece.calls, -1, "what=ramp_verifications_x1");
#ifdef BENCH_RAMP_WRAP
    out_line("planner_plan_piece_ramp_sizing", mean_x100(g_w_psize.counts, g_w_piece.calls, 0u), "piece",
             g_w_psize.calls, (int32_t)(g_w_psize.max_counts * 40u), NULL);
    out_line("planner_plan_piece_phase_eval", mean_x100(g_w_pphase.counts, g_w_piece.calls, 0u), "piece",
             g_w_pphase.calls, (int32_t)(g_w_pphase.max_counts * 40u), NULL);
#endif
    out_line("planner_full_backward_pass", as.full_pass_counts * 4000u, "call", 1u, -1, NULL);
    cm_out_str("note append_bp_nodes_per_block=");
    cm_out_fixed((int32_t)(as.n ? (as.bp_nodes * 100u + as.n / 2u) / as.n : 0u), 2);
    cm_out_str(" append_checks_per_block=");
    cm_out_fixed((int32_t)(as.n ? (as.checks * 100u + as.n / 2u) / as.n : 0u), 2);
    cm_out_str(" full_pass_blocks=");
    cm_out_u32(as.full_pass_blocks);
    cm_out_str(" dense_cycles=");
    cm_out_u32(ks[0].n + ks[1].n + ks[2].n + ks[3].n);
    cm_out_char('\n');

    return ok;
}

bool bench_planner_append(void)
{
    calibrate_overheads();
    return bench_append();
}

bool bench_planner(void)
{
    calibrate_overheads();
    bench_clothoid_step();
    bool ok = bench_cycles();
    ok = bench_append() && ok;
    cm_out_str("size lsm_pblock ");
    cm_out_u32((uint32_t)sizeof(lsm_pblock));
    cm_out_str("\nsize lsm_planner ");
    cm_out_u32((uint32_t)sizeof(lsm_planner));
    cm_out_str("\nsize lsm_interp ");
    cm_out_u32((uint32_t)sizeof(lsm_interp));
    cm_out_str("\nsize lsm_piece ");
    cm_out_u32((uint32_t)sizeof(lsm_piece));
    cm_out_str("\nsize lookahead_128_blocks ");
    cm_out_u32((uint32_t)(NBLK * sizeof(lsm_pblock) + sizeof(lsm_planner) + sizeof(lsm_interp)));
    cm_out_char('\n');
    return ok;
}
