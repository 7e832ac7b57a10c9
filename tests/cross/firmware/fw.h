/* Semihosting output for the Cortex-M4F link test (startup.c). */
#ifndef HSTPF_FW_H
#define HSTPF_FW_H

/* Writes a NUL-terminated string to the host (semihosting SYS_WRITE0). */
void fw_puts(const char *s);
/* Ends the program; the emulator's exit status is 0 for status 0, else 1. */
void fw_exit(int status);

#endif
