/*
 * contour_host.c: lissom-contour-host, the host twin of the contour part of lissom-selftest.elf. Runs the same
 * contour program (contour_prog.h) on the host's float core, one lsm_contour_cycle per cycle, and prints the same
 * report lines as the image ("contour ...", "contour_stats ...", "contour_sample ..."), which
 * tests/py/test_arm_image.py and scripts/arm_check.sh compare. Exit status 0 if the program ran to its end,
 * 1 otherwise. Usage: lissom-contour-host (no arguments).
 */
#include <stdio.h>

#include "contour_prog.h"

static void put_line(const char *line, void *ctx)
{
    (void)ctx;
    puts(line);
}

int main(void)
{
    static lsm_contour c;
    if (lsm_contour_init(&c) != LSM_OK) {
        fprintf(stderr, "lissom-contour-host: init failed\n");
        return 1;
    }
    lsm_contour_result r;
    do
        r = lsm_contour_cycle(&c);
    while (r == LSM_CONTOUR_RUNNING);
    printf("lissom-contour-host: float core, %u cycles\n", (unsigned)c.cycles);
    lsm_contour_report(&c, put_line, NULL);
    return r == LSM_CONTOUR_DONE ? 0 : 1;
}
