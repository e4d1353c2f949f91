#!/usr/bin/env python3
"""bench_klipper.py: host planning cost of lissom-sim against Klipper's batch mode on the same G-code (issue 12).

    scripts/bench_klipper.py --klipper DIR [--klipper-python PY] [--dict FILE] [--build-mcu CONFIG]
                             [--segments 50000] [--repeat 3] [--steps-per-mm 80] [--scv 5]
                             [--machine host_sim/machines/router.json] [--sim build/bin/lissom-sim] [--json]

A benchmark, not a test (it is not in scripts/test.sh). It writes two programs of `--segments` G1 chords with
lengths drawn uniformly from 0.1-0.2 mm at F12000: a circle of R 25 (wrapping round) and an Archimedean spiral
from R 25 to R 30. Both sides read the same G-code lines; Klipper's input has three lines of its own in front
(SET_KINEMATIC_POSITION, a dwell and a start mark) and its printer.cfg defines M2 as "wait for the moves, print the
print time", so that its motion time can be read exactly.

Klipper: `klippy.py printer.cfg -i FILE -o OUT.serial -d klipper.dict` (docs/Debugging.md of Klipper, batch mode;
-v is left out: it only adds debug logging), cartesian kinematics, max_velocity and max_accel of the machine
file's X axis, square_corner_velocity --scv (Klipper's default 5 mm/s; on these shapes neither Klipper's junction
speed nor its centripetal limit binds), `--steps-per-mm` (80: 16 microsteps, 200 steps, 40 mm per turn).
Klipper has no jerk limit. Its batch time includes: Python start and config (measured apart on a 2-block file),
G-code parsing, its look-ahead (trapezoids), step generation (itersolve) and step compression (C), and encoding
the MCU commands into the output file.
Lissom: `lissom-sim run FILE --machine M --no-drive --no-csv` (and once with the CSVs, for reference): G-code
parsing, arc fitting, corner smoothing, the look-ahead planner (sin² S-curves, jerk and snap limited), the
interpolator at the machine's cycle (1 ms on router.json) and the measurement of the setpoints (axis v, a, j by
backward differences, deviation from the programmed path, end error); no steps.

Time is CPU time (user + sys) of the child process (os.wait4), the smallest of --repeat runs (the wall time of
those runs is printed too: on a shared machine it includes waiting for a core); per block it is
reported both as total / blocks and as (total - the same side's time on a 2-block file) / blocks ("marginal").
Motion time: Klipper's print time from the start mark to the end of the last move; Lissom's `duration`.
Exits 2 with a message when Klipper, its Python or its data dictionary is missing.
"""
import argparse
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

KLIPPER_PRELUDE = "SET_KINEMATIC_POSITION X=0 Y=0 Z=0\nG4 P2000\n_BENCH_START\n"

PRINTER_CFG = """# written by lissom scripts/bench_klipper.py
[mcu]
serial: /dev/null

[printer]
kinematics: cartesian
max_velocity: {v}
max_accel: {a}
square_corner_velocity: {scv}
max_z_velocity: {vz}
max_z_accel: {az}

{steppers}
[force_move]
enable_force_move: True

[gcode_macro _BENCH_START]
gcode:
  {{action_respond_info("BENCH_START print_time=%.9f" % printer.toolhead.print_time)}}

[gcode_macro _BENCH_END]
gcode:
  {{action_respond_info("BENCH_END print_time=%.9f" % printer.toolhead.print_time)}}

[gcode_macro M2]
gcode:
  M400
  _BENCH_END
"""

STEPPER = """[stepper_{n}]
step_pin: {p}{s}
dir_pin: {p}{d}
enable_pin: !{p}{e}
microsteps: 16
rotation_distance: {rd}
endstop_pin: {p}{es}
position_endstop: -500
position_min: -500
position_max: 500

"""


def die(msg):
    sys.stderr.write("bench_klipper: " + msg + "\n")
    sys.exit(2)


