"""`lissom-sim run --no-csv` (the planning-only timing mode of scripts/bench_klipper.py): only summary.json is
written, and the summary is the one a run with the CSVs gives (host times apart); `--plots` with it is refused.
And scripts/bench_klipper.py, which needs a Klipper tree, stops with a clear message (exit 2) when it has none."""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PROGRAM = os.path.join(ROOT, "host_sim", "examples", "pocket.ngc")
MACHINE = os.path.join(ROOT, "host_sim", "machines", "router.json")
TIMES = ("append_ns_per_block", "interp_ns_per_cycle", "prepare_ns_per_piece")


def _without_times(s):
    s = dict(s)
    s["planner_stats"] = {k: v for k, v in s["planner_stats"].items() if k not in TIMES}
    return s


def test_no_csv_writes_only_the_summary(sim, tmp_path):
    for drive in ([], ["--no-drive"]):
        a, b = tmp_path / ("csv" + "".join(drive)), tmp_path / ("nocsv" + "".join(drive))
        with_csv = sim("run", PROGRAM, "--machine", MACHINE, "--out", a, "--json", "--no-progress", *drive)
        no_csv = sim("run", PROGRAM, "--machine", MACHINE, "--out", b, "--json", "--no-progress", "--no-csv", *drive)
        assert sorted(os.listdir(a)) == ["run.csv", "setpoints.csv", "summary.json"]
        assert os.listdir(b) == ["summary.json"]
        assert {k: v for k, v in _without_times(no_csv).items() if k != "program_held_max"} == \
            {k: v for k, v in _without_times(with_csv).items() if k != "program_held_max"}
        assert _without_times(json.loads((b / "summary.json").read_text())) == _without_times(no_csv)
        assert ("max_following_error" in no_csv["axes"][0]) == (not drive)


def test_no_csv_and_plots_refused(sim, tmp_path):
    p = sim("run", PROGRAM, "--machine", MACHINE, "--out", tmp_path, "--no-csv", "--plots", ok=False)
    assert p.returncode == 2 and "--no-csv" in p.stderr
    assert not os.listdir(tmp_path)


def test_bench_klipper_without_klipper_says_so(tmp_path):
    env = dict(os.environ)
    env.pop("KLIPPER_SRC", None)
    for args in ([], ["--klipper", str(tmp_path / "no-klipper")]):
        p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "bench_klipper.py"), *args],
                           capture_output=True, text=True, env=env, timeout=60)
        assert p.returncode == 2
        assert "no Klipper source" in p.stderr and "--klipper" in p.stderr


