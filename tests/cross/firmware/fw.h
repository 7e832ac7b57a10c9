/* Semihosting output for the Cortex-M4F link test (startup.c). */
#ifndef HSTPF_FW_H
#define HSTPF_FW_H

#include <stdint.h>

/* Writes a NUL-terminated string to the host (semihosting SYS_WRITE0). */
void fw_puts(const char *s);
/* Ends the program; the emulator's exit status is 0 for status 0, else 1. */
void fw_exit(int status);
/* SysTick counter on the processor clock (24-bit, wraps counted by its
 * interrupt): start, read (counts since start), stop. */
void fw_ticks_start(void);
uint64_t fw_ticks(void);
void fw_ticks_stop(void);

#endif
