/*
 * lsm_test_geom.h: the centre of an arc (geom.h) in double, whatever lsm_real is. The double build stores the
 * centre; the float build stores the start point, and the centre of that float arc (start, r, phi0 exactly as
 * stored) is computed here in double, so that distances to it are not limited by a float centre. Header-only.
 */
#ifndef LSM_TEST_GEOM_H
#define LSM_TEST_GEOM_H

#include <math.h>

#include "arc_centre.h" /* host_sim/: the centre in double, shared with the simulator */
#include "geom.h"

static inline void test_arc_centre(const lsm_geom *g, double c[3])
{
    sim_arc_centre_d(&g->u.arc, c);
}

#endif
