"""`lissom-sim check` (every error and warning of a program in one pass), the machine functions `lissom-sim run`
logs in summary.json, and the Python rig's reader, which takes its blocks from the firmware's parser."""
import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MACHINE = os.path.join(ROOT, "host_sim", "machines", "router.json")
sys.path.insert(0, os.path.join(ROOT, "hil"))
from lissom_hil.gcode import ARC_CW, LINE, GcodeError, read_gcode, read_program  # noqa: E402

BAD = """G21 G90
G0 X1 Q7
G1 X#2 F100
o100 sub
G43 H3
G28
G1 X5 F100
G2 X10 Y0 I5.1
G0 X1
M2
G0 X5
"""

CAM = """%
(a post-processor's preamble and machine functions)
G00 G17 G21 G40 G49 G80 G90
G54
T1 M6
G43 H1
S12000 M3
M8
G0 X10 Y0 Z5
G1 Z-1 F300
G1 X20 F600
G4 P0.25
G2 I.5 J.5
M0
G91 G28 Z0
G90
M5 M9
M30
%
"""


def test_check_lists_every_error_and_warning(sim, tmp_path):
    prog = tmp_path / "bad.ngc"
    prog.write_text(BAD)
    p = sim("check", prog, ok=False)
    assert p.returncode == 1
    lines = p.stdout.splitlines()
    assert lines == [
        f"{prog}:2:7: error: unknown word 'Q7'",
        f"{prog}:3:5: error: unsupported: parameters (#2)",
        f"{prog}:4:1: error: unsupported: O-words (subroutines, loops, conditionals) (O100)",
        f"{prog}:5: warning: G43 H3: lissom-sim has no tool table; no tool length offset is applied",
        f"{prog}:6: warning: G28 goes to its stored position, machine zero here (no G28.1 before it)",
        f"{prog}:8:1: error: arc start and end radii differ 'G2'",
        f"{prog}:11: warning: 1 line(s) after the end of the program are ignored",
        f"{prog}: 4 errors, 3 warnings",
    ]


def test_check_json_and_clean_program(sim, tmp_path):
    prog = tmp_path / "cam.ngc"
    prog.write_text(CAM)
    out = sim("check", prog, "--json")
    assert out["errors"] == 0 and out["warnings"] == 2  # G43 (no tool table), G28 without G28.1
    assert out["n_blocks"] == 5  # G0, G1 Z, G1 X, the full circle, G28 Z (its intermediate point is where Z is)
    p = sim("check", prog, ok=False)
    assert p.returncode == 0 and p.stdout.endswith(": 0 errors, 2 warnings\n")
    missing_end = tmp_path / "noend.ngc"
    missing_end.write_text("G0 X1\n")
    assert "the program has no end (M2, M30 or %)" in sim("check", missing_end).splitlines()[0]
    assert sim("check", "/nonexistent.ngc", ok=False).returncode == 2
    assert sim("check", prog, "--blocks", ok=False).returncode == 2  # --blocks needs --json
    axes = tmp_path / "a.ngc"
    axes.write_text("G0 A10\nM2\n")
    p = sim("check", axes, "--machine", MACHINE, ok=False)  # router: X Y Z
    assert p.returncode == 1 and "error: the machine has no such axis 'A10'" in p.stdout


def test_run_logs_machine_functions(sim, tmp_path):
    prog = tmp_path / "cam.ngc"
    prog.write_text(CAM)
    out = sim("run", prog, "--machine", MACHINE, "--out", tmp_path / "out", "--json", "--no-drive")
    assert out["within_limits"] is True and out["end_error"] == 0
    ev = [(e["line"], e["event"]) for e in out["events"]]
    assert ev == [(3, "tool_length_offset_cancel"), (5, "tool_select"), (5, "tool_change"), (6, "tool_length_offset"),
                  (7, "spindle_speed"), (7, "spindle_cw"), (8, "coolant_flood"), (12, "dwell"), (14, "pause"),
                  (14, "resume"), (17, "spindle_stop"), (17, "coolant_off"), (18, "end")]
    by = {(e["line"], e["event"]): e for e in out["events"]}
    assert by[(7, "spindle_cw")]["rpm"] == 12000 and by[(5, "tool_change")]["tool"] == 1
    assert by[(12, "dwell")]["seconds"] == 0.25
    t = [e["t"] for e in out["events"]]
    assert t == sorted(t) and t[-1] == out["duration"]
    # the dwell: the machine rests on the end of line 11 (X20 Y0 Z-1) for 250 cycles of 1 ms
    import csv
    rows = list(csv.DictReader(open(tmp_path / "out" / "run.csv")))
    t0 = by[(12, "dwell")]["t"]
    rest = [r for r in rows if t0 <= float(r["t_s"]) < t0 + 0.25]
    assert len(rest) >= 249
    assert all(float(r["X_set_mm"]) == 20 and float(r["Y_set_mm"]) == 0 and float(r["feed_mm_s"]) == 0 for r in rest)
    # the tool change, spindle and coolant happen at rest before the first move
    assert by[(8, "coolant_flood")]["t"] == 0
    # the reference planner logs them without times
    v = sim("run", prog, "--machine", MACHINE, "--out", tmp_path / "v", "--json", "--no-drive", "--planner", "vpop")
    assert [(e["line"], e["event"]) for e in v["events"]] == ev and all(e["t"] is None for e in v["events"])


def test_python_reader_is_the_firmware_parser():
    blocks = read_gcode("G21 G90\nG1 X60 Y30 F2400\nG0 X0\nG2 I5 J0 F600\nG18 G3 X10 Z0 I5 K0\n", rapid_mm_s=100)
    assert [b.type for b in blocks] == [LINE, LINE, ARC_CW, 3]
    assert blocks[0].end == (60, 30, 0) and blocks[0].feed == 40 and blocks[1].feed == 100
    assert blocks[2].centre == (5, 30) and blocks[2].end == (0, 30, 0)  # a full circle without end words
    assert blocks[3].plane == 1 and blocks[3].centre == (0, 5)  # G18: (Z, X)
    prog = read_program(CAM)
    assert [e["event"] for e in prog.events][:3] == ["tool_length_offset_cancel", "tool_select", "tool_change"]
    assert len(prog.warnings) == 2
    with pytest.raises(GcodeError, match=r"line 2 column 7: unknown word 'Q7'; line 3 column 5: unsupported"):
        read_gcode(BAD)
    with pytest.raises(GcodeError, match="no such axis"):
        read_gcode("G0 A1\n", n_axes=3)
    assert read_gcode("G0 X1\n", start=(5, 5, 5))[0].end == (1, 5, 5)
