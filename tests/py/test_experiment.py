"""`lissom-sim experiment kombarov`: the §5.2 comparison on the simulated drive runs, is consistent with the
firmware's own plans, and rejects bad input."""
import cmath
import math
import re
from pathlib import Path

import pytest

MACHINES = Path(__file__).resolve().parents[2] / "host_sim" / "machines"


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


# ---- the decomposition, the sweep options and the physics behind the ratios (docs/host_sim.md) ----

NEW_KEYS = {"motion_max_following_error", "motion_rms_following_error", "residual_max_error", "residual_rms_error",
            "settle_time", "max_motor_following_error", "max_deflection", "max_dynamic_deflection",
            "spectral_residual_resonance", "spectral_residual_antiresonance", "current_limited"}


def _csv(path):
    lines = (path / "kombarov.csv").read_text().splitlines()
    head = lines[0].split(",")
    return {h: [float(line.split(",")[i]) for line in lines[1:]] for i, h in enumerate(head)}


def test_kombarov_decomposition_consistent(sim, tmp_path):
    """The new per-profile figures agree with the error trace in the CSV: motion = the cycles whose setpoint
    moves, residual = from the cycle whose setpoint is the target, settle time = last exit from the band."""
    band = 0.005  # the residual (Coulomb friction holding the spring, ~7 um) leaves 5 um after arrival
    out = sim("experiment", "kombarov", "--settle-window", 0.5, "--band", band, "--out", tmp_path, "--json")
    assert out["band_mm"] == band and out["settle_window_s"] == 0.5 and out["drive"]["feedback"] == "load"
    col = _csv(tmp_path)
    for name in ("trapezoid", "sin2"):
        p = out["profiles"][name]
        assert NEW_KEYS <= set(p)
        n = round(p["duration"] / 0.001)
        fe, setp = col[f"{name}_fe"], col[f"{name}_set"]
        assert setp[n - 1] == setp[-1] == 100.0 > setp[n - 20]  # the motion ends at cycle n
        total = n + 500
        fe = fe[:total]
        assert p["motion_max_following_error"] == pytest.approx(max(abs(e) for e in fe[:n]), rel=1e-7)
        assert p["residual_max_error"] == pytest.approx(max(abs(e) for e in fe[n - 1:]), rel=1e-7)
        assert p["max_following_error"] == pytest.approx(max(p["motion_max_following_error"],
                                                             p["residual_max_error"]), rel=1e-7)
        out_idx = [k for k in range(n - 1, total) if abs(fe[k]) > band]
        assert out_idx  # leaves the band after arrival
        if out_idx[-1] == total - 1:
            assert p["settle_time"] is None
        else:
            assert p["settle_time"] == pytest.approx((out_idx[-1] - (n - 1) + 1) * 0.001, abs=1e-9)
        # the load error is the motor error plus the spring deflection
        assert p["max_following_error"] <= p["max_motor_following_error"] + p["max_deflection"] + 1e-9
    # a band the error does not reach within the window: no settle time (null), not a number
    tight = sim("experiment", "kombarov", "--band", 1e-6, "--json")
    assert tight["profiles"]["trapezoid"]["settle_time"] is None and tight["ratio_settle"] is None
    t, s = out["profiles"]["trapezoid"], out["profiles"]["sin2"]
    assert out["ratio_residual_max"] == pytest.approx(t["residual_max_error"] / s["residual_max_error"])
    assert out["ratio_motion_max"] == pytest.approx(t["motion_max_following_error"] /
                                                    s["motion_max_following_error"])


