#!/usr/bin/env python3
"""The parameter sweep of docs/host_sim.md ("Where sin² beats the trapezoid"), as Markdown tables.

usage: kombarov_sweep.py [--sim PATH] [--json OUT]

Runs `lissom-sim experiment kombarov --sweep --json` for six drive configurations of the default linear axis
(position loop on the load or on the motor, feed-forward on or off, Coulomb friction 30 N or 0), each over the
resonance frequencies 10..150 Hz, damping ratios 0.01..0.1 and velocity-loop bandwidths 20 and 40 Hz (kv scaled
with the bandwidth), with a 1 s settle window and a 1 um settling band. Prints:
  1. per configuration, at zeta 0.02 and a 40 Hz velocity loop: the trapezoid / sin² ratios of the max and RMS
     following error and of the max residual error after the setpoint reached the target, with the residuals;
  2. over the whole grid: how many cases reach 2x on each metric, and the range of the residual ratio.
Nothing is tuned here: every row the CLI prints is counted, including runs whose step test fails (marked).
"""
import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CONFIGS = [
    ("A", "load, FF, 30 N", []),
    ("B", "load, FF, 0 N", ["--coulomb", "0"]),
    ("C", "load, no FF, 30 N", ["--no-ff"]),
    ("D", "motor, FF, 30 N", ["--feedback", "motor"]),
    ("E", "motor, FF, 0 N", ["--feedback", "motor", "--coulomb", "0"]),
    ("F", "motor, no FF, 0 N", ["--feedback", "motor", "--no-ff", "--coulomb", "0"]),
]
COMMON = ["--sweep", "--settle-window", "1", "--band", "0.001", "--vel-bw-hz", "20,40", "--json"]


def run(sim, extra):
    p = subprocess.run([sim, "experiment", "kombarov", *COMMON, *extra], capture_output=True, text=True, check=True)
    return json.loads(p.stdout)["sweep"]


def um(mm):
    """3 significant digits, without an exponent"""
    x = 1e3 * mm
    if x >= 1000:
        return str(int(float(f"{x:.3g}")))
    return f"{x:.3g}"


def fmt(x, nd=2):
    return "-" if x is None else f"{x:.{nd}f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim", default=str(ROOT / "build" / "bin" / "lissom-sim"))
    ap.add_argument("--json", help="also write every row to this file")
    a = ap.parse_args()
    data = {key: run(a.sim, extra) for key, _, extra in CONFIGS}
    if a.json:
        Path(a.json).write_text(json.dumps(data, indent=1))

    print("Ratios trapezoid / sin² at zeta 0.02, velocity loop 40 Hz (kv 40 /s): max | RMS | residual, and the")
    print("residual max error in um (trapezoid / sin²). * = the 2 s step test does not settle.\n")
    print("| f_r Hz | " + " | ".join(f"{k}: {name}" for k, name, _ in CONFIGS) + " |")
    print("|---" * (len(CONFIGS) + 1) + "|")
    freqs = sorted({r["drive"]["resonance_hz"] for r in data["A"]})
    for f in freqs:
        cells = []
        for key, _, _ in CONFIGS:
            row = next(r for r in data[key] if abs(r["drive"]["resonance_hz"] - f) < 1e-6 and
                       abs(r["drive"]["damping"] - 0.02) < 1e-9 and abs(r["drive"]["vel_bw_hz"] - 40) < 0.5)
            t, s = row["profiles"]["trapezoid"], row["profiles"]["sin2"]
            cells.append(f"{fmt(row['ratio_max'])} / {fmt(row['ratio_rms'])} / **{fmt(row['ratio_residual_max'])}**"
                         f" ({um(t['residual_max_error'])} / {um(s['residual_max_error'])})"
                         + ("" if row["step_test_settled"] else " *"))
        print(f"| {f:.0f} | " + " | ".join(cells) + " |")

    print("\nWhole grid (8 resonances x 4 damping ratios x 2 velocity loops = 64 cases per configuration): cases")
    print("with ratio >= 2 (all cases / those whose step test settles), and the range of the residual ratio.\n")
    print("| Configuration | max >= 2x | RMS >= 2x | residual >= 2x | residual ratio min..max (settled) |")
    print("|---|---|---|---|---|")
    for key, name, _ in CONFIGS:
        rows = data[key]
        ok = [r for r in rows if r["step_test_settled"]]

        def count(rs, k):
            return sum(1 for r in rs if r[k] is not None and r[k] >= 2)

        res = [r["ratio_residual_max"] for r in ok if r["ratio_residual_max"] is not None]
        print(f"| {key}: {name} | {count(rows, 'ratio_max')} / {count(ok, 'ratio_max')} | "
              f"{count(rows, 'ratio_rms')} / {count(ok, 'ratio_rms')} | "
              f"{count(rows, 'ratio_residual_max')} / {count(ok, 'ratio_residual_max')} of {len(rows)} / {len(ok)} | "
              f"{min(res):.2f}..{max(res):.2f} |" if res else f"| {key}: {name} | - | - | - | - |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
