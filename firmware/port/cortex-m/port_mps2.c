/*
 * port_mps2.c: the Lissom port (firmware/port/lsm_port.h) for QEMU mps2-an386. What each facility maps to is
 * listed in cm_board.h: SysTick = control tick, CMSDK TIMER0 = microsecond clock, FPGA I/O LEDs/button =
 * GPIO, a RAM loopback queue = CAN (the board has no CAN controller).
 *
 * Contexts: the tick function runs in the SysTick handler. lsm_port_time_us and lsm_port_gpio_write may be
 * called from both the tick and the main loop (they mask interrupts briefly). The CAN loopback queue is
 * single producer / single consumer: send from one context, receive from one context.
 */
#include "lsm_port.h"

#include "cm_board.h"
#include "cm_tick.h"

#define CM_CAN_QUEUE 8u /* loopback depth; a power of two */

static struct {
    bool up;
    /* tick */
    volatile lsm_port_tick_fn tick_fn;
    void *volatile tick_ctx;
    volatile uint32_t overruns;
    uint32_t reload;                 /* SysTick reload value: period - 1 counts */
    volatile uint32_t events;        /* tick events taken by the handler (wraps) */
    volatile uint32_t worst_counts;  /* longest tick, from its timer event to the end of its function */
    volatile uint32_t busy_counts;   /* sum of the handler's own durations (wraps) */
    volatile bool in_wfi;            /* the main loop sleeps in cm_tick_idle */
    volatile uint32_t work_overruns; /* ticks longer than a period from their event, sleep latency excluded */
    volatile uint32_t late_wakes;    /* overruns of ticks that woke from cm_tick_idle and ran less than a period */
    /* microsecond clock: TIMER0 counts down at 25 MHz; us = acc_us + (elapsed counts) / 25 */
    uint32_t last_count;
    uint32_t acc_us;
    uint32_t rem_counts; /* counts not yet converted, < CM_SYSCLK_PER_US */
    /* CAN loopback ring (indices run freely; slot = index % CM_CAN_QUEUE) */
    lsm_can_frame can_q[CM_CAN_QUEUE];
    volatile uint32_t can_head; /* next slot to write (producer) */
    volatile uint32_t can_tail; /* next slot to read (consumer) */
} g_port;

lsm_status lsm_port_init(void)
{
    CM_SYST_CSR = 0u;
    CM_FPGAIO_LED0 = 0u; /* every output inactive */
    CM_TIMER0_CTRL = 0u;
    CM_TIMER0_RELOAD = 0xFFFFFFFFu;
    CM_TIMER0_VALUE = 0xFFFFFFFFu;
    CM_TIMER0_CTRL = CM_TIMER_CTRL_EN;
    g_port.last_count = CM_TIMER0_VALUE;
    g_port.acc_us = 0u;
    g_port.rem_counts = 0u;
    g_port.tick_fn = NULL;
    g_port.tick_ctx = NULL;
    g_port.overruns = 0u;
    g_port.reload = 0u;
    g_port.events = 0u;
    g_port.worst_counts = 0u;
    g_port.busy_counts = 0u;
    g_port.work_overruns = 0u;
    g_port.late_wakes = 0u;
    g_port.can_head = 0u;
    g_port.can_tail = 0u;
    g_port.up = true;
    return LSM_OK;
}

static bool can_frame_valid(const lsm_can_frame *f)
{
    if (f->dlc > LSM_CAN_MAX_DLC)
        return false;
    if ((f->flags & ~(LSM_CAN_FLAG_EXT | LSM_CAN_FLAG_RTR)) != 0u)
        return false;
    return f->id <= ((f->flags & LSM_CAN_FLAG_EXT) != 0u ? LSM_CAN_EXT_ID_MAX : LSM_CAN_STD_ID_MAX);
}

lsm_status lsm_port_can_send(const lsm_can_frame *frame)
{
    if (frame == NULL)
        return LSM_E_NULL;
    if (!g_port.up)
        return LSM_E_STATE;
    if (!can_frame_valid(frame))
        return LSM_E_ARG;
    uint32_t head = g_port.can_head;
    if (head - g_port.can_tail >= CM_CAN_QUEUE)
        return LSM_E_FULL;
    g_port.can_q[head % CM_CAN_QUEUE] = *frame;
    __asm__ volatile("dmb" ::: "memory"); /* the frame is in place before the consumer sees the index */
    g_port.can_head = head + 1u;
    return LSM_OK;
}

