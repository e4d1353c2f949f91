"""End-to-end: every example program through `lissom-sim run` (planner, interpolator, simulated drives), with its
limits checked independently of the C code from the CSV files the run writes:

- per-axis velocity, acceleration and jerk from the setpoints with backward differences (Beudaert eq 6), each within
  1e-6 relative of the machine file's limits;
- the path deviation: the distance of every setpoint to the programmed path (sampled every 0.5 um from a small
  G-code reader of its own, matched in order along the path) within the program's G64 P tolerance;
- the run ends exactly on the program's last point, at rest: held there for three more cycles, the stop is within
  the limits too;
- run.csv holds setpoints, actual positions, following error, feed and V/A/J per axis, consistent with setpoints.csv;
- the summary JSON and the numbers printed by --json agree.
Every program in host_sim/examples has a case here, and every program also runs on each other shipped XYZ machine
with its limits and end checked from the setpoints.
"""
import glob
import csv
import json
import math
import os
import re

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLES = os.path.join(ROOT, "host_sim", "examples")
MACHINES = os.path.join(ROOT, "host_sim", "machines")

# (program, machine): the trident runs on the paper's machine, the others on the router
CASES = [
    ("shahzadeh_corner.ngc", "router.json"),
    ("trident.ngc", "beudaert_table1.json"),
    ("circle_chords.ngc", "router.json"),
    ("pocket.ngc", "router.json"),
    ("surface_finish.ngc", "router.json"),
]

SAMPLE_MM = 0.0005
REL = 1e-6


def read_program(path, sample=True):
    """The example programs' subset: G0-G3 (G17, I J or R), X Y Z, G64 P. Returns (sampled points, last point, P);
    without `sample`, no points (only the end and P)."""
    pos = np.zeros(3)
    mode = 0
    tol = None
    pts = [pos.copy()]
    word = re.compile(r"([A-Z])\s*([-+]?[0-9]*\.?[0-9]+)")
    for raw in open(path, encoding="utf-8"):
        line = raw.split(";")[0]
        line = re.sub(r"\([^)]*\)", "", line).strip().upper()
        if not line or line == "%":
            continue
        words = word.findall(line)
        gs = [float(v) for k, v in words if k == "G"]
        vals = {k: float(v) for k, v in words if k != "G"}
        for g in gs:
            if g in (0, 1, 2, 3):
                mode = int(g)
            if g == 64 and "P" in vals:
                tol = vals["P"]
        if not any(k in vals for k in "XYZ"):
            continue
        end = pos.copy()
        for i, k in enumerate("XYZ"):
            if k in vals:
                end[i] = vals[k]
        if not sample:
            pos = end
            continue
        if mode in (0, 1):
            n = max(2, int(math.ceil(np.linalg.norm(end - pos) / SAMPLE_MM)) + 1)
            pts.extend(pos + (end - pos) * t for t in np.linspace(0, 1, n)[1:])
        else:
            cw = mode == 2
            if "R" in vals:  # centre from the radius (the short arc for R > 0)
                r = vals["R"]
                d = end[:2] - pos[:2]
                q = np.linalg.norm(d)
                h = math.sqrt(max(r * r - q * q / 4, 0.0))
                mid = pos[:2] + d / 2
                nrm = np.array([-d[1], d[0]]) / q
                sign = 1 if (cw == (r < 0)) else -1
                c = mid + sign * h * nrm
            else:
                c = pos[:2] + np.array([vals.get("I", 0.0), vals.get("J", 0.0)])
            a0 = math.atan2(pos[1] - c[1], pos[0] - c[0])
            a1 = math.atan2(end[1] - c[1], end[0] - c[0])
            if cw:
                while a1 >= a0:
                    a1 -= 2 * math.pi
            else:
                while a1 <= a0:
                    a1 += 2 * math.pi
            r = np.linalg.norm(pos[:2] - c)
            n = max(2, int(math.ceil(abs(a1 - a0) * r / SAMPLE_MM)) + 1)
            for t in np.linspace(0, 1, n)[1:]:
                a = a0 + (a1 - a0) * t
                pts.append(np.array([c[0] + r * math.cos(a), c[1] + r * math.sin(a), pos[2] + (end[2] - pos[2]) * t]))
        pos = end
    return np.array(pts), pos, tol


