"""Randomized end-to-end runs: seeded random G-code programs (lines, rapids, arcs and helices with CAM-rounded
centres, dense polylines of 0.05-0.2 mm chords, G61/G64 switches, feeds from 50 to 12000 mm/min) through
`lissom-sim run` on the three shipped machines. Checked from the files the run writes, independently of the C code:

- per-axis velocity, acceleration and jerk from setpoints.csv by backward differences (Beudaert eq 6), at rest
  before the first setpoint, within 1e-6 relative of the machine file's limits;
- the last setpoint is the program's last point exactly (the coordinates as written, parsed as doubles);
- the planner reports no fallback piece and no planning error.

Seed and count: LISSOM_RUN_SEED (default 1) and LISSOM_RUN_COUNT (default 24); a soak sets a large count.
"""
import csv
import json
import math
import os
import random

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MACHINES = ["router.json", "beudaert_table1.json", "kombarov_table1.json"]
SEED = int(os.environ.get("LISSOM_RUN_SEED", "1"))
COUNT = int(os.environ.get("LISSOM_RUN_COUNT", "24"))
REL = 1e-6


def program(r):
    """A random program and its last point (x, y, z) as written."""
    lines = ["G21 G90 G17"]
    lines.append(r.choice(["G64 P0.001", "G64 P0.005", "G64 P0.02", "G64 P0.1", "G61", "G64"]))
    x = y = z = 0.0
    fmt = lambda v: "%.4f" % v  # noqa: E731
    for _ in range(r.randint(3, 40)):
        k = r.random()
        f = r.choice([50, 300, 1200, 3000, 6000, 12000])
        if r.random() < 0.1:
            lines.append(r.choice(["G61", "G64 P0.01", "G64"]))
        if k < 0.45:
            step = r.choice([0.05, 0.1, 0.3, 2, 10, 40])
            x += r.uniform(-step, step)
            y += r.uniform(-step, step)
            if r.random() < 0.2:
                z += r.uniform(-step / 3, step / 3)
            x, y, z = (float(fmt(v)) for v in (x, y, z))
            lines.append("G1 X%s Y%s Z%s F%d" % (fmt(x), fmt(y), fmt(z), f))
        elif k < 0.55:
            x, y = float(fmt(x + r.uniform(-20, 20))), float(fmt(y + r.uniform(-20, 20)))
            lines.append("G0 X%s Y%s" % (fmt(x), fmt(y)))
        elif k < 0.8:  # arc (helical sometimes) by a centre rounded like CAM output
            rad = r.choice([0.2, 1, 5, 20])
            a0 = r.uniform(0, 2 * math.pi)
            cx, cy = x - rad * math.cos(a0), y - rad * math.sin(a0)
            sw = r.uniform(0.1, 6) * (1 if r.random() < 0.5 else -1)
            nx, ny = float(fmt(cx + rad * math.cos(a0 + sw))), float(fmt(cy + rad * math.sin(a0 + sw)))
            zz = ""
            if r.random() < 0.2:
                z = float(fmt(z + r.uniform(-1, 1)))
                zz = " Z" + fmt(z)
            lines.append("%s X%s Y%s%s I%s J%s F%d" % ("G3" if sw > 0 else "G2", fmt(nx), fmt(ny), zz,
                                                      fmt(cx - x), fmt(cy - y), f))
            x, y = nx, ny
        else:  # a dense polyline along a circle (CAM output)
            rad = r.uniform(1, 30)
            a = r.uniform(0, 6)
            seg = r.choice([0.05, 0.1, 0.2])
            cx, cy = x - rad * math.cos(a), y - rad * math.sin(a)
            for _ in range(r.randint(5, 80)):
                a += seg / rad
                x, y = float(fmt(cx + rad * math.cos(a))), float(fmt(cy + rad * math.sin(a)))
                lines.append("G1 X%s Y%s F%d" % (fmt(x), fmt(y), f))
    lines.append("M2")
    return "\n".join(lines) + "\n", (x, y, z)


def limits(machine):
    with open(os.path.join(ROOT, "host_sim", "machines", machine), encoding="utf-8") as f:
        m = json.load(f)
    return m["cycle_s"], {a["name"]: (a["v_max_mm_s"], a["a_max_mm_s2"], a["j_max_mm_s3"]) for a in m["axes"]}


@pytest.mark.parametrize("k", range(COUNT))
def test_random_program(sim, tmp_path, k):
    r = random.Random(SEED * 1000003 + k)
    text, last = program(r)
    machine = MACHINES[k % len(MACHINES)]
    prog = tmp_path / ("p%d.ngc" % k)
    prog.write_text(text)
    out = tmp_path / "out"
    res = sim("run", prog, "--machine", os.path.join(ROOT, "host_sim", "machines", machine), "--out", out,
              "--json", "--no-drive")
    stats = res["planner_stats"]
    assert stats["fallbacks"] == 0 and stats["plan_errors"] == 0, (k, machine, stats)
    dt, lim = limits(machine)
    with open(out / "setpoints.csv", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    head = rows[0]
    assert head[0] == "t"
    q = np.array([[float(c) for c in row] for row in rows[1:]])
    for j, name in enumerate(head[1:], start=1):
        col = np.concatenate([np.zeros(3), q[:, j]])  # at rest at the origin before the first setpoint
        v = np.diff(col) / dt
        a = np.diff(col, 2) / dt ** 2
        jk = np.diff(col, 3) / dt ** 3
        vmax, amax, jmax = lim[name]
        assert np.max(np.abs(v)) <= vmax * (1 + REL), (k, machine, name, "v", np.max(np.abs(v)))
        assert np.max(np.abs(a)) <= amax * (1 + REL), (k, machine, name, "a", np.max(np.abs(a)))
        assert np.max(np.abs(jk)) <= jmax * (1 + REL), (k, machine, name, "j", np.max(np.abs(jk)))
    end = dict(zip(head[1:], q[-1, 1:]))
    assert (end["X"], end["Y"], end["Z"]) == last, (k, machine, end, last)
    assert res["end_error"] == 0
