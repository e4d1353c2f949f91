/*
 * startup.c: reset and fault handling for the Cortex-M4F images (no C runtime startup files are linked).
 *
 * Reset_Handler copies .data from flash to RAM, zeroes .bss, enables the FPU (CPACR CP10/CP11 full access),
 * then calls main(); if main returns, its value is the semihosting exit code.
 * HardFault prints the stacked PC, LR, xPSR and the fault status registers through semihosting and exits
 * with code 99; any other unexpected exception prints IPSR and exits with 98. The other configurable faults
 * (MemManage, BusFault, UsageFault) are left disabled, so they escalate to HardFault.
 * The vector table lists the 16 system exceptions and 32 device interrupts of mps2-an386 (only UART 0's are
 * handled, by cm_uart.c, when an image enables them).
 */
#include <stdint.h>

#include "cm_board.h"
#include "cm_out.h"
#include "cm_semihost.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
int main(void);
void Reset_Handler(void);
void HardFault_Handler(void);
void Default_Handler(void);
void cm_hardfault_report(const uint32_t *frame);
void SysTick_Handler(void) __attribute__((weak, alias("Default_Handler")));
void UART0RX_Handler(void) __attribute__((weak, alias("Default_Handler")));
void UART0TX_Handler(void) __attribute__((weak, alias("Default_Handler")));

void Reset_Handler(void)
{
    const uint32_t *src = &_sidata;
    for (uint32_t *dst = &_sdata; dst < &_edata;)
        *dst++ = *src++;
    for (uint32_t *dst = &_sbss; dst < &_ebss;)
        *dst++ = 0u;
    CM_SCB_CPACR |= (0xFu << 20);
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    int rc = main();
    cm_out_flush();
    cm_semihost_exit((uint32_t)rc);
}

static void out_reg(const char *name, uint32_t value)
{
    cm_out_str(name);
    cm_out_hex32(value);
}

/* Called by HardFault_Handler with the exception stack frame (r0-r3, r12, lr, pc, xpsr). */
void cm_hardfault_report(const uint32_t *frame)
{
    cm_out_flush();
    cm_out_str("HardFault:");
    out_reg(" pc=", frame[6]);
    out_reg(" lr=", frame[5]);
    out_reg(" xpsr=", frame[7]);
    out_reg(" cfsr=", CM_SCB_CFSR);
    out_reg(" hfsr=", CM_SCB_HFSR);
    out_reg(" bfar=", CM_SCB_BFAR);
    cm_out_char('\n');
    cm_semihost_exit(99u);
}

/* Picks the stack that was in use (EXC_RETURN bit 2: 0 = MSP, 1 = PSP) and passes the frame on. */
__attribute__((naked)) void HardFault_Handler(void)
{
    __asm__ volatile("tst lr, #4\n\t"
                     "ite eq\n\t"
                     "mrseq r0, msp\n\t"
                     "mrsne r0, psp\n\t"
                     "b cm_hardfault_report\n");
}

void Default_Handler(void)
{
    uint32_t ipsr;
    __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
    cm_out_flush();
    cm_out_str("unexpected exception ");
    cm_out_u32(ipsr & 0x1FFu);
    cm_out_char('\n');
    cm_semihost_exit(98u);
}

#define CM_N_IRQ 32

typedef void (*cm_vector)(void);

__attribute__((section(".isr_vector"), used)) const cm_vector cm_vectors[16 + CM_N_IRQ] = {
    (cm_vector)(uintptr_t)&_estack, /* 0: initial main stack pointer */
    Reset_Handler,                  /* 1 */
    Default_Handler,                /* 2: NMI */
    HardFault_Handler,              /* 3 */
    Default_Handler,                /* 4: MemManage */
    Default_Handler,                /* 5: BusFault */
    Default_Handler,                /* 6: UsageFault */
    0,
    0,
    0,
    0,               /* 7-10: reserved */
    Default_Handler, /* 11: SVCall */
    Default_Handler, /* 12: DebugMonitor */
    0,               /* 13: reserved */
    Default_Handler, /* 14: PendSV */
    SysTick_Handler, /* 15: SysTick (port_mps2.c) */
    UART0RX_Handler, /* IRQ 0: UART 0 RX (cm_uart.c) */
    UART0TX_Handler, /* IRQ 1: UART 0 TX */
    [16 + 2 ... 16 + CM_N_IRQ - 1] = Default_Handler,
};
