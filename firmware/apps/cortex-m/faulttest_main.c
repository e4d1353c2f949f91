/*
 * faulttest_main.c: lissom-faulttest.elf, checks the fault path of startup.c. It reads from an unmapped
 * address; the BusFault escalates to HardFault, whose handler prints "HardFault: pc=... cfsr=..." and exits
 * with code 99. scripts/arm_check.sh expects exactly that (a broken handler would hang until the timeout).
 */
#include <stdint.h>

#include "cm_out.h"

int main(void)
{
    cm_out_str("lissom-faulttest: reading 0xF0000000 (unmapped), expect HardFault and exit 99\n");
    const uint32_t v = *(volatile const uint32_t *)(uintptr_t)0xF0000000u;
    cm_out_str("no fault: ");
    cm_out_hex32(v);
    cm_out_char('\n');
    return 1;
}
