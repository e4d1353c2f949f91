/*
 * cm_uart.c: CMSDK APB UART 0 with interrupt-driven rings (cm_uart.h).
 */
#include "cm_uart.h"

#include "cm_board.h"

#if (CM_UART_RX_RING & (CM_UART_RX_RING - 1u)) != 0u || (CM_UART_TX_RING & (CM_UART_TX_RING - 1u)) != 0u
#error "the UART rings must be powers of two"
#endif

static struct {
    uint8_t rx[CM_UART_RX_RING];
    volatile uint32_t rx_head, rx_tail; /* head: RX interrupt; tail: consumer */
    uint8_t tx[CM_UART_TX_RING];
    volatile uint32_t tx_head, tx_tail; /* head: producer; tail: TX interrupt */
    volatile uint32_t rx_chars, rx_dropped, tx_chars, tx_refused;
} g_uart;

void UART0RX_Handler(void);
void UART0TX_Handler(void);

lsm_status cm_uart_init(void)
{
    CM_NVIC_ICER0 = (1u << CM_IRQ_UART0_RX) | (1u << CM_IRQ_UART0_TX);
    CM_UART0_CTRL = 0u;
    g_uart.rx_head = g_uart.rx_tail = 0u;
    g_uart.tx_head = g_uart.tx_tail = 0u;
    g_uart.rx_chars = g_uart.rx_dropped = g_uart.tx_chars = g_uart.tx_refused = 0u;
    CM_UART0_BAUDDIV = 16u;
    CM_UART0_INTSTATUS = CM_UART_INT_TX | CM_UART_INT_RX;
    CM_UART0_STATE = CM_UART_STATE_OVERRUNS; /* write 1 to clear */
    CM_NVIC_IPR_BYTE(CM_IRQ_UART0_RX) = (uint8_t)CM_UART_IRQ_PRIO;
    CM_NVIC_IPR_BYTE(CM_IRQ_UART0_TX) = (uint8_t)CM_UART_IRQ_PRIO;
    CM_UART0_CTRL = CM_UART_CTRL_TXEN | CM_UART_CTRL_RXEN | CM_UART_CTRL_TXINT | CM_UART_CTRL_RXINT;
    CM_NVIC_ISER0 = (1u << CM_IRQ_UART0_RX) | (1u << CM_IRQ_UART0_TX);
    return LSM_OK;
}

void UART0RX_Handler(void)
{
    CM_UART0_INTSTATUS = CM_UART_INT_RX;
    uint32_t head = g_uart.rx_head;
    while ((CM_UART0_STATE & CM_UART_STATE_RXFULL) != 0u) {
        const uint8_t c = (uint8_t)CM_UART0_DATA;
        if (head - g_uart.rx_tail >= CM_UART_RX_RING) {
            g_uart.rx_dropped++;
            continue;
        }
        g_uart.rx[head % CM_UART_RX_RING] = c;
        head++;
        g_uart.rx_chars++;
    }
    cm_dmb(); /* the characters are in place before the consumer sees the index */
    g_uart.rx_head = head;
}

void UART0TX_Handler(void)
{
    CM_UART0_INTSTATUS = CM_UART_INT_TX;
    uint32_t tail = g_uart.tx_tail;
    const uint32_t head = g_uart.tx_head;
    cm_dmb();
    while (tail != head && (CM_UART0_STATE & CM_UART_STATE_TXFULL) == 0u) {
        CM_UART0_DATA = g_uart.tx[tail % CM_UART_TX_RING];
        tail++;
        g_uart.tx_chars++;
    }
    g_uart.tx_tail = tail;
}

int cm_uart_getc(void)
{
    const uint32_t tail = g_uart.rx_tail;
    if (tail == g_uart.rx_head)
        return -1;
    cm_dmb();
    const int c = g_uart.rx[tail % CM_UART_RX_RING];
    g_uart.rx_tail = tail + 1u;
    return c;
}

size_t cm_uart_tx_room(void)
{
    return CM_UART_TX_RING - (size_t)(g_uart.tx_head - g_uart.tx_tail);
}

bool cm_uart_write(const char *s, size_t n)
{
    if (n > cm_uart_tx_room()) {
        g_uart.tx_refused++;
        return false;
    }
    uint32_t head = g_uart.tx_head;
    for (size_t i = 0; i < n; i++)
        g_uart.tx[(head + i) % CM_UART_TX_RING] = (uint8_t)s[i];
    cm_dmb();
    g_uart.tx_head = head + (uint32_t)n;
    CM_NVIC_ISPR0 = 1u << CM_IRQ_UART0_TX; /* the TX interrupt sends it */
    return true;
}

void cm_uart_get_counters(cm_uart_counters *out)
{
    out->rx_chars = g_uart.rx_chars;
    out->rx_dropped = g_uart.rx_dropped;
    out->tx_chars = g_uart.tx_chars;
    out->tx_refused = g_uart.tx_refused;
}
