"""TPDO telemetry sampled at each SYNC, as a CANopen master sees it (no access to the node's internals).

The rig maps the objects it wants into the node's synchronous TPDOs (transmission type 1: one TPDO per SYNC)
and produces SYNC with python-can's periodic send (on socketcan that is the kernel's broadcast manager, so the
SYNC period does not depend on Python's scheduling). Every TPDO frame is attributed to the last SYNC captured
before it; the sample time is that SYNC's kernel timestamp.

    tel = Telemetry(framelog, node_id, {3: [(0x6062, 0, "i32", "X_set"), ...], ...})
    i0 = framelog.mark();  ... run ...;  s = tel.samples(since=i0)    # {"t": array, "X_set": array, ...}

Checks made from telemetry alone (valid on a real board too) must allow for the sampling: the node takes its
sample in the control cycle after the SYNC arrives, so a sample time is late by up to one cycle plus the
scheduling jitter; velocity estimates over one SYNC period carry a relative error of about cycle / period.
"""
import struct

import numpy as np

_FMT = {"i8": "b", "u8": "B", "i16": "h", "u16": "H", "i32": "i", "u32": "I"}


class Telemetry:
    SYNC_ID = 0x80

    def __init__(self, framelog, node_id, mapping):
        """mapping: {tpdo number 1..4: [(index, sub, type, name), ...]} as mapped in the node."""
        self.log = framelog
        self.node_id = node_id
        self.decoders = {}
        for k, objs in mapping.items():
            cob = 0x180 + 0x100 * (k - 1) + node_id
            fmt = "<" + "".join(_FMT[o[2]] for o in objs)
            self.decoders[cob] = (struct.Struct(fmt), [o[3] for o in objs])

    def samples(self, since=0, until=None):
        frames = self.log.select(None, since)
        if until is not None:
            frames = [f for f in frames if f.t <= until]
        rows = []
        cur = None
        for f in frames:
            if f.err or f.ext:
                continue
            if f.id == self.SYNC_ID and len(f.data) == 0:
                cur = {"t": f.t}
                rows.append(cur)
            elif f.id in self.decoders and cur is not None:
                st, names = self.decoders[f.id]
                if len(f.data) >= st.size:
                    for n, v in zip(names, st.unpack_from(f.data)):
                        cur[n] = v
        names = ["t"] + [n for st_names in self.decoders.values() for n in st_names[1]]
        rows = [r for r in rows if all(n in r for n in names)]  # complete samples only
        return {n: np.array([r[n] for r in rows], dtype=float) for n in names}


def velocity(t, p):
    """Finite-difference velocity between samples (len - 1 values) and the mid-sample times."""
    t = np.asarray(t, dtype=float)
    p = np.asarray(p, dtype=float)
    dt = np.diff(t)
    ok = dt > 0
    return (t[1:][ok] + t[:-1][ok]) / 2, np.diff(p)[ok] / dt[ok]


def write_run_csv(path, s, scale, axes=("X",), kinds=("set", "act")):
    """Samples as a run CSV for lissom_hil.plot: t_s and <axis>_<kind>_mm columns (counts / scale) plus the
    finite-difference velocity <axis>_v_mm_s of the demand (or of the first kind present)."""
    cols = {"t_s": s["t"] - s["t"][0]}
    for a in axes:
        for k in kinds:
            name = "%s_%s" % (a, k)
            if name in s:
                cols["%s_%s_mm" % (a, k)] = s[name] / scale
        src = "%s_set" % a if "%s_set" % a in s else "%s_%s" % (a, kinds[0])
        if src in s and len(s["t"]) > 2:
            _, v = velocity(s["t"], s[src] / scale)
            cols["%s_v_mm_s" % a] = np.concatenate([[0.0], v]) if len(v) == len(s["t"]) - 1 else np.zeros(len(s["t"]))
    names = list(cols)
    with open(path, "w") as f:
        f.write(",".join(names) + "\n")
        for row in zip(*(cols[n] for n in names)):
            f.write(",".join("%.9g" % x for x in row) + "\n")
    return path
