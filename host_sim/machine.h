/*
 * machine.h: machine description files for lissom-sim (host only, sim_machine_*).
 *
 * A machine file is strict JSON (see json.h and docs/machine_file.md):
 *
 *   { "format": "lissom-machine-1", "name": "router", "cycle_s": 0.001, "lookahead_blocks": 64,
 *     "blend_tol_mm": 0.02,
 *     "axes": [ { "name": "X", "v_max_mm_s": 250, "a_max_mm_s2": 3000, "j_max_mm_s3": 60000,
 *                 "snap_max_mm_s4": 1.2e7, "counts_per_mm": 1000,
 *                 "drive": { "load_mass_kg": 45, ... } }, ... ] }
 *
 * Linear axes (X Y Z) take their limits in mm, mm/s ... mm/s^4 and counts/mm. Rotary axes (A B C)
 * take them in degrees (v_max_deg_s ... snap_max_deg_s4, counts_per_deg), as in G-code; the loader
 * converts them to rad. In the loaded struct every limit is in the axis unit u (mm for a linear
 * axis, rad for a rotary one): field suffixes _u_s, _u_s2 ... mean u/s, u/s^2 ...
 * Each axis may carry a "drive" object with any sim_drive_params field (drive.h); missing fields take
 * sim_drive_params_default() for the axis kind, and the drive's encoder resolution is the axis's
 * counts per unit. An optional "comment" string is allowed in every object. Any other key is an
 * error naming the key; so is a missing required key, a wrong type, or a value out of range.
 */
#ifndef LSM_SIM_MACHINE_H
#define LSM_SIM_MACHINE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "drive.h"

#define SIM_MACHINE_MAX_AXES 6
#define SIM_MACHINE_FORMAT "lissom-machine-1"
#define SIM_MACHINE_MAX_FILE_BYTES (1u << 20)

typedef enum sim_machine_status {
    SIM_MACHINE_OK = 0,
    SIM_MACHINE_E_IO = -1,          /* the file cannot be read, or is larger than 1 MiB */
    SIM_MACHINE_E_JSON = -2,        /* not strict JSON (message has line and column) */
    SIM_MACHINE_E_FORMAT = -3,      /* "format" is missing or not SIM_MACHINE_FORMAT */
    SIM_MACHINE_E_UNKNOWN_KEY = -4, /* a key the format does not define (or a linear key on a rotary axis) */
    SIM_MACHINE_E_MISSING_KEY = -5, /* a required key is absent */
    SIM_MACHINE_E_TYPE = -6,        /* a value has the wrong JSON type */
    SIM_MACHINE_E_VALUE = -7,       /* a number is out of its range (zero/negative limit, cycle, ...) */
    SIM_MACHINE_E_AXES = -8,        /* no axes, more than SIM_MACHINE_MAX_AXES, a bad or repeated name */
    SIM_MACHINE_E_DRIVE = -9        /* the drive parameters fail sim_drive_validate (field named) */
} sim_machine_status;

typedef struct sim_machine_axis {
    char name;              /* 'X' 'Y' 'Z' 'A' 'B' 'C' */
    int index;              /* G-code axis index: X=0 .. C=5 (see gcode.h) */
    bool rotary;            /* unit u = rad (else mm) */
    double v_max_u_s;       /* velocity limit [u/s] */
    double a_max_u_s2;      /* acceleration limit [u/s^2] */
    double j_max_u_s3;      /* jerk limit [u/s^3] */
    double snap_max_u_s4;   /* snap (jerk derivative) limit [u/s^4] */
    double counts_per_u;    /* encoder / step resolution [counts/u] */
    sim_drive_params drive; /* the simulated drive of this axis */
} sim_machine_axis;

typedef struct sim_machine {
    char name[64];
    char description[256];
    double cycle_s;       /* control (interpolation) cycle [s] */
    int lookahead_blocks; /* planner look-ahead depth [blocks] */
    double blend_tol_mm;  /* default blend tolerance (G64 without P) [mm] */
    int n_axes;
    sim_machine_axis axes[SIM_MACHINE_MAX_AXES]; /* in file order */
    uint8_t axis_mask;                           /* bit k set: G-code axis k exists (for lsm_gcode_options.axis_mask) */
} sim_machine;

/* Load from a file / from text. `source` names the text in messages (e.g. the file name). On error
 * the message (if err != NULL) reads like "router.json:12:9: axes[0]: unknown key \"v_mx_mm_s\"".
 * *m is only written on success. */
sim_machine_status sim_machine_load_file(const char *path, sim_machine *m, char *err, size_t errlen);
sim_machine_status sim_machine_load_text(const char *text, size_t len, const char *source, sim_machine *m, char *err,
                                         size_t errlen);

/* The axis with this name ('x' or 'X'), or NULL. */
const sim_machine_axis *sim_machine_axis_by_name(const sim_machine *m, char name);

const char *sim_machine_status_str(sim_machine_status st);

#endif /* LSM_SIM_MACHINE_H */
