/*
 * bench_main.c: lissom-bench.elf, instruction counts of the float core on Cortex-M4F (QEMU mps2-an386).
 *
 * Method. Under `qemu -icount shift=0` every instruction takes 1 ns of virtual time and SysTick (processor
 * clock, 25 MHz) counts down once per 40 instructions. SysTick runs free (reload 0xFFFFFF, no interrupt);
 * a benchmark reads it before and after N calls: instructions = 40 x counts, so the resolution per call is
 * 40/N instructions. The 24-bit counter wraps after 671 M instructions; every measurement stays below.
 *   1. Calibration (self-test): a loop of exactly 2n instructions must read 2n/40 counts (+-1 count plus the
 *      few instructions around it) for n = 1e5, 4e5, 1.6e6; otherwise the image exits 1.
 *   2. Overhead: the harness loop calling an empty function through the same function pointer is measured
 *      and subtracted, so a figure is the instructions spent inside the benchmarked call (plus setting up
 *      its arguments).
 *   3. Per-cycle benchmarks run a whole move cycle by cycle and report the average per cycle, and the
 *      largest single cycle (read per call, so +-40 instructions).
 * Output, one line per benchmark (scripts/arm_bench.sh turns it into a table):
 *   bench <name> <instructions, 2 decimals> <unit> calls=<N> [max=<M> max_at=<where>]
 * The clothoid stepper (clothoid_step_*, clothoid_block_entry, clothoid_eval): the mean as above; max, the largest
 * single call, from a second pass that reads every call on its own (+-40).
 * The planner and interpolator benchmarks are in bench_planner.c.
 *   size <type> <bytes>
 * Exit code 0, or 1 if the calibration fails (99: HardFault).
 * Figures are instructions, not cycles: a real M4 adds flash wait states, 14-cycle VDIV/VSQRT, and so on.
 */
#include <math.h>
#include <string.h>

#include "bench_planner.h"
#include "clothoid.h"
#include "cm_board.h"
#include "cm_out.h"
#include "move.h"
#include "scurve.h"
#include "stepgen.h"

#define INSNS_PER_COUNT 40u
#define CYCLE_S 0.00025f /* 4 kHz control cycle */

typedef void (*bench_call)(void *ctx, uint32_t i);

static inline uint32_t systick_now(void)
{
    return CM_SYST_CVR;
}

static inline uint32_t counts_between(uint32_t t0, uint32_t t1)
{
    return (t0 - t1) & CM_SYST_MAX_RELOAD; /* down-counter */
}

__attribute__((noinline)) static void call_empty(void *ctx, uint32_t i)
{
    (void)ctx;
    (void)i;
    __asm__ volatile("" ::: "memory");
}

/* SysTick counts for n calls of fn. */
__attribute__((noinline)) static uint32_t run_counts(bench_call fn, void *ctx, uint32_t n)
{
    const uint32_t t0 = systick_now();
    for (uint32_t i = 0; i < n; i++)
        fn(ctx, i);
    const uint32_t t1 = systick_now();
    return counts_between(t0, t1);
}

static uint32_t g_overhead_x100; /* harness instructions per empty call, x100 */

/* Instructions per call x100 (rounded), harness not subtracted. */
static uint32_t raw_x100(uint32_t counts, uint32_t n)
{
    const uint64_t total_x100 = (uint64_t)counts * INSNS_PER_COUNT * 100u;
    return (uint32_t)((total_x100 + n / 2u) / n);
}

/* Instructions per call x100, the harness overhead (empty call) subtracted. */
static uint32_t insns_x100(uint32_t counts, uint32_t n)
{
    const uint32_t per_call = raw_x100(counts, n);
    return per_call > g_overhead_x100 ? per_call - g_overhead_x100 : 0u;
}

static const char *g_max_note; /* optional: where the largest single cycle happened (appended as a field) */

