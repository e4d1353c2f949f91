/*
 * lsm_config.h: compile-time configuration of the Lissom core.
 *
 * Real type: `lsm_real` is `double` unless LSM_REAL_FLOAT is defined (the Cortex-M4F build).
 * Units everywhere: mm, s, rad (and derived: mm/s, mm/s^2, mm/s^3, mm/s^4).
 * A project may supply its own overrides with -DLSM_CONFIG_HEADER="my_config.h"; every default
 * below is guarded by #ifndef so it can be overridden there or on the command line.
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

/* Maximum number of axes in one coordinated move (XYZ + ABC). */
#ifndef LSM_MAX_AXES
#define LSM_MAX_AXES 6
#endif

#define LSM_PI 3.14159265358979323846

#endif /* LSM_CONFIG_H */
