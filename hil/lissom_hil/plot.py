"""PNG plots of lissom-sim runs and S-curve samples (matplotlib, Agg backend: no display needed).

    python -m lissom_hil.plot run RUN.csv [--out DIR] [--prefix NAME] [--machine MACHINE.json] [--path X,Y]
    python -m lissom_hil.plot scurve SAMPLES.csv [--out FILE.png] [--title TEXT] [--unit mm]

`run` makes, from a run CSV (schema in docs/host_sim.md, columns found by name):
    <prefix>_feed.png    feed against time (and the programmed feed if the CSV has it)
    <prefix>_accel.png   per-axis acceleration against time (with +-a_max from --machine)
    <prefix>_jerk.png    per-axis jerk against time (with +-j_max from --machine)
    <prefix>_path.png    the path in the plane of two axes (default X, Y), coloured by feed
    <prefix>_error.png   per-axis following error against time
Plots whose columns are missing are skipped. `scurve` plots a CSV with the header t,j,a,v,s (extra columns
are ignored) as four stacked panels J, A, V, S sharing the time axis.
Each command prints the PNG files it wrote, one per line.
"""
import argparse
import csv
import json
import math
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

DPI = 110
# legends sit above the (top) panel, right-aligned, so that they never hide data
_LEGEND = dict(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=3, fontsize="small", frameon=False)
# per-axis columns: <AXIS>_<kind>[_<unit>...], AXIS one upper-case letter, kind one of these
_AXIS_COL = re.compile(r"^([A-Z])_(set|act|err|v|a|j|cur)(?:_[A-Za-z0-9_]+)?$")
_ALIASES = {"t": "t_s", "time": "t_s", "time_s": "t_s", "feed": "feed_mm_s", "feed_cmd": "feed_cmd_mm_s"}
_ROTARY = set("ABC")


def read_csv(path):
    """Read a CSV with a header row into {column name: float array}. Lines starting with '#' before the
    header are skipped; empty cells become NaN. Raises ValueError on a malformed file."""
    with open(path, newline="", encoding="utf-8") as f:
        header = None
        for line in f:
            if line.strip() and not line.startswith("#"):
                header = [h.strip() for h in next(csv.reader([line]))]
                break
        if header is None:
            raise ValueError("%s: no header" % path)
        if len(set(header)) != len(header):
            raise ValueError("%s: repeated column names" % path)
        try:  # fast path (numpy's C parser); the careful parser below explains any failure
            data = np.loadtxt(f, delimiter=",", ndmin=2, comments="#")
            if data.size == 0:
                data = np.zeros((0, len(header)))
            if data.shape[1] == len(header):
                return _with_aliases({h: data[:, j] for j, h in enumerate(header)})
        except ValueError:
            pass
    with open(path, newline="", encoding="utf-8") as f:
        rows = [r for r in csv.reader(f) if r and not (r[0].startswith("#"))]
    data = np.full((len(rows) - 1, len(header)), np.nan)
    for i, r in enumerate(rows[1:]):
        if len(r) != len(header):
            raise ValueError("%s:%d: %d cells, the header has %d" % (path, i + 2, len(r), len(header)))
        for j, cell in enumerate(r):
            cell = cell.strip()
            if cell:
                try:
                    data[i, j] = float(cell)
                except ValueError:
                    raise ValueError("%s:%d: column %s: not a number: %r" % (path, i + 2, header[j], cell))
    return _with_aliases({h: data[:, j] for j, h in enumerate(header)})


def _with_aliases(cols):
    for alias, name in _ALIASES.items():
        if alias in cols and name not in cols:
            cols[name] = cols[alias]
    return cols


def axis_columns(cols):
    """{axis letter: {kind: column name}} for the per-axis columns present, axes in X..C order."""
    found = {}
    for name in cols:
        m = _AXIS_COL.match(name)
        if m:
            found.setdefault(m.group(1), {}).setdefault(m.group(2), name)
    order = "XYZABCUVW"
    return {k: found[k] for k in sorted(found, key=lambda a: order.index(a) if a in order else 99)}


def _unit(axis, power):
    base = "rad" if axis in _ROTARY else "mm"
    return base if power == 0 else "%s/s%s" % (base, "" if power == 1 else "\u00b2\u00b3\u2074"[power - 2])


