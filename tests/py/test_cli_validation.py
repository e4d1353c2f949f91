"""Every lissom-sim option is validated where it enters (issue 14 item 7; ranges in docs/host_sim.md).

Each bad value is refused before any work, with exit code 2 and one message that names the option and the value.
"""
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROUTER = os.path.join(ROOT, "host_sim", "machines", "router.json")
POCKET = os.path.join(ROOT, "host_sim", "examples", "pocket.ngc")
CORNER = os.path.join(ROOT, "host_sim", "examples", "shahzadeh_corner.ngc")

SC = ["scurve", "--v0", 0, "--v1", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001]
MV = ["move", "--distance", 10, "--vmax", 1, "--amax", 1, "--jmax", 1, "--snap-max", 1, "--cycle", 0.001]


def with_opt(base, name, value):
    """base with --name set to value (replaced if present, appended if not)."""
    out = list(base)
    key = "--" + name
    if key in out:
        out[out.index(key) + 1] = value
    else:
        out += [key, value]
    return out


def refused(sim, args, *needles):
    p = sim(*args, ok=False)
    assert p.returncode == 2, (args, p.returncode, p.stderr)
    assert p.stdout == "", p.stdout
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, p.stderr
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


@pytest.mark.parametrize("cycle,shown", [("1e300", "1e+300"), ("0.2", "0.2"), ("0", "0"), ("-0.001", "-0.001"),
                                         ("nan", "nan"), ("inf", "inf")])
@pytest.mark.parametrize("base", [SC, MV], ids=["scurve", "move"])
def test_cycle_range(sim, base, cycle, shown):
    refused(sim, with_opt(base, "cycle", cycle), "--cycle", shown, "(0, 0.1]")


def test_cycle_edge_accepted(sim):
    out = sim(*with_opt(SC, "cycle", 0.1), "--json")
    assert out["n1"] >= 1


@pytest.mark.parametrize("name,value,shown", [
    ("amax", "1e308", "1e+308"), ("amax", "1e10", "1e+10"), ("jmax", "1e13", "1e+13"),
    ("snap-max", "1e16", "1e+16"), ("amax", "1e-9", "1e-09"), ("jmax", "-1", "-1"), ("snap-max", "0", "0"),
])
@pytest.mark.parametrize("base", [SC, MV], ids=["scurve", "move"])
def test_limits_range(sim, base, name, value, shown):
    refused(sim, with_opt(base, name, value), "--" + name, shown, "out of range")


@pytest.mark.parametrize("name,value", [("vmax", "1e7"), ("distance", "1e300"), ("v0", "-1e9")])
def test_move_ranges(sim, name, value):
    refused(sim, with_opt(MV, name, value), "--" + name, "out of range")


@pytest.mark.parametrize("name", ["v0", "v1"])
def test_scurve_velocity_range(sim, name):
    refused(sim, with_opt(SC, name, "1e9"), "--" + name, "1e+09")


def test_limits_at_the_bounds_accepted(sim):
    out = sim(*with_opt(with_opt(SC, "amax", 1e9), "snap-max", 1e15), "--json")
    assert out["tp"] > 0


def test_run_directory_as_program(sim, tmp_path):
    refused(sim, ["run", str(tmp_path), "--machine", ROUTER, "--out", str(tmp_path / "o")],
            str(tmp_path), "directory")


def test_run_missing_program(sim, tmp_path):
    missing = str(tmp_path / "missing.ngc")
    refused(sim, ["run", missing, "--machine", ROUTER, "--out", str(tmp_path / "o")], missing)


def test_run_directory_as_machine(sim, tmp_path):
    refused(sim, ["run", POCKET, "--machine", str(tmp_path), "--out", str(tmp_path / "o")], str(tmp_path), "directory")


@pytest.mark.parametrize("kind", ["under_a_file", "is_a_file", "dev_null"])
def test_run_out_not_writable_refused_before_the_run(sim, tmp_path, kind):
    """Checked before the run (so no time is spent), one message naming the directory."""
    f = tmp_path / "afile"
    f.write_text("x")
    out = {"under_a_file": str(f / "sub"), "is_a_file": str(f), "dev_null": "/dev/null/run"}[kind]
    line = refused(sim, ["run", POCKET, "--machine", ROUTER, "--out", out, "--json"], out)
    assert "cannot create" in line or "not writable" in line
    assert f.read_text() == "x"


@pytest.mark.parametrize("cmd", ["scurve", "move"])
def test_samples_not_writable(sim, tmp_path, cmd):
    bad = str(tmp_path / "nodir" / "s.csv")
    refused(sim, [*(SC if cmd == "scurve" else MV), "--samples", bad], "--samples", bad)


def test_samples_directory_refused(sim, tmp_path):
    refused(sim, [*SC, "--samples", str(tmp_path)], "--samples", "directory")


def test_move_samples_bounded_up_front(sim, tmp_path):
    """--cycle 1e-7 with --samples would write about 1 GB: refused before anything is written."""
    s = tmp_path / "s.csv"
    line = refused(sim, [*with_opt(MV, "cycle", "1e-7"), "--samples", str(s)], "--samples", "cycles", "1e-07")
    assert "2000000" in line
    assert not s.exists()


def test_scurve_samples_bounded_up_front(sim, tmp_path):
    s = tmp_path / "s.csv"
    refused(sim, [*with_opt(SC, "cycle", "1e-7"), "--samples", str(s)], "--samples", "1e-07")
    assert not s.exists()


def test_samples_within_bound_written(sim, tmp_path):
    s = tmp_path / "s.csv"
    out = sim(*MV, "--samples", str(s), "--json")
    assert len(s.read_text().splitlines()) == out["n_cycles"] + 2  # header, cycles 0..n


@pytest.mark.parametrize("cmd", [["smooth", "--tolerance", 0.01], ["clothoid", "g2path", "--segments", 6]])
def test_gcode_directory_refused(sim, tmp_path, cmd):
    p = sim(*cmd, "--gcode", str(tmp_path), ok=False)
    assert p.returncode != 0 and "directory" in p.stderr and str(tmp_path) in p.stderr


@pytest.mark.parametrize("cmd", [["smooth", "--tolerance", 0.01], ["clothoid", "g2path", "--segments", 6]])
def test_gcode_limits_range(sim, cmd):
    p = sim(*cmd, "--gcode", CORNER, "--amax", "1e308", ok=False)
    assert p.returncode != 0 and "--amax" in p.stderr and "1e+308" in p.stderr


def test_demo_out_not_writable(sim, tmp_path):
    f = tmp_path / "afile"
    f.write_text("x")
    refused(sim, ["demo", "--out", str(f), "--no-plot"], str(f))


def test_experiment_out_not_writable(sim, tmp_path):
    f = tmp_path / "afile"
    f.write_text("x")
    refused(sim, ["experiment", "kombarov", "--out", str(f)], str(f))