def test_kombarov_lag_tail_without_feed_forward(sim, tmp_path):
    """Without feed-forward the error when the setpoint arrives is the position loop's lag of the end of the
    profile: for a first-order loop x' = kv (set - x) it is kv^-2 times the Laplace transform at kv of the final
    jerk. The trapezoid arrives with a jerk step (transform J / kv), sin² with a jerk that has faded to zero over
    T1 = 45 ms, so sin² arrives closer. Checked: (1) at kv 20 /s (velocity loop 2 pi 40 / 20 = 12x faster) the
    drive's arrival error matches the first-order model computed here from the setpoints within 3 % (measured
    0.2 % and 1.2 %); (2) the trapezoid / sin² residual ratio grows with kv (measured 1.51, 2.05, 2.64 at kv 20,
    40, 80: the higher kv, the shorter the part of the tail the loop remembers); (3) it reaches 1.9 at kv 40
    (measured 2.05) with the default friction (30 N Coulomb, where it is 2.0 too): the arrival error is
    ~250 um against a friction deflection of ~7 um."""
    out = sim("experiment", "kombarov", "--no-ff", "--coulomb", 0, "--kv", 20, "--settle-window", 0.5,
              "--out", tmp_path, "--json")
    col = _csv(tmp_path)
    for name in ("trapezoid", "sin2"):
        p = out["profiles"][name]
        n = round(p["duration"] / 0.001)
        s, x, prev, sub, kv = col[f"{name}_set"], 0.0, 0.0, 64, 20.0
        for k in range(n):
            for j in range(1, sub + 1):
                x += 0.001 / sub * kv * (prev + (s[k] - prev) * j / sub - x)
            prev = s[k]
        predicted = s[n - 1] - x
        arrival = col[f"{name}_fe"][n - 1]
        assert arrival == pytest.approx(predicted, rel=0.03)
        assert p["residual_max_error"] == pytest.approx(arrival, rel=1e-6)  # the largest residual is on arrival
    ratios = [sim("experiment", "kombarov", "--no-ff", "--coulomb", 0, "--kv", kv, "--json")["ratio_residual_max"]
              for kv in (20, 40, 80)]
    assert ratios[0] < ratios[1] < ratios[2]
    assert ratios[1] >= 1.9
    dflt = sim("experiment", "kombarov", "--no-ff", "--json")
    assert dflt["ratio_residual_max"] >= 1.9
    # ... while the error during the motion is v / kv for both: no 2x there
    assert dflt["ratio_max"] < 1.05 and dflt["ratio_motion_max"] < 1.05


def test_kombarov_spectrum(sim, tmp_path):
    """The spectral argument. The setpoint acceleration's spectrum |A(w)| / w (the vibration an undamped mode at
    w is left with) falls off faster for sin², whose jerk rises over T1 = 45 ms instead of one cycle, but only
    above ~1 / T1 = 22 Hz: measured trapezoid / sin² 1.03 at 10 Hz, 15.5 at 50 Hz, 64 at 100 Hz. Checked against
    an independent evaluation from the CSV setpoint, then the margins 10 Hz < 1.5, 50 Hz > 8, 100 Hz > 30."""
    out = sim("experiment", "kombarov", "--resonance-hz", 50, "--out", tmp_path, "--json")
    col = _csv(tmp_path)
    f_res = out["drive"]["resonance_hz"]
    assert f_res == pytest.approx(50, rel=1e-9)
    for name in ("trapezoid", "sin2"):
        n = round(out["profiles"][name]["duration"] / 0.001)
        s = col[f"{name}_set"][:n]
        v = [(s[k] - (s[k - 1] if k else 0.0)) / 0.001 for k in range(n)] + [0.0]
        dv = [v[k] - (v[k - 1] if k else 0.0) for k in range(n + 1)]
        best = 0.0
        for i in range(41):
            w = 2 * math.pi * f_res * 1.25 ** ((i - 20) / 20)
            z = sum(d * cmath.exp(-1j * w * k * 0.001) for k, d in enumerate(dv))
            best = max(best, abs(z) / w)
        # the CSV has 9 significant digits: 1e-7 mm on a 100 mm position, which the second difference turns into
        # up to ~1e-5 mm here (measured 5e-8 and 2.5e-7 mm); the values compared are 4.8e-3 and 3.1e-4 mm
        assert out["profiles"][name]["spectral_residual_resonance"] == pytest.approx(best, rel=1e-3, abs=1e-5)
    # the spectrum does not depend on the drive: take it from a sweep (which also runs drives whose step test fails)
    rows = sim("experiment", "kombarov", "--sweep", "--resonance-hz", "10,50,100", "--damping", 0.05, "--json")["sweep"]
    r = {round(x["drive"]["resonance_hz"]): x["ratio_spectral_resonance"] for x in rows}
    assert r[10] < 1.5 and r[50] > 8 and r[100] > 30