def path_deviation(pts, xyz, step_max_mm):
    """Largest distance of the setpoints to the sampled path, matched in order along it (the trident's prongs come
    close to each other, so a plain nearest point could belong to another part of the path)."""
    fwd = int(math.ceil((2 * step_max_mm + 0.1) / SAMPLE_MM))
    back = int(math.ceil(0.1 / SAMPLE_MM))
    i0 = 0
    dev = 0.0
    for p in xyz:
        lo, hi = max(0, i0 - back), min(len(pts), i0 + fwd)
        d = np.einsum("ij,ij->i", pts[lo:hi] - p, pts[lo:hi] - p)
        k = int(np.argmin(d))
        i0 = lo + k
        dev = max(dev, math.sqrt(d[k]))
    return dev


def test_every_example_is_run():
    progs = sorted(os.path.basename(p) for p in glob.glob(os.path.join(EXAMPLES, "*.ngc")))
    assert progs and progs == sorted(c[0] for c in CASES)


def run_csv_header(names):
    """The run.csv columns of docs/host_sim.md, in the order lissom-sim writes them (linear axes, with drives)."""
    head = ["t_s", "feed_mm_s", "block"]
    for a in names:
        head += [f"{a}_set_mm", f"{a}_act_mm", f"{a}_err_mm", f"{a}_v_mm_s", f"{a}_a_mm_s2", f"{a}_j_mm_s3"]
    return head


def axis_maxima_within(q, limits, cycle_s):
    """Per-axis largest |v|, |a|, |j| of the positions q (rows: cycles) by backward differences (Beudaert eq 6),
    asserted within the limits; returns {axis: (v, a, j)} and the differences v, a, j (arrays)."""
    v = np.diff(q, axis=0) / cycle_s
    a = np.diff(q, 2, axis=0) / cycle_s**2
    jj = np.diff(q, 3, axis=0) / cycle_s**3
    out = {}
    for i, name in enumerate(limits):
        vmax, amax, jmax = limits[name]
        mv, ma, mj = np.abs(v[:, i]).max(), np.abs(a[:, i]).max(), np.abs(jj[:, i]).max()
        assert mv <= vmax * (1 + REL), f"{name} v {mv} > {vmax}"
        assert ma <= amax * (1 + REL), f"{name} a {ma} > {amax}"
        assert mj <= jmax * (1 + REL), f"{name} j {mj} > {jmax}"
        out[name] = (mv, ma, mj)
    return out, v, a, jj


def check_limits_and_end(data, limits, cycle_s, last):
    """Per-axis v, a, j by backward differences with the machine at rest before the first setpoint and held on the
    last one for three more cycles (so the stop counts too); the last setpoint is exactly the programmed end."""
    q = np.vstack([np.zeros((3, len(limits))), data[:, 1:], np.repeat(data[-1:, 1:], 3, axis=0)])
    axis_maxima_within(q, limits, cycle_s)
    assert np.array_equal(data[-1, 1:4], last), f"ends at {data[-1, 1:4]}, program ends at {last}"


def machine_limits(path):
    m = json.load(open(path, encoding="utf-8"))
    return {a["name"]: (a["v_max_mm_s"], a["a_max_mm_s2"], a["j_max_mm_s3"]) for a in m["axes"]}, m["cycle_s"]


