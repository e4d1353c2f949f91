/*
 * lsm_test_geom.h: the centre of an arc (geom.h) in double, whatever lsm_real is. The double build stores the
 * centre; the float build stores the start point, and the centre of that float arc (start, r, phi0 exactly as
 * stored) is computed here in double, so that distances to it are not limited by a float centre. Header-only.
 */
#ifndef LSM_TEST_GEOM_H
#define LSM_TEST_GEOM_H

#include <math.h>

#include "geom.h"

static inline void test_arc_centre(const lsm_geom *g, double c[3])
{
    const lsm_geom_arc *a = &g->u.arc;
#if LSM_REAL_IS_FLOAT
    const double cp = cos((double)a->phi0_rad), sp = sin((double)a->phi0_rad);
    for (int i = 0; i < 3; i++)
        c[i] = (double)a->start_mm[i] - (double)a->radius_mm * (cp * (double)a->e1[i] + sp * (double)a->e2[i]);
#else
    for (int i = 0; i < 3; i++)
        c[i] = a->centre_mm[i];
#endif
}

#endif