def test_kombarov_lightly_damped_residual(sim):
    """A lightly damped 50 Hz resonance (zeta 0.01) on a semi-closed loop with feed-forward and no Coulomb
    friction: the residual error after arrival (an oscillation that decays in ~80 ms) is 4.4x smaller with sin²
    (4.36 um against 0.99 um), because the trapezoid arrives with a jerk step that excites it and sin² with zero
    jerk and snap. Margin 3x. The max error during the motion (quasi-static spring deflection m_l a / k, 67 um)
    stays within 10 % between the profiles."""
    out = sim("experiment", "kombarov", "--feedback", "motor", "--coulomb", 0, "--resonance-hz", 50,
              "--damping", 0.01, "--settle-window", 0.5, "--json")
    assert out["drive"]["feedback"] == "motor" and out["drive"]["damping"] == pytest.approx(0.01)
    assert out["ratio_residual_max"] > 3
    assert out["ratio_motion_max"] < 1.1
    assert not out["profiles"]["trapezoid"]["current_limited"]


def test_kombarov_options_take_effect(sim):
    base = sim("experiment", "kombarov", "--json")["drive"]
    assert base["resonance_hz"] == pytest.approx(99.53, abs=0.01) and base["vff_gain"] == 1
    d = sim("experiment", "kombarov", "--resonance-hz", 60, "--damping", 0.03, "--vel-bw-hz", 30, "--json")["drive"]
    assert d["resonance_hz"] == pytest.approx(60) and d["damping"] == pytest.approx(0.03)
    assert d["vel_bw_hz"] == pytest.approx(30) and d["vel_ti_s"] == pytest.approx(0.02)
    assert d["kv_1_s"] == pytest.approx(base["kv_1_s"] * 30 / base["vel_bw_hz"])  # kv scaled with the loop
    d = sim("experiment", "kombarov", "--vel-bw-hz", 30, "--kv", 25, "--no-ff", "--json")["drive"]
    assert d["kv_1_s"] == 25 and d["vff_gain"] == 0 and d["aff_gain"] == 0
    # --damping alone keeps the resonance, --resonance-hz alone keeps the damping ratio
    d = sim("experiment", "kombarov", "--damping", 0.02, "--json")["drive"]
    assert d["resonance_hz"] == pytest.approx(base["resonance_hz"]) and d["damping"] == pytest.approx(0.02)
    d = sim("experiment", "kombarov", "--resonance-hz", 70, "--json")["drive"]
    assert d["damping"] == pytest.approx(base["damping"])
    m = sim("experiment", "kombarov", "--machine", MACHINES / "router.json", "--axis", "Y", "--json")["drive"]
    assert m["resonance_hz"] == pytest.approx(74.4, abs=0.1) and m["encoder_counts_per_mm"] == 1000


def test_kombarov_sweep(sim):
    out = sim("experiment", "kombarov", "--sweep", "--resonance-hz", "20,50,100", "--damping", "0.01,0.1",
              "--vel-bw-hz", "20,40", "--json")
    rows = out["sweep"]
    assert len(rows) == 12
    grid = {(round(r["drive"]["resonance_hz"], 6), round(r["drive"]["damping"], 9), round(r["drive"]["vel_bw_hz"], 6))
            for r in rows}
    assert grid == {(f, z, b) for f in (20, 50, 100) for z in (0.01, 0.1) for b in (20, 40)}
    for r in rows:
        assert set(r["profiles"]) == {"trapezoid", "sin2", "cjerk"} and isinstance(r["step_test_settled"], bool)
        assert "ratio_residual_max" in r and "ratio_max" in r
    # a 20 Hz resonance under a 40 Hz velocity loop closed on the load is unstable: flagged, not hidden
    bad = [r for r in rows if r["drive"]["resonance_hz"] == pytest.approx(20) and r["drive"]["vel_bw_hz"] > 30]
    assert bad and not any(r["step_test_settled"] for r in bad)
    # the same single run is refused
    p = sim("experiment", "kombarov", "--resonance-hz", 20, ok=False)
    assert p.returncode == 1 and "does not settle" in p.stderr


