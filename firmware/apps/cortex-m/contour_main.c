/*
 * contour_main.c: lissom-contour.elf, the built-in contour program (firmware/apps/contour: lines, arcs, a dense
 * polyline and clothoid corners through the look-ahead planner and the interpolator, 128-block look-ahead, float
 * core) on the Cortex-M4F (QEMU mps2-an386).
 *
 * The program runs in two contexts, in lock-step so that the order of calls is the host twin's:
 *   main loop  lsm_contour_background for cycle n (feed one item, lsm_interp_prepare) once step n-1 is done;
 *   SysTick    lsm_contour_step for cycle n (one interpolator step) once background n is done, at
 *              LSM_CONTOUR_CYCLE_US; a tick that finds background n not done yet steps nothing (a stall, counted:
 *              on a machine the interpolator would hold its setpoint for a cycle).
 * The tick therefore never plans: it cannot overrun. The main loop polls (no WFI: see docs/cortex_m.md on -icount
 * and WFI). Then it prints the report of lsm_contour_report ("contour ...", "contour_stats ...", "contour_sample ..."), the
 * same lines as its host twin lissom-contour-host, which scripts/arm_check.sh and tests/py/test_arm_image.py
 * compare (checksum of every setpoint, end point, samples).
 * Checks: the program ran to its end without an error, a fallback plan or a planning error; it ended exactly on
 * its programmed end point; it ran on lines, arcs and clothoids. Ticks that overran are reported as a warning.
 * Ends with "contour PASS" (exit code 0) or "contour FAIL" (1); 99: HardFault, 98: other exception.
 * Its linker map is also the flash/RAM figure of the core with a 128-block look-ahead (scripts/arm_report.sh):
 * it links nothing of the core but what the planner, the interpolator and the program need.
 */
#include "cm_board.h"
#include "cm_out.h"
#include "contour_prog.h"
#include "lsm_port.h"

#include <stdint.h>

static lsm_contour g_contour;
static volatile bool g_done;
static volatile uint32_t g_ticks;
static volatile uint32_t g_bg_done; /* background halves done (main loop writes) */
static volatile uint32_t g_steps;   /* steps done (tick writes) */
static volatile uint32_t g_stalls;  /* ticks that found the background of their cycle not done */
static unsigned g_failures;

static void check(bool ok, const char *what)
{
    cm_out_str(ok ? "check ok   " : "check FAIL ");
    cm_out_str(what);
    cm_out_char('\n');
    if (!ok)
        g_failures++;
}

static void tick(void *ctx)
{
    g_ticks++;
    if (g_done)
        return;
    if (g_bg_done != g_steps + 1u) {
        g_stalls++;
        return;
    }
    __asm__ volatile("dmb" ::: "memory"); /* the background's writes before the step reads them */
    const lsm_contour_result r = lsm_contour_step(ctx);
    __asm__ volatile("dmb" ::: "memory");
    g_steps = g_steps + 1u;
    if (r != LSM_CONTOUR_RUNNING)
        g_done = true;
}

/* Stack high-water mark: the 64 KB below the current stack pointer are painted before the run and scanned
 * after it (main loop, SysTick handler with its FPU context, everything the planner calls). */
extern uint32_t _ebss, _estack;
#define STACK_PAINT 0xA5A5A5A5u
#define STACK_WINDOW 65536u

static uint32_t *stack_floor(void)
{
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    uintptr_t lo = sp - STACK_WINDOW;
    if (lo < (uintptr_t)&_ebss)
        lo = (uintptr_t)&_ebss;
    return (uint32_t *)((lo + 3u) & ~(uintptr_t)3u);
}

static uint32_t *g_paint_lo;

__attribute__((noinline)) static void paint_stack(void)
{
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    g_paint_lo = stack_floor();
    for (volatile uint32_t *p = g_paint_lo; (uintptr_t)p < sp - 64u; p++)
        *p = STACK_PAINT;
}

static uint32_t stack_used(void)
{
    const uint32_t *p = g_paint_lo;
    while ((uintptr_t)p < (uintptr_t)&_estack && *p == STACK_PAINT)
        p++;
    return (uint32_t)((uintptr_t)&_estack - (uintptr_t)p);
}

static void put_line(const char *line, void *ctx)
{
    (void)ctx;
    cm_out_str(line);
    cm_out_char('\n');
}

int main(void)
{
    cm_out_str("lissom-contour: Cortex-M4F, QEMU mps2-an386, float core, planner + interpolator\n");
    check(lsm_port_init() == LSM_OK, "port init");
    check(lsm_contour_init(&g_contour) == LSM_OK, "contour init");
    paint_stack();
    check(lsm_port_tick_start(LSM_CONTOUR_CYCLE_US, tick, &g_contour) == LSM_OK, "tick start");
    while (!g_done) {
        if (g_bg_done == g_steps) { /* step n-1 done: the background of cycle n */
            __asm__ volatile("dmb" ::: "memory");
            (void)lsm_contour_background(&g_contour);
            __asm__ volatile("dmb" ::: "memory");
            g_bg_done = g_bg_done + 1u;
        }
    }
    check(lsm_port_tick_stop() == LSM_OK, "tick stop");
    lsm_contour_report(&g_contour, put_line, NULL);
    cm_out_str("tick period_us=");
    cm_out_u32(LSM_CONTOUR_CYCLE_US);
    cm_out_str(" ticks=");
    cm_out_u32(g_ticks);
    cm_out_str(" overruns=");
    cm_out_u32(lsm_port_tick_overruns());
    cm_out_str(" stalls=");
    cm_out_u32(g_stalls);
    cm_out_str(" stack_used_bytes=");
    cm_out_u32(stack_used());
    cm_out_str(" ram_lookahead_bytes=");
    cm_out_u32((uint32_t)(sizeof g_contour.blk + sizeof g_contour.pl + sizeof g_contour.ip));
    cm_out_char('\n');
    check(g_contour.result == LSM_CONTOUR_DONE && g_contour.err == LSM_OK, "contour ran to its end");
    check(lsm_contour_end_exact(&g_contour), "contour ends exactly on its programmed end point");
    check(g_contour.pl.stats.plan_fallbacks == 0u && g_contour.ip.plan_errors == 0u,
          "no fallback plan, no planning error");
    check(g_contour.pl.stats.corners > 0u && g_contour.kind_cycles[LSM_GEOM_LINE] > 0u &&
              g_contour.kind_cycles[LSM_GEOM_ARC] > 0u && g_contour.kind_cycles[LSM_GEOM_CLOTHOID] > 0u,
          "ran on lines, arcs and clothoid corners");
    /* The tick only steps the interpolator (a few thousand instructions): it must never overrun. Stalls are
     * reported, not failed: the program and its checksum do not depend on timing; a stall is a cycle whose
     * background (an append that replans the look-ahead, a piece planned by lsm_interp_prepare) took longer than
     * the period, 1 M instructions under -icount shift=0 (docs/cortex_m.md, figures of arm_bench). */
    check(lsm_port_tick_overruns() == 0u, "no tick overran");
    if (g_stalls != 0u) {
        cm_out_str("note: ");
        cm_out_u32(g_stalls);
        cm_out_str(" ticks found the background of their cycle not done and held the setpoint\n");
    }
    cm_out_str(g_failures == 0u ? "contour PASS\n" : "contour FAIL\n");
    return g_failures == 0u ? 0 : 1;
}