def _varied_program(path, seed, n_runs):
    """A long program of what CAM writes: chord runs (arc-fitted), arcs and helices, rapids, feed changes, exact-stop
    and blend modes, spindle, coolant, tool changes, dwells and pauses (machine functions with exact stops)."""
    import math
    import random
    rnd = random.Random(seed)
    out = ["%", "(varied long program, seed %d)" % seed, "G21 G90 G17 G64 P0.02", "G0 Z5", "G0 X0 Y0", "S12000 M3"]
    x, y = 0.0, 0.0
    for k in range(n_runs):
        kind = rnd.randrange(6)
        if kind == 0:  # a run of short chords on a circle
            r, th0 = rnd.uniform(3, 30), rnd.uniform(0, 2 * math.pi)
            cx, cy = x - r * math.cos(th0), y - r * math.sin(th0)
            th = th0
            out.append("G1 Z-1 F%d" % rnd.choice((300, 600)))
            out.append("F%d" % rnd.choice((1500, 3000, 6000, 12000)))
            for _ in range(rnd.randint(20, 300)):
                th += rnd.uniform(0.05, 0.3) / r
                x, y = cx + r * math.cos(th), cy + r * math.sin(th)
                out.append("G1 X%.4f Y%.4f" % (x, y))
        elif kind == 1:  # arcs and a helix
            r = rnd.uniform(1, 20)
            out.append("G%d X%.4f Y%.4f Z%.3f I%.4f J0 F%d" % (rnd.choice((2, 3)), x + 2 * r, y, rnd.uniform(-2, 0),
                                                              r, rnd.choice((600, 2400))))
            x += 2 * r
        elif kind == 2:  # a rapid elsewhere
            x, y = rnd.uniform(-60, 60), rnd.uniform(-60, 60)
            out.append("G0 Z5")
            out.append("G0 X%.3f Y%.3f" % (x, y))
        elif kind == 3:  # a zigzag in exact stop or a blend mode
            out.append(rnd.choice(("G61", "G64", "G64 P0.005", "G64 P0.05")))
            for _ in range(rnd.randint(2, 30)):
                x += rnd.uniform(-2, 2)
                y += rnd.uniform(-2, 2)
                out.append("G1 X%.4f Y%.4f F%d" % (x, y, rnd.choice((900, 4000))))
        elif kind == 4:  # machine functions
            out.append(rnd.choice(("M8", "M9", "G4 P0.05", "M5", "S8000 M3", "M0", "T2 M6", "M7")))
        else:  # blank lines, comments, line numbers
            out.append(rnd.choice(("", "(comment)", "; note", "N%d G1 X%.3f" % (k, x))))
    out += ["M5 M9", "G0 Z5", "M30", "%"]
    path.write_text("\n".join(out) + "\n")


def test_no_csv_long_program_is_windowed_and_measured_the_same(sim, tmp_path):
    """--no-csv reads the program in chunks and keeps only a window of it (simprog.h): over thousands of blocks
    with machine functions, mode changes and arcs, its summary is the one the run that loads the program whole and
    keeps every setpoint gives (times and the window's size apart), and the window is a small part of it."""
    prog = tmp_path / "varied.ngc"
    _varied_program(prog, 7, 700)
    a = sim("run", prog, "--machine", MACHINE, "--out", tmp_path / "a", "--json", "--no-progress", "--no-drive")
    b = sim("run", prog, "--machine", MACHINE, "--out", tmp_path / "b", "--json", "--no-progress", "--no-drive",
            "--no-csv")
    assert a["program_blocks"] > 20000, a["program_blocks"]
    assert a["program_held_max"] >= a["program_blocks"]  # whole: every block and path element
    assert b["program_held_max"] < a["program_blocks"] / 2, b["program_held_max"]
    strip = lambda s: {k: v for k, v in _without_times(s).items() if k != "program_held_max"}
    assert strip(b) == strip(a)


_RSS = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL); "
        "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")


def _circle(path, n):
    import math
    lines = ["G21 G90 G64", "G0 X25 Y0", "F12000"]
    for i in range(1, n + 1):
        th = i * 0.15 / 25
        lines.append("G1 X%.4f Y%.4f" % (25 * math.cos(th), 25 * math.sin(th)))
    path.write_text("\n".join(lines + ["M2"]) + "\n")


def test_no_csv_memory_does_not_grow_with_the_program(sim, tmp_path):
    """Peak memory (max RSS) of `run --no-csv` on a 200,000-block program is that of a 20,000-block one, within
    2 MB (a program loaded whole takes about 350 bytes per block: 60 MB more)."""
    path = os.environ.get("LISSOM_SIM") or os.path.join(ROOT, "build", "bin", "lissom-sim")
    rss = {}
    for n in (20000, 200000):
        prog = tmp_path / ("c%d.ngc" % n)
        _circle(prog, n)
        p = subprocess.run([sys.executable, "-c", _RSS, path, "run", str(prog), "--machine", MACHINE, "--out",
                            str(tmp_path / str(n)), "--no-csv", "--no-drive", "--no-progress"],
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        rss[n] = int(p.stdout.split()[-1])  # KiB
    assert rss[200000] <= rss[20000] + 2048, rss
