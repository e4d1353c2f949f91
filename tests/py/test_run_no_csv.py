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
        assert _without_times(no_csv) == _without_times(with_csv)
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