def machine_limits(path):
    """{axis letter: {"v": , "a": , "j": } in mm (or rad) units} from a machine file (lissom-machine-1)."""
    with open(path, encoding="utf-8") as f:
        m = json.load(f)
    out = {}
    for ax in m.get("axes", []):
        name = ax.get("name")
        if name in _ROTARY:
            k = math.pi / 180.0
            out[name] = {"v": ax["v_max_deg_s"] * k, "a": ax["a_max_deg_s2"] * k, "j": ax["j_max_deg_s3"] * k}
        else:
            out[name] = {"v": ax["v_max_mm_s"], "a": ax["a_max_mm_s2"], "j": ax["j_max_mm_s3"]}
    return out


def _time(cols):
    if "t_s" not in cols:
        raise ValueError("the CSV has no time column (t_s or t)")
    return cols["t_s"]


def _save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def plot_feed(cols, out_png, title=None):
    t = _time(cols)
    if "feed_mm_s" not in cols:
        return None
    fig, ax = plt.subplots(figsize=(10, 4))
    ax.plot(t, cols["feed_mm_s"], lw=1.0, label="path feed of the setpoints")
    if "feed_cmd_mm_s" in cols:
        ax.plot(t, cols["feed_cmd_mm_s"], lw=0.8, ls="--", color="0.4", label="programmed")
    ax.legend(**_LEGEND)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("feed [mm/s]")
    ax.set_title(title or "Feed", loc="left")
    ax.grid(True, alpha=0.3)
    return _save(fig, out_png)


def _plot_axis_kind(cols, out_png, kind, power, label, limits=None, limit_key=None, title=None, trace=None):
    t = _time(cols)
    axes = [(a, k[kind]) for a, k in axis_columns(cols).items() if kind in k]
    if not axes:
        return None
    fig, plots = plt.subplots(len(axes), 1, figsize=(10, 2.2 + 1.8 * len(axes)), sharex=True, squeeze=False)
    for (a, name), ax in zip(axes, plots[:, 0]):
        ax.plot(t, cols[name], lw=0.9, label=trace or "%s %s" % (a, label))
        if limits and a in limits and limit_key:
            lim = limits[a][limit_key]
            ax.axhline(lim, color="r", ls="--", lw=0.8, label="\u00b1%s_max (machine file)" % limit_key)
            ax.axhline(-lim, color="r", ls="--", lw=0.8)
        ax.set_ylabel("%s %s [%s]" % (a, label, _unit(a, power)))
        ax.grid(True, alpha=0.3)
    plots[-1, 0].set_xlabel("t [s]")
    plots[0, 0].set_title(title or "%s per axis" % label.capitalize(), loc="left")
    plots[0, 0].legend(**_LEGEND)
    return _save(fig, out_png)


def plot_accel(cols, out_png, limits=None, title=None):
    return _plot_axis_kind(cols, out_png, "a", 2, "acceleration", limits, "a", title,
                           "setpoint (backward difference)")


def plot_jerk(cols, out_png, limits=None, title=None):
    return _plot_axis_kind(cols, out_png, "j", 3, "jerk", limits, "j", title, "setpoint (backward difference)")


def plot_error(cols, out_png, title=None):
    axes = axis_columns(cols)
    # following error: the err column, or set - act
    derived = dict(cols)
    for a, k in axes.items():
        if "err" not in k and "set" in k and "act" in k:
            derived["%s_err" % a] = cols[k["set"]] - cols[k["act"]]
    return _plot_axis_kind(derived, out_png, "err", 0, "following error", title=title or "Following error",
                           trace="setpoint \u2212 actual")


