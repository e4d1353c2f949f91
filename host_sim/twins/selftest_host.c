/*
 * selftest_host.c: lissom-selftest-host, the host twin of the Cortex-M image lissom-selftest.elf. It runs the
 * same self-test program (selftest_prog.h) on the host's float core and prints the same "part" and "sample"
 * lines as the image, which tests/py/test_arm_image.py compares. Usage: lissom-selftest-host (no arguments).
 */
#include <stdio.h>

#include "selftest_prog.h"

int main(void)
{
    static lsm_selftest st;
    lsm_selftest_init(&st);
    uint32_t ticks = 0;
    for (;;) {
        while (lsm_selftest_plan(&st) == LSM_SELFTEST_PLANNED) {
        }
        if (lsm_selftest_tick(&st) == LSM_SELFTEST_DONE)
            break;
        ticks++;
    }
    printf("lissom-selftest-host: float core, %u ticks, %u idle\n", (unsigned)ticks, (unsigned)st.idle_ticks);
    for (uint32_t p = 0; p < st.n_parts; p++) {
        const lsm_selftest_part *r = &st.result[p];
        printf("part %s plans=%u cycles=%u plan_hash=0x%08x cycle_hash=0x%08x\n", r->name, (unsigned)r->n_plans,
               (unsigned)r->n_cycles, (unsigned)r->plan_hash, (unsigned)r->cycle_hash);
    }
    for (uint32_t i = 0; i < st.n_samples; i++) {
        const lsm_selftest_sample *s = &st.sample[i];
        printf("sample %u %u %u %u 0x%08x 0x%08x 0x%08x 0x%08x\n", (unsigned)s->part, (unsigned)s->item,
               (unsigned)s->cycle, (unsigned)s->axis, (unsigned)lsm_selftest_bits(s->v[0]),
               (unsigned)lsm_selftest_bits(s->v[1]), (unsigned)lsm_selftest_bits(s->v[2]),
               (unsigned)lsm_selftest_bits(s->v[3]));
    }
    printf("samples=%u lost=%u\n", (unsigned)st.n_samples, (unsigned)st.samples_lost);
    return 0;
}
