"""The command-line contract of `lissom-sim clothoid eval|fit|g2path` and `lissom-sim smooth`:
JSON on stdout with the documented keys, non-zero exit and a message on stderr for bad input.
The binary: env LISSOM_SIM, else build/bin/lissom-sim under the repository root (conftest.py)."""
import json
import math
import os

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLES = os.path.normpath(os.path.join(HERE, "..", "..", "host_sim", "examples"))
CORNER = os.path.join(EXAMPLES, "shahzadeh_corner.ngc")


def test_eval_keys_and_values(sim):
    r = sim("clothoid", "eval", "--x0", 1, "--y0", 2, "--theta0", 0.5, "--kappa0", 0.1, "--c", -0.02, "--s", 7.5,
            "--json")
    assert set(r) == {"x", "y", "theta", "kappa"}
    assert r["theta"] == pytest.approx(0.5 + 0.1 * 7.5 - 0.01 * 7.5 ** 2, abs=1e-15)
    assert r["kappa"] == pytest.approx(0.1 - 0.02 * 7.5, abs=1e-16)
    # the start state at s = 0
    r0 = sim("clothoid", "eval", "--x0", 1, "--y0", 2, "--theta0", 0.5, "--kappa0", 0.1, "--c", -0.02, "--s", 0,
             "--json")
    assert r0 == {"x": 1, "y": 2, "theta": 0.5, "kappa": 0.1}
    # a straight line and a circle
    line = sim("clothoid", "eval", "--theta0", 0.25, "--c", 0, "--s", 10, "--json")
    assert line["x"] == pytest.approx(10 * math.cos(0.25), abs=1e-14)
    assert line["y"] == pytest.approx(10 * math.sin(0.25), abs=1e-14)
    circ = sim("clothoid", "eval", "--kappa0", 0.1, "--c", 0, "--s", 10 * math.pi, "--json")  # half a circle, R 10
    assert circ["x"] == pytest.approx(0, abs=1e-13) and circ["y"] == pytest.approx(20, abs=1e-13)


def test_eval_text_output(sim):
    out = sim("clothoid", "eval", "--c", 1, "--s", 1)
    assert "x " in out and "kappa" in out


def test_fit_keys(sim):
    r = sim("clothoid", "fit", "--x0", 0, "--y0", 0, "--theta0", 0, "--kappa0", 0, "--line", "0,1,-10", "--json")
    for key in ("c", "s", "x", "y", "theta", "kappa", "iterations"):
        assert key in r
    assert r["y"] == pytest.approx(10, abs=1e-12)
    assert r["theta"] == pytest.approx(math.pi / 2, abs=1e-12)  # normal to y = 10
    assert isinstance(r["iterations"], int)


BAD_EVAL = [
    ["--c", 1],                                  # no --s
    ["--s", 1],                                  # no --c
    ["--c", "abc", "--s", 1],
    ["--c", 1, "--s", "1x"],
    ["--c", "nan", "--s", 1],
    ["--c", 1, "--s", "inf"],
    ["--c", 1, "--s", 1, "--x0", "nan"],
    ["--c", 1, "--s", 1, "--bogus", 3],
    ["--c", 1e300, "--s", 1e10],                 # result beyond double
    ["--c", 1, "--s"],                           # option without value
]


@pytest.mark.parametrize("args", BAD_EVAL)
def test_eval_bad_input(sim, args):
    p = sim("clothoid", "eval", *args, "--json", ok=False)
    assert p.returncode != 0 and p.stdout == "" and p.stderr.strip()


BAD_FIT = [
    ["--line", "0,0,1"],                         # degenerate line
    ["--line", "1,0"],                           # two numbers
    ["--line", "1,0,x"],
    ["--line", "nan,1,1"],
    ["--line", "1,inf,1"],
    ["--x0", 5, "--theta0", 1.5707963267948966, "--line", "1,0,-5"],  # on the line, along it
    ["--line", "1,0,10"],                        # heading straight away from x = -10: no solution
    [],                                          # no --line
]


@pytest.mark.parametrize("args", BAD_FIT)
def test_fit_bad_input(sim, args):
    p = sim("clothoid", "fit", *args, "--json", ok=False)
    assert p.returncode != 0 and p.stdout == "" and p.stderr.strip()


def test_unknown_action(sim):
    assert sim("clothoid", "evaluate", ok=False).returncode != 0
    assert sim("clothoid", ok=False).returncode != 0


def test_g2path_paper(sim):
    r = sim("clothoid", "g2path", "--gcode", CORNER, "--segments", 6, "--json")
    assert r["segments"] == 6
    assert r["deviation_polygon"] == pytest.approx(0.945, abs=0.0006)
    assert r["sharpness_max"] == pytest.approx(0.00817, abs=0.000005)
    assert r["feed_limit_eq8_mm_min"] == pytest.approx(2364, abs=1)
    assert r["feed_limit_eq7_mm_min"] == pytest.approx(1275, abs=1)
    r = sim("clothoid", "g2path", "--gcode", CORNER, "--segments", 96, "--json", "--list")
    assert r["deviation"] == pytest.approx(0.0040, abs=0.00005)
    assert r["sharpness_max"] == pytest.approx(0.1046, abs=0.0005)
    assert len(r["clothoids"]) == 96
    r = sim("clothoid", "g2path", "--gcode", CORNER, "--tolerance", 0.01, "--json")
    assert r["deviation"] <= 0.01