lsm_status lsm_port_can_recv(lsm_can_frame *frame)
{
    if (frame == NULL)
        return LSM_E_NULL;
    if (!g_port.up)
        return LSM_E_STATE;
    uint32_t tail = g_port.can_tail;
    if (tail == g_port.can_head)
        return LSM_E_EMPTY;
    __asm__ volatile("dmb" ::: "memory");
    *frame = g_port.can_q[tail % CM_CAN_QUEUE];
    g_port.can_tail = tail + 1u;
    return LSM_OK;
}

lsm_status lsm_port_gpio_read(lsm_gpio_in in, bool *active)
{
    if (active == NULL)
        return LSM_E_NULL;
    if ((unsigned)in >= (unsigned)LSM_GPIO_IN_COUNT)
        return LSM_E_ARG;
    if (!g_port.up) {
        *active = true;
        return LSM_E_STATE;
    }
    *active = (CM_FPGAIO_BUTTON & CM_BUTTON_ESTOP) != 0u;
    return LSM_OK;
}

lsm_status lsm_port_gpio_write(lsm_gpio_out out, bool active)
{
    static const uint32_t k_mask[LSM_GPIO_OUT_COUNT] = {CM_LED_DRIVE_ENABLE, CM_LED_IN_POSITION};
    if ((unsigned)out >= (unsigned)LSM_GPIO_OUT_COUNT)
        return LSM_E_ARG;
    if (!g_port.up)
        return LSM_E_STATE;
    uint32_t irq = cm_irq_save(); /* read-modify-write of a shared register */
    uint32_t leds = CM_FPGAIO_LED0;
    CM_FPGAIO_LED0 = active ? (leds | k_mask[out]) : (leds & ~k_mask[out]);
    cm_irq_restore(irq);
    return LSM_OK;
}

lsm_status lsm_port_tick_start(uint32_t period_us, lsm_port_tick_fn fn, void *ctx)
{
    if (period_us == 0u || period_us > (CM_SYST_MAX_RELOAD + 1u) / CM_SYSCLK_PER_US)
        return fn == NULL ? LSM_E_NULL : LSM_E_ARG;
    return cm_tick_start_counts(period_us * CM_SYSCLK_PER_US, fn, ctx);
}

lsm_status cm_tick_start_counts(uint32_t period_counts, lsm_port_tick_fn fn, void *ctx)
{
    if (fn == NULL)
        return LSM_E_NULL;
    if (period_counts < 2u || period_counts > CM_SYST_MAX_RELOAD + 1u)
        return LSM_E_ARG;
    if (!g_port.up)
        return LSM_E_STATE;
    CM_SYST_CSR = 0u;
    CM_SCB_ICSR = CM_SCB_ICSR_PENDSTCLR;
    g_port.tick_fn = fn;
    g_port.tick_ctx = ctx;
    g_port.reload = period_counts - 1u;
    CM_SCB_SHPR3 = (CM_SCB_SHPR3 & 0x00FFFFFFu); /* SysTick at the highest configurable priority (0) */
    CM_SYST_RVR = period_counts - 1u;
    CM_SYST_CVR = 0u;
    CM_SYST_CSR = CM_SYST_CSR_ENABLE | CM_SYST_CSR_TICKINT | CM_SYST_CSR_CLKSOURCE;
    return LSM_OK;
}

void cm_tick_get_stats(cm_tick_stats *out)
{
    uint32_t irq = cm_irq_save();
    out->ticks = g_port.events;
    out->overruns = g_port.overruns;
    out->work_overruns = g_port.work_overruns;
    out->late_wakes = g_port.late_wakes;
    out->worst_counts = g_port.worst_counts;
    out->busy_counts = g_port.busy_counts;
    cm_irq_restore(irq);
}

