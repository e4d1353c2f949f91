/*
 * vpop.h: a VPOp-style offline reference planner (host only, sim_vpop_*), after Beudaert, Lavernhe, Tournier 2012
 * ("Maximum feedrate interpolator for multi-axis CNC machining with jerk constraints", section 2).
 *
 * Model. The path is q(s) (positions of up to 6 axes as a function of arc length s). Time is discretised with the
 * control cycle dt, and velocity, acceleration and jerk of every axis are the backward differences of the
 * positions (paper eq 6). At each step j+1 every axis i bounds its next position by intersecting
 *     |q_i(s) - q_i,j| <= V_i dt,  |q_i(s) - 2 q_i,j + q_i,j-1| <= A_i dt²,
 *     |q_i(s) - 3 q_i,j + 3 q_i,j-1 - q_i,j-2| <= J_i dt³                                   (eqs 4-5, 6)
 * with s - s_j <= F dt (programmed feed) and s_j <= s <= L; the set of s that satisfies every axis is searched
 * on a grid finer than the jerk window (J dt³ / 4) and its ends refined by bisection: [s_min, s_max]. The
 * planner goes as fast as possible (s_max). When the set is empty, a dichotomy over the earlier steps finds the
 * latest step from which always taking s_min brings s' to 0 without an empty set; s_min is taken there, and the
 * planner goes on with s_max (paper Fig. 3). The constraints are the discrete ones, met exactly (the paper's own
 * VPOp allows a 120 % jerk overrun; this one allows none, up to the bisection tolerance of 1e-12 mm).
 * The motion ends at rest on s = L.
 *
 * Units: mm, s, rad (rotary axes).
 */
#ifndef LSM_SIM_VPOP_H
#define LSM_SIM_VPOP_H

#include <stddef.h>
#include <stdint.h>

#define SIM_VPOP_AXES 6

typedef struct sim_vpop_path {
    double length;                                           /* L (mm) */
    void (*eval)(void *ctx, double s, double q[SIM_VPOP_AXES]); /* positions at s in [0, L] */
    double (*feed)(void *ctx, double s);                     /* programmed feed at s (mm/s); NULL: no feed limit */
    void *ctx;
} sim_vpop_path;

typedef struct sim_vpop_limits {
    uint8_t axis_mask;                 /* axes constrained (and moving) */
    double v[SIM_VPOP_AXES], a[SIM_VPOP_AXES], j[SIM_VPOP_AXES];
} sim_vpop_limits;

typedef struct sim_vpop_stats {
    size_t steps;       /* setpoints */
    size_t evals;       /* path evaluations */
    size_t backtracks;  /* dichotomies run */
    size_t tests;       /* braking sequences simulated by the dichotomies */
} sim_vpop_stats;

/*
 * Plans the path; *s_out (malloc'd, *n_out values) is s at every cycle, the first one after t = 0 (s = 0 at t = 0,
 * at rest) and the last one L (at rest). Returns 0, or -1 (no motion found within max_steps, out of memory).
 */
int sim_vpop_plan(const sim_vpop_path *p, const sim_vpop_limits *lim, double dt, size_t max_steps, double **s_out,
                  size_t *n_out, sim_vpop_stats *st);

/* A clamped B-spline in the plane (X, Y), parametrised by arc length through a dense table (host helper). */
typedef struct sim_bspline {
    int degree;
    int n_ctrl;
    double knots[32];
    double ctrl[16][2];
    double *tab_u, *tab_s;  /* arc-length table */
    int n_tab;
    double length;
    double feed;            /* constant programmed feed (mm/s) */
} sim_bspline;

/* Builds the arc-length table (n_tab intervals, Gauss-Legendre). Returns 0 or -1. */
int sim_bspline_init(sim_bspline *b, int degree, int n_ctrl, const double *knots, const double (*ctrl)[2],
                     double feed_mm_s, int n_tab);
void sim_bspline_free(sim_bspline *b);
/* Position at parameter u in [0, 1] and at arc length s. */
void sim_bspline_point(const sim_bspline *b, double u, double xy[2]);
void sim_bspline_eval_s(void *ctx, double s, double q[SIM_VPOP_AXES]);
double sim_bspline_feed(void *ctx, double s);

#endif /* LSM_SIM_VPOP_H */
