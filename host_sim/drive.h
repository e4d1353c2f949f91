/*
 * drive.h: a simulated servo drive for one axis (host only, sim_drive_*).
 *
 * Control (a cascaded servo, as in an industrial drive in cyclic-synchronous-position mode):
 *
 *   x_set --(+)--[ kv ]--(+)--(+)--[ kp (1 + 1/(Ti s)) ]--(+)--[clamp +-i_max]--> i_cmd
 *            |            ^    |                             ^                     |
 *   x_load --+      vff * v_ff |       aff * (m_m + m_l) a_ff / kf     i' = (i_cmd - i) / tau
 *   (measured, optional        +-- v_motor                                         |
 *    encoder quantisation)                                               F = kf * i on the motor
 *
 *   The setpoint given once per control cycle is interpolated linearly over the cycle, the
 *   feed-forward values are held over it, and the loops run at the drive's servo period (the
 *   integration substep, typically 62.5 us = 16 kHz). With vff = aff = 1 the loops only have to
 *   correct what the rigid-body model misses: friction and the excitation of the resonance.
 *   The velocity integrator stops integrating while the current command is clamped (anti-windup).
 *
 *   With motor_feedback the position loop is closed on x_motor instead (semi-closed loop): the load is
 *   then outside the loop, and its vibration against the motor is only damped by the coupling.
 *
 * Plant (two-mass model: motor and load coupled by a spring and a damper; the load is measured):
 *
 *   m_m x_m'' = kf i - k (x_m - x_l) - c (x_m' - x_l')
 *   m_l x_l'' =        k (x_m - x_l) + c (x_m' - x_l') - b x_l' - F_c tanh(x_l' / v_eps)
 *
 *   Coulomb friction is regularised by tanh with v_eps = max(1e-4 m/s, 2 F_c dt / m_l) (the second
 *   term keeps the explicit integration stable). The plant is integrated with classical RK4 over
 *   each substep with the current command held. Everything is deterministic (no noise, no clock).
 *
 * Analytic modes of the mechanics (sim_drive_modes_analytic):
 *   resonance (motor free)        w_r = sqrt(k (m_m + m_l) / (m_m m_l)),  zeta_r = c / (2 sqrt(k mu)),
 *                                 mu = m_m m_l / (m_m + m_l);  damped w_d = w_r sqrt(1 - zeta_r^2)
 *   anti-resonance (motor locked) w_a = sqrt(k / m_l)
 *
 * Units: parameters are SI, with the unit in each name; positions and velocities at the API are in
 * mm and mm/s. The model is the linear equivalent of a rotary motor on a ball screw of lead L:
 * force_const_N_A = Kt 2 pi / L and motor_mass_kg = J_rotor (2 pi / L)^2. For a rotary axis
 * (params.rotary = true) the API positions are in rad (and rad/s) and the SI quantities read as
 * rad, kg m^2 (for kg), N m (for N) and N m s/rad (for N s/m).
 */
#ifndef LSM_SIM_DRIVE_H
#define LSM_SIM_DRIVE_H

#include <stdbool.h>
#include <stdint.h>

#include "status.h"

/* The shortest servo period a drive may have: real drives close their loops at 4-32 kHz, and a shorter period only
 * multiplies the substeps per cycle (cycle / period of them; a 1e-50 s period would overflow their count). */
#define SIM_DRIVE_MIN_SERVO_PERIOD_S 1e-6

typedef struct sim_drive_params {
    bool rotary; /* API positions in rad instead of mm (see above) */
    /* position loop, closed on the load position */
    double kv_1_s;   /* position gain: v_cmd = kv (x_set - x_meas) + vff_gain v_ff [1/s] */
    double vff_gain; /* velocity feed-forward gain, 0 (none) .. 1.5 (1 = full) */
    double aff_gain; /* acceleration (current) feed-forward gain, 0 (none) .. 1.5 (1 = full) */
    /* velocity loop, closed on the motor velocity */
    double vel_kp_A_s_m; /* proportional gain [A/(m/s)] */
    double vel_ti_s;     /* integral time [s]; 0 = proportional only */
    /* current loop */
    double current_tau_s;   /* first-order lag time constant of the closed current loop [s] */
    double current_max_A;   /* current limit [A] */
    double force_const_N_A; /* motor force per ampere, referred to the axis [N/A] */
    /* mechanics */
    double motor_mass_kg; /* rotor and screw inertia referred to the axis [kg] */
    double load_mass_kg;  /* table / carriage / gantry [kg] */
    double stiffness_N_m; /* coupling spring [N/m] */
    double damping_N_s_m; /* coupling damper [N s/m] */
    double viscous_N_s_m; /* viscous friction on the load [N s/m] */
    double coulomb_N;     /* Coulomb friction on the load [N] */
    /* simulation */
    double servo_period_s;        /* loop rate and integration substep [s] */
    double encoder_counts_per_mm; /* position encoder resolution [counts/mm or counts/rad]; 0 = ideal */
    bool motor_feedback;          /* close the position loop on the motor (semi-closed loop: rotary encoder,
                                     no linear scale) instead of the load; default false. Not a machine-file
                                     key. The following error reported is always setpoint - load. */
} sim_drive_params;