uint32_t cm_tick_now_counts(void)
{
    uint32_t irq = cm_irq_save();
    uint32_t p1, p2, cvr;
    do { /* a wrap between the reads would mix two periods: read until the pending bit is stable around CVR */
        p1 = CM_SCB_ICSR & CM_SCB_ICSR_PENDSTSET;
        cvr = CM_SYST_CVR;
        p2 = CM_SCB_ICSR & CM_SCB_ICSR_PENDSTSET;
    } while (p1 != p2);
    /* the counter reads 0 at the event itself (then reloads): position 0 of the period that event starts, which
     * the pending bit (or the handler's count) already includes */
    const uint32_t events = g_port.events + (p2 != 0u ? 1u : 0u);
    const uint32_t pos = cvr == 0u ? 0u : g_port.reload + 1u - cvr;
    const uint32_t now = events * (g_port.reload + 1u) + pos;
    cm_irq_restore(irq);
    return now;
}

lsm_status lsm_port_tick_stop(void)
{
    CM_SYST_CSR = 0u;
    CM_SCB_ICSR = CM_SCB_ICSR_PENDSTCLR;
    g_port.tick_fn = NULL;
    return LSM_OK;
}

uint32_t lsm_port_tick_overruns(void)
{
    return g_port.overruns;
}

void SysTick_Handler(void);
void SysTick_Handler(void)
{
    const uint32_t c0 = CM_SYST_CVR; /* counts left in this period when the handler starts */
    lsm_port_tick_fn fn = g_port.tick_fn;
    g_port.events++;
    (void)lsm_port_time_us(); /* keeps the microsecond clock's wrap tracking fresh (it needs a call per 171 s) */
    if (fn != NULL)
        fn(g_port.tick_ctx);
    const uint32_t c1 = CM_SYST_CVR;
    /* counts elapsed in the period at entry and at the end (the counter reads 0 at the event itself, then reloads) */
    const uint32_t period = g_port.reload + 1u;
    const bool pending = (CM_SCB_ICSR & CM_SCB_ICSR_PENDSTSET) != 0u;
    const uint32_t e0 = c0 == 0u ? 0u : period - c0;
    const uint32_t e1 = c1 == 0u && pending ? 0u : period - c1;
    /* a wrap during the handler: the pending bit, or the period position going back (QEMU updates the counter
     * from its virtual clock at once, the pending bit when it next processes its timers) */
    const bool late = pending || e1 < e0;
    if (late)
        g_port.overruns++; /* the next tick fell due while this one ran: it starts late */
    /* this handler's duration (one wrap at most is counted), and the tick's length from its timer event */
    const uint32_t dur = late ? (period - e0) + e1 : e1 - e0;
    /* latency: the counts between the timer event and the handler, unless the CPU slept (cm_tick_idle.h): a
     * wake-up from WFI takes a few cycles on the chip, while under QEMU -icount sleep=on the time slept follows
     * the host's clock and its scheduling delays */
    const uint32_t latency = g_port.in_wfi ? 0u : e0;
    const uint32_t since_event = latency + dur;
    g_port.busy_counts += dur;
    if (since_event > g_port.reload + 1u)
        g_port.work_overruns++;
    else if (late)
        g_port.late_wakes++;
    if (since_event > g_port.worst_counts)
        g_port.worst_counts = since_event;
}

uint32_t lsm_port_time_us(void)
{
    if (!g_port.up)
        return 0u;
    uint32_t irq = cm_irq_save();
    uint32_t now = CM_TIMER0_VALUE;
    uint32_t elapsed = g_port.last_count - now; /* down-counter: wrap-safe below 171 s between calls */
    g_port.last_count = now;
    uint32_t counts = g_port.rem_counts + elapsed;
    if (counts < elapsed) { /* 32-bit overflow of the sum: convert in two steps */
        g_port.acc_us += elapsed / CM_SYSCLK_PER_US;
        counts = g_port.rem_counts + elapsed % CM_SYSCLK_PER_US;
    }
    g_port.acc_us += counts / CM_SYSCLK_PER_US;
    g_port.rem_counts = counts % CM_SYSCLK_PER_US;
    uint32_t us = g_port.acc_us;
    cm_irq_restore(irq);
    return us;
}

void lsm_port_idle(void)
{
    cm_wfi();
}

void cm_tick_idle(void)
{
    g_port.in_wfi = true;
    cm_wfi();
    g_port.in_wfi = false;
}
