"""Plot an S-curve samples CSV (header t,j,a,v,s) as four stacked panels: J, A, V and S against time.

    python -m lissom_hil.scurve_plot CSV PNG
"""
import csv
import sys


def plot_scurve(csv_path, png_path, title="sin² S-curve"):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    if not rows or set(rows[0]) < {"t", "j", "a", "v", "s"}:
        raise ValueError(f"{csv_path}: expected columns t,j,a,v,s")
    t = [float(r["t"]) for r in rows]
    panels = [("j", "J (mm/s³)"), ("a", "A (mm/s²)"), ("v", "V (mm/s)"), ("s", "S (mm)")]
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(8, 9))
    for ax, (key, label) in zip(axes, panels):
        ax.plot(t, [float(r[key]) for r in rows], lw=1.2)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0].set_title(title)
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)
    plt.close(fig)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    plot_scurve(argv[0], argv[1])
    return 0


if __name__ == "__main__":
    sys.exit(main())
