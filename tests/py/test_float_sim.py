"""The float core (the Cortex-M4F's numerics) through `lissom-sim run`: the simulator built with the preset
`host-float` (build-float/bin/lissom-sim, LSM_SIM_FLOAT), checked from the setpoints it writes.

- every example program on every shipped XYZ machine, and the programs of issue 14 (an R 10000 arc over a 3.5 mm
  chord on a 2 ms machine and on router.json, an R 1000 arc back to Y 0 at F10), without drives;
- per axis, the backward differences of the setpoints (Beudaert eq 6, at rest before and after) within the machine
  file's limits up to the noise bound of float setpoints: |d^n q| / dt^n <= limit (1 + 1e-6) + 2^n E / dt^n with
  E = 2 ulp(M), M the largest |coordinate| of the n + 1 samples and the length of the program's longest move (the
  path parameter of a block is of that size; tests/plan/test_path_limits.c derives the bound: every setpoint is the
  planned motion plus at most E);
- the last setpoint is the programmed end rounded to float: the double simulator's last setpoint (the programmed end
  itself) rounded to float, bit for bit, and `end_error` is 0.
"""
import csv
import glob
import json
import math
import os
import re
import subprocess

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLES = sorted(glob.glob(os.path.join(ROOT, "host_sim", "examples", "*.ngc")))
MACHINES = ["router.json", "beudaert_table1.json", "kombarov_table1.json"]
NOISE_ULP = 2.0  # E in ulp (test_path_limits.c)
REL = 1e-6

ISSUE_MACHINE = {
    "format": "lissom-machine-1", "name": "issue14", "description": "2 ms, XYZ v 1000 a 20000 j 1e6 snap 1e9",
    "cycle_s": 0.002, "lookahead_blocks": 64, "blend_tol_mm": 0.02,
    "axes": [{"name": n, "v_max_mm_s": 1000, "a_max_mm_s2": 20000, "j_max_mm_s3": 1e6, "snap_max_mm_s4": 1e9,
              "counts_per_mm": 1000} for n in "XYZ"],
}
ISSUE_PROGRAMS = {
    "r10000": "G1 X13.5 Y12.5 F1200\nG3 X11 Y10 R10000\nM2\n",
    "r1000": "G1 Y2 F10\nG3 Y0 R1000\nM2\n",
}


def sim_path(env, *parts):
    return os.environ.get(env) or os.path.join(ROOT, *parts)


@pytest.fixture(scope="module")
def sims():
    f = sim_path("LISSOM_SIM_FLOAT", "build-float", "bin", "lissom-sim")
    d = sim_path("LISSOM_SIM", "build", "bin", "lissom-sim")
    for p in (f, d):
        if not os.access(p, os.X_OK):
            pytest.fail(f"lissom-sim not built at {p} (scripts/build.sh builds build/ and build-float/)")
    return f, d


