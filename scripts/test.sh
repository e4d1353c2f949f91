#!/usr/bin/env bash
# Quick start, command 2 of 2: runs every test. `.ci/run` runs exactly this.
#   1. dependencies (idempotent) and the host build
#   1b. lint: format drift (clang-format) and clang-tidy on firmware/ (scripts/lint.sh)
#   2. ctest: the cmocka unit tests, double and float builds (randomized tests at their CI counts)
#   3. the Cortex-M4F cross build: -Wall -Wextra -Werror, no heap or printf linked, images run under QEMU
#   4. pytest: the Python tests (CLI contracts, references, plots, EDS, ...)
#   4b. fuzz: each libFuzzer target (ASan + UBSan) for a few seconds (scripts/fuzz.sh --brief)
#   5. HIL: the CANopen node on a real vcan bus (a QEMU guest with Debian's kernel when this one has no CAN), then
#      the same suite against the Cortex-M4F controller image under QEMU, over slcan on TCP
# Ends with one line "tests: N passed, N failed".
set -uo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh || exit 1
scripts/build.sh || exit 1

passed=0; failed=0; status=0
log=$(mktemp)

# format drift (.clang-format, every tracked .c/.h) and clang-tidy on firmware/ (.clang-tidy): one check each
echo "== lint (scripts/lint.sh)"
for what in format tidy; do
  if scripts/lint.sh "$what"; then passed=$((passed + 1)); else failed=$((failed + 1)); status=1; fi
done

echo "== ctest"
ctest --preset host 2>&1 | tee "$log"
line=$(grep -E "tests passed, [0-9]+ tests? failed out of [0-9]+" "$log" | tail -1)
if [ -n "$line" ]; then
  nf=$(echo "$line" | sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\1/')
  nt=$(echo "$line" | sed -E 's/.* failed out of ([0-9]+).*/\1/')
  passed=$((passed + nt - nf)); failed=$((failed + nf))
  [ "$nf" -eq 0 ] || status=1
else
  failed=$((failed + 1)); status=1
fi

if [ -x scripts/arm_check.sh ]; then
  echo "== Cortex-M4F cross build and QEMU"
  if scripts/arm_check.sh; then passed=$((passed + 1)); else failed=$((failed + 1)); status=1; fi
fi

# Adds the counts of a pytest run (its log and exit code) to passed/failed; exit 5 (no tests) is not a failure.
count_pytest() {
  local log=$1 rc=$2 sum pp pf pe
  sum=$(grep -E "^[0-9]+ (passed|failed)|^=+ .*(passed|failed)" "$log" | tail -1)
  pp=$(echo "$sum" | grep -oE "[0-9]+ passed" | grep -oE "[0-9]+" || true)
  pf=$(echo "$sum" | grep -oE "[0-9]+ failed" | grep -oE "[0-9]+" || true)
  pe=$(echo "$sum" | grep -oE "[0-9]+ errors?" | grep -oE "[0-9]+" || true)
  passed=$((passed + ${pp:-0})); failed=$((failed + ${pf:-0} + ${pe:-0}))
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 5 ]; then status=1; [ -z "$pf$pe" ] && failed=$((failed + 1)); fi
  return 0
}

echo "== pytest"
export LISSOM_SIM="$PWD/build/bin/lissom-sim"
export LISSOM_SIM_FLOAT="$PWD/build-float/bin/lissom-sim"   # tests/py/test_float_sim.py
.venv/bin/python -m pytest -q -p no:cacheprovider tests/py 2>&1 | tee "$log"
count_pytest "$log" "${PIPESTATUS[0]}"

# ---- fuzz: every libFuzzer target briefly (about 30 s in all; scripts/fuzz.sh --brief, docs/reliability.md);
# ---- ctest above already replayed the seeds and every past finding. Counted as one test per target.
echo "== fuzz (scripts/fuzz.sh --brief)"
scripts/fuzz.sh --brief 2>&1 | tee "$log"
frc=${PIPESTATUS[0]}
fline=$(grep -E "^fuzz: [0-9]+ passed, [0-9]+ failed" "$log" | tail -1)
if [ -n "$fline" ]; then
  passed=$((passed + $(echo "$fline" | sed -E 's/fuzz: ([0-9]+) passed.*/\1/')))
  failed=$((failed + $(echo "$fline" | sed -E 's/.* ([0-9]+) failed.*/\1/')))
else
  failed=$((failed + 1))
fi
[ "$frc" -eq 0 ] || status=1

# ---- HIL: hil/run_hil.sh runs the CANopen suite hil/tests against build/bin/lissom-node on vcan0, inside one
# ---- QEMU guest when this kernel has no CAN (docs/hil.md); counted like pytest's.
echo "== HIL (hil/run_hil.sh)"
hil/run_hil.sh 2>&1 | tee "$log"
count_pytest "$log" "${PIPESTATUS[0]}"
# ---- HIL on the Cortex-M4F controller image: the same suite through slcan over TCP (hil/run_hil_mcu.sh, on this
# ---- host, no VM); counted like pytest's.
echo "== HIL on the Cortex-M4F controller image (hil/run_hil_mcu.sh)"
hil/run_hil_mcu.sh 2>&1 | tee "$log"
count_pytest "$log" "${PIPESTATUS[0]}"
# ---- end of the HIL block
rm -f "$log"

echo "tests: $passed passed, $failed failed"
exit $status
