"""`lissom-sim experiment kombarov`: the §5.2 comparison on the simulated drive runs, is consistent with the
firmware's own plans, and rejects bad input."""
import pytest


def test_kombarov_experiment_consistent(sim, tmp_path):
    out = sim("experiment", "kombarov", "--distance", 20, "--out", tmp_path, "--json")
    prof = out["profiles"]
    assert set(prof) == {"trapezoid", "sin2", "cjerk"}
    # the sin² and trapezoid durations are the firmware's own move plans (Table 1 Test 2 and Test 1 limits)
    for name, snap in (("sin2", 560000), ("trapezoid", 25132000)):
        mv = sim("move", "--distance", 20, "--vmax", 220, "--amax", 1570, "--jmax", 16000, "--snap-max", snap,
                 "--cycle", 0.001, "--json")
        assert prof[name]["duration"] == pytest.approx(mv["duration"], abs=1e-12)
    # bounding the snap costs time against the constant-jerk optimum
    assert prof["cjerk"]["duration"] < prof["trapezoid"]["duration"] + 0.001 < prof["sin2"]["duration"] + 0.001
    for p in prof.values():
        assert 0 < p["rms_following_error"] <= p["max_following_error"] < 1.0
    assert out["ratio_max"] == pytest.approx(prof["trapezoid"]["max_following_error"] /
                                             prof["sin2"]["max_following_error"])
    lines = (tmp_path / "kombarov.csv").read_text().splitlines()
    assert lines[0] == "t,trapezoid_set,trapezoid_fe,sin2_set,sin2_fe,cjerk_set,cjerk_fe"
    last = [float(x) for x in lines[-1].split(",")]
    assert last[1] == last[3] == last[5] == 20.0  # every profile ends exactly on the target


@pytest.mark.parametrize("args", [["experiment"], ["experiment", "other"],
                                  ["experiment", "kombarov", "--distance", 0],
                                  ["experiment", "kombarov", "--vff", 7]])
def test_experiment_bad_input(sim, args):
    p = sim(*args, ok=False)
    assert p.returncode != 0 and p.stderr