@pytest.mark.parametrize("args", [["--damping", 1], ["--damping", -0.1], ["--damping", "nan"],
                                  ["--resonance-hz", 0], ["--resonance-hz", "x"], ["--vel-bw-hz", -5],
                                  ["--kv", 0], ["--coulomb", -1], ["--band", 0], ["--settle-window", 20],
                                  ["--feedback", "encoder"], ["--no-ff", "--vff", 1], ["--axis", "X"],
                                  ["--resonance-hz", "50,60"], ["--sweep", "--out", "/tmp/x"],
                                  ["--machine", "/nonexistent.json"],
                                  ["--machine", str(Path(__file__).parents[2] / "host_sim/machines/router.json"),
                                   "--axis", "A"],
                                  ["--sweep", "--damping", "0.01,2"], ["--bogus", 1]])
def test_kombarov_bad_options(sim, args):
    p = sim("experiment", "kombarov", *args, ok=False)
    assert p.returncode == 2 and p.stderr.startswith("error:")


def test_kombarov_positioning_machine(sim):
    """The shipped chosen case (host_sim/machines/kombarov_positioning.json, docs/host_sim.md): a lightly damped
    45 Hz axis in position mode without feed-forward. Measured: positioning error at arrival 262 um against
    131 um (2.00x), max error over the move 5481 um for both (1.00x). Checked: the file is the case the docs
    describe, the residual ratio is >= 1.9 and the max-error ratio < 1.05; with feed-forward switched on the same
    axis no longer gives 2x on the residual (measured 1.84: friction and spring deflection, 13 um and 7 um)."""
    m = str(MACHINES / "kombarov_positioning.json")
    out = sim("experiment", "kombarov", "--machine", m, "--settle-window", 1, "--json")
    d = out["drive"]
    assert d["resonance_hz"] == pytest.approx(45, abs=0.05) and d["damping"] == pytest.approx(0.02, abs=1e-4)
    assert d["vff_gain"] == 0 and d["aff_gain"] == 0 and d["feedback"] == "load" and d["kv_1_s"] == 40
    assert out["ratio_residual_max"] >= 1.9
    assert out["ratio_max"] < 1.05 and out["ratio_rms"] < 1.05
    ff = sim("experiment", "kombarov", "--machine", m, "--vff", 1, "--aff", 1, "--settle-window", 1, "--json")
    assert ff["ratio_residual_max"] < 2


# ---- the JSON keys documented in docs/host_sim.md, and the ratios ----

RATIOS = {  # ratio key: (numerator profile, per-profile key); the denominator is always sin2
    "ratio_max": ("trapezoid", "max_following_error"), "ratio_rms": ("trapezoid", "rms_following_error"),
    "ratio_max_cjerk": ("cjerk", "max_following_error"), "ratio_rms_cjerk": ("cjerk", "rms_following_error"),
    "ratio_residual_max_cjerk": ("cjerk", "residual_max_error"),
    "ratio_motion_max": ("trapezoid", "motion_max_following_error"),
    "ratio_motion_rms": ("trapezoid", "motion_rms_following_error"),
    "ratio_residual_max": ("trapezoid", "residual_max_error"), "ratio_residual_rms": ("trapezoid", "residual_rms_error"),
    "ratio_settle": ("trapezoid", "settle_time"),
    "ratio_spectral_resonance": ("trapezoid", "spectral_residual_resonance"),
    "ratio_spectral_antiresonance": ("trapezoid", "spectral_residual_antiresonance"),
}


