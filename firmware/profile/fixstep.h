/*
 * fixstep.h: integer-only per-cycle evaluator (lsm_fixstep_*): positions as int64 counts, no floating point
 * and no trigonometry at run time. With -DLSM_INTEGER_ONLY the core for such a target needs only this module
 * (fixstep.c uses integers only; tests/arm check that no float routine is linked from it).
 *
 * Model (cycle units: tau = m cycles). Within each phase of a move (move.h), every axis is
 *     p(m) = P0 + V0 m + A0h m² + J12 m³ + sgn (JK8 m - JK16 sin(pi m / n1))       [sin² phases]
 *     p(m) = P0 + V0 m + A0h m² + J6 m³                                            [constant-jerk phases]
 * which is the closed form of scurve.h with 1/(8w²) = n1²/(2 pi²) and 1/(16w³) = n1³/(2 pi³) folded into the
 * per-axis coefficients JK8 = J n1²/(2 pi²), JK16 = J n1³/(2 pi³) (sgn = -1 rise, +1 fall). All coefficients are
 * signed Q32.32 fixed point in counts, counts/cycle, ... (the cubic coefficient in Q52, multiplied through a
 * 128-bit intermediate made of 32x32 products, so m³ up to 2^42 keeps its precision). The rest is evaluated with wrapping 64-bit
 * integer arithmetic, which is exact modulo 2^64, so intermediate terms may overflow as long as the position
 * itself fits (|p| < 2^31 counts). sin(pi m / n1) comes from a Q30 rotation recurrence restarted at every
 * phase. The final cycle outputs the exact target count. The program is made from a planned move by
 * lsm_fixprog_compile (fixprog.h), on a machine with floating point.
 *
 * Error budget (per cycle, in counts): coefficient rounding 2^-33 (m + m²) + 2^-53 m³ with the limits below,
 * plus the rotation's drift; the tests hold every cycle within 1 count of the double reference.
 * Limits (else compile returns LSM_E_RANGE): phases with jerk or acceleration at most 16384 cycles;
 * positions within +/-2^31 counts.
 */
#ifndef LSM_FIXSTEP_H
#define LSM_FIXSTEP_H

#include <stdbool.h>
#include <stdint.h>

#include "lsm_config.h"
#include "status.h"

/* Compile-time settings (LSM_MAX_AXES): lsm_config.h. */
#define LSM_FIX_PHASES 15
#define LSM_FIX_MAX_RAMP_CYCLES 16384u

typedef struct lsm_fix_axis_phase {
    int64_t p0_q32;   /* start position, counts (Q32) */
    int64_t v0_q32;   /* counts/cycle */
    int64_t a0h_q32;  /* a0 / 2, counts/cycle² */
    int64_t j3_q52;   /* J/12 (sin² phases) or J/6 (constant jerk), counts/cycle³, Q52 (|J/6| < 2048) */
    int64_t jk8_q32;  /* J n1² / (2 pi²), counts/cycle (sin² phases) */
    int64_t jk16_q32; /* J n1³ / (2 pi³), counts (sin² phases) */
} lsm_fix_axis_phase;

typedef struct lsm_fix_phase {
    uint32_t n_cycles;
    uint8_t shape;  /* 0 rise, 1 constant, 2 fall (lsm_phase_shape) */
    int32_t cd_q30; /* cos(pi / n1), Q30 */
    int32_t sd_q30; /* sin(pi / n1), Q30 */
} lsm_fix_phase;

typedef struct lsm_fixprog {
    uint8_t n_axes;
    uint32_t total_cycles;
    lsm_fix_phase phase[LSM_FIX_PHASES];
    lsm_fix_axis_phase ax[LSM_FIX_PHASES][LSM_MAX_AXES];
    int64_t target_counts[LSM_MAX_AXES];
} lsm_fixprog;

typedef struct lsm_fixstep {
    const lsm_fixprog *prog;
    uint32_t k; /* cycles emitted */
    uint8_t phase;
    uint32_t m; /* cycles into the phase */
    int32_t c_q30, s_q30;
} lsm_fixstep;

lsm_status lsm_fixstep_init(lsm_fixstep *g, const lsm_fixprog *prog);

/* Advances one cycle; writes every axis's position in counts. Returns false at and after the last cycle
 * (which outputs the exact target counts). */
bool lsm_fixstep_next(lsm_fixstep *g, int64_t *pos_counts);

#endif /* LSM_FIXSTEP_H */
