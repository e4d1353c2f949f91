/*
 * cm_board.h: the Cortex-M4F port's view of its board, QEMU `mps2-an386` (ARM MPS2, AN386 FPGA image).
 *
 * What this board provides to Lissom (see firmware/port/lsm_port.h for the contract):
 *   - CPU: Cortex-M4 with single-precision FPU (fpv4-sp-d16), enabled by startup.c.
 *   - Clock: 25 MHz system clock. SysTick runs on it (CLKSOURCE = processor clock) and makes the control
 *     tick (lsm_port_tick_start). Under `qemu -icount shift=0` every instruction takes 1 ns of virtual time, so
 *     one SysTick count is exactly 40 instructions (the bench image checks this).
 *   - Microsecond clock: CMSDK APB TIMER0 (0x40000000), a 32-bit down-counter at 25 MHz, free running and
 *     extended in software to microseconds (lsm_port_time_us).
 *   - GPIO: the FPGA I/O block (0x40028000). LED0 register bit 0 = drive enable, bit 1 = in position;
 *     BUTTON register bit 0 = E-stop (pressed = active). QEMU never presses a button, so the E-stop reads
 *     inactive; on this demo board the input is NOT fail-safe (a real board wires a normally closed contact).
 *   - CAN: the MPS2 has no CAN controller. The port implements a loopback: every frame sent is queued and
 *     comes back through lsm_port_can_recv (8 frames deep). Enough to exercise a CAN node's code paths.
 *   - UART: CMSDK APB UART 0 (cm_uart.h), QEMU's first -serial: the controller image's slcan link.
 *   - Output: ARM semihosting (cm_semihost.h): text to QEMU's stderr and an exit code for QEMU. On real
 *     hardware without a debugger a semihosting call faults: replace cm_semihost.c by a UART driver.
 * Memory: 4 MB code SSRAM at 0x0 (our "flash"), 4 MB data SSRAM at 0x20000000 (mps2_an386.ld).
 */
#ifndef CM_BOARD_H
#define CM_BOARD_H

#include <stdint.h>

#define CM_REG32(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

#define CM_SYSCLK_HZ 25000000u /* processor and APB clock of mps2-an386 */
#define CM_SYSCLK_PER_US 25u   /* CM_SYSCLK_HZ / 1e6 */

/* System control space (ARMv7-M architecture reference manual, B3) */
#define CM_SYST_CSR CM_REG32(0xE000E010u) /* SysTick control and status */
#define CM_SYST_RVR CM_REG32(0xE000E014u) /* SysTick reload value (24 bit) */
#define CM_SYST_CVR CM_REG32(0xE000E018u) /* SysTick current value (24-bit down-counter) */
#define CM_SYST_CSR_ENABLE 0x1u
#define CM_SYST_CSR_TICKINT 0x2u
#define CM_SYST_CSR_CLKSOURCE 0x4u /* 1 = processor clock */
#define CM_SYST_MAX_RELOAD 0x00FFFFFFu
#define CM_SCB_ICSR CM_REG32(0xE000ED04u) /* interrupt control and state */
#define CM_SCB_ICSR_PENDSTSET (1u << 26)
#define CM_SCB_ICSR_PENDSTCLR (1u << 25)
#define CM_SCB_SHPR3 CM_REG32(0xE000ED20u) /* priorities of PendSV (23:16) and SysTick (31:24) */
#define CM_SCB_CFSR CM_REG32(0xE000ED28u)  /* configurable fault status */
#define CM_SCB_HFSR CM_REG32(0xE000ED2Cu)  /* hard fault status */
#define CM_SCB_MMFAR CM_REG32(0xE000ED34u)
#define CM_SCB_BFAR CM_REG32(0xE000ED38u)
#define CM_SCB_CPACR CM_REG32(0xE000ED88u) /* coprocessor access (CP10/CP11 = FPU) */

/* CMSDK APB timer 0 */
#define CM_TIMER0_CTRL CM_REG32(0x40000000u)
#define CM_TIMER0_VALUE CM_REG32(0x40000004u)
#define CM_TIMER0_RELOAD CM_REG32(0x40000008u)
#define CM_TIMER_CTRL_EN 0x1u

/* CMSDK APB UART 0 (0x40004000): RX interrupt = IRQ 0, TX interrupt = IRQ 1 (QEMU hw/arm/mps2.c); QEMU's
 * first -serial is this UART. One-byte holding registers, no FIFO. */
#define CM_UART0_DATA CM_REG32(0x40004000u)
#define CM_UART0_STATE CM_REG32(0x40004004u)     /* bit 0 TX full, bit 1 RX full, bit 2/3 TX/RX overrun */
#define CM_UART0_CTRL CM_REG32(0x40004008u)      /* bit 0 TX enable, 1 RX enable, 2 TX int, 3 RX int */
#define CM_UART0_INTSTATUS CM_REG32(0x4000400Cu) /* read: bit 0 TX, bit 1 RX; write 1 to clear */
#define CM_UART0_BAUDDIV CM_REG32(0x40004010u)   /* >= 16 (QEMU refuses smaller dividers) */
#define CM_UART_STATE_TXFULL 0x1u
#define CM_UART_STATE_RXFULL 0x2u
#define CM_UART_STATE_OVERRUNS 0xCu
#define CM_UART_CTRL_TXEN 0x1u
#define CM_UART_CTRL_RXEN 0x2u
#define CM_UART_CTRL_TXINT 0x4u
#define CM_UART_CTRL_RXINT 0x8u
#define CM_UART_INT_TX 0x1u
#define CM_UART_INT_RX 0x2u
#define CM_IRQ_UART0_RX 0u
#define CM_IRQ_UART0_TX 1u

/* NVIC (ARMv7-M B3.4): enable, pend, priority (8 bits per IRQ, the M4 implements the top 3 here) */
#define CM_NVIC_ISER0 CM_REG32(0xE000E100u)
#define CM_NVIC_ICER0 CM_REG32(0xE000E180u)
#define CM_NVIC_ISPR0 CM_REG32(0xE000E200u)
#define CM_NVIC_IPR_BYTE(irq) (*(volatile uint8_t *)(uintptr_t)(0xE000E400u + (irq)))

/* MPS2 FPGA I/O */
#define CM_FPGAIO_LED0 CM_REG32(0x40028000u)
#define CM_FPGAIO_BUTTON CM_REG32(0x40028008u)
#define CM_LED_DRIVE_ENABLE 0x1u
#define CM_LED_IN_POSITION 0x2u
#define CM_BUTTON_ESTOP 0x1u

/* Interrupt masking (PRIMASK): returns the previous state for cm_irq_restore. */
static inline uint32_t cm_irq_save(void)
{
    uint32_t primask;
    __asm__ volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
    return primask;
}

static inline void cm_irq_restore(uint32_t primask)
{
    __asm__ volatile("msr primask, %0" ::"r"(primask) : "memory");
}

static inline void cm_dmb(void)
{
    __asm__ volatile("dmb" ::: "memory");
}

static inline void cm_wfi(void)
{
    __asm__ volatile("wfi" ::: "memory");
}

#endif /* CM_BOARD_H */
