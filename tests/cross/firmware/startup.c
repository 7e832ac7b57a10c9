/* Bare-metal start-up for the link test on a Cortex-M4F (QEMU mps2-an386):
 * vector table, FPU enable, .data copy, .bss clear, main(), and ARM
 * semihosting (BKPT 0xAB) for text output and the exit status. No newlib
 * start files, no stdio, no heap. */
#include <stdint.h>

#include "fw.h"

/* Linker-script symbols. __stack_top__ is declared as a function so that the
 * vector table can be an array of function pointers without casts. */
extern uint32_t __data_load__, __data_start__, __data_end__, __bss_start__, __bss_end__;
extern void __stack_top__(void);

int main(void);
void Reset_Handler(void);
void Fault_Handler(void);
void SysTick_Handler(void);

/* ---- instruction counter: SysTick on the processor clock ----
 * Under QEMU with -icount shift=0 the virtual clock advances 1 ns per
 * instruction, and the mps2-an386 processor clock (the SysTick's source
 * here) is 25 MHz: one SysTick count is 40 instructions. */
#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define SYST_RELOAD 0x00FFFFFFu

static volatile uint32_t systick_wraps;

void SysTick_Handler(void)
{
    ++systick_wraps;
}

void fw_ticks_start(void)
{
    SYST_CSR = 0u;
    systick_wraps = 0u;
    SYST_RVR = SYST_RELOAD;
    SYST_CVR = 0u;
    SYST_CSR = 7u; /* enable, interrupt on wrap, processor clock */
    while (SYST_CVR == 0u) {
        /* the first count loads the reload value; no wrap is counted */
    }
}

uint64_t fw_ticks(void)
{
    uint32_t w0, w1, cvr;
    do {
        w0 = systick_wraps;
        cvr = SYST_CVR;
        w1 = systick_wraps;
    } while (w0 != w1);
    return (uint64_t)w0 * (SYST_RELOAD + 1u) + (SYST_RELOAD - (cvr & SYST_RELOAD));
}

void fw_ticks_stop(void)
{
    SYST_CSR = 0u;
}

#define SEMI_SYS_WRITE0 0x04u
#define SEMI_SYS_EXIT 0x18u
#define ADP_STOPPED_APPLICATION_EXIT 0x20026u
#define ADP_STOPPED_RUNTIME_ERROR 0x20023u

static uint32_t semihost(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void fw_puts(const char *s)
{
    (void)semihost(SEMI_SYS_WRITE0, s);
}

void fw_exit(int status)
{
    /* 32-bit ARM semihosting: r1 carries the reason itself. QEMU exits with
     * 0 for ApplicationExit and 1 for any other reason. */
    for (;;) {
        (void)semihost(SEMI_SYS_EXIT,
                       (const void *)(uintptr_t)(status == 0 ? ADP_STOPPED_APPLICATION_EXIT
                                                             : ADP_STOPPED_RUNTIME_ERROR));
    }
}

void Fault_Handler(void)
{
    fw_puts("HSTPF-M4F-FAIL: fault exception\n");
    fw_exit(1);
}

void Reset_Handler(void)
{
    volatile uint32_t *const cpacr = (volatile uint32_t *)0xE000ED88u;
    uint32_t *src = &__data_load__, *dst = &__data_start__;
    /* full access to CP10/CP11 (the FPU) before any floating-point code */
    *cpacr |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    while (dst < &__data_end__) {
        *dst++ = *src++;
    }
    for (dst = &__bss_start__; dst < &__bss_end__; ++dst) {
        *dst = 0u;
    }
    fw_exit(main());
}

__attribute__((section(".isr_vector"), used)) static void (*const vectors[16])(void) = {
    __stack_top__,  Reset_Handler, Fault_Handler, Fault_Handler, Fault_Handler, Fault_Handler,
    Fault_Handler, 0, 0, 0, 0, Fault_Handler, Fault_Handler, 0, Fault_Handler, SysTick_Handler,
};
