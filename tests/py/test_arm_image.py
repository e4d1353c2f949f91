"""The Cortex-M4F self-test image under QEMU computes what the host float build computes.

Runs build-arm/bin/lissom-selftest.elf under `qemu-system-arm -M mps2-an386 -icount shift=0` and its host
twin build/bin/lissom-selftest-host (same program, same float core, compiled for the host), then compares:
  - the image's own checks passed and it exited 0;
  - the formatter line (the image's printf replacement) prints exactly the expected text;
  - per part: number of plans, number of cycles, and the plan-side hash agree exactly;
  - the sampled setpoints agree: bit-exact where the libm does not matter, otherwise within float rounding;
  - the cycle-side hash (every setpoint of every cycle) agrees exactly.
And the contour program (firmware/apps/contour: lines, arcs, a helix, a dense polyline and clothoid corners through
the look-ahead planner and the interpolator) on build-arm/bin/lissom-contour.elf against its host twin
build/bin/lissom-contour-host (same source, host float core):
  - the image's own checks passed ("contour PASS", exit 0), the host twin exited 0;
  - the checksum of every setpoint of every cycle, the cycle count, the end point and the planner statistics are
    equal, bit for bit (the float core uses only + - * /, sqrt, floor/ceil and its own sin/cos/cbrt/atan2, and
    neither build contracts a*b+c to a fused multiply-add: -std=c11);
  - every sampled setpoint is equal bit for bit (a mismatch names the first cycle that differs);
  - the run ends exactly on the programmed end point (0, 0, 0), on both.

Build directories: $LSM_BUILD_DIR (default build/) and $LSM_ARM_BUILD_DIR (default build-arm/). The test is
skipped, with the reason, when qemu-system-arm or the image is missing (scripts/arm_check.sh always builds it).
"""

import os
import shutil
import struct
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("LSM_BUILD_DIR", ROOT / "build"))
ARM_BUILD = Path(os.environ.get("LSM_ARM_BUILD_DIR", ROOT / "build-arm"))
IMAGE = ARM_BUILD / "bin" / "lissom-selftest.elf"
HOST = BUILD / "bin" / "lissom-selftest-host"
CONTOUR_IMAGE = ARM_BUILD / "bin" / "lissom-contour.elf"
CONTOUR_HOST = BUILD / "bin" / "lissom-contour-host"
QEMU = shutil.which("qemu-system-arm")
QEMU_CMD = [
    "qemu-system-arm", "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none",
    "-serial", "none", "-semihosting-config", "enable=on,target=native", "-icount", "shift=0", "-kernel",
]

EXPECTED_FMT = "fmt 0 4294967295 -2147483648 -42 0xdeadbeef 0x0000001a 123.45 -0.07 5 1000.000"

# Parts allowed to differ from the host by an ulp: none. The float core carries its own sin, cos, cbrt and atan2
# (firmware/base/lsm_math.c, + - * / only), so every part must match the host bit for bit. (Before it did, the
# closed-form part differed where newlib-nano and glibc round sinf differently.) Keep the mechanism for a
# future part that must call the C library.
LIBM_DEPENDENT_PARTS = set()

# Sampled values must agree to this fraction of the largest magnitude of the same quantity in the same part
# (float has 2^-23 = 1.2e-7 relative resolution; an ulp-level difference in sinf stays far below this).
SAMPLE_REL_TOL = 1e-5


