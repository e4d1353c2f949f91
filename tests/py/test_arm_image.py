"""The Cortex-M4F self-test image under QEMU computes what the host float build computes.

Runs build-arm/bin/lissom-selftest.elf under `qemu-system-arm -M mps2-an386 -icount shift=0` and its host
twin build/bin/lissom-selftest-host (same program, same float core, compiled for the host), then compares:
  - the image's own checks passed and it exited 0;
  - the formatter line (the image's printf replacement) prints exactly the expected text;
  - per part: number of plans, number of cycles, and the plan-side hash agree exactly;
  - the sampled setpoints agree: bit-exact where the libm does not matter, otherwise within float rounding;
  - the cycle-side hash (every setpoint of every cycle) agrees exactly.

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
QEMU = shutil.which("qemu-system-arm")
QEMU_CMD = [
    "qemu-system-arm", "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none",
    "-serial", "none", "-semihosting-config", "enable=on,target=native", "-icount", "shift=0", "-kernel",
]

EXPECTED_FMT = "fmt 0 4294967295 -2147483648 -42 0xdeadbeef 0x0000001a 123.45 -0.07 5 1000.000"

# Parts allowed to differ from the host by an ulp: none. The float core carries its own sin, cos, cbrt and atan2
# (firmware/lsm_math.c, + - * / only), so every part must match the host bit for bit. (Before it did, the
# closed-form part differed where newlib-nano and glibc round sinf differently.) Keep the mechanism for a
# future part that must call the C library.
LIBM_DEPENDENT_PARTS = set()

# Sampled values must agree to this fraction of the largest magnitude of the same quantity in the same part
# (float has 2^-23 = 1.2e-7 relative resolution; an ulp-level difference in sinf stays far below this).
SAMPLE_REL_TOL = 1e-5


def _run_image():
    if QEMU is None:
        pytest.skip("qemu-system-arm not installed (apt-get install qemu-system-arm)")
    if not IMAGE.exists():
        pytest.skip(f"{IMAGE} not built (scripts/arm_check.sh or cmake --preset cortex-m4f && "
                    "cmake --build build-arm)")
    proc = subprocess.run(QEMU_CMD + [str(IMAGE)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, timeout=120)
    return proc.returncode, proc.stdout


def _run_host():
    assert HOST.exists(), f"{HOST} missing: build the host first (cmake --build {BUILD})"
    proc = subprocess.run([str(HOST)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
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
