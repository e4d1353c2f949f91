/*
 * bench_ramp_main.c: lissom-bench-ramp.elf, the append benchmark of bench_planner.c built with BENCH_RAMP_WRAP:
 * besides corner smoothing and arc fitting, it times the planner's ramp sizing (lsm_scurve_strict_intervals) and
 * phase evaluation (lsm_phase_end / lsm_phase_advance) inside each append, i.e. the ramp work of the backward
 * pass. A separate image because these wrappers would add instructions to the figures of lissom-bench.elf; its
 * own append totals include them (about 25 instructions per wrapped call) and are not the reference figures.
 * Output: "bench" lines as lissom-bench.elf, then "bench PASS" (exit 0) or "bench FAIL" (exit 1).
 */
#include "bench_planner.h"
#include "cm_board.h"
#include "cm_out.h"

int main(void)
{
    CM_SYST_CSR = 0u;
    CM_SYST_RVR = CM_SYST_MAX_RELOAD;
    CM_SYST_CVR = 0u;
    CM_SYST_CSR = CM_SYST_CSR_ENABLE | CM_SYST_CSR_CLKSOURCE; /* free running, no interrupt */
    cm_out_str(
        "lissom-bench-ramp: the planner's ramp work inside appends, -icount shift=0, instructions = 40 x SysTick\n");
    const bool ok = bench_planner_append();
    cm_out_str(ok ? "bench PASS\n" : "bench FAIL\n");
    return ok ? 0 : 1;
}
