/* cm_semihost.c: ARM semihosting calls (see cm_semihost.h). */
#include "cm_semihost.h"

#define SEMI_SYS_WRITE0 0x04
#define SEMI_SYS_GET_CMDLINE 0x15
#define SEMI_SYS_EXIT_EXTENDED 0x20
#define SEMI_ADP_STOPPED_APPLICATION_EXIT 0x20026u

static int semi_call(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void cm_semihost_write0(const char *s)
{
    (void)semi_call(SEMI_SYS_WRITE0, s);
}

void cm_semihost_exit(uint32_t code)
{
    const uint32_t block[2] = {SEMI_ADP_STOPPED_APPLICATION_EXIT, code};
    (void)semi_call(SEMI_SYS_EXIT_EXTENDED, block);
    for (;;) {
    }
}

bool cm_semihost_cmdline(char *buf, uint32_t size)
{
    if (buf == NULL || size < 2u)
        return false;
    uint32_t block[2] = {(uint32_t)(uintptr_t)buf, size - 1u};
    if (semi_call(SEMI_SYS_GET_CMDLINE, block) != 0)
        return false;
    buf[block[1] < size ? block[1] : size - 1u] = '\0';
    return true;
}