static void out_bench(const char *name, uint32_t x100, const char *unit, uint32_t calls, int32_t max_insns)
{
    cm_out_str("bench ");
    cm_out_str(name);
    cm_out_char(' ');
    cm_out_fixed((int32_t)x100, 2);
    cm_out_char(' ');
    cm_out_str(unit);
    cm_out_str(" calls=");
    cm_out_u32(calls);
    if (max_insns >= 0) {
        cm_out_str(" max=");
        cm_out_i32(max_insns);
    }
    if (g_max_note != NULL) {
        cm_out_char(' ');
        cm_out_str(g_max_note);
        g_max_note = NULL;
    }
    cm_out_char('\n');
}

static void out_size(const char *type, uint32_t bytes)
{
    cm_out_str("size ");
    cm_out_str(type);
    cm_out_char(' ');
    cm_out_u32(bytes);
    cm_out_char('\n');
}

/* ---- calibration ---- */

static bool calibrate(void)
{
    bool ok = true;
    for (uint32_t n = 100000u; n <= 1600000u; n *= 4u) {
        uint32_t left = n;
        const uint32_t t0 = systick_now();
        __asm__ volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(left)::"cc"); /* exactly 2n instructions */
        const uint32_t t1 = systick_now();
        const uint32_t counts = counts_between(t0, t1);
        const uint32_t insns = 2u * n;
        const uint32_t measured = counts * INSNS_PER_COUNT;
        const uint32_t err = measured > insns ? measured - insns : insns - measured;
        const bool this_ok = err <= INSNS_PER_COUNT + 8u; /* one count + the reads around the loop */
        cm_out_str("calib insns=");
        cm_out_u32(insns);
        cm_out_str(" counts=");
        cm_out_u32(counts);
        cm_out_str(this_ok ? " ok\n" : " FAIL\n");
        ok = ok && this_ok;
    }
    return ok;
}

/* ---- S-curve plans ---- */

typedef struct sc_case {
    float v0, v1, a, j, snap;
} sc_case;

static const sc_case k_sc_cases[8] = {
    {0.0f, 100.0f, 1000.0f, 20000.0f, 1.0e6f}, {100.0f, 30.0f, 500.0f, 10000.0f, 5.0e5f},
    {30.0f, 0.0f, 2000.0f, 1.0e5f, 1.0e7f},    {0.0f, 5.0f, 3000.0f, 5.0e4f, 2.0e6f},
    {12.5f, 250.0f, 4000.0f, 8.0e4f, 4.0e6f},  {250.0f, 0.0f, 1500.0f, 3.0e4f, 1.0e6f},
    {0.0f, 1000.0f, 10000.0f, 2.0e5f, 2.0e7f}, {60.0f, 61.0f, 1000.0f, 20000.0f, 1.0e6f},
};

static lsm_scurve g_sc;

static void call_scurve_plan(void *ctx, uint32_t i)
{
    const sc_case *c = &k_sc_cases[i % 8u];
    const lsm_scurve_limits lim = {c->a, c->j, c->snap};
    (void)ctx;
    (void)lsm_scurve_plan(&g_sc, &lim, CYCLE_S, c->v0, c->v1, LSM_SCURVE_RULE_STRICT, NULL);
}

static void call_scurve_strict_intervals(void *ctx, uint32_t i)
{
    const sc_case *c = &k_sc_cases[i % 8u];
    const lsm_scurve_limits lim = {c->a, c->j, c->snap};
    lsm_scurve_intervals iv;
    (void)ctx;
    (void)lsm_scurve_strict_intervals(&lim, CYCLE_S, c->v1 > c->v0 ? c->v1 - c->v0 : c->v0 - c->v1, &iv);
    __asm__ volatile("" ::"r"(&iv) : "memory");
}

/* libm primitives the core calls (newlib-nano), for attributing costs; arguments vary over a range */
static volatile float g_sink;
static void call_sinf(void *ctx, uint32_t i)
{
    (void)ctx;
    g_sink = sinf((float)(i % 1024u) * 0.00306796f); /* 0 .. pi */
}
static void call_cbrtf(void *ctx, uint32_t i)
{
    (void)ctx;
    g_sink = cbrtf(1.0f + (float)(i % 1024u) * 37.5f);
}
static void call_sqrtf(void *ctx, uint32_t i)
{
    (void)ctx;
    g_sink = sqrtf(1.0f + (float)(i % 1024u) * 37.5f);
}