@pytest.mark.parametrize("prog,machine", CASES, ids=[c[0].split(".")[0] for c in CASES])
def test_example_runs_within_limits(sim, tmp_path, prog, machine):
    out = tmp_path / "run"
    mpath = os.path.join(MACHINES, machine)
    j = sim("run", os.path.join(EXAMPLES, prog), "--machine", mpath, "--out", out, "--json")
    summary = json.load(open(out / "summary.json", encoding="utf-8"))
    for k in ("duration", "cycles", "max_deviation", "end_error"):
        assert summary[k] == pytest.approx(j[k], rel=1e-12, abs=1e-15), k
    limits, cycle_s = machine_limits(mpath)

    # setpoints.csv: t, then one column per axis
    with open(out / "setpoints.csv", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    head, data = rows[0], np.array(rows[1:], dtype=float)
    assert head[0] == "t" and head[1:] == list(limits)
    n = data.shape[0]
    assert n == j["cycles"]
    t = data[:, 0]
    assert np.allclose(t, cycle_s * np.arange(1, n + 1), rtol=0, atol=1e-9)
    assert j["duration"] == pytest.approx(t[-1], abs=1e-9)

    # the machine rests at the origin before the first setpoint
    q = np.vstack([np.zeros((3, len(limits))), data[:, 1:]])
    maxima, v, a, jj = axis_maxima_within(q, limits, cycle_s)
    for name, (mv, ma, mj) in maxima.items():
        # what the run prints is the same measurement
        assert j["max_axis_velocity"][name] == pytest.approx(mv, rel=1e-6, abs=1e-9)
        assert j["max_axis_acceleration"][name] == pytest.approx(ma, rel=1e-6, abs=1e-6)
        assert j["max_axis_jerk"][name] == pytest.approx(mj, rel=1e-6, abs=1e-3)
    assert j["within_limits"] is True

    # the path: every setpoint within the blend tolerance of the programmed path
    pts, last, tol = read_program(os.path.join(EXAMPLES, prog))
    assert tol is not None and tol > 0
    dev = path_deviation(pts, q[3:, :3], cycle_s * max(x[0] for x in limits.values()) * math.sqrt(3))
    assert dev <= tol + SAMPLE_MM, f"deviation {dev} mm > {tol} mm"
    assert j["max_deviation"] <= tol * (1 + 1e-9)
    assert j["max_deviation"] == pytest.approx(dev, abs=SAMPLE_MM)

    # exact end, at rest (the stop within the limits too)
    check_limits_and_end(data, limits, cycle_s, last)
    assert j["end_error"] == 0

    # run.csv: setpoints, actual positions, following error, feed, V A J per axis
    with open(out / "run.csv", encoding="utf-8") as f:
        r = list(csv.DictReader(f))
    assert len(r) == n
    assert list(r[0]) == run_csv_header(list(limits))  # the schema of docs/host_sim.md, exactly
    for i, name in enumerate(limits):
        for col in ("set_mm", "act_mm", "err_mm", "v_mm_s", "a_mm_s2", "j_mm_s3"):
            assert f"{name}_{col}" in r[0], f"run.csv lacks {name}_{col}"
        s = np.array([float(x[f"{name}_set_mm"]) for x in r])
        act = np.array([float(x[f"{name}_act_mm"]) for x in r])
        err = np.array([float(x[f"{name}_err_mm"]) for x in r])
        assert np.allclose(s, data[:, 1 + i], rtol=0, atol=1e-9)
        assert np.allclose(err, s - act, rtol=0, atol=1e-6)
        jv = np.array([float(x[f"{name}_j_mm_s3"]) for x in r])
        assert np.allclose(jv, jj[:, i], rtol=1e-5, atol=1e-3 * limits[name][2])
        vv = np.array([float(x[f"{name}_v_mm_s"]) for x in r])
        av = np.array([float(x[f"{name}_a_mm_s2"]) for x in r])
        assert np.allclose(vv, v[2:, i], rtol=1e-6, atol=1e-6 * limits[name][0])
        assert np.allclose(av, a[1:, i], rtol=1e-6, atol=1e-5 * limits[name][1])
        t_csv = np.array([float(x["t_s"]) for x in r])
        assert np.allclose(t_csv, t, rtol=0, atol=1e-9)
    feed = np.array([float(x["feed_mm_s"]) for x in r])
    assert feed.min() >= -1e-9 and feed[-1] == pytest.approx(0, abs=1e-9)


OTHER = [(prog, m) for prog, _ in CASES for m in ("router.json", "kombarov_table1.json", "beudaert_table1.json")
         if (prog, m) not in CASES]


@pytest.mark.parametrize("prog,machine", OTHER, ids=["%s-%s" % (p.split(".")[0], m.split(".")[0]) for p, m in OTHER])
def test_example_on_other_machines(sim, tmp_path, prog, machine):
    out = tmp_path / "run"
    mpath = os.path.join(MACHINES, machine)
    j = sim("run", os.path.join(EXAMPLES, prog), "--machine", mpath, "--out", out, "--json", "--no-drive")
    limits, cycle_s = machine_limits(mpath)
    with open(out / "setpoints.csv", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float)
    _, last, tol = read_program(os.path.join(EXAMPLES, prog), sample=False)
    check_limits_and_end(data, limits, cycle_s, last)
    assert j["within_limits"] is True and j["end_error"] == 0
    assert j["max_deviation"] <= tol * (1 + 1e-9)
