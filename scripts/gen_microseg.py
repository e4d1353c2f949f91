#!/usr/bin/env python3
"""gen_microseg.py: G-code programs of the pcb2gcode / V-carve class (issue 12): long polylines of micro-segments.

The path is a chain of outlines, each a smooth closed curve (a circle with a few harmonics, like the isolation
outline of a pad or a trace end) or a straight trace with rounded ends, sampled with segment lengths drawn
log-normally around a median (8 um by default: pcb2gcode's output), coordinates rounded to the file's precision
(0.1 um). Between outlines the tool moves with a G0 at a safe height and plunges (G1 Z at the plunge feed).
The cutting feed is F (600 mm/min default). Deterministic for a seed.

    scripts/gen_microseg.py [--seed N] [--outlines N] [--median-um U] [--feed F] [--tol P] > prog.ngc

Prints the programmed cutting length and the length/feed bound on stderr (and in a comment at the top).
"""
import argparse
import math
import random
import sys


def outline(rng, cx, cy):
    """A closed smooth curve r(t) = r0 (1 + sum a_k cos(k t + p_k)), or a trace: two half circles and two lines."""
    if rng.random() < 0.5:
        r0 = rng.uniform(0.4, 2.5)
        harm = [(k, rng.uniform(0, 0.12 / k), rng.uniform(0, 2 * math.pi)) for k in (2, 3, 5)]
        def f(t):
            r = r0 * (1 + sum(a * math.cos(k * t + p) for k, a, p in harm))
            return cx + r * math.cos(t), cy + r * math.sin(t)
        return f, 2 * math.pi * r0 * 1.05
    w = rng.uniform(0.2, 0.6)
    L = rng.uniform(2.0, 12.0)
    th = rng.uniform(0, math.pi)
    c, s = math.cos(th), math.sin(th)
    per = 2 * L + 2 * math.pi * w
    def f(t):
        u = (t / (2 * math.pi)) * per
        if u < L:
            x, y = u, -w
        elif u < L + math.pi * w:
            a = -math.pi / 2 + (u - L) / w
            x, y = L + w * math.cos(a), w * math.sin(a)
        elif u < 2 * L + math.pi * w:
            x, y = L - (u - L - math.pi * w), w
        else:
            a = math.pi / 2 + (u - 2 * L - math.pi * w) / w
            x, y = w * math.cos(a), w * math.sin(a)
        return cx + c * x - s * y, cy + s * x + c * y
    return f, per


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--outlines", type=int, default=40)
    ap.add_argument("--median-um", type=float, default=8.0)
    ap.add_argument("--feed", type=float, default=600.0, help="cutting feed, mm/min")
    ap.add_argument("--tol", type=float, default=0.01, help="G64 P tolerance, mm")
    ap.add_argument("--decimals", type=int, default=4)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    med = a.median_um * 1e-3
    out = ["%", "(micro-segment test program: scripts/gen_microseg.py --seed %d --outlines %d --median-um %g --feed %g)"
           % (a.seed, a.outlines, a.median_um, a.feed), "G21 G90 G17 G64 P%g" % a.tol]
    fmt = "%%.%df" % a.decimals
    length = 0.0
    nseg = 0
    body = []
    for i in range(a.outlines):
        cx, cy = rng.uniform(0, 80), rng.uniform(0, 60)
        f, per = outline(rng, cx, cy)
        x0, y0 = f(0.0)
        body.append(("G0 Z1\nG0 X" + fmt + " Y" + fmt) % (x0, y0))
        body.append("G1 Z-0.05 F120")
        body.append("G1 F%g" % a.feed)
        t, px, py = 0.0, round(x0, a.decimals), round(y0, a.decimals)
        first = True
        while t < 2 * math.pi:
            ds = med * math.exp(rng.gauss(0.0, 0.6))
            t = min(2 * math.pi, t + ds / per * 2 * math.pi)
            x, y = f(t)
            x, y = round(x, a.decimals), round(y, a.decimals)
            if (x, y) == (px, py):
                continue
            length += math.hypot(x - px, y - py)
            nseg += 1
            body.append(("X" + fmt + " Y" + fmt) % (x, y) if not first else ("G1 X" + fmt + " Y" + fmt) % (x, y))
            first = False
            px, py = x, y
    bound = length / (a.feed / 60.0)
    out.append("(cutting: %d segments, %.3f mm, length/feed %.2f s)" % (nseg, length, bound))
    out += body
    out += ["G0 Z1", "M2"]
    sys.stdout.write("\n".join(out) + "\n")
    sys.stderr.write("segments %d  length %.3f mm  length/feed %.2f s\n" % (nseg, length, bound))


if __name__ == "__main__":
    main()