@pytest.mark.parametrize("args", [["--segments", 6], ["--gcode", CORNER], ["--gcode", CORNER, "--segments", 2],
                                  ["--gcode", CORNER, "--segments", 6, "--tolerance", 0.1],
                                  ["--gcode", CORNER, "--tolerance", 0], ["--gcode", "/nonexistent.ngc", "--segments", 6],
                                  ["--gcode", CORNER, "--segments", 6, "--amax", -1]])
def test_g2path_bad_input(sim, args):
    p = sim("clothoid", "g2path", *args, "--json", ok=False)
    assert p.returncode != 0 and p.stdout == ""


@pytest.mark.parametrize("tol", [0.001, 0.01, 0.05])
def test_smooth_contract(sim, tol):
    r = sim("smooth", "--gcode", CORNER, "--tolerance", tol, "--amax", 50, "--jmax", 500, "--json")
    for key in ("max_deviation", "max_curvature_jump", "feed_limit_eq7_mm_s", "feed_limit_eq8_mm_s", "corners"):
        assert key in r
    smoothed = [c for c in r["corners"] if c["status"] == "smoothed"]
    assert len(smoothed) == 2  # A and B: the line-arc joints (tangent, curvature jump)
    for c in smoothed:
        for key in ("deviation", "kappa_max", "sharpness_max"):
            assert key in c and c[key] > 0
        assert c["deviation"] <= tol and c["deviation_sampled"] <= tol * (1 + 1e-9)
    assert r["max_deviation"] <= tol and r["max_deviation_sampled"] <= tol * (1 + 1e-9)
    assert r["max_curvature_jump"] < 1e-9 * r["kappa_max"]
    assert r["max_curvature_jump_rel"] < 1e-9
    assert r["max_position_gap"] < 1e-9 and r["max_tangent_jump_rad"] < 1e-9
    # eq 7 and eq 8 from the reported maxima
    assert r["feed_limit_eq7_mm_s"] == pytest.approx(math.sqrt(50 / r["kappa_max"]), rel=1e-12)
    assert r["feed_limit_eq8_mm_s"] == pytest.approx((500 / r["sharpness_max"]) ** (1 / 3), rel=1e-12)
    assert r["feed_limit_mm_s"] == min(r["feed_limit_eq7_mm_s"], r["feed_limit_eq8_mm_s"])


def test_smooth_examples(sim):
    for name in ("pocket.ngc", "circle_chords.ngc", "trident.ngc"):
        r = sim("smooth", "--gcode", os.path.join(EXAMPLES, name), "--tolerance", 0.02, "--json")
        assert r["max_deviation_sampled"] <= 0.02 * (1 + 1e-9)
        assert r["max_curvature_jump_rel"] < 1e-9
        assert r["smoothed"] > 0


def test_smooth_stops_and_joins(sim, tmp_path):
    prog = tmp_path / "p.ngc"
    prog.write_text("G21 G90 G17 G64\nG0 X-5 Y0\nG1 X10 Y0 F1000\nG1 X20 Y0\nG1 X20 Y10\nG1 X10 Y10 A30\n"
                    "G1 X10 Y20\nG61\nG1 X0 Y20\nG1 X0 Y0\nM2\n")
    r = sim("smooth", "--gcode", str(prog), "--tolerance", 0.01, "--json")
    st = [(c["status"], c.get("reason", "")) for c in r["corners"]]
    assert st[0][0] == "stop" and "rapid" in st[0][1]
    assert st[1][0] == "joined"                    # collinear X10 -> X20
    assert st[2][0] == "smoothed"
    assert st[3][0] == "stop" and "rotary" in st[3][1]
    assert st[4][0] == "stop"                      # the A move again
    assert st[6][0] == "stop" and "G61" in st[6][1]


@pytest.mark.parametrize("args", [["--tolerance", 0.01], ["--gcode", CORNER], ["--gcode", CORNER, "--tolerance", 0],
                                  ["--gcode", CORNER, "--tolerance", -0.1], ["--gcode", CORNER, "--tolerance", "nan"],
                                  ["--gcode", CORNER, "--tolerance", "x"], ["--gcode", "/nonexistent.ngc", "--tolerance", 1],
                                  ["--gcode", CORNER, "--tolerance", 0.01, "--jmax", 0]])
def test_smooth_bad_input(sim, args):
    p = sim("smooth", *args, "--json", ok=False)
    assert p.returncode != 0 and p.stdout == "" and p.stderr.strip()


def test_smooth_bad_gcode(sim, tmp_path):
    prog = tmp_path / "bad.ngc"
    prog.write_text("G1 X10 Y0 F100\nG1 X10 Y10 Q7\n")
    p = sim("smooth", "--gcode", str(prog), "--tolerance", 0.01, "--json", ok=False)
    assert p.returncode != 0 and "bad.ngc:2" in p.stderr
