"""Checks shared by the HIL tests: motion limits on the node's trace and on CAN telemetry.

On the trace (per control cycle, exact): lissom_hil.trace.check_limits on the demand positions.
On telemetry (per SYNC, what any master can see): the velocity between samples, with the sampling allowance
described in lissom_hil.telemetry (the sample is taken in the control cycle after the SYNC).
"""
import numpy as np

from .telemetry import velocity
from .trace import check_limits


def moving_span(p, eps=1e-12):
    """(first, last) sample index where p changes, or None if it never does."""
    d = np.nonzero(np.abs(np.diff(np.asarray(p, dtype=float))) > eps)[0]
    if len(d) == 0:
        return None
    return int(d[0]), int(d[-1]) + 1


def last_move(p):
    """(start, end) of the last motion of p: p[start] is the rest position before it (the first change is
    p[start] -> p[start + 1]) and p[end] the rest position after it; None if p never changes."""
    p = np.asarray(p, dtype=float)
    moving = np.abs(np.diff(p)) > 0
    idx = np.nonzero(moving)[0]
    if len(idx) == 0:
        return None
    end = int(idx[-1]) + 1
    still = np.nonzero(~moving[: idx[-1]])[0]
    start = int(still[-1]) + 1 if len(still) else 0
    return start, end


def stop_violations(trace, axis, start, lim, rel=1e-6, what=None, pre=3):
    """Limits (v, a, j, and snap if given) of the demand of `axis` from `pre` cycles before cycle `start` to the
    end, plus the requirement that it ends at rest. lim: dict with keys v, a, j, snap (mm units; a missing key
    or None skips that check)."""
    p = trace.axis(axis, "set_mm")[max(start - pre, 0):]
    what = what or "axis %d stop" % axis
    out = check_limits(p, trace.cycle_s, lim.get("v"), lim.get("a"), lim.get("j"), lim.get("snap"), rel, what)
    if len(p) > 2 and abs(p[-1] - p[-2]) > 1e-9:
        out.append("%s: still moving at the end of the trace" % what)
    return out


def telemetry_velocity_ok(t, p_mm, v_max, cycle_s, period_s, slack=0.03):
    """Peak velocity between telemetry samples against v_max, with the allowance for the sampling: each sample
    is up to one cycle (plus jitter, `slack` relative) late relative to its SYNC time stamp.
    Returns (ok, peak, allowed)."""
    _, v = velocity(t, p_mm)
    if len(v) == 0:
        return True, 0.0, v_max
    peak = float(np.max(np.abs(v)))
    allowed = v_max * (1 + 2 * cycle_s / period_s + slack)
    return peak <= allowed, peak, allowed
