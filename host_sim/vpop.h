/*
 * vpop.h: a VPOp-style offline reference planner (host only, sim_vpop_*), after Beudaert, Lavernhe, Tournier 2012
 * ("Maximum feedrate interpolator for multi-axis CNC machining with jerk constraints", section 2).
 *
 * Model. The path is q(s) (positions of up to 6 axes as a function of arc length s). Time is discretised with the
 * control cycle dt, and velocity, acceleration and jerk of every axis are the backward differences of the
 * positions (paper eq 6). At each step j+1 every axis i bounds its next position by intersecting
 *     |q_i(s) - q_i,j| <= V_i dt,  |q_i(s) - 2 q_i,j + q_i,j-1| <= A_i dt²,
 *     |q_i(s) - 3 q_i,j + 3 q_i,j-1 - q_i,j-2| <= J_i dt³                                   (eqs 4-5, 6)
 * with s - s_j <= F dt (F: the programmed feed at s_j, or the lower feed where the step would end), s_j <= s <= L
 * and s not past the next stop point (below). The set of s that satisfies every axis is [s_min, s_max] (if it is a
 * union of intervals, its outer ends may be missed: the searches are local, see below). The planner goes as fast
 * as possible (s_max). When the set is empty, a dichotomy over the steps since the last such event finds the
 * latest step k from which a braking sequence comes to rest without an empty set; the braking step is taken at k
 * and the planner goes on with s_max (paper Fig. 3, reproduced step for step in tests/sim/test_sim_vpop.c). The
 * paper's braking sequence (s_min at every step) ends at rest with the deceleration still in the history, a dead
 * end on curves (on the trident it creeps for minutes), so the sequences tried are the jerk-limited stop of a
 * point on the local tangent (as hard as the release of the deceleration allows) with two jerk values, then two
 * softer ones; the first that comes to rest certifies the step. With limits->refine_iters > 0, the step taken at
 * k is the largest (by bisection) from which a braking sequence still comes to rest (a later switch). The
 * constraints are the discrete ones, met exactly: every setpoint is checked against the exact bounds (only the
 * rounding of the positions shows in their differences, ~1e-10 relative); the paper's VPOp allows a 120 % jerk
 * overrun.
 *
 * Searches (docs/vpop.md). s_max: if s = top is feasible, top; else Newton on the end of the linearised set,
 * x <- the upper end of the intersection of the per-axis intervals of q_i(x) + q_i'(x) (s - x), from the
 * zero-jerk prediction 3 s_j - 3 s_j-1 + s_j-2, then a check against the exact bounds (backing off by 1e-7 J dt³
 * steps). If Newton fails: the window where the dominant axis (largest |q_i'|) is within its bounds is found by
 * Newton on that axis alone, widened, scanned on 48 points and its feasible ends refined by bisection; no
 * feasible point there = empty. s_min likewise. With linear axes only, s is also bounded by the chord of the
 * step: s0 + |P| - |J| dt³ <= s <= s0 + 1.1 (|P| + |J| dt³), P = 2 q_j - 3 q_j-1 + q_j-2.
 *
 * Continuous check (optional, path->step_cont: the continuous-limit reference, pathrun.c vpop-cont): every candidate
 * step (forward, braking sequences, switching step) must also pass a check of the motion between the samples; an end
 * of the discrete set that fails it moves inwards to the last point that passes (grid, then bisection).
 *
 * Stops: path->next_stop gives points where the motion must come to rest (corners the geometry leaves sharp,
 * where the real-time planner stops too); the planner does not pass one before it is at rest on it.
 * The motion ends at rest on s = L.
 *
 * Units: mm, s, rad (rotary axes).
 */
#ifndef LSM_SIM_VPOP_H
#define LSM_SIM_VPOP_H

#include <stddef.h>
#include <stdint.h>

#define SIM_VPOP_AXES 6

struct sim_vpop_limits;

typedef struct sim_vpop_path {
    double length;                                              /* L (mm) */
    void (*eval)(void *ctx, double s, double q[SIM_VPOP_AXES]); /* positions at s in [0, L] */
    double (*feed)(void *ctx, double s);                        /* programmed feed at s (mm/s); NULL: no feed limit */
    void *ctx;
    /* optional: positions and their derivatives dq/ds at s (the searches linearise with them); NULL: central
     * differences of eval */
    void (*eval_d)(void *ctx, double s, double q[SIM_VPOP_AXES], double dq[SIM_VPOP_AXES]);
    /* optional: the first point >= s where the motion must be at rest (a corner the geometry does not smooth),
     * or length. The planner does not pass such a point before it is at rest on it. NULL: none but L. */
    double (*next_stop)(void *ctx, double s);
    /* optional: the continuous check of a step (a reference held to its limits between its samples: pathrun.c,
     * vpop-cont). s4 = {s_j-2, s_j-1, s_j, s}: the history and the candidate s_j+1; returns 1 if the motion between
     * the samples that this step defines holds the limits lim continuously. Every candidate (the forward step, the
     * braking sequences, the switching step) must pass it as well as the discrete bounds: where an end of the
     * discrete set fails, the searches move inwards to the last point that passes (a grid of CONT_GRID points, then
     * bisection). NULL: no continuous check (plain VPOp). */
    int (*step_cont)(void *ctx, const struct sim_vpop_limits *lim, double dt, const double s4[4]);
} sim_vpop_path;

