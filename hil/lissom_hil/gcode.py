"""G-code programs as Lissom path blocks (co_path.h), read by the firmware's own parser.

There is one implementation of the dialect: firmware/gcode/gcode.c. This module runs it through
`lissom-sim check - --json --blocks` and turns its blocks into path blocks for streaming:

    blocks = read_gcode(text, n_axes=3)   # [Block(type, plane, end, centre, feed, line), ...]

Rapids (G0) come as lines at `rapid_mm_s`; arcs carry their plane code (0 XY, 1 ZX, 2 YZ) and their centre on the
plane's first and second axis. Machine functions (S, M3, G4, ...) are in `read_program(...).events`.
Errors raise GcodeError with every message of the program (line, column, the word and the reason).
The binary is $LISSOM_SIM, else lissom-sim next to $LISSOM_NODE, else this checkout's build/bin, else `lissom-sim`
on PATH.
"""
import json
import os
import shutil
import subprocess
from collections import namedtuple

Block = namedtuple("Block", "type plane end centre feed line")
Program = namedtuple("Program", "blocks events warnings")
LINE, ARC_CW, ARC_CCW = 1, 2, 3
_PLANE_CODE = {17: 0, 18: 1, 19: 2}
_PLANE_AXES = {17: (0, 1), 18: (2, 0), 19: (1, 2)}
_AXES = "XYZABC"
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class GcodeError(ValueError):
    pass


def find_sim():
    """The lissom-sim binary: $LISSOM_SIM, this checkout's build/bin/lissom-sim, or lissom-sim on PATH."""
    env = os.environ.get("LISSOM_SIM")
    if env:
        return env
    node = os.environ.get("LISSOM_NODE")  # the HIL rig's build (run_hil.sh sets it)
    for local in ([os.path.join(os.path.dirname(node), "lissom-sim")] if node else []) + [
            os.path.join(ROOT, "build", "bin", "lissom-sim")]:
        if os.access(local, os.X_OK):
            return local
    found = shutil.which("lissom-sim")
    if found:
        return found
    raise FileNotFoundError("lissom-sim not found (build it with scripts/build.sh, install it, or set LISSOM_SIM)")


def parse(text, n_axes=3, start=None, sim=None):
    """The parser's JSON for a program: blocks (mm, mm/s, rad), events and messages."""
    args = [sim or find_sim(), "check", "-", "--json", "--blocks", "--axes", _AXES[:n_axes]]
    if start is not None:
        args += ["--start", ",".join(repr(float(v)) for v in start)]
    r = subprocess.run(args, input=text.encode(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, check=False)
    if r.returncode not in (0, 1):
        raise GcodeError("lissom-sim check failed (%d): %s" % (r.returncode, r.stderr.decode().strip()))
    out = json.loads(r.stdout)
    if out["errors"]:
        raise GcodeError("; ".join("line %d column %d: %s" % (m["line"], m["column"], m["text"])
                                   for m in out["messages"] if m["severity"] == "error"))
    return out


def read_program(text, n_axes=3, rapid_mm_s=200.0, start=None, sim=None):
    """Blocks, machine functions (dicts with line, event, code, before_block, exact_stop, tool, value) and
    warnings of a program."""
    out = parse(text, n_axes, start, sim)
    blocks = []
    for b in out["blocks"]:
        end = tuple(b["end"][:n_axes])
        if b["type"] == "arc":
            pa, pb = _PLANE_AXES[b["plane"]]
            if pa >= n_axes or pb >= n_axes:
                raise GcodeError("line %d: plane G%d needs axis %s" % (b["line"], b["plane"], _AXES[max(pa, pb)]))
            blocks.append(Block(ARC_CW if b["dir"] < 0 else ARC_CCW, _PLANE_CODE[b["plane"]], end,
                                (b["centre"][pa], b["centre"][pb]), b["feed_mm_s"], b["line"]))
        else:
            feed = rapid_mm_s if b["type"] == "rapid" else b["feed_mm_s"]
            blocks.append(Block(LINE, 0, end, None, feed, b["line"]))
    warnings = [m for m in out["messages"] if m["severity"] == "warning"]
    return Program(blocks, out["events"], warnings)


def read_gcode(text, n_axes=3, rapid_mm_s=200.0, start=None, sim=None):
    """The program's motion as path blocks (see the module doc)."""
    return read_program(text, n_axes, rapid_mm_s, start, sim).blocks