static void call_scurve_eval(void *ctx, uint32_t i)
{
    lsm_kin k;
    (void)ctx;
    lsm_scurve_eval(&g_sc, (float)i * CYCLE_S, &k);
    __asm__ volatile("" ::"r"(&k) : "memory");
}

/* ---- moves ---- */

static const lsm_axis_limits k_lim[LSM_MAX_AXES] = {
    {200.0f, 2000.0f, 40000.0f, 2.0e6f}, {200.0f, 2000.0f, 40000.0f, 2.0e6f}, {50.0f, 800.0f, 10000.0f, 5.0e5f},
    {360.0f, 3000.0f, 60000.0f, 3.0e6f}, {360.0f, 3000.0f, 60000.0f, 3.0e6f}, {720.0f, 5000.0f, 1.0e5f, 5.0e6f},
};

/* Four moves per axis count, from short (no cruise) to long. */
static const float k_dist[4][LSM_MAX_AXES] = {
    {100.0f, -40.0f, 5.0f, 90.0f, -45.0f, 10.0f},
    {0.5f, 0.2f, -0.1f, 1.0f, 2.0f, -3.0f},
    {20.0f, -20.0f, 3.0f, 30.0f, -30.0f, 0.0f},
    {-7.0f, 12.0f, -1.5f, 5.0f, 45.0f, 180.0f},
};

static lsm_move_request g_req;
static lsm_move g_mv;
static lsm_stepgen g_gen;
static lsm_status g_last_status;

static void make_request(uint8_t n_axes, uint32_t which)
{
    memset(&g_req, 0, sizeof g_req);
    g_req.n_axes = n_axes;
    g_req.cycle_s = CYCLE_S;
    g_req.rule = LSM_SCURVE_RULE_STRICT;
    for (unsigned a = 0; a < n_axes; a++) {
        g_req.distance_mm[a] = k_dist[which % 4u][a];
        g_req.lim[a] = k_lim[a];
    }
}

static void call_move_plan(void *ctx, uint32_t i)
{
    const uint8_t n_axes = *(const uint8_t *)ctx;
    make_request(n_axes, i);
    g_last_status = lsm_move_plan(&g_mv, &g_req);
}

static void call_stepgen_init(void *ctx, uint32_t i)
{
    (void)ctx;
    (void)i;
    (void)lsm_stepgen_init(&g_gen, &g_mv, NULL);
}

static void call_stepgen_next(void *ctx, uint32_t i)
{
    lsm_real pos[LSM_MAX_AXES];
    (void)ctx;
    (void)i;
    (void)lsm_stepgen_next(&g_gen, pos);
    __asm__ volatile("" ::"r"(pos) : "memory");
}

static void call_make_request(void *ctx, uint32_t i)
{
    make_request(*(const uint8_t *)ctx, i);
}

/* Plans: the request set-up is measured separately and subtracted. */
static void bench_move_plan(const char *name, uint8_t n_axes)
{
    const uint32_t n = 64u;
    const uint32_t setup = run_counts(call_make_request, &n_axes, n);
    const uint32_t total = run_counts(call_move_plan, &n_axes, n);
    out_bench(name, raw_x100(total - setup, n), "plan", n, -1); /* the harness cancels out */
}

/* Per-cycle evaluation over whole moves (the four distances): average and largest single cycle. */
/* Plans move `which` of `n_axes` axes into g_mv for the benchmark `name`; says so and returns false if it fails. */
static bool plan_bench_move(const char *name, uint8_t n_axes, uint32_t which)
{
    make_request(n_axes, which);
    if (lsm_move_plan(&g_mv, &g_req) == LSM_OK)
        return true;
    cm_out_str("bench setup failed: ");
    cm_out_str(name);
    cm_out_char('\n');
    return false;
}

