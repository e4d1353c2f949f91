/*
 * lsm_config.h: every compile-time setting of the Lissom core, in one place, with its default, unit and meaning.
 *
 * How to change a setting: every default below is guarded by #ifndef, so it can be overridden on the compiler's
 * command line (-DLSM_GCODE_MAX_LINE=512) or in a project header named with -DLSM_CONFIG_HEADER="my_config.h",
 * which is included first. The component headers take their settings from here and define none of their own.
 * Build the whole core (every component library) with the same settings: they change struct sizes.
 *
 * Build switches (defined or not; no default value):
 *   LSM_REAL_FLOAT     `lsm_real` is float (the Cortex-M4F build, presets cortex-m4f and the *_f libraries);
 *                      otherwise double (the host reference). LSM_REAL_IS_FLOAT is 1 or 0 accordingly.
 *   LSM_INTEGER_ONLY   the integer-only evaluator (profile/fixstep.c) for targets without an FPU; see fixstep.h.
 *   LSM_CONFIG_HEADER  a project header with overrides (above).
 *
 * Not settings (they belong to the code's algorithms and are not meant to be overridden): the small-step region of
 * the clothoid stepper (LSM_CLOTHOID_FAST_*_RAD, clothoid.h), LSM_PIECE_PHASES (planner.h), and the private tuning
 * constants of each module (named, with their reasons, at the top of its .c file).
 *
 * Units everywhere: mm, s, rad (and derived: mm/s, mm/s^2, mm/s^3, mm/s^4); CANopen times in microseconds.
 */
#ifndef LSM_CONFIG_H
#define LSM_CONFIG_H

#ifdef LSM_CONFIG_HEADER
#include LSM_CONFIG_HEADER
#endif

#include <stdint.h>
#include <stddef.h>
#include <stdbool.h>

#ifdef LSM_REAL_FLOAT
typedef float lsm_real;
#define LSM_R(x) ((lsm_real)(x##f))
#define LSM_REAL_IS_FLOAT 1
#else
typedef double lsm_real;
#define LSM_R(x) ((lsm_real)(x))
#define LSM_REAL_IS_FLOAT 0
#endif

#define LSM_PI 3.14159265358979323846

/* ------------------------------------------------------------------------------------------------ base, profile */

/* The tick / background hand-off (lsm_atomic.h) on one core: 1 orders the shared accesses for the compiler only
 * (an interrupt and the code it interrupts see each other's stores in program order), 0 with C11 acquire/release
 * (a multi-core host, ThreadSanitizer). Default 1 on a bare-metal Cortex-M (__ARM_ARCH_7EM__, no OS), else 0;
 * unit: a switch. */
#ifndef LSM_HANDOFF_SINGLE_CORE
#if defined(__ARM_ARCH_7EM__) && !defined(__linux__)
#define LSM_HANDOFF_SINGLE_CORE 1
#else
#define LSM_HANDOFF_SINGLE_CORE 0
#endif
#endif

/* Axes of one coordinated move (XYZ + ABC). Default 6; unit: axes. Sizes every per-axis array. */
#ifndef LSM_MAX_AXES
#define LSM_MAX_AXES 6
#endif

/* Largest |distance| of one move on one axis (profile/move.c). Default 1e7 (10 km); unit: mm. Beyond it positions
 * lose meaning in float; lsm_move_plan refuses longer moves. */
#ifndef LSM_MAX_DISTANCE_MM
#define LSM_MAX_DISTANCE_MM 1.0e7
#endif

/* ----------------------------------------------------------------------------------------------------------- path */

/* Arc construction from end points (geom.h): largest |r_start - r_end| accepted. Default 0.03; unit: mm. The arc
 * keeps the start radius, so its end lies at most this far from the programmed end. */
#ifndef LSM_GEOM_ARC_TOL_MM
#define LSM_GEOM_ARC_TOL_MM 0.03
#endif

/* Clothoid evaluation (clothoid.h): the largest turning bound Phi = |kappa0| s + |c| s^2 / 2 evaluated with the
 * piecewise Taylor series; above it the Fresnel form. Default 32; unit: rad. */
#ifndef LSM_CLOTHOID_SERIES_PHASE_RAD
#define LSM_CLOTHOID_SERIES_PHASE_RAD 32.0
#endif
/* Most Taylor terms per series (clothoid.h; the sums stop earlier, at epsilon). Default 40; unit: terms. */
#ifndef LSM_CLOTHOID_MAX_TERMS
#define LSM_CLOTHOID_MAX_TERMS 40
#endif
/* Clothoid fit (clothoid.h, paper section IV): Newton iteration cap. Default 40; unit: iterations. */
#ifndef LSM_CLOTHOID_FIT_MAX_ITER
#define LSM_CLOTHOID_FIT_MAX_ITER 40
#endif
/* Clothoid fit: the largest turning |kappa0| s + |c| s^2 / 2 a candidate may have (the fit's domain). Default 25;
 * unit: rad. */
