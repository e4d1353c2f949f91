"""lissom_hil.plot: the plot functions write real, non-blank PNGs from small synthetic CSVs, find columns by
name (order and extra columns do not matter, missing ones skip a plot), and reject malformed input."""
import os
import subprocess
import sys

import numpy as np
import pytest

HIL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "hil")
sys.path.insert(0, HIL)

from lissom_hil import plot  # noqa: E402

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def write_csv(path, cols):
    names = list(cols)
    n = len(next(iter(cols.values())))
    with open(path, "w") as f:
        f.write(",".join(names) + "\n")
        for i in range(n):
            f.write(",".join("%.9g" % cols[c][i] for c in names) + "\n")


def run_cols(n=400):
    """A circle of radius 10 at a feed that ramps up and down, with derivatives by differences."""
    t = np.arange(n) * 1e-3
    feed = 50.0 * np.sin(np.pi * t / t[-1]) ** 2
    s = np.concatenate([[0.0], np.cumsum(feed[1:] * 1e-3)])
    ang = s / 10.0
    cols = {"t_s": t, "feed_mm_s": feed}
    for a, f in (("X", np.cos), ("Y", np.sin)):
        p = 10.0 * f(ang)
        v = np.gradient(p, t)
        acc = np.gradient(v, t)
        j = np.gradient(acc, t)
        act = np.concatenate([[p[0]], p[:-1]])  # one cycle behind
        cols.update({a + "_set_mm": p, a + "_act_mm": act, a + "_err_mm": p - act, a + "_v_mm_s": v,
                     a + "_a_mm_s2": acc, a + "_j_mm_s3": j})
    return cols


def check_png(path, min_w=300, min_h=200):
    assert os.path.isfile(path), path
    assert os.path.getsize(path) > 2000, path
    with open(path, "rb") as f:
        assert f.read(8) == PNG_MAGIC
    import matplotlib.image as mpimg
    img = mpimg.imread(path)
    assert img.shape[0] >= min_h and img.shape[1] >= min_w
    assert float(np.std(img[..., :3])) > 0.01, "blank image: " + path  # not a uniform picture


def test_run_plots(tmp_path):
    csv_path = tmp_path / "circle.csv"
    write_csv(csv_path, run_cols())
    machine = tmp_path / "m.json"
    machine.write_text('{"axes": [{"name": "X", "v_max_mm_s": 100, "a_max_mm_s2": 300, "j_max_mm_s3": 5000},'
                       ' {"name": "A", "v_max_deg_s": 90, "a_max_deg_s2": 180, "j_max_deg_s3": 3600}]}')
    paths = plot.plot_run(str(csv_path), str(tmp_path / "out"), machine=str(machine))
    names = sorted(os.path.basename(p) for p in paths)
    assert names == ["circle_accel.png", "circle_error.png", "circle_feed.png", "circle_jerk.png", "circle_path.png"]
    for p in paths:
        check_png(p)
    lim = plot.machine_limits(str(machine))
    assert lim["X"]["a"] == 300 and abs(lim["A"]["v"] - np.pi / 2) < 1e-12


def test_columns_by_name(tmp_path):
    cols = run_cols(200)
    # reorder, add unknown columns, drop the jerk and error columns, use the short time name
    keep = {k: v for k, v in reversed(list(cols.items())) if "_j_" not in k and "_err_" not in k}
    keep["t"] = keep.pop("t_s")
    keep["block"] = np.arange(200) // 10
    keep["Z_cur_A"] = np.zeros(200)
    csv_path = tmp_path / "r.csv"
    write_csv(csv_path, keep)
    paths = plot.plot_run(str(csv_path), str(tmp_path), prefix="p")
    names = sorted(os.path.basename(p) for p in paths)
    assert "p_jerk.png" not in names  # no jerk columns: skipped
    assert "p_error.png" in names     # derived from set - act
    assert "p_path.png" in names and "p_feed.png" in names and "p_accel.png" in names
    for p in paths:
        check_png(p)
    ax = plot.axis_columns(plot.read_csv(str(csv_path)))
    assert list(ax) == ["X", "Y", "Z"]
    assert ax["X"]["set"] == "X_set_mm"