def run(sim, prog, machine, out):
    p = subprocess.run([sim, "run", prog, "--machine", machine, "--out", out, "--json", "--no-drive",
                        "--no-progress"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    summary = json.loads(p.stdout)
    with open(os.path.join(out, "setpoints.csv")) as fh:
        rows = list(csv.reader(fh))
    header, data = rows[0], np.array([[float(x) for x in r] for r in rows[1:]])
    return summary, header, data


def longest_move(text):
    """The length of the longest G0-G3 move of a program (G17 arcs with R or I J; the examples' subset)."""
    word = re.compile(r"([A-Z])\s*([-+]?[0-9]*\.?[0-9]+)")
    pos, mode, best = np.zeros(3), 0, 0.0
    for raw in text.splitlines():
        line = re.sub(r"\([^)]*\)", "", raw.split(";")[0]).strip().upper()
        words = word.findall(line)
        for k, v in words:
            if k == "G" and float(v) in (0, 1, 2, 3):
                mode = int(float(v))
        vals = {k: float(v) for k, v in words if k != "G"}
        if not any(k in vals for k in "XYZ"):
            continue
        end = np.array([vals.get(k, pos[i]) for i, k in enumerate("XYZ")])
        length = float(np.linalg.norm(end - pos))
        if mode in (2, 3):
            d = end[:2] - pos[:2]
            q = float(np.linalg.norm(d))
            if "R" in vals:
                r = abs(vals["R"])
                sweep = 2 * math.asin(min(1.0, q / (2 * r)))
                if vals["R"] < 0:
                    sweep = 2 * math.pi - sweep
            else:
                c = pos[:2] + np.array([vals.get("I", 0.0), vals.get("J", 0.0)])
                r = float(np.linalg.norm(pos[:2] - c))
                a0 = math.atan2(pos[1] - c[1], pos[0] - c[0])
                a1 = math.atan2(end[1] - c[1], end[0] - c[0])
                sweep = (a0 - a1 if mode == 2 else a1 - a0) % (2 * math.pi) or 2 * math.pi
            length = math.hypot(r * sweep, end[2] - pos[2])
        best = max(best, length)
        pos = end
    return best


def ulp32(x):
    x = np.abs(x).astype(np.float32)
    return (np.nextafter(x, np.float32(np.inf)) - x).astype(np.float64)


def check_limits(header, q, machine, what, move_mm):
    """Backward differences of every axis within the limits and the float noise bound; returns the worst ratio."""
    dt = machine["cycle_s"]
    axes = [a for a in machine["axes"] if a["name"] in header]
    # at rest before and after: three copies of the first and the last sample
    q = np.vstack([np.repeat(q[:1], 3, axis=0), q, np.repeat(q[-1:], 3, axis=0)])
    xyz = np.array([header.index(a["name"]) for a in axes])
    mag = np.maximum(np.max(np.abs(q[:, xyz]), axis=1), move_mm)
    worst = 0.0
    for a in axes:
        x = q[:, header.index(a["name"])]
        lim = {1: a["v_max_mm_s"], 2: a["a_max_mm_s2"], 3: a["j_max_mm_s3"]}
        for n in (1, 2, 3):
            d = np.abs(np.diff(x, n))
            m = np.max([mag[k: len(mag) - n + k] for k in range(n + 1)], axis=0)
            bound = lim[n] * (1 + REL) * dt ** n + 2 ** n * NOISE_ULP * ulp32(m)
            k = int(np.argmax(d / bound))
            worst = max(worst, d[k] / bound[k])
            assert d[k] <= bound[k], (f"{what}: axis {a['name']} order {n} at sample {k}: {d[k] / dt ** n:.6g} > "
                                      f"limit {lim[n]:.6g} + noise {2 ** n * NOISE_ULP * ulp32(m)[k] / dt ** n:.3g}")
    return worst


def check_end(f_sum, f_data, d_data, what):
    assert f_sum["end_error"] == 0, f"{what}: end_error {f_sum['end_error']}"
    want = d_data[-1, 1:].astype(np.float32).astype(np.float64)  # the programmed end, rounded to float
    got = f_data[-1, 1:]
    assert np.array_equal(got, want), f"{what}: last setpoint {got.tolist()} != programmed end in float {want.tolist()}"


@pytest.mark.parametrize("machine", MACHINES)
@pytest.mark.parametrize("prog", EXAMPLES, ids=[os.path.basename(p) for p in EXAMPLES])
def test_examples_float(sims, tmp_path, prog, machine):
    fsim, dsim = sims
    mpath = os.path.join(ROOT, "host_sim", "machines", machine)
    with open(mpath) as fh:
        m = json.load(fh)
    what = f"{os.path.basename(prog)} on {machine}"
    f_sum, header, f_data = run(fsim, prog, mpath, str(tmp_path / "f"))
    _, _, d_data = run(dsim, prog, mpath, str(tmp_path / "d"))
    with open(prog) as fh:
        move = longest_move(fh.read())
    check_limits(header, f_data, m, what, move)
    check_end(f_sum, f_data, d_data, what)


@pytest.mark.parametrize("machine", ["issue14", "router.json"])
@pytest.mark.parametrize("name", sorted(ISSUE_PROGRAMS))
def test_issue14_float(sims, tmp_path, name, machine):
    """The float build held X jerk at 5.9e6 against 1e6 and ended 1 um off on the R 10000 arc."""
    fsim, dsim = sims
    prog = tmp_path / f"{name}.ngc"
    prog.write_text(ISSUE_PROGRAMS[name])
    if machine == "issue14":
        m = ISSUE_MACHINE
        mpath = tmp_path / "issue14.json"
        mpath.write_text(json.dumps(m))
    else:
        mpath = os.path.join(ROOT, "host_sim", "machines", machine)
        with open(mpath) as fh:
            m = json.load(fh)
    what = f"{name} on {machine}"
    f_sum, header, f_data = run(fsim, str(prog), str(mpath), str(tmp_path / "f"))
    d_sum, _, d_data = run(dsim, str(prog), str(mpath), str(tmp_path / "d"))
    check_limits(header, f_data, m, what, longest_move(ISSUE_PROGRAMS[name]))
    check_end(f_sum, f_data, d_data, what)
    # double: the programmed end bit for bit (it ended at X 11.000000000000909, Y 2.9e-13)
    assert d_sum["end_error"] == 0
    end = {"r10000": (11.0, 10.0, 0.0), "r1000": (0.0, 0.0, 0.0)}[name]
    assert tuple(d_data[-1, 1:4]) == end