#ifndef LSM_CLOTHOID_FIT_MAX_PHASE_RAD
#define LSM_CLOTHOID_FIT_MAX_PHASE_RAD 25.0
#endif
/* Clothoid fit: step cap of the bracketed fallback when Newton stalls. Default 170; unit: steps. The bracket at
 * least halves every 3 steps, so 170 narrow the widest bracket (relative width 1) to double rounding (2^-52). */
#ifndef LSM_CLOTHOID_FIT_BRACKET_MAX_ITER
#define LSM_CLOTHOID_FIT_BRACKET_MAX_ITER 170
#endif

/* G2 paths (g2path.h): largest gap between consecutive elements of a contour. Default 1e-3; unit: mm. */
#ifndef LSM_G2PATH_GAP_TOL_MM
#define LSM_G2PATH_GAP_TOL_MM 1e-3
#endif

/* Corner smoothing (corner.h): largest distance between the end of block 1 and the start of block 2. Default 1e-3;
 * unit: mm. */
#ifndef LSM_CORNER_GAP_TOL_MM
#define LSM_CORNER_GAP_TOL_MM 1e-3
#endif
/* Corner smoothing: largest part of an arc's turning a trim may take. Default 0.75; unit: rad. */
#ifndef LSM_CORNER_MAX_ARC_TRIM_RAD
#define LSM_CORNER_MAX_ARC_TRIM_RAD 0.75
#endif
/* Corner smoothing: the scale search stops once the deviation is within [LSM_CORNER_ACCEPT, 1] of the tolerance
 * (or the trims limit the size). Default 0.9; unit: share of the tolerance. Closer to 1 uses more of the tolerance
 * (lower curvature) at the price of more iterations for corners with arcs. */
#ifndef LSM_CORNER_ACCEPT
#define LSM_CORNER_ACCEPT 0.9
#endif
/* Corner smoothing: default trim limit of each block. Default 0.49; unit: share of the block's length (two corners
 * per block must fit). */
#ifndef LSM_CORNER_DEFAULT_TRIM_FRACTION
#define LSM_CORNER_DEFAULT_TRIM_FRACTION 0.49
#endif
/* Corner smoothing: tangent angles closer than this are "the same direction" (collinear) or, from pi, a reversal.
 * Default 1e-5 (float), 1e-9 (double); unit: rad. */
#ifndef LSM_CORNER_ANGLE_EPS_RAD
#if LSM_REAL_IS_FLOAT
#define LSM_CORNER_ANGLE_EPS_RAD 1e-5
#else
#define LSM_CORNER_ANGLE_EPS_RAD 1e-9
#endif
#endif

/* Arc fitting (arcfit.h): most points of one run, pending in the planner until the run is emitted. Default 32;
 * unit: points. */
#ifndef LSM_ARCFIT_MAX
#define LSM_ARCFIT_MAX 32
#endif

/* ----------------------------------------------------------------------------------------------------------- plan */
/* Defaults of lsm_planner_config (planner.h); each run may set its own in the config. */

/* rho: share of A and J the path's curvature may use at the feed cap. Default 0.9; unit: share. */
#ifndef LSM_PLANNER_CAP_MARGIN
#define LSM_PLANNER_CAP_MARGIN 0.9
#endif
/* A valley of the feed cap is a node if it is this much below its surroundings. Default 0.05; unit: relative. */
#ifndef LSM_PLANNER_NODE_HYST
#define LSM_PLANNER_NODE_HYST 0.05
#endif
/* A drop of the cap by this much from one block to the next is a node. Default 0.25; unit: relative. */
#ifndef LSM_PLANNER_NODE_DROP
#define LSM_PLANNER_NODE_DROP 0.25
#endif
/* Share of the blend tolerance for fitting arcs through dense polylines. Default 0.5; unit: share. */
#ifndef LSM_PLANNER_FIT_SHARE
#define LSM_PLANNER_FIT_SHARE 0.5
#endif
/* Largest part of a block one corner transition may take. Default 0.5; unit: share of the block's length. */
#ifndef LSM_PLANNER_TRIM_SHARE
#define LSM_PLANNER_TRIM_SHARE 0.5
#endif

/* ---------------------------------------------------------------------------------------------------------- gcode */

/* Longest line accepted (gcode.h), not counting the line ending. Default 256; unit: bytes. */
#ifndef LSM_GCODE_MAX_LINE
#define LSM_GCODE_MAX_LINE 256
#endif
/* Largest magnitude of any number and of any resulting coordinate: beyond it a value is "too large to represent"
 * (LSM_E_GC_NUMBER_RANGE). Default 1e6; unit: mm, deg, mm/min or in/min. In float builds keep in mind that the
 * spacing of floats at 1e6 is 0.06. */
