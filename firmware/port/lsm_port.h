/*
 * lsm_port.h: everything a board (a "port") must provide to run Lissom.
 *
 * The core in firmware/ is pure computation: it never touches hardware, reads a clock or allocates. A port
 * connects it to a board. A port is one directory firmware/port/<name>/ with one C file (or a few) that
 * implements every function below. firmware/port/template/ is a blank port that builds: copy it to start.
 * Ports in this repository: template (blank), cortex-m (QEMU mps2-an386, Cortex-M4F) and linux (SocketCAN, libgpiod
 * GPIO, timerfd tick; used by the lissom-node daemon, docs/hil.md).
 *
 * What a board provides, exactly:
 *   1. CAN: send one classic CAN frame (11- or 29-bit id, 0..8 data bytes) without blocking, and poll for one
 *      received frame without blocking. The port owns its queues/mailboxes; CAN FD is not used.
 *   2. GPIO, by logical function (the port maps functions to pins and handles the electrical polarity):
 *        in:  E-stop            active = stop requested. Wire it fail-safe (normally closed contact: a broken
 *                               wire reads active). If the read fails, the caller treats it as active.
 *        out: drive enable      active = power stages enabled. Reset state must be inactive.
 *        out: in position       active = the axes are at their commanded target.
 *   3. The control tick: call one function periodically (period in microseconds) from a timer, e.g. SysTick.
 *      The tick never re-enters itself. If a tick is still running when the next one is due, the next one is
 *      late; the port counts it (lsm_port_tick_overruns) and does not queue more than one pending tick.
 *   4. A free-running microsecond clock (32 bit, wraps after about 71.6 minutes). Compare two readings wrap-safe
 *      with (int32_t)(a - b) < 0, never with a < b.
 *   5. lsm_port_idle: wait until something happens (an interrupt, a tick); it may return at once.
 *
 * Contexts. On an MCU the tick function runs in interrupt context; everything else is called from the main
 * loop. can_send/can_recv are each called from one context only (single producer, single consumer), so a
 * lock-free ring is enough; if an application sends from both the tick and the main loop, the port must
 * make can_send safe for that (document it in the port). gpio_write must be safe from the tick.
 *
 * Errors: every function that can fail returns lsm_status (status.h): LSM_OK, LSM_E_NULL for a NULL pointer,
 * LSM_E_ARG for an out-of-range argument (pin, dlc, id, period), LSM_E_FULL when a send finds no room,
 * LSM_E_EMPTY when no frame is waiting, LSM_E_STATE when called before lsm_port_init, LSM_E_PORT_IO when the
 * hardware or OS reports an error, LSM_E_PORT_UNSUPPORTED when this board has no such facility.
 * Time units: microseconds (`_us`).
 */
#ifndef LSM_PORT_H
#define LSM_PORT_H

#include "lsm_config.h"
#include "status.h"

/* ---- CAN ---- */

/* The frame type (lsm_can_frame, LSM_CAN_FLAG_*, LSM_CAN_*_ID_MAX) is the core's, from can.h: a port passes
 * frames between the controller and the CANopen layer unchanged. */
#include "can.h"

/* ---- GPIO, by logical function ---- */

typedef enum lsm_gpio_in {
    LSM_GPIO_IN_ESTOP = 0, /* emergency stop: active = stop requested (fail-safe wiring) */
    LSM_GPIO_IN_COUNT
} lsm_gpio_in;

typedef enum lsm_gpio_out {
    LSM_GPIO_OUT_DRIVE_ENABLE = 0, /* active = drives' power stages enabled; inactive after reset */
    LSM_GPIO_OUT_IN_POSITION = 1,  /* active = all axes at their commanded target */
    LSM_GPIO_OUT_COUNT
} lsm_gpio_out;

/* ---- Control tick ---- */

/* The function the port calls once per tick. ctx is passed through unchanged. */
typedef void (*lsm_port_tick_fn)(void *ctx);

/* ---- The functions a port implements ---- */

/*
 * Brings up the board: clocks, CAN controller (bit rate chosen by the port), GPIO with every output inactive,
 * the microsecond clock (starting near 0). Call once, before anything else. Errors: LSM_E_PORT_IO.
 */
lsm_status lsm_port_init(void);

/*
 * Queues one frame for transmission and returns at once.
 * Errors: LSM_E_NULL, LSM_E_ARG (dlc > 8, id out of range for its format), LSM_E_FULL (no free mailbox or
 * queue slot: nothing was queued, try again later), LSM_E_STATE, LSM_E_PORT_IO.
 */
lsm_status lsm_port_can_send(const lsm_can_frame *frame);

/*
 * Polls for one received frame and returns at once. LSM_OK with *frame filled, or LSM_E_EMPTY when no frame
 * is waiting (*frame untouched). Frames come out in the order they arrived.
 * Errors: LSM_E_NULL, LSM_E_STATE, LSM_E_PORT_IO.
 */
lsm_status lsm_port_can_recv(lsm_can_frame *frame);

/*
 * Reads a logical input: *active = true when the function is active (E-stop: stop requested).
 * Errors: LSM_E_NULL, LSM_E_ARG (unknown input), LSM_E_STATE, LSM_E_PORT_IO. On any error the caller must
 * treat the E-stop as active.
 */
lsm_status lsm_port_gpio_read(lsm_gpio_in in, bool *active);

/*
 * Drives a logical output: active = true switches the function on (drive enable: power stages on).
 * Safe to call from the tick. Errors: LSM_E_ARG (unknown output), LSM_E_STATE, LSM_E_PORT_IO.
 */
lsm_status lsm_port_gpio_write(lsm_gpio_out out, bool active);

/*
 * Starts calling fn(ctx) every period_us microseconds, the first call one period from now. Calling it while
 * a tick runs replaces the tick (stop, then start). Errors: LSM_E_NULL (fn), LSM_E_ARG (period 0 or beyond
 * what the timer can do), LSM_E_STATE, LSM_E_PORT_IO.
 */
lsm_status lsm_port_tick_start(uint32_t period_us, lsm_port_tick_fn fn, void *ctx);

/* Stops the tick; after it returns, fn is not called again. Stopping a stopped tick is LSM_OK. */
lsm_status lsm_port_tick_stop(void);

/* Number of ticks that started late because the previous one had not finished (since lsm_port_init). */
uint32_t lsm_port_tick_overruns(void);

/* Microseconds since lsm_port_init, modulo 2^32. Compare wrap-safe: (int32_t)(a - b) < 0. */
uint32_t lsm_port_time_us(void);

/* Waits until something happens (an interrupt or a tick); may return at once. For the main loop. */
void lsm_port_idle(void);

#endif /* LSM_PORT_H */
