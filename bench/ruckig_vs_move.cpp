/*
 * ruckig_vs_move.cpp: planning time of Lissom's lsm_move_plan / lsm_scurve_plan against Ruckig's calculate,
 * side by side in one process on the same random cases (issue 12 item 6). A benchmark, not a test: it prints
 * ns per plan and the ratio Lissom / Ruckig, and checks nothing but that both planned. Built and run by
 * scripts/bench_ruckig.sh RUCKIG_SRC (Ruckig is not a dependency of the project).
 *
 * Cases (limits log-uniform over the ranges of tests/profile/test_scurve_props.c, cycle 1 ms; Ruckig gets the
 * same v, a and j limits, it has no snap limit):
 *   vc_nosnap  1-DoF velocity change v0 -> v1, snap loose (DJ >= J² pi / (2 A)-ish: the jerk or a binds)
 *   vc_snap    1-DoF velocity change, snap binding (DJ small)
 *   r2r        1-DoF rest-to-rest move, distance 1e-2 .. 1e3 mm
 *   3axis      3 axes from rest to rest, synchronised (Lissom: a straight line; Ruckig: Phase, and Time)
 */
#include <time.h>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <ruckig/ruckig.hpp>

extern "C" {
#include "move.h"
}

static uint64_t g_rng = 0x2545F4914F6CDD1Dull;
static double u01()
{
    g_rng ^= g_rng << 13;
    g_rng ^= g_rng >> 7;
    g_rng ^= g_rng << 17;
    return (double)(g_rng >> 11) / 9007199254740992.0;
}
static double logu(double lo, double hi) { return lo * std::exp(std::log(hi / lo) * u01()); }

struct axis_case {
    double d, v0, v1, vmax, amax, jmax, snap;
};
struct bench_case {
    int n;
    axis_case ax[3];
};

static volatile double g_sink;
/* CPU time of this thread: the machine is shared, and wall time would count other processes' slices */
static double now_s()
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static const double DT = 0.001;
static double g_budget = 0.5;

static axis_case random_axis(bool rest, bool snap_binds)
{
    axis_case a;
    a.vmax = logu(5, 2000);
    a.amax = logu(50, 20000);
    a.jmax = logu(500, 2e6);
    /* the snap binds when the sin² ramp's dt1 = pi J / (2 DJ) would exceed the others' */
    const double dj_free = M_PI * a.jmax * a.jmax / (2 * a.amax);
    a.snap = snap_binds ? dj_free * logu(1e-3, 0.3) : dj_free * logu(3, 100);
    a.d = rest ? logu(1e-2, 1e3) * (u01() < 0.5 ? -1 : 1) : 0;
    a.v0 = rest ? 0 : u01() * a.vmax;
    a.v1 = rest ? 0 : u01() * a.vmax;
    return a;
}

/* ---- Lissom ---- */
static bool lissom_vc(const axis_case &a)
{
    lsm_scurve_limits lim = {(lsm_real)a.amax, (lsm_real)a.jmax, (lsm_real)a.snap};
    lsm_scurve sc;
    const lsm_status st =
        lsm_scurve_plan(&sc, &lim, (lsm_real)DT, (lsm_real)a.v0, (lsm_real)a.v1, LSM_SCURVE_RULE_STRICT, nullptr);
    g_sink = g_sink + (double)sc.jp_mm_s3;
    return st == LSM_OK;
}
static bool lissom_move(const bench_case &c)
{
    lsm_move_request r = {};
    r.n_axes = (uint8_t)c.n;
    r.cycle_s = (lsm_real)DT;
    r.rule = LSM_SCURVE_RULE_STRICT;
    for (int i = 0; i < c.n; i++) {
        r.distance_mm[i] = (lsm_real)c.ax[i].d;
        r.lim[i] = {(lsm_real)c.ax[i].vmax, (lsm_real)c.ax[i].amax, (lsm_real)c.ax[i].jmax, (lsm_real)c.ax[i].snap};
    }
    lsm_move mv;
    const lsm_status st = lsm_move_plan(&mv, &r);
    g_sink = g_sink + (double)mv.cruise_cycles;
    return st == LSM_OK;
}