#ifndef LSM_GCODE_MAX_ABS
#define LSM_GCODE_MAX_ABS 1.0e6
#endif
/* Centre-form arcs: largest start/end radius difference, absolute. Default 2 * 0.01 * sqrt(2) (LinuxCNC);
 * unit: mm. */
#ifndef LSM_GCODE_ARC_ABS_TOL_MM
#define LSM_GCODE_ARC_ABS_TOL_MM 0.028284271247461901
#endif
/* Centre-form arcs: largest start/end radius difference, relative. Default 0.001 (LinuxCNC: 0.1 %); unit: share of
 * the radius. */
#ifndef LSM_GCODE_ARC_REL_TOL
#define LSM_GCODE_ARC_REL_TOL 0.001
#endif
/* Smallest arc radius, and the amount by which a radius-form chord may exceed the diameter. Default 0.00127
 * (LinuxCNC: 0.00005 inch); unit: mm. */
#ifndef LSM_GCODE_ARC_RADIUS_TOL_MM
#define LSM_GCODE_ARC_RADIUS_TOL_MM 0.00127
#endif
/* Motion blocks one line can produce. Default 2 (G28/G30: the intermediate point, then home); unit: blocks. */
#ifndef LSM_GCODE_MAX_BLOCKS
#define LSM_GCODE_MAX_BLOCKS 2
#endif
/* Machine-function events one line can produce (S T M6 M3 M7 M8 G4 G43 M0 M2 and the M5 M9 of an end). Default 12;
 * unit: events. */
#ifndef LSM_GCODE_MAX_EVENTS
#define LSM_GCODE_MAX_EVENTS 12
#endif
/* Largest S (rpm), T and H: beyond it a value is refused (LSM_E_GC_BAD_VALUE). Default 99999; unit: rpm or a
 * tool / offset number. */
#ifndef LSM_GCODE_MAX_TOOL
#define LSM_GCODE_MAX_TOOL 99999
#endif
/* Largest P (number of turns) of an arc. Default 1000; unit: turns. */
#ifndef LSM_GCODE_MAX_TURNS
#define LSM_GCODE_MAX_TURNS 1000
#endif

/* -------------------------------------------------------------------------------------------------------- canopen */

/* SDO buffer (canopen.h): the largest object transferred in segments (path block 48 bytes, device name). Default
 * 64; unit: bytes. */
#ifndef LSM_CANOPEN_SDO_BUF
#define LSM_CANOPEN_SDO_BUF 64
#endif
/* SDO request frames in flight from the tick to the background SDO server, and responses back (canopen.h, with
 * sdo_background). A CiA 301 client has one confirmed request outstanding per channel (two when it aborts and starts
 * again at once), so 8 is never reached by a client that keeps the protocol. Default 8; unit: frames; power of 2. */
#ifndef LSM_CANOPEN_SDO_QUEUE
#define LSM_CANOPEN_SDO_QUEUE 8u
#endif
/* Default time a segmented SDO transfer may wait for its next segment (co_sdo.h). Default 1 000 000; unit: us. */
#ifndef LSM_CO_SDO_TIMEOUT_US
#define LSM_CO_SDO_TIMEOUT_US 1000000u
#endif
/* Heartbeat consumer entries (co_nmt.h, 0x1016 sub-indices). Default 2; unit: entries. */
#ifndef LSM_CO_HB_CONSUMERS
#define LSM_CO_HB_CONSUMERS 2
#endif
/* Receive and transmit PDOs (co_pdo.h). Default 4 each; unit: PDOs. */
#ifndef LSM_CO_N_RPDO
#define LSM_CO_N_RPDO 4
#endif
#ifndef LSM_CO_N_TPDO
#define LSM_CO_N_TPDO 4
#endif
/* Most objects mapped into one PDO (co_pdo.h). Default 8 (CAN's 8 bytes); unit: mapping entries. */
#ifndef LSM_CO_PDO_MAX_MAP
#define LSM_CO_PDO_MAX_MAP 8
#endif
/* EMCY (co_emcy.h): entries of the error history 0x1003. Default 8; unit: entries. */
#ifndef LSM_CO_EMCY_HISTORY
#define LSM_CO_EMCY_HISTORY 8
#endif
/* EMCY: error conditions tracked as active at once. Default 12; unit: conditions. */
#ifndef LSM_CO_EMCY_ACTIVE
#define LSM_CO_EMCY_ACTIVE 12
#endif

#endif /* LSM_CONFIG_H */