static void bench_stepgen(const char *name, uint8_t n_axes)
{
    uint32_t cycles = 0, counts = 0, max_counts = 0;
    bool max_at_boundary = false;
    for (uint32_t w = 0; w < 4u; w++) {
        if (!plan_bench_move(name, n_axes, w))
            return;
        const uint32_t n = lsm_move_total_cycles(&g_mv);
        (void)lsm_stepgen_init(&g_gen, &g_mv, NULL);
        counts += run_counts(call_stepgen_next, NULL, n);
        cycles += n;
        (void)lsm_stepgen_init(&g_gen, &g_mv, NULL);
        for (uint32_t k = 0; k < n; k++) { /* per-cycle maximum, one reading per call */
            const uint8_t phase = g_gen.phase;
            const uint32_t t0 = systick_now();
            call_stepgen_next(NULL, k);
            const uint32_t t1 = systick_now();
            const uint32_t c = counts_between(t0, t1);
            if (c > max_counts) {
                max_counts = c;
                max_at_boundary = g_gen.phase != phase; /* this cycle ended a phase */
            }
        }
    }
    const int32_t max_insns = (int32_t)(max_counts * INSNS_PER_COUNT) - (int32_t)(g_overhead_x100 / 100u);
    g_max_note = max_at_boundary ? "max_at=phase_end" : "max_at=inside_phase";
    out_bench(name, insns_x100(counts, cycles), "cycle", cycles, max_insns);
}

/* The closed-form state of a PP move (lsm_move_eval_cycle: axprof.c calls it every cycle beside the stepgen for
 * the velocity, acceleration and jerk), over whole 1-axis moves (the four distances): average and largest call. */
static void call_move_eval(void *ctx, uint32_t k)
{
    lsm_kin kin;
    (void)ctx;
    lsm_move_eval_cycle(&g_mv, 0, k, 0, &kin);
    __asm__ volatile("" ::"r"(&kin) : "memory");
}

static void bench_move_eval(const char *name)
{
    uint32_t calls = 0, counts = 0, max_counts = 0;
    for (uint32_t w = 0; w < 4u; w++) {
        if (!plan_bench_move(name, 1, w))
            return;
        const uint32_t n = lsm_move_total_cycles(&g_mv);
        counts += run_counts(call_move_eval, NULL, n);
        calls += n;
        for (uint32_t k = 0; k < n; k++) {
            const uint32_t t0 = systick_now();
            call_move_eval(NULL, k);
            const uint32_t c = counts_between(t0, systick_now());
            max_counts = c > max_counts ? c : max_counts;
        }
    }
    const int32_t max_insns = (int32_t)(max_counts * INSNS_PER_COUNT) - (int32_t)(g_overhead_x100 / 100u);
    out_bench(name, insns_x100(counts, calls), "call", calls, max_insns);
}

/* ---- clothoid stepper: what interp.c calls per cycle on a clothoid block (lsm_clothoid_step) and at block entry
 * (lsm_clothoid_init + lsm_clothoid_stepper_init) ---- */

static lsm_clothoid_stepper g_cst;
static lsm_clothoid g_cseg;

/* Clothoid blocks of the contour program (firmware/apps/contour) with the cursor's offset at entry (s0). */
typedef struct cl_entry {
    float k0, c, len, s0, th0;
} cl_entry;

static const cl_entry k_cl_entries[8] = {
    {0.0f, 0.00271966f, 2.84329f, 0.0421085f, 0.0f},
    {0.1f, 0.00274748f, 2.84329f, 0.0954885f, -0.448705f},
    {31.6934f, -471.185f, 0.0676876f, 9.94876e-05f, 1.07263f},
    {7.26892f, -61.1442f, 0.118882f, 0.000501692f, 0.444982f},
    {0.218756f, -2.18779f, 0.0999895f, 0.00970078f, 0.0109367f},
    {0.599577f, -0.348337f, 0.165717f, 0.00557643f, 0.0496799f},
    {0.593474f, -0.182161f, 0.283386f, 0.0281467f, 0.0809828f},
    {0.0f, 3.74738f, 0.109703f, 0.0f, 0.0f},
};

