/*
 * cm_tick.h: the mps2-an386 port's control tick beyond lsm_port.h (port_mps2.c): a period given in SysTick counts
 * (so that an image can give its tick an exact instruction budget under QEMU -icount), the tick's timing
 * statistics, and a free-running clock in SysTick counts for measuring the background.
 *
 * SysTick runs on the 25 MHz processor clock of the board model: one count is 40 ns of QEMU virtual time, which is
 * 40 >> shift instructions under `-icount shift=N` (40 at shift 0, 5 at shift 3).
 * Statistics (all in counts): worst = the longest tick from its timer event (reload) to the end of the tick
 * function, i.e. the interrupt latency (masked sections, exception entry) plus the handler, except that a tick
 * that wakes the CPU from cm_tick_idle counts no latency (QEMU's sleeping time follows the host's clock, see
 * cm_tick_idle); busy = the sum of the
 * handlers' own durations. A tick that has not ended when the next one falls due is an overrun (lsm_port.h);
 * the duration of such a tick is counted over one wrap of the counter only.
 */
#ifndef CM_TICK_H
#define CM_TICK_H

#include "lsm_port.h"

typedef struct cm_tick_stats {
    uint32_t ticks;         /* tick events handled (wraps) */
    uint32_t overruns;      /* as lsm_port_tick_overruns: the next tick fell due before this one ended */
    uint32_t work_overruns; /* ticks that took more than a period from their event (sleep latency excluded) */
    uint32_t late_wakes;    /* the other overruns: a tick woken late from cm_tick_idle (QEMU: the host woke it
                               late) that ran less than a period itself */
    uint32_t worst_counts;  /* longest tick from its timer event to the end of its function, counts */
    uint32_t busy_counts;   /* sum of the handlers' durations, counts (wraps) */
} cm_tick_stats;

/* Starts the tick with a period of period_counts SysTick counts (2 .. 2^24). Otherwise as lsm_port_tick_start
 * (which calls it with period_us x 25). Errors: LSM_E_NULL, LSM_E_ARG, LSM_E_STATE. Main loop. */
lsm_status cm_tick_start_counts(uint32_t period_counts, lsm_port_tick_fn fn, void *ctx);

/* A consistent copy of the statistics (masks interrupts for a few instructions). Any context; inside the tick
 * function they cover the ticks before this one. */
void cm_tick_get_stats(cm_tick_stats *out);

/* SysTick counts since the tick started, wrapping at 2^32 (ticks x period + the counts of the running period).
 * Masks interrupts for a few instructions. Any context. */
uint32_t cm_tick_now_counts(void);

/* Sleeps in WFI until the next interrupt, marked so that the tick does not count the wake-up as latency: under
 * QEMU -icount with sleep=on the virtual time of a sleep follows the host's real clock, so a host that wakes
 * QEMU late makes the next tick look late by its scheduling delay (a chip wakes in a few cycles). Main loop. */
void cm_tick_idle(void);

#endif /* CM_TICK_H */
