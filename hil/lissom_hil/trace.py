"""The per-cycle trace of lissom-node (--trace FILE) and the exact limit checks made on it.

File format (written by host_sim/node/node_main.c):
    line 1   "LSMTRACE1 <ncols> <cycle_s>"
    line 2   the column names, comma-separated
    then     rows of <ncols> little-endian float64, one row per control cycle
Columns: t_s (cycle count x cycle), t_real_s (the port's clock), cycle, nmt, estop, enable, inpos, path_state,
path_seq (block being executed or last finished), path_free, feed_mm_s, and per axis L (X, Y, Z, ...):
L_set_mm (demand), L_act_mm (simulated drive), L_v_mm_s, L_a_mm_s2, L_j_mm_s3 (the generator's closed form),
L_err_mm, L_sw (statusword), L_state (CiA 402 state 0..7), L_mode (mode display), L_tgt_mm (0x607A).

The checks use finite differences of the demand positions (independent of the generator's own v, a, j):
    v_k = (p_k - p_{k-1}) / dt,  a_k = (v_k - v_{k-1}) / dt,  j_k = (a_k - a_{k-1}) / dt
Each is an average of the continuous quantity over one to three cycles, so it cannot exceed the continuous
maximum: a limit that holds for the trajectory holds for these differences (up to float rounding).
"""
import numpy as np


class Trace:
    def __init__(self, path):
        with open(path, "rb") as f:
            head = f.readline().decode().split()
            if len(head) != 3 or head[0] != "LSMTRACE1":
                raise ValueError("%s: not a lissom-node trace" % path)
            ncols = int(head[1])
            self.cycle_s = float(head[2])
            self.names = f.readline().decode().strip().split(",")
            if len(self.names) != ncols:
                raise ValueError("%s: %d names for %d columns" % (path, len(self.names), ncols))
            raw = f.read()
        nrows = len(raw) // (8 * ncols)
        data = np.frombuffer(raw[: nrows * 8 * ncols], dtype="<f8").reshape(nrows, ncols)
        self.cols = {n: data[:, i] for i, n in enumerate(self.names)}
        self.axes = [n[0] for n in self.names if n.endswith("_set_mm")]

    def __len__(self):
        return len(self.cols["cycle"])

    def __getitem__(self, name):
        return self.cols[name]

    def axis(self, k, kind):
        """Column `kind` (set_mm, act_mm, v_mm_s, a_mm_s2, j_mm_s3, err_mm, sw, state, mode, tgt_mm) of axis k."""
        return self.cols["%s_%s" % (self.axes[k], kind)]

    def first(self, mask, start=0):
        idx = np.nonzero(np.asarray(mask)[start:])[0]
        return int(idx[0]) + start if len(idx) else None

    def write_csv(self, path, start=0, stop=None, decimate=1):
        """The trace as a run CSV for lissom_hil.plot (columns t_s, X_set_mm, X_act_mm, X_v_mm_s, ...)."""
        keep = ["t_s", "feed_mm_s"] + [n for n in self.names if n[1:2] == "_" and n[0] in self.axes
                                       and not n.endswith(("_sw", "_state", "_mode", "_tgt_mm"))]
        sl = slice(start, stop, decimate)
        with open(path, "w") as f:
            f.write(",".join(keep) + "\n")
            for row in zip(*(self.cols[n][sl] for n in keep)):
                f.write(",".join("%.9g" % x for x in row) + "\n")
        return path


def differences(p, dt):
    """Finite-difference velocity, acceleration and jerk of a sampled position (arrays 1, 2, 3 shorter)."""
    v = np.diff(p) / dt
    a = np.diff(v) / dt
    j = np.diff(a) / dt
    return v, a, j


def check_limits(p, dt, v_max=None, a_max=None, j_max=None, snap_max=None, rel=1e-6, what="axis"):
    """Returns a list of violations (empty = ok) of the limits by the finite differences of p.
    rel: relative tolerance for float rounding; an absolute rounding allowance is added from |p|."""
    p = np.asarray(p, dtype=float)
    out = []
    if len(p) < 4:
        return out
    scale = max(1.0, float(np.max(np.abs(p))))
    eps = 4 * np.finfo(float).eps * scale
    v, a, j = differences(p, dt)
    s = np.diff(j) / dt
    for name, arr, lim, noise in (("velocity", v, v_max, 2 * eps / dt), ("acceleration", a, a_max, 4 * eps / dt ** 2),
                                  ("jerk", j, j_max, 8 * eps / dt ** 3), ("snap", s, snap_max, 16 * eps / dt ** 4)):
        if lim is None or len(arr) == 0:
            continue
        peak = float(np.max(np.abs(arr)))
        if peak > lim * (1 + rel) + noise:
            k = int(np.argmax(np.abs(arr)))
            out.append("%s: %s %.6g > limit %.6g (sample %d)" % (what, name, peak, lim, k))
    return out


def peak_abs(x):
    x = np.asarray(x, dtype=float)
    return float(np.max(np.abs(x))) if len(x) else 0.0
