/* bench_planner.h: the look-ahead planner and interpolator benchmarks of lissom-bench.elf (bench_planner.c). */
#ifndef BENCH_PLANNER_H
#define BENCH_PLANNER_H

#include <stdbool.h>

/* Prints the "bench", "size" and "note" lines; false if a program did not run to its end. */
bool bench_planner(void);

/* Only the append benchmark (lissom-bench-ramp.elf, built with BENCH_RAMP_WRAP: also times the planner's ramp
 * sizing and phase evaluation inside the appends). */
bool bench_planner_append(void);

#endif /* BENCH_PLANNER_H */