def documented_keys():
    """The first column of the key table under **CLI.** in docs/host_sim.md: (top-level keys, per-profile keys),
    and the sub-keys listed for `drive` and `profiles.*.limits`."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "host_sim.md").read_text(encoding="utf-8")
    table = text[text.index("| Key | Unit | Meaning |"):]
    table = table[:table.index("\n\n")]
    top, per, sub = set(), set(), {}
    for row in table.splitlines()[2:]:
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", row.strip()[1:-1])]  # cells split on unescaped |
        names = re.findall(r"`([^`]+)`", cells[0])
        if names[0].startswith("profiles.*."):  # `profiles.*.a`, `b`: both per profile
            per.update(k.replace("profiles.*.", "") for k in names)
        else:
            top.update(names)
        if cells[0] in ("`drive`", "`profiles.*.limits`"):
            sub[cells[0].strip("`")] = set(re.findall(r"`([a-z_0-9]+)`", cells[2])) - {"load", "motor", "null"}
    return top, per, sub


def check_ratios(obj):
    prof = obj["profiles"]
    for key, (num, field) in RATIOS.items():
        a, b = prof[num][field], prof["sin2"][field]
        if a is None or b is None or b == 0:
            assert obj[key] is None, key
        else:
            assert obj[key] == pytest.approx(a / b, rel=1e-7), key


def test_kombarov_json_keys_documented(sim):
    top, per, sub = documented_keys()
    assert {"ratio_max", "ratio_rms", "ratio_max_cjerk", "profiles", "drive"} <= top and "limits" in per
    out = sim("experiment", "kombarov", "--json")
    assert set(out) == top  # every documented key, and no other
    assert set(out["drive"]) == sub["drive"]
    for name, snap in (("trapezoid", 25132000), ("sin2", 560000), ("cjerk", None)):
        p = out["profiles"][name]
        assert set(p) == per, name
        assert p["limits"] == {"v_max_mm_s": 220, "a_max_mm_s2": 1570, "j_max_mm_s3": 16000, "snap_max_mm_s4": snap}
        assert set(p["limits"]) == sub["profiles.*.limits"]
    check_ratios(out)
    # the sweep rows carry the same per-row keys
    sweep = sim("experiment", "kombarov", "--sweep", "--resonance-hz", "50,100", "--damping", 0.05, "--json")
    assert set(sweep) == {"distance_mm", "band_mm", "settle_window_s", "sweep"}
    for row in sweep["sweep"]:
        assert set(row) == {"drive", "step_test_settled", "profiles"} | set(RATIOS)
        assert all(set(p) == per for p in row["profiles"].values())
        check_ratios(row)


def test_kombarov_text_output(sim):
    """Without --json: one row per profile with its max and RMS error, and the two lines of ratios, which agree
    with the JSON run."""
    text = sim("experiment", "kombarov")
    js = sim("experiment", "kombarov", "--json")
    rows = {}
    for line in text.splitlines():
        m = re.match(r"\s+(trapezoid|sin2|cjerk)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s", line)
        if m:
            rows[m.group(1)] = [float(x) for x in m.groups()[1:]]
    assert set(rows) == {"trapezoid", "sin2", "cjerk"}
    for name, (dur, mx, rms) in rows.items():
        p = js["profiles"][name]
        assert dur == pytest.approx(p["duration"], abs=1e-4)
        assert mx == pytest.approx(1e3 * p["max_following_error"], abs=1e-3)  # printed in um
        assert rms == pytest.approx(1e3 * p["rms_following_error"], abs=1e-3)
    m = re.search(r"trapezoid / sin2: max ([\d.]+)x, RMS ([\d.]+)x, residual ([\d.]+)x", text)
    assert m and float(m.group(1)) == pytest.approx(js["ratio_max"], abs=0.006)
    assert float(m.group(2)) == pytest.approx(js["ratio_rms"], abs=0.006)
    assert float(m.group(3)) == pytest.approx(js["ratio_residual_max"], abs=0.006)
    m = re.search(r"cjerk / sin2:\s+max ([\d.]+)x, RMS ([\d.]+)x, residual ([\d.]+)x", text)
    assert m and float(m.group(1)) == pytest.approx(js["ratio_max_cjerk"], abs=0.006)
    assert float(m.group(2)) == pytest.approx(js["ratio_rms_cjerk"], abs=0.006)
    assert float(m.group(3)) == pytest.approx(js["ratio_residual_max_cjerk"], abs=0.006)