typedef struct sim_drive {
    sim_drive_params p;
    double cycle_s;   /* control cycle (the setpoint period) */
    uint32_t n_sub;   /* substeps per cycle */
    double dt_s;      /* substep = cycle_s / n_sub (<= servo_period_s) */
    double unit_m;    /* metres per API unit: 1e-3 (mm) or 1 (rad) */
    double v_eps_m_s; /* Coulomb regularisation velocity */
    /* state, SI */
    double x_m, v_m, x_l, v_l, i_A;
    double integ_m_s;  /* velocity-loop integrator, in m/s (i = kp (e + integ)) */
    double set_prev_m; /* setpoint at the end of the previous cycle */
    double set_m;      /* setpoint of the last cycle */
    double i_cmd_A;    /* last current command (after the clamp) */
    bool limited;      /* the current command was clamped during the last cycle */
    uint64_t cycles;
} sim_drive;

typedef struct sim_drive_state {
    double load_pos;        /* actual (load) position [mm or rad] */
    double load_vel;        /* [mm/s or rad/s] */
    double load_acc;        /* [mm/s^2 or rad/s^2] */
    double motor_pos;       /* [mm or rad] */
    double motor_vel;       /* [mm/s or rad/s] */
    double setpoint;        /* last setpoint [mm or rad] */
    double following_error; /* setpoint - load_pos [mm or rad] */
    double current_A;       /* actual current */
    double current_cmd_A;   /* last current command (clamped) */
    bool current_limited;   /* the clamp was active during the last cycle */
} sim_drive_state;

typedef struct sim_drive_modes {
    double f_res_hz;        /* undamped resonance, motor free */
    double f_res_damped_hz; /* damped resonance (what a free oscillation shows) */
    double zeta_res;        /* damping ratio of the resonance */
    double f_antires_hz;    /* anti-resonance (load against a locked motor) */
} sim_drive_modes;

/* A plausible axis: 0.4 kW servo on a 20 mm-lead screw, 45 kg carriage, resonance near 100 Hz
 * (linear), or a rotary table with a 50:1 gear (rotary). */
void sim_drive_params_default(sim_drive_params *p, bool rotary);

/* Checks every parameter and the cycle. On error returns the status and, if bad_field is not NULL,
 * the name of the offending field ("cycle_s" for the cycle):
 *   LSM_E_NULL; LSM_E_NAN / LSM_E_INF for a non-finite value; LSM_E_CYCLE for a cycle <= 0;
 *   LSM_E_LIMIT for a gain, mass, time constant, stiffness or current limit <= 0 (vel_ti_s may be 0);
 *   LSM_E_ARG for a negative damping/friction/encoder value, vff_gain or aff_gain outside [0, 1.5], or a servo
 *   period too long for the dynamics (it must be <= 0.5 / w_r, <= current_tau_s and <= cycle_s). */
lsm_status sim_drive_validate(const sim_drive_params *p, double cycle_s, const char **bad_field);

/* Validates and starts at rest at pos (mm or rad), spring relaxed, setpoint = pos. */
lsm_status sim_drive_init(sim_drive *d, const sim_drive_params *p, double cycle_s, double pos);

/* One control cycle in position mode: the setpoint for the end of this cycle (mm or rad) and an
 * optional velocity feed-forward (mm/s or rad/s; pass 0 for none; it is scaled by vff_gain).
 * Writes the actual load position at the end of the cycle. LSM_E_NULL, LSM_E_NAN, LSM_E_INF.
 * Same as sim_drive_step_ff with acc_ff = 0. */
lsm_status sim_drive_step(sim_drive *d, double setpoint, double vel_ff, double *actual);

/* The same with an acceleration feed-forward (mm/s^2 or rad/s^2), scaled by aff_gain and turned into
 * current through the rigid-body model: i_ff = aff_gain (m_m + m_l) acc_ff / kf. */
lsm_status sim_drive_step_ff(sim_drive *d, double setpoint, double vel_ff, double acc_ff, double *actual);

/* One control cycle in current (torque) mode: the loops are bypassed and i_cmd (A, clamped to the
 * limit) goes straight to the current loop. For identification and tests. */
lsm_status sim_drive_step_current(sim_drive *d, double i_cmd_A, double *actual);

void sim_drive_get_state(const sim_drive *d, sim_drive_state *s);

/* Closed-loop step test: a step of `step` (mm or rad) held for duration_s at the given cycle. */
typedef struct sim_drive_step_stats {
    double overshoot;   /* (peak - step) / step */
    double settle_s;    /* last time the error was outside 2 % of the step */
    double final_error; /* step - position at the end */
    double max_error;   /* largest |step - position| over the last quarter of the test */
    bool settled;       /* max_error <= 2 % of the step (the loop is stable and damped) */
} sim_drive_step_stats;

/* Runs the step test on a fresh drive (validation errors as sim_drive_init). Parameters that pass
 * sim_drive_validate can still make an unstable loop (e.g. a resonance below the velocity-loop
 * bandwidth); the machine loader uses this to reject them. */
lsm_status sim_drive_step_test(const sim_drive_params *p, double cycle_s, double step, double duration_s,
                               sim_drive_step_stats *out);

void sim_drive_modes_analytic(const sim_drive_params *p, sim_drive_modes *m);

#endif /* LSM_SIM_DRIVE_H */
