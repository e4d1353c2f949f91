"""Benchmark: Lissom's sin² S-curve against Ruckig's constant-jerk profile (same v, a, j limits), in one run.

    python -m lissom_hil.bench_scurve [--sim build/bin/lissom-sim]

For each of Kombarov's Table 1 tests (a velocity change from rest) and a few point-to-point moves it reports
the duration of Lissom's strict sin² profile (snap-limited, whole 1 ms cycles), Ruckig's time-optimal
constant-jerk duration for the same v/a/j limits, and their ratio. The sin² profile is expected to be longer:
bounding the snap costs time (+16 % in the paper's Test 2). It also reports calculation times: Ruckig's 1-DoF
calculation (Python binding, so call overhead included) and Lissom's host figures from `lissom-sim bench`.
This is a benchmark, not a test: timings vary from machine to machine; duration ratios are exact.
"""
import argparse
import json
import os
import subprocess
import sys
import time

TABLE1 = [  # (name, dF m/s, A, J, DJ)
    ("Test 1", 0.22, 1.57, 16.0, 25132.0),
    ("Test 2", 0.22, 1.57, 16.0, 560.0),
    ("Test 3", 0.08, 1.57, 16.0, 560.0),
    ("Test 4", 0.015, 1.57, 16.0, 560.0),
    ("Test 5", 0.15, 1.05, 24.0, 500.0),
]
MOVES = [  # (distance mm, vmax mm/s, A mm/s², J mm/s³, DJ mm/s⁴)
    (100.0, 220.0, 1570.0, 16000.0, 560000.0),
    (10.0, 220.0, 1570.0, 16000.0, 560000.0),
    (1.0, 220.0, 1570.0, 16000.0, 560000.0),
    (500.0, 500.0, 5000.0, 100000.0, 2.0e7),
]


def default_sim():
    here = os.path.dirname(os.path.abspath(__file__))
    return os.environ.get("LISSOM_SIM") or os.path.join(here, "..", "..", "build", "bin", "lissom-sim")


def lissom(sim, *args):
    out = subprocess.run([sim, *args, "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def ruckig_velocity(df, a, j):
    from ruckig import ControlInterface, InputParameter, Result, Ruckig, Trajectory
    inp = InputParameter(1)
    inp.control_interface = ControlInterface.Velocity
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_velocity, inp.target_acceleration = [df], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [1e9], [a], [j]
    return _calc(inp)


def ruckig_move(d, v, a, j):
    from ruckig import InputParameter
    inp = InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [d], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v], [a], [j]
    return _calc(inp)


def _calc(inp):
    from ruckig import Result, Ruckig, Trajectory
    otg, traj = Ruckig(1), Trajectory(1)
    res = otg.calculate(inp, traj)
    if res not in (Result.Working, Result.Finished):
        raise RuntimeError(f"ruckig: {res}")
    n = 2000
    t0 = time.perf_counter()
    for _ in range(n):
        otg.calculate(inp, traj)
    return traj.duration, 1e9 * (time.perf_counter() - t0) / n


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim", default=default_sim())
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    try:
        import ruckig  # noqa: F401
        have_ruckig = True
    except ImportError:
        have_ruckig = False
    rows = []
    for name, df, a, j, dj in TABLE1:
        ours = lissom(args.sim, "scurve", "--v0", "0", "--v1", str(df), "--amax", str(a), "--jmax", str(j),
                      "--snap-max", str(dj), "--cycle", "0.001")
        row = {"case": f"Table 1 {name}", "lissom_s": ours["tp"]}
        if have_ruckig:
            row["ruckig_s"], row["ruckig_ns"] = ruckig_velocity(df, a, j)
            row["ratio"] = ours["tp"] / row["ruckig_s"]
        rows.append(row)
    for d, v, a, j, dj in MOVES:
        ours = lissom(args.sim, "move", "--distance", str(d), "--vmax", str(v), "--amax", str(a), "--jmax", str(j),
                      "--snap-max", str(dj), "--cycle", "0.001")
        row = {"case": f"move {d:g} mm", "lissom_s": ours["duration"]}
        if have_ruckig:
            row["ruckig_s"], row["ruckig_ns"] = ruckig_move(d, v, a, j)
            row["ratio"] = ours["duration"] / row["ruckig_s"]
        rows.append(row)
    host = lissom(args.sim, "bench")
    if args.json:
        print(json.dumps({"rows": rows, "lissom_host": host, "ruckig": have_ruckig}))
        return 0
    print(f"{'case':<16} {'lissom s':>9} {'ruckig s':>9} {'ratio':>6} {'ruckig calc ns':>15}")
    for r in rows:
        if have_ruckig:
            print(f"{r['case']:<16} {r['lissom_s']:9.4f} {r['ruckig_s']:9.4f} {r['ratio']:6.3f} {r['ruckig_ns']:15.0f}")
        else:
            print(f"{r['case']:<16} {r['lissom_s']:9.4f}   (ruckig not installed)")
    print("lissom host calculation (ns): " + ", ".join(f"{k} {v}" for k, v in host.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
