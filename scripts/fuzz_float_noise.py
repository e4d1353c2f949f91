#!/usr/bin/env python3
"""Replays fuzz_planner_float (or fuzz_gcode_path_float) inputs with FZ_MEASURE=1 (tests/fuzz/fz_measure.h) and
classifies them by the float noise they show.

Usage: scripts/fuzz_float_noise.py [--bin build/bin/fuzz_planner_float_replay] [--worst N] [--csv FILE] PATH...
  PATH: input files or directories. Prints, for every input: its outcome (pass, limit, crawl, end, fatal), the
  largest excess over the axis limits per difference order in units of 2^n u (u = FLT_EPSILON x the largest
  |coordinate|, so an excess of K means a setpoint noise of K u explains it), the largest position error against
  the exact curve of the float plan at the cursor (geom, in u) and of the cursor along the path against the piece's travel at the exact time (travel, in u); then the
  histograms. Exit 0 (a measurement, not a test).
"""
import argparse
import os
import re
import subprocess
import sys

BINS = [0, 0.5, 1, 2, 4, 8, 16, 64, 1e3, 1e30]


def run(binary, path):
    env = dict(os.environ, FZ_MEASURE="1", LSM_FUZZ_KNOWN="report")
    try:
        p = subprocess.run([binary, path], env=env, capture_output=True, text=True, timeout=300)
        err = p.stderr
    except subprocess.TimeoutExpired:
        return {"outcome": "timeout"}
    r = {"outcome": "pass", "msg": ""}
    for line in err.splitlines():
        m = re.match(r"FUZZ KNOWN (\w+) \(float build\): (.*)", line)
        if m and r["outcome"] == "pass":
            r["outcome"], r["msg"] = m.group(1), m.group(2)
        if "FUZZ VIOLATION" in line or "runtime error" in line:
            r["outcome"], r["msg"] = "fatal", line
        if line.startswith("FZ_MEASURE"):
            f = line.split()[1:]
            for k, v in zip(f[0::2], f[1::2]):
                try:
                    r[k] = float(v)
                except ValueError:
                    r[k] = v
    if p.returncode != 0 and r["outcome"] == "pass":
        r["outcome"] = "fatal"
    return r


def hist(name, vals):
    counts = [0] * (len(BINS) - 1)
    for v in vals:
        for i in range(len(BINS) - 1):
            if v <= BINS[i + 1] and (v > BINS[i] or i == 0):
                counts[i] += 1
                break
    labels = ["0" if i == 0 else f"({BINS[i]:g}, {BINS[i + 1]:g}]" for i in range(len(BINS) - 1)]
    labels[0] = f"<= {BINS[1]:g}"
    labels[-1] = f"> {BINS[-2]:g}"
    print(f"{name}: " + ", ".join(f"{lab}: {c}" for lab, c in zip(labels, counts) if c))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default="build/bin/fuzz_planner_float_replay")
    ap.add_argument("--worst", type=int, default=15)
    ap.add_argument("--csv")
    ap.add_argument("paths", nargs="+")
    a = ap.parse_args()
    files = []
    for p in a.paths:
        if os.path.isdir(p):
            files += sorted(os.path.join(p, f) for f in os.listdir(p) if not f.startswith((".", "README")))
        else:
            files.append(p)
    rows = []
    for f in files:
        r = run(a.bin, f)
        r["file"] = os.path.basename(f)
        r["ex"] = max(r.get("ex1", 0), r.get("ex2", 0), r.get("ex3", 0))
        rows.append(r)
    outcomes = {}
    for r in rows:
        outcomes[r["outcome"]] = outcomes.get(r["outcome"], 0) + 1
    print(f"{len(rows)} inputs: " + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items())))
    hist("excess over the limit (max over orders, units of 2^n u)", [r["ex"] for r in rows])
    for n in (1, 2, 3):
        hist(f"  order {n}", [r.get(f"ex{n}", 0) for r in rows])
    hist("position error against the exact curve (lines, arcs; u)", [r.get("geom", 0) for r in rows])
    hist("travel error along the path against the exact time (u)", [r.get("travel", 0) for r in rows])
    hist("K_eff: the setpoint error's own n-th difference / 2^n (max over n; u)",
         [max(r.get("keff1", 0), r.get("keff2", 0), r.get("keff3", 0)) for r in rows])
    for n in (1, 2, 3):
        hist(f"  order {n}", [r.get(f"keff{n}", 0) for r in rows])
    print(f"worst {a.worst} by excess:")
    for r in sorted(rows, key=lambda r: -r["ex"])[: a.worst]:
        print(f"  {r['file'][:18]} {r['outcome']:6} ex {r['ex']:9.3g} geom {r.get('geom', 0):7.3g} "
              f"travel {r.get('travel', 0):6.3g} keff {max(r.get('keff1', 0), r.get('keff2', 0), r.get('keff3', 0)):6.3g} span {r.get('span', 0):7.4g} {r.get('msg', '')[:110]}")
    if a.csv:
        keys = ["file", "outcome", "machine", "span", "ex1", "ex2", "ex3", "ratio1", "ratio2", "ratio3", "geom",
                "geom_kind", "travel", "keff1", "keff2", "keff3", "msg"]
        with open(a.csv, "w") as fo:
            fo.write(",".join(keys) + "\n")
            for r in rows:
                fo.write(",".join(str(r.get(k, "")).replace(",", ";") for k in keys) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