def gen_program(kind, n, seed=1):
    """G1 chords of 0.1-0.2 mm from (0, 0) round a centre at (-25, 0): a circle of R 25 or a spiral R 25 -> 30."""
    rng = random.Random(seed)
    r0, r1 = 25.0, 30.0
    cx, cy = -r0, 0.0
    th, r = 0.0, r0
    lines = ["G90", "G21", "G1 F12000"]
    length, px, py = 0.0, 0.0, 0.0
    for i in range(n):
        c = rng.uniform(0.1, 0.2)
        if kind == "spiral":
            r = r0 + (r1 - r0) * (i + 1) / n
        th += 2 * math.asin(c / (2 * r))
        x, y = round(cx + r * math.cos(th), 4), round(cy + r * math.sin(th), 4)
        length += math.hypot(x - px, y - py)
        px, py = x, y
        lines.append("G1 X%.4f Y%.4f" % (x, y))
    lines.append("M2")
    return "\n".join(lines) + "\n", length


def run_cpu(cmd, cwd=None):
    """Runs cmd; returns (cpu seconds user+sys of the child, wall seconds, stdout, stderr, exit status)."""
    with tempfile.TemporaryFile() as fo, tempfile.TemporaryFile() as fe:
        t0 = time.monotonic()
        p = subprocess.Popen(cmd, stdout=fo, stderr=fe, cwd=cwd)
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.monotonic() - t0
        p.returncode = os.waitstatus_to_exitcode(status)
        fo.seek(0)
        fe.seek(0)
        return ru.ru_utime + ru.ru_stime, wall, fo.read().decode(), fe.read().decode(), p.returncode


def klipper_run(a, work, cfg, gcode_text, name):
    path = os.path.join(work, name + ".klipper.gcode")
    with open(path, "w") as f:
        f.write(KLIPPER_PRELUDE + gcode_text)
    cmd = [a.klipper_python, os.path.join(a.klipper, "klippy", "klippy.py"), cfg, "-i", path,
           "-o", os.path.join(work, name + ".serial"), "-d", a.dict]
    best = None
    for _ in range(a.repeat):
        cpu, wall, _, err, rc = run_cpu(cmd)
        if rc != 0:
            die("klippy failed (exit %d) on %s:\n%s" % (rc, path, err[-3000:]))
        t0 = re.search(r"BENCH_START print_time=([0-9.]+)", err)
        t1 = re.search(r"BENCH_END print_time=([0-9.]+)", err)
        if not t0 or not t1:
            die("klippy printed no BENCH_START/BENCH_END marks on %s:\n%s" % (path, err[-3000:]))
        motion = float(t1.group(1)) - float(t0.group(1))
        if best is None or cpu < best[0]:
            best = (cpu, motion, wall)
    return best


def lissom_run(a, work, gcode_text, name, csv=False):
    path = os.path.join(work, name + ".ngc")
    with open(path, "w") as f:
        f.write(gcode_text)
    cmd = [a.sim, "run", path, "--machine", a.machine, "--out", os.path.join(work, name + ".lissom"), "--no-drive",
           "--json", "--no-progress"] + ([] if csv else ["--no-csv"])
    best = None
    for _ in range(a.repeat):
        cpu, wall, out, err, rc = run_cpu(cmd)
        if rc != 0:
            die("lissom-sim failed (exit %d) on %s:\n%s" % (rc, path, err[-3000:]))
        s = json.loads(out)
        if not s["within_limits"] or s["planner_stats"]["fallbacks"]:
            die("lissom-sim run on %s is not within the limits or had fallbacks: not a valid comparison" % path)
        if best is None or cpu < best[0]:
            best = (cpu, s["duration"], s, wall)
    return best