typedef struct sim_vpop_limits {
    uint8_t axis_mask; /* axes constrained (and moving) */
    double v[SIM_VPOP_AXES], a[SIM_VPOP_AXES], j[SIM_VPOP_AXES];
    /* 0: at an empty set, take the first step of the certified braking sequence at the switching step (the
     * paper's rule, with its s_min replaced by our sequences). N > 0: N bisection steps for the largest step
     * there from which a braking sequence still comes to rest: later switches, faster and more symmetric
     * profiles (trident: 2.196 -> 2.094 s), 4-8x the planning time. SIM_VPOP_REFINE is the value the CLI uses. */
    int refine_iters;
} sim_vpop_limits;

#define SIM_VPOP_REFINE 8

typedef struct sim_vpop_stats {
    size_t steps;       /* setpoints */
    size_t evals;       /* path evaluations */
    size_t backtracks;  /* dichotomies run */
    size_t tests;       /* braking sequences simulated by the dichotomies */
    size_t fallbacks;   /* steps where the linearised search gave no answer and the window scan ran */
    size_t cont_checks; /* continuous checks of candidate steps (path->step_cont) */
    /* the first empty set, numbered as the paper does (s_j, j = 1 the first step after s_0 = 0 at rest): the
     * step j, the steps the dichotomy then tested (in order) and the step where s_min was taken; 0: none */
    long first_fail, first_brake;
    long first_tests[32];
    int n_first_tests;
} sim_vpop_stats;

/*
 * Plans the path; *s_out (malloc'd, *n_out values) is s at every cycle, the first one after t = 0 (s = 0 at t = 0,
 * at rest) and the last one L (at rest). Returns 0, or -1 (no motion found within max_steps, out of memory).
 */
int sim_vpop_plan(const sim_vpop_path *p, const sim_vpop_limits *lim, double dt, size_t max_steps, double **s_out,
                  size_t *n_out, sim_vpop_stats *st);

/*
 * Largest |backward difference| (eq 6) of every axis over the planned motion S[0 .. n-1], at rest on q(0) before
 * and on q(S[n-1]) after: velocity v, acceleration a, jerk j (units/s, /s², /s³).
 */
void sim_vpop_measure(const sim_vpop_path *p, const double *S, size_t n, double dt, double v[SIM_VPOP_AXES],
                      double a[SIM_VPOP_AXES], double j[SIM_VPOP_AXES]);

/* A clamped B-spline in the plane (X, Y), parametrised by arc length through a dense table (host helper). */
typedef struct sim_bspline {
    int degree;
    int n_ctrl;
    double knots[32];
    double ctrl[16][2];
    double *tab_u, *tab_s; /* arc-length table */
    double *tab_v;         /* |C'(u)| at the table's nodes */
    int n_tab;
    double length;
    double feed; /* constant programmed feed (mm/s) */
} sim_bspline;

/* Builds the arc-length table (n_tab intervals, Gauss-Legendre). Returns 0 or -1. */
int sim_bspline_init(sim_bspline *b, int degree, int n_ctrl, const double *knots, const double (*ctrl)[2],
                     double feed_mm_s, int n_tab);
void sim_bspline_free(sim_bspline *b);
/* Position at parameter u in [0, 1] and at arc length s. */
void sim_bspline_point(const sim_bspline *b, double u, double xy[2]);
void sim_bspline_eval_s(void *ctx, double s, double q[SIM_VPOP_AXES]);
/* Position and unit tangent (dq/ds) at arc length s. */
void sim_bspline_eval_sd(void *ctx, double s, double q[SIM_VPOP_AXES], double dq[SIM_VPOP_AXES]);
double sim_bspline_feed(void *ctx, double s);
/* The path for sim_vpop_plan (X = axis 0, Y = axis 1). */
sim_vpop_path sim_bspline_path(sim_bspline *b);

/*
 * Loads a planar B-spline file (host_sim/examples/trident_bspline.json): {"degree": 3, "knots": [...],
 * "control_points_mm": [[x, y], ...], "programmed_feed_mm_min": F, ...}; builds the table with n_tab intervals.
 * Returns 0, or -1 with err set.
 */
int sim_bspline_load(const char *path, sim_bspline *b, int n_tab, char *err, size_t errlen);

#endif /* LSM_SIM_VPOP_H */
