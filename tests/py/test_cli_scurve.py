"""CLI contract of `lissom-sim scurve` and `lissom-sim move` (issue: foundation), checked from outside."""
import csv
import math

import pytest

# Kombarov Table 1 (m, s): dF, A, J, DJ -> printed values (Test 4's first J_P is 9.626; the paper's 6.685 is a typo)
TABLE1 = [
    ((0.22, 1.57, 16, 25132), dict(dt1=0.001, dt2=0.097, dt4=0.041, tp=0.239, jp_initial=16.0, jp=16.035, ap=1.568,
                                   dt1j=0.001, dt1a=0.009, dt1f=0.019, dt2a=0.097, dt2f=0.116, dt4f=0.041)),
    ((0.22, 1.57, 16, 560), dict(dt1=0.044, dt2=0.054, dt4=0.001, tp=0.285, jp_initial=15.686, jp=15.699, ap=1.537,
                                 dt1j=0.044, dt1a=0.066, dt1f=0.067, dt2a=0.056, dt2f=0.054, dt4f=0.001)),
    ((0.08, 1.57, 16, 560), dict(dt1=0.044, dt2=0.009, dt4=0.0, tp=0.194, jp_initial=15.686, jp=15.561, ap=0.831,
                                 dt1j=0.044, dt1a=0.066, dt1f=0.048, dt2a=0.056, dt2f=0.009, dt4f=-0.001)),
    ((0.015, 1.57, 16, 560), dict(dt1=0.027, dt2=0.001, dt4=0.001, tp=0.111, jp_initial=9.626, jp=9.566, ap=0.270,
                                  dt1j=0.044, dt1a=0.066, dt1f=0.027, dt2a=0.136, dt2f=0.001, dt4f=0.001)),
    ((0.15, 1.05, 24, 500), dict(dt1=0.057, dt2=0.0, dt4=0.031, tp=0.259, jp_initial=18.144, jp=18.149, ap=1.034,
                                 dt1j=0.075, dt1a=0.057, dt1f=0.061, dt2a=0.0, dt2f=0.01, dt4f=0.031)),
]


@pytest.mark.parametrize("inp,want", TABLE1)
def test_table1_paper_rule(sim, inp, want):
    df, a, j, dj = inp
    out = sim("scurve", "--v0", 0, "--v1", df, "--amax", a, "--jmax", j, "--snap-max", dj, "--cycle", 0.001,
              "--rule", "paper", "--json")
    for key, value in want.items():
        assert abs(out[key] - value) <= 0.001 + 1e-12, (key, out[key], value)
    assert out["n1"] == round(want["dt1"] / 0.001)
    assert abs(out["distance"] - df * out["tp"] / 2) < 1e-12


@pytest.mark.parametrize("inp,want", TABLE1)
def test_strict_rule_holds_limits(sim, inp, want):
    df, a, j, dj = inp
    out = sim("scurve", "--v0", 0, "--v1", df, "--amax", a, "--jmax", j, "--snap-max", dj, "--cycle", 0.001,
              "--json")
    assert out["rule"] == "strict"
    assert out["jp"] <= j and out["ap_final"] <= a and out["snap_final"] <= dj
    assert out["tp"] <= want["tp"] + 0.001 + 1e-12  # never meaningfully longer than the paper's own rule


def test_samples_csv(sim, tmp_path):
    f = tmp_path / "s.csv"
    out = sim("scurve", "--v0", 0.3, "--v1", 0.05, "--amax", 1.57, "--jmax", 16, "--snap-max", 560, "--cycle", 0.001,
              "--samples", f, "--json")
    rows = list(csv.DictReader(open(f)))
    assert list(rows[0].keys()) == ["t", "j", "a", "v", "s"]
    assert len(rows) == out["n1"] * 4 + out["n2"] * 2 + out["n4"] + 1
    assert float(rows[0]["v"]) == pytest.approx(0.3) and float(rows[-1]["v"]) == pytest.approx(0.05, abs=1e-12)
    assert float(rows[-1]["s"]) == pytest.approx(out["distance"], rel=1e-12)
    assert all(abs(float(r["j"])) <= out["jp"] * (1 + 1e-12) for r in rows)


def test_move_multi_axis(sim, tmp_path):
    f = tmp_path / "m.csv"
    out = sim("move", "--distance", "100,50,-20", "--vmax", 200, "--amax", 2000, "--jmax", 50000,
              "--snap-max", 2e6, "--cycle", 0.001, "--samples", f, "--json")
    assert out["n_cycles"] > 0 and out["duration"] == pytest.approx(out["n_cycles"] * 0.001)
    assert len(out["axes"]) == 3
    for ax in out["axes"]:
        assert abs(ax["end_error"]) < 1e-9 and ax["jp"] <= 50000
    assert out["axes"][1]["jp"] == pytest.approx(out["axes"][0]["jp"] / 2, rel=1e-9)  # per-axis corrected J_P
    rows = list(csv.reader(open(f)))
    assert rows[0] == ["t", "p0", "p1", "p2"]
    assert [float(x) for x in rows[-1][1:]] == [100.0, 50.0, -20.0]  # exactly on target


@pytest.mark.parametrize("args", [
    ["scurve", "--v0", "nan", "--v1", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["scurve", "--v0", 0, "--v1", "inf", "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["scurve", "--v0", 0, "--v1", 1, "--amax", 0, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["scurve", "--v0", 0, "--v1", 1, "--amax", 1, "--jmax", -1, "--snap-max", 1, "--cycle", 0.001],
    ["scurve", "--v0", 0, "--v1", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0],
    ["scurve", "--v0", -1, "--v1", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["scurve", "--v0", 0, "--v1", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001, "--rule", "x"],
    ["scurve", "--v0", "abc", "--v1", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["scurve", "--v1", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["move", "--distance", 0, "--vmax", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["move", "--distance", "1e300", "--vmax", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["move", "--distance", 10, "--vmax", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001,
     "--v0", 2],
    ["move", "--distance", "1,2", "--vmax", "1,2,3", "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001],
    ["move", "--distance", 10, "--vmax", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001, "--bogus"],
])
def test_bad_input_exits_nonzero(sim, args):
    p = sim(*args, "--json", ok=False)
    assert p.returncode != 0
    assert p.stderr.strip() and not p.stdout.strip()