def check_inputs(a):
    if not a.klipper or not os.path.isfile(os.path.join(a.klipper, "klippy", "klippy.py")):
        die("no Klipper source at %r (klippy/klippy.py missing). Give its path with --klipper DIR or $KLIPPER_SRC "
            "(git clone https://github.com/Klipper3d/klipper)." % a.klipper)
    if not a.klipper_python:
        guess = os.path.join(os.path.dirname(os.path.abspath(a.klipper)), "kvenv", "bin", "python")
        a.klipper_python = guess if os.path.exists(guess) else None
    if not a.klipper_python or not os.path.exists(a.klipper_python):
        die("no Python for Klipper (--klipper-python or $KLIPPER_PYTHON): make a venv apart from the project's, "
            "e.g. python3 -m venv kvenv && kvenv/bin/pip install -r KLIPPER/scripts/klippy-requirements.txt "
            "(cffi, greenlet, Jinja2, markupsafe, pyserial are what batch mode needs)")
    chk = subprocess.run([a.klipper_python, "-c", "import cffi, greenlet, jinja2, serial"], capture_output=True)
    if chk.returncode != 0:
        die("%s cannot import cffi, greenlet, jinja2 and serial (Klipper's batch mode needs them):\n%s"
            % (a.klipper_python, chk.stderr.decode()[-1000:]))
    if not a.dict:
        a.dict = os.path.join(a.klipper, "out", "klipper.dict")
    if not os.path.isfile(a.dict) and a.build_mcu:
        cfg = a.build_mcu if os.path.isabs(a.build_mcu) else os.path.join(a.klipper, a.build_mcu)
        sys.stderr.write("building Klipper's MCU code with %s (for its data dictionary)\n" % cfg)
        shutil.copy(cfg, os.path.join(a.klipper, ".config"))
        for c in (["make", "olddefconfig"], ["make"]):
            r = subprocess.run(c, cwd=a.klipper, capture_output=True)
            if r.returncode != 0:
                die("%s in %s failed:\n%s" % (" ".join(c), a.klipper, r.stderr.decode()[-2000:]))
    if not os.path.isfile(a.dict):
        die("no data dictionary %r: build Klipper's MCU code once (cd KLIPPER; cp test/configs/stm32f407.config "
            ".config; make olddefconfig; make: needs arm-none-eabi-gcc), or pass --build-mcu "
            "test/configs/stm32f407.config, or --dict FILE" % a.dict)
    if not os.path.isfile(a.sim) or not os.access(a.sim, os.X_OK):
        die("no lissom-sim at %r (scripts/build.sh, or --sim PATH)" % a.sim)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--klipper", default=os.environ.get("KLIPPER_SRC"), help="Klipper source tree")
    ap.add_argument("--klipper-python", default=os.environ.get("KLIPPER_PYTHON"),
                    help="Python with Klipper's requirements (default: kvenv/bin/python next to the Klipper tree)")
    ap.add_argument("--dict", help="Klipper data dictionary (default KLIPPER/out/klipper.dict); printer.cfg uses "
                    "STM32 pin names (PA0 ...), so the dictionary must be of an STM32 build")
    ap.add_argument("--build-mcu", metavar="CONFIG", help="build the MCU code with this Klipper config if no dict")
    ap.add_argument("--segments", type=int, default=50000)
    ap.add_argument("--repeat", type=int, default=3, help="runs per measurement; the smallest CPU time is kept")
    ap.add_argument("--steps-per-mm", type=float, default=80.0, help="Klipper's X Y step resolution")
    ap.add_argument("--scv", type=float, default=5.0, help="Klipper's square_corner_velocity, mm/s")
    ap.add_argument("--machine", default=os.path.join(REPO, "host_sim", "machines", "router.json"))
    ap.add_argument("--sim", default=os.path.join(REPO, "build", "bin", "lissom-sim"))
    ap.add_argument("--work", help="directory for the programs and outputs (default: a temporary one)")
    ap.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    a = ap.parse_args()
    check_inputs(a)
    if a.segments < 10 or a.repeat < 1 or not a.steps_per_mm > 0 or not a.scv > 0:
        die("--segments >= 10, --repeat >= 1, --steps-per-mm > 0 and --scv > 0, please")
    with open(a.machine) as f:
        m = json.load(f)
    ax = {x["name"]: x for x in m["axes"]}
    v = min(ax[n]["v_max_mm_s"] for n in "XY")
    acc = min(ax[n]["a_max_mm_s2"] for n in "XY")
    z = ax.get("Z", ax["X"])
    work = a.work or tempfile.mkdtemp(prefix="bench_klipper_")
    os.makedirs(work, exist_ok=True)
    rd = 16 * 200 / a.steps_per_mm
    steppers = "".join(STEPPER.format(n=n, p=p, s=0, d=1, e=2, es=3, rd="%.6g" % rd) for n, p in (("x", "PA"), ("y", "PB")))
    steppers += STEPPER.format(n="z", p="PC", s=0, d=1, e=2, es=3, rd="%.6g" % (rd / 5))
    cfg = os.path.join(work, "printer.cfg")
    with open(cfg, "w") as f:
        f.write(PRINTER_CFG.format(v=v, a=acc, scv=a.scv, vz=z["v_max_mm_s"], az=z["a_max_mm_s2"], steppers=steppers))

    tiny, _ = gen_program("circle", 2)
    klipper_run(a, work, cfg, tiny, "warmup")  # Klipper compiles its C helper (cffi) on its first run: not timed
    kt = klipper_run(a, work, cfg, tiny, "tiny")
    lt = lissom_run(a, work, tiny, "tiny")
    rows = []
    for shape in ("circle", "spiral"):
        text, length = gen_program(shape, a.segments)
        k = klipper_run(a, work, cfg, text, shape)
        lc = lissom_run(a, work, text, shape)
        lcsv = lissom_run(a, work, text, shape + "_csv", csv=True)
        n = a.segments
        row = {
            "shape": shape, "blocks": n, "length_mm": length, "length_over_feed_s": length / 200.0,
            "klipper_cpu_s": k[0], "klipper_us_per_block": 1e6 * k[0] / n,
            "klipper_marginal_us_per_block": 1e6 * (k[0] - kt[0]) / n, "klipper_motion_s": k[1],
            "lissom_cpu_s": lc[0], "lissom_us_per_block": 1e6 * lc[0] / n,
            "lissom_marginal_us_per_block": 1e6 * (lc[0] - lt[0]) / n, "lissom_motion_s": lc[1],
            "lissom_with_csv_cpu_s": lcsv[0],
            "klipper_wall_s": k[2], "lissom_wall_s": lc[3], "lissom_with_csv_wall_s": lcsv[3],
            "lissom_append_ns_per_block": lc[2]["planner_stats"]["append_ns_per_block"],
            "lissom_pieces": lc[2]["planner_stats"]["pieces"],
        }
        row["ratio"] = row["lissom_cpu_s"] / row["klipper_cpu_s"]
        row["ratio_marginal"] = row["lissom_marginal_us_per_block"] / row["klipper_marginal_us_per_block"]
        row["ratio_with_csv"] = row["lissom_with_csv_cpu_s"] / row["klipper_cpu_s"]
        rows.append(row)
    res = {"klipper": os.path.abspath(a.klipper), "dict": os.path.abspath(a.dict), "machine": a.machine,
           "steps_per_mm": a.steps_per_mm, "square_corner_velocity": a.scv, "max_velocity": v, "max_accel": acc,
           "repeat": a.repeat, "klipper_startup_cpu_s": kt[0], "lissom_startup_cpu_s": lt[0], "rows": rows,
           "goal_ratio": 0.25, "work": work}
    if a.json:
        print(json.dumps(res, indent=1))
        return
    print("Klipper %s (dict %s), %g steps/mm, scv %g mm/s, v %g mm/s, a %g mm/s^2 (no jerk limit)"
          % (a.klipper, os.path.basename(a.dict), a.steps_per_mm, a.scv, v, acc))
    print("Lissom %s --no-drive --no-csv on %s; CPU time (user+sys), best of %d; startup: Klipper %.3f s, Lissom "
          "%.3f s" % (os.path.relpath(a.sim, REPO), os.path.relpath(a.machine, REPO), a.repeat, kt[0], lt[0]))
    print("%-7s %7s | %9s %9s %9s %8s | %9s %9s %9s %8s %9s | %6s %6s %6s" % (
        "shape", "blocks", "K cpu s", "K us/blk", "K marg", "K mot s", "L cpu s", "L us/blk", "L marg", "L mot s",
        "L+csv s", "ratio", "marg", "+csv"))
    for r in rows:
        print("%-7s %7d | %9.3f %9.2f %9.2f %8.3f | %9.3f %9.2f %9.2f %8.3f %9.3f | %6.3f %6.3f %6.3f" % (
            r["shape"], r["blocks"], r["klipper_cpu_s"], r["klipper_us_per_block"],
            r["klipper_marginal_us_per_block"], r["klipper_motion_s"], r["lissom_cpu_s"], r["lissom_us_per_block"],
            r["lissom_marginal_us_per_block"], r["lissom_motion_s"], r["lissom_with_csv_cpu_s"], r["ratio"],
            r["ratio_marginal"], r["ratio_with_csv"]))
    for r in rows:
        print("%-7s wall time of the same runs: Klipper %.3f s, Lissom %.3f s (%.3f s with the CSVs): ratio %.3f" % (
            r["shape"], r["klipper_wall_s"], r["lissom_wall_s"], r["lissom_with_csv_wall_s"],
            r["lissom_wall_s"] / r["klipper_wall_s"]))
    worst = max(max(r["ratio"], r["ratio_marginal"]) for r in rows)
    print("goal: Lissom <= 0.25x Klipper per block: %s (worst ratio %.3f)" % ("met" if worst <= 0.25 else "NOT met",
                                                                            worst))
    if not a.work:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
