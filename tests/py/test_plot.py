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


def test_labels_units_legends(tmp_path, monkeypatch):
    """Every run plot is readable on its own: a title, axis labels with units in brackets (mm, mm/s, mm/s², mm/s³;
    rad for the rotary axis), and a legend naming what is drawn (the setpoint trace, the machine's limits, the
    actual path, start and end); the feed colour bar is labelled with its unit."""
    seen = {}
    real_save = plot._save

    def capture(fig, path):
        axes = []
        for ax in fig.axes:
            leg = ax.get_legend()
            axes.append({"x": ax.get_xlabel(), "y": ax.get_ylabel(), "title": ax.get_title(loc="left"),
                         "legend": [t.get_text() for t in leg.get_texts()] if leg else []})
        seen[os.path.basename(path)] = axes
        return real_save(fig, path)

    monkeypatch.setattr(plot, "_save", capture)
    cols = run_cols(300)
    cols["A_set_rad"] = np.linspace(0, 1, 300)
    cols["A_a_rad_s2"] = np.zeros(300)
    cols["A_j_rad_s3"] = np.zeros(300)
    csv_path = tmp_path / "r.csv"
    write_csv(csv_path, cols)
    machine = tmp_path / "m.json"
    machine.write_text('{"axes": [{"name": "X", "v_max_mm_s": 100, "a_max_mm_s2": 300, "j_max_mm_s3": 5000},'
                       ' {"name": "Y", "v_max_mm_s": 100, "a_max_mm_s2": 300, "j_max_mm_s3": 5000},'
                       ' {"name": "A", "v_max_deg_s": 90, "a_max_deg_s2": 180, "j_max_deg_s3": 3600}]}')
    plot.plot_run(str(csv_path), str(tmp_path), prefix="p", machine=str(machine))
    assert set(seen) == {"p_feed.png", "p_accel.png", "p_jerk.png", "p_path.png", "p_error.png"}

    feed = seen["p_feed.png"][0]
    assert feed["x"] == "t [s]" and feed["y"] == "feed [mm/s]" and feed["title"]
    assert feed["legend"] == ["path feed of the setpoints"]
    for name, what, unit, lim in (("p_accel.png", "acceleration", "s\u00b2", "a_max"),
                                  ("p_jerk.png", "jerk", "s\u00b3", "j_max")):
        panels = seen[name]
        assert [p["y"] for p in panels] == ["X %s [mm/%s]" % (what, unit), "Y %s [mm/%s]" % (what, unit),
                                            "A %s [rad/%s]" % (what, unit)]
        assert panels[-1]["x"] == "t [s]" and panels[0]["title"]
        assert panels[0]["legend"] == ["setpoint (backward difference)", "\u00b1%s (machine file)" % lim]
    err = seen["p_error.png"]
    assert [p["y"] for p in err] == ["X following error [mm]", "Y following error [mm]"]
    assert err[0]["legend"] == ["setpoint \u2212 actual"] and err[-1]["x"] == "t [s]"
    path, cbar = seen["p_path.png"]
    assert path["x"] == "X [mm]" and path["y"] == "Y [mm]" and path["title"]
    assert path["legend"] == ["setpoint (colour: feed)", "actual", "start", "end"]
    assert cbar["y"] == "feed [mm/s]"


def test_sim_run_plots(sim, tmp_path):
    """`lissom-sim run --plots --json`: the five PNGs in the run directory, and stdout is only the summary."""
    root = os.path.dirname(HIL)
    prog = os.path.join(root, "host_sim", "examples", "circle_chords.ngc")
    machine = os.path.join(root, "host_sim", "machines", "router.json")
    out = sim("run", prog, "--machine", machine, "--out", tmp_path / "run", "--json", "--plots")
    assert out["within_limits"] is True  # parsed as JSON: nothing else on stdout
    names = sorted(p.name for p in (tmp_path / "run").glob("*.png"))
    assert names == ["run_accel.png", "run_error.png", "run_feed.png", "run_jerk.png", "run_path.png"]
    for p in (tmp_path / "run").glob("*.png"):
        check_png(str(p))
