/*
 * cm_uart.h: interrupt-driven CMSDK APB UART 0 of mps2-an386 (QEMU's first -serial), with a receive ring filled
 * by the RX interrupt and a transmit ring drained by the TX interrupt, so that neither direction ever makes its
 * caller wait.
 *
 * Rings: single producer, single consumer each, indices running freely (slot = index % size), published with a
 * barrier after the data. RX: producer the RX interrupt, consumer one context of the application (cm_uart_getc).
 * TX: producer one context of the application (cm_uart_write), consumer the TX interrupt; cm_uart_write pends the
 * TX interrupt, which writes characters while the UART takes them (the CMSDK UART holds one character; under
 * QEMU a write to a socket completes at once, so a whole burst goes out in one interrupt).
 * Both interrupts run at CM_UART_IRQ_PRIO, below SysTick (the control tick preempts them, they never delay it).
 * A character that finds the RX ring full is dropped and counted (QEMU itself never drops: it holds the next
 * character while the UART's holding register is full).
 * Baud rate: BAUDDIV 16 (the smallest QEMU accepts); QEMU does not model the line's speed.
 */
#ifndef CM_UART_H
#define CM_UART_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "status.h"

#define CM_UART_RX_RING 4096u  /* characters; a power of two (a burst of ~180 slcan frame lines) */
#define CM_UART_TX_RING 8192u  /* characters; a power of two */
#define CM_UART_IRQ_PRIO 0x80u /* NVIC priority byte of both interrupts: below SysTick (0) */

/* UART 0 on, both rings empty, interrupts enabled. Main loop, before the tick starts. */
lsm_status cm_uart_init(void);

/* The next received character (0..255), or -1 when none is waiting. The RX consumer context only. */
int cm_uart_getc(void);

/* Queues n characters, all of them or none: false (nothing queued, counted) when the ring lacks room.
 * The TX producer context only. */
bool cm_uart_write(const char *s, size_t n);

/* Free room of the TX ring (characters). The TX producer context. */
size_t cm_uart_tx_room(void);

typedef struct cm_uart_counters {
    uint32_t rx_chars, rx_dropped, tx_chars, tx_refused;
} cm_uart_counters;

/* Counters since cm_uart_init (wrap). Any context (each is read on its own). */
void cm_uart_get_counters(cm_uart_counters *out);

#endif /* CM_UART_H */
