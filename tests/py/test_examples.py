"""The committed example programs (host_sim/examples) are exactly what hil/lissom_hil/make_examples.py
generates, and the trident spline in them has the length given in the papers' NOTES.md."""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "hil"))

from lissom_hil import make_examples  # noqa: E402

EXAMPLES = os.path.normpath(os.path.join(HERE, "..", "..", "host_sim", "examples"))


def test_examples_are_reproducible():
    files = make_examples.generate()
    assert set(files) == {"shahzadeh_corner.ngc", "trident.ngc", "trident_bspline.json", "circle_chords.ngc",
                          "pocket.ngc", "surface_finish.ngc"}
    for name, text in files.items():
        with open(os.path.join(EXAMPLES, name), encoding="utf-8") as f:
            assert f.read() == text, name + " differs from make_examples.py output: regenerate it"
        if name.endswith(".ngc"):
            lines = text.splitlines()
            assert lines[0] == "%" and lines[-1] == "%" and lines[-2] == "M2"
            assert max(len(line) for line in lines) <= 256  # LSM_GCODE_MAX_LINE
            for line in lines:  # no nested parentheses in "( )" comments (";" comments may hold any text)
                code = line.split(";")[0]
                if "(" in code:
                    inner = code[code.index("(") + 1:code.rindex(")")]
                    assert "(" not in inner and ")" not in inner, line


def test_trident_spline():
    meta = json.load(open(os.path.join(EXAMPLES, "trident_bspline.json")))
    assert meta["degree"] == 3 and len(meta["control_points_mm"]) == 7 and len(meta["knots"]) == 11
    assert abs(meta["length_mm"] - 59.168013) < 1e-6
    # de Boor evaluation hits the end control points (clamped knots)
    p0 = make_examples.bspline_basis_eval(0.0, 3, meta["knots"], meta["control_points_mm"])
    p1 = make_examples.bspline_basis_eval(1.0, 3, meta["knots"], meta["control_points_mm"])
    assert list(p0) == [10, 0] and list(p1) == [10, 0]
