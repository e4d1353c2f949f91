"""The continuous axis jerk that the VPOp reference's motion asks between its samples (`run --planner vpop`,
`intersample_jerk_ratio`, host_sim/pathrun.c). VPOp holds the jerk limit on the backward differences of its samples
(Beudaert eq 6); between them the axis jerk is q_s s''' + 3 q_ss s' s'' + q_sss s'^3 (Beudaert eq 3).

- On a straight line q_ss = q_sss = 0: the continuous jerk is the tangential one, which VPOp keeps at the limit, so
  its 99th percentile is 1 within the finite-difference noise.
- On the trident polyline (Beudaert's example), whose curvature changes fast at the tips, VPOp's motion asks much
  more than the limit between its samples: the measured figures are what docs/vpop.md reports.
"""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run_vpop(sim, program, machine, tmp_path):
    return sim("run", program, "--machine", machine, "--out", tmp_path / "o", "--json", "--planner", "vpop",
               "--no-drive", "--no-progress")


def test_line_holds_the_limit_between_samples(sim, tmp_path):
    prog = tmp_path / "line.ngc"
    prog.write_text("G21 G90 G17 G64 P0.01\nG1 X40 Y25 F6000\nM2\n")
    d = run_vpop(sim, str(prog), os.path.join(ROOT, "host_sim/machines/router.json"), tmp_path)
    isj = d["intersample_jerk_ratio"]
    assert 0 <= isj["p99"] <= isj["max"]
    assert isj["p99"] <= 1.0 + 1e-3
    assert isj["max"] <= 1.0 + 1e-2


def test_trident_asks_more_than_the_limit_between_samples(sim, tmp_path):
    d = run_vpop(sim, os.path.join(ROOT, "host_sim/examples/trident.ngc"),
                 os.path.join(ROOT, "host_sim/machines/beudaert_table1.json"), tmp_path)
    isj = d["intersample_jerk_ratio"]
    # held at the samples (eq 6) ...
    assert all(a["max_axis_jerk"] <= a["j_max"] * (1 + 1e-6) for a in d["axes"])
    # ... but not in between (measured 2.10 and 1.72)
    assert isj["max"] > 1.9 and isj["p99"] > 1.5
