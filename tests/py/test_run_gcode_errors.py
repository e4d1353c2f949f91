"""`lissom-sim run` on malformed G-code: each malformed input the issue lists stops the run with exit status 1 and
one message on stderr naming the line, the column, the word and what is wrong; nothing goes to stdout, even with --json.
(The parser's own tests, with every error code, are in tests/gcode/test_gcode.c.)"""
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MACHINE = os.path.join(ROOT, "host_sim", "machines", "router.json")
HEAD = b"%\n(a valid start)\nG21 G90 G17 G64 P0.01\nG1 F1200 X5 Y5\n"  # lines 1-4; the bad line is line 5

CASES = [
    ("unknown word", b"G1 X10 Q5\n", 8, "unknown word 'Q5'"),
    ("missing argument", b"G1 X\n", 4, "word without a number 'X'"),
    ("arc radius", b"G2 X45 Y5 R10\n", 11, "arc radius shorter than half the chord 'R10'"),
    ("arc centre", b"G2 X15 Y5 I0 J0\n", 11, "arc centre on its start or end point 'I0'"),
    ("arc radii differ", b"G2 X15 Y5 I5.1\n", 1, "arc start and end radii differ 'G2'"),
    ("number too large", b"G1 X123456789012345678901234\n", 4, "number too large 'X1234567890123456789...'"),
    ("overlong line", b"G1 X6" + b" " * 300 + b"Y6\n", 257, "line too long (more than 256 bytes)"),
    ("binary junk", b"\x89PNG\r\n", 1, "binary or non-printable byte '0x89'"),
    ("byte in a word", b"G1 X6\x00Y7\n", 6, "binary or non-printable byte '0x00'"),
    ("parameters", b"G1 X#2\n", 5, "unsupported: parameters (#2)"),
    ("O-word", b"o100 sub\n", 1, "unsupported: O-words (subroutines, loops, conditionals) (O100)"),
]


@pytest.mark.parametrize("bad,column,msg", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_run_reports_line_and_column(sim, tmp_path, bad, column, msg):
    prog = tmp_path / "bad.ngc"
    prog.write_bytes(HEAD + bad + b"G1 X0 Y0\nM2\n%\n")
    p = sim("run", prog, "--machine", MACHINE, "--out", tmp_path / "out", "--json", ok=False)
    assert p.returncode == 1
    assert p.stdout == ""
    assert p.stderr == f"error: G-code line 5 column {column}: {msg}\n"


def test_run_good_program_of_the_same_shape(sim, tmp_path):
    """The frame of the cases above is itself valid: only the bad line makes them fail."""
    prog = tmp_path / "good.ngc"
    prog.write_bytes(HEAD + b"G1 X6 Y6\nG1 X0 Y0\nM2\n%\n")
    out = sim("run", prog, "--machine", MACHINE, "--out", tmp_path / "out", "--json")
    assert out["within_limits"] is True and out["end_error"] == 0


def test_run_counts_every_refused_line(sim, tmp_path):
    """Every line is read: the first error is shown, the others are counted (lissom-sim check lists them)."""
    prog = tmp_path / "bad.ngc"
    prog.write_bytes(HEAD + b"G1 X1 Q7\nG1 X#2\nG41\nG1 X0 Y0\nM2\n")
    p = sim("run", prog, "--machine", MACHINE, "--out", tmp_path / "out", ok=False)
    assert p.returncode == 1
    assert p.stderr == ("error: G-code line 5 column 7: unknown word 'Q7' (and 2 more: lissom-sim check lists "
                        "them)\n")
