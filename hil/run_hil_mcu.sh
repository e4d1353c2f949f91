#!/usr/bin/env bash
# Runs the HIL pytest suite (hil/tests) against the Cortex-M4F controller image lissom-controller.elf under QEMU
# (scripts/mcu_node.sh), reached through python-can's slcan interface on its TCP port: the same suite as
# hil/run_hil.sh runs against lissom-node on vcan (tests that need a simulated input the board lacks skip and say
# why). Runs on this host: no CAN in the kernel is needed. One image for the whole session (NMT reset per test);
# at the end the image's tick statistics (0x5F00) are in $OUT/tick_stats.json and printed.
# Usage: hil/run_hil_mcu.sh [pytest args...]
# Env:   LSM_ARM_BUILD_DIR (default build-arm): where bin/lissom-controller.elf is (built if missing);
#        LISSOM_HIL_OUT (default out/hil-mcu): artefacts (qemu.log, frame logs, tick_stats.json).
# The last line of the pytest output is its summary; exit code = pytest's.
set -uo pipefail
cd "$(dirname "$0")/.."
REPO=$PWD
OUT=${LISSOM_HIL_OUT:-$REPO/out/hil-mcu}
PY=$REPO/.venv/bin/python
ARM=${LSM_ARM_BUILD_DIR:-build-arm}
t0=$(date +%s%N)
[ -x "$PY" ] || { echo "run_hil_mcu: no venv at .venv (scripts/deps.sh)" >&2; exit 2; }
"$PY" -c "import serial" 2>/dev/null || { echo "run_hil_mcu: pyserial is missing in .venv (hil/requirements.txt; scripts/deps.sh)" >&2; exit 2; }
if [ ! -f "$ARM/CMakeCache.txt" ]; then cmake --preset cortex-m4f >/dev/null || exit 2; fi
cmake --build "$ARM" --target lissom-controller >/dev/null || { echo "run_hil_mcu: image build failed" >&2; exit 2; }
rm -rf "$OUT"; mkdir -p "$OUT"
export PYTHONPATH=$REPO/hil${PYTHONPATH:+:$PYTHONPATH}
export LSM_ARM_BUILD_DIR=$ARM
"$PY" -m pytest -q -p no:cacheprovider --rig mcu --hil-out "$OUT" -o "junit_family=xunit2" \
  --junitxml "$OUT/junit.xml" -rs hil/tests "$@"
rc=$?
[ -f "$OUT/tick_stats.json" ] && echo "[hil-mcu] tick statistics (0x5F00): $(tr -d '\n ' < "$OUT/tick_stats.json")"
ms=$(( ($(date +%s%N) - t0) / 1000000 ))
echo "[hil-mcu] artefacts in $OUT; total $((ms / 1000)).$(printf '%03d' $((ms % 1000))) s"
exit $rc