def _run_image(image=IMAGE):
    if QEMU is None:
        pytest.skip("qemu-system-arm not installed (apt-get install qemu-system-arm)")
    if not image.exists():
        pytest.skip(f"{image} not built (scripts/arm_check.sh or cmake --preset cortex-m4f && "
                    "cmake --build build-arm)")
    proc = subprocess.run(QEMU_CMD + [str(image)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, timeout=120)
    return proc.returncode, proc.stdout


def _run_host(host=HOST):
    assert host.exists(), f"{host} missing: build the host first (cmake --build {BUILD})"
    proc = subprocess.run([str(host)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


def _parts(text):
    parts = {}
    for line in text.splitlines():
        if line.startswith("part "):
            fields = line.split()
            parts[fields[1]] = dict(f.split("=", 1) for f in fields[2:])
    return parts


def _samples(text):
    out = {}
    for line in text.splitlines():
        if line.startswith("sample "):
            f = line.split()
            key = tuple(int(x) for x in f[1:5])  # part, item, cycle, axis
            out[key] = [int(x, 16) for x in f[5:9]]
    return out


def _f32(bits):
    return struct.unpack("<f", struct.pack("<I", bits))[0]


@pytest.fixture(scope="module")
def image():
    return _run_image()


@pytest.fixture(scope="module")
def host():
    return _run_host()


def test_image_passes_its_own_checks(image):
    rc, out = image
    assert "check FAIL" not in out, out
    assert "selftest PASS" in out, out
    assert rc == 0, f"QEMU exit status {rc}\n{out}"


def test_formatter_prints_expected_text(image):
    _, out = image
    lines = [l for l in out.splitlines() if l.startswith("fmt ")]
    assert lines == [EXPECTED_FMT]


def test_plans_and_cycle_counts_match_host(image, host):
    arm, ref = _parts(image[1]), _parts(host)
    assert ref, "host printed no parts"
    assert sorted(arm) == sorted(ref)
    for name in ref:
        for key in ("plans", "cycles", "plan_hash"):
            assert arm[name][key] == ref[name][key], f"part {name}: {key} {arm[name][key]} != {ref[name][key]}"


def test_sampled_setpoints_match_host(image, host):
    arm, ref = _samples(image[1]), _samples(host)
    assert len(ref) > 100, "too few samples to compare"
    assert sorted(arm) == sorted(ref), "the image sampled other cycles than the host"
    scale = {}
    for (part, _item, _cycle, _axis), vals in ref.items():
        for i, b in enumerate(vals):
            scale[(part, i)] = max(scale.get((part, i), 0.0), abs(_f32(b)))
    part_names = list(_parts(host))
    for key, vals in ref.items():
        part = key[0]
        for i, (a, b) in enumerate(zip(arm[key], vals)):
            if a == b:
                continue
            assert part_names[part] in LIBM_DEPENDENT_PARTS, (
                f"sample {key}[{i}] differs in part {part_names[part]}, expected to match bit for bit")
            tol = SAMPLE_REL_TOL * max(scale[(part, i)], 1e-30)
            assert abs(_f32(a) - _f32(b)) <= tol, (key, i, _f32(a), _f32(b))


@pytest.mark.parametrize("part", ["scurve", "move"])
def test_cycle_hash_matches_host(image, host, part, request):
    if part in LIBM_DEPENDENT_PARTS:
        request.applymarker(pytest.mark.xfail(
            strict=True, reason="closed-form evaluation calls sinf/cosf each cycle; newlib-nano and glibc "
                                "differ by an ulp on some arguments (core needs its own sin/cos to match)"))
    arm, ref = _parts(image[1]), _parts(host)
    assert arm[part]["cycle_hash"] == ref[part]["cycle_hash"]


# ---- contour program (planner + interpolator) ----

def _contour(text):
    """The report of lsm_contour_report: (main fields, stats fields, {cycle: (x, y, z) bits})."""
    main = stats = None
    samples = {}
    for line in text.splitlines():
        f = line.split()
        if line.startswith("contour result="):
            main = dict(x.split("=", 1) for x in f[1:])
        elif line.startswith("contour_stats "):
            stats = dict(x.split("=", 1) for x in f[1:])
        elif line.startswith("contour_sample "):
            samples[int(f[1])] = tuple(int(x, 16) for x in f[2:5])
    assert main is not None and stats is not None, "no contour report in:\n" + text[-2000:]
    return main, stats, samples


@pytest.fixture(scope="module")
def contour_image():
    if not CONTOUR_IMAGE.exists():
        pytest.skip(f"{CONTOUR_IMAGE} not built (scripts/arm_check.sh)")
    return _run_image(CONTOUR_IMAGE)


@pytest.fixture(scope="module")
def contour_host():
    return _run_host(CONTOUR_HOST)


def test_contour_image_passes_its_own_checks(contour_image):
    rc, out = contour_image
    assert "check FAIL" not in out, out
    assert "contour PASS" in out, out
    assert rc == 0, f"QEMU exit status {rc}\n{out}"


def test_contour_runs_lines_arcs_clothoids_to_its_end(contour_host):
    main, stats, samples = _contour(contour_host)
    assert main["result"] == "1" and main["err"] == "0", main  # LSM_CONTOUR_DONE
    assert int(main["cycles"]) >= 300, "a few hundred ms of motion at least (1 ms cycle)"
    assert int(stats["corners"]) > 0 and int(stats["clothoid_cycles"]) > 0, stats
    assert int(stats["arc_cycles"]) > 0 and int(stats["line_cycles"]) > 0, stats
    assert stats["fallbacks"] == "0" and stats["plan_errors"] == "0", stats


def test_contour_ends_exactly_on_its_target(contour_image, contour_host):
    for name, text in (("image", contour_image[1]), ("host", contour_host)):
        main, _, samples = _contour(text)
        # the program's end is (0, 0, 0): bit pattern 0 (+0.0) on every axis, reported and sampled
        assert main["end"] == "0x00000000,0x00000000,0x00000000", (name, main["end"])
        assert main["end_exact"] == "1", name
        last = max(samples)
        assert last == int(main["cycles"]) - 1 and samples[last] == (0, 0, 0), (name, last, samples[last])


def test_contour_checksum_matches_host(contour_image, contour_host):
    arm, ref = _contour(contour_image[1]), _contour(contour_host)
    for key in ("cycles", "appends", "full_retries", "checksum", "end"):
        assert arm[0][key] == ref[0][key], f"{key}: image {arm[0][key]} != host {ref[0][key]}"
    assert arm[1] == ref[1], "planner statistics differ"


def test_contour_samples_match_host_bit_for_bit(contour_image, contour_host):
    arm, ref = _contour(contour_image[1])[2], _contour(contour_host)[2]
    assert len(ref) > 50
    assert sorted(arm) == sorted(ref), "the image sampled other cycles than the host"
    diff = [c for c in sorted(ref) if arm[c] != ref[c]]
    assert not diff, (f"{len(diff)} samples differ, first at cycle {diff[0]}: image "
                      f"{[_f32(b) for b in arm[diff[0]]]} host {[_f32(b) for b in ref[diff[0]]]}")
