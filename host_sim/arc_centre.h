/*
 * arc_centre.h: the centre of an arc in double, for host-side checks (deviation, sampling). The float build stores
 * an arc's exact start point rather than its centre (geom.h); the centre is computed here in double from the
 * stored start, radius and phi0, so that distances are not limited by a float centre. The double build stores the
 * centre and it is returned as it is. Header-only: used by host_sim and by the tests (tests/common/lsm_test_geom.h).
 */
#ifndef SIM_ARC_CENTRE_H
#define SIM_ARC_CENTRE_H

#include <math.h>

#include "geom.h"

static inline void sim_arc_centre_d(const lsm_geom_arc *a, double c[3])
{
    const double cp = cos((double)a->phi0_rad), sp = sin((double)a->phi0_rad);
    for (int i = 0; i < 3; i++)
        c[i] = (double)a->start_mm[i] - (double)a->radius_mm * (cp * (double)a->e1[i] + sp * (double)a->e2[i]);
}

#endif