/* ---- Ruckig ---- */
template <size_t N>
static bool ruckig_plan(const bench_case &c, bool velocity, ruckig::Synchronization sync)
{
    static ruckig::Ruckig<N> otg;
    ruckig::InputParameter<N> in;
    ruckig::Trajectory<N> traj;
    in.synchronization = sync;
    if (velocity)
        in.control_interface = ruckig::ControlInterface::Velocity;
    for (size_t i = 0; i < N; i++) {
        const axis_case &a = c.ax[i];
        in.current_position[i] = 0;
        in.current_velocity[i] = velocity ? a.v0 : 0;
        in.current_acceleration[i] = 0;
        in.target_position[i] = a.d;
        in.target_velocity[i] = velocity ? a.v1 : 0;
        in.target_acceleration[i] = 0;
        in.max_velocity[i] = a.vmax;
        in.max_acceleration[i] = a.amax;
        in.max_jerk[i] = a.jmax;
    }
    const ruckig::Result res = otg.calculate(in, traj);
    g_sink = g_sink + traj.get_duration();
    return res == ruckig::Result::Working || res == ruckig::Result::Finished;
}

/* ns per call over all cases, repeated until the budget is spent; counts failures on the first pass */
template <class F>
static double time_cases(const std::vector<bench_case> &cs, F f, long *fails)
{
    *fails = 0;
    for (const auto &c : cs)
        if (!f(c))
            (*fails)++;
    long n = 0;
    const double t0 = now_s();
    double t;
    do {
        for (const auto &c : cs) {
            f(c);
            n++;
        }
        t = now_s() - t0;
    } while (t < g_budget);
    return 1e9 * t / (double)n;
}

static void row(const char *name, const std::vector<bench_case> &cs, double lis, long lis_fail, double ruck,
                long ruck_fail, bool *first)
{
    std::printf("%s  \"%s\": {\"cases\": %zu, \"lissom_ns\": %.1f, \"ruckig_ns\": %.1f, \"ratio\": %.2f, "
                "\"lissom_failed\": %ld, \"ruckig_failed\": %ld}",
                *first ? "" : ",\n", name, cs.size(), lis, ruck, lis / ruck, lis_fail, ruck_fail);
    *first = false;
}

int main(int argc, char **argv)
{
    const int n_cases = argc > 1 ? std::atoi(argv[1]) : 2000;
    if (argc > 2)
        g_budget = std::atof(argv[2]);
    if (argc > 3)
        g_rng ^= std::strtoull(argv[3], nullptr, 0);
    std::vector<bench_case> vc_free, vc_snap, r2r, ax3;
    for (int k = 0; k < n_cases; k++) {
        bench_case c = {};
        c.n = 1;
        c.ax[0] = random_axis(false, false);
        vc_free.push_back(c);
        c.ax[0] = random_axis(false, true);
        vc_snap.push_back(c);
        c.ax[0] = random_axis(true, u01() < 0.5);
        r2r.push_back(c);
        c.n = 3;
        const bool sb = u01() < 0.5;
        for (int i = 0; i < 3; i++)
            c.ax[i] = random_axis(true, sb);
        ax3.push_back(c);
    }
    long lf, rf;
    bool first = true;
    std::printf("{\"real\": \"%s\", \"cycle_s\": %g, \"budget_s\": %g,\n", LSM_REAL_IS_FLOAT ? "float" : "double", DT,
                g_budget);
    double l, r;
    l = time_cases(vc_free, [](const bench_case &c) { return lissom_vc(c.ax[0]); }, &lf);
    r = time_cases(vc_free, [](const bench_case &c) { return ruckig_plan<1>(c, true, ruckig::Synchronization::Time); },
                   &rf);
    row("velocity_change_snap_free", vc_free, l, lf, r, rf, &first);
    l = time_cases(vc_snap, [](const bench_case &c) { return lissom_vc(c.ax[0]); }, &lf);
    r = time_cases(vc_snap, [](const bench_case &c) { return ruckig_plan<1>(c, true, ruckig::Synchronization::Time); },
                   &rf);
    row("velocity_change_snap_binds", vc_snap, l, lf, r, rf, &first);
    l = time_cases(r2r, lissom_move, &lf);
    r = time_cases(r2r, [](const bench_case &c) { return ruckig_plan<1>(c, false, ruckig::Synchronization::Time); },
                   &rf);
    row("rest_to_rest_1dof", r2r, l, lf, r, rf, &first);
    l = time_cases(ax3, lissom_move, &lf);
    r = time_cases(ax3, [](const bench_case &c) { return ruckig_plan<3>(c, false, ruckig::Synchronization::Phase); },
                   &rf);
    row("synchronised_3axis_vs_phase", ax3, l, lf, r, rf, &first);
    const double r_time =
        time_cases(ax3, [](const bench_case &c) { return ruckig_plan<3>(c, false, ruckig::Synchronization::Time); },
                   &rf);
    row("synchronised_3axis_vs_time", ax3, l, lf, r_time, rf, &first);
    std::printf("\n}\n");
    return 0;
}