def test_scurve_plot(tmp_path):
    # a sin^2 jerk pulse and its integrals
    t = np.linspace(0.0, 0.1, 101)
    j = 16000.0 * np.sin(np.pi * t / 0.1) ** 2
    a = np.concatenate([[0.0], np.cumsum(0.5 * (j[1:] + j[:-1]) * np.diff(t))])
    v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * np.diff(t))])
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    csv_path = tmp_path / "sc.csv"
    with open(csv_path, "w") as f:
        f.write("# lissom-sim scurve samples\n")
        write_rows = ["t,j,a,v,s,extra"] + ["%g,%g,%g,%g,%g,0" % r for r in zip(t, j, a, v, s)]
        f.write("\n".join(write_rows) + "\n")
    out = plot.plot_scurve(str(csv_path), str(tmp_path / "sc.png"), title="test")
    check_png(out, min_h=600)
    # default output name
    out2 = plot.plot_scurve(str(csv_path))
    assert out2 == str(tmp_path / "sc.png")


def test_bad_input(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("x,y\n1,2\n")
    with pytest.raises(ValueError, match="time column"):
        plot.plot_run(str(p), str(tmp_path))
    with pytest.raises(ValueError, match="t,j,a,v,s"):
        plot.plot_scurve(str(p))
    p.write_text("t_s,feed_mm_s\n0,1\n1,abc\n")
    with pytest.raises(ValueError, match="not a number"):
        plot.read_csv(str(p))
    p.write_text("t_s,feed_mm_s\n0,1,2\n")
    with pytest.raises(ValueError, match="3 cells"):
        plot.read_csv(str(p))
    p.write_text("t_s,t_s\n0,1\n")
    with pytest.raises(ValueError, match="repeated"):
        plot.read_csv(str(p))


def test_cli(tmp_path):
    csv_path = tmp_path / "c.csv"
    write_csv(csv_path, run_cols(100))
    env = dict(os.environ, PYTHONPATH=HIL + os.pathsep + os.environ.get("PYTHONPATH", ""))
    r = subprocess.run([sys.executable, "-m", "lissom_hil.plot", "run", str(csv_path), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    outs = r.stdout.split()
    assert len(outs) == 5
    for p in outs:
        check_png(p)
    r = subprocess.run([sys.executable, "-m", "lissom_hil.plot", "scurve", str(csv_path)], capture_output=True,
                       text=True, env=env, timeout=120)
    assert r.returncode == 1 and "t,j,a,v,s" in r.stderr


def test_sim_plot_subcommand(sim, tmp_path):
    """`lissom-sim run` then `lissom-sim plot RUN_DIR`: the five PNGs from the run's own CSV, and clean errors."""
    root = os.path.dirname(HIL)
    prog = os.path.join(root, "host_sim", "examples", "shahzadeh_corner.ngc")
    machine = os.path.join(root, "host_sim", "machines", "router.json")
    run_dir = tmp_path / "run"
    sim("run", prog, "--machine", machine, "--out", run_dir)
    assert not list(run_dir.glob("*.png"))  # no --plots: the run itself drew nothing
    sim("plot", run_dir, "--machine", machine, "--out", tmp_path / "png")
    names = sorted(p.name for p in (tmp_path / "png").glob("*.png"))
    assert names == ["run_accel.png", "run_error.png", "run_feed.png", "run_jerk.png", "run_path.png"]
    for p in (tmp_path / "png").glob("*.png"):
        check_png(str(p))
    sim("plot", run_dir)  # default output: the run directory
    assert len(list(run_dir.glob("*.png"))) == 5
    r = sim("plot", tmp_path / "missing", ok=False)
    assert r.returncode == 1 and "run.csv not found" in r.stderr
    r = sim("plot", run_dir, "--machine", tmp_path / "none.json", ok=False)
    assert r.returncode == 1 and "machine file" in r.stderr
    r = sim("plot", ok=False)
    assert r.returncode == 2 and "usage" in r.stderr
    r = sim("plot", run_dir, "--bogus", "1", ok=False)
    assert r.returncode == 2