def plot_path(cols, out_png, plane=("X", "Y"), title=None):
    axes = axis_columns(cols)
    u, v = plane
    if u not in axes or v not in axes:
        return None
    ku = axes[u].get("set") or axes[u].get("act")
    kv = axes[v].get("set") or axes[v].get("act")
    if not ku or not kv:
        return None
    x, y = cols[ku], cols[kv]
    fig, ax = plt.subplots(figsize=(8, 7))
    if "feed_mm_s" in cols and len(x) > 1:
        feed = cols["feed_mm_s"]
        pts = np.column_stack([x, y])
        segs = np.stack([pts[:-1], pts[1:]], axis=1)
        lc = LineCollection(segs, cmap="viridis", linewidths=2.0, label="setpoint (colour: feed)")
        lc.set_array(0.5 * (feed[:-1] + feed[1:]))
        ax.add_collection(lc)
        fig.colorbar(lc, ax=ax, label="feed [mm/s]")
    else:
        ax.plot(x, y, lw=1.5, label="setpoint")
    if "act" in axes[u] and "act" in axes[v] and ku != axes[u]["act"]:
        ax.plot(cols[axes[u]["act"]], cols[axes[v]["act"]], lw=0.6, color="0.3", alpha=0.6, label="actual")
    if len(x):
        ax.plot([x[0]], [y[0]], "o", color="tab:green", ms=5, label="start")
        ax.plot([x[-1]], [y[-1]], "s", color="tab:red", ms=5, label="end")
    ax.legend(**dict(_LEGEND, ncol=2))
    ax.set_xlabel("%s [%s]" % (u, _unit(u, 0)))
    ax.set_ylabel("%s [%s]" % (v, _unit(v, 0)))
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_title(title or "Path coloured by feed", loc="left")
    ax.grid(True, alpha=0.3)
    return _save(fig, out_png)


def plot_run(csv_path, out_dir=None, prefix=None, machine=None, plane=("X", "Y")):
    """All run plots for one CSV. Returns the list of PNG paths written."""
    cols = read_csv(csv_path)
    _time(cols)
    out_dir = out_dir or os.path.dirname(os.path.abspath(csv_path))
    os.makedirs(out_dir, exist_ok=True)
    prefix = prefix or os.path.splitext(os.path.basename(csv_path))[0]
    limits = machine_limits(machine) if machine else None
    base = os.path.join(out_dir, prefix)
    written = [
        plot_feed(cols, base + "_feed.png"),
        plot_accel(cols, base + "_accel.png", limits),
        plot_jerk(cols, base + "_jerk.png", limits),
        plot_path(cols, base + "_path.png", plane),
        plot_error(cols, base + "_error.png"),
    ]
    return [p for p in written if p]


def plot_scurve(csv_path, out_png=None, title=None, unit="mm"):
    """Four stacked panels (J, A, V, S) against t from a CSV with columns t,j,a,v,s. Returns the PNG path."""
    cols = read_csv(csv_path)
    missing = [c for c in ("j", "a", "v", "s") if c not in cols]
    if missing or "t_s" not in cols:
        raise ValueError("%s: an S-curve CSV needs the columns t,j,a,v,s (missing: %s)"
                         % (csv_path, ", ".join(missing + ([] if "t_s" in cols else ["t"]))))
    out_png = out_png or os.path.splitext(csv_path)[0] + ".png"
    t = cols["t_s"]
    fig, plots = plt.subplots(4, 1, figsize=(9, 9), sharex=True)
    spec = [("j", "J [%s/s\u00b3]" % unit), ("a", "A [%s/s\u00b2]" % unit), ("v", "V [%s/s]" % unit),
            ("s", "S [%s]" % unit)]
    for ax, (key, label) in zip(plots, spec):
        ax.plot(t, cols[key], lw=1.0)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    plots[-1].set_xlabel("t [s]")
    plots[0].set_title(title or os.path.basename(csv_path))
    return _save(fig, out_png)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m lissom_hil.plot", description="PNG plots of lissom-sim output")
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="feed, acceleration, jerk, path and following-error plots of a run CSV")
    r.add_argument("csv")
    r.add_argument("--out", help="output directory (default: the CSV's directory)")
    r.add_argument("--prefix", help="file name prefix (default: the CSV's name)")
    r.add_argument("--machine", help="machine file: draw the a and j limits")
    r.add_argument("--path", default="X,Y", help="the two axes of the path plot (default X,Y)")
    s = sub.add_parser("scurve", help="J, A, V, S panels of an S-curve samples CSV (t,j,a,v,s)")
    s.add_argument("csv")
    s.add_argument("--out", help="PNG file (default: the CSV's name with .png)")
    s.add_argument("--title")
    s.add_argument("--unit", default="mm", help="length unit for the labels (default mm)")
    args = ap.parse_args(argv)
    try:
        if args.cmd == "run":
            plane = tuple(a.strip().upper() for a in args.path.split(","))
            if len(plane) != 2:
                ap.error("--path needs two axes, e.g. X,Y")
            paths = plot_run(args.csv, args.out, args.prefix, args.machine, plane)
        else:
            paths = [plot_scurve(args.csv, args.out, args.title, args.unit)]
    except (OSError, ValueError, KeyError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 1
    for p in paths:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