static void call_cl_step(void *ctx, uint32_t i)
{
    (void)i;
    (void)lsm_clothoid_step(&g_cst, *(const lsm_real *)ctx, NULL);
}

static void call_cl_entry(void *ctx, uint32_t i)
{
    const cl_entry *e = &k_cl_entries[i % 8u];
    lsm_clothoid seg;
    (void)ctx;
    (void)lsm_clothoid_init(&seg, 0.0f, 0.0f, e->th0, e->k0, e->c, e->len);
    (void)lsm_clothoid_stepper_init(&g_cst, &seg, e->s0, 64u);
}

static void call_cl_eval(void *ctx, uint32_t i)
{
    lsm_clothoid_state o;
    (void)ctx;
    (void)lsm_clothoid_eval(&g_cseg, 0.01f * (lsm_real)(i % 500u), &o);
    __asm__ volatile("" ::"r"(&o) : "memory");
}

/* The largest single call of n (each read on its own: +-40), the harness subtracted. */
static int32_t max_single(bench_call fn, void *ctx, uint32_t n)
{
    uint32_t mx = 0;
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t t0 = systick_now();
        fn(ctx, i);
        const uint32_t c = counts_between(t0, systick_now());
        if (c > mx)
            mx = c;
    }
    return (int32_t)(mx * INSNS_PER_COUNT) - (int32_t)(g_overhead_x100 / 100u);
}

/* n steps of ds along a clothoid from s = 0, re-anchored every `anchor` steps (0: never), that never reach its
 * end (which would be an anchor too): the mean (one window around all n, harness subtracted: exact to 40 / n, plus
 * the few instructions of passing the arguments) and the largest single step (a second pass, read step by step). */
static void bench_cl_steps(const char *name, lsm_real k0, lsm_real c, lsm_real ds, uint32_t anchor)
{
    const uint32_t n = 2048u;
    (void)lsm_clothoid_init(&g_cseg, 0.0f, 0.0f, 0.3f, k0, c, (lsm_real)n * ds * 1.01f);
    (void)lsm_clothoid_stepper_init(&g_cst, &g_cseg, 0.0f, anchor);
    const uint32_t mean = insns_x100(run_counts(call_cl_step, &ds, n), n);
    (void)lsm_clothoid_stepper_init(&g_cst, &g_cseg, 0.0f, anchor);
    out_bench(name, mean, "call", n, max_single(call_cl_step, &ds, n));
}

static void bench_clothoid(void)
{
    /* free steps of 0.1 mm with |kappa ds| about 0.001, 0.02 (the contour program's median), 0.15 (its largest)
     * and 0.5 */
    bench_cl_steps("clothoid_step_free_kds0.001", 0.01f, 1.0e-6f, 0.1f, 0u);
    bench_cl_steps("clothoid_step_free_kds0.02", 0.2f, 1.0e-5f, 0.1f, 0u);
    bench_cl_steps("clothoid_step_free_kds0.15", 1.5f, 1.0e-4f, 0.1f, 0u);
    bench_cl_steps("clothoid_step_free_kds0.5", 5.0f, 1.0e-4f, 0.1f, 0u);
    /* re-anchored every 64 steps as interp.c does, along a clothoid that turns 3 rad over the 205 mm (curvature
     * 0.005 -> 0.025 /mm); max: an anchoring step (an evaluation from the start, so it grows with the turning) */
    bench_cl_steps("clothoid_step_anchor64", 0.005f, 1.0e-4f, 0.1f, 64u);
    /* block entry, as interp.c does it: lsm_clothoid_init, then lsm_clothoid_stepper_init at s0 */
    out_bench("clothoid_block_entry", insns_x100(run_counts(call_cl_entry, NULL, 800u), 800u), "call", 800u,
              max_single(call_cl_entry, NULL, 800u));
    /* direct evaluation at s = 0 .. 5 mm on a 5 mm clothoid (curvature 0 -> 0.4 /mm) */
    (void)lsm_clothoid_init(&g_cseg, 0.0f, 0.0f, 0.3f, 0.0f, 0.08f, 5.0f);
    out_bench("clothoid_eval", insns_x100(run_counts(call_cl_eval, NULL, 500u), 500u), "call", 500u,
              max_single(call_cl_eval, NULL, 500u));
}

