/*
 * lsm_port_template.c: a blank Lissom port. It builds (host and Cortex-M, in CI) and does nothing.
 *
 * To port Lissom to a new board: copy this directory to firmware/port/<board>/, fill in every function, and
 * add the directory to firmware/port/CMakeLists.txt. The contract of each function (what it must do, from
 * which context it is called, which errors it returns) is in firmware/port/lsm_port.h; the comments below say
 * what a typical MCU implementation touches. Until a function is filled in it returns LSM_E_PORT_UNSUPPORTED,
 * so an application running on a half-done port fails loudly instead of moving axes blindly.
 *
 * Checklist for a new board:
 *   [ ] lsm_port_init          clocks, CAN controller + pins, GPIO (outputs inactive), microsecond timer
 *   [ ] lsm_port_can_send      copy one frame into a free TX mailbox/queue; LSM_E_FULL if none
 *   [ ] lsm_port_can_recv      pop one frame from the RX FIFO/queue; LSM_E_EMPTY if none
 *   [ ] lsm_port_gpio_read     E-stop input, logical (active = stop), fail-safe wiring
 *   [ ] lsm_port_gpio_write    drive-enable and in-position outputs, logical (active = on)
 *   [ ] lsm_port_tick_start    periodic timer interrupt (e.g. SysTick) that calls fn(ctx)
 *   [ ] lsm_port_tick_stop     disable that interrupt
 *   [ ] lsm_port_tick_overruns count ticks that were due while the previous one still ran
 *   [ ] lsm_port_time_us       free-running 32-bit microsecond counter
 *   [ ] lsm_port_idle          WFI (MCU) or a short sleep (hosted)
 * Then run the application's self-test on the board (see docs/cortex_m.md for the QEMU example).
 */
#include "lsm_port.h"

lsm_status lsm_port_init(void)
{
    /* Enable peripheral clocks; configure the CAN controller (bit rate, filters accepting all ids the
     * application uses) and its pins; configure the GPIOs with every output inactive; start a free-running
     * timer for lsm_port_time_us. Return LSM_E_PORT_IO if a peripheral does not come up. */
    return LSM_E_PORT_UNSUPPORTED;
}

lsm_status lsm_port_can_send(const lsm_can_frame *frame)
{
    if (frame == NULL)
        return LSM_E_NULL;
    /* Validate dlc <= LSM_CAN_MAX_DLC and the id range (LSM_CAN_STD_ID_MAX / LSM_CAN_EXT_ID_MAX with
     * LSM_CAN_FLAG_EXT) -> LSM_E_ARG. Find a free TX mailbox (or queue slot) -> LSM_E_FULL if none.
     * Copy id, flags, dlc and data; request transmission; return without waiting for the bus. */
    return LSM_E_PORT_UNSUPPORTED;
}

lsm_status lsm_port_can_recv(lsm_can_frame *frame)
{
    if (frame == NULL)
        return LSM_E_NULL;
    /* If the RX FIFO (or the queue the CAN interrupt fills) holds a frame: copy it into *frame, release it,
     * return LSM_OK. Otherwise return LSM_E_EMPTY and leave *frame untouched. Keep arrival order. */
    return LSM_E_PORT_UNSUPPORTED;
}

lsm_status lsm_port_gpio_read(lsm_gpio_in in, bool *active)
{
    if (active == NULL)
        return LSM_E_NULL;
    if ((unsigned)in >= (unsigned)LSM_GPIO_IN_COUNT)
        return LSM_E_ARG;
    /* LSM_GPIO_IN_ESTOP: read the pin and convert to logical: *active = true when a stop is requested.
     * With a normally closed contact to ground and a pull-up, a high level (open contact or broken wire)
     * means active. */
    *active = true; /* blank port: report E-stop active, the fail-safe answer */
    return LSM_E_PORT_UNSUPPORTED;
}

lsm_status lsm_port_gpio_write(lsm_gpio_out out, bool active)
{
    if ((unsigned)out >= (unsigned)LSM_GPIO_OUT_COUNT)
        return LSM_E_ARG;
    /* LSM_GPIO_OUT_DRIVE_ENABLE / LSM_GPIO_OUT_IN_POSITION: set or clear the pin, applying the board's
     * polarity. Use the atomic set/reset register so that it is safe from the tick interrupt. */
    (void)active;
    return LSM_E_PORT_UNSUPPORTED;
}

lsm_status lsm_port_tick_start(uint32_t period_us, lsm_port_tick_fn fn, void *ctx)
{
    if (fn == NULL)
        return LSM_E_NULL;
    if (period_us == 0u)
        return LSM_E_ARG;
    /* Stop a running tick, store fn and ctx, program the timer reload for period_us (LSM_E_ARG if the timer
     * cannot reach it), enable its interrupt. In the interrupt handler: call fn(ctx); afterwards, if the timer
     * interrupt is pending again, the tick took longer than a period: count an overrun. */
    (void)ctx;
    return LSM_E_PORT_UNSUPPORTED;
}

lsm_status lsm_port_tick_stop(void)
{
    /* Disable the timer interrupt; after this returns, fn must not be called again. */
    return LSM_E_PORT_UNSUPPORTED;
}

uint32_t lsm_port_tick_overruns(void)
{
    /* Return the overrun counter kept by the tick interrupt handler. */
    return 0u;
}

uint32_t lsm_port_time_us(void)
{
    /* Return a free-running microsecond count (32 bit, wrapping), e.g. a 1 MHz timer or the tick count times
     * the period plus the timer's progress within the current period. */
    return 0u;
}

void lsm_port_idle(void)
{
    /* MCU: __WFI() (wait for interrupt). Hosted: sleep until the next tick or return at once. */
}
