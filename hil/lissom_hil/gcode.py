"""A small G-code reader that turns a program into Lissom path blocks (co_path.h) for streaming.

Supported: G0 (rapid: at `rapid_mm_s`), G1, G2/G3 with I J K (incremental centre, the default) or R,
G17/G18/G19 planes, G20/G21 (inch/mm), G90/G91, F (mm/min), comments "( ... )" and "; ...", N numbers.
M, S, T and other words are ignored (they have no motion). Axes: X Y Z (and A B C as further coordinates
that move linearly). Full circles: G2/G3 with I/J and the end equal to the start.

    blocks = read_gcode(text, n_axes=3)   # [Block(type, plane, end_mm, centre_mm, feed_mm_s, line), ...]
"""
import math
import re
from collections import namedtuple

Block = namedtuple("Block", "type plane end centre feed line")
LINE, ARC_CW, ARC_CCW = 1, 2, 3
PLANES = {17: (0, (0, 1)), 18: (1, (2, 0)), 19: (2, (1, 2))}  # G17 XY, G18 ZX, G19 YZ: (plane code, axes)
_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")
_AXES = "XYZABC"


class GcodeError(ValueError):
    pass


def read_gcode(text, n_axes=3, rapid_mm_s=200.0, start=None):
    pos = list(start) if start is not None else [0.0] * n_axes
    absolute, unit, plane, feed = True, 1.0, 17, None
    motion = None
    out = []
    for ln, raw in enumerate(text.splitlines(), 1):
        line = re.sub(r"\(.*?\)", " ", raw).split(";")[0].strip()
        if not line or line.startswith("%"):
            continue
        words = _WORD.findall(line)
        rest = _WORD.sub("", line).strip()
        if rest:
            raise GcodeError("line %d: cannot read %r" % (ln, rest))
        g_codes = [float(v) for k, v in words if k.upper() == "G"]
        vals = {}
        for k, v in words:
            k = k.upper()
            if k not in "GMNST":
                vals[k] = float(v)
        for g in g_codes:
            if g in (0, 1, 2, 3):
                motion = int(g)
            elif g in (17, 18, 19):
                plane = int(g)
            elif g == 20:
                unit = 25.4
            elif g == 21:
                unit = 1.0
            elif g == 90:
                absolute = True
            elif g == 91:
                absolute = False
        if "F" in vals:
            feed = vals["F"] * unit / 60.0
        target = list(pos)
        moved = False
        for i, a in enumerate(_AXES[:n_axes]):
            if a in vals:
                target[i] = vals[a] * unit + (0.0 if absolute else pos[i])
                moved = True
        if motion is None or not (moved or (motion in (2, 3) and any(k in vals for k in "IJKR"))):
            continue
        if motion == 0:
            out.append(Block(LINE, 0, tuple(target), None, rapid_mm_s, ln))
        elif motion == 1:
            if feed is None:
                raise GcodeError("line %d: G1 without a feed (F)" % ln)
            out.append(Block(LINE, 0, tuple(target), None, feed, ln))
        else:
            if feed is None:
                raise GcodeError("line %d: G%d without a feed (F)" % (ln, motion))
            code, (pa, pb) = PLANES[plane]
            if pa >= n_axes or pb >= n_axes:
                raise GcodeError("line %d: plane G%d needs axis %s" % (ln, plane, _AXES[max(pa, pb)]))
            offs = {0: "I", 1: "J", 2: "K"}
            if "R" in vals:
                centre = _centre_from_radius(pos, target, pa, pb, vals["R"] * unit, motion == 2, ln)
            else:
                centre = (pos[pa] + vals.get(offs[pa], 0.0) * unit, pos[pb] + vals.get(offs[pb], 0.0) * unit)
            if math.hypot(pos[pa] - centre[0], pos[pb] - centre[1]) == 0:
                raise GcodeError("line %d: arc with zero radius" % ln)
            out.append(Block(ARC_CW if motion == 2 else ARC_CCW, code, tuple(target), centre, feed, ln))
        pos = target
    return out


def _centre_from_radius(p, q, a, b, r, cw, ln):
    dx, dy = q[a] - p[a], q[b] - p[b]
    d = math.hypot(dx, dy)
    if d == 0 or abs(r) < d / 2 - 1e-9:
        raise GcodeError("line %d: R form arc cannot reach its end" % ln)
    h = math.sqrt(max(r * r - d * d / 4, 0.0))
    mx, my = p[a] + dx / 2, p[b] + dy / 2
    # left of the chord for a CCW arc shorter than half a circle; R < 0 asks for the longer arc
    sgn = (1 if not cw else -1) * (1 if r > 0 else -1)
    return (mx - sgn * h * dy / d, my + sgn * h * dx / d)
