/*
 * cm_semihost.h: ARM semihosting (BKPT 0xAB) for output and exit under QEMU or a debugger.
 * QEMU needs `-semihosting-config enable=on,target=native`; text goes to QEMU's stderr, and the exit code
 * passed to cm_semihost_exit becomes QEMU's exit status.
 */
#ifndef CM_SEMIHOST_H
#define CM_SEMIHOST_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* SYS_WRITE0: writes a NUL-terminated string to the host's console. */
void cm_semihost_write0(const char *s);

/* SYS_GET_CMDLINE: the command line QEMU passes (-semihosting-config ...,arg=A,arg=B gives "A B"), NUL-terminated
 * in buf[size]. False when the host has none (then buf is untouched). */
bool cm_semihost_cmdline(char *buf, uint32_t size);

/* SYS_EXIT_EXTENDED (ADP_Stopped_ApplicationExit, code): ends the program; never returns. */
__attribute__((noreturn)) void cm_semihost_exit(uint32_t code);

#endif /* CM_SEMIHOST_H */
