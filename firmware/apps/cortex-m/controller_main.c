/*
 * controller_main.c: lissom-controller.elf, the controller image for QEMU mps2-an386 (Cortex-M4F): the full node
 * of ctl_app.h (CANopen CiA 301 + CiA 402 axes + path buffer + the motion layer of ctl_motion.h) with its CAN bus
 * on UART 0 as an slcan (Lawicel) adapter would present it (cm_uart.h, slcan.h). Start: scripts/mcu_node.sh.
 *
 * Two contexts:
 *   tick        SysTick, highest priority, every CTL_TICK_INSTR instructions (below): ctl_app_tick (the host's slcan
 *               lines -> the node, lsm_canopen_process, ctl_motion_tick, the node's frames -> UART), the 0x5F00
 *               statistics, the outputs (FPGA LEDs: drive enable, in position);
 *   background  the main loop: ctl_app_background (the SDO server, whose object accesses the tick applies:
 *               canopen.h; the motion layer's path feed: block appends, lsm_interp_prepare, the interpolator run
 *               ahead of the tick, motion.h); when it has nothing to do it sleeps in WFI until the next interrupt.
 *               It reaches the node only through the hand-offs (canopen.h, mpipe.h); the tick never waits on it.
 *   UART 0's RX and TX interrupts (below the tick) only move characters between the UART and two rings.
 *
 * Time. The image models a 168 MHz Cortex-M4 executing one instruction per cycle: a 1 ms control cycle is
 * CTL_TICK_INSTR = 168,000 instructions. Under QEMU `-icount shift=S` an instruction takes 2^S ns of virtual time
 * and SysTick (25 MHz board clock) counts every 40 ns, i.e. every 40 >> S instructions; the tick period is
 * therefore CTL_TICK_INSTR / (40 >> S) counts. The image is built for CTL_ICOUNT_SHIFT = 3 (docs/cortex_m.md,
 * "Controller image": why 3, and how the guest's time relates to the master's), so one tick is 33,600 counts =
 * 1.344 ms of virtual time. The node's µs clock is SysTick's count converted at 168 instructions per µs
 * (clock_us), like a hardware timer: it follows virtual time, not the number of ticks.
 *
 * Tick statistics (0x5F00): ticks, overruns (a tick still running when the next fell due), the worst tick in
 * instructions from its timer event to the end of its work (interrupt latency included), and the background
 * load: the share of the last 1000 ticks' instructions that were neither the tick nor idle (WFI), per mille.
 * Idle time is measured around each WFI (minus the ticks inside it); the idle interval that is still open
 * when a window closes (at most one tick) falls into the next window.
 *
 * Command line (semihosting, QEMU -semihosting-config ...,arg=...): "--node-id N --axes A" (defaults 1 and 3).
 * Position feedback: ideal loopback (ctl_motion.h). E-stop input: FPGA button 0 (QEMU never presses it).
 */
#include "cm_board.h"
#include "cm_out.h"
#include "cm_semihost.h"
#include "cm_tick.h"
#include "cm_uart.h"
#include "ctl_app.h"
#include "ctl_motion_impl.h"
#include "lsm_port.h"

#include <stdint.h>

#ifndef CTL_ICOUNT_SHIFT
#define CTL_ICOUNT_SHIFT 3
#endif
#define CTL_CORE_MHZ 168u                             /* modelled core clock, one instruction per cycle */
#define CTL_CYCLE_US 1000u                            /* control cycle */
#define CTL_TICK_INSTR (CTL_CORE_MHZ * CTL_CYCLE_US)  /* instructions per tick: 168,000 */
#define CTL_INSTR_PER_COUNT (40u >> CTL_ICOUNT_SHIFT) /* SysTick count = 40 ns of virtual time */
#define CTL_TICK_COUNTS (CTL_TICK_INSTR / CTL_INSTR_PER_COUNT)
#define CTL_LOAD_WINDOW_TICKS 1000u /* background load window: 1 s */

_Static_assert(CTL_ICOUNT_SHIFT <= 3, "a SysTick count must be a whole number of instructions");
_Static_assert(CTL_TICK_INSTR % CTL_INSTR_PER_COUNT == 0u, "the tick must be a whole number of SysTick counts");

static ctl_app g_app;
static struct ctl_motion g_motion;
static volatile uint32_t g_idle_counts; /* main loop: SysTick counts spent in WFI, ticks excluded (wraps) */

/* The node's µs clock: SysTick counts since the start, converted at 168 instructions per µs (the modelled core
 * clock), so it follows QEMU's virtual time (and the chip's clock), not the number of ticks. */
static struct {
    uint32_t last_counts;
    uint32_t rem_instr; /* instructions not yet converted, < CTL_CORE_MHZ */
    uint32_t us;
} g_clock;

static uint32_t clock_us(void)
{
    const uint32_t c = cm_tick_now_counts();
    const uint64_t instr = (uint64_t)(c - g_clock.last_counts) * CTL_INSTR_PER_COUNT + g_clock.rem_instr;
    g_clock.last_counts = c;
    g_clock.us += (uint32_t)(instr / CTL_CORE_MHZ);
    g_clock.rem_instr = (uint32_t)(instr % CTL_CORE_MHZ);
    return g_clock.us;
}

static struct {
    uint32_t window_ticks;
    uint32_t idle0, busy0; /* idle and tick-busy counts at the start of the window */
    uint16_t load_permille;
} g_load;

static int link_getc(void *ctx)
{
    (void)ctx;
    return cm_uart_getc();
}