int main(void)
{
    CM_SYST_CSR = 0u;
    CM_SYST_RVR = CM_SYST_MAX_RELOAD;
    CM_SYST_CVR = 0u;
    CM_SYST_CSR = CM_SYST_CSR_ENABLE | CM_SYST_CSR_CLKSOURCE; /* free running, no interrupt */

    cm_out_str("lissom-bench: Cortex-M4F float core, QEMU mps2-an386 -icount shift=0, instructions = 40 x SysTick\n");
    if (!calibrate()) {
        cm_out_str("bench FAIL: SysTick is not 40 instructions per count (run with -icount shift=0)\n");
        return 1;
    }
    {
        const uint32_t n = 100000u;
        const uint32_t c = run_counts(call_empty, NULL, n);
        g_overhead_x100 = raw_x100(c, n);
        cm_out_str("overhead empty_call ");
        cm_out_fixed((int32_t)g_overhead_x100, 2);
        cm_out_str(" call (subtracted below)\n");
    }

    /* S-curve engine */
    out_bench("scurve_plan", insns_x100(run_counts(call_scurve_plan, NULL, 800u), 800u), "plan", 800u, -1);
    {
        const sc_case *c = &k_sc_cases[0];
        const lsm_scurve_limits lim = {c->a, c->j, c->snap};
        (void)lsm_scurve_plan(&g_sc, &lim, CYCLE_S, c->v0, c->v1, LSM_SCURVE_RULE_STRICT, NULL);
        const uint32_t n = lsm_scurve_total_cycles(&g_sc.iv) + 1u;
        out_bench("scurve_eval_closed_form", insns_x100(run_counts(call_scurve_eval, NULL, n), n), "call", n, -1);
    }

    out_bench("scurve_strict_intervals", insns_x100(run_counts(call_scurve_strict_intervals, NULL, 800u), 800u), "call",
              800u, -1);
    out_bench("libm_sinf", insns_x100(run_counts(call_sinf, NULL, 1024u), 1024u), "call", 1024u, -1);
    out_bench("libm_cbrtf", insns_x100(run_counts(call_cbrtf, NULL, 1024u), 1024u), "call", 1024u, -1);
    out_bench("libm_sqrtf", insns_x100(run_counts(call_sqrtf, NULL, 1024u), 1024u), "call", 1024u, -1);

    /* point-to-point moves: plan, evaluator start, per-cycle evaluation */
    bench_move_plan("move_plan_1ax", 1);
    bench_move_plan("move_plan_3ax", 3);
    bench_move_plan("move_plan_6ax", 6);
    make_request(6, 0);
    (void)lsm_move_plan(&g_mv, &g_req);
    out_bench("stepgen_init_6ax", insns_x100(run_counts(call_stepgen_init, NULL, 256u), 256u), "call", 256u, -1);
    bench_stepgen("stepgen_cycle_1ax", 1);
    bench_stepgen("stepgen_cycle_3ax", 3);
    bench_stepgen("stepgen_cycle_6ax", 6);
    bench_move_eval("move_eval_cycle_1ax");

    /* clothoid stepper alone */
    bench_clothoid();

    /* look-ahead planner and interpolator (bench_planner.c) */
    const bool planner_ok = bench_planner();

    out_size("lsm_scurve", (uint32_t)sizeof(lsm_scurve));
    out_size("lsm_move", (uint32_t)sizeof(lsm_move));
    out_size("lsm_stepgen", (uint32_t)sizeof(lsm_stepgen));
    if (!planner_ok) {
        cm_out_str("bench FAIL: a planner benchmark did not run to its end\n");
        return 1;
    }
    if (g_last_status != LSM_OK) {
        cm_out_str("bench FAIL: a move plan failed\n");
        return 1;
    }
    cm_out_str("bench PASS\n");
    return 0;
}