static bool link_write(void *ctx, const char *s, size_t n)
{
    (void)ctx;
    return cm_uart_write(s, n);
}

static size_t link_room(void *ctx)
{
    (void)ctx;
    return cm_uart_tx_room();
}

/* The background load of the window that ends at this tick (see the header comment). */
static void load_window(const cm_tick_stats *ts)
{
    if (++g_load.window_ticks < CTL_LOAD_WINDOW_TICKS)
        return;
    const uint32_t idle = g_idle_counts;
    const uint32_t window = CTL_LOAD_WINDOW_TICKS * CTL_TICK_COUNTS;
    const uint32_t used = (idle - g_load.idle0) + (ts->busy_counts - g_load.busy0);
    const uint32_t bg = used < window ? window - used : 0u;
    g_load.load_permille = (uint16_t)((uint64_t)bg * 1000u / window);
    g_load.window_ticks = 0u;
    g_load.idle0 = idle;
    g_load.busy0 = ts->busy_counts;
}

static void tick(void *ctx)
{
    ctl_app *a = ctx;
    cm_tick_stats ts;
    cm_tick_get_stats(&ts);
    load_window(&ts);
    lsm_canopen_tick_stats st;
    st.ticks = ts.ticks;
    st.overruns = ts.work_overruns;
    st.late_wakes = ts.late_wakes;
    st.worst_instr = ts.worst_counts * CTL_INSTR_PER_COUNT;
    st.bg_load_permille = g_load.load_permille;
    const uint32_t now_us = clock_us();
    st.clock_ms = now_us / 1000u;
    ctl_motion_stats(&g_motion, &st.path_underruns, &st.path_min_ahead);
    bool estop = true;
    if (lsm_port_gpio_read(LSM_GPIO_IN_ESTOP, &estop) != LSM_OK)
        estop = true; /* fail-safe: an unreadable input stops */
    ctl_app_tick(a, now_us, estop, &st);
    (void)lsm_port_gpio_write(LSM_GPIO_OUT_DRIVE_ENABLE, lsm_canopen_drive_enable(&a->co));
    (void)lsm_port_gpio_write(LSM_GPIO_OUT_IN_POSITION, lsm_canopen_in_position(&a->co));
}

/* "--node-id N --axes A" from the semihosting command line; absent or bad values keep the defaults. */
static uint32_t parse_u32(const char **p)
{
    uint32_t v = 0u;
    while (**p == ' ')
        (*p)++;
    while (**p >= '0' && **p <= '9')
        v = v * 10u + (uint32_t)(*(*p)++ - '0');
    return v;
}

static bool starts(const char *p, const char *word)
{
    while (*word != '\0')
        if (*p++ != *word++)
            return false;
    return true;
}

static void parse_cmdline(uint8_t *node_id, uint8_t *axes)
{
    static char line[128];
    if (!cm_semihost_cmdline(line, sizeof line))
        return;
    for (const char *p = line; *p != '\0';) {
        if (starts(p, "--node-id")) {
            p += 9;
            const uint32_t v = parse_u32(&p);
            if (v >= 1u && v <= 127u)
                *node_id = (uint8_t)v;
        } else if (starts(p, "--axes")) {
            p += 6;
            const uint32_t v = parse_u32(&p);
            if (v >= 1u && v <= LSM_MAX_AXES)
                *axes = (uint8_t)v;
        } else {
            p++;
        }
    }
}

/* Nothing to do: sleep until the next interrupt, and count the sleep (ticks excluded) as idle. */
static void idle_once(void)
{
    cm_tick_stats s0, s1;
    cm_tick_get_stats(&s0);
    const uint32_t t0 = cm_tick_now_counts();
    cm_tick_idle();
    const uint32_t t1 = cm_tick_now_counts();
    cm_tick_get_stats(&s1);
    g_idle_counts += (t1 - t0) - (s1.busy_counts - s0.busy_counts);
}

int main(void)
{
    uint8_t node_id = 1u, axes = 3u;
    parse_cmdline(&node_id, &axes);
    if (lsm_port_init() != LSM_OK || cm_uart_init() != LSM_OK) {
        cm_out_str("lissom-controller: board init failed\n");
        return 1;
    }
    ctl_app_config cfg = {0};
    cfg.node_id = node_id;
    cfg.n_axes = axes;
    cfg.cycle_us = CTL_CYCLE_US;
    cfg.heartbeat_ms = 100u;
    cfg.device_name = "Lissom motion controller (Cortex-M4F)";
    cfg.motion = &g_motion;
    cfg.link = (ctl_link){link_getc, link_write, link_room, NULL};
    const lsm_status st = ctl_app_init(&g_app, &cfg);
    if (st != LSM_OK) {
        cm_out_str("lissom-controller: init failed, status ");
        cm_out_i32((int32_t)st);
        cm_out_char('\n');
        return 1;
    }
    cm_out_str("lissom-controller: ready node=");
    cm_out_u32(node_id);
    cm_out_str(" axes=");
    cm_out_u32(axes);
    cm_out_str(" cycle_us=1000 tick_instructions=");
    cm_out_u32(CTL_TICK_INSTR);
    cm_out_str(" icount_shift=");
    cm_out_u32(CTL_ICOUNT_SHIFT);
    cm_out_str(" link=uart0-slcan motion=");
    cm_out_str(ctl_motion_name());
    cm_out_char('\n');
    cm_out_flush();
    if (cm_tick_start_counts(CTL_TICK_COUNTS, tick, &g_app) != LSM_OK)
        return 1;
    for (;;) {
        if (!ctl_app_background(&g_app))
            idle_once();
    }
}
